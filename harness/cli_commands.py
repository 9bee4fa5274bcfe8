"""The `shootout` subcommands behind `harness.cli`'s parser: one ``_cmd_<command>(args)`` per
command (run, methods, datasets, report, views, eval, compare) that returns its exit code, and
the helpers only they use. A command's problems are raised as one `ShootoutError` (`harness.cli`
prints it; exit 2 unless it says otherwise); each imports what it runs when it is called, so
importing the command line loads none of it.
"""
from __future__ import annotations

import sys
from pathlib import Path

from .errors import ConfigError, ShootoutError


def check_output_file(path, flag: str, protect=(), run_dirs=(), kind=None) -> None:
    """`harness.results.check_output_file`, imported when a command needs it."""
    from .results import check_output_file as check
    check(path, flag, protect=protect, run_dirs=run_dirs, kind=kind)


def _cmd_run(a) -> int:
    from .config import load_config
    from .errors import problems_error
    from .results import out_dir_problems
    from .session import run_args_problems
    P = run_args_problems(a.workers, a.timeout, a.executor, a.scheduler)   # every problem, then one message
    if a.out is not None and not a.out.strip():
        P.append("--out: an empty path; give the run folder, or leave --out out for results/<name>")
        a.out = None
    try:
        check_output_file(a.export_benchmark_json, "--export-benchmark-json", protect=[a.config], kind="json")
    except ShootoutError as exc:
        P.append(str(exc))
    from .session import _results_config, run, scored_results
    raw = _results_config(Path(a.config))
    if raw is not None:                                       # results: score files made elsewhere
        given = [f for f, on in (("--resume", a.resume), ("--timeout", a.timeout is not None),
                                 ("--executor", a.executor != "local"), ("--scheduler", bool(a.scheduler)),
                                 ("--workers", a.workers is not None),
                                 ("--export-benchmark-json", bool(a.export_benchmark_json))) if on]
        if given:                        # scoring files runs no case: these would be silently ignored
            P.append(f"{', '.join(given)}: {a.config} is a results: config (it scores files made elsewhere and "
                     "runs no case); drop these flags")
        if a.out:
            P += out_dir_problems(Path(a.out))
        if P:                            # the config's own problems join the same message
            scored_results(raw, Path(a.config), P)
            raise problems_error(list(dict.fromkeys(P)))
        a.run_started = "scoring"         # what an interrupt leaves is not said here
        frames = run(Path(a.config), out=a.out)
        out = Path(a.out) if a.out else Path("results") / (raw[0].get("name") or "eval")
        print(_eval_summary(frames, out))
        return 0
    cfg, bad_config = None, None       # loaded even when a flag is bad: its problems join the same message
    try:
        cfg = load_config(Path(a.config))
    except ConfigError as exc:
        bad_config = exc
    out_dir = Path(a.out) if a.out else Path("results") / cfg.name if cfg is not None else None
    if out_dir is not None:
        P += out_dir_problems(out_dir, a.resume)
        try:
            check_output_file(a.export_benchmark_json, "--export-benchmark-json", run_dirs=(out_dir,), kind="json")
        except ShootoutError as exc:
            P.append(str(exc))
    if bad_config is not None and not P:
        raise bad_config
    if bad_config is not None:
        P += [f"{bad_config.source}: {p}" for p in bad_config.problems]
    if P:
        raise problems_error(list(dict.fromkeys(P)))
    from .executors import isolation, local
    reap = a.executor == "local" and a.command_process   # this process is ours: orphans of cases die here
    local.REAP = reap and isolation.become_subreaper()
    a.run_started = "cases"              # an interrupt from here on may leave rows to resume
    try:
        frames = run(cfg, out=a.out, workers=a.workers, executor=a.executor, scheduler=a.scheduler,
                     resume=a.resume, timeout=a.timeout, quiet=a.quiet,
                     export_benchmark_json=a.export_benchmark_json)
    finally:
        if local.REAP:
            local.REAP = False
            isolation.become_subreaper(False)
    out = Path(a.out) if a.out else Path("results") / cfg.name
    total = {}
    for df in frames.values():
        if "status" not in df:
            continue
        for s, n in df["status"].value_counts().items():
            total[s] = total.get(s, 0) + int(n)
    summary = ", ".join(f"{n} {s}" for s, n in sorted(total.items()))
    not_written = getattr(frames, "not_written", [])
    if not_written:                      # the rows are whole, but what the user reads was not (re)written
        print(f"{cfg.name}: {summary or 'no cases'}; not written: {'; '.join(not_written)} (see the warnings "
              f"above; `shootout report {out}` retries)")
        return 1
    print(f"{cfg.name}: {summary or 'no cases'}; report: {out / 'report.html'}")
    return 0


