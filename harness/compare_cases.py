"""The rows of two run folders matched by case id, and every change between them.

`_rows` reads a run folder's rows (``{case_id: row}``, each with its task and why it is not a
valid result by the task's ``invalid_when`` rules), refusing a folder with a case id in two
rows; `compare_rows` matches the two runs' rows by case id (rows with one id that describe
different cases, by ``IDENTITY``, are listed as changed) and lists each status, validity, time
and metric change with its verdict (`harness.compare_rules.judge`,
`harness.compare_time.judge_time`), the cases only one run has, and the inputs that differ.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

from .compare_rules import _blank, judge, rule_for
from .compare_time import TIME_FACTOR, _time_note, judge_time, run_drift, whole_run_change
from .core.params import id_form
from .errors import ShootoutError
from .leaderboard import params_text, validity
from .results import RunFolder, recorded_specs
from .schema import number as _num

SKIP = {"case_id", "task", "mesh", "noise_model", "noise_level", "seed", "method", "library", "params",
        "status", "error", "time_s", "time_min_s", "time_max_s", "time_q1_s", "time_q3_s", "time_cold_s", "times",
        "time_cpu_s", "cpu_times", "others_cpu", "threads_busy",
        "method_mem_mb", "repeats", "min_angle_hist"}


def _rows(run, specs: dict | None = None, meta: dict | None = None) -> dict[str, dict]:
    """``{case_id: row}`` of a run folder, each row with ``task`` and ``_invalid`` (why it is not a
    valid result, by ``specs``' rules for its task where given, else by its own run's: ``meta``,
    its run.json, read here when not given)."""
    folder = RunFolder(run)
    if not Path(run).is_dir():
        raise ShootoutError(f"{run}: no such run folder")
    from . import tasks
    unknown = folder.missing_task_kinds()
    if unknown:               # a task kind this installation lacks (e.g. a fork's harness/tasks/area.py): its rows
        raise ShootoutError(f"{run}: its task kind(s) {', '.join(unknown)} are not known to this installation "
                            f"(known: {', '.join(tasks.names())}), so their rows could not be compared; compare it "
                            "with the version that made it")
    frames = folder.frames()
    if not frames:
        raise ShootoutError(f"{run}: not a run folder (no task CSV such as smoothing.csv)")
    meta = (folder.read_run_json() or {}) if meta is None else meta
    specs = {**recorded_specs(meta, frames), **(specs or {})}
    out, twice = {}, set()
    for task, df in frames.items():
        why = validity(specs.get(task) or {"name": task}, df, measured=True)
        for rec, bad in zip(df.to_dict("records"), why):
            rec = {k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in rec.items()}
            rec["task"], rec["_invalid"] = task, bad if rec.get("status") == "ok" else ""
            cid = str(rec["case_id"])
            if cid in out:
                twice.add(cid)
            out[cid] = rec
    if twice:
        raise ShootoutError(f"{run}: {len(twice)} case id(s) appear in more than one row (first: "
                            f"{sorted(twice)[0]}): a run folder holds one row per case; which one to compare is "
                            "not decidable")
    return out


IDENTITY = ("task", "mesh", "method", "params", "noise_model", "noise_level", "seed")


def _label(r: dict) -> str:
    try:
        p = json.loads(r.get("params") or "{}")
    except json.JSONDecodeError:
        p = {}
    ps = params_text(p if isinstance(p, dict) else {})
    lvl, seed = r.get("noise_level"), _num(r.get("seed"))
    noise = str(r.get("noise_model")) if _blank(lvl) else f"{r.get('noise_model')} {lvl:g}"
    noise += "" if seed is None or not math.isfinite(seed) else f" seed {seed:g}"    # two seeds: two cases
    return f"{r.get('mesh')} {noise} {r.get('method')}[{ps}]"


def _params_identity(r: dict, ids: dict | None = None) -> str:
    """A row's parameters as its case id records them (`harness.core.params.id_form` under
    ``ids``, ``{method: id_spec}`` from the runs' run.json: a renamed parameter under its old
    name, an added one left out at its default), so a run recorded before a rename or an
    addition describes the same case as one after it."""
    try:
        p = json.loads(str(r.get("params")))
    except (TypeError, ValueError):
        return str(r.get("params"))
    if not isinstance(p, dict):
        return str(r.get("params"))
    return json.dumps(id_form(p, (ids or {}).get(str(r.get("method")))), sort_keys=True, default=str)


def param_ids(*metas) -> dict:
    """``{method: id_spec}`` the runs' run.json record (`harness.session.task_specs`), merged."""
    out: dict = {}
    for meta in metas:
        for spec in ((meta or {}).get("tasks") or {}).values():
            ids = spec.get("param_ids") if isinstance(spec, dict) else None
            if isinstance(ids, dict):
                out.update({m: v for m, v in ids.items() if isinstance(v, dict)})
    return out


