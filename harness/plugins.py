"""Importing the method registry, with a clear message when a user's own module shadows it, and
trying a user's plugin modules in a child process before they are imported here."""
from __future__ import annotations

import sys
from pathlib import Path

from . import trial as _trial
from .errors import ShootoutError
from .trial import import_failure

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


def import_plugins(modules) -> dict:
    """Import ``modules`` into the method registry, each tried first in another process
    (`import_problems`), and ``{module: why}`` for those that failed there or here
    (`import_failure`), in their order."""
    methods = import_methods()
    found = import_problems(modules)
    failed: dict = {}
    for mod in dict.fromkeys(modules):
        if mod not in found:
            try:
                methods.load_plugins([mod])
                continue
            except (Exception, SystemExit) as exc:   # a user's module: its failure is the answer
                found[mod] = import_failure(exc)
        failed[mod] = found[mod]
    return failed


def import_problems(modules) -> dict:
    """`harness.trial.import_problems` for plugin modules: the registry is loaded first, so a
    forked trial adds to it as the run would."""
    return _trial.import_problems(modules, prepare=lambda: import_methods().load_plugins([]))
