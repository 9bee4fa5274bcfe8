"""Trying modules' imports in a throwaway process before they are imported here: one that
raises, calls ``sys.exit``, ends the process or closes its files on import is named, not
imported (`import_problems`). Used for a config's plugins (`harness.plugins`) and installed
entry-point modules (`methods.registry`); it imports neither the registry nor any method."""
from __future__ import annotations

import os
import sys

ENDED: dict = {}      # module -> why, for a module whose import ended the trial process (latest trial here)
LOST_PIPE = 86        # the trial's exit code when it cannot write its record (an import closed the pipe)


def import_failure(exc: BaseException) -> str:
    """How an import failed, in a config message: ``it called sys.exit(3) on import`` or
    ``ValueError: ...`` (its text cut at 500 characters; a text that cannot be made is said)."""
    from .yaml_input import short
    if isinstance(exc, SystemExit):
        return f"it called sys.exit({short(exc.code)}) on import"
    try:
        text = str(exc)[:500]
    except Exception:  # noqa: BLE001 - a user's exception whose text fails
        text = "(its message could not be made)"
    return f"{type(exc).__name__}: {text}"


def import_problems(modules, prepare=None) -> dict:
    """``{module: why}`` for each of ``modules`` whose import, tried first in another process
    (one after the other, each in the state the earlier ones left), raised, called ``sys.exit``
    or ended that process (``os._exit``, a signal, a crash in compiled code): such a module is not
    imported here, so it cannot end the caller with a misleading exit status. The trial process
    is a fork of this one when no other Python thread runs here (a fork copies no import lock
    another thread holds) and a fork would not hang in GNU OpenMP (`_openmp_hazard`), else a
    fresh interpreter with this ``sys.path`` (`harness.executors.procs.python_child`); it writes
    to /dev/null, runs in a process group of its own that is killed once it is done (with
    whatever the imports started) and dies with this process. Modules already imported here are not tried; each trial is new (a module fixed since
    is tried again). `ENDED` keeps the modules whose import ended the trial process, for a case
    forked from here. ``prepare``: called before a forked trial (what the fork should inherit)."""
    import threading
    todo = [m for m in dict.fromkeys(modules) if m not in sys.modules]
    if not todo:
        return {}
    forking = hasattr(os, "fork") and threading.active_count() == 1 and not _openmp_hazard()
    if forking and prepare is not None:
        prepare()                                 # e.g. the registry the imports add to, inherited
    found: dict = {}
    while todo:
        tried = _trial(todo, forking)
        for mod, (why, ended) in tried.items():
            if why is not None:
                found[mod] = why
            if ended:                             # set or dropped, never cleared first: a case forked
                ENDED[mod] = why                  # meanwhile from another thread sees one or the other
            else:
                ENDED.pop(mod, None)
        todo = todo[len(tried):]
    return found


def _openmp_hazard() -> bool:
    """Whether a fork of this process would hang in GNU OpenMP (`harness.executors.gomp`): an
    import that enters an OpenMP region then hangs the forked trial, so a fresh interpreter tries it."""
    from .executors.gomp import forked_openmp_hangs
    return forked_openmp_hangs()


