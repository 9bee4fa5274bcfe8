"""Rankings across meshes: mean ranks, the Friedman test and the Nemenyi critical difference
(Demšar 2006, "Statistical comparisons of classifiers over multiple data sets", JMLR 7).

For each task and each ranking metric (``rank=True`` in the task's declaration), a *cell* is one
(mesh, noise model, noise level) and, for tasks with axis parameters, one value of them (e.g.
simplification's target). In each cell every method variant gets the mean of its metric over
seeds, and the variants are ranked (1 = best, by the metric's declared direction). Values closer
than the metric's declared resolution tie (`tie_groups`: within ``max(rel * |best|, abs)`` of the
best value of their group, ``rel``/``abs`` the compare tolerance of the task's declaration), so a
difference in rounding noise wins nothing; ties get the average rank. Rows that are not valid
results (`validity`: the task's declared ``invalid_when`` rules, e.g. diverged, ended worse than
the noisy input, over the face target, made non-manifold or topology-changing output) rank last
in their cell, tied, and are counted
in ``invalid_cells``; so does a variant whose method failed (error or timeout) on any seed of
the cell, which is not ranked on the seeds it survived. Cells where a variant has no value for
some seed otherwise (not run, unavailable, the metric not measured) are left out of the test
and counted in ``missing_cells``; a variant with no value in any cell (e.g. its library is not
installed) is left out of the ranking altogether instead of emptying it, and a cell where no
valid ok row of the ranked variants has a value, though some exist (the metric does not apply
there: a spectrum without an analytic reference), is no cell of that metric (`_applies`). With N complete cells
and k variants:

- Friedman: ``chi2_F = 12 N / (k (k+1)) [sum_j R_j^2 - k (k+1)^2 / 4] / C``, R_j the mean ranks
  (Demšar eq. 1); ``friedman_p`` by permutation of each cell's ranks (`friedman_permutation_p`,
  with its Monte Carlo standard error), the chi-square approximation with k - 1 degrees of
  freedom in ``friedman_p_chi2`` (conservative for few cells).
  ``C = 1 - sum_ties (t^3 - t) / (N k (k^2 - 1))``, t the size of each group of tied ranks in a
  cell, is the usual correction for ties (Hollander & Wolfe; as in scipy's
  ``friedmanchisquare`` and R's ``friedman.test``): without it the many ties of tolerance and
  invalid results would make p too large. A table where every cell is a full tie gives
  ``chi2_F = 0``, p = 1.
- Nemenyi: two variants differ significantly (alpha = 0.05) when their mean ranks differ by more
  than ``CD = q_0.05 sqrt(k (k+1) / (6 N))``, ``q_0.05`` the studentized range quantile over
  sqrt(2) (Demšar eq. 5). As in Demšar's procedure the post-hoc test applies only where the
  Friedman test rejects (p < alpha): the tables and the report say so and show no difference
  otherwise (``critical_difference`` stays in the CSV, a function of N and k alone).
"""
from __future__ import annotations

import json
import math
import re

import numpy as np
import pandas as pd

COLUMNS = ["task", "metric", "better", "method", "mean_rank", "cells", "missing_cells", "invalid_cells",
           "friedman_chi2", "friedman_p", "critical_difference", "k", "left_out", "friedman_p_se", "friedman_p_chi2"]
LEFT_OUT = ("no measurement in some cells (the reference scored against itself): left out of the ranking, "
            "their other cells are in winners.md")


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


def label_keys(methods, params, axis=(), defaults=None) -> dict[str, list[str]]:
    """Per method, the parameters its variants' labels name: those (other than axis parameters)
    that vary between its rows, and those set away from the method's default (``defaults``:
    ``{method: {param: default}}`` as run.json's task declaration records it), so a label without
    a parameter means that parameter's default."""
    def key(v):
        return json.dumps(v, sort_keys=True, default=str)
    seen: dict[str, dict[str, set]] = {}
    for m, p in zip(methods, params):
        for k, v in p.items():
            if k not in axis:
                seen.setdefault(m, {}).setdefault(k, set()).add(key(v))
    defaults = defaults if isinstance(defaults, dict) else {}
    out = {}
    for m, ks in seen.items():
        d = defaults.get(m) if isinstance(defaults.get(m), dict) else {}
        out[m] = sorted(k for k, vals in ks.items() if len(vals) > 1 or (k in d and vals != {key(d[k])}))
    return out


def label_value(v) -> str:
    """A parameter value in a label: JSON (``true``, ``null``, ``0.25``) as a config writes it;
    text bare where it cannot be read as anything else (``scipy``), quoted where it could
    (``"null"``, ``"3"``, one with a space, ``=`` or quote), so two settings never share a label."""
    if isinstance(v, str):
        bare = v and re.fullmatch(r"[A-Za-z_][A-Za-z0-9_.:/+-]*", v) and v not in ("true", "false", "null", "NaN", "Infinity")
        return v if bare else json.dumps(v)
    return json.dumps(v, sort_keys=True, default=str)


def label_text(method: str, params: dict, keys) -> str:
    """A variant's label: ``method k=v ...`` for the ``keys`` (`label_keys`), values by
    `label_value`. The report, the leaderboard and the winners all label variants this way."""
    return method + "".join(f" {k}={label_value(params.get(k))}" for k in keys)


def params_text(params: dict) -> str:
    """A case's parameters as ``k=v,k=v`` (sorted keys, values by `label_value`, unset ones
    left out): how `shootout compare` and the benchmark JSON name a case's setting."""
    return ",".join(f"{k}={label_value(params[k])}" for k in sorted(params) if params[k] is not None)


def params_of(s) -> dict:
    """A row's ``params`` JSON as a dict ({} when it is blank or not a JSON object)."""
    try:
        p = json.loads(s) if isinstance(s, str) and s else {}
        return p if isinstance(p, dict) else {}
    except json.JSONDecodeError:
        return {}


def variant_labels(df, axis_params=frozenset(), defaults=None) -> list[str]:
    """Method name plus the parameters `label_keys` names: those that vary between this method's
    rows and those set away from its default (axis params excluded); `label_text` writes them.
    The report, the leaderboard and the winners label rows with this one function."""
    ps = [params_of(s) for s in df["params"]] if "params" in df else [{} for _ in range(len(df))]
    keys = label_keys(df["method"], ps, set(axis_params), defaults)
    return [label_text(m, p, keys.get(m, ())) for m, p in zip(df["method"], ps)]


FAILED = ("error", "timeout")     # a method's own failure: ranks last; "unavailable" is not run (missing)
CELL_SEP = "\x1f"                 # joins a cell's mesh, noise, level and setting: a mesh label is free text ('|' too)