def _cmd_methods(a) -> int:
    from .plugins import import_methods, import_plugins
    methods = import_methods()
    if str(Path.cwd()) not in sys.path:              # a plugin beside the caller, as for a config
        sys.path.append(str(Path.cwd()))
    failed = import_plugins(a.plugin)
    if failed:
        from .errors import problems_error
        raise problems_error([f"--plugin {mod}: cannot import it ({why})" for mod, why in failed.items()])
    if not methods.all_methods(a.task):
        print(f"no method registered{' for task ' + a.task if a.task else ''} (a plugin's methods: --plugin MODULE)",
              file=sys.stderr)
    if a.json:
        import json
        print(json.dumps([method_record(m) for m in methods.all_methods(a.task)], indent=1))
        return 0
    for m in methods.all_methods(a.task):
        why = m.unavailable_reason()
        params = ", ".join(p.describe() for p in m.params.values()) or "-"
        state = "available" if why is None else f"unavailable ({why})"
        print(f"{m.name:32s} {m.task:15s} {m.library:20s} {state}")
        if m.summary:
            print(f"    {m.summary}")
        if m.cite:
            print(f"    cite: {m.cite}")
        print(f"    params: {params}")
    from methods.registry import BROKEN
    for mod, why in BROKEN.items():
        print(f"warning: module {mod} failed to import, its methods are missing: {why}", file=sys.stderr)
    return 0


def method_record(m) -> dict:
    """JSON-ready description of a registered method."""
    return {"name": m.name, "task": m.task, "library": m.library, "available": m.unavailable_reason() is None,
            "unavailable_reason": m.unavailable_reason(), "summary": m.summary, "cite": m.cite,
            "module": m.func.__module__,
            "params": [{"name": p.name, "default": p.default, "kind": p.kind, "low": p.low, "high": p.high,
                        "choices": list(p.choices) if p.choices else None, "doc": p.doc}
                       for p in m.params.values()]}


def _cmd_datasets(a) -> int:
    from .datasets import describe_all
    if a.json:
        import json
        print(json.dumps(describe_all(), indent=1, default=str))
        return 0
    print(f"{'name':24s} {'kind':18s} {'vertices':>9s} {'faces':>9s}  description")
    for r in describe_all():
        print(f"{r['name']:24s} {r['kind']:18s} {r['vertices']:9d} {r['faces']:9d}  {r['description']}")
        if r["kind"] == "procedural":
            print(f"{'':24s} parameters (defaults; counts above are for them): {r['file'].strip('()')}")
    return 0


def _cmd_report(a) -> int:
    from . import tasks
    from .report import build_report
    from .results import RunFolder
    d = Path(a.run_dir)
    folder = RunFolder(d)
    ours = folder.run_json_state() == "ok"
    has_rows = any(folder.csv_path(t).is_file() for t in tasks.names())
    if not ours and (not has_rows or (d / "report.html").exists()):
        raise ShootoutError(f"{d}: not a run folder of mesh-shootout (no run.json of ours" +
                            ("; its report.html is not ours to replace)" if has_rows else ", no task CSV)"))
    why = folder.readable_problem()
    if why:
        raise ShootoutError(why + "; nothing written")
    lock = folder.lock("wait for it to finish: its end rebuilds the report")
    try:
        for note in _rules_changed(d):
            print(f"note: {note}", file=sys.stderr)
        meta = folder.read_run_json() or {}
        if ours and meta.get("kind") != "eval":      # the rankings too: an interrupted run's, or a failed write's
            from .leaderboard import write as write_leaderboard
            from .results import recorded_specs, with_not_run
            frames = with_not_run(folder.frames(), folder.read_plan())
            write_leaderboard(d, frames, recorded_specs(meta, frames))
        print(build_report(d))
    finally:
        lock.close()
    return 0


