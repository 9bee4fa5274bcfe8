"""Score results made elsewhere exactly as a run scores its own: `evaluate` for arrays,
`eval_files` (``shootout eval``) for mesh files, writing a normal run folder.

The measurement is the task's own (`harness.tasks`): the same metrics, the same definitions, the
same code path as `harness.runner.run_case` after the method call. A smoothing result must have
the clean mesh's vertices in the same order (the same count as the clean file, or as the clean
mesh after the documented repairs); a simplification result is compared as a surface.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from . import tasks
from .errors import ShootoutError
from .mesh import Mesh, read_mesh, validate
from .provenance import git_commit, machine_info, now_iso, package_versions
from .results import RunFolder
from .tasks.base import CaseInput


def _result(task_name: str, V, F):
    task = tasks.get(task_name)
    if task_name == "smoothing":
        return task.result_type(V=np.asarray(V, dtype=np.float64))
    if task_name == "simplification":
        return task.result_type(V=np.asarray(V, dtype=np.float64), F=np.asarray(F, dtype=np.int64))
    raise ShootoutError(f"eval scores smoothing and simplification results, not {task_name!r}")


def evaluate(V, F, V_clean, F_clean, task: str = "smoothing", V_noisy=None, hausdorff_samples: int = 20000,
             target_faces: int | None = None) -> dict:
    """The task's metrics of a result ``(V, F)`` against the clean mesh ``(V_clean, F_clean)``.

    ``task``: ``smoothing`` (``V`` has the clean mesh's vertices in order; ``F`` is ignored) or
    ``simplification`` (``(V, F)`` is compared to the input surface: ``V_noisy`` with the clean
    faces when given, else the clean mesh). ``V_noisy``: the input the result was made from
    (smoothing: gives the ``input_*`` columns; blank without it). Lengths are fractions of the clean
    mesh's bounding-box diagonal, as in a run.
    """
    clean = validate(V_clean, F_clean, name="clean", repair=False)
    V_in = clean.V if V_noisy is None else np.asarray(V_noisy, dtype=np.float64)
    if V_in.shape != clean.V.shape:
        raise ShootoutError(f"the noisy input has {len(V_in)} vertices, the clean mesh {len(clean.V)}")
    inp = CaseInput(clean, V_in, clean.F, clean.diagonal(), {"hausdorff_samples": hausdorff_samples})
    res = _result(task, V, F)
    t = tasks.get(task)
    res = t.validate_result("result", res, inp.V, inp.F)
    params = {}
    if task == "simplification":
        params = {"target_ratio": None, "target_faces": int(target_faces or len(res.F))}
    row = t.measure(inp, res, params)
    if V_noisy is None:
        for k in [k for k in row if k.startswith("input_")]:
            row[k] = None
    return row


def _label(path: Path, labels, i) -> str:
    return labels[i] if labels and i < len(labels) else path.stem


def eval_files(clean, results, out, noisy=None, task: str | None = None, labels=None,
               hausdorff_samples: int = 20000) -> dict:
    """Score result files against ``clean`` (and ``noisy``); write a run folder at ``out``."""
    from . import datasets
    from .report import build_report
    clean, results = Path(clean), [Path(r) for r in results]
    if labels and len(labels) != len(results):
        raise ShootoutError(f"--label: {len(labels)} label(s) for {len(results)} result file(s)")
    for p in [clean] + results + ([Path(noisy)] if noisy else []):
        if not p.is_file():
            raise ShootoutError(f"{p}: no such file")
    if noisy:
        src = datasets.load({"file": str(Path(noisy).resolve()), "clean": str(clean.resolve())})
        cmesh, V_in = src.clean, src.noisy_V
    else:
        cmesh, V_in = read_mesh(clean), None
    n_raw = len(read_mesh(clean, repair=False).V)          # the clean file's own vertex count
    rows_by_task: dict[str, list] = {}
    for i, rp in enumerate(results):
        r = read_mesh(rp, repair=False)
        t = task or ("smoothing" if len(r.V) in (cmesh.n_vertices, n_raw) else "simplification")
        V = r.V
        if t == "smoothing":
            V = _in_clean_order(r, cmesh, n_raw, rp)
        row = {"case_id": f"eval{i:04d}", "task": t, "mesh": cmesh.name, "n_vertices": cmesh.n_vertices,
               "n_faces": cmesh.n_faces, "noise_model": "given" if noisy else "none", "noise_level": None,
               "seed": None, "method": _label(rp, labels, i), "library": "external",
               "params": json.dumps({"file": str(rp)}), "status": "ok",
               "error": ("input repaired: " + "; ".join(cmesh.repairs)) if cmesh.repairs else ""}
        row.update(evaluate(V, r.F, cmesh.V, cmesh.F, task=t, V_noisy=V_in, hausdorff_samples=hausdorff_samples))
        rows_by_task.setdefault(t, []).append(row)
    folder = RunFolder(out)
    folder.path.mkdir(parents=True, exist_ok=True)
    for t, rows in rows_by_task.items():
        folder.csv_path(t).unlink(missing_ok=True)
        for row in rows:
            folder.append(t, row)
    folder.write_run_json({
        "name": Path(out).name, "kind": "eval", "config": {"eval": {"clean": str(clean), "noisy": noisy and str(noisy),
                                                                    "results": [str(r) for r in results]}},
        "started": now_iso(), "finished": now_iso(), "status": "finished", "executor": "eval", "workers": 1,
        "n_cases": len(results), "versions": package_versions(), "git_commit": git_commit(),
        "machine": machine_info(), "command": " ".join(sys.argv),
        "tasks": {t: tasks.get(t).spec() for t in rows_by_task}})
    build_report(out)
    return folder.frames()


def _in_clean_order(r: Mesh, cmesh: Mesh, n_raw: int, path: Path) -> np.ndarray:
    """A smoothing result's positions in the clean mesh's (repaired) vertex order: the result has
    either the repaired count or the clean file's own count (then the repair's vertex map applies)."""
    if len(r.V) == cmesh.n_vertices:
        return r.V
    if len(r.V) == n_raw and cmesh.vertex_map is not None:
        return r.V[cmesh.vertex_map]
    raise ShootoutError(f"{path.name}: {len(r.V)} vertices, but the clean mesh has {cmesh.n_vertices}: a smoothing "
                        "result must keep the clean mesh's vertices in order (use --task simplification to "
                        "compare surfaces instead)")
