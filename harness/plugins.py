"""Importing the method registry, with a clear message when a user's own module shadows it, and
trying a user's plugin modules in a child process before they are imported here."""
from __future__ import annotations

import os
import sys
from pathlib import Path

from .errors import ShootoutError

OURS = Path(__file__).resolve().parent.parent / "methods"


def _shadow_message(mod) -> str:
    where = getattr(mod, "__file__", None) or "an unknown location"
    return (f"the module 'methods' was imported from {where}, not from mesh-shootout's methods package "
            f"({OURS}): a file or folder named 'methods' next to your script or notebook comes first on "
            "sys.path and shadows it. Rename yours (e.g. my_methods.py) and name it under plugins: in the config")


def import_methods():
    """The ``methods`` package (the registry); `ShootoutError` explaining a shadowing module."""
    try:
        import methods
    except ImportError as exc:
        mod = sys.modules.get("methods")
        if mod is None:
            import importlib.util
            import types
            spec = importlib.util.find_spec("methods")
            mod = types.SimpleNamespace(__file__=spec.origin) if spec and spec.origin else None
        if mod is not None and getattr(mod, "__file__", None) and \
                Path(mod.__file__).resolve().parent != OURS.resolve():
            raise ShootoutError(_shadow_message(mod)) from None
        raise ShootoutError(f"cannot import the methods package ({exc})") from None
    if not hasattr(methods, "register") or not hasattr(methods, "__path__"):
        raise ShootoutError(_shadow_message(methods))
    return methods


FAILED: dict = {}     # module -> why, for every module `import_problems` found failing in this process


def import_problems(modules) -> dict:
    """``{module: why}`` for each of ``modules`` whose import, tried first in a forked child of
    this process (one after the other, each in the state the earlier ones left), raised, called
    ``sys.exit`` or ended the process (``os._exit``, a signal, a crash in compiled code): such a
    module is never imported here, so it cannot end the caller with a misleading exit status
    (each finding is kept in `FAILED`, which a forked case reads). Modules already imported
    here, and every module where ``fork`` is missing, are not tried. The child writes to
    /dev/null, runs in a process group of its own that is killed once it is done (with whatever
    the imports started) and dies with this process."""
    known = {m: FAILED[m] for m in modules if m in FAILED}
    todo = [m for m in dict.fromkeys(modules) if m not in sys.modules and m not in FAILED]
    if not todo or not hasattr(os, "fork"):
        return known
    from .executors.parent import die_with_parent
    from .yaml_input import short
    import_methods().load_plugins([])            # the registry the imports add to, inherited
    found: dict = {}
    while todo:
        tried = _try_in_child(todo, die_with_parent, short)
        for mod, why in tried.items():
            if why is not None:
                found[mod] = why
        todo = todo[len(tried):]
    FAILED.update(found)
    return {**known, **found}


def _try_in_child(todo: list, die_with_parent, short) -> dict:
    """``{module: why or None}`` for the modules of ``todo`` tried in one child, in order, up to
    and including the one that ended it."""
    import importlib
    import json
    import select
    import signal
    parent = os.getpid()
    r, w = os.pipe()
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:                                  # the child: never returns
        try:
            os.close(r)
            os.setpgid(0, 0)
            die_with_parent()
            if os.getppid() != parent:
                os._exit(0)
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, 1)
            os.dup2(null, 2)
            for mod in todo:
                os.write(w, (json.dumps([mod]) + "\n").encode())
                try:
                    importlib.import_module(mod)
                    why = None
                except KeyboardInterrupt:      # an interrupt, not the module's failure: the import here says so
                    why = None
                except SystemExit as exc:
                    why = f"it called sys.exit({short(exc.code)}) on import"
                except BaseException as exc:  # noqa: BLE001 - a user's module: its failure is the answer
                    why = f"{type(exc).__name__}: {str(exc)[:500]}"
                os.write(w, (json.dumps([mod, why]) + "\n").encode())
        finally:
            os._exit(0)
    os.close(w)
    buf, status, eof = b"", None, False
    try:
        while True:                               # until it ends (left a zombie: its group id stays its own)
            if not eof and select.select([r], [], [], 0.1)[0]:
                chunk = os.read(r, 65536)
                buf += chunk
                if chunk:
                    continue
                eof = True                        # every writer gone: it is ending, wait for it
            if os.waitid(os.P_PID, pid, os.WEXITED | os.WNOWAIT | (0 if eof else os.WNOHANG)) is not None:
                break
        while select.select([r], [], [], 0)[0] and (chunk := os.read(r, 65536)):
            buf += chunk                          # what it wrote before it ended
    finally:
        os.close(r)
        try:
            os.killpg(pid, signal.SIGKILL)       # what its imports started (and it, when interrupted)
        except (ProcessLookupError, PermissionError):
            pass
        status = os.waitpid(pid, 0)[1]
    tried: dict = {}
    for line in buf.decode(errors="replace").split("\n"):
        try:
            rec = json.loads(line)
            mod, why = rec[0], rec[1] if len(rec) > 1 else _ended(status)
        except (ValueError, TypeError, IndexError, KeyError):
            continue                              # not one of its records (empty, or bytes of the plugin's own)
        if mod in todo:
            tried[mod] = why
    if not tried:                                 # it ended before its first import: no endless retry
        tried[todo[0]] = f"the process trying it ended before importing it ({_ended(status)})"
    return tried


def _ended(status) -> str:
    """How a child that did not finish an import ended, from its wait status."""
    if status is not None and os.WIFSIGNALED(status):
        import signal
        sig = os.WTERMSIG(status)
        try:
            name = signal.Signals(sig).name
        except ValueError:
            name = str(sig)
        return f"importing it killed the process ({name})"
    code = os.WEXITSTATUS(status) if status is not None else None
    return f"importing it ended the process (exit status {code})"