def cell_values(spec: dict, df: pd.DataFrame, metric: str, axis_params=(), cells=None):
    """(values, invalid): cells x variants tables of the metric's mean over seeds (ok rows; blank
    when the variant has no value on a seed of the cell: a blank value, or no row at all) and
    of whether a variant's result in the cell is invalid (a seed errored or timed out, or broke a validity rule). Cell labels are
    mesh, noise model, noise level and axis parameters (JSON) joined by `CELL_SEP`. ``cells``: `_cells` of ``df``, when
    already made (it does not depend on the metric)."""
    d = _cells(spec, df, axis_params) if cells is None else cells
    keys = [d["_cell"], d["_variant"]]
    g = _value(d, metric).groupby(keys)
    seed = _seed_text(d)
    own = seed.groupby(keys).nunique()               # a variant with no row on a seed of its cell (a case that
    cell_seeds = _cell_seeds(d)                      # never ran) is blank there too, not a mean over fewer seeds
    all_seeds = own.to_numpy() == cell_seeds.reindex(own.index.get_level_values(0)).to_numpy()
    every_seed = (g.count() == g.size()) & all_seeds  # no mean over the seeds that happen to have a value
    vals = g.mean().where(every_seed).unstack("_variant")
    inval = d["_invalid"].groupby(keys).any().unstack("_variant").reindex_like(vals).fillna(False).astype(bool)
    return vals, inval


def _seed_text(d: pd.DataFrame) -> pd.Series:
    """Each row's noise seed as text ("0" where the frame has no seed column)."""
    return (d["seed"] if "seed" in d else pd.Series(0, index=d.index)).astype(str)


def _cell_seeds(d: pd.DataFrame) -> pd.Series:
    """How many noise seeds each cell's rows have (`_cells` frame), by cell label."""
    return _seed_text(d).groupby(d["_cell"]).nunique()


def seed_values(spec: dict, df: pd.DataFrame, metric: str, axis_params=(), cells=None) -> pd.DataFrame:
    """The metric per seed: (cell, seed) x variants (ok rows; blank otherwise), cells as in
    `cell_values`."""
    d = _cells(spec, df, axis_params) if cells is None else cells
    seed = d["seed"] if "seed" in d else pd.Series(0, index=d.index)
    return pd.DataFrame({"_cell": d["_cell"], "_seed": seed, "_variant": d["_variant"], "_value": _value(d, metric)}
                        ).pivot_table(index=["_cell", "_seed"], columns="_variant", values="_value", aggfunc="mean",
                                      dropna=False)


def _value(d: pd.DataFrame, metric: str) -> pd.Series:
    """The metric of ok rows that are a measurement (blank elsewhere: `not_measured`)."""
    ok = d["status"] == "ok"
    if "_unmeasured" in d:
        ok &= ~d["_unmeasured"].astype(bool)
    return pd.to_numeric(d[metric], errors="coerce").where(ok)


def _cells(spec: dict, df: pd.DataFrame, axis_params=()) -> pd.DataFrame:
    """``df`` with ``_variant``, ``_invalid`` and ``_cell`` (see `cell_values`): the same for
    every metric of the task."""
    d = df.copy()
    d["_variant"] = variant_labels(d, set(axis_params), (spec or {}).get("method_defaults"))
    d["_invalid"] = (validity(spec, d, measured=True) != "") & d["status"].isin(FAILED + ("ok",))
    d["_unmeasured"] = not_measured(spec, d) if "status" in d else False
    ps = [params_of(p) for p in d["params"]]
    text = lambda col: [("" if pd.isna(v) else str(v)) for v in d[col]] if col in d else [""] * len(d)  # noqa: E731
    d["_cell"] = [CELL_SEP.join(t) for t in zip(text("mesh"), text("noise_model"), text("noise_level"),
                                           [json.dumps({k: p.get(k) for k in sorted(axis_params)}) for p in ps])]
    return d


def _mean_se(spec: dict, df: pd.DataFrame, metric: str, axis_params=(), cells=None,
             ties: bool = True) -> pd.DataFrame | None:
    """For a sampled metric (a declared ``se`` column): cells x variants of ``se_z`` times the
    standard error of the metric's mean over the cell's n seeds, ``sqrt(mean(se^2) / n)``, or, for
    an error over a sample the seeds share (``se_shared``), the mean of the seeds' errors (its
    upper bound); else None. ``ties``: for a tie tolerance, which a shared sample's error is not
    (None then: the variants' comparison on the one sample is paired and exact)."""
    m = next((m for m in spec.get("metrics", []) if m.get("name") == metric), {})
    col = m.get("se")
    shared = m.get("se_shared") is True
    if not col or col not in df or (ties and shared):
        return None
    d = (_cells(spec, df, axis_params) if cells is None else cells).copy()
    if shared:
        d["_se"] = pd.to_numeric(d[col], errors="coerce")
        return float(m.get("se_z", 3.0)) * cell_values(spec, d, "_se", axis_params, d)[0]
    d["_se2"] = pd.to_numeric(d[col], errors="coerce") ** 2
    mean_sq, _ = cell_values(spec, d, "_se2", axis_params, d)
    n = _cell_seeds(d).reindex(mean_sq.index).to_numpy(dtype=np.float64)[:, None]
    return float(m.get("se_z", 3.0)) * np.sqrt(mean_sq / n)


def tolerance(spec: dict, metric: str) -> tuple[float, float]:
    """``(rel, abs)``: the compare tolerance the task declares for ``metric`` (defaults 0.01, 0)."""
    for m in spec.get("metrics", []):
        if m.get("name") == metric:
            return float(m.get("rel", 0.01)), float(m.get("abs", 0.0))
    return 0.01, 0.0


def tie_groups(score: np.ndarray, rel: float, abs_: float, se: np.ndarray | None = None,
               top: np.ndarray | None = None) -> np.ndarray:
    """Group ids (0 = best) of ``score`` (lower is better; +inf for invalid results, which all tie
    last). Sorted ascending, a value joins the current group when it lies within
    ``max(rel * |g|, abs_)`` of the group's first (best) value g, or, with ``se`` (each value's
    standard error times ``SE_Z``, a sampled metric), within their combined ``hypot``; else it
    starts the next group: a chain of small steps cannot tie values that differ by more than the
    tolerance. With ``top`` (a certified bracket's upper end of each value, the value its lower
    end: `bracket_rows`), the distance is measured from g's upper end: brackets that overlap, or lie
    within the tolerance of each other, tie, as `harness.compare` judges them."""
    score = np.asarray(score, dtype=np.float64)
    err = np.zeros(len(score)) if se is None else np.nan_to_num(np.asarray(se, dtype=np.float64), nan=0.0)
    up = score if top is None else np.fmax(score, np.nan_to_num(np.asarray(top, dtype=np.float64), nan=-np.inf))
    order = np.argsort(score, kind="stable")
    gid = np.empty(len(score), np.int64)
    g, head, reach, e_head = -1, None, None, 0.0
    for i in order:
        v = score[i]
        if head is None or not (v == head or (np.isfinite(head) and np.isfinite(v) and
                                              v - reach <= max(rel * abs(head), abs_, math.hypot(err[i], e_head)))):
            g, head, reach, e_head = g + 1, v, up[i], err[i]
        gid[i] = g
    return gid


