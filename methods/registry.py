"""The method registry: built-ins (every module below `methods`), entry points, plugins.

Built-in methods are discovered by importing every submodule of the `methods` package (a
backend module imports its library lazily, so a missing library makes its methods
`unavailable` instead of breaking this import). Third-party methods register through the
entry-point group ``mesh_shootout.methods`` or a module named under ``plugins:`` in a config.
"""
from __future__ import annotations

import dataclasses

import difflib
import functools
import importlib
import os
import pkgutil
from importlib.metadata import entry_points

from harness import tasks as _tasks

from .base import Method, Param

ENTRY_POINT_GROUP = "mesh_shootout.methods"
_REGISTRY: dict[str, Method] = {}
_LOADED = False
_SKIP = {"methods.base", "methods.registry", "methods.vocabulary", "methods.checks"}
# modules (built-in or entry point) that failed to import: name -> reason. A broken backend
# module costs its own methods, not the registry; `shootout methods` and the tests show it.
BROKEN: dict[str, str] = {}


def register(name: str, *, task: str, library: str, params: dict | None = None,
             requires: tuple | list | None = None, doc: str | None = None, cite: str = "",
             expected_failures: dict | None = None, extra: str = "", precheck=None, setting_check=None):
    """Decorator registering ``func(V, F, **params)`` as method ``name``.

    ``params`` maps each parameter name to its default or to a `Param` (bounds, choices).
    ``requires`` lists importable modules the method needs (availability check).
    The task's shared parameters (e.g. simplification's ``target_ratio``/``target_faces``) are
    added automatically; the task's ``prepare`` decides what the function receives.
    ``cite``: the paper or documentation the method follows (shown by ``shootout methods``).
    ``expected_failures``: ``{check name: why}`` for conformance checks (`methods.checks`) the
    method is known to fail. ``extra``: the optional-dependency extra of mesh-shootout that
    installs its library (not in the default install; without it the method is unavailable).
    ``precheck(V, F, name)``: raises ValueError for an input the library cannot take (e.g.
    zero-area faces for libigl's cotangents); run with the harness's own checks, untimed, before
    every call, so a method's time is its library's alone. The decorator then returns the
    function wrapped so that a direct call screens too (``Method.func`` stays the bare function,
    which the runner times). ``setting_check(params)``: given a whole setting (defaults filled
    in), the reason it is refused (values fine alone but not together) or None; a config with
    such a setting is refused when it loads, and a direct call raises.
    """
    if task not in _tasks.names():
        raise ValueError(f"register({name!r}): task must be one of {_tasks.names()}, got {task!r}")
    if "." not in name:
        raise ValueError(f"register({name!r}): name must be '<backend>.<method>'")

    def deco(func):
        if not str(getattr(func, "__module__", "")).startswith("methods."):
            _load_builtins()           # a plugin imported first must not take a built-in's name
        if name in _REGISTRY:
            raise ValueError(f"method {name!r} is already registered "
                             f"(by {_REGISTRY[name].func.__module__})")
        declared = {}
        for k, v in (params or {}).items():
            # a shared Param (e.g. `methods.vocabulary.solver_param`) takes the key it is declared
            # under: listings, errors and the run's rows all name the parameter the user passes
            declared[k] = (v if v.name == k else dataclasses.replace(v, name=k)) if isinstance(v, Param) else Param(k, v)
        problems = _signature_problems(func, declared)
        if problems:
            raise ValueError(f"register({name!r}): " + "; ".join(problems))
        declared = {**_tasks.get(task).params, **declared}
        _REGISTRY[name] = Method(name=name, task=task, library=library, func=func,
                                 params=declared, requires=tuple(requires or ()),
                                 doc=(doc or (func.__doc__ or "")).strip(), cite=cite,
                                 expected_failures=dict(expected_failures or {}), extra=extra,
                                 precheck=precheck, setting_check=setting_check)
        if precheck is None and setting_check is None:
            return func
        method = _REGISTRY[name]

        @functools.wraps(func)
        def checked(V, F, *args, **kwargs):          # a direct call of the function screens too
            if precheck is not None:
                precheck(V, F, name)
            why = method.setting_problem(kwargs)
            if why:
                raise ValueError(f"{name}: {why}")
            return func(V, F, *args, **kwargs)
        return checked

    return deco


