"""3D views: the meshes of a few chosen cases, computed by the session after the last row and
stored in the run folder (``views/index.json`` plus one ``views/<case_id>.json`` per view), so
the report only reads files.

Which cases: ``report.views`` in the config (case ids), else the best valid and the worst ok
case of each task that declares a ``view_metric`` (by that metric's direction). Each chosen case runs
once more in an isolated child process (`harness.executors.isolation.run_isolated`, with a time
budget; a fresh interpreter where a fork would hang in GNU OpenMP, `harness.executors.fresh`)
and its task's ``view`` gives the meshes and per-vertex values. Lengths are fractions of the
clean mesh's bounding-box diagonal.
"""
from __future__ import annotations

import base64
import dataclasses
import json
import math
import time

import numpy as np

from . import tasks
from .schema import scalar

MAX_VIEWS = 6               # 3D views per report
VIEW_BUDGET_S = 60.0        # wall time spent computing view meshes before giving up
MAX_DISPLAY_FACES = 8000    # larger meshes are decimated for display only


def choose_views(report_cfg: dict, frames) -> list[tuple[str, str]]:
    """(case_id, why) for the 3D views: ``report.views``, else best and worst per task by its view
    metric, or, where that metric is blank everywhere (no ground truth), one ok case of the task."""
    wanted = (report_cfg or {}).get("views")
    if isinstance(wanted, list) and wanted:
        return [(str(c), "chosen in the config (report.views)") for c in wanted[:MAX_VIEWS]]
    out = []
    for name, task in tasks.all_tasks().items():
        metric = task.metric(task.view_metric) if task.view_metric else None
        df = frames.get(name)
        if metric is None or df is None or metric.name not in df:
            continue
        ok = df[(df["status"] == "ok") & df[metric.name].notna()]
        from .leaderboard import validity
        if not len(ok):
            done = df[df["status"] == "ok"]
            done = done[validity(task.spec(), done) == ""].sort_values("case_id")   # not a diverged one
            if len(done) and task.view is not None:   # no ground truth to rank by: one case to look at
                out.append((str(done["case_id"].iloc[0]), f"a {name} case ({metric.name} is blank on these "
                                                          "meshes: no ground truth to pick a best or worst by)"))
            continue
        col = ok[metric.name].astype(float)
        valid = col[validity(task.spec(), ok) == ""]     # the best is a valid result; the worst may not be
        pick = valid if len(valid) else col
        best = pick.idxmax() if metric.better == "higher" else pick.idxmin()
        worst = col.idxmin() if metric.better == "higher" else col.idxmax()
        out.append((str(ok.loc[best, "case_id"]), f"best {name} case by {metric.name}"))
        if worst != best:
            out.append((str(ok.loc[worst, "case_id"]), f"worst {name} case by {metric.name}"))
    return out[:MAX_VIEWS]


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


def _decimate(V, F, err, limit):
    """(V, F, err, note): at most ``limit`` faces, for display only; err mapped by nearest vertex."""
    if len(F) <= limit:
        return V, F, err, None
    import fast_simplification
    from scipy.spatial import cKDTree
    V2, F2 = fast_simplification.simplify(np.ascontiguousarray(V, dtype=np.float32).astype(np.float64),
                                          np.ascontiguousarray(F, dtype=np.int64), 1.0 - limit / len(F))
    V2, F2 = np.asarray(V2, dtype=np.float64), np.asarray(F2, dtype=np.int64)
    e2 = None
    if err is not None:
        _, idx = cKDTree(V).query(V2)
        e2 = err[idx]
    return V2, F2, e2, f"{len(F):,} faces shown decimated to {len(F2):,}"


def _finite_values(err) -> np.ndarray:
    """Per-vertex values as float64, those that are not finite (an infinity too) as NaN; None when
    none is finite (no colours)."""
    err = np.asarray(err, dtype=np.float64)
    ok = np.isfinite(err)
    return err if ok.all() else np.where(ok, err, np.nan) if ok.any() else None


