"""A plugin whose import ends the process (``os._exit(0)``) inside a Dask worker process only (the
driver imports it fine): on a forking worker it ended the worker itself."""
import multiprocessing
import os

if "Dask Worker" in multiprocessing.current_process().name:
    os._exit(0)

from methods import SmoothingResult, register  # noqa: E402


@register("dask_exiter.identity", task="smoothing", library="dask_exiter")
def identity(V, F):
    """The input, unchanged."""
    return SmoothingResult(V=V.copy())
