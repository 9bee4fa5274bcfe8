"""The guard between a case and the process that forked it: the case runs in a child of the
guard (`_guard`) and dies with it (`_die_with_guard`); the guard takes the signals of `_GUARDED`
(every signal whose default ends a process) from the driver alone, waits for the case and ends
as it did, so a method that signals its parent costs the case nothing and never reaches the
driver.
"""
from __future__ import annotations

import contextlib
import os
import signal

from .procs import die_with_parent, end_by
from .subreaper import become_subreaper, reap_strays


# every signal whose default ends a process (a method may send any to its parent, os.getppid()):
# the guard takes them only from the driver, so a method's cost the case nothing and never reach it
_NOT_ENDING = {getattr(signal, n) for n in ("SIGKILL", "SIGSTOP", "SIGCHLD", "SIGCONT", "SIGTSTP", "SIGTTIN",
                                            "SIGTTOU", "SIGWINCH", "SIGURG") if hasattr(signal, n)}
_GUARDED = tuple(sorted(set(signal.valid_signals()) - _NOT_ENDING)) if hasattr(signal, "valid_signals") else ()
_GUARD_WAITS = set(_GUARDED) | ({signal.SIGCHLD} if hasattr(signal, "SIGCHLD") else set())


def _die_with_guard(guard: int) -> None:
    """In the case process: killed (SIGKILL) the moment its guard ends, whatever ends it, so the
    case never becomes a child of the driver (a subreaper) and cannot outlive a guard the
    driver killed, even from a session of its own."""
    if not die_with_parent(guard):        # it ended before that
        os._exit(70)


def _guard(pid: int) -> None:
    """The case process as the driver sees it: the parent of the process that runs the case
    (``pid``), which dies with it (`_die_with_guard`). It takes the signals of `_GUARDED` from
    the driver alone (stopped by it, it kills the case and ends by that signal); from anyone
    else, the case's own processes included (a method signalling its parent), they are
    dropped. It dies with the driver (``PR_SET_PDEATHSIG``), and the case with it. It is a child
    subreaper (what the case leaves, even outside its group, comes back here and is killed),
    waits for the case, then ends as the case did: the same exit code, or killed by the same
    signal (without a core file of its own). Where ``sigwaitinfo`` is missing (macOS) the sender
    cannot be told: the guarded signals are ignored. Never returns."""
    driver = os.getppid()
    try:
        import resource
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))     # a core file is the case's, never this one's
    except (ImportError, OSError, ValueError):
        pass
    if not die_with_parent(driver):                          # with the driver, even a SIGKILLed one
        os.kill(pid, signal.SIGKILL)
        os._exit(70)
    become_subreaper()
    if not hasattr(signal, "sigwaitinfo"):   # (macOS) no sender to check: the guarded signals are ignored
        for sig in _GUARDED:
            with contextlib.suppress(OSError, ValueError):
                signal.signal(sig, signal.SIG_IGN)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, _GUARD_WAITS)
    status = None
    while status is None and not hasattr(signal, "sigwaitinfo"):
        try:
            status = os.waitpid(pid, 0)[1]
        except ChildProcessError:
            status = 0
    while status is None:
        try:
            done, st = os.waitpid(pid, os.WNOHANG)
        except ChildProcessError:
            done, st = pid, 0
        if done:
            status = st
            break
        info = signal.sigwaitinfo(_GUARD_WAITS)
        if info.si_signo in _GUARDED and info.si_pid == driver:
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
            reap_strays()
            end_by(info.si_signo)
    reap_strays()
    if os.WIFSIGNALED(status):
        end_by(os.WTERMSIG(status))
    os._exit(os.waitstatus_to_exitcode(status) if os.WIFEXITED(status) else 1)
