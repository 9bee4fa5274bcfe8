"""A case that kills the process that started it: on a Dask worker that forks its cases, the
worker itself (a case that exhausts the worker's memory does the same). Never run it locally:
there its parent is the run's own process."""
import os
import signal

from methods import register


@register("worker_killer.parent", task="smoothing", library="worker_killer")
def parent(V, F):
    """Returns nothing: SIGKILLs the process that started its case first (on a daemonic worker,
    where the case runs behind a guard process, the guard's parent)."""
    import psutil
    pid = os.getppid()
    if "harness.executors.dask" in psutil.Process(pid).cmdline():
        pid = psutil.Process(pid).ppid()
    os.kill(pid, signal.SIGKILL)
    return V
