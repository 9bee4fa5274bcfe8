"""Cases -> rows. `run_case` runs in a worker (any process, any machine); the driver writes.

A row is a flat dict of the contract's common columns plus the task's columns. The timed
call is the method alone (``repeats`` times; median, min, max); metrics are not timed.
"""
from __future__ import annotations

import json
import math
import resource
import statistics
import time
import traceback
from pathlib import Path

import numpy as np

from .config import Case, Config, load_config
from .errors import ShootoutError

COMMON_COLUMNS = ["case_id", "task", "mesh", "n_vertices", "n_faces", "noise_model", "noise_level", "seed",
                  "method", "library", "params", "status", "error", "time_s", "time_min_s", "time_max_s",
                  "repeats", "peak_rss_mb"]


def peak_rss_mb() -> float:
    """Peak resident set size of this process so far, from the OS (getrusage), in MiB."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _library(name: str):
    import methods
    try:
        return methods.get(name).library
    except KeyError:
        return None


def base_row(case: Case) -> dict:
    """The common columns known before running (status error until proven otherwise)."""
    return {"case_id": case.case_id, "task": case.task, "mesh": case.mesh_key, "n_vertices": None,
            "n_faces": None, "noise_model": case.noise_model,
            "noise_level": None if math.isnan(case.noise_level) else case.noise_level,
            "seed": case.seed, "method": case.method, "library": _library(case.method),
            "params": json.dumps(case.params, sort_keys=True), "status": "error", "error": "",
            "time_s": None, "time_min_s": None, "time_max_s": None, "repeats": case.repeats,
            "peak_rss_mb": None}


def prepare_input(case: Case):
    """(clean Mesh, input vertex positions) for a case: the pair's noisy positions, or seeded noise."""
    from . import datasets
    from .noise import apply_noise
    src = datasets.load(case.mesh)
    clean = src.clean
    if src.noisy_V is not None:
        return clean, src.noisy_V, src.pair_level
    V_in = apply_noise(clean.V, clean.F, case.noise_model, case.noise_level, case.seed,
                       mesh_key=case.mesh_key, fraction=case.fraction)
    return clean, V_in, None


def run_case(case: Case, want_meshes: bool = False) -> tuple[dict, dict]:
    """Run one case and measure it; never raises (failures become an error row).

    Returns ``(row, meshes)``; ``meshes`` maps file names to ``(V, F)`` for the driver to write
    (the input and the result, when ``want_meshes`` and the task produces a mesh).
    """
    row = base_row(case)
    meshes = {}
    try:
        import methods
        methods.load_plugins(list(case.plugins))
        method = methods.get(case.method)
        row["library"] = method.library
        row["params"] = json.dumps({**{k: p.default for k, p in method.params.items()}, **case.params},
                                   sort_keys=True, default=str)
        clean, V_in, pair_level = prepare_input(case)
        if pair_level is not None:
            row["noise_level"] = pair_level
        row["n_vertices"], row["n_faces"] = clean.n_vertices, clean.n_faces
        why = method.unavailable_reason()
        if why:
            row.update(status="unavailable", error=why)
            return row, meshes
        F = clean.F
        _warm_up(method, case.params)
        times, result = [], None
        for _ in range(case.repeats):
            V_arg, F_arg = V_in.copy(), F.copy()   # a method that writes into its input spoils nothing
            t0 = time.perf_counter()
            result = method(V_arg, F_arg, **case.params)
            times.append(time.perf_counter() - t0)
        row.update(time_s=statistics.median(times), time_min_s=min(times), time_max_s=max(times))
        row.update(_measure(case, method, result, clean, V_in))
        if want_meshes and case.task in ("smoothing", "simplification"):
            meshes = _result_meshes(case, clean, V_in, result)
        row["status"] = "ok"
        if clean.repairs:
            row["error"] = "input repaired: " + "; ".join(clean.repairs)
    except ShootoutError as exc:
        row.update(status="error", error=f"{type(exc).__name__}: {exc}")
    except (Exception, SystemExit) as exc:  # a method's own failure is data: one error row
        tb = traceback.extract_tb(exc.__traceback__)
        where = f" at {Path(tb[-1].filename).name}:{tb[-1].lineno}" if tb else ""
        row.update(status="error", error=f"{type(exc).__name__}: {exc}{where}"[:2000])
    finally:
        row["peak_rss_mb"] = round(peak_rss_mb(), 1)
    return row, meshes


