"""``shootout compare RUN_A RUN_B``: match cases by ``case_id``, show what changed, flag regressions.

RUN_A is the baseline, RUN_B the candidate. For every case present in both runs and every
metric column, the two values are compared with the rule its task declares (`harness.tasks`:
each metric's ``better`` direction and ``rel``/``abs`` tolerance, recorded in run.json; the
baseline's rule where the two runs declare different ones, and a note names those metrics).
Two rows with one case id that describe different cases (task, mesh, method, params, noise or
seed differ) are listed as ``changed`` and not compared; a folder with a case id in two rows is
refused:

* error-like metrics (lower is better: ``ev_*``, ``dist_mean``, ``hausdorff``, normal errors,
  ``sym_error``, ``lin_error``, ``neg_weights``, ``obtuse_fraction``, ``max_angle``) regress when
  ``b > a + max(rel * |a|, abs)``: worse by more than ``rel`` (1 %) relative *and* more than a
  small absolute amount (lengths are fractions of the bounding-box diagonal, so ``1e-6`` is
  far below anything visible; angles ``0.01`` degrees); a sampled one (``Rule.se``:
  ``surface_dist_mean``) also only beyond ``se_z`` combined standard errors, and a certified
  bracket (``Rule.upper``: ``hausdorff`` to ``hausdorff_upper``) only when the two brackets lie
  apart by more than that;
* quality metrics (higher is better: ``min_angle``, ``radius_ratio_mean``, ``min_eig``) regress
  when ``b < a - max(rel * |a|, abs)``;
* ratios that should be 1 (``volume_ratio``, ``area_ratio``) regress when ``|b - 1|`` grows
  by more than ``max(1 % of |a - 1|, 1e-4)``;
* flags regress when a good value turns bad: ``SYM LOC LIN POS psd operator_symmetric manifold``
  true -> false, ``diverged topology_changed`` false -> true; ``loc_violations`` may not grow;
* a count with a target (``out_faces``, ``Metric.target``: ``target_faces``) regresses when its
  miss of the target grows by more than ``1 % of the target + 2`` (`harness.tasks.base.target_tolerance`,
  which also decides simplification's ``over_target``);
* a value that becomes blank (not measurable any more) regresses; one that appears improves;
  except a sampled metric's when the runs drew another number of points (``hausdorff_samples``,
  0 measuring none): changed;
* time is decided on the stored samples (``times``): it regresses when B is slower with
  statistical significance *and* by a minimum effect: the one-sided Mann-Whitney U test of
  B's samples against A's gives p < ``ALPHA`` (0.01), the lower end of the 95% bootstrap
  confidence interval of the median ratio B/A exceeds ``time_factor`` (1.5: B is, with
  confidence, at least that much slower), B's fastest sample is also more than ``time_factor``
  times A's fastest, and the medians differ by more than 1 ms. A method that does more work
  slows every sample, its fastest included; a burst of load elsewhere slows some samples but
  rarely the fastest, so it widens the interval or moves the median without raising an alarm.
  The ratio is printed with its interval. Cases whose sample counts cannot reach significance
  (the exact test's smallest p, ``1 / C(n_A + n_B, n_A)``, is not below ``ALPHA``: e.g. 3
  samples a side) are inconclusive, never regressions. B's samples are first divided by the
  run's drift (the median over all cases of the ratio of median times; ``--absolute-time``
  turns this off), and the verdict must hold on the raw times too, else it is inconclusive
  (load slows multi-threaded cases more than single-threaded ones, so one drift fits neither).
  A drift of ``time_factor`` or more is itself one regression line for the whole run
  (`whole_run_change`) where neither run oversubscribed its machine, or, on a busier or
  unmeasured machine, where one thread per case was busy and the CPU time changed with the
  wall time.

  Load from other processes slows every sample, the fastest included. ``others_cpu`` is how
  many cores other processes (with several workers, the case's siblings too) kept busy from
  the first sample to the last (from the cold call in runs before 2026-11-27), blank for
  windows under 0.2 s, so runs with ``time_budget: 0`` and millisecond cases often have no
  load check; ``threads_busy`` how many
  threads of the case ran (`threads_used`). A wall-time regression (improvement) of B (A) is
  inconclusive when (threads ``t``, the slower run's load ``o``, the CPU time ratio ``c``):
  - ``t`` > 1 and ``t + o`` exceeds the cores by ``BUSY_CORES`` (0.5) or more: threads waiting
    for a core, and BLAS pools spinning while they wait, grow the wall and CPU time alike;
  - neither run measured its load, and ``t`` > 1 or ``c`` did not grow by ``time_factor``;
  - only the slower run measured its load, ``BUSY_CORES`` or more, and ``c`` did not grow by
    ``time_factor``;
  - the slower run's machine was busier by ``BUSY_CORES`` or more, ``t + o`` exceeded the cores,
    and (for one thread) ``c`` did not grow by more than ``CONTENDED_CPU`` (2) x ``time_factor``;
  - the load stretched the slower samples ``OVERSUBSCRIBED`` (1.25) times or more beyond the
    other run's (`load_stretch`: ``max(1, u / free)``, ``u`` the cores the faster row used,
    ``free`` the cores the load left), ``c`` did not grow by more than ``CONTENDED_CPU`` x
    ``time_factor``, and, where ``c`` grew with the wall time (0.75 of it or more), the change
    divided by that stretch is not past ``time_factor``
    (a waiting process's CPU time itself grows under shared caches and hyperthreads, by 1.95x
    measured here once);
  - the slower run's machine was busier by ``BUSY_CORES`` or more and ``c`` did not grow by
    ``time_factor``.
  Under equal load nothing is excused: on equally quiet machines a wall-time change counts
  whatever its CPU time does (sleeps, I/O, lost parallelism). Rows without samples fall back
  to: median over ``time_factor`` x A's, fastest B repeat slower than slowest A repeat, > 1 ms;
* a case whose result was valid and is not any more (the task's ``invalid_when`` rules, e.g.
  ``diverged``, or a smoothing result farther from the clean surface than its noisy input; both
  runs judged by the rules A's run.json recorded, or the installed kind's, and a note when B
  declares others) regresses, whatever its metrics' own verdicts; one that turns valid improves;
  one invalid for another reason changed;
* a case whose status was ok and is not any more regresses; a case of RUN_A missing in RUN_B
  regresses too (an interrupted or shrunken run must not pass CI); cases new in RUN_B are listed.

Inputs (``input_*``, ``n_vertices``, ``n_faces``) are compared only to warn that the two runs
did not see the same data. ``nnz``, ``peak_rss_mb``, ``genus_change``, ``boundary_loops_change``
are informational. Exit code: 1 if anything regressed, else 0.
"""
from __future__ import annotations

