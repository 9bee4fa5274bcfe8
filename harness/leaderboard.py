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

import pandas as pd

from .leaderboard_cells import (CELL_SEP, FAILED, _cells, _tied_rank_row, bracket_rows, cell_ranks,  # noqa: F401
                                cell_values, ranking_metrics, row_tops, seed_values, tie_groups)
from .leaderboard_labels import (label_keys, label_text, label_value, noise_label, params_of,  # noqa: F401
                                 params_text, setting_text, variant_labels)
from .leaderboard_stats import PERMUTATIONS, friedman_nemenyi, friedman_permutation_p, range_quantile  # noqa: F401
from .leaderboard_tables import (ALPHA, FIT, LEFT_OUT, SHARED_SE_NOTE, _rank, _tex, cd_applies,  # noqa: F401
                                 friedman_p_text, to_latex, to_markdown, winners_latex, winners_markdown)
from .leaderboard_validity import not_measured, tolerance, validity  # noqa: F401
from .leaderboard_winners import WINNER_COLUMNS, winners  # noqa: F401

__all__ = ["ALPHA", "CELL_SEP", "COLUMNS", "FAILED", "FIT", "LEFT_OUT", "PERMUTATIONS", "SHARED_SE_NOTE", "WINNER_COLUMNS",
           "bracket_rows", "cd_applies", "cell_ranks", "cell_values", "friedman_nemenyi", "friedman_p_text",
           "friedman_permutation_p", "label_keys", "label_text", "label_value", "leaderboard", "no_ranking_text",
           "noise_label", "not_measured", "params_of", "params_text", "range_quantile", "ranking_metrics", "row_tops",
           "seed_values", "setting_text", "settings_note", "tie_groups", "to_latex", "to_markdown", "tolerance",
           "validity", "variant_labels", "winners", "winners_latex", "winners_markdown", "write",
           "_rank", "_tex", "_tied_rank_row"]     # the private three: tests import them from here


COLUMNS = ["task", "metric", "better", "method", "mean_rank", "cells", "missing_cells", "invalid_cells",
           "friedman_chi2", "friedman_p", "critical_difference", "k", "left_out", "friedman_p_se", "friedman_p_chi2"]


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
