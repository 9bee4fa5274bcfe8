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


_CALLED = []


@register("slowdown.cold", task="smoothing", library="slowdown", params={"cold_ms": 1500.0, "ms": 2.0})
def cold(V, F, *, cold_ms=1500.0, ms=2.0):
    """Identity smoothing that sleeps ``cold_ms`` milliseconds on its first call in a process (a
    first-call cost such as a compile), ``ms`` on every later one."""
    time.sleep((ms if _CALLED else cold_ms) / 1000.0)
    _CALLED.append(1)
    return SmoothingResult(V=V.copy())


@register("slowdown.identity", task="smoothing", library="slowdown")
def identity(V, F):
    """Its input, as is: a timed call of a microsecond, the harness's untimed work around it larger."""
    return SmoothingResult(V=V)
