"""A child process that ends with the process that forked it."""
from __future__ import annotations

import signal


def die_with_parent() -> None:
    """Have the kernel SIGKILL this process the moment the thread that forked it ends (Linux's
    ``PR_SET_PDEATHSIG``; nothing where it is missing). The caller then checks ``os.getppid()``:
    a parent that ended before the call is not noticed by it."""
    try:
        import ctypes
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL, 0, 0, 0)      # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass
