"""The self-contained report.html of a run folder, built from its CSVs and run.json only.

Layout: the Python side prepares the data (rows of every task CSV with a few derived columns,
the run's provenance, the Laplacian property matrix, and the meshes of the 3D views) and
writes one HTML file with that data as an inline JSON block; a small hand-written script
(``report.js``, inlined) draws the sortable tables, the SVG plots and the canvas-2D mesh
views. Nothing is loaded from the network.

3D views need meshes, which a run folder has only with ``save_meshes: true``. Otherwise the
chosen cases are recomputed deterministically: the cases are rebuilt from ``run.json``'s
``config`` with `harness.config.load_config`, found by ``case_id`` and re-run once with
`harness.runner.run_case` in a child process (`harness.executors.run_isolated`, with a
timeout). Failures are written on the page; they never stop the report.
"""
from __future__ import annotations

import base64
import dataclasses
import html
import json
import math
import re
import time
from collections import Counter, defaultdict
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from ..results import RunFolder

HERE = Path(__file__).parent
TASKS = ("laplacian", "smoothing", "simplification")
MAX_VIEWS = 6               # 3D views per report
VIEW_BUDGET_S = 60.0        # wall time spent recomputing view meshes before giving up
MAX_DISPLAY_FACES = 8000    # larger meshes are decimated for display only
VIEW_METRIC = {"smoothing": "dist_mean", "simplification": "hausdorff"}
# parameters that are an axis of a plot rather than part of a method variant's name
AXIS_PARAMS = {"simplification": {"target_ratio", "target_faces"}}
PROPS = [("SYM", "SYM", "sym_error", "max |W-Wᵀ| / max|W|"),
         ("LOC", "LOC", "loc_violations", "non-zeros between vertices sharing no edge"),
         ("LIN", "LIN", "lin_error", "max |W X| / (max|W| diag), planar meshes only"),
         ("POS", "POS", "neg_weights", "fraction of negative off-diagonal weights"),
         ("PSD", "psd", "min_eig", "smallest eigenvalue of -(W+Wᵀ)/2, relative")]


# ----------------------------------------------------------------------------- helpers

def _clean(v):
    """JSON-safe scalar: NaN/inf -> None, numpy scalars -> Python."""
    if v is None:
        return None
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        f = float(v)
        return f if math.isfinite(f) else None
    return str(v)


def _esc(x) -> str:
    return html.escape("" if x is None else str(x))


def _fmt(v, digits=3) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "—"
    if isinstance(v, (bool, np.bool_)):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    v = float(v)
    if v == 0:
        return "0"
    if 1e-3 <= abs(v) < 1e5:
        return f"{v:.{digits}g}"
    return f"{v:.{max(digits - 1, 1)}e}"


def _params(s) -> dict:
    try:
        p = json.loads(s) if isinstance(s, str) and s else {}
        return p if isinstance(p, dict) else {}
    except json.JSONDecodeError:
        return {}


def _short(v) -> str:
    return json.dumps(v) if isinstance(v, (dict, list)) else str(v)


def variant_labels(df, task) -> list[str]:
    """Method name plus the parameters that vary between this method's rows (axis params excluded)."""
    skip = AXIS_PARAMS.get(task, set())
    ps = [_params(s) for s in df["params"]] if "params" in df else [{} for _ in range(len(df))]
    varying: dict[str, set] = defaultdict(set)
    by_method: dict[str, list[dict]] = defaultdict(list)
    for m, p in zip(df["method"], ps):
        by_method[m].append(p)
    for m, plist in by_method.items():
        keys = set().union(*plist) if plist else set()
        varying[m] = {k for k in keys - skip if len({_short(p.get(k)) for p in plist}) > 1}
    out = []
    for m, p in zip(df["method"], ps):
        extra = " ".join(f"{k}={_short(p.get(k))}" for k in sorted(varying[m]))
        out.append(f"{m} {extra}".strip())
    return out