def row_tops(df: pd.DataFrame, metric: str, upper: str) -> pd.Series:
    """Each row's bracket upper end: its ``upper`` column where that is a finite number at or
    above the value (the lower end), else the value (as `harness.compare` reads a row's bracket)."""
    lo, up = pd.to_numeric(df[metric], errors="coerce"), pd.to_numeric(df[upper], errors="coerce")
    return up.where((up >= lo) & np.isfinite(up), lo)


def bracket_rows(spec: dict, df: pd.DataFrame, metric: str, better: str, axis_params=(),
                 cells=None) -> pd.DataFrame | None:
    """For a certified bound (a lower-is-better metric declaring ``upper``, e.g. ``hausdorff`` to
    ``hausdorff_upper``): the `_cells` frame with ``_top``, each row's bracket upper end
    (`row_tops`), whose means `cell_values` (per seed: `seed_values`) give as they give the
    metric's; else None."""
    m = next((m for m in spec.get("metrics", []) if m.get("name") == metric), {})
    col = m.get("upper")
    if better != "lower" or not col or col not in df:
        return None
    d = (_cells(spec, df, axis_params) if cells is None else cells).copy()
    d["_top"] = row_tops(d, metric, col)
    return d


def _tied_rank_row(score: np.ndarray, rel: float, abs_: float, se: np.ndarray | None = None,
                   top: np.ndarray | None = None) -> np.ndarray:
    """Ranks 1..k of one cell's scores, tied within the tolerance (`tie_groups`), average rank per tie."""
    gid = tie_groups(score, rel, abs_, se, top)
    ranks = np.empty(len(score))
    start = 0
    for g in range(int(gid.max()) + 1 if len(gid) else 0):
        members = gid == g
        n = int(members.sum())
        ranks[members] = start + (n + 1) / 2.0
        start += n
    return ranks


def _applies(cells: pd.DataFrame, metric: str, index) -> pd.Series:
    """Per cell of ``index``: whether ``metric`` applies there, i.e. a valid, measured ok row of
    ``cells`` (the `_cells` frame) has a value, or no such row exists (every result failed,
    diverged, was invalid or did not run: "no valid result"). A cell whose valid ok rows all lack
    it (a spectrum on a mesh with no analytic reference) is no cell of the metric's, whatever
    failed there too."""
    ok = (cells["status"] == "ok") & ~cells["_invalid"].astype(bool) & ~cells["_unmeasured"].astype(bool)
    has = (ok & _value(cells, metric).notna()).groupby(cells["_cell"]).any().reindex(index).fillna(False)
    any_ok = ok.groupby(cells["_cell"]).any().reindex(index).fillna(False)
    return has.astype(bool) | ~any_ok.astype(bool)


def cell_ranks(spec: dict, df: pd.DataFrame, metric: str, better: str, axis_params=(), cells=None):
    """(ranks DataFrame cells x variants, missing per variant, invalid per variant, left out); values
    within the metric's tolerance tie (`tie_groups`). A variant that is no measurement in some cell
    (`not_measured`: the reference scored against itself) is left out, as one that never ran
    (counted missing there, it would drop the cell for every method), and named in the sorted
    list ``left out``."""
    if metric not in df or not len(df):
        return pd.DataFrame(), {}, {}, []
    cells = _cells(spec, df, axis_params) if cells is None else cells
    vals, inval = cell_values(spec, df, metric, axis_params, cells)
    gone = set(cells.loc[cells["_unmeasured"].astype(bool), "_variant"])
    vals, inval = vals.loc[:, [v not in gone for v in vals.columns]], inval.loc[:, [v not in gone for v in inval.columns]]
    missing = vals.isna() & ~inval
    ran = ~missing.all(axis=0)             # a variant with no value anywhere (unavailable) is left out
    vals, inval, missing = vals.loc[:, ran], inval.loc[:, ran], missing.loc[:, ran]
    applies = _applies(cells[cells["_variant"].isin(set(vals.columns))], metric, vals.index)   # the ranked variants' rows
    vals, inval, missing = vals.loc[applies], inval.loc[applies], missing.loc[applies]
    complete = vals[~missing.any(axis=1)]
    inv = inval.loc[complete.index]
    sign = -1.0 if better == "higher" else 1.0
    score = (sign * complete).where(~inv, np.inf)
    rel, abs_ = tolerance(spec, metric)
    err = _mean_se(spec, df, metric, axis_params, cells)        # a sampled metric: SE_Z x its cell means' errors
    err = None if err is None else err.reindex(index=score.index, columns=score.columns).to_numpy()
    d = bracket_rows(spec, df, metric, better, axis_params, cells)             # a certified bound's upper ends
    top = (None if d is None else
           cell_values(spec, d, "_top", axis_params, d)[0].reindex(index=score.index, columns=score.columns).to_numpy())
    ranks = pd.DataFrame([_tied_rank_row(r, rel, abs_, None if err is None else err[i], None if top is None else top[i])
                          for i, r in enumerate(score.to_numpy())], index=score.index, columns=score.columns)
    return ranks, missing.sum().to_dict(), inv.sum().to_dict(), sorted(map(str, gone))


WINNER_COLUMNS = ["task", "metric", "better", "mesh", "noise_model", "noise_level", "setting", "best", "value",
                  "tied_with_best", "runner_up", "runner_up_value", "tied_with_runner_up", "input_value", "variants",
                  "invalid_excluded", "seeds", "value_upper", "value_se", "runner_up_upper", "runner_up_se",
                  "not_measured"]


