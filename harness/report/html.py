"""The self-contained report.html of a run folder, built from its CSVs and run.json only.

Layout: the Python side prepares the data (rows of every task CSV with a few derived columns,
the run's provenance, the Laplacian property matrix, and the meshes of the 3D views) and
writes one HTML file with that data as an inline JSON block; a small hand-written script
(``report.js``, inlined) draws the sortable tables, the SVG plots and the canvas-2D mesh
views. Nothing is loaded from the network.

The 3D views are read from the run folder's ``views/`` (computed by the session after the last
row; ``shootout views RUN_DIR`` recomputes them). Building a report runs no method and imports no
plugin: it reads files only. Task titles, intros, metric specs and extra sections come from the
task declarations recorded in ``run.json`` (or, for older runs, `harness.tasks`).
"""
from __future__ import annotations

import json
from datetime import datetime, timezone
from pathlib import Path


from .. import tasks as _tasks
from ..leaderboard import (LEFT_OUT, friedman_p_text, leaderboard, no_ranking_text, not_measured, setting_text,
                           settings_note, validity)
from ..results import REPORT_FILES, RunFolder, recorded_specs, with_not_run
from ..schema import scalar as _clean
from ..schema import text
from .common import esc as _esc
from .common import fmt as _fmt
from .common import natural_key, noise_label, params_of, variant_labels
from .convergence import convergence
from .laplacian import property_matrix_section
from .overview import _header_html, _others_text, _paired, _status_html, _test_mean, _timing_text

__all__ = ["HERE", "MAX_DISPLAY_FACES", "SECTIONS", "collect", "render", "build_report",   # and the names tests inspect:
           "_leaderboard_payload", "_fmt", "_others_text", "_paired", "_status_html", "_test_mean", "_timing_text"]

HERE = Path(__file__).parent
MAX_DISPLAY_FACES = 8000    # what the views were decimated to (stated on the page)


# ----------------------------------------------------------------------------- helpers

def _frame_payload(spec, df) -> dict:
    """Columns and rows of one task CSV plus derived columns (prefixed with _)."""
    cols = list(df.columns)
    rows = [[_clean(v) for v in rec] for rec in df.itertuples(index=False, name=None)]
    variants = variant_labels(df, spec.get("axis_params") or (), spec.get("method_defaults"))
    noise = [noise_label(m, lv) for m, lv in zip(df["noise_model"], df["noise_level"])]
    hist = []
    for h in (df["min_angle_hist"] if "min_angle_hist" in df else [None] * len(df)):
        try:
            val = json.loads(h) if isinstance(h, str) and h else None
        except json.JSONDecodeError:
            val = None
        hist.append(val if isinstance(val, list) else None)
    target, axis = [], []
    axes = sorted(spec.get("axis_params") or ())
    for s in df["params"]:
        p = params_of(s)
        target.append(p.get("target_ratio") if p.get("target_ratio") is not None else p.get("target_faces"))
        axis.append(setting_text(json.dumps({k: p.get(k) for k in axes if k in p})))   # e.g. "k=50": as winners.md
    invalid = validity(spec, df).tolist() if "status" in df else [""] * len(rows)
    missing = not_measured(spec, df).tolist() if "status" in df else [False] * len(rows)   # never a result
    cols += ["_variant", "_noise", "_hist", "_target", "_invalid", "_axis", "_missing"]
    for r, v, n, h, t, bad, ax, miss in zip(rows, variants, noise, hist, target, invalid, axis, missing):
        r += [v, n, h, _clean(t) if not isinstance(t, str) else t, bad or None, ax, bool(miss)]
    order = sorted(set(variants), key=natural_key)
    return {"columns": cols, "rows": rows, "variants": order, "spec": spec,
            "convergence": convergence(spec, df, variants, invalid)}


# ----------------------------------------------------------------------------- page

SECTIONS = {"property_matrix": property_matrix_section}     # extra sections a task may declare


def collect(run_dir) -> dict:
    """Everything the page shows, as JSON-ready data (also what the tests inspect)."""
    folder = RunFolder(run_dir)
    meta = folder.read_run_json() or {}
    frames = with_not_run(folder.frames(), folder.read_plan())   # cases an interrupted run never ran: "not run" rows
    specs = recorded_specs(meta, frames)
    tasks = {t: _frame_payload(specs[t], frames[t]) for t in specs if t in frames}
    return {"meta": meta, "frames": frames, "specs": specs, "tasks": tasks,
            "views": folder.read_views(), "leaderboard": _leaderboard_payload(frames, specs),
            "no_ranking": no_ranking_text(frames, specs)}


def _leaderboard_payload(frames, specs) -> list[dict]:
    lb = leaderboard(frames, specs)
    out = []
    for (task, metric), g in lb.groupby(["task", "metric"], sort=False):
        r0 = g.iloc[0]
        out.append({"task": task, "metric": metric, "better": r0.better, "cells": int(r0.cells), "k": int(r0.k),
                    "p": _clean(r0.friedman_p), "p_text": None if _clean(r0.friedman_p) is None else friedman_p_text(r0),
                    "cd": _clean(r0.critical_difference),
                    "left_out": r0.left_out if isinstance(r0.left_out, str) else "", "left_out_why": LEFT_OUT,
                    "methods": [{"method": r.method, "mean_rank": float(r.mean_rank), "missing": int(r.missing_cells),
                                 "invalid": int(r.invalid_cells)} for r in g.itertuples()]})
    return out


