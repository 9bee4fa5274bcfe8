"""The report's run overview (`_header_html`): the run's provenance, timing protocol and linear
solvers, its cases by status, its errors grouped by message, and, for a tuned run, tuned against
as configured; HTML fragments built from run.json's metadata (``meta``) and the task frames.
"""
from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

from ..leaderboard import label_text
from .common import esc as _esc
from .common import fmt as _fmt


def _status_html(frames) -> str:
    statuses = ["ok", "error", "timeout", "unavailable"]
    for df in frames.values():
        statuses += [s for s in df["status"].unique() if s not in statuses]
    head = "".join(f"<th>{_esc(s)}</th>" for s in statuses)
    body = []
    for task in frames:
        if task not in frames:
            continue
        vc = frames[task]["status"].value_counts()
        cells = "".join(f"<td class='st-{_esc(s)}'>{int(vc.get(s, 0))}</td>" for s in statuses)   # 0 too: a count
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


def _test_mean(rows, metric: str) -> str:
    """The metric's mean over the ok test cases, with how many of the cases that is when some
    failed ("failed (0 of n ok)" when all did): never another setting's value in their place."""
    n = len(rows)
    if not n:
        return "—"
    ok = rows[(rows["status"] == "ok") & rows[metric].notna()]
    if not len(ok):
        return f"failed (0 of {n} ok)"
    val = _fmt(float(ok[metric].mean()), 4)
    return val if len(ok) == n else f"{val} ({len(ok)} of {n} ok)"


def _paired(every, is_tuned, metric: str, ch: dict, spec: dict) -> str:
    """Tuned against as configured case by case: pairs of ok rows with the same mesh, noise,
    level, seed and other parameters; in how many the tuned setting is better, tied, worse as
    `harness.compare.judge` tells the pair apart (beyond the metric's compare tolerance
    ``max(rel * |as configured|, abs)``, for a sampled metric beyond ``se_z`` times the pair's
    combined standard error, for a certified bracket only where the two brackets lie apart), of
    how many pairs."""
    import pandas as pd

    from ..compare import judge, rules_from_specs
    rule = rules_from_specs({"t": spec}).get("t", {}).get(metric)
    tuned_keys = set(ch.get("chosen") or {})

    def key(r):
        try:
            p = {k: v for k, v in json.loads(r["params"]).items() if k not in tuned_keys}
        except (TypeError, ValueError):
            p = {}
        return (str(r.get("mesh")), str(r.get("noise_model")), str(r.get("noise_level")), str(r.get("seed")),
                json.dumps(p, sort_keys=True))
    ok = every[(every["status"] == "ok") & pd.to_numeric(every[metric], errors="coerce").notna()]
    base = {key(r): r.to_dict() for _, r in ok[~is_tuned[ok.index]].iterrows()}
    counts = [0, 0, 0]
    for _, r in ok[is_tuned[ok.index]].iterrows():
        a = base.get(key(r))
        if a is None:
            continue
        b = r.to_dict()
        verdict = judge(metric, float(a[metric]), float(b[metric]), a, b, rule=rule)
        counts[0 if verdict == "improvement" else 2 if verdict == "regression" else 1] += 1
    n = sum(counts)
    total = int(is_tuned.sum())
    return f"{counts[0]} / {counts[1]} / {counts[2]} of {n}" + ("" if n == total else f" ({total} tuned cases)")