def winners(frames: dict, specs: dict) -> pd.DataFrame:
    """Per task, ranking metric and cell: the best valid variant, the variants tied with it
    (``tied_with_best``, comma-separated: within the metric's tolerance of its mean over seeds,
    `tie_groups`, or, with several seeds, not worse than the best beyond that tolerance on every
    seed they share; for a sampled metric the tolerance on a seed is at least ``SE_Z`` times the
    two values' combined standard error) and the runner-up, the best variant outside that tie (invalid results are excluded and counted in
    ``invalid_excluded``); ``input_value``: the metric of the case's input where the task
    measures it (``input_<metric>``, e.g. smoothing's noisy input), else blank. For a certified
    bound (``hausdorff``), ``value`` is the mean lower end of the brackets and ``value_upper`` the
    mean upper end; for a sampled metric (``surface_dist_mean``), ``value_se`` is the standard
    error of the mean over seeds, ``sqrt(sum se_i^2) / n`` (`_mean_se` over ``se_z``; over a sample
    the seeds share, ``se_shared``, the mean of theirs); the same for the runner-up; blank otherwise."""
    rows = []
    for task, df in frames.items():
        spec = specs.get(task) or {}
        axis = spec.get("axis_params") or ()
        cells = _cells(spec, df, axis) if len(df) else None       # once per task, for every metric
        n_seeds = {} if cells is None else _cell_seeds(cells).to_dict()      # the noise draws each cell's rows have
        gone = ({} if cells is None else cells[cells["_unmeasured"].astype(bool) & (cells["status"] == "ok")]
                .groupby("_cell")["_variant"].agg(lambda v: ", ".join(sorted(set(map(str, v))))).to_dict())
        for m in ranking_metrics(spec):
            if m["name"] not in df or not len(df):
                continue
            vals, inval = cell_values(spec, df, m["name"], axis, cells)
            applies = _applies(cells, m["name"], vals.index) if cells is not None else None
            per_seed = seed_values(spec, df, m["name"], axis, cells)
            se_col = m.get("se")                  # a sampled metric: its standard error per seed (ties)
            per_seed_se = (seed_values(spec, df, se_col, axis, cells)
                           if se_col and se_col in df and m.get("se_shared") is not True else None)
            se_z = float(m.get("se_z", 3.0))
            errs = _mean_se(spec, df, m["name"], axis, cells, ties=False)   # se_z x each mean's error (printed)
            d = bracket_rows(spec, df, m["name"], m["better"], axis, cells)         # a certified bound's upper ends
            tops = None if d is None else cell_values(spec, d, "_top", axis, d)[0]
            seed_tops = None if d is None else seed_values(spec, d, "_top", axis, d)
            rel, abs_ = tolerance(spec, m["name"])
            given = f"input_{m['name']}"
            inputs = (cell_values(spec, df, given, axis, cells)[0].mean(axis=1) if given in df
                      else pd.Series(dtype=float))
            for cell, v in vals.iterrows():
                iv = inputs.get(cell)
                iv = None if iv is None or pd.isna(iv) else float(iv)
                ok = v[~inval.loc[cell] & v.notna()]
                mesh, noise, level, setting = cell.split(CELL_SEP, 3)
                if ok.empty:
                    if inval.loc[cell].any() and (applies is None or applies.loc[cell]):   # every result invalid: said
                        rows.append({"task": task, "metric": m["name"], "better": m["better"], "mesh": mesh,
                                     "noise_model": noise, "noise_level": level,
                                     "setting": "" if setting == "{}" else setting, "best": "", "value": None,
                                     "tied_with_best": "", "runner_up": "", "runner_up_value": None,
                                     "tied_with_runner_up": "", "input_value": iv,
                                     "variants": int(v.notna().sum()), "invalid_excluded": int(inval.loc[cell].sum()),
                                     "seeds": int(n_seeds.get(cell, 1)), "value_upper": None, "value_se": None,
                                     "runner_up_upper": None, "runner_up_se": None, "not_measured": gone.get(cell, "")})
                    continue
                order = ok.sort_values(ascending=m["better"] == "lower", kind="stable")
                sign = -1.0 if m["better"] == "higher" else 1.0
                S = per_seed.loc[cell] if cell in per_seed.index.get_level_values(0) else None
                E = (se_z * per_seed_se.loc[cell] if S is not None and per_seed_se is not None
                     and cell in per_seed_se.index.get_level_values(0) else None)
                err = None if errs is None or cell not in errs.index else errs.loc[cell] / se_z
                T = (seed_tops.loc[cell] if S is not None and seed_tops is not None
                     and cell in seed_tops.index.get_level_values(0) else None)
                S = None if S is None else (S, E, T)
                top = None if tops is None else tops.loc[cell]
                tie = _tied_with_first(order, S, sign, rel, abs_, top)
                rest = order[[v for v in order.index[1:] if v not in tie]]
                second = _tied_with_first(rest, S, sign, rel, abs_, top) if len(rest) else []
                first, up = order.index[0], (rest.index[0] if len(rest) else None)
                rows.append({"task": task, "metric": m["name"], "better": m["better"], "mesh": mesh,
                             "noise_model": noise, "noise_level": level, "setting": "" if setting == "{}" else setting,
                             "value_upper": _at(top, first), "runner_up_upper": _at(top, up),
                             "value_se": _at(err, first), "runner_up_se": _at(err, up),
                             "best": order.index[0], "value": float(order.iloc[0]),
                             "tied_with_best": ", ".join(str(x) for x in tie),
                             "runner_up": rest.index[0] if len(rest) else "",
                             "tied_with_runner_up": ", ".join(str(x) for x in second),
                             "runner_up_value": float(rest.iloc[0]) if len(rest) else None, "input_value": iv,
                             "variants": int(v.notna().sum()), "invalid_excluded": int(inval.loc[cell].sum()),
                             "seeds": int(n_seeds.get(cell, 1)), "not_measured": gone.get(cell, "")})
    return pd.DataFrame(rows, columns=WINNER_COLUMNS)


def _at(values: pd.Series | None, variant) -> float | None:
    """``values[variant]`` as a float, None where absent or blank."""
    if values is None or variant is None or variant not in values.index or pd.isna(values[variant]):
        return None
    return float(values[variant])


def _tied_with_first(order: pd.Series, S, sign: float, rel: float, abs_: float, top: pd.Series | None = None) -> list:
    """The variants of ``order`` (sorted, best first) tied with its first: within the tolerance
    of its mean (`tie_groups`; ``top``: the variants' bracket upper ends, `bracket_rows`) or,
    with several seeds (``S``), not beaten on every seed."""
    gid = tie_groups(sign * order.to_numpy(), rel, abs_, None,
                     None if top is None else top.reindex(order.index).to_numpy(dtype=np.float64))
    return [v for v, g in zip(order.index[1:], gid[1:])
            if g == 0 or not _beaten_on_every_seed(S, order.index[0], v, sign, rel, abs_)]


