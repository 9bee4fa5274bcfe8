"""Methods that attack the driver on purpose (hardening tests). Imported through
``plugins: [tests.plugins.hostile]`` with the repository root on ``sys.path``."""
import os
import signal
import sys
import time

import numpy as np

from methods import SmoothingResult, register

MARK = os.environ.get("HOSTILE_MARK_DIR", "/tmp")


def _mark(name: str, text) -> None:
    """Leave ``text`` in the file ``name`` of the mark folder (pids for the tests to check),
    whole: written beside it and renamed, so a reader never sees it empty."""
    path = os.path.join(MARK, name)
    with open(path + ".part", "w") as fh:
        fh.write(str(text))
    os.replace(path + ".part", path)


@register("hostile.fork_return", task="smoothing", library="hostile")
def fork_return(V, F):
    """Forks; parent and child both return a result."""
    os.fork()
    return SmoothingResult(V=V.copy())


@register("hostile.orphan_segfault", task="smoothing", library="hostile")
def orphan_segfault(V, F):
    """Leaves a forked child sleeping (holding every inherited descriptor), then segfaults."""
    pid = os.fork()
    if pid == 0:
        _mark(f"orphan-{os.getpid()}.pid", str(os.getpid()))
        time.sleep(120)
        os._exit(0)
    time.sleep(0.2)
    import ctypes
    import faulthandler
    faulthandler.disable()
    ctypes.string_at(0)
    return SmoothingResult(V=V.copy())


@register("hostile.killpg", task="smoothing", library="hostile")
def killpg(V, F):
    """Sends SIGTERM to its own process group."""
    os.killpg(0, signal.SIGTERM)
    time.sleep(1)
    return SmoothingResult(V=V.copy())


@register("hostile.kill_parent", task="smoothing", library="hostile")
def kill_parent(V, F):
    """Signals its parent process (SIGTERM, SIGINT, SIGUSR1, SIGHUP), as a library that takes
    itself for a pool worker might, then returns its input."""
    for sig in (signal.SIGTERM, signal.SIGINT, signal.SIGUSR1, signal.SIGHUP, signal.SIGSYS, signal.SIGPWR,
                signal.SIGRTMIN + 2, signal.SIGIO):
        os.kill(os.getppid(), sig)
    time.sleep(0.2)
    return SmoothingResult(V=V.copy())


@register("hostile.kill_parent_hard", task="smoothing", library="hostile")
def kill_parent_hard(V, F):
    """SIGKILLs its parent at every call (a case calls it twice: the cold call and a sample)."""
    _mark(f"hard-{os.getpid()}-{time.monotonic_ns()}.ppid", str(os.getppid()))
    os.kill(os.getppid(), signal.SIGKILL)
    time.sleep(0.5)
    return SmoothingResult(V=V.copy())


@register("hostile.setsid_sleep", task="smoothing", library="hostile")
def setsid_sleep(V, F):
    """Leaves its process group (setsid) and sleeps: a timeout must still end it."""
    _mark(f"setsid-{os.getpid()}.pid", str(os.getpid()))
    try:
        os.setsid()
    except OSError:
        pass
    time.sleep(120)
    return SmoothingResult(V=V.copy())


@register("hostile.stop_parent", task="smoothing", library="hostile")
def stop_parent(V, F):
    """Stops its parent (SIGSTOP), then returns its input."""
    os.kill(os.getppid(), signal.SIGSTOP)
    return SmoothingResult(V=V.copy())


@register("hostile.spam_parent", task="smoothing", library="hostile")
def spam_parent(V, F):
    """Sends SIGTERM to its parent in a loop for 30 s."""
    t_end = time.monotonic() + 30
    while time.monotonic() < t_end:
        os.kill(os.getppid(), signal.SIGTERM)
    return SmoothingResult(V=V.copy())


@register("hostile.escape_hang", task="smoothing", library="hostile")
def escape_hang(V, F):
    """Leaves a grandchild in a session of its own (setsid and a double fork), then hangs."""
    if os.fork() == 0:
        os.setsid()
        if os.fork() == 0:
            _mark(f"escaped-{os.getpid()}.pid", str(os.getpid()))
            time.sleep(120)
        os._exit(0)
    time.sleep(120)
    return SmoothingResult(V=V.copy())


@register("hostile.chatty", task="smoothing", library="hostile")
def chatty(V, F):
    """Prints 50 MB to stdout and a line to stderr."""
    line = "x" * 999 + "\n"
    for _ in range(50_000):
        sys.stdout.write(line)
    sys.stdout.flush()
    print("chatty: done", file=sys.stderr)
    return SmoothingResult(V=V.copy())


@register("hostile.complex", task="smoothing", library="hostile")
def complex_result(V, F):
    """Returns complex coordinates."""
    return SmoothingResult(V=V.astype(np.complex128))


