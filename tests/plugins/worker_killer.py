"""A case that kills the process that started it: on a Dask worker that forks its cases, the
worker itself (a case that exhausts the worker's memory does the same). Never run it locally:
there its parent is the run's own process."""
import os
import signal

from methods import register


@register("worker_killer.parent", task="smoothing", library="worker_killer")
def parent(V, F):
    """Returns nothing: SIGKILLs the worker that started its case first. The case runs behind a
    guard process: on a daemonic worker a ``python -m harness.executors.dask`` subprocess, else a
    fork of the worker (the same command line); the worker is the guard's parent."""
    import psutil
    guard = psutil.Process(os.getppid())
    pid = guard.ppid() if ("harness.executors.dask" in guard.cmdline()
                           or guard.cmdline() == psutil.Process(guard.ppid()).cmdline()) else guard.pid
    os.kill(pid, signal.SIGKILL)
    return V
