"""The compare rule of each metric and the verdict on one metric's pair of values.

A `Rule` is a metric's declared direction (``better``: lower, higher, one, true, false, count,
target; info and input compare only for a change) and its tolerance ``max(rel * |a|, abs)``,
widened for a sampled metric to ``se_z`` combined standard errors and, for a certified bracket,
to the two brackets' gap. The rules come from the task declarations a run.json records
(`rules_from_specs`), else from the installed task kinds (``KNOWN``, ``RULES``). `judge` gives
'regression', 'improvement', 'changed' or 'same' for one metric of one case; the rules
themselves are stated in `harness.compare`'s docstring.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .tasks.base import target_tolerance
from .schema import number as _num


@dataclass(frozen=True)
class Rule:
    kind: str            # lower | higher | one | true | false | count | target | info | input
    rel: float = 0.01
    abs: float = 0.0
    se: str = ""         # a sampled metric's standard-error column (`harness.tasks.base.Metric`)
    se_z: float = 3.0
    target: str = ""     # kind target: the column of the count asked for (`Metric.target`)
    upper: str = ""      # a certified bracket's upper end (`Metric.upper`)


COMMON_RULES = {"n_vertices": Rule("input"), "n_faces": Rule("input"), "peak_rss_mb": Rule("info")}


def _rule(m: dict) -> Rule | None:
    """The compare rule a metric's declaration (run.json) gives, or None for one that is not a
    declaration this version could have written (an unknown direction, a tolerance that is not a
    finite number >= 0): the installed kind's rule is used instead."""
    from .tasks.base import BETTER
    try:
        r = Rule(m.get("better", "info"), float(m.get("rel", 0.01)), float(m.get("abs", 0.0)),
                 "" if m.get("se_shared") is True else str(m.get("se") or ""),   # a shared sample: paired, exact
                 float(m.get("se_z", 3.0)), str(m.get("target") or ""),
                 str(m.get("upper") or ""))
    except (AttributeError, TypeError, ValueError):
        return None
    ok = r.kind in BETTER and all(math.isfinite(x) and x >= 0 for x in (r.rel, r.abs, r.se_z))
    return r if ok else None


def rules_from_specs(specs: dict) -> dict[str, dict[str, Rule]]:
    """``{task: {metric: Rule}}`` from task declarations (run.json's ``tasks``); a declaration
    that is not one (`_rule`) is left out, and the installed kind's rule applies."""
    out = {}
    for task, spec in (specs or {}).items():
        metrics = spec.get("metrics") if isinstance(spec, dict) else None
        if not isinstance(metrics, list):
            continue
        rules = {m["name"]: _rule(m) for m in metrics if isinstance(m, dict) and isinstance(m.get("name"), str)}
        out[task] = {k: r for k, r in rules.items() if r is not None}
    return out


def _known_rules() -> dict[str, dict[str, Rule]]:
    from . import tasks
    return rules_from_specs({n: t.spec() for n, t in tasks.all_tasks().items()})


KNOWN = _known_rules()
# metric -> rule over every known task (used when a row's task is not given)
RULES: dict[str, Rule] = {**{m: r for t in KNOWN.values() for m, r in t.items()}, **COMMON_RULES}


def rule_for(metric: str, task: str | None = None, rules: dict | None = None) -> Rule:
    """The compare rule of ``metric`` in ``task`` (from ``rules``, else the known tasks)."""
    for source in (rules or {}, KNOWN):
        r = source.get(task, {}).get(metric) if task else None
        if r is not None:
            return r
    return RULES.get(metric, Rule("info"))


def _blank(v) -> bool:
    return v is None or (isinstance(v, float) and math.isnan(v)) or v == ""


def judge(metric: str, a, b, row_a=None, row_b=None, rule: Rule | None = None) -> str:
    """'regression' | 'improvement' | 'changed' (beyond tolerance, no direction) | 'same' (within it).
    The tolerance is ``max(rel * |a|, abs)``, and for a sampled metric (``rule.se``) at least
    ``se_z`` times the two rows' combined standard error."""
    rule = rule or rule_for(metric, (row_b or row_a or {}).get("task"))
    if _blank(a) and _blank(b):
        return "same"
    if rule.kind in ("info", "input"):
        if _blank(a) != _blank(b):
            return "changed"
        x, y = _num(a), _num(b)
        if x is not None and y is not None:
            return "same" if abs(x - y) <= 1e-12 * max(abs(x), abs(y), 1.0) else "changed"
        return "same" if str(a) == str(b) else "changed"
    if _blank(b):
        return "regression"
    if _blank(a):
        return "improvement"
    if rule.kind in ("true", "false"):
        good = rule.kind == "true"
        va, vb = bool(a), bool(b)
        if va == vb:
            return "same"
        return "regression" if va == good else "improvement"
    x, y = _num(a), _num(b)
    if x is None or y is None:
        return "same" if str(a) == str(b) else "changed"
    if rule.kind == "count":
        return "same" if x == y else ("regression" if y > x else "improvement")
    if rule.kind == "target":
        t = _num((row_b or {}).get(rule.target)) if rule.target else None
        if t is None:
            return "same" if x == y else "changed"
        miss_a, miss_b = abs(x - t), abs(y - t)
        tol = target_tolerance(t)
        if miss_b > miss_a + tol:
            return "regression"
        return "improvement" if miss_b < miss_a - tol else "same"
    if rule.kind == "one":
        x, y = abs(x - 1.0), abs(y - 1.0)
    if not (math.isfinite(x) and math.isfinite(y)):   # an infinity: its order decides (no tolerance of it)
        if x == y:
            return "same"
        return "regression" if (y > x) == (rule.kind in ("lower", "one")) else "improvement"
    tol = max(rule.rel * abs(x), rule.abs)
    if rule.se:                  # a sampled metric: within SE_Z combined standard errors is the same
        sa, sb = _num((row_a or {}).get(rule.se)), _num((row_b or {}).get(rule.se))
        if sa is not None and sb is not None and math.isfinite(sa) and math.isfinite(sb):
            tol = max(tol, rule.se_z * math.hypot(sa, sb))
    if rule.upper and rule.kind == "lower":     # certified brackets [x, x_up], [y, y_up]: apart, or the same
        xu, yu = _upper(x, (row_a or {}).get(rule.upper)), _upper(y, (row_b or {}).get(rule.upper))
        if y - xu > tol:
            return "regression"
        return "improvement" if x - yu > tol else "same"
    worse = (y - x) if rule.kind in ("lower", "one") else (x - y)
    if worse > tol:
        return "regression"
    if worse < -tol:
        return "improvement"
    return "same"


def _upper(lo: float, up) -> float:
    """A bracket's upper end: the row's ``up`` where it is a finite number at or above ``lo``,
    else ``lo`` (no bracket)."""
    u = _num(up)
    return u if u is not None and math.isfinite(u) and u >= lo else lo
