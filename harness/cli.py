"""`shootout` command line. Exit codes: 0 finished, 1 internal failure (or `compare` found a
regression), 2 bad config or arguments (one message, nothing written)."""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from .errors import ConfigError, ShootoutError


class _Parser(argparse.ArgumentParser):
    def error(self, message):                       # argparse exits 2 as well; keep one style
        self.print_usage(sys.stderr)
        print(f"shootout: error: {message}", file=sys.stderr)
        raise SystemExit(2)


def _number(kind):
    """An argparse type that converts to ``kind`` when it can and keeps the text otherwise, so a
    malformed number is listed with the config's and the other flags' problems in one message
    (argparse would stop at the first)."""
    def convert(text: str):
        try:
            return kind(text)
        except ValueError:
            return text
    convert.__name__ = kind.__name__
    return convert


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="shootout", description="Compare geometry-processing methods (Laplacians, smoothing, simplification, geodesics, curvature, spectra).")
    from . import __version__
    p.add_argument("--version", action="version", version=f"mesh-shootout {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    r = sub.add_parser("run", help="run a config and write its run folder")
    r.add_argument("config")
    r.add_argument("--out", help="run folder (default results/<name>)")
    r.add_argument("--workers", type=_number(int), help="cases in parallel (default: number of cores; 1 for timing-grade numbers)")
    r.add_argument("--executor", choices=["local", "dask", "serial"], default="local")
    r.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://host:8786")
    r.add_argument("--resume", action="store_true", help="skip cases already recorded with status ok")
    r.add_argument("--timeout", type=_number(float), help="seconds per case before it is killed (status timeout)")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    r.add_argument("--export-benchmark-json", metavar="FILE", help="also write timings in pytest-benchmark's JSON layout")
    m = sub.add_parser("methods", help="list registered methods")
    from . import tasks                     # here, not at import: main's Ctrl-C handler is set by now
    m.add_argument("--task", choices=tasks.names())
    m.add_argument("--json", action="store_true", help="machine-readable: one JSON list")
    m.add_argument("--plugin", action="append", default=[], metavar="MODULE",
                   help="import this plugin module first (as a config's plugins:), to list its methods")
    ds = sub.add_parser("datasets", help="list bundled and procedural meshes")
    ds.add_argument("--json", action="store_true", help="machine-readable: one JSON list")
    rp = sub.add_parser("report", help="rebuild report.html, the leaderboard and the winners from a run folder "
                                       "(reads files only, runs no code)")
    rp.add_argument("run_dir")
    vw = sub.add_parser("views", help="recompute a run folder's 3D views (runs the chosen methods again)")
    vw.add_argument("run_dir")
    ev = sub.add_parser("eval", help="score result meshes made elsewhere; writes a run folder and its report")
    ev.add_argument("results", nargs="+", metavar="RESULT", help="result mesh files (OBJ, OFF, PLY, STL)")
    ev.add_argument("--clean", required=True, help="the clean (reference) mesh")
    ev.add_argument("--noisy", help="the noisy input the results were made from (smoothing: the input_* columns; "
                    "simplification: the surface a result is compared to, as in a run; without it, the clean mesh)")
    ev.add_argument("--out", required=True, help="run folder to write")
    ev.add_argument("--task", choices=["smoothing", "simplification"],
                    help="default: smoothing when a result has the clean mesh's vertex and face counts, else simplification")
    ev.add_argument("--label", action="append", metavar="NAME",
                    help="method label of each result, in order, one per --label (--label a --label b: one name "
                         "each, so a result file after it is never read as a label; default: file stem)")
    ev.add_argument("--hausdorff-samples", type=_number(int), default=20000, help="area samples per side (as in a config)")
    ev.add_argument("--hausdorff-eps", type=_number(float), default=1e-3, metavar="EPS",
                    help="relative gap the certified Hausdorff distance aims for (as in a config; default 1e-3)")
    ev.add_argument("--target-faces", type=_number(int), default=None, metavar="N",
                    help="simplification: the face count the results were asked for (judges over_target)")
    ev.add_argument("--target-ratio", type=_number(float), default=None, metavar="R",
                    help="simplification: the fraction of the clean mesh's faces asked for (instead of --target-faces)")
    c = sub.add_parser("compare", help="compare two run folders; exit 1 on a regression")
    c.add_argument("run_a")
    c.add_argument("run_b")
    c.add_argument("--html", metavar="FILE", help="also write an HTML diff")
    c.add_argument("--time-factor", type=_number(float), default=None, metavar="X",
                   help="a time regression needs B slower than X times A (default 1.5)")
    c.add_argument("--absolute-time", action="store_true",
                   help="judge raw times (default: relative to the whole run's drift, the median B/A over cases)")
    c.add_argument("--no-time", action="store_true",
                   help="compare metrics only (runs from different or loaded machines)")
    return p


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


class _PipeSafe:
    """A text stream that survives its reader going away (``| head -1``, ``2>&-``): once a write
    fails with a broken pipe (or there is no stream at all), the rest goes to /dev/null, so the
    command still finishes its work and returns its own exit code (a regression found by
    `compare` is exit 1 whether or not anyone read the lines)."""

    def __init__(self, inner):
        self._inner, self.broken = inner, inner is None

    def _call(self, fn, *args):
        """``fn(*args)`` on the inner stream; a reader gone (broken pipe, closed stream) ends it."""
        try:
            return fn(*args)
        except BrokenPipeError:
            self._broke()
        except ValueError:                    # also an encoding error, which is not a reader gone
            if not getattr(self._inner, "closed", False):
                raise
            self._broke()
        return None

    def write(self, s):
        if self.broken:
            return len(s)
        try:
            n = self._call(self._inner.write, s)
        except UnicodeEncodeError:            # a name the terminal's encoding lacks: escaped, not lost
            enc = getattr(self._inner, "encoding", None) or "utf-8"
            return self.write(s.encode(enc, "backslashreplace").decode(enc))
        return len(s) if n is None else n

    def flush(self):
        if not self.broken:
            self._call(self._inner.flush)

    def isatty(self) -> bool:
        try:
            return not self.broken and self._inner.isatty()
        except (OSError, ValueError):
            return False

    def _broke(self):
        self.broken = True
        try:                                 # the interpreter's last flush must not fail either
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, self._inner.fileno())
            os.close(devnull)
        except (OSError, ValueError, AttributeError):
            pass

    def __getattr__(self, name):
        return getattr(self._inner, name)