def natural_key(s: str):
    """Sort key that orders "iterations=5" before "iterations=20"."""
    return [(0, float(t), "") if re.fullmatch(r"\d+(\.\d+)?", t) else (1, 0.0, t) for t in re.split(r"(\d+(?:\.\d+)?)", s)]


def noise_label(model, level) -> str:
    if model in (None, "none") or (isinstance(model, float) and math.isnan(model)):
        return "no noise"
    if level is None or (isinstance(level, float) and math.isnan(level)):
        return str(model)
    return f"{model} {level:g}"


def _frame_payload(task, df) -> dict:
    """Columns and rows of one task CSV plus derived columns (prefixed with _)."""
    cols = list(df.columns)
    rows = [[_clean(v) for v in rec] for rec in df.itertuples(index=False, name=None)]
    variants = variant_labels(df, task)
    noise = [noise_label(m, lv) for m, lv in zip(df["noise_model"], df["noise_level"])]
    hist = []
    for h in (df["min_angle_hist"] if "min_angle_hist" in df else [None] * len(df)):
        try:
            val = json.loads(h) if isinstance(h, str) and h else None
        except json.JSONDecodeError:
            val = None
        hist.append(val if isinstance(val, list) else None)
    target = []
    for s in df["params"]:
        p = _params(s)
        target.append(p.get("target_ratio") if p.get("target_ratio") is not None else p.get("target_faces"))
    cols += ["_variant", "_noise", "_hist", "_target"]
    for r, v, n, h, t in zip(rows, variants, noise, hist, target):
        r += [v, n, h, _clean(t) if not isinstance(t, str) else t]
    order = sorted(set(variants), key=natural_key)
    return {"columns": cols, "rows": rows, "variants": order}


# ----------------------------------------------------------------------------- header

def _status_html(frames) -> str:
    statuses = ["ok", "error", "timeout", "unavailable"]
    for df in frames.values():
        statuses += [s for s in df["status"].unique() if s not in statuses]
    head = "".join(f"<th>{_esc(s)}</th>" for s in statuses)
    body = []
    for task in TASKS:
        if task not in frames:
            continue
        vc = frames[task]["status"].value_counts()
        cells = "".join(f"<td class='st-{_esc(s)}'>{int(vc.get(s, 0)) or ''}</td>" for s in statuses)
        body.append(f"<tr><th><a href='#task-{task}'>{task}</a></th>{cells}<td>{len(frames[task])}</td></tr>")
    if not body:
        return "<p class='warn'>No rows: the run folder has no task CSV.</p>"
    return (f"<table class='status'><tr><th>task</th>{head}<th>total</th></tr>{''.join(body)}</table>")


def _errors_html(frames) -> str:
    groups: dict[tuple, dict] = {}
    notes: Counter = Counter()
    for task, df in frames.items():
        for rec in df.itertuples(index=False):
            msg = str(getattr(rec, "error", "") or "").strip()
            if rec.status == "ok":
                if msg:
                    notes[(task, msg.splitlines()[0][:300])] += 1
                continue
            key = (rec.status, msg.splitlines()[0][:300] if msg else "(no message)")
            g = groups.setdefault(key, {"n": 0, "methods": set(), "meshes": set(), "tasks": set(), "ids": []})
            g["n"] += 1
            g["methods"].add(str(rec.method))
            g["meshes"].add(str(rec.mesh))
            g["tasks"].add(task)
            if len(g["ids"]) < 3:
                g["ids"].append(str(rec.case_id))
    if not groups and not notes:
        return "<p class='ok'>Every case finished with status ok.</p>"
    out = []
    if groups:
        out.append("<table class='errors'><tr><th>status</th><th>cases</th><th>message</th><th>methods</th>"
                   "<th>meshes</th><th>e.g. case</th></tr>")
        for (st, msg), g in sorted(groups.items(), key=lambda kv: -kv[1]["n"]):
            out.append(f"<tr><td class='st-{_esc(st)}'>{_esc(st)}</td><td>{g['n']}</td><td class='msg'>{_esc(msg)}</td>"
                       f"<td>{_esc(', '.join(sorted(g['methods'])))}</td><td>{_esc(', '.join(sorted(g['meshes'])))}</td>"
                       f"<td class='mono'>{_esc(', '.join(g['ids']))}</td></tr>")
        out.append("</table>")
    if notes:
        out.append("<p>Notes on rows with status ok:</p><ul>")
        for (task, msg), n in notes.most_common():
            out.append(f"<li>{task}: {n} × {_esc(msg)}</li>")
        out.append("</ul>")
    return "".join(out)


