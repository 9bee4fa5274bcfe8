"""Which result rows are valid results and which are no measurement: a task's declared
``invalid_when`` rules (`harness.tasks.base.Invalid`) applied to its rows (`validity`,
`not_measured`), a rule against another column beyond the metric's compare tolerance
(`tolerance`: ``max(rel * |other|, abs)``), and the rules of a run.json written before rules or
their ``missing`` key were recorded read as the installed task kind declares them now.
"""
from __future__ import annotations

import numpy as np
import pandas as pd


def _truthy(v):
    if isinstance(v, str):
        return {"true": True, "false": False}.get(v.strip().lower(), v)
    return v


def validity(spec: dict, df: pd.DataFrame, measured: bool = False) -> pd.Series:
    """Why each row is not a valid result ('' when it is): status not ok, or the first of the
    task's declared ``invalid_when`` rules (`harness.tasks.base.Invalid`) that matches; a rule
    against another column (``than``) matches only beyond the metric's compare tolerance
    (``max(rel * |other|, abs)``), so rounding noise does not decide validity. ``measured``:
    leave out the rules that mark a row as no measurement (``missing``, `not_measured`)."""
    why = pd.Series([""] * len(df), index=df.index, dtype=object)
    for rule, hit in _rule_hits(spec, df, why):
        if not (measured and rule.get("missing")):
            why[hit & (why == "")] = rule.get("why") or rule.get("column")
    return why


def _installed_spec(name) -> dict:
    """The declaration of the installed task kind ``name`` (`harness.tasks.base.Task.spec`), or
    {} when no such kind is installed."""
    from . import tasks
    try:
        return tasks.get(name or "").spec()
    except KeyError:
        return {}


def _with_current_missing(spec: dict, rule: dict) -> dict:
    """``rule`` with ``missing`` as the task declares it now, where a run.json written before
    rules had the key recorded it without (the same column, operator, value and method)."""
    if not isinstance(rule, dict) or "missing" in rule:
        return rule
    now = _installed_spec((spec or {}).get("name")).get("invalid_when")
    if now is None:
        return rule
    same = ("op", "value", "method", "than")
    match = next((r for r in now if rule.get("column") in (r.get("column"), r.get("was"))
                  and all(r.get(k) == rule.get(k) for k in same)), None)
    return {**rule, "missing": bool(match and match.get("missing"))}


def not_measured(spec: dict, df: pd.DataFrame) -> pd.Series:
    """Whether each ok row matches a ``missing`` rule of the task's ``invalid_when``: its values
    are no measurement of the method (e.g. the reference method scored against itself), so
    rankings count them as missing, neither as a result nor as an invalid one."""
    out = pd.Series(False, index=df.index)
    for rule, hit in _rule_hits(spec, df, pd.Series([""] * len(df), index=df.index, dtype=object)):
        if rule.get("missing"):
            out |= hit
    return out


def _rule_hits(spec: dict, df: pd.DataFrame, why: pd.Series):
    """``(rule, hit)`` for each ``invalid_when`` rule, ``hit`` the ok rows it matches; fills
    ``why`` with the status of rows that are not ok."""
    if "status" not in df:
        return
    ok = df["status"] == "ok"
    why[~ok] = "status " + df.loc[~ok, "status"].astype(str)
    rules = (spec or {}).get("invalid_when")
    if rules is None:                        # a run folder written before tasks declared their rules
        rules = _installed_spec((spec or {}).get("name")).get("invalid_when", [])
    for rule in rules:
        rule = _with_current_missing(spec, rule)
        col = rule.get("column")
        if col not in df and rule.get("was") in df:      # a CSV from before the column: the rule's old one
            rule = {**rule, "column": rule["was"]}
            col = rule["column"]
        if col not in df:
            continue
        if rule.get("than"):
            if rule["than"] not in df:
                continue
            a, b = pd.to_numeric(df[col], errors="coerce"), pd.to_numeric(df[rule["than"]], errors="coerce")
            rel, abs_ = tolerance(spec or {}, col)      # beyond the metric's own resolution, as compare
            hit = (a > b + np.maximum(rel * b.abs(), abs_)).fillna(False)
        elif rule.get("op") == "blank":
            hit = pd.to_numeric(df[col], errors="coerce").isna()
        elif rule.get("op") == ">":
            hit = (pd.to_numeric(df[col], errors="coerce") > float(rule["value"])).fillna(False)
        else:
            hit = df[col].map(_truthy).map(lambda v, want=rule.get("value"): v == want and not pd.isna(v))
        if rule.get("method"):
            hit = hit.astype(bool) & (df["method"] == rule["method"] if "method" in df else False)
        yield rule, ok & hit.astype(bool)


def tolerance(spec: dict, metric: str) -> tuple[float, float]:
    """``(rel, abs)``: the compare tolerance the task declares for ``metric`` (defaults 0.01, 0)."""
    for m in spec.get("metrics", []):
        if m.get("name") == metric:
            return float(m.get("rel", 0.01)), float(m.get("abs", 0.0))
    return 0.01, 0.0