def pack(meshes: list) -> dict:
    """JSON payload of ``[(label, V, F, values or None, what[, options]), ...]``: positions
    quantised to 16 bits in a common box, faces as uint32, values to 8 bits on one colour scale per
    quantity (meshes showing the same ``what`` share it: 99th percentile of their values, or their
    maximum when ``options`` has ``isolines: n``, which also draws ``n`` evenly spaced level lines
    of the values, e.g. of a distance field). With ``signed: True`` in ``options`` (a quantity
    with a meaningful sign: a curvature, an eigenvector) the scale is symmetric about 0 (of
    |values|) and 0 maps to the middle of the 8 bits; other values are clipped at 0. Values that
    are not finite are left out of the scale and the summaries, and drawn as 0; a mesh with a
    coordinate that is not finite (a diverged result) cannot be drawn: ValueError."""
    meshes = [tuple(m) + ({},) * (6 - len(m)) for m in meshes]
    meshes = [(label, V, F, None if err is None else _finite_values(err), what, opt)
              for label, V, F, err, what, opt in meshes]
    allV = np.vstack([np.asarray(m[1], dtype=np.float64) for m in meshes])
    if not np.isfinite(allV).all():
        bad = [m[0] for m in meshes if not np.isfinite(np.asarray(m[1], dtype=np.float64)).all()]
        raise ValueError(f"{', '.join(bad)}: coordinates that are not finite (a diverged result), nothing to draw")
    lo = allV.min(0)
    span = float((allV.max(0) - lo).max()) or 1.0
    scale: dict[str, float] = {}
    signed = {what for _, _, _, err, what, opt in meshes if opt.get("signed") and err is not None and len(err)}
    for _, _, _, err, what, opt in meshes:
        if err is not None and len(err):
            mag = np.abs(err) if what in signed else err      # a signed quantity: symmetric about 0
            top = float(np.nanmax(mag)) if opt.get("isolines") else float(np.nanpercentile(mag, 99))
            scale[what] = max(scale.get(what, 0.0), top)
    out = []
    for label, V, F, err, what, opt in meshes:
        V, F, err, note = _decimate(np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64), err,
                                    MAX_DISPLAY_FACES)
        q = np.clip(np.round((V - lo) / span * 65535.0), 0, 65535).astype("<u2")
        m = {"label": label, "what": what, "nv": int(len(V)), "nf": int(len(F)), "V": _b64(q),
             "F": _b64(F.astype("<u4")), "note": note}
        if err is not None and len(err):
            emax = scale.get(what, 0.0)
            e0 = np.nan_to_num(err, nan=0.0)                  # a value that is not finite is drawn as 0
            if emax > 0:
                t = (0.5 + 0.5 * e0 / emax) if what in signed else e0 / emax    # signed: 0 maps to the middle
                qe = np.clip(np.round(t * 255.0), 0, 255)
            else:
                qe = np.full(len(err), 128.0 if what in signed else 0.0)
            m.update(e=_b64(qe.astype(np.uint8)), emean=float(np.nanmean(err)), emaxv=float(np.nanmax(err)),
                     eminv=float(np.nanmin(err)), escale=float(emax), signed=what in signed)
            if opt.get("isolines"):
                m["isolines"] = int(opt["isolines"])
        out.append(m)
    shared = len(scale) == 1
    note = ("one colour scale for every coloured mesh (99th percentile of all)" if shared else
            "one colour scale per quantity (each up to its own 99th percentile)")
    return {"meshes": out, "lo": lo.tolist(), "span": span, "scale_note": note,
            "unit": "fractions of the bounding-box diagonal"}


def _title(row) -> str:
    lvl = row.get("noise_level")
    noise = row.get("noise_model") if lvl is None or (isinstance(lvl, float) and math.isnan(lvl)) \
        else f"{row.get('noise_model')} {lvl:g}"
    return f"{row['method']} on {row['mesh']} ({noise})"


def compute_views(cases_by_id: dict, frames, report_cfg: dict, budget_s: float = VIEW_BUDGET_S,
                  timeout: float | None = None, threads: int | None = None) -> list[dict]:
    """View payloads of the chosen cases, each run again with the run's ``threads`` per case (so
    its result is the measured one); each failure is a view with an ``error`` text."""
    from .executors.fresh import isolated_runner
    run_isolated = isolated_runner()
    rows = {str(r["case_id"]): r for df in frames.values() for r in df.to_dict("records")}
    views, t0 = [], time.perf_counter()
    for cid, why in choose_views(report_cfg, frames):
        v = {"case_id": cid, "why": why}
        views.append(v)
        row = rows.get(cid)
        if row is None:
            v["error"] = f"case {cid} is not in this run's CSVs"
            continue
        task = tasks.get(row["task"])
        v.update(task=row["task"], title=_title(row), params=str(row.get("params") or ""))
        if task.view is None:
            v["error"] = f"{row['task']} cases have no mesh to show"
            continue
        if task.view_metric:
            v["metric"], v["value"] = task.view_metric, scalar(row.get(task.view_metric))
            m = task.metric(task.view_metric)
            if m is not None and m.upper:           # a certified bracket's lower end: its upper end beside it
                v["upper"] = scalar(row.get(m.upper))
        if row.get("status") != "ok":
            v["error"] = f"the case has status {row.get('status')}: {row.get('error')}"
            continue
        case = cases_by_id.get(cid)
        if case is None:
            v["error"] = ("this case is not among the cases rebuilt from run.json: a mesh file it reads changed "
                          "since the run (a case id includes the file's sha1) or is gone")
            v["not_rebuilt"] = True
            continue
        left = budget_s - (time.perf_counter() - t0)
        if left <= 0:
            v["error"] = f"not computed: the {budget_s:.0f} s budget for 3D views was used up"
            continue
        left = min(left, timeout) if timeout else left
        try:
            new_row, extras = run_isolated(dataclasses.replace(case, repeats=1, threads=threads or case.threads), max(left, 5.0),
                                           want_view=True)
            if new_row.get("status") != "ok" or "view" not in extras:
                v["error"] = f"computing the view failed ({new_row.get('status')}): {new_row.get('error')}"
                continue
            packed = pack(extras["view"])
            json.dumps(packed, allow_nan=False)       # what the view file cannot hold fails this view alone
            v.update(packed)
            m = task.view_metric
            a, b = scalar(row.get(m)) if m else None, scalar(new_row.get(m)) if m else None
            if a is not None and b is not None and abs(a - b) > 1e-6 * max(abs(a), 1e-12) + 1e-12:
                v["mismatch"] = (f"the view's run has {m} = {b:.6g} but the CSV row says {a:.6g}: the method "
                                 "is not deterministic")
        except Exception as exc:  # a view must never break the run
            v["error"] = f"could not build the view: {type(exc).__name__}: {exc}"[:500]
    return views