def _tune_html(meta, frames) -> str:
    """Default vs tuned, per tuned method: the chosen setting, training scores and the test meshes' mean."""
    tune = meta.get("tune")
    if not isinstance(tune, dict) or not isinstance(tune.get("methods"), dict):
        return ""
    metric = str(tune.get("metric"))
    body = []
    for m, ch in tune["methods"].items():
        df = frames.get(ch.get("task"))
        tuned_ids = set(ch.get("test_case_ids") or [])
        test_default = test_tuned = test_input = "—"
        per_case = "—"
        if df is not None and metric in df:
            every = df[df["method"] == m]
            is_tuned = every["case_id"].astype(str).isin(tuned_ids)
            test_default = _test_mean(every[~is_tuned], metric)
            # the chosen setting equal to the configured one runs no tuned case: its test value is that one's
            test_tuned = _test_mean(every[is_tuned], metric) if ch.get("chosen") else "= as configured"
            ok = every[every["status"] == "ok"]
            if f"input_{metric}" in ok and len(ok):
                test_input = _fmt(float(ok[f"input_{metric}"][~is_tuned[ok.index]].mean()), 4) \
                    if (~is_tuned[ok.index]).any() else "—"
            if ch.get("chosen"):
                per_case = _paired(every, is_tuned, metric, ch, (meta.get("tasks") or {}).get(ch.get("task")) or {})
        picked = ch.get("chosen") if isinstance(ch.get("chosen"), dict) else {}
        chosen = label_text("", picked, sorted(picked)).strip() or "as configured"    # as the labels write it
        dtrain = "no score: failed, invalid or not measured" if ch.get("default_train_score") is None else _fmt(ch["default_train_score"], 4)
        body.append(f"<tr><td>{_esc(m)}</td><td>{_esc(chosen)}</td><td class='num'>{_esc(ch.get('candidates'))}</td>"
                    f"<td class='num'>{_esc(dtrain)}</td><td class='num'>{_fmt(ch.get('train_score'), 4)}</td>"
                    f"<td class='num'>{_esc(test_default)}</td><td class='num'>{_esc(test_tuned)}</td>"
                    f"<td class='num'>{_esc(per_case)}</td><td class='num'>{_esc(test_input)}</td></tr>")
    better = next((c.get("better") for c in tune["methods"].values() if isinstance(c, dict)), "")
    return (f"<h3>Tuning: as configured vs tuned (by {_esc(metric)}, {_esc(better)} is better)</h3>"
            f"<p>Parameters searched on the training meshes ({_esc(', '.join(tune.get('train_meshes') or []))}), "
            "then run on this report's (test) meshes. A setting with a failed or invalid training case (diverged, worse "
            "than its noisy input) is never chosen. <i>As configured</i>: the method's parameters in the config, its "
            "defaults where the config sets none. Rows of other methods are ranked as configured.</p>"
            "<table class='best tune'><tr><th>method</th><th>chosen</th><th>settings tried</th><th>train, as configured</th>"
            f"<th>train, chosen</th><th>test, as configured</th><th>test, tuned</th>"
            "<th title='test cases where both settings are ok, paired by mesh, noise, level and seed: tuned better / "
            "tied / worse beyond the metric&#39;s compare tolerance (a sampled metric&#39;s: and its standard errors)'>test, per case: better / tied / worse</th>"
            "<th>test, noisy input</th></tr>"
            f"{''.join(body)}</table>")


def _solver_text(solver: dict) -> str:
    """The sparse solvers the run could use and which the automatic choice takes, in words."""
    vers = solver.get("versions") if isinstance(solver.get("versions"), dict) else {}
    installed = solver.get("installed") if isinstance(solver.get("installed"), list) else []
    inst = ", ".join(f"{n} {vers.get(n, '')}".strip() for n in installed if isinstance(n, str))
    parts = [f"automatic: {solver.get('auto_small', '?')} below {solver.get('auto_small_max_n', '?')} unknowns, "
             f"else {solver.get('auto', '?')}"]
    if solver.get("env_override"):
        parts.append(f"overridden by the environment: {solver['env_override']}")
    if inst:
        parts.append(f"installed: {inst}")
    used = solver.get("used")
    if isinstance(used, dict) and used:
        said = []
        for k, v in sorted(used.items(), key=lambda kv: str(kv[0])):
            v = v if isinstance(v, dict) else {}
            who = v.get("methods") if isinstance(v.get("methods"), list) else []
            said.append(f"{k} in {v.get('cases', '?')} case(s) of {', '.join(map(str, who)) or '?'} "
                        f"(up to {v.get('unknowns_max', '?')} unknowns)")
        parts.append("used by this session's cases: " + "; ".join(said))
    return "; ".join(parts)


def _others_text(frames) -> str:
    """How busy other processes kept the machine during the cases' timed calls (the rows'
    ``others_cpu``): what slowed the timings, where the load average also counts processes that
    wait without running."""
    import pandas as pd
    vals = pd.concat([pd.to_numeric(df["others_cpu"], errors="coerce") for df in frames.values()
                      if "others_cpu" in df] or [pd.Series(dtype=float)]).dropna()
    if vals.empty:
        return ""
    return (f"other processes kept {vals.median():.2g} cores busy in the median case (max {vals.max():.2g}) during "
            f"the timed calls of {len(vals)} case(s) (others_cpu; with several workers, the sibling cases count)")