def _beaten_on_every_seed(S, best, other, sign: float, rel: float, abs_: float) -> bool:
    """Whether ``best`` is better than ``other`` beyond the tolerance on every seed both have
    (``S``: seeds x variants, or ``(values, E, T)`` with, for a sampled metric, ``E`` ``SE_Z``
    times its standard errors, which widen the tolerance to ``SE_Z sqrt(se_a^2 + se_b^2)`` where
    larger, and, for a certified bound, ``T`` the brackets' upper ends: ``other``'s lower end
    must lie beyond ``best``'s upper end); True without a shared seed (the means decide)."""
    S, E, T = S if isinstance(S, tuple) else (S, None, None)
    if S is None or best not in S or other not in S:
        return True
    a, b = S[best], S[other]
    both = a.notna() & b.notna()
    if not both.any():
        return True
    reach = a if T is None or best not in T else np.fmax(a, T[best].reindex(a.index))
    gap = sign * (b[both] - reach[both])
    tol = np.maximum(rel * a[both].abs(), abs_)
    if E is not None and best in E and other in E:
        ea, eb = E[best].reindex(a.index)[both], E[other].reindex(a.index)[both]
        tol = np.maximum(tol, np.hypot(ea, eb).fillna(0.0))
    return bool((gap > tol).all())


def noise_label(model, level) -> str:
    """A noise cell's label, as every output prints it: ``no noise``, ``gaussian_normal 0.3``."""
    if model in (None, "none") or (isinstance(model, float) and math.isnan(model)):
        return "no noise"
    if level is None or (isinstance(level, float) and math.isnan(level)):
        return str(model)
    try:
        return f"{model} {float(level):g}"
    except (TypeError, ValueError):
        return f"{model} {level}"


def _best(r) -> str:
    """The best variant, and those tied with it ("no valid result" where every result is invalid)."""
    if pd.isna(r.best) or not str(r.best):
        return "no valid result"
    tied = "" if pd.isna(r.tied_with_best) else str(r.tied_with_best)
    return f"{r.best} (tied: {tied})" if tied else str(r.best)


def _runner_up(r) -> str:
    """The runner-up, and those tied with it."""
    tied = "" if pd.isna(r.tied_with_runner_up) else str(r.tied_with_runner_up)
    return f"{r.runner_up} (tied: {tied})" if tied and str(r.runner_up) else ("" if pd.isna(r.runner_up) else str(r.runner_up))


def _g(x) -> str:
    return "" if x is None or pd.isna(x) else format(x, ".4g")


def _val(x, upper=None, se=None) -> str:
    """A winner's value as printed: ``[lower, upper]`` for a certified bracket whose ends differ
    at 4 digits, ``value ± se`` for a sampled metric, else the value (4 significant digits)."""
    text = _g(x)
    if text and upper is not None and not pd.isna(upper) and _g(upper) != text:
        return f"[{text}, {_g(upper)}]"
    if text and se is not None and not pd.isna(se):
        return f"{text} ± {format(se, '.2g')}"
    return text


SHARED_SE_NOTE = ("± its standard error over the sample every method of the cell shares (e.g. the sources: another "
                  "sample could move the values; the methods compare on this one, so ties ignore it), over seeds the "
                  "mean of theirs")


def _shared_se(specs: dict | None, task: str, metric: str) -> bool:
    """Whether ``metric`` of ``task`` declares an error over a shared sample (``se_shared``), by
    ``specs`` or else the installed task kind."""
    spec = (specs or {}).get(task)
    if spec is None:
        spec = _installed_spec(task)
    m = next((m for m in spec.get("metrics", []) if m.get("name") == metric), {})
    return m.get("se_shared") is True


def winners_markdown(w: pd.DataFrame, specs: dict | None = None) -> str:
    """winners.md from `winners`' frame; ``specs`` (the tasks' declarations) word the captions."""
    out = []
    for (task, metric), g in w.groupby(["task", "metric"], sort=False):
        inp = g["input_value"].notna().any()          # the input's own value, where the task measures it
        out.append(f"### {task}: best by {metric} ({g.iloc[0].better} is better)\n\n"
                   "| mesh | noise | setting | best | value | runner-up | value |" + (" input |" if inp else "") +
                   " invalid excluded |\n|---|---|---|---|---:|---|---:|" + ("---:|" if inp else "") + "---:|")
        out += [f"| {_md(r.mesh)} | {_md(noise_label(r.noise_model, r.noise_level))} | {_md(setting_text(r.setting))} | {_md(_best(r))} | "
                f"{_val(r.value, getattr(r, 'value_upper', None), getattr(r, 'value_se', None))} | "
                f"{_md(_runner_up(r))} | "
                f"{_val(r.runner_up_value, getattr(r, 'runner_up_upper', None), getattr(r, 'runner_up_se', None))} |"
                + (f" {_g(r.input_value)} |" if inp else "") + f" {r.invalid_excluded} |"
                for r in g.itertuples()]
        if _carries(g, "upper"):
            out.append(f"\n{metric}: the lower end of a certified bracket; [lower, upper] where the two differ "
                       "at 4 digits (means over seeds).")
        if _carries(g, "se"):
            out.append(f"\n{metric}: {SHARED_SE_NOTE}." if _shared_se(specs, task, metric) else
                       f"\n{metric}: a sampled estimate ± its standard error (of the mean over seeds).")
        if inp:
            out.append(f"\ninput: {metric} of the case's input itself; a result worse than it made the input worse.")
        out.append(_not_measured_note(g))
        out.append(_seeds_note(g))
        out.append("")
    return "\n".join(out)


def _not_measured_note(g: pd.DataFrame) -> str:
    """The variants left out of cells as no measurement there (`not_measured`), named, with in how
    many of the cells: neither among the variants nor the invalid ones."""
    if "not_measured" not in g:
        return ""
    names = [n for s in g["not_measured"] if isinstance(s, str) for n in s.split(", ") if n]   # blank: NaN from a CSV
    if not names:
        return ""
    counts = pd.Series(names).value_counts(sort=False)
    said = "; ".join(f"{k} ({v} of {len(g)} cells)" for k, v in counts.items())
    return f"\nLeft out as no measurement of the method (the task's rules: e.g. the reference scored against itself): {said}."


def _seeds_note(g: pd.DataFrame) -> str:
    """What the cells' winners rest on: how many noise draws (seeds), said plainly when one."""
    noisy = g[g["noise_model"].astype(str) != "none"]
    if not len(noisy) or "seeds" not in noisy:
        return ""
    n = pd.to_numeric(noisy["seeds"], errors="coerce").dropna()
    if not len(n):
        return ""
    lo, hi = int(n.min()), int(n.max())
    said = f"{lo}" if lo == hi else f"{lo}-{hi}"
    one = (" A winner from one seed is one noise draw's: another draw may name another method (run more seeds, "
           "`noise: [{..., seeds: N}]`).") if lo == 1 else ""
    return f"\nNoisy cells rest on {said} noise seed(s) each.{one}"


