"""Score results made elsewhere exactly as a run scores its own: `evaluate` for arrays,
`eval_files` (``shootout eval``) for mesh files, writing a normal run folder.

The measurement is the task's own (`harness.tasks`): the same metrics, the same definitions, the
same code path as `harness.runner.run_case` after the method call. A smoothing result must have
the clean mesh's vertices in the same order (the same count as the clean file, or as the clean
mesh after the documented repairs); a simplification result is compared as a surface.
"""
from __future__ import annotations

import functools
import hashlib
import json
import sys
from pathlib import Path

import numpy as np

from . import tasks
from .config import name_problem, samples_problem
from .errors import ShootoutError, problems_error
from .mesh import Mesh, missing_file_problem, read_mesh, validate
from .provenance import code_hash, git_commit, git_dirty, machine_info, now_iso, package_versions
from .results import Frames, RunFolder, out_dir_problems
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

    ``task``: ``smoothing`` (``V`` has the clean mesh's vertices in order; ``F`` is None or the
    clean mesh's faces, in any order and from any starting corner) or ``simplification``
    (``(V, F)`` is compared to the input surface: ``V_noisy`` with the clean faces when given, else
    the clean mesh). ``V_noisy``: the input the result was made from (smoothing: gives the
    ``input_*`` columns; blank without it), finite. ``F``: integer indices. Lengths are fractions
    of the clean mesh's bounding-box diagonal, as in a run. `ShootoutError` on input that breaks
    these preconditions.
    """
    P = []
    if task not in ("smoothing", "simplification"):
        P.append(f"task: eval scores smoothing and simplification results, not {task!r}")
    if samples_problem(hausdorff_samples):
        P.append(f"hausdorff_samples: {samples_problem(hausdorff_samples)}")
    if target_faces is not None and (isinstance(target_faces, bool) or not isinstance(target_faces, (int, np.integer))
                                     or target_faces < 1):
        P.append(f"target_faces: expected an integer >= 1 (the face count the simplification was asked for), "
                 f"got {target_faces!r}")
    if P:
        raise ShootoutError("; ".join(P))
    clean = validate(V_clean, F_clean, name="clean", repair=False)
    V_in = clean.V if V_noisy is None else np.asarray(V_noisy, dtype=np.float64)
    if V_in.shape != clean.V.shape:
        raise ShootoutError(f"the noisy input has {len(V_in)} vertices, the clean mesh {len(clean.V)}")
    if not np.isfinite(V_in).all():
        raise ShootoutError(f"the noisy input has {int((~np.isfinite(V_in).all(axis=1)).sum())} vertices with NaN "
                            "or inf coordinates")
    if F is not None:
        Fa = np.asarray(F)
        if Fa.dtype.kind not in "iu" and not (Fa.dtype.kind == "f" and np.array_equal(Fa, np.round(Fa))):
            raise ShootoutError(f"F: expected integer vertex indices, got dtype {Fa.dtype}")
    if task == "smoothing" and F is not None and not _same_faces(np.asarray(F, np.int64), clean.F):
        raise ShootoutError("F: a smoothing result keeps the clean mesh's faces (pass F_clean or None); these differ "
                            "(task='simplification' compares surfaces instead)")
    inp = CaseInput(clean, V_in, clean.F, clean.diagonal(), {"hausdorff_samples": hausdorff_samples})
    res = _result(task, V, F)
    t = tasks.get(task)
    res = t.validate_result("result", res, inp.V, inp.F)
    params = {}
    if task == "simplification":
        params = {"target_ratio": None, "target_faces": int(len(res.F) if target_faces is None else target_faces)}
    row = t.measured(inp, res, params)
    if V_noisy is None:
        for k in [k for k in row if k.startswith("input_")]:
            row[k] = None
    return row


def _sha1_file(p) -> str | None:
    try:
        st = Path(p).stat()
    except OSError:
        return None
    return _sha1_path(str(Path(p).resolve()), st.st_size, st.st_mtime_ns)


@functools.lru_cache(maxsize=64)
def _sha1_path(p: str, size: int, mtime_ns: int) -> str | None:
    try:
        return hashlib.sha1(Path(p).read_bytes()).hexdigest()
    except OSError:
        return None


def _eval_id(e: dict, seen: set) -> str:
    """A scored file's case id: a hash of its label, the clean (and noisy) mesh's bytes and the task
    asked for, so that two evals' rows of one label match in `shootout compare` whatever order the
    files were given in (the files themselves may differ: that is what compare measures); a
    repeat of a label within one eval gets the next free id."""
    key = [e.get("label") or Path(e["file"]).stem, _sha1_file(e["clean"]), _sha1_file(e["noisy"]) if e.get("noisy") else None, e.get("task")]
    i = 0
    while True:
        cid = hashlib.sha1(json.dumps(key + ([i] if i else [])).encode()).hexdigest()[:12]
        if cid not in seen:
            seen.add(cid)
            return cid
        i += 1


def _label(path: Path, labels, i) -> str:
    return labels[i] if labels and i < len(labels) else path.stem


def eval_files(clean, results, out, noisy=None, task: str | None = None, labels=None,
               hausdorff_samples: int = 20000) -> dict:
    """Score result files against ``clean`` (and ``noisy``); write a run folder at ``out``."""
    results = [Path(r) for r in results]
    if labels and len(labels) != len(results):
        raise ShootoutError(f"--label: {len(labels)} label(s) for {len(results)} result file(s)")
    entries = [{"file": r, "clean": Path(clean), "noisy": Path(noisy) if noisy else None, "task": task,
                "label": _label(r, labels, i)} for i, r in enumerate(results)]
    return eval_entries(entries, out, hausdorff_samples,
                        {"eval": {"clean": str(clean), "noisy": noisy and str(noisy), "results": [str(r) for r in results]}})


def eval_entries(entries: list[dict], out, hausdorff_samples: int = 20000, config: dict | None = None) -> dict:
    """Score each ``{file, clean, noisy, task, label}`` entry (paths; ``noisy``, ``task`` optional)
    and write one run folder at ``out`` with its report."""
    from . import datasets
    from .report import build_report
    out = Path(out)
    folder = RunFolder(out)
    P = out_dir_problems(out)                    # nothing of the user's is replaced or deleted
    if samples_problem(hausdorff_samples):
        P.append(f"--hausdorff-samples: {samples_problem(hausdorff_samples)}")
    for e in entries:
        for p in [e["file"], e["clean"]] + ([e["noisy"]] if e.get("noisy") else []):
            why = missing_file_problem(p)
            if why:
                P.append(f"{p}: {why}")
    if P:                                        # every problem at once, nothing written
        raise problems_error(list(dict.fromkeys(P)))
    rows: list[tuple[dict, bool]] = []          # each file's row, and whether its task was given
    cleans: dict = {}
    seen_ids: set = set()
    for i, e in enumerate(entries):
        clean, noisy, rp = Path(e["clean"]), e.get("noisy"), Path(e["file"])
        key = (str(clean), str(noisy))
        if key not in cleans:
            raw = read_mesh(clean, repair=False)
            if noisy:
                src = datasets.cached({"file": str(Path(noisy).resolve()), "clean": str(clean.resolve())})
                cleans[key] = (src.clean, src.noisy_V, len(raw.V), raw.F)
            else:
                cleans[key] = (read_mesh(clean), None, len(raw.V), raw.F)
        cmesh, V_in, n_raw, F_raw = cleans[key]
        m_raw = len(F_raw)
        row = {"case_id": _eval_id(e, seen_ids), "task": e.get("task") or "smoothing", "mesh": cmesh.name,
               "n_vertices": cmesh.n_vertices, "n_faces": cmesh.n_faces, "noise_model": "given" if noisy else "none",
               "noise_level": None, "seed": None, "method": e.get("label") or rp.stem, "library": "external",
               "params": json.dumps({"file": str(rp)}), "status": "ok",
               "error": ("input repaired: " + "; ".join(cmesh.repairs)) if cmesh.repairs else ""}
        try:                                     # a bad result file costs its row, as a crashing method does
            r = read_mesh(rp, repair=False, finite=False)     # NaN: scored as the task scores it (diverged)
            same_faces = len(r.F) in (cmesh.n_faces, m_raw)
            t = row["task"] = e.get("task") or ("smoothing" if len(r.V) in (cmesh.n_vertices, n_raw) and same_faces
                                                else "simplification")
            if t == "smoothing" and not same_faces:
                raise ShootoutError(f"{rp.name}: {len(r.F)} faces, but the clean mesh has {cmesh.n_faces}: a "
                                    "smoothing result keeps the clean mesh's faces (use --task simplification to "
                                    "compare surfaces)")
            V = _in_clean_order(r, cmesh, n_raw, F_raw, rp) if t == "smoothing" else r.V
            row.update(evaluate(V, r.F, cmesh.V, cmesh.F, task=t, V_noisy=V_in, hausdorff_samples=hausdorff_samples))
        except Exception as exc:  # noqa: BLE001 - any failure scoring one file is that file's error row
            row.update(status="error", error=(f"{type(exc).__name__}: {exc}" if not isinstance(exc, ShootoutError)
                                              else str(exc))[:2000])
        rows.append((row, bool(e.get("task"))))
    scored = {r["task"] for r, _ in rows if r["status"] == "ok"}
    if len(scored) == 1:              # a file that could not be read goes beside the others it was scored with
        for r, asked in rows:
            if r["status"] != "ok" and not asked:
                r["task"] = next(iter(scored))
    rows_by_task: dict[str, list] = {}
    for r, _ in rows:
        rows_by_task.setdefault(r["task"], []).append(r)
    lock = folder.lock()                         # one writer per folder, as for a run
    try:
        if folder.foreign_files():
            raise folder.foreign_error()
        folder.reset()                           # a previous run or eval here: replaced as a whole
        for t, task_rows in rows_by_task.items():
            for row in task_rows:
                folder.append(t, row)
        folder.write_run_json({
            "name": out.name, "kind": "eval", "config": config or {},
            "started": now_iso(), "finished": now_iso(), "status": "finished", "executor": "eval", "workers": 1,
            "n_cases": len(entries), "versions": package_versions(), "git_commit": git_commit(), "git_dirty": git_dirty(), "code_sha256": code_hash(),
            "machine": machine_info(), "command": " ".join(sys.argv),
            "tasks": {t: tasks.get(t).spec() for t in rows_by_task}})
        build_report(out)
        return Frames(folder.frames())
    finally:
        lock.close()


RESULTS_KEYS = {"file", "clean", "noisy", "label", "task"}


def results_config(raw: dict, base_dir: Path) -> tuple[list[dict], int]:
    """Validate a ``results:`` config (``name``, ``hausdorff_samples``, ``results: [{file, clean,
    noisy, label, task}]``): the entries with resolved paths, or `ConfigError` listing every
    problem with its key path."""
    from .errors import ConfigError
    P = []
    for k in sorted(set(raw) - {"name", "results", "hausdorff_samples"}):
        P.append(f"{k}: unknown key in a results config; expected name, results, hausdorff_samples")
    if name_problem(raw.get("name", "eval")):
        P.append(f"name: {name_problem(raw.get('name', 'eval'))}")
    hs = raw.get("hausdorff_samples", 20000)
    if samples_problem(hs):
        P.append(f"hausdorff_samples: {samples_problem(hs)}")
    res = raw.get("results")
    entries = []
    if not isinstance(res, list) or not res:
        P.append("results: expected a non-empty list of {file: ..., clean: ..., label: ...}")
        res = []
    for i, e in enumerate(res):
        at = f"results[{i}]"
        if not isinstance(e, dict):
            P.append(f"{at}: expected a mapping with file and clean")
            continue
        for k in sorted(set(e) - RESULTS_KEYS):
            P.append(f"{at}.{k}: unknown key; expected one of {sorted(RESULTS_KEYS)}")
        entry = {"label": e.get("label"), "task": e.get("task"), "noisy": None}
        for k in ("file", "clean", "noisy"):
            if k not in e:
                if k != "noisy":
                    P.append(f"{at}.{k}: missing")
                continue
            v = e[k]
            path = Path(v) if isinstance(v, str) else None
            if path is not None and not path.is_absolute():
                path = base_dir / path
            if path is None or not path.is_file():
                P.append(f"{at}.{k}: file not found: {v!r}"[:300])
                continue
            entry[k] = path
        if entry["task"] not in (None, "smoothing", "simplification"):
            P.append(f"{at}.task: expected smoothing or simplification, got {entry['task']!r}"[:200])
        if entry["label"] is not None and not isinstance(entry["label"], str):
            P.append(f"{at}.label: expected a string")
        entries.append(entry)
    if P:
        raise ConfigError("<config>", P)
    return entries, hs


def _same_faces(A: np.ndarray, B: np.ndarray) -> bool:
    """Whether two face lists hold the same oriented triangles, in any order and from any starting
    corner (each face rotated to start at its smallest index, then the rows sorted)."""
    if A.shape != B.shape:
        return False

    def canonical(F):
        F = np.asarray(F, np.int64)
        k = np.argmin(F, axis=1)[:, None]
        R = np.take_along_axis(F, (k + np.arange(3)) % 3, axis=1)
        return R[np.lexsort(R.T[::-1])]
    return bool(np.array_equal(canonical(A), canonical(B)))


def _in_clean_order(r: Mesh, cmesh: Mesh, n_raw: int, F_raw: np.ndarray, path: Path) -> np.ndarray:
    """A smoothing result's positions in the clean mesh's (repaired) vertex order: the result has
    either the repaired mesh's vertices and faces or the clean file's own (then the repair's
    vertex map applies), faces in any order and from any starting corner. Equal counts with other faces (e.g. an STL, whose reader welds and
    re-sorts the corners) are an error: per-vertex errors would pair unrelated vertices."""
    if len(r.V) == cmesh.n_vertices and _same_faces(r.F, cmesh.F):
        return r.V
    if len(r.V) == n_raw and _same_faces(r.F, F_raw) and cmesh.vertex_map is not None:
        return r.V[cmesh.vertex_map]
    if len(r.V) in (cmesh.n_vertices, n_raw):
        raise ShootoutError(f"{path.name}: as many vertices as the clean mesh, but other faces: a smoothing result "
                            "must keep the clean mesh's vertices in order and its faces (STL loses the order: save "
                            "OBJ, OFF or PLY; or use --task simplification to compare surfaces instead)")
    raise ShootoutError(f"{path.name}: {len(r.V)} vertices, but the clean mesh has {cmesh.n_vertices}: a smoothing "
                        "result must keep the clean mesh's vertices in order (use --task simplification to "
                        "compare surfaces instead)")
