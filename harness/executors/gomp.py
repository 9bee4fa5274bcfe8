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
nothing) and exits; a child still running after ``timeout`` seconds hangs, and is killed (one
that crashes counts as hanging too). Linux;
False where ``/proc`` says nothing.
"""
from __future__ import annotations

import os
import time


def _loaded_gomp() -> list[str]:
    """Paths of the libgomp shared objects mapped in this process (several wheels bundle their own)."""
    try:
        with open("/proc/self/maps") as fh:
            return sorted({ln.split()[-1] for ln in fh if "libgomp" in ln and ln.split()[-1].startswith("/")})
    except OSError:
        return []


def gnu_openmp_started() -> bool:
    """Whether this process has GNU OpenMP (libgomp) loaded and threads that Python did not start
    (possibly libgomp's pool; see the module)."""
    import threading
    if not _loaded_gomp():
        return False
    try:
        return len(os.listdir("/proc/self/task")) > threading.active_count()
    except OSError:
        return False


def forked_openmp_hangs(timeout: float = 2.0) -> bool:
    """Whether a child forked from this process hangs in its first OpenMP parallel region (the
    module's probe); False at once unless `gnu_openmp_started`. A probe that cannot run (no
    ``fork``, a libgomp without ``GOMP_parallel``) says True: the caller then avoids forking."""
    if not gnu_openmp_started():
        return False
    import ctypes
    import signal
    try:
        libs = [ctypes.CDLL(p) for p in _loaded_gomp()]     # the copies already loaded, not new ones
        free = ctypes.cast(ctypes.CDLL(None).free, ctypes.c_void_p)
        calls = [lib.GOMP_parallel for lib in libs]
    except (OSError, AttributeError):
        return True
    for call in calls:
        call.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_uint, ctypes.c_uint)
        call.restype = None
    pid = os.fork()
    if pid == 0:                                  # C calls only, then out without Python's exit
        try:
            for call in calls:
                call(free, None, 2, 0)
        finally:
            os._exit(0)
    status = None
    try:
        end = time.monotonic() + timeout
        while status is None and time.monotonic() < end:
            done, st = os.waitpid(pid, os.WNOHANG)
            if done:
                status = st
            else:
                time.sleep(0.005)
    finally:                                      # hung, or interrupted meanwhile: it ends here
        if status is None:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
            os.waitpid(pid, 0)
    return status is None or os.waitstatus_to_exitcode(status) != 0