def _header_html(meta, frames, run_dir) -> str:
    name = meta.get("name") or Path(run_dir).name
    mach = meta.get("machine") or {}
    vers = meta.get("versions") or {}
    started, finished = meta.get("started"), meta.get("finished")
    wall = meta.get("wall_s")
    workers = meta.get("workers")
    cores = mach.get("cpu_count")
    rows = [("run", f"<b>{_esc(name)}</b> — status {_esc(meta.get('status', 'unknown'))}"),
            ("date", f"started {_esc(started or 'unknown')}, "
                     + (f"finished {_esc(finished)}" if finished else "<span class='warn'>not finished</span>")
                     + (f" ({_fmt(wall)} s wall)" if wall else "")),
            ("machine", _esc(", ".join(str(x) for x in [mach.get("cpu"), f"{cores} cores" if cores else None,
                                                        f"{mach.get('memory_gb')} GB" if mach.get("memory_gb") else None,
                                                        mach.get("system"), mach.get("release"), mach.get("node")]
                                    if x))),
            ("execution", _esc(f"executor {meta.get('executor', '?')}, {workers} worker(s), timeout "
                               f"{meta.get('timeout_s') or 'none'}")),
            ("commit", f"<span class='mono'>{_esc(meta.get('git_commit') or 'not a git checkout')}</span>"),
            ("command", f"<span class='mono'>{_esc(meta.get('command', ''))}</span>")]
    if workers and cores and workers > 1:
        rows.append(("timing", f"<span class='warn'>{workers} cases ran in parallel on {cores} cores: timings include "
                               "contention; use <code>--workers 1</code> for timing-grade numbers.</span>"))
    key_vers = ", ".join(f"{k} {v}" for k, v in vers.items() if v)
    rows.append(("versions", _esc(key_vers)))
    solver = meta.get("solver")
    if solver:
        rows.append(("solvers", _esc(json.dumps(solver, default=str))))
    info = "".join(f"<tr><th>{k}</th><td>{v}</td></tr>" for k, v in rows)
    cfg = json.dumps(meta.get("config", {}), indent=2, default=str)
    return (f"<section id='overview'><h2>Run</h2><table class='info'>{info}</table>"
            f"<details class='config'><summary>config ({_esc(meta.get('config_source', 'run.json'))})</summary>"
            f"<pre>{_esc(cfg)}</pre></details>"
            f"<h3>Cases by status</h3>{_status_html(frames)}<h3>Errors, grouped by message</h3>{_errors_html(frames)}"
            "</section>")


# ----------------------------------------------------------------------------- Laplacian property matrix

