"""Small facts about child processes: one that ends with its parent, the name of the signal that
ended one, and the command and environment of a fresh interpreter that imports what this one can."""
from __future__ import annotations

import os
import signal
import sys


def die_with_parent() -> None:
    """Have the kernel SIGKILL this process the moment the thread that forked it ends (Linux's
    ``PR_SET_PDEATHSIG``; nothing where it is missing). The caller then checks ``os.getppid()``:
    a parent that ended before the call is not noticed by it."""
    try:
        import ctypes
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL, 0, 0, 0)      # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


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
