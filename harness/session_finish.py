"""What a run writes after its last row, from the rows on disk: the 3D views, the leaderboard,
report.html and the optional benchmark export (a failure is a warning and an entry of what was
not written, never a lost run); and `recompute_views`, which rebuilds a run's cases from its
run.json and computes the 3D views again."""
from __future__ import annotations

import sys
from pathlib import Path

from .config import Config, load_config
from .errors import ShootoutError
from .results import RunFolder, with_not_run
from .session_record import task_specs
from .session_tune import _recorded_tuned_cases


def finish(out_dir, cfg: Config, timeout=None, export_benchmark_json=None, extra_cases=(), threads=None) -> list[str]:
    """After the last row: the 3D views (views/, with the run's ``threads`` per case), the report
    and the optional benchmark export.
    The rows are safe on disk; a failure here is a warning and an entry of the returned list of
    what was not written, never a lost run."""
    from .report import build_report
    from .views import compute_views
    problems: list[str] = []
    folder = RunFolder(out_dir)

    def warn(what: str, exc: Exception, extra: str = "") -> None:
        problems.append(what)
        print(f"shootout: warning: {what} ({type(exc).__name__}: {exc}){extra}", file=sys.stderr)
    try:
        views = compute_views({c.case_id: c for c in list(cfg.cases) + list(extra_cases)}, folder.frames(), cfg.report,
                              timeout=timeout, threads=threads)
        folder.write_views(views)
    except Exception as exc:  # noqa: BLE001
        warn("3D views could not be computed", exc)
    try:
        from .leaderboard import write as write_leaderboard
        write_leaderboard(out_dir, with_not_run(folder.frames(), folder.read_plan()),
                          {t: s for t, s in task_specs(cfg).items()})
    except Exception as exc:  # noqa: BLE001
        warn("the leaderboard could not be written", exc)
    try:
        build_report(out_dir)
    except Exception as exc:  # noqa: BLE001
        warn("report.html could not be built", exc,
             f"; rows are in {out_dir}; retry with `shootout report {out_dir}`")
    if export_benchmark_json:
        from .benchmark_json import export_benchmark_json as _export
        _export(out_dir, export_benchmark_json)
    return problems


def recompute_views(run_dir) -> list[dict]:
    """Rebuild the cases from run.json's config and compute the 3D views again (this runs the
    chosen methods, including any plugin named in run.json). Returns the views written (a
    failed one carries its ``error`` text)."""
    from .views import compute_views
    folder = RunFolder(run_dir)
    meta = folder.read_run_json()
    if meta is None and folder.run_json_state() == "corrupt":
        raise ShootoutError(f"{folder.run_json}: damaged or not written by mesh-shootout (unreadable JSON, or keys "
                            "such as 'versions' missing): the cases cannot be rebuilt from it")
    if not meta or not isinstance(meta.get("config"), dict):
        raise ShootoutError(f"{run_dir}: no run.json with a config to rebuild the cases from")
    src, where = meta.get("config_source"), meta.get("config_dir")
    if where and Path(where).is_dir():               # relative mesh files resolve where the run did
        base = Path(where)
    else:
        base = Path(src).parent if src and Path(src).parent.is_dir() else Path.cwd()
    raw = dict(meta["config"])
    report = raw.pop("report", None)     # a listed id no longer a case (its file changed): its view says so
    cfg = load_config({**raw, "report": {k: v for k, v in report.items() if k != "views"}} if isinstance(report, dict)
                      else raw, base_dir=base.resolve(), label=f"{folder.run_json} (its config)")
    threads = (meta.get("timing") or {}).get("threads_per_case") if isinstance(meta.get("timing"), dict) else None
    threads = threads if isinstance(threads, int) and not isinstance(threads, bool) and 0 < threads <= 4096 else None
    cases = list(cfg.cases) + _recorded_tuned_cases(cfg, meta)
    views = compute_views({c.case_id: c for c in cases}, folder.frames(),
                          report if isinstance(report, dict) else cfg.report, threads=threads)
    stored = {v.get("case_id"): v for v in folder.read_views() if isinstance(v, dict) and not v.get("error")}
    views = [{**stored[v["case_id"]], "why": v.get("why"), "kept": v["error"]}     # the run's own view stays
             if v.get("not_rebuilt") and v.get("case_id") in stored else v for v in views]
    folder.write_views(views)
    return views