def property_matrix(df) -> list[dict]:
    """Per operator variant: for each property, whether it holds on every measured row and the worst size."""
    ok = df[df["status"] == "ok"].copy()
    ok["_variant"] = variant_labels(ok, "laplacian") if len(ok) else []
    out = []
    for var in sorted(ok["_variant"].unique(), key=natural_key) if len(ok) else []:
        g = ok[ok["_variant"] == var]
        entry = {"variant": var, "n": len(g), "props": {}}
        for label, flag, val, _ in PROPS + [("M⁻¹W sym", "operator_symmetric", None, "")]:
            if flag not in g:
                continue
            flags = g[flag].dropna()
            measured = len(flags)
            fails = g.loc[flags.index][flags.astype(bool) == False]  # noqa: E712
            worst = None
            if val and val in g and g[val].notna().any():
                col = g[val].astype(float)
                worst = float(col.min()) if val == "min_eig" else float(col.max())
            per_mesh = [(str(r.mesh), noise_label(r.noise_model, r.noise_level), _clean(getattr(r, flag)),
                         _clean(getattr(r, val)) if val else None) for r in g.itertuples(index=False)]
            entry["props"][label] = {"measured": measured, "fails": len(fails), "worst": worst, "rows": per_mesh,
                                     "fail_meshes": sorted(set(fails["mesh"].astype(str)))}
        out.append(entry)
    return out


def _matrix_html(df) -> str:
    mat = property_matrix(df)
    if not mat:
        return "<p class='warn'>No Laplacian row with status ok: no property matrix.</p>"
    labels = [p[0] for p in PROPS] + ["M⁻¹W sym"]
    docs = {p[0]: p[3] for p in PROPS}
    docs["M⁻¹W sym"] = "the pointwise operator M⁻¹W itself is symmetric (not one of the four)"
    head = "".join(f"<th title='{_esc(docs[lb])}'>{lb}</th>" for lb in labels)
    body = []
    for e in mat:
        cells = []
        for lb in labels:
            p = e["props"].get(lb)
            if p is None or p["measured"] == 0:
                why = "LIN is measured on planar meshes only" if lb == "LIN" else "not measured"
                cells.append(f"<td class='na' title='{why}'>n/a</td>")
                continue
            tip = "\n".join(f"{m}, {nz}: {'holds' if f else 'fails'}" + (f" ({_fmt(v)})" if v is not None else "")
                            for m, nz, f, v in p["rows"] if f is not None)
            size = ""
            if p["worst"] is not None:
                kind = "min" if lb == "PSD" else "max"
                size = f"<span class='size'>{kind} {_fmt(p['worst'])}</span>"
            if p["fails"] == 0:
                cells.append(f"<td class='yes' title='{_esc(tip)}'>✓ <small>{p['measured']}/{p['measured']}</small>{size}</td>")
            else:
                cells.append(f"<td class='no' title='{_esc(tip)}'>✗ <small>fails {p['fails']}/{p['measured']}</small>{size}</td>")
        body.append(f"<tr><th>{_esc(e['variant'])}</th>{''.join(cells)}</tr>")
    return (f"<table class='propmatrix'><tr><th>operator</th>{head}</tr>{''.join(body)}</table>"
            "<p class='caption'>✓: the property holds on every measured mesh (count shown); ✗: it fails on the "
            "given number of them. The small number is the worst violation size over the meshes "
            "(<code>sym_error</code>, <code>loc_violations</code>, <code>lin_error</code>, <code>neg_weights</code>, "
            "<code>min_eig</code>); hover a cell for the value on each mesh. Tolerances: SYM 1e-10, LIN 1e-9, "
            "PSD −1e-10 (relative).</p>")


