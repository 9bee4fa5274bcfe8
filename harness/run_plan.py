"""The cases a run plans (``plan.csv``'s rows) and the "not run" rows of those no CSV holds.

`PLAN_COLUMNS`: the identifying columns of a case; `_plan_row` types a row as a task CSV's;
`with_not_run` adds a row of status `NOT_RUN` (in memory only, never written) for every planned
case without a row, so the readers count the cases an interrupted run never reached.
"""
from __future__ import annotations

import json

import numpy as np
import pandas as pd

from . import tasks
from .schema import columns


PLAN_COLUMNS = ("case_id", "task", "mesh", "noise_model", "noise_level", "seed", "method", "library", "params")
NOT_RUN = "not run"               # a planned case with no row (in memory only, never in a CSV)


def _plan_row(r: dict) -> dict | None:
    """A plan.csv row with its columns typed as a task CSV's (seed int, noise level float or
    None), or None when a value is not what the harness writes."""
    try:
        params = json.loads(r["params"])
        level = None if r["noise_level"] == "" else float(r["noise_level"])
        seed = int(r["seed"])
    except (TypeError, ValueError, KeyError):
        return None
    ok = (isinstance(params, dict) and r["task"] in tasks.names() and all(r[k] for k in ("case_id", "mesh", "method"))
          and (level is None or np.isfinite(level)))
    return {**r, "noise_level": level, "seed": seed} if ok else None


def with_not_run(frames: dict, plan: list | None) -> dict:
    """``frames`` plus one row of status `NOT_RUN` for every case of ``plan`` (`RunFolder.read_plan`)
    that no CSV holds, e.g. the cases an interrupted run never reached: a seed or a whole cell
    such a run never ran is then missing in the leaderboard and the winners, and the report
    counts the cases. A published pair's level is measured when its case runs, so a planned row
    without one takes the level the pair's other rows give. ``frames`` as they are without a plan."""
    if not plan:
        return frames
    seen = {cid for df in frames.values() if "case_id" in df for cid in df["case_id"].astype(str)}
    pair_level = {}
    for df in frames.values():
        if {"mesh", "noise_model", "noise_level"} <= set(df.columns):
            given = df[(df["noise_model"] == "given") & df["noise_level"].notna()]
            pair_level.update(zip(given["mesh"], given["noise_level"]))
    extra: dict[str, list] = {}
    for r in plan:
        if r["case_id"] in seen:
            continue
        level = r["noise_level"] if r["noise_level"] is not None or r["noise_model"] != "given" \
            else pair_level.get(r["mesh"])
        extra.setdefault(r["task"], []).append({**r, "noise_level": level, "status": NOT_RUN,
                                                "error": "not run: its task's CSV has no row for this case (the run stopped "
                                                         "before it, or the row was removed)"})
    out = dict(frames)
    for task, rows in extra.items():
        add = pd.DataFrame(rows)
        base = out.get(task)
        if base is None:
            base = pd.DataFrame(columns=columns(task))
        if "seed" in base and len(base):
            add = add.astype({"seed": base["seed"].dtype}, errors="ignore")
        out[task] = pd.concat([base, add.reindex(columns=base.columns)], ignore_index=True)
    return out
