"""A case that kills the process that started it: on a Dask worker that forks its cases, the
worker itself (a case that exhausts the worker's memory does the same). Never run it locally:
there its parent is the run's own process."""
import os
import signal

from methods import register


@register("worker_killer.parent", task="smoothing", library="worker_killer")
def parent(V, F):
    """Returns nothing: SIGKILLs its parent process first."""
    os.kill(os.getppid(), signal.SIGKILL)
    return V