def _uniform_note(df) -> str:
    ok = df[df["status"] == "ok"]
    uni = ok[ok["method"].astype(str).str.contains("uniform|umbrella|graph", regex=True)]
    planar = uni[uni["lin_error"].notna()] if "lin_error" in uni else uni.iloc[0:0]
    parts = ["<div class='note'><b>The uniform (graph) Laplacian.</b> Its weights are symmetric (w<sub>ij</sub> = 1 "
             "for every edge), so SYM holds for W itself; only the normalised form D W with D = diag(1/N<sub>i</sub>) "
             "(the umbrella operator, N<sub>i</sub> the valence) is not symmetric as a matrix. It is local and positive, "
             "but it is not linearly precise: on an irregular planar mesh, W X ≠ 0 at interior vertices, so it fails LIN."]
    if len(planar):
        items = "".join(f"<li>{_esc(r.method)} on {_esc(r.mesh)} ({_esc(noise_label(r.noise_model, r.noise_level))}): "
                        f"lin_error = {_fmt(r.lin_error)}, LIN {_esc(_fmt(r.LIN))}, SYM {_esc(_fmt(r.SYM))}, "
                        f"M⁻¹W symmetric {_esc(_fmt(r.operator_symmetric))}</li>"
                        for r in planar.itertuples(index=False))
        parts.append(f" From this run's planar meshes:<ul>{items}</ul>")
    elif len(uni):
        parts.append(" <i>This run has no planar mesh (LIN is measured only on planar inputs, e.g. "
                     "<code>plane_nondelaunay</code> with noise model <code>none</code>), so the numbers are not shown.</i>")
    else:
        parts.append(" <i>No uniform Laplacian in this run.</i>")
    parts.append("</div>")
    return "".join(parts)


def _all_four_html(df) -> str:
    """Which operators have SYM, LOC, LIN and POS at once on each planar mesh of the run (from the rows)."""
    ok = df[(df["status"] == "ok") & df["lin_error"].notna()] if "lin_error" in df else df.iloc[0:0]
    if not len(ok):
        return ""
    ok = ok.assign(_variant=variant_labels(ok, "laplacian"))
    items = []
    for (mesh, nz), g in ok.groupby([ok["mesh"].astype(str), [noise_label(m, lv) for m, lv in
                                                             zip(ok["noise_model"], ok["noise_level"])]]):
        good = g[g["SYM"].astype(bool) & g["LOC"].astype(bool) & g["LIN"].astype(bool) & g["POS"].astype(bool)]
        names = sorted(good["_variant"].unique(), key=natural_key)
        items.append(f"<li><b>{_esc(mesh)}</b> ({_esc(nz)}): "
                     + (_esc(", ".join(names)) if names else "<i>no operator in this run</i>")
                     + f" <span class='muted'>({len(names)} of {g['_variant'].nunique()})</span></li>")
    return ("<p>All four of SYM, LOC, LIN and POS at once, per planar mesh of this run (the only meshes where "
            f"LIN is measured):</p><ul class='allfour'>{''.join(items)}</ul>")


def _laplacian_static(frames) -> str:
    if "laplacian" not in frames:
        return ""
    df = frames["laplacian"]
    return ("<h3>Property matrix (Wardetzky et al. 2007)</h3>"
            "<p class='theorem'><b>Theorem</b> (Wardetzky, Mathur, Kälberer &amp; Grinspun, <i>Discrete Laplace "
            "operators: no free lunch</i>, SGP 2007): no discrete Laplacian satisfies symmetry (SYM), locality (LOC), "
            "linear precision (LIN) and positive weights (POS) on all triangle meshes. On the plane, all four hold "
            "at once exactly on regular / weighted Delaunay triangulations, where the cotangent weights are "
            "non-negative; PSD follows from SYM and POS.</p>"
            + _matrix_html(df) + _all_four_html(df) + _uniform_note(df))


# ----------------------------------------------------------------------------- 3D views

def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


def _read_obj(path: Path):
    V, F = [], []
    for line in path.read_text().splitlines():
        if line.startswith("v "):
            V.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("f "):
            F.append([int(x.split("/")[0]) - 1 for x in line.split()[1:4]])
    return np.asarray(V, dtype=np.float64).reshape(-1, 3), np.asarray(F, dtype=np.int64).reshape(-1, 3)


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


