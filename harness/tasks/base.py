"""What a task kind is: a declared object the registry, runner, compare, report and CLI read.

A task module (one file in ``harness/tasks/``) defines ``TASK = Task(...)``: the result type its
methods return, the parameters every method of the task takes, its metric specs, the function
that measures a result against the case's input, the output mesh it can save, and what the
report needs. Nothing else in the pipeline names a task.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import scipy.sparse as sp

from ..errors import MethodFailed

# the columns every task CSV starts with (no task metric may take one of these names)
COMMON_COLUMNS = ["case_id", "task", "mesh", "n_vertices", "n_faces", "noise_model", "noise_level", "seed",
                  "method", "library", "params", "status", "error", "time_s", "time_min_s", "time_max_s",
                  "time_q1_s", "time_q3_s", "time_cold_s", "repeats", "times", "time_cpu_s", "cpu_times", "others_cpu",
                  "threads_busy", "method_mem_mb", "peak_rss_mb"]
BETTER = ("lower", "higher", "one", "true", "false", "count", "target", "info", "input")


SE_Z = 3.0      # a sampled metric's values differ only beyond SE_Z combined standard errors (`Metric.se`)


def target_tolerance(target: float) -> float:
    """How far a ``target`` metric (a count asked for, `Metric.target`) may miss its target and
    still reach it: 1% of the target + 2."""
    return 0.01 * target + 2


@dataclass(frozen=True)
class Metric:
    """One result column.

    ``better``: ``lower``/``higher`` (numbers), ``one`` (a ratio that should be 1), ``true``/
    ``false`` (the good value of a flag), ``count`` (an integer that may not grow), ``target``
    (a count that should hit a target column), ``info`` (no direction), ``input`` (describes the
    case's input, not the result). ``rel``/``abs``: the compare tolerance, a change counts when
    it exceeds ``max(rel * |a|, abs)``. ``unit``: ``diag`` (fraction of the clean mesh's
    bounding-box diagonal), ``deg``, ``s``, ``MiB`` or empty. ``kind``: ``float``, ``int``,
    ``bool``, ``str`` (a name, for ``info``) or ``json`` (a JSON-encoded list). ``se``: for a sampled metric, the column of its
    standard error: two values also count as the same (compare, ties of the winners) while they
    differ by at most ``SE_Z`` = 3 times their combined standard error ``sqrt(se_a^2 + se_b^2)``,
    and the winners print the value ``± se``. ``se_shared``: the error is over a sample the case
    fixes and every variant of a cell and every seed shares (geodesics' seeded sources):
    comparisons on one sample are paired and exact, so compare, the ties of the winners and the
    leaderboard, and tune ignore it; it is printed as the value's ``±`` alone, over seeds the mean
    of theirs (an upper bound of the mean's error, equal to it when the seeds' errors move
    together, as on a shared sample).
    ``target``: for ``better="target"``, the column holding the count asked for; a result reaches
    it within `target_tolerance`, and compare counts a miss that grows beyond that. ``upper``: for
    a certified bound (``better="lower"``), the column of the upper end of its bracket (the value
    is the lower end, what was found): compare counts a change only when the two brackets lie
    apart beyond the tolerance, so runs measured to other precisions agree where they overlap.
    """

    name: str
    better: str = "info"
    doc: str = ""
    unit: str = ""
    rel: float = 0.01
    abs: float = 0.0
    kind: str = "float"
    rank: bool = False          # offered as a ranking metric in the report
    se: str = ""                # the column of its standard error (a sampled metric), or ""
    se_shared: bool = False     # the error is over a sample every variant and seed of a cell shares
    target: str = ""            # better="target": the column of the count asked for
    upper: str = ""             # a certified bracket's upper end (the value is its lower end)

    def __post_init__(self):
        if self.better not in BETTER:
            raise ValueError(f"metric {self.name}: better must be one of {BETTER}, got {self.better!r}")

    def spec(self) -> dict:
        out = {"name": self.name, "better": self.better, "doc": self.doc, "unit": self.unit,
               "rel": self.rel, "abs": self.abs, "kind": self.kind, "rank": self.rank}
        if self.se:
            out.update(se=self.se, se_z=SE_Z)
            if self.se_shared:
                out["se_shared"] = True
        if self.target:
            out["target"] = self.target
        if self.upper:
            out["upper"] = self.upper
        return out


@dataclass(frozen=True)
class Invalid:
    """A row is not a valid result when ``column`` ``op`` (``==`` or ``>``) ``value``, or, with
    ``than``, when ``column > row[than]`` (e.g. an error above the input's own error), or, with
    ``op`` ``blank``, when the ok row has no value in ``column`` (e.g. a check the result gave
    nothing to make); with ``method``, only that method's rows (e.g. the method that computes the
    reference itself); ``why`` is what the report and leaderboard say. Otherwise blank values
    never match. ``missing``: the
    matching rows are no measurement of the method at all (the reference scored against itself):
    rankings leave the method out instead of ranking it last (`harness.leaderboard.not_measured`);
    the report still hides them as invalid. ``was``: the column an earlier version's rule had in
    place of ``column`` (a run.json from before ``missing`` existed is read with this rule's
    ``missing`` then)."""

    column: str
    op: str
    why: str
    value: Any = None
    than: str | None = None
    method: str | None = None
    missing: bool = False
    was: str | None = None

    def spec(self) -> dict:
        out = {"column": self.column, "op": self.op, "value": self.value, "than": self.than, "why": self.why,
               "method": self.method, "missing": self.missing}
        if self.was:
            out["was"] = self.was
        return out


def rule_ok(r) -> bool:
    """Whether ``r`` is a validity rule as a version writes it (`harness.tasks.base.Invalid.spec`):
    a column, an operator ``==``, ``>`` or ``blank``, a number to compare with for ``>`` unless
    it compares with another column (``than``)."""
    if not (isinstance(r, dict) and isinstance(r.get("column"), str) and r.get("op") in ("==", ">", "blank")):
        return False
    if r.get("than") is not None:
        return isinstance(r["than"], str)
    v = r.get("value")
    return r["op"] != ">" or (isinstance(v, (int, float)) and not isinstance(v, bool))


@dataclass
class CaseInput:
    """What a method is run on and measured against.

    ``clean``: the reference `harness.mesh.Mesh`; ``V``: the input positions (clean plus noise,
    or the given noisy file); ``F``: the faces (``clean.F``); ``diag``: the clean mesh's
    bounding-box diagonal; ``settings``: case-level measurement settings (e.g.
    ``hausdorff_samples``); ``cache``: per-input facts a task may memoise (topology, ...);
    ``shape``: for a procedural mesh the exact surface it samples, ``{"procedural": kind,
    **parameters}`` (e.g. ``{"procedural": "sphere", "subdivisions": 3, "radius": 1.0}``), so a
    task can compute analytic ground truth from the positions; None for files and pairs.
    """

    clean: Any
    V: np.ndarray
    F: np.ndarray
    diag: float
    settings: dict = field(default_factory=dict)
    cache: dict = field(default_factory=dict)
    shape: dict | None = None


@dataclass(frozen=True)
class Task:
    """A task kind. See the module docstring; README "Adding a task kind" walks through one."""

    name: str
    title: str
    intro: str
    result_type: type
    metrics: tuple
    measure: Callable[[CaseInput, Any, dict], dict]
    params: dict = field(default_factory=dict)
    prepare: Callable[[dict, np.ndarray, np.ndarray], dict] | None = None
    check_result: Callable[[Any, np.ndarray, np.ndarray], Any] | None = None
    output_mesh: Callable[[CaseInput, Any], tuple] | None = None
    view: Callable[[CaseInput, Any], list] | None = None
    view_metric: str | None = None
    axis_params: frozenset = frozenset()
    sections: tuple = ()
    order: int = 100            # position in the report and listings
    checks: tuple = ()          # (name, fn(method, V, F)) conformance checks of this task's methods
    invalid_when: tuple = ()    # `Invalid` rules: rows that are not valid results (ranked last, never "best")
    preload: Callable[[], None] | None = None   # warm compiled measuring code in the driver before forking
    input_facts: tuple = ()     # `CaseInput.cache` keys that depend on the input alone (harness.input_store)

    @property
    def columns(self) -> list[str]:
        return [m.name for m in self.metrics]

    def metric(self, name: str) -> Metric | None:
        return next((m for m in self.metrics if m.name == name), None)

    def validate_result(self, name: str, result, V: np.ndarray, F: np.ndarray):
        """The method's result, normalised; `MethodFailed` naming what came back otherwise."""
        if not isinstance(result, self.result_type):
            raise MethodFailed(f"{name} returned {type(result).__name__}, expected {self.result_type.__name__}")
        if self.check_result is None:
            return result
        try:
            return self.check_result(result, V, F)
        except MethodFailed as exc:
            raise MethodFailed(f"{name} {str(exc).lstrip()}") from None

    def measured(self, inp: CaseInput, result, params: dict) -> dict:
        """``measure``'s columns, checked: only declared metrics (a key of a common column or a
        misspelt metric would overwrite or vanish silently), each a scalar (a number, a flag, a
        string or None; an array would be written as its repr). `MethodFailed` otherwise."""
        out = self.measure(inp, result, params)
        if not isinstance(out, dict):
            raise MethodFailed(f"task {self.name!r}: measure returned {type(out).__name__}, expected a dict")
        extra = sorted(str(k) for k in out if k not in set(self.columns))
        if extra:
            raise MethodFailed(f"task {self.name!r}: measure returned {extra}, which are not its declared metrics "
                               f"{self.columns} (a bug in the task's module)")
        for k, v in out.items():
            if not (v is None or isinstance(v, (bool, int, float, str, np.bool_, np.integer, np.floating))):
                shape = f" of shape {np.shape(v)}" if hasattr(v, "shape") else ""
                raise MethodFailed(f"task {self.name!r}: metric {k!r} is a {type(v).__name__}{shape}, not a "
                                   "number, flag or string")
        return out

    def spec(self) -> dict:
        """JSON-ready declaration (written to run.json, read by the report and compare)."""
        return {"name": self.name, "title": self.title, "intro": self.intro,
                "metrics": [m.spec() for m in self.metrics], "view_metric": self.view_metric,
                "axis_params": sorted(self.axis_params), "sections": list(self.sections),
                "params": sorted(self.params), "invalid_when": [r.spec() for r in self.invalid_when],
                "order": self.order}


def assembled_sparse(what: str, A, n: int):
    """``A`` (a method's sparse matrix) as float64 CSR of shape (n, n); `MethodFailed` for anything
    but a CSR, CSC or DIA (``scipy.sparse.diags``) matrix: a dense array, COO triplets or another
    format is refused, as assembling it is the method's work, which converting it here would leave
    out of its timed call; and for another shape or dtype. The conversions done here are linear
    in the stored entries (libigl returns CSC)."""
    if not (sp.issparse(A) and A.format in ("csr", "csc", "dia")):
        raise MethodFailed(f"returned {what} as {type(A).__name__}"
                           + (f" ({A.format})" if sp.issparse(A) else "")
                           + ", expected a scipy sparse CSR or CSC matrix, or DIA (assembled: building it is "
                           "the method's work)")
    if A.dtype.kind != "f":
        raise MethodFailed(f"returned {what} of dtype {A.dtype}, expected float64")
    if A.shape != (n, n):
        raise MethodFailed(f"returned {what} of shape {A.shape}, expected ({n}, {n})")
    return sp.csr_matrix(A).astype(np.float64, copy=False)


def float_array(name: str, what: str, X, shape: tuple) -> np.ndarray:
    """``X`` as float64 of ``shape`` (``-1`` = any length); `MethodFailed` naming what came back.

    Refuses complex, boolean, string and object arrays instead of converting them, and anything
    but a numpy array without touching it (a lazy array computed on conversion would do the
    method's work outside its timed call).
    """
    if not isinstance(X, np.ndarray):
        raise MethodFailed(f"{name} returned {what} as {type(X).__name__}, expected a float64 numpy array")
    if X.dtype.kind != "f":
        raise MethodFailed(f"{name} returned {what} of dtype {X.dtype}, expected float64")
    if X.ndim != len(shape) or any(s != -1 and s != a for s, a in zip(shape, X.shape)):
        want = "(" + ", ".join("k" if s == -1 else str(s) for s in shape) + ")"
        raise MethodFailed(f"{name} returned {what} of shape {X.shape}, expected {want}")
    return np.ascontiguousarray(X, dtype=np.float64)