def _carries(g: pd.DataFrame, kind: str) -> bool:
    """Whether some winners row of ``g`` carries a bracket upper end (``kind`` ``upper``) or a
    standard error (``se``) for its value or its runner-up's (a caption then says so)."""
    cols = [c for c in (f"value_{kind}", f"runner_up_{kind}") if c in g]
    return bool(g[cols].notna().any(axis=None))


def _tex_val(r, which: str) -> str:
    """`_val` of a winners row's ``value`` or ``runner_up`` value, in LaTeX."""
    v = r.value if which == "value" else r.runner_up_value
    return _val(v, getattr(r, f"{which}_upper", None), getattr(r, f"{which}_se", None)).replace(" ± ", r" $\pm$ ")


def winners_latex(w: pd.DataFrame, specs: dict | None = None) -> str:
    """winners.tex from `winners`' frame; ``specs`` (the tasks' declarations) word the captions."""
    out = ["% mesh-shootout winners per cell; needs \\usepackage{booktabs} and \\usepackage{graphicx}"]
    for (task, metric), g in w.groupby(["task", "metric"], sort=False):
        inp = g["input_value"].notna().any()          # the input's own value, where the task measures it
        out += [r"\begin{table}[t]", r"\centering", FIT, r"\begin{tabular}{llllrlr" + ("r" if inp else "") + "}",
                r"\toprule", r"mesh & noise & setting & best & value & runner-up & value" + (" & input" if inp else "")
                + r" \\", r"\midrule"]
        out += [f"{_tex(r.mesh)} & {_tex(noise_label(r.noise_model, r.noise_level))} & {_tex(setting_text(r.setting))} & {_tex(_best(r))} & "
                f"{_tex_val(r, 'value')} & {_tex(_runner_up(r))} & {_tex_val(r, 'runner_up')}"
                + (f" & {_g(r.input_value)}" if inp else "") + " \\\\" for r in g.itertuples()]
        said = (f"; input: \\texttt{{{_tex(metric)}}} of the case's input itself (a result worse than it made the "
                "input worse)") if inp else ""
        if _carries(g, "upper"):
            said += "; values are the lower ends of certified brackets, [lower, upper] where the two differ at 4 digits"
        if _carries(g, "se"):
            said += (r"; values $\pm$ their standard errors over the sample every method of the cell shares "
                     r"(ties ignore them; over seeds the mean of theirs)" if _shared_se(specs, task, metric) else
                     r"; sampled estimates $\pm$ their standard errors")
        gone = _not_measured_note(g).strip()
        if gone:
            said += "; " + _tex(gone[0].lower() + gone[1:].rstrip("."))
        out += [r"\bottomrule", r"\end{tabular}}",
                f"\\caption{{{_tex(task)}: best valid method per cell by \\texttt{{{_tex(metric)}}} ({g.iloc[0].better} is "
                f"better); invalid results excluded{said}.}}", r"\end{table}", ""]
    return "\n".join(out)


def friedman_nemenyi(ranks: pd.DataFrame, alpha: float = 0.05) -> tuple[float | None, float | None, float | None]:
    """(chi2_F, p, critical difference) of a cells x variants rank table (Demšar 2006)."""
    from scipy.special import chdtrc
    N, k = ranks.shape
    if N < 2 or k < 2:
        return None, None, None
    R = ranks.mean(axis=0).to_numpy()
    chi2 = 12.0 * N / (k * (k + 1)) * (np.sum(R ** 2) - k * (k + 1) ** 2 / 4.0)
    ties = sum(float(np.sum(t ** 3 - t)) for t in (np.unique(row, return_counts=True)[1].astype(float)
                                                     for row in ranks.to_numpy()))
    correction = 1.0 - ties / (N * k * (k * k - 1.0))
    if correction <= 1e-12:                  # every cell a full tie: no evidence of any difference
        return 0.0, 1.0, _critical_difference(N, k, alpha)
    chi2 = max(chi2 / correction, 0.0)
    p = float(chdtrc(k - 1, chi2))                       # the chi-square survival function
    return float(chi2), p, _critical_difference(N, k, alpha)


PERMUTATIONS = 20000              # draws of the Friedman permutation test (fewer for very large tables)