def _pack_view(meshes, lo, span, emax) -> list[dict]:
    """``emax``: one colour-scale maximum for all meshes, or a list with one per mesh."""
    out = []
    scales = emax if isinstance(emax, list) else [emax] * len(meshes)
    for (label, V, F, err, what), emax in zip(meshes, scales):
        V, F, err, note = _decimate(V, F, err, MAX_DISPLAY_FACES)
        q = np.clip(np.round((V - lo) / span * 65535.0), 0, 65535).astype("<u2")
        m = {"label": label, "what": what, "nv": int(len(V)), "nf": int(len(F)), "V": _b64(q),
             "F": _b64(F.astype("<u4")), "note": note}
        if err is not None:
            q = np.clip(np.round(err / emax * 255.0), 0, 255) if emax > 0 else np.zeros(len(err))
            m["e"] = _b64(q.astype(np.uint8))
            m["emean"] = float(np.mean(err))
            m["emaxv"] = float(np.max(err))
            m["escale"] = float(emax)
        out.append(m)
    return out


def choose_views(meta, frames) -> list[tuple[str, str]]:
    """(case_id, why) for the 3D views: config ``report.views``, else best and worst per task."""
    wanted = ((meta.get("config") or {}).get("report") or {}).get("views")
    if isinstance(wanted, list) and wanted:
        return [(str(c), "chosen in the config (report.views)") for c in wanted[:MAX_VIEWS]]
    out = []
    for task, metric in VIEW_METRIC.items():
        df = frames.get(task)
        if df is None or metric not in df:
            continue
        ok = df[(df["status"] == "ok") & df[metric].notna()]
        if not len(ok):
            continue
        best = ok.loc[ok[metric].idxmin()]
        worst = ok.loc[ok[metric].idxmax()]
        out.append((str(best["case_id"]), f"best {task} case by {metric}"))
        if worst["case_id"] != best["case_id"]:
            out.append((str(worst["case_id"]), f"worst {task} case by {metric}"))
    return out[:MAX_VIEWS]


def _rebuild_cases(meta):
    from ..config import load_config
    src = meta.get("config_source")
    base = Path(src).parent if src and Path(src).parent.is_dir() else Path.cwd()
    cfg = load_config(meta["config"], base_dir=base.resolve())
    return {c.case_id: c for c in cfg.cases}


def build_views(run_dir, meta, frames) -> list[dict]:
    """Mesh payloads of the chosen views; each failure is a view with an ``error`` text."""
    chosen = choose_views(meta, frames)
    if not chosen:
        return []
    rows = {}
    for task, df in frames.items():
        for rec in df.to_dict("records"):
            rows[str(rec["case_id"])] = rec
    views, cases, cases_err = [], None, None
    t0 = time.perf_counter()
    for cid, why in chosen:
        v = {"case_id": cid, "why": why}
        views.append(v)
        row = rows.get(cid)
        if row is None:
            v["error"] = f"case {cid} is not in this run's CSVs"
            continue
        v.update(task=row["task"], title=f"{row['method']} on {row['mesh']} ({noise_label(row['noise_model'], row['noise_level'])})",
                 params=str(row.get("params") or ""))
        metric = VIEW_METRIC.get(row["task"])
        if metric is None:
            v["error"] = f"{row['task']} cases have no result mesh to show (views exist for smoothing and simplification)"
            continue
        v["metric"], v["value"] = metric, _clean(row.get(metric))
        if row.get("status") != "ok":
            v["error"] = f"the case has status {row.get('status')}: {row.get('error')}"
            continue
        if time.perf_counter() - t0 > VIEW_BUDGET_S:
            v["error"] = f"not recomputed: the report's {VIEW_BUDGET_S:.0f} s budget for 3D views was used up"
            continue
        try:
            if cases is None and cases_err is None:
                try:
                    cases = _rebuild_cases(meta)
                except Exception as exc:  # the page says why instead of failing
                    cases_err = f"cannot rebuild the cases from run.json's config: {type(exc).__name__}: {exc}"
            if cases_err:
                v["error"] = cases_err
                continue
            case = cases.get(cid)
            if case is None:
                v["error"] = ("the config in run.json no longer produces this case id (file paths or "
                              "plugins differ from the run?)")
                continue
            left = max(5.0, VIEW_BUDGET_S - (time.perf_counter() - t0))
            v.update(_view_meshes(Path(run_dir), case, row, metric, timeout=left))
        except Exception as exc:  # a view must never break the report
            v["error"] = f"could not build the view: {type(exc).__name__}: {exc}"[:500]
    return views


