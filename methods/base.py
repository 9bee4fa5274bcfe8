"""The one method interface: the callable `Method` and input validation.

A method is a plain function ``func(V, F, **params)`` plus a declaration (name, task, library,
parameters with defaults and bounds, importable modules it needs). What a task's methods take
and return is declared by the task (`harness.tasks`); the runner learns everything from the two
declarations and never special-cases a backend or a task.
"""
from __future__ import annotations

import difflib
import importlib
import re
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from harness import tasks as _tasks
from harness.core.params import Param  # noqa: F401  (re-exported: methods.Param)
from harness.errors import MethodFailed


def check_arrays(V, F) -> tuple[np.ndarray, np.ndarray]:
    """Validate and normalise a triangle mesh: V float64 (n, 3) finite, F int64 (m, 3) in range.

    Raises ValueError with the reason.
    """
    V = np.asarray(V)
    F = np.asarray(F)
    if V.ndim != 2 or V.shape[1] != 3:
        raise ValueError(f"V must have shape (n, 3), got {V.shape}")
    if F.ndim != 2 or F.shape[1] != 3:
        raise ValueError(f"F must have shape (m, 3) (triangles), got {F.shape}")
    if V.shape[0] == 0 or F.shape[0] == 0:
        raise ValueError(f"empty mesh: {V.shape[0]} vertices, {F.shape[0]} faces")
    if not np.issubdtype(V.dtype, np.number) or np.iscomplexobj(V):
        raise ValueError(f"V must be real numbers, got dtype {V.dtype}")
    if not np.issubdtype(F.dtype, np.integer):
        if np.issubdtype(F.dtype, np.floating) and np.all(np.mod(F, 1) == 0):
            F = F.astype(np.int64)
        else:
            raise ValueError(f"F must hold integer indices, got dtype {F.dtype}")
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    if not np.isfinite(V).all():            # (a row-wise all() is 30x slower: only on failure)
        idx = np.flatnonzero(~np.isfinite(V).all(axis=1))
        raise ValueError(f"{idx.size} vertices have NaN or inf coordinates (first: {idx[:5].tolist()})")
    if F.min() < 0 or F.max() >= V.shape[0]:
        raise ValueError(f"face indices out of range [0, {V.shape[0]}): min {F.min()}, max {F.max()}")
    return V, F


# Other names of a declared parameter, accepted from Python and in configs and recorded under the
# declared one: a Python keyword (lambda), and a library's own spelling of a concept that has one
# name across adapters (fast-simplification's agg and preserve_border, meshoptimizer's lock_border,
# MeshLab's fit_iterations for Sun et al.'s vertex iterations)
ALIASES = {"lam": "lambda", "agg": "aggressiveness", "preserve_border": "preserve_boundary",
           "lock_border": "preserve_boundary", "fit_iterations": "vertex_iterations"}
# names an adapter once took with another meaning: refused, naming the one to give (a config
# written for the old name must not run another setting)
RENAMED = {"sigma_r": "normal_sigma", "sigma_s": "spatial_multiple"}