def _timing_text(meta) -> str:
    """run.json's timing protocol in one line: threads per case, samples, load averages, fixed cost."""
    t = meta.get("timing") if isinstance(meta.get("timing"), dict) else {}
    parts = []
    if t.get("threads_per_case") is not None:
        ran = [x for x in meta.get("sessions") or [] if isinstance(x, dict) and x.get("status_counts")]
        other = sorted({x.get("threads_per_case") for x in ran if isinstance(x.get("threads_per_case"), int)}
                       - {t["threads_per_case"]})
        parts.append(f"{t['threads_per_case']} thread(s) per case (BLAS/OpenMP pools and libigl's)"
                     + (f" in the last session, {' and '.join(map(str, other))} in earlier ones" if other else ""))
    if t.get("min_repeats") is not None or t.get("time_budget_s") is not None:
        parts.append(f"one untimed cold call, then timed samples until there are at least {t.get('min_repeats', '?')} "
                     f"and they sum to at least {_fmt(t.get('time_budget_s'))} s; median and quartiles")
    loads = meta.get("load_average") if isinstance(meta.get("load_average"), list) else []
    said = [f"{x:.2f} at the {when}" if isinstance(x, (int, float)) and not isinstance(x, bool) else f"unknown at the {when}"
            for x, when in zip(loads[:2], ("start", "end"))]
    if any(not s.startswith("unknown") for s in said):
        parts.append("load average " + ", ".join(said) + " (1 min)")
    fc = meta.get("fixed_cost_per_case_s")
    if isinstance(fc, dict) and fc.get("mean") is not None:
        share = fc.get("share_of_method_time")
        parts.append(f"fixed cost per case {_fmt(fc['mean'])} s mean, {_fmt(fc.get('max'))} s max"
                     + (f", {_fmt(share)} of the method time" if share is not None else ""))
    return "; ".join(parts)


def _provenance_text(x: dict) -> str:
    """One entry of run.json's ``provenance_changed``: what a resumed session ran otherwise."""
    said = (("git_commit", "commit"), ("git_dirty", "uncommitted changes"), ("code_sha256", "source files (code_sha256)"))
    parts = ["{} {} -> {}".format(what, *(x[k] + [None, None])[:2]) for k, what in said if isinstance(x.get(k), list)]
    if isinstance(x.get("versions"), dict):
        parts += [f"{p} {v[0]} -> {v[1]}" for p, v in x["versions"].items() if isinstance(v, list) and len(v) == 2]
    return f"session {x.get('session')}: " + ", ".join(parts)


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
            ("commit", f"<span class='mono'>{_esc(meta.get('git_commit') or 'not a git checkout')}</span>"
                       + (" <b>with uncommitted changes to tracked files</b>" if meta.get("git_dirty") else "")),
            ("command", f"<span class='mono'>{_esc(meta.get('command', ''))}</span>")]
    protocol = "; ".join(x for x in (_timing_text(meta), _others_text(frames)) if x)
    if protocol:
        rows.append(("timing protocol", _esc(protocol)))
    if workers and cores and workers > 1:
        rows.append(("timing", f"<span class='warn'>{workers} cases ran in parallel on {cores} cores: timings include "
                               "contention; use <code>--workers 1</code> for timing-grade numbers.</span>"))
    key_vers = ", ".join(f"{k} {v}" for k, v in vers.items() if v)
    rows.append(("versions", _esc(key_vers)))
    changed = [x for x in meta.get("provenance_changed") or [] if isinstance(x, dict)]
    if changed:
        rows.append(("provenance", "<span class='warn'>" + _esc(
            f"{len(changed)} later session(s) ran other code or packages than the commit and versions above, "
            "so the rows mix both: " + "; ".join(_provenance_text(x) for x in changed)) + "</span>"))
    solver = meta.get("solver")
    if isinstance(solver, dict) and solver:
        rows.append(("linear solvers", _esc(_solver_text(solver))))
    info = "".join(f"<tr><th>{k}</th><td>{v}</td></tr>" for k, v in rows)
    cfg = json.dumps(meta.get("config", {}), indent=2, default=str)
    return (f"<section id='overview'><h2>Run</h2><table class='info'>{info}</table>"
            f"<details class='config'><summary>config ({_esc(meta.get('config_source', 'run.json'))})</summary>"
            f"<pre>{_esc(cfg)}</pre></details>"
            f"<h3>Cases by status</h3>{_status_html(frames)}<h3>Errors, grouped by message</h3>{_errors_html(frames)}"
            f"{_tune_html(meta, frames)}"
            "</section>")