def compare_rows(rows_a: dict, rows_b: dict, time_factor: float | None = TIME_FACTOR, rules=None,
                 absolute_time: bool = False, load_rule: bool = True, cores: int | None = None,
                 threads: tuple | None = None, samples_differ: bool = False, ids: dict | None = None) -> dict:
    """Every change between two runs' rows: ``{"changes": [...], "only_a": [...], "only_b": [...], ...}``.

    ``rules``: ``{task: {metric: Rule}}`` from the runs' task declarations (default: the known tasks).
    Times are judged relative to the whole run's drift (`run_drift`) unless ``absolute_time``;
    ``load_rule``: the other processes' load may make a time change inconclusive (`judge_time`;
    ``cores``, the core count both runs' machines share, lets `load_stretch` do so; ``threads``,
    A's and B's threads per case). A drift of
    ``time_factor`` or more (or its inverse) on machines that were not oversubscribed
    (`whole_run_change`) is itself a change of the whole run: every case slowed alike, which no case's verdict relative to the
    drift can see. ``samples_differ``: the runs drew another number of points (`_measurement`'s
    ``hausdorff_samples``; 0 measures no sampled metric), so a sampled metric's value (``Rule.se``)
    one of them left blank was not measured there: changed, not a regression. ``ids``: how case
    ids record renamed and added parameters (`param_ids`), so rows recorded before and after one
    compare as the same case.
    """
    changes, input_changes = [], []
    unmatched: set = set()
    drift = run_drift(rows_a, rows_b)
    used_drift = 1.0 if absolute_time else drift
    common = [c for c in rows_a if c in rows_b]
    for cid in common:
        ra, rb = rows_a[cid], rows_b[cid]
        base = {"case_id": cid, "task": ra["task"], "case": _label(ra)}
        # eval: not the result's path (params), nor the clean mesh's name, which depends on the other
        # clean files of that eval; its case id hashes the clean mesh's bytes
        keys = IDENTITY if ra.get("library") != "external" else [k for k in IDENTITY if k not in ("params", "mesh")]
        differ = [k for k in keys if (_params_identity(ra, ids) != _params_identity(rb, ids) if k == "params"
                                      else str(ra.get(k)) != str(rb.get(k)))]
        if differ:                          # one id, two different cases (e.g. two evals' files in another order)
            changes.append({**base, "metric": "case", "a": _label(ra), "b": _label(rb), "verdict": "changed",
                            "note": f"not compared: the rows describe different cases ({', '.join(differ)} differ)"})
            continue
        sa, sb = ra.get("status"), rb.get("status")
        if sa != sb:
            verdict = "regression" if sa == "ok" else ("improvement" if sb == "ok" else "changed")
            changes.append({**base, "metric": "status", "a": sa, "b": sb, "verdict": verdict,
                            "note": str(rb.get("error") or "")[:200]})
        if sa == "ok" and sb == "ok" and time_factor:
            v = judge_time(ra, rb, time_factor, used_drift, load_rule, cores, threads)
            a, b = _num(ra.get("time_s")), _num(rb.get("time_s"))
            if a is not None and b is not None and a != b:
                changes.append({**base, "metric": "time_s", "a": a, "b": b,
                                "verdict": "within tolerance" if v == "same" else v,
                                "note": _time_note(ra, rb, used_drift)})
        if sa != "ok" or sb != "ok":
            continue
        wa, wb = ra.get("_invalid") or "", rb.get("_invalid") or ""
        if wa != wb:                 # a valid result turned invalid (e.g. diverged, worse than its input), or back
            why = "; ".join(f"{w} invalid: {x}" for w, x in (("A", wa), ("B", wb)) if x)
            changes.append({**base, "metric": "validity", "a": "invalid" if wa else "valid",
                            "b": "invalid" if wb else "valid",
                            "verdict": "regression" if not wa else ("improvement" if not wb else "changed"),
                            "note": f"{why} (the task's invalid_when rules, A's)"})
        for metric in {**ra, **rb}:
            if metric in SKIP or metric.startswith("_"):
                continue
            if metric not in ra or metric not in rb:     # a column one version writes and the other not
                unmatched.add((ra["task"], metric, "A" if metric in ra else "B"))
                continue
            a, b = ra.get(metric), rb.get(metric)
            rule = rule_for(metric, rb.get("task"), rules)
            verdict = judge(metric, a, b, ra, rb, rule=rule)
            if verdict == "same":
                if not (_blank(a) and _blank(b)) and a != b and not (_num(a) == _num(b) and _num(a) is not None):
                    changes.append({**base, "metric": metric, "a": a, "b": b, "verdict": "within tolerance"})
                continue
            if verdict == "changed" and rule.kind == "info":
                verdict = "info"              # e.g. peak_rss_mb: counted, not listed
            note = ""
            if samples_differ and rule.se and verdict in ("regression", "improvement") and _blank(a) != _blank(b):
                verdict, note = "changed", "not measured by one run's settings"
            entry = {**base, "metric": metric, "a": a, "b": b, "verdict": verdict, **({"note": note} if note else {})}
            (input_changes if rule.kind == "input" else changes).append(entry)
    whole = (whole_run_change(rows_a, rows_b, drift, time_factor, cores, threads) if time_factor and not absolute_time
             else None)
    if whole is not None:
        changes.append(whole)
    only_a = [c for c in rows_a if c not in rows_b]
    only_b = [c for c in rows_b if c not in rows_a]
    for cid in only_a:
        r = rows_a[cid]
        changes.append({"case_id": cid, "task": r["task"], "case": _label(r), "metric": "case", "a": r.get("status"),
                        "b": None, "verdict": "regression", "note": "missing in RUN_B"})
    return {"changes": changes, "input_changes": input_changes, "unmatched_columns": sorted(unmatched),
            "common": len(common), "only_a": only_a,
            "only_b": only_b, "rows_a": rows_a, "rows_b": rows_b, "drift": drift, "absolute_time": absolute_time}
