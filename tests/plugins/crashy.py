"""Methods that misbehave on purpose, for the isolation, timeout and durability tests.

Imported through ``plugins: [tests.plugins.crashy]`` (the repository root must be on
``sys.path``/``PYTHONPATH``, in the driver and in every worker). Each method is registered
once per process (importing the module twice is a no-op).
"""
import ctypes
import faulthandler
import os
import time

import numpy as np

from methods import LaplacianResult, SimplificationResult, SmoothingResult, register


@register("crashy.abort", task="laplacian", library="crashy")
def abort(V, F):
    """Calls ``os.abort()``: the process dies of SIGABRT, like a failed C++ assertion."""
    faulthandler.disable()            # pytest's dump of the crash is noise here
    os.abort()


@register("crashy.segfault", task="laplacian", library="crashy")
def segfault(V, F):
    """Reads address 0 through ctypes: the process dies of SIGSEGV."""
    faulthandler.disable()
    ctypes.string_at(0)


@register("crashy.kill9", task="laplacian", library="crashy")
def kill9(V, F):
    """SIGKILLs its own process, as the kernel's out-of-memory killer would."""
    os.kill(os.getpid(), 9)


@register("crashy.sleep", task="laplacian", library="crashy")
def sleep_forever(V, F):
    """Never returns (until killed by the timeout)."""
    while True:
        time.sleep(3600)


@register("crashy.exit", task="laplacian", library="crashy")
def hard_exit(V, F):
    """``os._exit(3)``: the process ends with a code, no signal, no result."""
    os._exit(3)


@register("crashy.raises", task="laplacian", library="crashy")
def raises(V, F):
    """Raises an ordinary exception."""
    raise RuntimeError("crashy.raises failed on purpose")


@register("crashy.missing", task="laplacian", library="crashy", requires=("no_such_module_xyz",))
def missing(V, F):
    """Needs a module that does not exist: the method is `unavailable`."""
    raise AssertionError("never called")


@register("crashy.slow", task="laplacian", library="crashy", params={"seconds": 0.3})
def slow(V, F, *, seconds=0.3):
    """A valid (uniform) Laplacian after sleeping ``seconds``: ok rows that take a while."""
    import scipy.sparse as sp
    time.sleep(seconds)
    n = len(V)
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    E = np.unique(np.sort(E, axis=1), axis=0)
    A = sp.coo_matrix((np.ones(len(E)), (E[:, 0], E[:, 1])), shape=(n, n)).tocsr()
    A = A + A.T
    W = A - sp.diags(np.asarray(A.sum(1)).ravel())
    return LaplacianResult(W=W)


@register("crashy.nan_smooth", task="smoothing", library="crashy")
def nan_smooth(V, F):
    """Returns NaN coordinates: must be recorded as diverged, never as a good result."""
    out = V.copy()
    out[::2] = np.nan
    return SmoothingResult(V=out)


@register("crashy.bad_faces", task="simplification", library="crashy")
def bad_faces(V, F, *, target_faces):
    """Returns face indices out of range: must be an error row."""
    F2 = F[:target_faces].copy()
    F2[0, 0] = len(V) + 10
    return SimplificationResult(V=V, F=F2)
