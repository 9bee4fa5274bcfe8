"""The one method interface: parameters, result types and the callable `Method`.

A method is a plain function ``func(V, F, **params)`` plus a declaration (name, task,
library, parameters with defaults and bounds, importable modules it needs). The runner
learns everything from the declaration and never special-cases a backend.
"""
from __future__ import annotations

import importlib
import math
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import scipy.sparse as sp

TASKS = ("laplacian", "smoothing", "simplification")


@dataclass
class LaplacianResult:
    """Laplacian in libigl's sign convention.

    ``W``: scipy sparse (n, n); off-diagonal entries are the edge weights (positive where POS
    holds), each row sums to zero. ``M``: diagonal mass matrix (n, n) or None. The pointwise
    operator is ``M^-1 W``.
    """

    W: Any
    M: Any = None


@dataclass
class SmoothingResult:
    """Smoothed vertex positions ``V`` (n, 3), same order as the input; faces unchanged."""

    V: np.ndarray


@dataclass
class SimplificationResult:
    """Simplified mesh: ``V`` (k, 3) float64, ``F`` (l, 3) int."""

    V: np.ndarray
    F: np.ndarray


RESULT_TYPES = {
    "laplacian": LaplacianResult,
    "smoothing": SmoothingResult,
    "simplification": SimplificationResult,
}


@dataclass(frozen=True)
class Param:
    """A declared method parameter.

    ``kind`` is one of ``int``, ``float``, ``bool``, ``str``; ``low``/``high`` are inclusive
    bounds for numbers, ``choices`` the allowed values of a string. ``default=None`` with
    ``optional=True`` means "not given".
    """

    name: str
    default: Any
    kind: str = ""
    low: float | None = None
    high: float | None = None
    choices: tuple | None = None
    doc: str = ""
    optional: bool = False

    def __post_init__(self):
        if not self.kind:
            d = self.default
            kind = ("bool" if isinstance(d, bool) else "int" if isinstance(d, int)
                    else "float" if isinstance(d, float) else "str" if isinstance(d, str) else "")
            if not kind:
                raise TypeError(f"parameter {self.name!r}: give kind= for default {d!r}")
            object.__setattr__(self, "kind", kind)
        if self.choices is not None:
            object.__setattr__(self, "choices", tuple(self.choices))

    def problem(self, value) -> str | None:
        """Return why ``value`` is not acceptable, or None."""
        if value is None and self.optional:
            return None
        k = self.kind
        if k == "bool":
            ok = isinstance(value, (bool, np.bool_))
        elif k == "int":
            ok = isinstance(value, (int, np.integer)) and not isinstance(value, bool)
        elif k == "float":
            ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
        else:
            ok = isinstance(value, str)
        if not ok:
            return f"expected {k}, got {type(value).__name__} {value!r}"
        if k in ("int", "float"):
            if not math.isfinite(float(value)):
                return f"expected a finite number, got {value!r}"
            if self.low is not None and value < self.low:
                return f"must be >= {self.low}, got {value!r}"
            if self.high is not None and value > self.high:
                return f"must be <= {self.high}, got {value!r}"
        if self.choices is not None and value not in self.choices:
            return f"must be one of {list(self.choices)}, got {value!r}"
        return None

    def describe(self) -> str:
        s = f"{self.name}={self.default!r}"
        if self.choices:
            s += f" {{{'|'.join(map(str, self.choices))}}}"
        elif self.low is not None or self.high is not None:
            lo = "-inf" if self.low is None else self.low
            hi = "inf" if self.high is None else self.high
            s += f" [{lo}, {hi}]"
        return s


# Parameters every simplification method takes; the Method wrapper turns them into one
# integer ``target_faces`` before calling the adapter.
SIMPLIFICATION_TARGET_PARAMS = {
    "target_ratio": Param("target_ratio", 0.5, "float", low=1e-6, high=1.0,
                          doc="fraction of input faces to keep (ignored when target_faces is set)"),
    "target_faces": Param("target_faces", None, "int", low=1, optional=True,
                          doc="number of faces to keep; overrides target_ratio"),
}


def target_face_count(n_faces: int, target_ratio: float | None, target_faces: int | None) -> int:
    """Faces asked for: ``target_faces`` if given, else ``round(target_ratio * n_faces)``, >= 1."""
    if target_faces is not None:
        return max(1, int(target_faces))
    return max(1, int(round(float(target_ratio) * n_faces)))


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
    if not np.issubdtype(V.dtype, np.number):
        raise ValueError(f"V must be numeric, got dtype {V.dtype}")
    if not np.issubdtype(F.dtype, np.integer):
        if np.issubdtype(F.dtype, np.floating) and np.all(np.mod(F, 1) == 0):
            F = F.astype(np.int64)
        else:
            raise ValueError(f"F must hold integer indices, got dtype {F.dtype}")
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        idx = np.flatnonzero(bad)
        raise ValueError(f"{idx.size} vertices have NaN or inf coordinates (first: {idx[:5].tolist()})")
    if F.min() < 0 or F.max() >= V.shape[0]:
        raise ValueError(f"face indices out of range [0, {V.shape[0]}): min {F.min()}, max {F.max()}")
    return V, F


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

    @property
    def backend(self) -> str:
        return self.name.split(".", 1)[0]

    def unavailable_reason(self) -> str | None:
        """Why the method cannot run here (a required module fails to import), or None."""
        for mod in self.requires:
            try:
                importlib.import_module(mod)
            except Exception as exc:  # ImportError, or a broken binary wheel
                return f"{self.library}: cannot import {mod!r} ({type(exc).__name__}: {exc})"
        return None

    @property
    def is_available(self) -> bool:
        return self.unavailable_reason() is None

    def param_problems(self, params: dict) -> list[str]:
        """Every problem with ``params`` (unknown names, wrong types, out of range)."""
        out = []
        for k, v in params.items():
            if k not in self.params:
                import difflib
                close = difflib.get_close_matches(k, list(self.params), n=3)
                hint = f" (did you mean {', '.join(close)}?)" if close else ""
                known = ", ".join(self.params) or "none"
                out.append(f"unknown parameter {k!r}{hint}; {self.name} takes: {known}")
                continue
            why = self.params[k].problem(v)
            if why:
                out.append(f"parameter {k!r}: {why}")
        return out

    def resolve_params(self, params: dict) -> dict:
        """Defaults filled in and values checked; raises ValueError listing every problem."""
        problems = self.param_problems(params)
        if problems:
            raise ValueError(f"{self.name}: " + "; ".join(problems))
        full = {k: p.default for k, p in self.params.items()}
        full.update(params)
        return full

    def __call__(self, V, F, **params):
        V, F = check_arrays(V, F)
        full = self.resolve_params(params)
        if self.task == "simplification":
            full["target_faces"] = target_face_count(
                F.shape[0], full.pop("target_ratio"), full.pop("target_faces"))
        result = self.func(V, F, **full)
        expected = RESULT_TYPES[self.task]
        if not isinstance(result, expected):
            raise TypeError(f"{self.name} returned {type(result).__name__}, expected {expected.__name__}")
        if self.task == "laplacian":
            result.W = sp.csr_matrix(result.W)
            if result.M is not None:
                result.M = sp.csr_matrix(result.M)
        return result