import html
import statistics
import sys
from dataclasses import replace
from pathlib import Path

from .compare_cases import IDENTITY, SKIP, _label, _rows, compare_rows, param_ids
from .compare_rules import COMMON_RULES, KNOWN, RULES, Rule, judge, rule_for, rules_from_specs
from .compare_time import (ALPHA, BOOTSTRAP, BUSY_CORES, CONTENDED_CPU, OVERSUBSCRIBED, TIME_FACTOR, TIME_FLOOR_S,
                           _fmt, busier, cpu_ratio, judge_time, load_stretch, run_drift, threads_used, time_effect,
                           time_samples, whole_run_change)
from .results import RunFolder, recorded_specs
from .schema import number as _num

__all__ = ["ALPHA", "BOOTSTRAP", "BUSY_CORES", "COMMON_RULES", "CONTENDED_CPU", "IDENTITY", "KNOWN", "ORDER", "_label",
           "OVERSUBSCRIBED", "RULES", "Rule", "SKIP", "TIME_FACTOR", "TIME_FLOOR_S", "busier", "compare_rows",
           "compare_runs", "cpu_ratio", "judge", "judge_time", "load_stretch", "param_ids", "rule_for",
           "rules_from_specs", "run_drift", "threads_used", "time_effect", "time_samples", "timing_notes",
           "whole_run_change"]


