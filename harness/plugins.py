"""Importing the method registry, with a clear message when a user's own module shadows it."""
from __future__ import annotations

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