def _leaderboard_files_text(run_dir, scored: bool = False) -> str:
    """Where else the leaderboard is: the files of it this run folder holds (a run writes them
    when it finishes, and `shootout report` rebuilds them; an interrupted run and `eval` do not;
    ``scored``: an eval folder, which `shootout report` does not rewrite either)."""
    have = [n for n in REPORT_FILES if n.startswith("leaderboard.") and (Path(run_dir) / n).is_file()]
    if not have and scored:
        return "An eval folder has no leaderboard files: this page's leaderboard is the only one."
    if not have:
        return ("This run folder has no leaderboard files (they are written when a run finishes, and by "
                "`shootout report`).")
    return "Also in " + ", ".join(have) + "."


def _task_section(task, spec, frames) -> str:
    title, intro = _esc(spec.get("title") or task), _esc(spec.get("intro") or "")
    if task not in frames:
        return (f"<section id='task-{task}' class='task' data-task='{task}'><h2>{title}</h2>"
                f"<p class='muted'>This run has no {task} cases.</p></section>")
    extra = "".join(SECTIONS[s](frames[task], spec) for s in spec.get("sections") or () if s in SECTIONS)
    return (f"<section id='task-{task}' class='task' data-task='{task}'><h2>{title}</h2><p>{intro}</p>{extra}"
            f"<div class='plots' id='plots-{task}'></div>"
            f"<h3>All {task} rows</h3><div class='rows' id='rows-{task}'></div></section>")


def render(run_dir) -> str:
    data = collect(run_dir)
    meta, frames, specs = data["meta"], data["frames"], dict(data["specs"])
    def position(t):                          # the declared order: recorded, else this version's
        o = specs[t].get("order")
        if not isinstance(o, (int, float)) or isinstance(o, bool):
            o = _tasks.get(t).order if t in _tasks.names() else 100
        return (o, t)
    order = sorted(specs, key=position)
    views, views_note = data["views"], None
    if meta.get("kind") == "eval" and not views:
        views_note = "No 3D views: an eval scores result files, it runs no method to draw."
    elif not views and not (Path(run_dir) / "views").is_dir() and frames:
        why = ({"interrupted": "the run was interrupted before its views were computed",
                "running": "the run had not finished (or its driver was killed) when this page was built"}
               .get(meta.get("status"), "this run folder has no views/ (made by an older version, or the views "
                                         "could not be computed)"))
        views_note = f"No 3D views: {why}; `shootout views RUN_DIR` computes them (it runs the chosen methods again)."
    payload = {"name": meta.get("name") or Path(run_dir).name, "tasks": data["tasks"], "views": views,
               "views_note": views_note,
               "max_display_faces": MAX_DISPLAY_FACES, "leaderboard": data["leaderboard"],
               "no_ranking": data["no_ranking"]}
    blob = json.dumps(payload, allow_nan=False, separators=(",", ":"), default=_clean)
    blob = blob.replace("</", "<\\/").replace("<!--", "<\\!--")
    css = (HERE / "report.css").read_text()
    js = (HERE / "report.js").read_text()
    name = _esc(payload["name"])
    present = [t for t in order if t in frames]
    nav = ("<a href='#leaderboard'>leaderboard</a>" + "".join(f"<a href='#task-{t}'>{_esc(t)}</a>" for t in order)
           + "<a href='#views'>3D views</a>")
    built = datetime.now(timezone.utc).isoformat(timespec="seconds")
    body = [f"<header><h1>mesh-shootout report: {name}</h1><nav><a href='#overview'>run</a>{nav}</nav></header>",
            "<main>",
            _header_html(meta, frames, run_dir),
            "<section id='leaderboard'><h2>Leaderboard across meshes</h2><p>Per task and ranking metric: the mean "
            "rank of each method over all (mesh, noise, level[, target]) cells, the Friedman test and the Nemenyi "
            "critical difference (Demšar 2006): methods joined by a bar do not differ significantly (α = 0.05). "
            "Invalid results (diverged, worse than the noisy input, over the face target, made non-manifold or topology-changing) rank last in "
            "their cell; cells with a missing result are left out; values closer than the metric's compare tolerance tie. "
            f"{'' if meta.get('kind') == 'eval' else _esc(settings_note(meta.get('tune')))} "
            f"{_leaderboard_files_text(run_dir, meta.get('kind') == 'eval')}</p>"
            "<div id='leaderboard-body'></div></section>",
            *[_task_section(t, specs[t], frames) for t in order],
            "<section id='views'><h2>3D views</h2><p>Meshes side by side, coloured by the per-vertex quantity "
            "named under each (lengths are fractions of the bounding-box diagonal; the clean mesh is the grey "
            "reference). Drag to rotate (all turn together), wheel to zoom, double-click to reset. The views were "
            "computed when the run finished and stored in the run folder's views/; large meshes are decimated "
            "for display only.</p><div id='view-list'></div></section>",
            f"<footer>Built {built} from the files of <span class='mono'>{_esc(Path(run_dir).resolve())}"
            f"</span> (no code was run); rebuild with <code>shootout report RUN_DIR</code>. Tasks in this run: "
            f"{_esc(', '.join(present) or 'none')}.</footer>",
            "</main>"]
    return ("<!doctype html>\n<html lang='en'><head><meta charset='utf-8'>"
            "<meta name='viewport' content='width=device-width, initial-scale=1'>"
            f"<title>mesh-shootout: {name}</title><style>{css}</style></head>"
            "<body data-plots-rendered='0' data-view3d='pending'>"
            + "\n".join(body)
            + f"<script type='application/json' id='report-data'>{blob}</script>"
            + f"<script>{js}</script></body></html>")


def build_report(run_dir) -> Path:
    """Write ``run_dir/report.html`` from the CSVs and run.json; return its path."""
    out = Path(run_dir) / "report.html"
    page = text(render(run_dir))                    # a path's undecodable bytes (surrogateescape) as escapes
    from ..results import atomic_write
    atomic_write(out, lambda fh: fh.write(page))       # no half-written page, no temporary left behind
    return out