def _view_meshes(run_dir: Path, case, row, metric, timeout: float = VIEW_BUDGET_S) -> dict:
    from ..runner import prepare_input
    clean, V_in, _ = prepare_input(case)
    diag = clean.diagonal() or 1.0
    saved = run_dir / "meshes" / f"{case.case_id}.obj"
    out = {}
    if saved.is_file():
        V_out, F_out = _read_obj(saved)
        out["source"] = f"result mesh read from meshes/{saved.name}"
    else:
        t = time.perf_counter()
        # in a child process with a timeout, like the run itself: a crash or a hang of the method
        # costs this view, never the report
        from ..executors import run_isolated
        new_row, meshes = run_isolated(dataclasses.replace(case, repeats=1), timeout=timeout, want_meshes=True)
        if new_row.get("status") != "ok":
            raise RuntimeError(f"recomputing the case failed ({new_row.get('status')}): {new_row.get('error')}")
        V_out, F_out = meshes[f"{case.case_id}.obj"]
        V_out, F_out = np.asarray(V_out, dtype=np.float64), np.asarray(F_out, dtype=np.int64)
        out["source"] = (f"result recomputed from run.json's config in {time.perf_counter() - t:.2f} s "
                         "(the run did not save meshes)")
        a, b = row.get(metric), new_row.get(metric)
        if a is not None and b is not None and not (isinstance(a, float) and math.isnan(a)):
            if abs(float(a) - float(b)) > 1e-6 * max(abs(float(a)), 1e-12) + 1e-12:
                out["mismatch"] = (f"the recomputed result has {metric} = {_fmt(b, 6)} but the CSV row says "
                                   f"{_fmt(a, 6)}: the method is not deterministic or its code changed since the run")
    e_in = np.linalg.norm(V_in - clean.V, axis=1) / diag
    if case.task == "smoothing":
        e_out = np.linalg.norm(V_out - clean.V, axis=1) / diag
        what_out = "distance of each vertex to its clean position"
    else:
        from ..metrics.surface_distance import point_surface_distance
        e_out = point_surface_distance(V_out, V_in, clean.F) / diag
        what_out = "distance of each vertex to the noisy input surface (what the Hausdorff column measures)"
    p_in = float(np.percentile(e_in, 99)) if len(e_in) else 0.0
    p_out = float(np.percentile(e_out, 99)) if len(e_out) else 0.0
    if case.task == "smoothing":       # the same quantity on both meshes: one colour scale
        emax = [0.0, max(p_in, p_out), max(p_in, p_out)]
        out["scale_note"] = "one colour scale for the noisy input and the result (99th percentile of both)"
    else:                              # two different distances: each mesh gets its own scale
        emax = [0.0, p_in, p_out]
        out["scale_note"] = ("separate colour scales: the input shows its noise, the result its distance to the "
                             "input (each up to its own 99th percentile)")
    allV = np.vstack([clean.V, V_in, V_out])
    lo = allV.min(0)
    span = float((allV.max(0) - lo).max()) or 1.0
    meshes = [("clean", clean.V, clean.F, None, "reference mesh"),
              ("noisy input", V_in, clean.F, e_in, "distance of each vertex to its clean position"),
              ("result", V_out, F_out, e_out, what_out)]
    out.update(meshes=_pack_view(meshes, lo, span, emax), lo=lo.tolist(), span=span,
               unit="fractions of the bounding-box diagonal")
    return out


# ----------------------------------------------------------------------------- page

