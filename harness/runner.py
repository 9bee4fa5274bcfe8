"""One case -> one row. `run_case` runs in a worker (any process, any machine); it knows nothing
of sessions, executors or run folders.

A row is a flat dict of the common columns (`harness.schema`) plus the task's columns. The timed
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

from . import tasks
from .config import Case
from .errors import ShootoutError
from .tasks.base import CaseInput


def peak_rss_mb() -> float:
    """Peak resident set size of this process so far, from the OS (getrusage), in MiB."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _library(name: str):
    from .plugins import import_methods
    methods = import_methods()
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


def prepare_input(case: Case) -> tuple[CaseInput, float | None]:
    """The case's input (clean mesh, input positions) and the noise level of a given pair."""
    from . import datasets
    from .noise import apply_noise
    src = datasets.load(case.mesh)
    clean = src.clean
    settings = {"hausdorff_samples": case.hausdorff_samples}
    if src.noisy_V is not None:
        return CaseInput(clean, src.noisy_V, clean.F, clean.diagonal(), settings), src.pair_level
    V_in = apply_noise(clean.V, clean.F, case.noise_model, case.noise_level, case.seed,
                       mesh_key=case.mesh_key, fraction=case.fraction)
    return CaseInput(clean, V_in, clean.F, clean.diagonal(), settings), None


def input_mesh_name(case: Case) -> str:
    lvl = "pair" if math.isnan(case.noise_level) else f"{case.noise_level:g}"
    return f"{case.mesh_key}-{case.noise_model}-{lvl}-{case.seed}-input.obj"


def run_case(case: Case, want_meshes: bool = False, want_view: bool = False) -> tuple[dict, dict]:
    """Run one case and measure it; never raises (failures become an error row).

    Returns ``(row, extras)``. ``extras["meshes"]`` maps file names to ``(V, F)`` for the driver to
    write (the input and the result, when ``want_meshes`` and the task has an output mesh);
    ``extras["view"]`` holds the task's view meshes (``want_view``).
    """
    row = base_row(case)
    extras: dict = {}
    try:
        from .plugins import import_methods
        methods = import_methods()
        methods.load_plugins(list(case.plugins))
        method = methods.get(case.method)
        task = tasks.get(case.task)
        row["library"] = method.library
        full = method.resolve_params(case.params)
        row["params"] = json.dumps(full, sort_keys=True, default=str)
        inp, pair_level = prepare_input(case)
        if pair_level is not None:
            row["noise_level"] = pair_level
        row["n_vertices"], row["n_faces"] = inp.clean.n_vertices, inp.clean.n_faces
        why = method.unavailable_reason()
        if why:
            row.update(status="unavailable", error=why)
            return row, extras
        _warm_up(method, case.params)
        times, result = [], None
        for _ in range(case.repeats):
            V_arg, F_arg = inp.V.copy(), inp.F.copy()   # a method that writes into its input spoils nothing
            t0 = time.perf_counter()
            result = method(V_arg, F_arg, **case.params)
            times.append(time.perf_counter() - t0)
        row.update(time_s=statistics.median(times), time_min_s=min(times), time_max_s=max(times))
        row.update(task.measure(inp, result, full))
        if want_meshes and task.output_mesh is not None:
            V_out, F_out = task.output_mesh(inp, result)
            extras["meshes"] = {input_mesh_name(case): (inp.V, inp.F), f"{case.case_id}.obj": (V_out, F_out)}
        if want_view and task.view is not None:
            extras["view"] = task.view(inp, result)
        row["status"] = "ok"
        if inp.clean.repairs:
            row["error"] = "input repaired: " + "; ".join(inp.clean.repairs)
    except ShootoutError as exc:
        row.update(status="error", error=f"{type(exc).__name__}: {exc}")
    except (Exception, SystemExit) as exc:  # a method's own failure is data: one error row
        tb = traceback.extract_tb(exc.__traceback__)
        where = f" at {Path(tb[-1].filename).name}:{tb[-1].lineno}" if tb else ""
        row.update(status="error", error=f"{type(exc).__name__}: {exc}{where}"[:2000])
    finally:
        row["peak_rss_mb"] = round(peak_rss_mb(), 1)
    return row, extras


def _warm_up(method, params: dict) -> None:
    """One untimed call on a 320-face icosphere in this process, so imports, JIT cache loads
    and library start-up are not timed (each case runs in a fresh process). Failures here are
    ignored: the timed calls on the real mesh report them."""
    from .datasets import icosphere
    V, F = icosphere(2)
    p = dict(params)
    if p.get("target_faces") is not None:
        p["target_faces"] = min(int(p["target_faces"]), 160)
    try:
        method(V, F, **p)
    except Exception:  # noqa: BLE001 - see docstring
        pass
