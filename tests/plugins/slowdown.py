"""A method whose cost is set from outside, for the statistical compare tests.

``slowdown.sleep`` returns its input after sleeping ``SLOWDOWN_MS`` milliseconds (default 4) times
``$SLOWDOWN_FACTOR`` (default 1): a run with the factor at 2 is the same code made 2x slower.
"""
import os
import time

from methods import SmoothingResult, register


@register("slowdown.sleep", task="smoothing", library="slowdown", params={"ms": 4.0})
def sleep(V, F, *, ms=4.0):
    """Identity smoothing after sleeping ``ms * $SLOWDOWN_FACTOR`` milliseconds."""
    time.sleep(ms * float(os.environ.get("SLOWDOWN_FACTOR", "1")) / 1000.0)
    return SmoothingResult(V=V.copy())


@register("slowdown.until", task="smoothing", library="slowdown")
def until(V, F):
    """Identity smoothing that waits (at most 60 s) until the file ``$SLOWDOWN_RELEASE`` exists;
    returns at once when that variable is not set."""
    release = os.environ.get("SLOWDOWN_RELEASE")
    deadline = time.monotonic() + 60
    while release and not os.path.exists(release) and time.monotonic() < deadline:
        time.sleep(0.02)
    return SmoothingResult(V=V.copy())
