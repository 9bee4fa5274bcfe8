"""One run of a config: prepare the folder, run the cases, write rows, run.json and the report."""
from __future__ import annotations

import hashlib
import json
import os
import sys
import time
from pathlib import Path

from .config import Config
from .errors import ShootoutError
from .executors import make_executor
from .mesh import write_obj
from .results import RunFolder, git_commit, machine_info, now_iso, package_versions


def config_hash(cfg: Config) -> str:
    """sha1 of what the rows depend on (case ids, repeats, Hausdorff samples), so a resume
    with a changed config is detected."""
    hs = cfg.cases[0].hausdorff_samples if cfg.cases else None
    blob = json.dumps([sorted(c.case_id for c in cfg.cases), cfg.repeats, hs]).encode()
    return hashlib.sha1(blob).hexdigest()[:16]


def _solver_info() -> dict | None:
    try:
        from methods.scratch.solvers import solver_info
    except ImportError:
        return None
    try:
        return solver_info()
    except Exception as exc:  # provenance must never fail a run
        return {"error": f"{type(exc).__name__}: {exc}"}


def run_session(cfg: Config, out=None, workers=None, executor="local", scheduler=None, resume=False,
                timeout=None, quiet=True, export_benchmark_json=None):
    out_dir = Path(out) if out else Path("results") / cfg.name
    folder = RunFolder(out_dir)
    workers = int(workers) if workers else (os.cpu_count() or 1)
    timeout = timeout if timeout is not None else cfg.timeout
    chash = config_hash(cfg)
    cases = list(cfg.cases)
    done: set[str] = set()
    if resume:
        prev = folder.read_run_json()
        if prev and prev.get("config_hash") not in (None, chash):
            raise ShootoutError(
                f"--resume: the config changed since the run in {out_dir} started "
                "(cases, repeats or hausdorff_samples differ); run without --resume to start over, "
                "or use a new --out folder")
    # before anything is written: an unreachable Dask scheduler is exit 2 with the folder untouched
    ex = make_executor(executor, workers, timeout, scheduler)
    try:
        if resume:
            done = folder.keep_ok_rows()
            cases = [c for c in cases if c.case_id not in done]
        else:
            folder.reset()
    except BaseException:
        ex.close()
        raise
    started = now_iso()
    prev_meta = folder.read_run_json() if resume else None
    if prev_meta and prev_meta.get("started"):
        started = prev_meta["started"]
    meta = {"name": cfg.name, "config_source": cfg.source, "config": cfg.raw, "config_hash": chash,
            "started": started, "finished": None, "status": "running", "executor": executor,
            "scheduler": scheduler, "workers": workers, "timeout_s": timeout,
            "n_cases": len(cfg.cases), "resumed_ok_cases": len(done),
            "versions": package_versions(), "git_commit": git_commit(), "machine": machine_info(),
            "solver": _solver_info(), "command": " ".join(sys.argv)}
    if resume:
        meta["resumed_at"] = now_iso()
    if hasattr(ex, "n_workers"):       # dask: the cluster's worker threads, not --workers
        meta["workers"] = ex.n_workers()
    folder.write_run_json(meta)
    bar = None
    if not quiet:
        from tqdm import tqdm
        bar = tqdm(total=len(cfg.cases), initial=len(done), unit="case", dynamic_ncols=True,
                   disable=not sys.stderr.isatty())
    counts: dict[str, int] = {}
    t0 = time.perf_counter()
    try:
        for case, row, meshes in ex.run(cases, want_meshes=cfg.save_meshes):
            folder.append(case.task, row)
            for fname, (V, F) in meshes.items():
                mdir = out_dir / "meshes"
                mdir.mkdir(parents=True, exist_ok=True)
                if not (mdir / fname).exists() or fname.startswith(case.case_id):
                    write_obj(mdir / fname, V, F)
            counts[row["status"]] = counts.get(row["status"], 0) + 1
            if bar is not None:
                bar.set_postfix_str(f"{case.method} on {case.mesh_key}", refresh=False)
                bar.update(1)
        meta["status"] = "finished"
    except KeyboardInterrupt:
        meta["status"] = "interrupted"
        raise
    finally:
        if bar is not None:
            bar.close()
        ex.close()
        meta.update(finished=now_iso(), wall_s=round(time.perf_counter() - t0, 3),
                    status_counts=folder.status_counts(), status_counts_this_session=counts)
        folder.write_run_json(meta)
    from .report import build_report
    try:
        build_report(out_dir)
    except Exception as exc:  # the rows are safe on disk; a report bug must not lose the run
        print(f"shootout: warning: report.html could not be built ({type(exc).__name__}: {exc}); "
              f"rows are in {out_dir}; retry with `shootout report {out_dir}`", file=sys.stderr)
    if export_benchmark_json:
        from .benchmark_json import export_benchmark_json as _export
        _export(out_dir, export_benchmark_json)
    return folder.frames()
