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
dies with the thread that forked it (``PR_SET_PDEATHSIG``) or after its own alarm; a child
still running after ``timeout`` seconds hangs, and is killed (one that crashes counts as
hanging too). Linux; False where ``/proc`` says nothing.
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


_SEEN_HANG: list = []     # a probe that hung: the pool stays for the life of the process (and its forks)


def forked_openmp_hangs(timeout: float = 2.0) -> bool:
    """Whether a child forked from this process hangs in its first OpenMP parallel region (the
    module's probe); False at once unless `gnu_openmp_started`, True at once once a probe hung
    here. A probe that cannot run (no ``fork``, a libgomp without ``GOMP_parallel`` or whose file
    is gone) says True: the caller then avoids forking. It asks for two threads whatever the cases'
    own count: a forked case limited to one thread runs its regions alone, but a method may ask
    OpenMP for threads of its own. The probe child ends itself after ``timeout`` + 2 s (``alarm``)
    should this process lose track of it, and an interrupt during the probe is raised after it
    (`harness.errors.interrupts_deferred`, where the run's handler is installed). With SIGCHLD
    ignored (children reaped by the kernel) a child that is gone before ``timeout`` did not hang."""
    if _SEEN_HANG:
        return True
    if not gnu_openmp_started():
        return False
    import ctypes
    import signal

    from ..errors import interrupts_deferred
    from .procs import die_with_parent
    paths = _loaded_gomp()
    if not paths or not hasattr(os, "fork"):      # named in the maps but no file to load; no fork
        return True
    try:
        libs = [ctypes.CDLL(p) for p in paths]    # the copies already loaded (a deleted one: OSError)
        libc = ctypes.CDLL(None)
        free = ctypes.cast(libc.free, ctypes.c_void_p)
        calls = [lib.GOMP_parallel for lib in libs]
        alarm, set_handler = libc.alarm, libc.signal
    except (OSError, AttributeError):
        return True
    for call in calls:
        call.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_uint, ctypes.c_uint)
        call.restype = None
    set_handler.argtypes, set_handler.restype = (ctypes.c_int, ctypes.c_void_p), ctypes.c_void_p
    parent, status, gone = os.getpid(), None, False
    with interrupts_deferred():
        pid = os.fork()
        if pid == 0:                              # C calls, then out without Python's exit
            code = 1
            try:
                set_handler(signal.SIGALRM, None)          # SIG_DFL: the alarm ends this process
                alarm(int(timeout) + 2)
                if die_with_parent(parent):       # with the thread that forked it
                    for call in calls:
                        call(free, None, 2, 0)
                    code = 0
            finally:
                os._exit(code)
        try:
            end = time.monotonic() + timeout
            while status is None and not gone and time.monotonic() < end:
                try:
                    done, st = os.waitpid(pid, os.WNOHANG)
                except ChildProcessError:         # SIGCHLD ignored: the kernel reaped it, it ended
                    gone = True
                    break
                if done:
                    status = st
                else:
                    time.sleep(0.005)
        finally:                                  # hung, or interrupted meanwhile: it ends here
            if status is None and not gone:
                try:
                    os.kill(pid, signal.SIGKILL)
                    os.waitpid(pid, 0)
                except (ProcessLookupError, ChildProcessError):
                    pass
    hangs = not gone and (status is None or os.waitstatus_to_exitcode(status) != 0)
    if hangs:
        _SEEN_HANG.append(True)
    return hangs