def threading_main() -> bool:
    import threading
    return threading.current_thread() is threading.main_thread()


def main(argv=None) -> int:
    """The ``shootout`` command: ``main()`` reads ``sys.argv`` and is the command itself (after it
    returns, a SIGINT or SIGTERM ends the process with its exit code, so a late signal cannot turn
    a 130 into an exit by SIGTERM); a caller from Python passes ``argv`` and gets its own signal
    handlers back."""
    import signal

    from . import errors
    from .errors import on_interrupt
    errors._INTERRUPTED = False
    saved = None
    if threading_main():
        # a terminated run stops like an interrupted one; both are remembered (harness.errors)
        saved = signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT)
        signal.signal(signal.SIGTERM, on_interrupt)
        signal.signal(signal.SIGINT, on_interrupt)
    streams = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = _PipeSafe(sys.stdout), _PipeSafe(sys.stderr)
    code = 1
    try:
        code = _main(argv)
        return code
    except SystemExit as exc:            # argparse: --help (0), a usage error (2)
        code = exc.code if isinstance(exc.code, int) else 1
        raise
    finally:
        sys.stdout.flush()               # a pipe is block-buffered: its break shows here, not at exit
        sys.stderr.flush()
        sys.stdout, sys.stderr = streams
        if saved is not None and argv is None:  # the command's code is known: a late signal ends it with that
            def end(*_):                        # code (the default handler made a 130 an exit by SIGTERM)
                os._exit(code)
            signal.signal(signal.SIGTERM, end)
            signal.signal(signal.SIGINT, end)
        elif saved is not None:                 # an embedding process gets its handlers back
            signal.signal(signal.SIGTERM, saved[0])
            signal.signal(signal.SIGINT, saved[1])
        errors._INTERRUPTED = False


def _main(argv) -> int:
    from .errors import interrupt_seen
    args = None
    try:                       # a Ctrl-C while the parser loads the task kinds is an interrupt too
        args = _parser().parse_args(argv)
        args.command_process = argv is None          # the `shootout` command itself, not a call from Python
        handler = {"run": _cmd_run, "methods": _cmd_methods, "datasets": _cmd_datasets,
                   "report": _cmd_report, "views": _cmd_views, "eval": _cmd_eval,
                   "compare": _cmd_compare}[args.command]
        code = handler(args)
        if interrupt_seen():             # an interrupt swallowed where exceptions are ignored
            raise KeyboardInterrupt
        return code
    except ShootoutError as exc:
        print(f"shootout: {exc}", file=sys.stderr)
        return getattr(exc, "exit_code", 2)
    except KeyboardInterrupt:
        started = getattr(args, "run_started", None)
        print("shootout: interrupted; rows finished so far are saved (use --resume)" if started == "cases" else
              "shootout: interrupted; nothing was written" if getattr(args, "command", None) == "run" and not started
              else "shootout: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:              # stdout closed early (`| head`): stop quietly, like other tools
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        except (OSError, ValueError):
            pass
        return 0
    except OSError as exc:               # a file that cannot be written or read (permissions, a folder in its place)
        if not exc.filename:             # not a file's problem: the traceback says more
            raise
        print(f"shootout: {exc.filename}: {exc.strerror or exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    _code = main()
    # Under `python -m`, CPython ends the process by SIGINT (not this exit code) when a
    # KeyboardInterrupt ever left code run by a string exec, even one caught since: dataclasses
    # build their methods that way, so a Ctrl-C during an import did it. A string exec resets that flag.
    exec("pass")  # noqa: S102
    sys.exit(_code)