def _trial(todo: list, forking: bool) -> dict:
    """``{module: (why or None, ended)}`` for the modules of ``todo`` tried in one process, in
    order, up to and including the one whose import ended it or took its record pipe
    (``ended``); the caller tries the rest in a new one."""
    import json
    import select
    import signal
    import subprocess
    r, w = os.pipe()
    sys.stdout.flush()
    sys.stderr.flush()
    proc = None
    if forking:
        parent = os.getpid()
        pid = os.fork()
        if pid == 0:                              # the child: never returns
            try:
                os.close(r)
                os.setpgid(0, 0)
                from .executors.procs import die_with_parent
                if not die_with_parent(parent):
                    os._exit(0)
                for sig in (signal.SIGINT, signal.SIGTERM):   # not the caller's handlers (an interrupt flag)
                    signal.signal(sig, signal.SIG_DFL)
                _trial_main(w, todo)
            finally:
                os._exit(1)
    else:
        from .executors.procs import python_child
        try:                                      # a session of its own: its group is its pid
            argv, env = python_child("harness.trial", str(w), *todo)
            proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                    stderr=subprocess.DEVNULL, pass_fds=(w,), env=env, start_new_session=True)
        except BaseException:
            os.close(r)
            os.close(w)
            raise
        pid = proc.pid
    os.close(w)
    reaped = signal.getsignal(signal.SIGCHLD) == signal.SIG_IGN   # the system reaps it: no exit code to read
    buf, code, eof = b"", None, False
    poll = select.poll()
    poll.register(r, select.POLLIN | select.POLLHUP | select.POLLERR)
    try:
        while True:                               # until it ends (a zombie: its group id stays its own)
            if not eof and poll.poll(100):
                chunk = os.read(r, 65536)
                buf += chunk
                if chunk:
                    continue
                eof = True                        # every writer gone: it is ending, wait for it
            try:
                if os.waitid(os.P_PID, pid, os.WEXITED | os.WNOWAIT | (0 if eof else os.WNOHANG)) is not None:
                    break
            except ChildProcessError:             # reaped already (this process ignores SIGCHLD)
                break
        while poll.poll(0) and (chunk := os.read(r, 65536)):
            buf += chunk                          # what it wrote before it ended
    finally:
        os.close(r)
        try:
            os.killpg(pid, signal.SIGKILL)       # what its imports started (and it, when interrupted)
        except (ProcessLookupError, PermissionError):
            pass
        try:
            code = proc.wait() if proc is not None else os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1])
        except ChildProcessError:
            code = None
        if reaped:                                # Popen.wait says 0 there
            code = None
    tried: dict = {}
    for line in buf.decode(errors="replace").split("\n"):
        try:
            rec = json.loads(line)
            mod = rec[0]
            got = (rec[1], False) if len(rec) > 1 else (_ended(code), True)
        except (ValueError, TypeError, IndexError, KeyError):
            continue                              # not one of its records (empty, or bytes of the plugin's own)
        if mod in todo:
            tried[mod] = got
    if not tried:                                 # it ended before its first import: no endless retry
        tried[todo[0]] = (f"the process trying it ended before importing it ({_ended(code)})", True)
    return tried


def _trial_main(w: int, todo: list) -> None:
    """The trial process: output to /dev/null (where it can be opened), then each module of
    ``todo`` imported in turn, a JSON record on ``w`` before (``[module]``) and after
    (``[module, why or null]``) each; a KeyboardInterrupt is no failure of the module (its import
    in the caller says so). A record it cannot write (a module closed ``w``) ends it with
    exit code `LOST_PIPE`, the module's own last record unfinished."""
    import importlib
    import json
    try:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)
        os.dup2(null, 2)
    except OSError:
        pass

    def say(rec) -> None:
        try:
            os.write(w, (json.dumps(rec) + "\n").encode())
        except OSError:
            os._exit(LOST_PIPE)
    for mod in todo:
        say([mod])
        try:
            importlib.import_module(mod)
            why = None
        except KeyboardInterrupt:
            why = None
        except BaseException as exc:  # noqa: BLE001 - a user's module: its failure is the answer
            why = import_failure(exc)
        say([mod, why])
    os._exit(0)


def _ended(code) -> str:
    """How a trial process that did not finish an import ended, from its exit code (negative:
    the signal that killed it; None: not known, the system reaped it)."""
    from .executors.procs import signal_name
    if code is not None and code < 0:
        return f"importing it killed the process ({signal_name(code)})"
    if code == LOST_PIPE:
        return (f"importing it closed the files the process had open, or ended the process with exit status "
                f"{LOST_PIPE}")
    return f"importing it ended the process (exit status {'unknown' if code is None else code})"


if __name__ == "__main__":              # the fresh-interpreter trial: python -m harness.trial FD MODULE...
    from harness.executors.procs import die_with_parent
    die_with_parent()
    _trial_main(int(sys.argv[1]), sys.argv[2:])