def _warm_up(method, params: dict) -> None:
    """One untimed call on a 320-face icosphere in this process, so imports, JIT cache loads
    and library start-up are not timed (each case runs in a fresh process). Failures here are
    ignored: the timed calls on the real mesh report them."""
    from .datasets import icosphere
    V, F = icosphere(2)
    p = dict(params)
    if method.task == "simplification" and p.get("target_faces") is not None:
        p["target_faces"] = min(int(p["target_faces"]), 160)
    try:
        method(V, F, **p)
    except Exception:  # noqa: BLE001 - see docstring
        pass


def _measure(case: Case, method, result, clean, V_in) -> dict:
    from .measure import measure_laplacian, measure_simplification, measure_smoothing
    from .mesh import topology
    diag = clean.diagonal()
    if case.task == "laplacian":
        for name, A in (("W", result.W), ("M", result.M)):     # NaN weights would pass as NaN metrics
            data = None if A is None else getattr(A, "data", None)
            if data is not None and not np.isfinite(data).all():
                k = int((~np.isfinite(data)).sum())
                raise ValueError(f"{case.method} returned {name} with {k} non-finite (NaN or inf) entries")
        return measure_laplacian(result, V_in, clean.F)
    if case.task == "smoothing":
        V_out = np.asarray(result.V, dtype=np.float64)
        if V_out.shape != V_in.shape:
            raise ValueError(f"{case.method} returned V of shape {V_out.shape}, expected {V_in.shape}")
        if not np.isfinite(V_out).all():
            # non-finite output is instability (diverged, kept as data) on a sound mesh, but a
            # library dividing by zero on a degenerate one: that is an error row naming the faces
            from methods.scratch.operators import zero_area_faces
            bad = zero_area_faces(V_in, clean.F)
            if bad.size:
                raise ValueError(f"{case.method} returned non-finite coordinates on an input with "
                                 f"{bad.size} zero-area face(s) (first: {bad[:5].tolist()})")
        closed = topology(clean.V, clean.F)["boundary_edges"] == 0
        return measure_smoothing(V_out, V_in, clean.V, clean.F, closed, diag, case.hausdorff_samples)
    from methods.base import check_arrays, target_face_count
    V_out, F_out = np.asarray(result.V, dtype=np.float64), np.asarray(result.F)
    if F_out.size == 0:
        raise ValueError(f"{case.method} returned an empty mesh ({len(V_out)} vertices, 0 faces)")
    check_arrays(V_out, F_out)         # a malformed output is an error row, not a metric
    p = {**{k: pp.default for k, pp in method.params.items()}, **case.params}
    target = target_face_count(clean.n_faces, p.get("target_ratio"), p.get("target_faces"))
    return measure_simplification(V_out, F_out, V_in, clean.F, target, diag, case.hausdorff_samples)


def _result_meshes(case: Case, clean, V_in, result) -> dict:
    lvl = "pair" if math.isnan(case.noise_level) else f"{case.noise_level:g}"
    F = clean.F if case.task == "smoothing" else np.asarray(result.F)
    return {f"{case.mesh_key}-{case.noise_model}-{lvl}-{case.seed}-input.obj": (V_in, clean.F),
            f"{case.case_id}.obj": (np.asarray(result.V), F)}


def run(config_or_path, out=None, workers=None, executor="local", scheduler=None, resume=False,
        timeout=None, quiet=True, export_benchmark_json=None):
    """Run a config end to end; returns ``{task: DataFrame}`` of the rows in the run folder."""
    from .session import run_session
    cfg: Config = config_or_path if isinstance(config_or_path, Config) else load_config(config_or_path)
    return run_session(cfg, out=out, workers=workers, executor=executor, scheduler=scheduler,
                       resume=resume, timeout=timeout, quiet=quiet,
                       export_benchmark_json=export_benchmark_json)
