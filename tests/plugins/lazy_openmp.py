"""A method that loads an OpenMP runtime on its first call (PyMeshLab's libgomp), for the
thread-limit test: ``lazy_openmp.identity`` appends the OpenMP pools' thread counts it sees in
each call to ``$LAZY_OPENMP_LOG`` (one JSON list per line) and returns its input."""
import json
import os

from methods import SmoothingResult, register


@register("lazy_openmp.identity", task="smoothing", library="lazy_openmp", requires=())
def identity(V, F):
    """Identity smoothing; imports pymeshlab (and with it libgomp) inside the call."""
    import pymeshlab  # noqa: F401
    import threadpoolctl
    seen = [p["num_threads"] for p in threadpoolctl.threadpool_info() if p["internal_api"] == "openmp"]
    with open(os.environ["LAZY_OPENMP_LOG"], "a") as fh:
        fh.write(json.dumps(seen) + "\n")
    return SmoothingResult(V=V.copy())
