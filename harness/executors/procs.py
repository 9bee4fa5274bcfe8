"""Small facts about child processes: one that ends with its parent, one that ends by a signal,
the name of the signal that ended one, and the command and environment of a fresh interpreter
that imports what this one can."""
from __future__ import annotations

import os
import signal
import sys


def die_with_parent(parent: int | None = None) -> bool:
    """Have the kernel SIGKILL this process the moment the thread that forked it ends (Linux's
    ``PR_SET_PDEATHSIG``; nothing where it is missing). A parent that ended before the call is
    not noticed by it: with ``parent`` (its pid, read before the fork), whether it is still this
    process's parent after the call (False: the caller ends now)."""
    try:
        import ctypes
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL, 0, 0, 0)      # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass
    return parent is None or os.getppid() == parent


def end_by(sig: int) -> None:
    """End this process by ``sig`` (its default action, unblocked; no faulthandler report of its
    own), as a process that waited for a child killed by ``sig`` ends for its own parent to read;
    ``128 + sig`` as its exit code where the signal does not end it."""
    import contextlib
    import faulthandler
    faulthandler.disable()
    with contextlib.suppress(OSError, ValueError):      # SIGKILL and SIGSTOP cannot be handled: no need
        signal.signal(sig, signal.SIG_DFL)
    with contextlib.suppress(OSError, ValueError, AttributeError):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {sig})
    os.kill(os.getpid(), sig)
    os._exit(128 + sig)


def signal_name(code: int) -> str:
    """'SIGSEGV' for a process exit code -11 (a process killed by that signal)."""
    try:
        return signal.Signals(-code).name
    except (ValueError, TypeError):
        return f"signal {-code}"


def python_child(module: str, *args: str) -> tuple[list, dict]:
    """``(argv, env)`` of ``python -m module args...`` in a fresh interpreter that finds what this
    one finds: this process's ``sys.path`` (``''`` as the working directory now) goes first on
    its ``PYTHONPATH`` (plugins beside a config), and ``-P`` (3.11+) keeps its own working
    directory from coming first."""
    env = dict(os.environ)
    try:
        here = os.getcwd()
    except OSError:                               # a working directory since removed
        here = None
    paths = [p for p in (here if p == "" else p for p in sys.path) if p]    # archives and paths inside them too
    env["PYTHONPATH"] = os.pathsep.join(dict.fromkeys(paths + env.get("PYTHONPATH", "").split(os.pathsep)))
    safe = ["-P"] if sys.version_info >= (3, 11) else []
    return [sys.executable, *safe, "-m", module, *args], env
