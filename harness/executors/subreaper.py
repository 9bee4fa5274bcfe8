"""Child subreaper (Linux ``PR_SET_CHILD_SUBREAPER``): orphaned descendants of this process come
back to it instead of init (`become_subreaper`), even after they left its session; its children
read from /proc (`_children`); and every child it does not keep killed and reaped
(`reap_strays`), round after round, as their own children come back in turn.
"""
from __future__ import annotations

import contextlib
import os
import signal
import time


PR_SET_CHILD_SUBREAPER = 36


def become_subreaper(on: bool = True) -> bool:
    """Make this process a child subreaper (Linux; ``on=False`` undoes it): orphaned descendants
    are re-parented to it instead of init, even after they left its session. False where
    unsupported."""
    try:
        import ctypes
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(PR_SET_CHILD_SUBREAPER, int(on), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _children(pid: int) -> list[int]:
    """Pids whose parent is ``pid`` (from /proc: each thread's ``children`` list where the kernel
    has it, else every process's parent; [] without /proc)."""
    try:
        tids = os.listdir(f"/proc/{pid}/task")
        kids: set[int] = set()
        for t in tids:
            with open(f"/proc/{pid}/task/{t}/children") as fh:
                kids.update(int(x) for x in fh.read().split())
        return sorted(kids)
    except (OSError, ValueError):
        pass
    out = []
    try:
        names = os.listdir("/proc")
    except OSError:
        return out
    for name in names:
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/stat", "rb") as fh:
                stat = fh.read()
        except OSError:
            continue
        fields = stat[stat.rfind(b")") + 2:].split()     # after the command name, which may hold spaces
        if len(fields) > 1 and int(fields[1]) == pid:
            out.append(int(name))
    return out


def reap_strays(keep=(), rounds: int = 20, wait_s: float = 2.0) -> int:
    """Kill and reap every child of this process that is not in ``keep`` (running cases, and
    children this process had before its cases): the orphaned descendants of cases that
    escaped their process group, re-parented here because this process is a subreaper. Their
    own children come here in turn as they die, so this repeats until none is left (at most
    ``rounds`` times); each round waits at most ``wait_s`` for the killed to be reaped (one
    stuck in uninterruptible sleep is left to init). Returns how many were killed."""
    me, keep, n = os.getpid(), set(keep), 0
    for _ in range(rounds):
        strays = [c for c in _children(me) if c not in keep]
        if not strays:
            break
        for c in strays:
            with contextlib.suppress(OSError):
                os.kill(c, signal.SIGKILL)
        left, t_end = set(strays), time.monotonic() + wait_s
        while left and time.monotonic() < t_end:
            for c in list(left):
                try:
                    if os.waitpid(c, os.WNOHANG)[0]:
                        left.discard(c)
                except ChildProcessError:
                    left.discard(c)
            if left:
                time.sleep(0.01)
        n += len(strays)
        keep |= left                                 # not reaped in time: not ours to wait for
    return n