def _rules_changed(run_dir: Path) -> list[str]:
    """Tasks whose axis parameters or validity rules in the folder's run.json differ from this
    version's: the report keeps the recorded ones (it reads files only), a rerun applies these."""
    from . import tasks
    from .results import RunFolder
    recorded = (RunFolder(run_dir).read_run_json() or {}).get("tasks") or {}
    if not isinstance(recorded, dict):
        return []
    def norm(x):              # a rule's absent and None fields are the same rule
        return [{k: v for k, v in r.items() if v is not None} if isinstance(r, dict) else r for r in x or []]
    out = []
    for name, spec in recorded.items():
        try:
            now = tasks.get(name).spec()
        except KeyError:
            continue
        if not isinstance(spec, dict):
            continue
        keys = [k for k in ("axis_params", "invalid_when") if k in spec and norm(spec[k]) != norm(now[k])]
        if keys:
            out.append(f"{name}: this run ranks by the {' and '.join(keys)} recorded when it ran; this version "
                       "declares others (rerun the config to apply them)")
    return out


def _cmd_views(a) -> int:
    from .session import recompute_views
    from .results import RunFolder
    d = Path(a.run_dir)
    folder = RunFolder(d)
    if not folder.run_json.exists():
        raise ShootoutError(f"{d}: not a run folder (no run.json)")
    if (folder.read_run_json() or {}).get("kind") == "eval":
        raise ShootoutError(f"{d}: holds the scores of `shootout eval`, which has no cases to run again; its "
                            "report is `shootout report`")
    lock = folder.lock("wait for it to finish: its end rebuilds the views and the report")
    try:
        print(f"shootout views: rebuilding the cases from {d / 'run.json'} and running the chosen ones again "
              "(this executes the methods, including plugins named there)", file=sys.stderr)
        views = recompute_views(d)
        from .report import build_report
        failed = [v for v in views if v.get("error")]
        kept = [v for v in views if v.get("kept")]
        print(f"{len(views)} view(s) written to {d / 'views'}" + (f", {len(failed)} of them failed (first: case "
              f"{failed[0].get('case_id')}: {failed[0]['error'][:300]})" if failed else "")
              + (f", {len(kept)} kept as the run made them (first: case {kept[0].get('case_id')}: "
                 f"{kept[0]['kept'][:300]})" if kept else "")
              + f"; report: {build_report(d)}")
    finally:
        lock.close()
    return 0


def _cmd_eval(a) -> int:
    from .scoring import eval_files
    frames = eval_files(a.clean, a.results, a.out, noisy=a.noisy, task=a.task, labels=a.label,
                        hausdorff_samples=a.hausdorff_samples, target_faces=a.target_faces,
                        target_ratio=a.target_ratio, hausdorff_eps=a.hausdorff_eps)
    print(_eval_summary(frames, Path(a.out)))
    return 0


def _eval_summary(frames, out: Path) -> str:
    """One line: how many results were scored, how many are error rows, where the report is."""
    n = sum(len(df) for df in frames.values())
    bad = sum(int((df["status"] != "ok").sum()) for df in frames.values() if "status" in df)
    return (f"eval: {n} result(s) scored" + (f", {bad} of them error rows (see their error column)" if bad else "")
            + f"; report: {out / 'report.html'}")


def _cmd_compare(a) -> int:
    from .compare import TIME_FACTOR, compare_runs
    from .errors import problems_error
    problems = [f"compare: {d} is not a run folder" for d in (a.run_a, a.run_b) if not Path(d).is_dir()]
    if a.time_factor is not None and (isinstance(a.time_factor, str) or not 1 < a.time_factor < float("inf")):
        problems.append(f"--time-factor: expected a finite number > 1, got {a.time_factor!r}")
    if a.no_time and (a.time_factor is not None or a.absolute_time):
        problems.append("--no-time compares no times: --time-factor and --absolute-time would be ignored; "
                        "give one or the other")
    try:
        check_output_file(a.html, "--html", run_dirs=(a.run_a, a.run_b), kind="html")
    except ShootoutError as exc:
        problems.append(str(exc))
    if problems:
        raise problems_error(problems)
    factor = None if a.no_time else (a.time_factor or TIME_FACTOR)
    return compare_runs(a.run_a, a.run_b, html_out=a.html, time_factor=factor, absolute_time=a.absolute_time)