def collect(run_dir) -> dict:
    """Everything the page shows, as JSON-ready data (also what the tests inspect)."""
    folder = RunFolder(run_dir)
    meta = folder.read_run_json() or {}
    frames = folder.frames()
    tasks = {t: _frame_payload(t, frames[t]) for t in TASKS if t in frames}
    mat = property_matrix(frames["laplacian"]) if "laplacian" in frames else []
    return {"meta": meta, "frames": frames, "tasks": tasks, "matrix": mat}


def _task_section(task, frames) -> str:
    intro = {
        "laplacian": "Discrete Laplacians W (libigl's sign convention) measured for Wardetzky et al.'s properties "
                     "on each input mesh.",
        "smoothing": "Smoothed meshes against the clean mesh. Lengths are fractions of the clean mesh's "
                     "bounding-box diagonal; lower is better. Choose the accuracy metric for all plots of this "
                     "section below.",
        "simplification": "Simplified meshes against their (noisy) input. Hausdorff and mean distances are "
                          "fractions of the bounding-box diagonal; lower is better.",
    }[task]
    title = {"laplacian": "Laplacians", "smoothing": "Smoothing", "simplification": "Simplification"}[task]
    if task not in frames:
        return (f"<section id='task-{task}' class='task' data-task='{task}'><h2>{title}</h2>"
                f"<p class='muted'>This run has no {task} cases.</p></section>")
    static = _laplacian_static(frames) if task == "laplacian" else ""
    return (f"<section id='task-{task}' class='task' data-task='{task}'><h2>{title}</h2><p>{intro}</p>{static}"
            f"<div class='plots' id='plots-{task}'></div>"
            f"<h3>All {task} rows</h3><div class='rows' id='rows-{task}'></div></section>")


def render(run_dir) -> str:
    data = collect(run_dir)
    meta, frames = data["meta"], data["frames"]
    try:
        views = build_views(run_dir, meta, frames)
    except Exception as exc:  # never fail the report over the views
        views = [{"case_id": "-", "why": "", "error": f"3D views failed: {type(exc).__name__}: {exc}"}]
    payload = {"name": meta.get("name") or Path(run_dir).name, "tasks": data["tasks"], "views": views,
               "max_display_faces": MAX_DISPLAY_FACES}
    blob = json.dumps(payload, allow_nan=False, separators=(",", ":"), default=_clean)
    blob = blob.replace("</", "<\\/").replace("<!--", "<\\!--")
    css = (HERE / "report.css").read_text()
    js = (HERE / "report.js").read_text()
    name = _esc(payload["name"])
    present = [t for t in TASKS if t in frames]
    nav = "".join(f"<a href='#task-{t}'>{t}</a>" for t in TASKS) + "<a href='#views'>3D views</a>"
    built = datetime.now(timezone.utc).isoformat(timespec="seconds")
    body = [f"<header><h1>mesh-shootout report: {name}</h1><nav><a href='#overview'>run</a>{nav}</nav></header>",
            "<main>",
            _header_html(meta, frames, run_dir),
            *[_task_section(t, frames) for t in TASKS],
            "<section id='views'><h2>3D views</h2><p>Clean, noisy and result meshes side by side, coloured by "
            "per-vertex error (lengths are fractions of the bounding-box diagonal; the clean mesh is the grey reference). Drag to rotate "
            "(all three turn together), wheel to zoom, double-click to reset. Views are recomputed from the "
            "CSVs and run.json when the run did not save meshes; large meshes are decimated for display only.</p>"
            "<div id='view-list'></div></section>",
            f"<footer>Built {built} from the CSVs and run.json of <span class='mono'>{_esc(Path(run_dir).resolve())}"
            f"</span>; rebuild with <code>shootout report RUN_DIR</code>. Tasks in this run: "
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
    page = render(run_dir)
    tmp = out.with_suffix(".html.tmp")
    tmp.write_text(page, encoding="utf-8")
    tmp.replace(out)
    return out
