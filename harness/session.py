"""One run of a config: prepare the folder, run the cases through an executor, write the rows,
run.json, the 3D views and the report. ``harness.run`` and ``shootout run`` call `run`."""
from __future__ import annotations

import dataclasses
import os
import re
import secrets
import statistics
import sys
import time
from pathlib import Path

from . import tasks
from .config import Config, load_config
from .errors import ConfigError, RunInterrupted, ShootoutError, check_interrupt, problems_error
from .executors import make_executor
from .mesh import write_ply
from .provenance import code_hash, git_commit, git_dirty, machine_info, now_iso, package_versions, usable_cpus
from .results import PLAN_FILE, Frames, RunFolder, check_output_file, out_dir_problems
from .session_checks import (_accepted, _config_problem, _mesh_ok, _results_config, config_hash, folder_problems,
                             relabelled_meshes, run_args_problems, scored_results)
from .session_disk import NO_ROOM, DiskFull, _inside, _no_room, _write_status_in_place
from .session_finish import finish, recompute_views
from .session_progress import _duration, _Lines, _progress
from .session_record import (PROVENANCE, _count_solvers, _fixed_cost, _keep_first_provenance, _load, _merged_solvers,
                             _solver_info, method_sources, task_specs)
from .session_tune import _earlier_tuned_ids, _training_left, _tune

__all__ = ["NO_ROOM", "PROVENANCE", "DiskFull", "_Lines", "_duration", "_no_room", "_results_config",
           "_write_status_in_place", "config_hash", "finish", "folder_problems", "method_sources", "plan",
           "recompute_views", "relabelled_meshes", "run", "run_args_problems", "scored_results", "task_specs"]


def plan(cases) -> list[dict]:
    """The run folder's ``plan.csv``: the identifying columns (`results.PLAN_COLUMNS`) of every case
    the run means to run, as its rows would start (`runner.base_row`), so that a report of an
    interrupted run counts the cases it never ran (`results.with_not_run`)."""
    from .results import PLAN_COLUMNS
    from .runner import base_row
    return [{k: r[k] for k in PLAN_COLUMNS} for r in map(base_row, cases)]


