"""The winners of each cell (`winners`, columns `WINNER_COLUMNS`): per task, ranking metric and
cell, the best valid variant, the variants tied with it (within the metric's tolerance of its
mean, or not beaten beyond it on every seed they share) and the runner-up, the best variant
outside that tie.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from .leaderboard_cells import (CELL_SEP, _applies, _cell_seeds, _cells, _mean_se, bracket_rows, cell_values,
                                ranking_metrics, seed_values, tie_groups)
from .leaderboard_validity import tolerance


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