def _change(a, b) -> str:
    x, y = _num(a), _num(b)
    if x is None or y is None or isinstance(a, bool) or isinstance(b, bool):
        return ""
    if x == 0:
        return "" if y == 0 else f"{y - x:+.3g}"
    return f"{(y - x) / abs(x) * 100:+.1f}%"


ORDER = {"regression": 0, "improvement": 1, "changed": 2, "within tolerance": 3, "inconclusive": 4, "info": 5}


def _measurement(meta: dict) -> dict:
    """A run's measurement settings: run.json's ``measurement``, else its config's keys (an
    eval's under ``eval``), else the defaults; none when there is no run.json to read (``meta``
    empty: missing or damaged), as they are then not known."""
    if not meta:
        return {}
    got = meta.get("measurement") if isinstance(meta.get("measurement"), dict) else None
    if got is None:
        cfg = meta.get("config") if isinstance(meta.get("config"), dict) else {}
        cfg = cfg.get("eval") if isinstance(cfg.get("eval"), dict) else cfg
        got = {"hausdorff_samples": cfg.get("hausdorff_samples", 20000), "hausdorff_eps": cfg.get("hausdorff_eps", 1e-3)}
    return {k: got.get(k) for k in ("hausdorff_samples", "hausdorff_eps") if got.get(k) is not None}


def timing_notes(meta_a: dict, meta_b: dict, res: dict) -> list[str]:
    """Why time changes between these two runs may not mean what they seem."""
    notes = []
    ma, mb = meta_a.get("machine"), meta_b.get("machine")
    if ma and mb and any(ma[k] != mb[k] for k in ma.keys() & mb.keys()):     # keys one version records alone: not a difference
        notes.append("the runs come from different machines: time changes compare different hardware")
    wa, wb = meta_a.get("workers"), meta_b.get("workers")
    if wa and wb and wa != wb:
        notes.append(f"A ran {wa} worker(s) in parallel, B {wb}: time changes include a different contention")
    elif (wa or 1) > 1 and ma and (ma.get("cpu_count") or 0) <= (wa or 1):
        notes.append(f"{wa} workers on {ma.get('cpu_count')} cores: timings include contention "
                     "(run both with --workers 1 for timing-grade comparisons)")
    drift = res.get("drift", 1.0)
    if abs(drift - 1.0) > 0.1:
        how = ("judged without correcting for it (--absolute-time)" if res.get("absolute_time") else
               "each case's time is judged relative to this common factor (--absolute-time to judge raw times)")
        notes.append(f"B ran {drift:.2f}x A's time overall (median over cases): a busier or faster machine "
                     f"slows or speeds every case alike; {how}")
    la, lb = meta_a.get("load_average"), meta_b.get("load_average")
    if la or lb:
        notes.append(f"load average (1 min) at start/end: A {la}, B {lb}")
    busy = []
    for rows in (res["rows_a"], res["rows_b"]):
        v = sorted(x for x in (_num(r.get("others_cpu")) for r in rows.values()) if x is not None)
        busy.append(f"{statistics.median(v):.2g} (max {v[-1]:.2g}, {len(v)} cases)" if v else "not measured")
    if busy != ["not measured", "not measured"]:
        notes.append(f"cores other processes kept busy during the timed calls (others_cpu, median): A {busy[0]}, "
                     f"B {busy[1]}; what the load average says may differ (it counts waiting processes)")
    n_inc = sum(c["verdict"] == "inconclusive" for c in res["changes"])
    if n_inc:
        notes.append(f"{n_inc} case(s) are inconclusive on time (not counted as regressions): too few timed samples "
                     "on one side (raise repeats or time_budget), a wall-time change that other processes' load "
                     "explains, or a change the raw times and the times relative to the run's drift disagree on "
                     "(each case's note is in the --html page)")
    if any(time_samples(r) is None for r in list(res["rows_a"].values()) + list(res["rows_b"].values())
           if r.get("status") == "ok" and r.get("library") != "external"):        # eval rows have no time at all
        notes.append("some rows store no timed samples (older runs): their time is judged on median/min/max only")
    return notes


