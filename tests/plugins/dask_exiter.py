"""A plugin whose import ends the process (``os._exit(0)``) where ``SHOOTOUT_TEST_EXIT_ON_IMPORT``
is set (the test sets it on the Dask workers only; the driver imports it fine): on a forking
worker it ended the worker itself."""
import os

if os.environ.get("SHOOTOUT_TEST_EXIT_ON_IMPORT"):
    os._exit(0)

from methods import SmoothingResult, register  # noqa: E402


@register("dask_exiter.identity", task="smoothing", library="dask_exiter")
def identity(V, F):
    """The input, unchanged."""
    return SmoothingResult(V=V.copy())