def run(config_or_path, out=None, workers=None, executor="local", scheduler=None, resume=False,
        timeout=None, quiet=True, export_benchmark_json=None):
    """Run a config (a `Config`, a path, YAML text or a dict) end to end; returns
    ``{task: DataFrame}`` of the rows in the run folder (a `Frames`: its ``not_written`` lists
    what the end of the run could not write, e.g. the report). ``out``: a non-empty folder path,
    or None for ``results/<name>``. A ``results:`` config (scoring files made elsewhere) runs no
    case: it takes ``out`` and ``quiet`` only, as ``shootout run`` takes no other flag for it. Bad
    arguments are one `ShootoutError` listing each, before anything is written."""
    P = [re.sub(r"--(workers|timeout|executor|scheduler)\b", r"\1", p)      # arguments here, not flags
         for p in run_args_problems(workers, timeout, executor, scheduler)]
    if out is not None and not isinstance(out, (str, os.PathLike)):
        P.append(f"out: expected a folder path, got {type(out).__name__} {out!r}")
    elif isinstance(out, str) and not out.strip():       # Path("") would be the current folder
        P.append("out: an empty path; give the run folder, or out=None for results/<name>")
    why = _config_problem(config_or_path)
    if why:
        P.append(why)
    if out is not None and isinstance(out, (str, os.PathLike)) and str(out).strip():
        P += out_dir_problems(Path(out), resume)      # before a results: config's problems, which join them
    raw = None if why else _results_config(config_or_path)
    if raw is not None:
        given = [k for k, on in (("resume", resume), ("timeout", timeout is not None), ("executor", executor != "local"),
                                 ("scheduler", bool(scheduler)), ("workers", workers is not None),
                                 ("export_benchmark_json", bool(export_benchmark_json))) if on]
        if given:                        # scoring files runs no case: these would be silently ignored
            P.append(f"{', '.join(given)}: a results: config scores files made elsewhere and runs no case; "
                     "drop these arguments")
        scored = scored_results(raw, config_or_path, P)
    bad_config = None
    if raw is None and not why and not isinstance(config_or_path, Config):
        try:                             # the config's own problems join the arguments', as the CLI's do
            config_or_path = load_config(config_or_path)
        except ConfigError as exc:
            bad_config = exc
    if bad_config is not None:
        if not P:
            raise bad_config
        P += [f"{bad_config.source}: {p}" for p in bad_config.problems]
    if P:
        raise problems_error(list(dict.fromkeys(P)))
    if raw is not None:                  # a results: config scores files made elsewhere (shootout eval)
        from .scoring import eval_entries
        entries, hs = scored
        out_dir = Path(out) if out else Path("results") / str(raw[0].get("name") or "eval")
        return eval_entries(entries, out_dir, hs, raw[0], hausdorff_eps=raw[0].get("hausdorff_eps", 1e-3))
    cfg: Config = config_or_path if isinstance(config_or_path, Config) else load_config(config_or_path)
    out_dir = Path(out) if out else Path("results") / cfg.name
    folder = RunFolder(out_dir)
    cpus = usable_cpus()                 # the cores this run may use
    workers = 1 if executor == "serial" else int(workers) if workers else cpus
    timeout = None if executor == "serial" else timeout if timeout is not None else cfg.timeout
    chash = config_hash(cfg)
    threads = 1 if executor == "dask" else max(1, cpus // workers)
    cases = [dataclasses.replace(c, threads=threads) for c in cfg.cases]
    # refused before the folder or its lock is made (a given out was checked with the config above)
    problems = [] if out else out_dir_problems(out_dir, resume)
    try:
        check_output_file(export_benchmark_json, "export_benchmark_json", run_dirs=(out_dir,), kind="json")
    except ShootoutError as exc:
        problems.append(str(exc))
    if not problems and out_dir.is_dir():
        problems = folder_problems(folder, out_dir, _accepted(cfg, chash), resume, cfg)
    if problems:
        raise problems_error(problems)
    # before anything is written: an unreachable Dask scheduler is exit 2 with the folder untouched
    ex = make_executor(executor, workers, timeout, scheduler)
    try:
        lock = folder.lock()              # one run per folder; held until this function returns
    except BaseException:
        ex.close()
        raise
    from .runner import thread_env
    try:
        # libigl's count, inherited by forked cases should the driver start libigl's threads during
        # the run; the other variables are set in each case only (MKL loaded here would keep them)
        with thread_env(threads, ("IGL_NUM_THREADS",)):
            return _locked_run(cfg, folder, out_dir, cases, workers, timeout, chash, threads, executor, scheduler,
                               resume, quiet, export_benchmark_json, ex)
    except BaseException:
        try:
            ex.close()
        except Exception:  # noqa: BLE001 - already closed
            pass
        raise
    finally:
        lock.close()


def _locked_run(cfg, folder, out_dir, cases, workers, timeout, chash, threads, executor, scheduler, resume, quiet,
                export_benchmark_json, ex):
    done: set[str] = set()
    refused = folder_problems(folder, out_dir, _accepted(cfg, chash), resume, cfg)   # before the lock too; again under it
    if refused:
        raise problems_error(refused)
    try:
        planned = plan(cfg.cases)                # before anything is removed: a case no row can hold fails here
        if resume:
            relabelled = relabelled_meshes(folder, list(cfg.cases) + (list(cfg.tune.cases) if cfg.tune else []))
            if relabelled:
                raise problems_error(relabelled)
            try:
                known = None if cfg.tune is not None else {c.case_id for c in cfg.cases}   # tuned cases come later
                done = folder.keep_ok_rows(known=known)
                if cfg.save_meshes:              # an ok row whose saved mesh is missing or torn runs again
                    meshed = {c.case_id for c in cfg.cases if tasks.get(c.task).output_mesh is not None}
                    done = {cid for cid in done if cid not in meshed or _mesh_ok(out_dir / "meshes" / f"{cid}.ply")}
                    folder.drop_rows(lambda r: r["case_id"] not in done)
            except OSError as exc:
                if exc.errno in NO_ROOM:
                    folder.remove_temporaries()
                    raise DiskFull(_no_room(exc, out_dir, "--resume rewrites the CSVs with their ok rows first and "
                                            "could not finish (each CSV is whole: written to a temporary file and "
                                            "renamed); make room (or raise the limit) and resume again")) from None
                raise
            folder.remove_temporaries()
            cases = [c for c in cases if c.case_id not in done]
        else:
            folder.reset()
    except BaseException:
        ex.close()
        raise
    started = session_started = now_iso()
    session_id = secrets.token_hex(8)         # names this session's record in run.json (times are to the second)
    command = " ".join(sys.argv)
    prev_meta = folder.read_run_json() if resume else None
    prev_sessions: list = []
    if prev_meta and prev_meta.get("started"):
        started = prev_meta["started"]
        command = prev_meta.get("command") or command
        prev_sessions = list(prev_meta.get("sessions") or [])
        last_id, last = prev_meta.get("session_id"), prev_meta.get("session_started")
        if last_id:
            unrecorded = not any(x.get("id") == last_id for x in prev_sessions)
        elif last:                         # run.json before session ids: start times (to the second)
            unrecorded = not any(x.get("started") == last for x in prev_sessions)
        else:
            unrecorded = not prev_sessions or prev_meta.get("status") == "running"
        if unrecorded:
            # the last session never wrote its own record: its driver was killed (we hold the
            # folder's lock, so none runs) or its last write failed (a full disk); when it ran
            # and how long are what run.json kept
            prev_sessions.append({"id": last_id, "started": prev_meta.get("session_started") or prev_meta.get("started"),
                                  "finished": prev_meta.get("finished"), "wall_s": prev_meta.get("wall_s")
                                  if prev_meta.get("status") != "running" else None,
                                  "command": prev_meta.get("session_command") or prev_meta.get("command"),
                                  "status": "killed" if prev_meta.get("status") == "running"
                                  else prev_meta.get("status"), "executor": prev_meta.get("executor"),
                                  "scheduler": prev_meta.get("scheduler"), "workers": prev_meta.get("workers")})
    src = Path(cfg.source) if cfg.source and cfg.source != "<config>" else None
    meta = {"name": cfg.name, "config_source": cfg.source,
            "config_dir": str(src.resolve().parent) if src is not None and src.is_file() else str(Path.cwd()),
            "config": cfg.raw, "config_hash": chash,
            "started": started, "session_started": session_started, "session_id": session_id,
            "session_command": " ".join(sys.argv),
            "finished": None, "status": "running", "executor": executor,
            "scheduler": scheduler, "workers": workers, "timeout_s": timeout,
            "n_cases": len(cfg.cases), "resumed_ok_cases": len(done),
            "versions": package_versions(), "git_commit": git_commit(), "git_dirty": git_dirty(),
            "code_sha256": code_hash(cfg.plugins), "machine": machine_info(),
            "solver": _solver_info(), "command": command, "tasks": task_specs(cfg),
            "method_sources": method_sources(cfg),
            "measurement": {"hausdorff_samples": cfg.cases[0].hausdorff_samples if cfg.cases else None,
                            "hausdorff_eps": cfg.cases[0].hausdorff_eps if cfg.cases else None,
                            "sample_seed": 0},
            "timing": {"threads_per_case": threads, "min_repeats": cfg.repeats,
                       "time_budget_s": cfg.cases[0].time_budget if cfg.cases else None,
                       "protocol": "one untimed cold call on the case's own input (time_cold_s), then samples "
                                   "until both repeats and time_budget_s are reached; median and quartiles; each sample's "
                                   "process CPU time kept too (cpu_times); "
                                   "BLAS/OpenMP pools and libigl's own threads limited to "
                                   "threads_per_case (pools by the local driver before "
                                   "it forks, inherited; else in the case; in the case for libraries loaded since); "
                                   "IGL_NUM_THREADS, MKL_NUM_THREADS, OMP_NUM_THREADS and OPENBLAS_NUM_THREADS "
                                   "set to it in every case, for libraries a method loads during its cold call"}}
    meta["load_average"] = [_load()]
    load0 = meta["load_average"][0]             # this session's start (the run's stays first in run.json)
    own = {k: meta[k] for k in PROVENANCE}        # this session's code and packages, in its own record
    if prev_meta:
        _keep_first_provenance(meta, prev_meta, session_id, quiet)
    meta["sessions"] = prev_sessions          # kept if this session's driver is killed
    if resume:
        meta["resumed_at"] = now_iso()
        if cfg.tune is not None and isinstance((prev_meta or {}).get("tune"), dict):
            meta["tune"] = prev_meta["tune"]      # the earlier choice stands until this session's tuning chooses
            meta["n_cases"] = len(cfg.cases) + len(_earlier_tuned_ids(meta["tune"]))   # its cases too, until then
    if executor == "dask":       # the cluster's worker threads, not --workers
        meta.update(ex.describe())
    try:
        if not (resume and cfg.tune is not None):   # a tuned resume keeps its plan until tuning has chosen
            folder.write_plan(planned)
        folder.write_run_json(meta)
    except BaseException as exc:          # a full disk, or an interrupt between the two files
        ex.close()
        folder.remove_temporaries()
        if not resume:                    # a fresh run whose run.json was not written leaves no plan either
            (out_dir / PLAN_FILE).unlink(missing_ok=True)
        if isinstance(exc, OSError) and exc.errno in NO_ROOM:
            raise DiskFull(_no_room(exc, out_dir, "nothing half-written was kept; make room (or raise the limit), "
                                    "then run again" + (" with --resume" if resume else ""))) from None
        raise
    bar = None
    if not quiet:
        n_todo = len(cases) + _training_left(cfg, out_dir, resume)
        own_ids = {c.case_id for c in cfg.cases}
        if resume:
            print(f"shootout: resuming {out_dir}: {len(done)} finished case(s) kept, {n_todo} to run"
                  + (" (and the tuned cases the choice makes)" if cfg.tune is not None else ""),
                  file=sys.stderr, flush=True)
        budget = cfg.cases[0].time_budget if cfg.cases else 0.25
        floor = n_todo * budget / max(int(meta["workers"] or 1), 1)     # every case samples its budget at least
        print(f"shootout: {meta['n_cases']} case(s), {n_todo} to run on {meta['workers']} worker(s)"
              + (f" (a large run: {n_todo:,} cases, at least {_duration(floor)} of timing alone, "
                 f"time_budget {budget:g} s each; --timeout bounds each one)" if n_todo > 1000 else ""),
              file=sys.stderr, flush=True)
        bar = _progress(len(cfg.cases), len(done & own_ids))
    counts: dict[str, int] = {}
    overhead: list[tuple[float, float, float]] = []
    solver_used: dict[str, dict] = {}
    t0 = time.perf_counter()
    extra_cases: list = []
    try:
        if cfg.tune is not None:
            extra_cases = _tune(cfg, ex, out_dir, meta, threads, resume, quiet,
                                previous=(prev_meta or {}).get("tune") if resume else None)
            if resume:                   # rows of tuned settings this choice no longer makes are not this run's
                ours = {c.case_id for c in list(cfg.cases) + extra_cases}
                folder.drop_rows(lambda r: r["case_id"] not in ours)
                done &= ours
            todo = [c for c in extra_cases if c.case_id not in done]
            cases = cases + todo
            meta["n_cases"] = len(cfg.cases) + len(extra_cases)
            folder.write_run_json(meta)
            folder.write_plan(plan(list(cfg.cases) + list(extra_cases)))
            if bar is not None:
                bar.total = meta["n_cases"]
                kept_tuned = len(extra_cases) - len(todo)
                if kept_tuned:            # tuned test cases a resume kept: done, as the config's own kept ones
                    bar.update(kept_tuned)
        for case, row, extras in ex.run(cases, want_meshes=cfg.save_meshes):
            for fname, (V, F, q, what) in (extras.get("meshes") or {}).items():   # meshes first, then the row
                if not (out_dir / "meshes" / fname).exists() or fname.startswith(case.case_id):
                    folder.save_mesh(fname, lambda fh, V=V, F=F, q=q, w=what: write_ply(fh, V, F, q, w))
            folder.append(case.task, row)
            counts[row["status"]] = counts.get(row["status"], 0) + 1
            fixed = _fixed_cost(row, extras)
            if fixed is not None:
                overhead.append(fixed)
            _count_solvers(solver_used, case, extras.get("solver"))
            if bar is not None:
                bar.set_postfix_str(f"{case.method} on {case.mesh_key}", refresh=False)
                bar.update(1)
            check_interrupt()
        check_interrupt()
        meta["status"] = "finished"
    except KeyboardInterrupt:
        meta["status"] = "interrupted"
        raise
    except OSError as exc:
        meta["status"] = "interrupted"
        folder.remove_temporaries()
        if exc.errno in NO_ROOM:
            raise DiskFull(_no_room(exc, out_dir)) from None
        if exc.filename is None or not _inside(str(exc.filename), out_dir):   # not a run file (a socket, a fork)
            raise
        raise RunInterrupted(f"{exc.filename}: {exc.strerror or exc}: the run could not write its "
                             "files (was the run folder changed while it ran?); the rows written so far are kept: "
                             "mend it and run again with --resume") from None
    except BaseException:
        meta["status"] = "interrupted"        # never 'finished' when something escaped the executor
        raise
    finally:
        if bar is not None:
            bar.close()
        ex.close()
        meta["load_average"] = meta["load_average"][:1] + [_load()]
        wall = round(time.perf_counter() - t0, 3)
        session = {"id": session_id, "started": session_started, "finished": now_iso(), "wall_s": wall,
                   "command": " ".join(sys.argv), "status": meta["status"], "resumed_ok_cases": len(done),
                   "executor": meta.get("executor"), "scheduler": meta.get("scheduler"), "workers": meta.get("workers"),
                   "threads_per_case": threads, "timeout_s": timeout, "status_counts": counts,
                   "load_average": [load0, meta["load_average"][-1]], **own}
        session["solver_used"] = {k: solver_used[k] for k in sorted(solver_used)}
        if isinstance(meta.get("solver"), dict):
            meta["solver"]["used"] = _merged_solvers(solver_used, prev_sessions)
        if overhead:
            fixed = [f for f, _, _ in overhead]
            spent = sum(m for _, m, _ in overhead)
            shares = [f / m for f, m, _ in overhead if m > 0]
            meta["fixed_cost_per_case_s"] = {
                "mean": round(sum(fixed) / len(fixed), 4), "max": round(max(fixed), 4), "cases": len(fixed),
                "measuring_mean": round(sum(g for _, _, g in overhead) / len(overhead), 4),
                "share_of_method_time": round(sum(fixed) / spent, 4) if spent > 0 else None,
                "median_case_share": round(statistics.median(shares), 4) if shares else None,
                "definition": "wall time of the case call in its process minus its timed samples and cold call "
                              "(imports, mesh loading, noise, measuring; not the fork itself); ok cases of this session; "
                              "share_of_method_time: the cases' summed fixed cost over their summed method time "
                              "(samples + cold call); median_case_share: the median of that ratio per case; "
                              "measuring_mean: the part of the mean spent measuring the results (the task's metrics)"}
            session["fixed_cost_per_case_s"] = meta["fixed_cost_per_case_s"]
        elif prev_meta and isinstance(prev_meta.get("fixed_cost_per_case_s"), dict):
            meta["fixed_cost_per_case_s"] = prev_meta["fixed_cost_per_case_s"]   # the last session that ran cases
        try:
            on_disk = folder.status_counts()
        except (OSError, ShootoutError):       # a CSV that cannot be read now: this session's counts
            on_disk = counts
        meta.update(finished=session["finished"], status_counts=on_disk,
                    status_counts_this_session=counts, sessions=prev_sessions + [session],
                    wall_s=round(wall + sum(x.get("wall_s") or 0 for x in prev_sessions), 3))
        try:
            folder.write_run_json(meta)
        except OSError:                       # disk full: the status below is the best we can record
            folder.remove_temporaries()
            _write_status_in_place(folder, meta["status"])
    try:
        not_written = finish(out_dir, cfg, timeout=timeout, export_benchmark_json=export_benchmark_json,
                             extra_cases=extra_cases, threads=threads)
    except KeyboardInterrupt:               # the rows are whole; the views, report or export are not
        meta["status"] = meta["sessions"][-1]["status"] = "interrupted"
        try:
            folder.write_run_json(meta)
        except OSError:
            pass
        raise
    return Frames(folder.frames(), not_written)