def _sorted(changes):
    return sorted(changes, key=lambda c: (ORDER.get(c["verdict"], 9), c["task"], c["case"], c["metric"]))


def compare_runs(run_a, run_b, html_out=None, time_factor: float | None = TIME_FACTOR, out=None,
                 max_lines: int = 200, absolute_time: bool = False) -> int:
    """Print the changes from RUN_A (baseline) to RUN_B; write an HTML diff if asked; 1 on a regression.

    ``time_factor=None`` (or 0) leaves timings out (metrics only), e.g. for runs from different machines.
    """
    out = out or sys.stdout
    meta_a = RunFolder(run_a).read_run_json() or {}
    meta_b = RunFolder(run_b).read_run_json() or {}
    ra = _rows(run_a, meta=meta_a)
    spec_a = recorded_specs(meta_a, {r["task"]: None for r in ra.values()})
    rb = _rows(run_b, spec_a, meta_b)                # validity by the baseline's rules, as its metrics' tolerances
    spec_b = recorded_specs(meta_b, {r["task"]: None for r in rb.values()})
    other_validity = sorted(t for t in spec_a.keys() & spec_b.keys()
                            if spec_a[t].get("invalid_when") != spec_b[t].get("invalid_when"))
    rules_a, rules_b = rules_from_specs(meta_a.get("tasks")), rules_from_specs(meta_b.get("tasks"))
    rules = {t: {**rules_b.get(t, {}), **rules_a.get(t, {})} for t in {*rules_a, *rules_b}}   # the baseline's rules
    for t in rules_a.keys() & rules_b.keys():   # a standard-error column either run names is read (older A: none)
        for m in rules_a[t].keys() & rules_b[t].keys():
            if not rules_a[t][m].se and rules_b[t][m].se:
                rules[t][m] = replace(rules_a[t][m], se=rules_b[t][m].se, se_z=rules_b[t][m].se_z)
    for t, rs in rules.items():       # a target or bracket column A does not name (older run.json): B's, or the kind's
        for m, r in rs.items():
            b, known = rules_b.get(t, {}).get(m) or r, rule_for(m, t)
            if r.kind == "target" and not r.target:
                rs[m] = r = replace(r, target=b.target or known.target)
            if r.kind == "lower" and not r.upper and (b.upper or known.upper) and known.kind == "lower":
                rs[m] = replace(r, upper=b.upper or known.upper)
    other_rules = sorted(f"{t}.{m}" for t in rules_a.keys() & rules_b.keys()
                         for m in rules_a[t].keys() & rules_b[t].keys()
                         if replace(rules_a[t][m], se="", se_z=3.0, target="", upper="")
                         != replace(rules_b[t][m], se="", se_z=3.0, target="", upper=""))
    ca, cb = ((m.get("machine") or {}).get("cpu_count") for m in (meta_a, meta_b))
    threads = tuple((m.get("timing") or {}).get("threads_per_case") if isinstance(m.get("timing"), dict) else None
                    for m in (meta_a, meta_b))
    threads = tuple(t if isinstance(t, int) and not isinstance(t, bool) and t > 0 else None for t in threads)
    ma_, mb_ = _measurement(meta_a), _measurement(meta_b)
    differ = [f"{k} A {ma_[k]}, B {mb_[k]}" for k in ma_ if k in mb_ and ma_[k] != mb_[k]]
    res = compare_rows(ra, rb, time_factor, rules, absolute_time, cores=ca if ca == cb else None, threads=threads,
                       samples_differ=not ma_ or not mb_ or ma_.get("hausdorff_samples") != mb_.get("hausdorff_samples"),
                       ids=param_ids(meta_a, meta_b))
    changes = _sorted(res["changes"])
    regress = [c for c in changes if c["verdict"] == "regression"]
    shown = [c for c in changes if c["verdict"] not in ("within tolerance", "info", "inconclusive")]
    quiet = sum(c["verdict"] == "within tolerance" for c in changes)
    n_info = sum(c["verdict"] == "info" for c in changes)
    print(f"compare A={run_a} (baseline) B={run_b}: {res['common']} cases in both, "
          f"{len(res['only_a'])} only in A, {len(res['only_b'])} only in B", file=out)
    for note in (timing_notes(meta_a, meta_b, res) if time_factor else []):     # --no-time: no timing notes
        print(f"note: {note}", file=out)
    for which, meta, run in (("A", meta_a, run_a), ("B", meta_b, run_b)):
        if not meta:
            print(f"note: {which}'s run.json is {RunFolder(run).run_json_state()}: its measurement settings, metric "
                  "rules and validity rules are not known; the installed version's rules are used, and a sampled "
                  "value only one run has is a change, not a regression", file=out)
        if meta.get("status") in ("running", "interrupted"):
            print(f"note: {which}'s run.json says {meta['status']}: the run is still going, was killed or was "
                  "interrupted, so a case missing from it may not have run yet (--resume finishes it)", file=out)
    code = [(m.get("code_sha256"), m.get("git_commit"), m.get("git_dirty")) for m in (meta_a, meta_b)]
    if code[0][0] and code[1][0] and code[0][0] != code[1][0]:
        said = [f"{w} {(c or '?')[:10]}{' with uncommitted changes' if d else ''}" for w, (_, c, d) in zip("AB", code)]
        print(f"note: the runs ran different code ({', '.join(said)}; their code_sha256 differ): a change may be "
              "the code's", file=out)
    if res["common"] == 0 and res["only_a"] and res["only_b"]:
        print("note: the runs share no case: they ran other configs (or meshes whose files changed), so every case "
              "of A counts as missing in B", file=out)
    if res["unmatched_columns"]:
        cols = ", ".join(f"{t}.{m} (only in {w})" for t, m, w in res["unmatched_columns"][:8])
        print(f"note: not compared, a column only one run's CSV has (another version wrote it?): {cols}"
              + (f" and {len(res['unmatched_columns']) - 8} more" if len(res["unmatched_columns"]) > 8 else ""),
              file=out)
    if differ:
        print(f"note: the runs measured with other settings ({'; '.join(differ)}): sampled metrics "
              "(surface_dist_mean) differ by their sampling too, within their standard errors; certified brackets "
              "(hausdorff to hausdorff_upper) count only where they lie apart; a sampled value one run did not "
              "measure (hausdorff_samples 0) is a change, not a regression", file=out)
    if other_rules:
        print(f"note: B declares other rules (direction or tolerance) for {len(other_rules)} metric(s), e.g. "
              f"{', '.join(other_rules[:5])}: A's (the baseline's) are used", file=out)
    if other_validity:
        print(f"note: B declares other validity rules (invalid_when) for {', '.join(other_validity)}: both runs' "
              "results are judged valid or not by A's (the baseline's)", file=out)
    if res["input_changes"]:
        n = len({c['case_id'] for c in res['input_changes']})
        print(f"warning: {n} case(s) saw different input data (mesh or noise changed): "
              + ", ".join(sorted({c['metric'] for c in res['input_changes']})), file=out)
    if shown:
        w = max(12, min(90, max(len(c["case"]) for c in shown)))
        head = (f"{'verdict':11s} {'task':14s} {'case id':12s} {'case':{w}s} {'metric':22s} {'A':>11s} {'B':>11s} "
                f"{'change':>9s}")
        print(head, file=out)
        print("-" * len(head), file=out)
        for c in shown[:max_lines]:
            flag = "REGRESSION" if c["verdict"] == "regression" else c["verdict"]
            case = c["case"] if len(c["case"]) <= w else c["case"][:w - 1] + "…"
            line = (f"{flag:11s} {c['task']:14s} {c['case_id']:12s} {case:{w}s} {c['metric']:22s} {_fmt(c['a']):>11s} "
                    f"{_fmt(c['b']):>11s} {_change(c['a'], c['b']):>9s}")
            if c.get("note"):
                line += f"  {c['note']}"
            print(line, file=out)
        if len(shown) > max_lines:
            print(f"... {len(shown) - max_lines} more changes (see --html)", file=out)
    n_imp = sum(c["verdict"] == "improvement" for c in changes)
    print(f"{len(regress)} regression(s) in {len({c['case_id'] for c in regress})} case(s), {n_imp} improvement(s), "
          f"{quiet} change(s) within tolerance, {n_info} informational (peak_rss_mb ...); tolerances: each metric's "
          f"declared rel/abs (errors: worse by >1% and a small absolute amount; " +
          (f"time: Mann-Whitney p<{ALPHA:g}, the 95% interval of the median ratio and the ratio of the fastest samples above {time_factor:g}x)"
           if time_factor else "time not compared)"), file=out)
    if res["only_b"]:
        print(f"new in B: {len(res['only_b'])} case(s), e.g. " + ", ".join(_label(rb[c]) for c in res["only_b"][:3]),
              file=out)
    if html_out:
        Path(html_out).parent.mkdir(parents=True, exist_ok=True)
        Path(html_out).write_text(_html(run_a, run_b, res, changes, time_factor), encoding="utf-8")
        print(f"HTML diff: {html_out}", file=out)
    return 1 if regress else 0


