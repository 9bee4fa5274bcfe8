"""Whether a process forked from this one would hang in GNU OpenMP.

libgomp keeps the thread pool of its first parallel region for the life of the process. A
forked child inherits the pool's bookkeeping but not its threads, and its first parallel region
of two or more threads waits forever at the team's barrier for threads that do not exist (GNU
OpenMP is not fork-safe). A driver that ran a MeshLab filter, or PARDISO through MKL on libgomp,
before ``harness.run`` is such a process (as a notebook often is).

`gnu_openmp_started` is the cheap test: libgomp loaded and threads Python did not start (they
may be another library's: importing PyMeshLab starts one). `forked_openmp_hangs` settles it: it
forks a child that runs an empty parallel region of two threads in every libgomp this process
has loaded (``GOMP_parallel(free, NULL, 2, 0)``: each thread calls ``free(NULL)``, which does
nothing) and exits at once (``os._exit``: exit code 0 only when every region returned); it
dies with the driver (``PR_SET_PDEATHSIG``); a child still running after ``timeout`` seconds hangs, and is killed (one
that crashes counts as hanging too). Linux;
False where ``/proc`` says nothing.
"""
from __future__ import annotations

import os
import time


def _loaded_gomp() -> list[str]:
    """Paths of the libgomp shared objects mapped in this process (several wheels bundle their own;
    a path may hold spaces, and a file replaced since it was loaded ends in `` (deleted)``)."""
    try:
        with open("/proc/self/maps") as fh:
            lines = [ln.rstrip("\n").split(maxsplit=5) for ln in fh if "libgomp" in ln]
    except OSError:
        return []
    return sorted({p[5] for p in lines if len(p) == 6 and "libgomp" in p[5]})


def gnu_openmp_started() -> bool:
    """Whether this process has GNU OpenMP (libgomp) loaded and threads that Python did not start
    (possibly libgomp's pool; see the module)."""
    import threading
    try:
        with open("/proc/self/maps") as fh:
            if "libgomp" not in fh.read():
                return False
        return len(os.listdir("/proc/self/task")) > threading.active_count()
    except OSError:
        return False


def forked_openmp_hangs(timeout: float = 2.0) -> bool:
    """Whether a child forked from this process hangs in its first OpenMP parallel region (the
    module's probe); False at once unless `gnu_openmp_started`. A probe that cannot run (no
    ``fork``, a libgomp without ``GOMP_parallel`` or whose file is gone) says True: the caller then
    avoids forking. It asks for two threads whatever the cases' own count: a forked case limited
    to one thread runs its regions alone, but a method may ask OpenMP for threads of its own."""
    if not gnu_openmp_started():
        return False
    import ctypes
    import signal
    if not hasattr(os, "fork") or not hasattr(signal, "pthread_sigmask"):
        return True

    from .procs import die_with_parent
    paths = _loaded_gomp()
    if not paths:                                 # named in the maps, but no file to load
        return True
    try:
        libs = [ctypes.CDLL(p) for p in paths]    # the copies already loaded (a deleted one: OSError)
        free = ctypes.cast(ctypes.CDLL(None).free, ctypes.c_void_p)
        calls = [lib.GOMP_parallel for lib in libs]
    except (OSError, AttributeError):
        return True
    for call in calls:
        call.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_uint, ctypes.c_uint)
        call.restype = None
    parent, pid, status = os.getpid(), -1, None
    held = {signal.SIGINT, signal.SIGTERM}
    try:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, held)      # no interrupt between the fork and the try
        try:
            pid = os.fork()
            if pid == 0:                          # the regions, then out without Python's exit
                code = 1
                try:
                    if die_with_parent(parent):   # a driver killed meanwhile takes it along
                        for call in calls:
                            call(free, None, 2, 0)
                        code = 0
                finally:
                    os._exit(code)
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)
        end = time.monotonic() + timeout
        while status is None and time.monotonic() < end:
            done, st = os.waitpid(pid, os.WNOHANG)
            if done:
                status = st
            else:
                time.sleep(0.005)
    finally:                                      # hung, or interrupted meanwhile: it ends here
        if pid > 0 and status is None:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
            os.waitpid(pid, 0)
    return status is None or os.waitstatus_to_exitcode(status) != 0