@register("hostile.strings", task="smoothing", library="hostile")
def string_result(V, F):
    """Returns coordinates as strings."""
    return SmoothingResult(V=V.astype(str))


@register("hostile.bools", task="smoothing", library="hostile")
def bool_result(V, F):
    """Returns booleans."""
    return SmoothingResult(V=V > 0)


@register("hostile.lists", task="smoothing", library="hostile")
def list_result(V, F):
    """Returns a Python list."""
    return SmoothingResult(V=V.tolist())


_FLOODED = []


@register("hostile.stderr_flood", task="smoothing", library="hostile")
def stderr_flood(V, F):
    """Writes 40 MB to stderr (once per process), then waits up to 20 s for the driver to cut its
    stderr file back below 17 MB; raises if it never does (a flood would fill the disk)."""
    if not _FLOODED:
        _FLOODED.append(1)
        chunk = b"y" * (1 << 20)
        for _ in range(40):
            os.write(2, chunk)
        t0 = time.time()
        while os.fstat(2).st_size > 17 << 20:
            if time.time() - t0 > 20:
                raise RuntimeError(f"stderr file still {os.fstat(2).st_size} bytes")
            time.sleep(0.05)
    return SmoothingResult(V=V.copy())


@register("hostile.escape", task="smoothing", library="hostile", params={"crash": False, "hang": False})
def escape(V, F, *, crash=False, hang=False):
    """Leaves a grandchild in a session of its own (setsid and a double fork: out of the case's
    process group), which records its pid and sleeps; then returns, (``crash``) segfaults or
    (``hang``) sleeps a minute."""
    r, w = os.pipe()
    if os.fork() == 0:
        os.setsid()
        if os.fork() == 0:
            _mark(f"escaped-{os.getpid()}.pid", str(os.getpid()))
            os.write(w, b"x")                        # the pid file is written: the method may go on
            time.sleep(60)
            os._exit(0)
        os._exit(0)
    os.close(w)
    os.read(r, 1)
    os.close(r)
    if hang:
        time.sleep(60)
    if crash:
        import ctypes
        import faulthandler
        faulthandler.disable()
        ctypes.string_at(0)
    return SmoothingResult(V=V.copy())


@register("hostile.nul_warning", task="smoothing", library="hostile")
def nul_warning(V, F):
    """A good result, with a NUL byte in a warning's text (which the row's error column quotes)."""
    import warnings
    warnings.warn("library said: \x00 done")
    return SmoothingResult(V=V.copy())


@register("hostile.surrogate_raise", task="smoothing", library="hostile")
def surrogate_raise(V, F):
    """Raises with a lone surrogate in its message (a path decoded with ``surrogateescape``)."""
    raise FileNotFoundError("cannot open " + b"/data/scan\xff.obj".decode("utf-8", "surrogateescape"))


@register("hostile.global_state", task="smoothing", library="hostile")
def global_state(V, F):
    """Changes the process's working directory and numpy's error state, then returns a good result."""
    os.chdir("/")
    np.seterr(all="raise")
    return SmoothingResult(V=V.copy())


@register("hostile.report_igl_threads", task="smoothing", library="hostile")
def report_igl_threads(V, F):
    """Writes the IGL_NUM_THREADS its process sees into the mark directory."""
    mark = os.environ.get("HOSTILE_MARK_DIR", MARK)          # at call time: the module may be older
    with open(os.path.join(mark, f"igl-threads-{os.getpid()}.txt"), "w") as fh:
        fh.write(os.environ.get("IGL_NUM_THREADS", "unset"))
    return SmoothingResult(V=V.copy())


@register("hostile.lazy_mkl", task="smoothing", library="hostile")
def lazy_mkl(V, F):
    """Loads MKL by a first pypardiso solve (as scratch.implicit's PARDISO backend does inside its
    cold call) and writes the threads MKL then has, per call, into the mark directory."""
    import numpy as np
    import pypardiso
    import scipy.sparse as sp
    import threadpoolctl
    A = sp.eye(50, format="csr") * 2.0
    pypardiso.spsolve(A, np.ones(50))
    mkl = [p["num_threads"] for p in threadpoolctl.threadpool_info() if p["internal_api"] == "mkl"]
    mark = os.environ.get("HOSTILE_MARK_DIR", MARK)
    with open(os.path.join(mark, f"mkl-threads-{os.getpid()}.txt"), "a") as fh:
        fh.write(f"{max(mkl) if mkl else 'none'}\n")
    return SmoothingResult(V=V.copy())


@register("hostile.reads_stdin", task="smoothing", library="hostile")
def reads_stdin(V, F):
    """Reads its standard input to the end (nothing, where it has none to read)."""
    sys.stdin.read()
    return SmoothingResult(V=V.copy())
