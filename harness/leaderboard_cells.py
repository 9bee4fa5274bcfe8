"""The cells of a ranking (see `harness.leaderboard`): per (mesh, noise model, noise level, axis
setting) and variant, a metric's mean over seeds (`cell_values`, per seed `seed_values`) and
whether the variant's result there is invalid; the ties within a metric's tolerance, widened by
the standard errors of a sampled metric and measured from a certified bracket's upper end
(`tie_groups`); and each cell's ranks, 1 = best, ties at their average rank (`cell_ranks`).
"""
from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd

from .leaderboard_labels import params_of, variant_labels
from .leaderboard_validity import not_measured, tolerance, validity


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
    """Each row's noise seed as text ("0" where the frame has no seed column, "" where the row has
    none: a scored file's, `shootout eval`; pandas keeps a blank as NaN through ``astype(str)``,
    and ``nunique`` counted such a cell's seeds as 0, its standard errors as infinite)."""
    if "seed" not in d:
        return pd.Series("0", index=d.index)
    return pd.Series(["" if pd.isna(v) else str(v) for v in d["seed"]], index=d.index, dtype=object)


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


def ranking_metrics(spec: dict) -> list[dict]:
    """The task's ranking metrics: declared ``rank`` with a direction (lower or higher is better)."""
    return [m for m in spec.get("metrics", []) if m.get("rank") and m.get("better") in ("lower", "higher")]