@dataclass(frozen=True)
class Method:
    """A registered method: call it as ``method(V, F, **params)``."""

    name: str
    task: str
    library: str
    func: Callable = field(repr=False, compare=False)
    params: dict = field(default_factory=dict)
    requires: tuple = ()
    doc: str = ""
    cite: str = ""
    expected_failures: dict = field(default_factory=dict, compare=False)
    extra: str = ""             # optional-dependency extra that installs its library ("" = default install)
    precheck: Callable | None = field(default=None, repr=False, compare=False)
    setting_check: Callable | None = field(default=None, repr=False, compare=False)   # full params -> problem or None

    @property
    def backend(self) -> str:
        return self.name.split(".", 1)[0]

    @property
    def summary(self) -> str:
        """The docstring's first sentence as one line (it may wrap over lines): up to the first
        full stop (not of "e.g.", "i.e.", "et al.", "vs.") followed by a capital or a quote, else the
        first paragraph."""
        para = " ".join(self.doc.strip().split("\n\n", 1)[0].split())
        m = re.match(r"(.+?(?<!\be\.g)(?<!\bi\.e)(?<!\bet al)(?<!\bvs)[.!?])\s+(?=[A-Z`'\"(])", para)
        return m.group(1) if m else para

    def unavailable_reason(self) -> str | None:
        """Why the method cannot run here (a required module fails to import), or None."""
        for mod in self.requires:
            try:
                importlib.import_module(mod)
            except Exception as exc:  # ImportError, or a broken binary wheel
                hint = f"; optional: pip install -e '.[{self.extra}]' in the mesh-shootout checkout" if self.extra else ""
                return f"{self.library}: cannot import {mod!r} ({type(exc).__name__}: {exc}){hint}"
        return None

    @property
    def is_available(self) -> bool:
        return self.unavailable_reason() is None

    def param_problems(self, params: dict) -> list[str]:
        """Every problem with ``params`` (unknown names, wrong types, out of range)."""
        out = []
        for k, v in params.items():
            if k not in self.params:
                close = difflib.get_close_matches(str(k), list(self.params), n=3)
                hint = f" (did you mean {', '.join(close)}?)" if close else ""
                if RENAMED.get(k) in self.params:
                    hint = f" (renamed, with another meaning than before: give {RENAMED[k]})"
                known = ", ".join(self.params) or "none"
                out.append(f"unknown parameter {k!r}{hint}; {self.name} takes: {known}")
                continue
            why = self.params[k].problem(v)
            if why:
                out.append(f"parameter {k!r}: {why}")
        return out

    def setting_problem(self, params: dict) -> str | None:
        """What is wrong with a whole setting (values that are each fine but not together, e.g. a
        parameter the chosen variant ignores), by the method's ``setting_check``; None if nothing."""
        if self.setting_check is None:
            return None
        try:
            return self.setting_check(self.with_defaults(params))
        except Exception as exc:  # noqa: BLE001 - a plugin's check that fails refuses the setting, naming why
            return f"its setting_check failed on this setting ({type(exc).__name__}: {exc})"

    def canonical(self, params: dict) -> tuple[dict, list[str]]:
        """``params`` with each alias (`ALIASES`) of a declared parameter under the declared name,
        and the problems of two names of one parameter given together (an alias and the declared
        name, or two aliases)."""
        alias = lambda k: ALIASES.get(k) in self.params and k not in self.params   # noqa: E731
        names: dict = {}
        for k in params:
            names.setdefault(ALIASES[k] if alias(k) else k, []).append(k)
        both = [" and ".join(ks) + ": the same parameter given twice" for ks in names.values() if len(ks) > 1]
        return {ALIASES[k] if alias(k) else k: v for k, v in params.items()}, both

    def resolve_params(self, params: dict) -> dict:
        """Defaults filled in and values checked; raises ValueError listing every problem."""
        params, both = self.canonical(params)
        problems = both + self.param_problems(params)
        if not problems:
            why = self.setting_problem(params)
            problems = [why] if why else []
        if problems:
            raise ValueError(f"{self.name}: " + "; ".join(problems))
        return self.with_defaults(params)

    def with_defaults(self, params: dict) -> dict:
        """``params`` with the declared defaults filled in (no validation); numpy scalars become
        Python ones and integers given for a float parameter floats: equal settings, equal case
        ids (and a setting a run can record as JSON)."""
        full = {k: p.default for k, p in self.params.items()}
        full.update(params)
        for k, p in self.params.items():
            v = full.get(k)
            if isinstance(v, np.generic):
                full[k] = v = v.item()
            if p.kind == "float" and isinstance(v, int) and not isinstance(v, bool):
                full[k] = float(v)
            full[k] = p.normalised(full[k])
        return full

    def bind(self, V, F, **params) -> tuple[Callable[[], object], Callable[[object], object]]:
        """The call in two parts, ``(run, finish)``: the mesh checked (`check_arrays`, then the
        method's own ``precheck`` of input its library cannot take) and the parameters resolved
        (and prepared by the task) now; ``run()`` calls the adapter alone,
        ``finish(result)`` validates and normalises what it returned (the task's
        ``validate_result``). ``method(V, F, **params)`` is ``finish(run())``; the runner times
        ``run()`` only, so the harness's checks are never part of a method's time."""
        V, F = check_arrays(V, F)
        if self.precheck is not None:
            self.precheck(V, F, self.name)
        full = self.resolve_params(params)
        task = _tasks.get(self.task)
        if task.prepare is not None:
            full = task.prepare(full, V, F)
        return (lambda: self.func(V, F, **full)), (lambda result: task.validate_result(self.name, result, V, F))

    def __call__(self, V, F, **params):
        """``finish(run())`` of `bind`, on copies of the caller's arrays wherever `check_arrays`
        may have kept their memory (a numpy array, a memoryview, an object numpy reads in place):
        a method that writes into its input, or returns it, never changes or shares the caller's."""
        V0, F0 = V, F
        V, F = check_arrays(V, F)                  # copies where they may still be the caller's memory
        shared = lambda X, X0: not isinstance(X0, (list, tuple)) and np.may_share_memory(X, np.asarray(X0))  # noqa: E731
        V = V.copy() if shared(V, V0) else V
        F = F.copy() if shared(F, F0) else F
        run, finish = self.bind(V, F, **params)
        return finish(run())


__all__ = ["Method", "Param", "MethodFailed", "check_arrays", "ALIASES"]