def _signature_problems(func, declared: dict) -> list[str]:
    """What would make every call of ``func`` with its declared parameters fail: a parameter it
    does not take as a keyword (nor through ``**kwargs``), or a default its own bounds refuse."""
    import inspect
    try:
        sig = inspect.signature(func)
    except (TypeError, ValueError):
        return []
    ps = sig.parameters
    keyword_ok = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in ps.values())
    P = [f"the function does not take parameter {k!r} as a keyword" for k in declared
         if not keyword_ok and (k not in ps or ps[k].kind not in (inspect.Parameter.KEYWORD_ONLY,
                                                                   inspect.Parameter.POSITIONAL_OR_KEYWORD))]
    P += [f"the default of {k!r} is refused by its own declaration: {p.problem(p.default)}"
          for k, p in declared.items() if not (p.default is None and p.optional) and p.problem(p.default)]
    return P


def _load_builtins() -> None:
    global _LOADED
    if _LOADED:
        return
    _LOADED = True
    import methods
    for info in pkgutil.walk_packages(methods.__path__, prefix="methods.", onerror=_onerror):
        if info.name not in _SKIP:
            try:
                importlib.import_module(info.name)
            except Exception as exc:  # noqa: BLE001 - recorded and shown, never swallowed silently
                BROKEN[info.name] = f"{type(exc).__name__}: {exc}"
    eps = list(entry_points(group=ENTRY_POINT_GROUP))
    if eps:                          # an installed package's modules: tried in another process first, as plugins
        from harness.trial import import_failure, import_problems
        found = import_problems([ep.module for ep in eps])
    for ep in eps:
        label = f"entry point {ep.name} ({ep.value})"
        if ep.module in found:       # it raised, exited or ended the process trying it: not imported here
            BROKEN[label] = found[ep.module]
            continue
        try:
            with _same_cwd():
                obj = ep.load()
                if callable(obj) and not isinstance(obj, type(importlib)):
                    obj()
        except (Exception, SystemExit) as exc:  # noqa: BLE001 - an installed package's code: its failure is shown
            BROKEN[label] = import_failure(exc)


def _onerror(name):
    BROKEN[name] = "package failed to import"


class _same_cwd:
    """The working directory as it was, after a user's module is imported: one that changes it
    at import would otherwise move every relative path of the run (its folder, ``results/``)."""

    def __enter__(self):
        try:
            self.cwd = os.getcwd()
        except OSError:                  # already gone: nothing to go back to
            self.cwd = None

    def __exit__(self, *exc):
        if self.cwd is not None:
            try:
                os.chdir(self.cwd)
            except OSError:              # removed meanwhile: there is no going back
                pass


def load_plugins(modules) -> None:
    """Import plugin modules (they register methods as a side effect); the working directory is
    kept (`_same_cwd`)."""
    _load_builtins()
    for mod in modules or ():
        with _same_cwd():
            importlib.import_module(mod)


def all_methods(task: str | None = None) -> list[Method]:
    """Every registered method (available or not), sorted by name; of one task kind where
    ``task`` names one (an unknown kind is a KeyError naming the known ones)."""
    if task is not None and task not in _tasks.names():
        close = difflib.get_close_matches(str(task), _tasks.names(), n=3, cutoff=0.5)
        raise KeyError(f"unknown task {task!r}" + (f"; did you mean {', '.join(close)}?" if close else "")
                       + f" (task kinds: {', '.join(_tasks.names())})")
    _load_builtins()
    return sorted((m for m in _REGISTRY.values() if task is None or m.task == task),
                  key=lambda m: m.name)


def available(task: str | None = None) -> list[str]:
    """Names of registered methods whose libraries import here."""
    return [m.name for m in all_methods(task) if m.is_available]


def get(name: str, task: str | None = None) -> Method:
    """The method called ``name``; KeyError naming the close matches when unknown (among the
    methods of ``task`` where given, else among all)."""
    _load_builtins()
    try:
        return _REGISTRY[name]
    except KeyError:
        pool = [k for k, m in _REGISTRY.items() if task is None or m.task == task]
        close = difflib.get_close_matches(str(name), pool, n=3, cutoff=0.5)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        eps = [f"{k}: {v}" for k, v in BROKEN.items()]
        if eps:                        # the method may live in a module that failed
            hint += f" (not imported: {'; '.join(eps)})"
        raise KeyError(f"unknown method {name!r}{hint}") from None