def friedman_permutation_p(ranks: pd.DataFrame, draws: int = PERMUTATIONS, seed: int = 0) -> tuple[float | None, float | None]:
    """``(p, its Monte Carlo standard error)`` of the Friedman test by permutation: under the null
    hypothesis the ranks within each cell are exchangeable, so each cell's row of ranks (its ties
    kept) is shuffled independently, ``draws`` times (seeded: the same table gives the same p),
    and ``p = (1 + #{S >= S_obs}) / (draws + 1)``, ``S = sum_j R_j^2`` (chi2_F up to constants
    that permutations keep, the tie correction included), with standard error
    ``sqrt(p (1 - p) / draws)``. Unlike the chi-square approximation (conservative for few cells:
    0.055 where this gives 0.043 on 6 cells x 6 methods) it needs no large N. ``draws`` shrinks
    to keep ``draws x N x k`` at most 4e7 (at least 2,000). None for one cell or one variant."""
    X = ranks.to_numpy(dtype=np.float64)
    N, k = X.shape
    if N < 2 or k < 2:
        return None, None
    draws = int(max(2000, min(draws, 4e7 // (N * k))))
    obs = float(np.sum(X.mean(axis=0) ** 2))
    rng = np.random.default_rng(seed)
    hits, done, batch = 0, 0, max(1, int(2e6 // (N * k)))
    while done < draws:
        b = min(batch, draws - done)
        P = rng.permuted(np.broadcast_to(X, (b, N, k)), axis=2)
        S = np.sum(P.mean(axis=1) ** 2, axis=1)
        hits += int(np.count_nonzero(S >= obs * (1 - 1e-12)))    # an equal statistic counts (rounding of the sums)
        done += b
    p = (1 + hits) / (draws + 1)
    return float(p), float(math.sqrt(p * (1 - p) / draws))


def _critical_difference(N: int, k: int, alpha: float) -> float:
    """Nemenyi's critical difference ``q_alpha sqrt(k (k + 1) / (6 N))``, ``q_alpha`` the
    ``1 - alpha`` quantile of the range of ``k`` standard normals over sqrt(2)."""
    return range_quantile(1 - alpha, k) / math.sqrt(2.0) * math.sqrt(k * (k + 1) / (6.0 * N))


def _range_cdf(q: float, k: int) -> float:
    """P(range of k iid standard normals <= q) = k int phi(z) (Phi(z + q) - Phi(z))^(k-1) dz
    (the studentized range with infinite degrees of freedom), by the trapezoidal rule on
    [-9, 9] at step 0.005: the integrand is smooth and below 1e-17 outside."""
    from scipy.special import ndtr
    z = np.linspace(-9.0, 9.0, 3601)
    f = np.exp(-z * z / 2) / math.sqrt(2 * math.pi) * (ndtr(z + q) - ndtr(z)) ** (k - 1)
    return k * float(np.trapezoid(f, z))


def range_quantile(p: float, k: int) -> float:
    """The ``p`` quantile of the range of ``k`` iid standard normals (bisection on `_range_cdf`
    to 1e-13; equal to ``scipy.stats.studentized_range.ppf(p, k, inf)`` to 1e-12 relative for
    k up to 2000 and 1 - p >= 1e-4 (1e-10 to 3e-8 at 1 - p = 1e-8), without importing
    scipy.stats, which costs a run 0.4-0.8 s)."""
    lo, hi = 0.0, 1.0
    while _range_cdf(hi, k) < p and hi < 64.0:   # past 64 the CDF is 1 in float64: p that close to 1 ends there
        hi *= 2.0
    while hi - lo > 1e-13 * hi:
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if _range_cdf(mid, k) < p else (lo, mid)
    return (lo + hi) / 2


def leaderboard(frames: dict, specs: dict) -> pd.DataFrame:
    """One row per (task, ranking metric, variant): see `COLUMNS` and the module docstring."""
    rows = []
    for task, df in frames.items():
        spec = specs.get(task) or {}
        axis = spec.get("axis_params") or ()
        cells = _cells(spec, df, axis) if len(df) else None       # once per task, for every metric
        for m in ranking_metrics(spec):
            ranks, missing, invalid, gone = cell_ranks(spec, df, m["name"], m["better"], axis, cells)
            if ranks.empty:
                continue
            chi2, p_chi2, cd = friedman_nemenyi(ranks)
            p, p_se = friedman_permutation_p(ranks)
            for v, r in sorted(ranks.mean(axis=0).items(), key=lambda x: (x[1], str(x[0]))):   # ties: by name
                rows.append({"task": task, "metric": m["name"], "better": m["better"], "method": v,
                             "mean_rank": float(r), "cells": int(len(ranks)), "missing_cells": int(missing.get(v, 0)),
                             "invalid_cells": int(invalid.get(v, 0)), "friedman_chi2": chi2, "friedman_p": p,
                             "critical_difference": cd, "k": int(ranks.shape[1]), "left_out": ", ".join(gone),
                             "friedman_p_se": p_se, "friedman_p_chi2": p_chi2})
    return pd.DataFrame(rows, columns=COLUMNS)


ALPHA = 0.05                      # the level of the Friedman test and of the Nemenyi post-hoc test


def cd_applies(p, cd) -> bool:
    """Whether the Nemenyi critical difference may be read: the Friedman test rejected at `ALPHA`."""
    return not (p is None or pd.isna(p) or cd is None or pd.isna(cd)) and float(p) < ALPHA


def friedman_p_text(r0, num=lambda x, d: f"{x:.{d}g}", pm: str = "±") -> str:
    """``p = 0.043 ± 0.0014`` (the Friedman permutation p and its Monte Carlo standard error), or
    ``p < 0.00015`` when no permutation reached the observed statistic (3 / draws: the 95% upper
    bound of a rate never seen in that many draws); ``num(x, digits)`` formats a number."""
    p, se = float(r0.friedman_p), getattr(r0, "friedman_p_se", None)
    if se is None or pd.isna(se) or not se > 0:
        return f"p = {num(p, 2)}"
    draws = p * (1 - p) / se ** 2
    if p * (draws + 1) < 1.5:                  # no hit: p is 1 / (draws + 1)
        return f"p < {num(3.0 / draws, 2)}"
    return f"p = {num(p, 2)} {pm} {num(se, 1)}"


def _cd_text(r0, dash: str) -> str:
    if pd.isna(r0.critical_difference):
        return dash
    if pd.isna(r0.friedman_p):
        return "not applied (no Friedman test: one cell or one method)"
    if not cd_applies(r0.friedman_p, r0.critical_difference):
        return f"not applied (Friedman p >= {ALPHA:g}: no pair is shown to differ)"
    return f"{r0.critical_difference:.2f}"


def to_markdown(lb: pd.DataFrame) -> str:
    out = []
    for (task, metric), g in lb.groupby(["task", "metric"], sort=False):
        r0 = g.iloc[0]
        p = "p = —" if pd.isna(r0.friedman_p) else friedman_p_text(r0)
        cd = _cd_text(r0, "—")
        out.append(f"### {task}: {metric} ({r0.better} is better)\n\n{int(r0.cells)} cell{'' if int(r0.cells) == 1 else 's'}, Friedman {p}, "
                   f"Nemenyi critical difference (alpha 0.05) = {cd}\n\n| method | mean rank | missing | invalid |\n"
                   "|---|---:|---:|---:|")
        out += [f"| {_md(r.method)} | {_rank(r.mean_rank)} | {r.missing_cells} | {r.invalid_cells} |" for r in g.itertuples()]
        gone = getattr(r0, "left_out", "")
        if isinstance(gone, str) and gone:
            out.append(f"\nLeft out: {_md(gone)}: {LEFT_OUT}.")
        out.append("")
    return "\n".join(out)


def _md(s) -> str:
    """A table cell's text for Markdown: ``|`` escaped (it ends a cell), ``<`` ``>`` ``&`` as HTML
    entities (Markdown renderers pass raw HTML through; a mesh's file stem is free text), a line
    break as ``<br>`` (it ends the table row)."""
    t = str(s).replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace("|", "\\|")
    return t.replace("\r\n", "<br>").replace("\n", "<br>").replace("\r", "<br>")


def _rank(x: float) -> str:
    """A mean rank to 2 decimals, a half rounded up (2.125 is 2.13), as the report's
    ``toFixed(2)`` prints it (Python's format rounds a half to even: 2.12)."""
    from decimal import ROUND_HALF_UP, Decimal
    return str(Decimal(float(x)).quantize(Decimal("0.01"), rounding=ROUND_HALF_UP))


def _tex_num(x: float, digits: int = 2) -> str:
    """``x`` to ``digits`` significant digits for LaTeX math: ``1.5 \\times 10^{-5}``, not ``1.5e-05``."""
    t = f"{float(x):.{digits}g}"
    if "e" not in t:
        return t
    m, e = t.split("e")
    return f"{m} \\times 10^{{{int(e)}}}"


def _tex(s: str) -> str:
    """Text for a LaTeX table cell, in OT1 (pdflatex's default, which prints ``<`` ``>`` ``|``
    ``"`` as other glyphs) or T1: the special characters escaped, those four as text symbols,
    the characters of TeX's ligatures (``--`` an en dash, ``''`` a closing quote, ``!``` an
    inverted exclamation mark, T1's ``,,``) kept apart by empty groups, and a leading ``[`` or
    ``*`` behind ``{}`` (after ``\\\\`` or ``\\midrule`` it would be read as their argument).
    Characters outside LaTeX's UTF-8 tables (e.g. CJK) need xelatex or lualatex."""
    out = "".join({"_": r"\_", "&": r"\&", "%": r"\%", "#": r"\#", "$": r"\$", "{": r"\{", "}": r"\}",
                    "~": r"\textasciitilde{}", "^": r"\textasciicircum{}", "\\": r"\textbackslash{}",
                    "<": r"\textless{}", ">": r"\textgreater{}", "|": r"\textbar{}", '"': r"\texttt{\char34}",
                    "-": "-{}", "`": "{}`{}", "'": "'{}", ",": ",{}",   # no ligature: -- ``  '' !` ?` ,,
                    "\n": " ", "\r": " "}.get(c, c)           # a blank line would end the tabular's paragraph
                  for c in str(s))
    return "{}" + out if out[:1] in ("[", "*") else out


FIT = r"\resizebox{\ifdim\width>\linewidth\linewidth\else\width\fi}{!}{%"   # shrink a table wider than the text only


def setting_text(setting) -> str:
    """A cell's setting (the axis parameters as JSON) as ``k=v`` pairs (`params_text`), unset ones
    left out: ``target_ratio=0.1``, not ``{"target_faces": null, "target_ratio": 0.1}``."""
    try:
        d = json.loads(setting) if isinstance(setting, str) and setting else {}
    except json.JSONDecodeError:
        return str(setting)
    return params_text(d) if isinstance(d, dict) else str(setting)


def to_latex(lb: pd.DataFrame) -> str:
    """booktabs tables, one per (task, metric)."""
    out = ["% mesh-shootout leaderboard; needs \\usepackage{booktabs} and \\usepackage{graphicx}"]
    for (task, metric), g in lb.groupby(["task", "metric"], sort=False):
        r0 = g.iloc[0]
        p = ("no Friedman test" if pd.isna(r0.friedman_p) else
             "Friedman $" + friedman_p_text(r0, lambda x, d: _tex_num(x, d), r"\pm") + "$ (permutation test)")
        gone = getattr(r0, "left_out", "")
        cd = _cd_text(r0, "--").replace(">=", r"$\geq$")
        out += [r"\begin{table}[t]", r"\centering", FIT, r"\begin{tabular}{lrrr}", r"\toprule",
                r"method & mean rank & missing & invalid \\", r"\midrule"]
        out += [f"{_tex(r.method)} & {_rank(r.mean_rank)} & {r.missing_cells} & {r.invalid_cells} \\\\"
                for r in g.itertuples()]
        out += [r"\bottomrule", r"\end{tabular}}",
                f"\\caption{{{_tex(task)}: mean rank by \\texttt{{{_tex(metric)}}} ({r0.better} is better) over "
                f"{int(r0.cells)} cell{'' if int(r0.cells) == 1 else 's'}; {p}, Nemenyi CD$_{{0.05}}$: {cd}."
                + (f" Left out: {_tex(gone)}: {_tex(LEFT_OUT)}." if isinstance(gone, str) and gone else "") + "}",
                r"\end{table}", ""]
    return "\n".join(out)


def ranking_metrics(spec: dict) -> list[dict]:
    """The task's ranking metrics: declared ``rank`` with a direction (lower or higher is better)."""
    return [m for m in spec.get("metrics", []) if m.get("rank") and m.get("better") in ("lower", "higher")]


def no_ranking_text(frames: dict, specs: dict) -> str:
    """Why a run ranks nothing: per task, its ranking metrics and whether any row has a value in one."""
    why = []
    for task in sorted(frames):
        names = [m["name"] for m in ranking_metrics(specs.get(task) or {})]
        df = frames[task]
        if not names:
            why.append(f"{task} declares no ranking metric (it reports properties)")
        else:
            listed = ", ".join(names)
            why.append(f"{task} has no value in {listed}" if not any(n in df and df[n].notna().any() for n in names)
                       else f"{task}: no cell compares two or more methods on {listed}")
    return f"No ranking: {'; '.join(why) or 'no results'}."


def settings_note(tune) -> str:
    """What the ranked variants are: the settings the config gave (defaults where it gave none),
    not each method at its best, and which ones ``tune:`` chose (``tune``: run.json's ``tune``)."""
    chosen, kept = [], []
    if isinstance(tune, dict) and isinstance(tune.get("methods"), dict):
        for m, ch in tune["methods"].items():
            picked = ch.get("chosen") if isinstance(ch, dict) else None
            if isinstance(picked, dict) and picked:
                chosen.append(f"{m} {label_text('', picked, sorted(picked)).strip()}")
            else:
                kept.append(str(m))
    said = ("Each method is ranked at the parameters the config gave it, its defaults where it gave none: a "
            "ranking of these settings, not of each method at its best.")
    if chosen:
        said += (" Tuned on the training meshes (tune:), each a variant of its own beside the configured one: "
                 + "; ".join(chosen) + ".")
    if kept:
        said += (" Tuned, no candidate beating the configured setting on the training meshes (kept): "
                 + ", ".join(kept) + ".")
    if not chosen and not kept:
        said += " Nothing was tuned (tune: chooses parameters on training meshes)."
    return said


def write(run_dir, frames: dict, specs: dict) -> pd.DataFrame:
    """``leaderboard.csv|md|tex`` and ``winners.csv|md|tex`` in the run folder; the ``.md`` files
    open with `settings_note`."""
    from pathlib import Path
    lb = leaderboard(frames, specs)
    d = Path(run_dir)
    from .results import atomic_write
    none = no_ranking_text(frames, specs) + " See report.html.\n"
    w = winners(frames, specs)
    try:
        import json
        tune = json.loads((d / "run.json").read_text(encoding="utf-8")).get("tune")
    except (OSError, ValueError, AttributeError):
        tune = None
    note = settings_note(tune) + "\n\n"
    lb_md, w_md = to_markdown(lb), winners_markdown(w, specs)
    for name, text in (("leaderboard.csv", lb.to_csv(index=False)), ("leaderboard.md", note + lb_md if lb_md else none),
                       ("leaderboard.tex", to_latex(lb)), ("winners.csv", w.to_csv(index=False)),
                       ("winners.md", note + w_md if w_md else none), ("winners.tex", winners_latex(w, specs))):
        atomic_write(d / name, lambda fh, text=text: fh.write(text))      # never a half-written table
    return lb