def _html(run_a, run_b, res, changes, time_factor) -> str:
    e = html.escape
    colors = {"regression": "#fdecec", "improvement": "#e8f5ec", "changed": "#fff8e1", "within tolerance": "#fff"}
    rows = "".join(
        f"<tr style='background:{colors.get(c['verdict'], '#fff')}'><td>{e(c['verdict'])}</td><td>{e(c['task'])}</td>"
        f"<td>{e(c['case'])}</td><td><code>{e(c['case_id'])}</code></td><td>{e(c['metric'])}</td>"
        f"<td class=n>{e(_fmt(c['a']))}</td><td class=n>{e(_fmt(c['b']))}</td><td class=n>{e(_change(c['a'], c['b']))}</td>"
        f"<td>{e(c.get('note', ''))}</td></tr>" for c in changes)
    n_reg = sum(c["verdict"] == "regression" for c in changes)
    summary = (f"{res['common']} cases in both runs, {len(res['only_a'])} only in A, {len(res['only_b'])} only in B; "
               f"<b>{n_reg} regression(s)</b>.")
    doc = e(__doc__ or "")
    return ("<!doctype html><html><head><meta charset='utf-8'><title>mesh-shootout compare</title><style>"
            "body{font:14px system-ui,sans-serif;margin:20px;color:#1d2330}table{border-collapse:collapse;font-size:12px}"
            "td,th{border:1px solid #d9dee7;padding:3px 6px;text-align:left}td.n{text-align:right;font-variant-numeric:tabular-nums}"
            "pre{background:#f5f7fa;padding:8px;white-space:pre-wrap;font-size:12px}</style></head><body>"
            f"<h1>mesh-shootout compare</h1><p>A (baseline): <code>{e(str(Path(run_a).resolve()))}</code><br>"
            f"B (candidate): <code>{e(str(Path(run_b).resolve()))}</code></p><p>{summary}</p>"
            f"<table><tr><th>verdict</th><th>task</th><th>case</th><th>id</th><th>metric</th><th>A</th><th>B</th>"
            f"<th>change</th><th>note</th></tr>{rows}</table>"
            f"<details><summary>Tolerances (time factor {time_factor or 'off'})</summary><pre>{doc}</pre></details>"
            "</body></html>")
