"""Score results made elsewhere exactly as a run scores its own: `evaluate` for arrays,
`eval_files` (``shootout eval``) for mesh files, writing a normal run folder.

The measurement is the task's own (`harness.tasks`): the same metrics, the same definitions, the
same code path as `harness.runner.run_case` after the method call. A smoothing result must have
the clean mesh's vertices in the same order (the same count as the clean file, or as the clean
mesh after the documented repairs); a simplification result is compared as a surface.
"""
from __future__ import annotations

import hashlib
import json
import os
import sys
from pathlib import Path

from . import tasks
from .config import eps_problem, name_problem, samples_problem
from .errors import ShootoutError, problems_error
from .mesh import file_sha1, missing_file_problem, read_mesh
from .provenance import code_hash, git_commit, git_dirty, machine_info, now_iso, package_versions
from .results import Frames, RunFolder, out_dir_problems
from .scoring_arrays import evaluate, in_clean_order, target_problems  # noqa: F401

__all__ = ["RESULTS_KEYS", "default_labels", "eval_entries", "eval_files", "evaluate", "in_clean_order",
           "results_config", "target_problems"]


def _sha1_file(p) -> str | None:
    try:
        return file_sha1(p)
    except OSError:
        return None


def _eval_id(e: dict, task: str, seen: set) -> str:
    """A scored file's case id: a hash of its label, the clean (and noisy) mesh's bytes, the
    ``task`` its row is scored under (given or detected: the CSV it goes to) and its target when
    one was given, so that two evals' rows of one label match in `shootout compare` whatever
    order the files were given in and whether the task was given or detected (the files
    themselves may differ: that is what compare measures); a repeat of a label within one eval
    gets the next free id. Versions before 2026-11-27 hashed the task as given (none when
    detected): their eval folders share no case id with this version's."""
    key = [e.get("label") or Path(e["file"]).stem, _sha1_file(e["clean"]), _sha1_file(e["noisy"]) if e.get("noisy") else None, task]
    key += [[k, e[k]] for k in ("target_faces", "target_ratio") if e.get(k) is not None]
    i = 0
    while True:
        cid = hashlib.sha1(json.dumps(key + ([i] if i else [])).encode()).hexdigest()[:12]
        if cid not in seen:
            seen.add(cid)
            return cid
        i += 1


def _label(path: Path, labels, i) -> str | None:
    return labels[i] if labels and i < len(labels) else None


def default_labels(paths: list) -> list[str]:
    """Each result file's label when none is given: its name without the extension, or, where
    other files of one eval share that name (``toolA/out.obj``, ``toolB/out.obj``), the fewest
    trailing folders that tell them apart (``toolA/out``, ``toolB/out``; with the extension when
    only it does: ``out.obj``, ``out.ply``): a label, and so a case id, that does not depend on
    the order the files were given in. One file given twice keeps one label."""
    paths = [Path(p) for p in paths]
    full = [Path(os.path.abspath(p)).parts[1:] for p in paths]           # no root
    bare = [f[:-1] + (Path(f[-1]).stem,) if f else f for f in full]
    out = [p.stem for p in paths]
    for stem in {s for s in out if out.count(s) > 1}:
        group = [i for i, s in enumerate(out) if s == stem]
        files = {full[i] for i in group}
        if len(files) < 2:
            continue                            # one file given twice: the same label
        depth = max(len(full[i]) for i in group)
        for parts in (bare, full):              # folders first; the extension only when it alone tells them apart
            n = next((n for n in range(1, depth + 1) if len({parts[i][-n:] for i in group}) == len(files)), None)
            if n is not None:
                for i in group:
                    out[i] = "/".join(parts[i][-n:])
                break
    return out


def eval_files(clean, results, out, noisy=None, task: str | None = None, labels=None,
               hausdorff_samples: int = 20000, target_faces: int | None = None,
               target_ratio: float | None = None, hausdorff_eps: float = 1e-3) -> dict:
    """Score result files against ``clean`` (and ``noisy``); write a run folder at ``out``.
    ``target_faces`` / ``target_ratio``: what the simplification results were asked for (see
    `evaluate`)."""
    results = [Path(r) for r in results]
    P = target_problems(target_faces, target_ratio, at="--")
    P = [p.replace("--target_faces", "--target-faces").replace("--target_ratio", "--target-ratio") for p in P]
    if labels and len(labels) != len(results):
        P.append(f"--label: {len(labels)} label(s) for {len(results)} result file(s)")
    if task == "smoothing" and (target_faces is not None or target_ratio is not None):
        P.append("--target-faces, --target-ratio: a smoothing result has no target (drop them, or --task simplification)")
    entries = [{"file": r, "clean": Path(clean), "noisy": Path(noisy) if noisy else None, "task": task,
                "label": _label(r, labels, i), "target_faces": target_faces, "target_ratio": target_ratio}
               for i, r in enumerate(results)]
    return eval_entries(entries, out, hausdorff_samples, hausdorff_eps=hausdorff_eps, config=
                        {"eval": {"clean": str(clean), "noisy": noisy and str(noisy), "results": [str(r) for r in results],
                                  **({"target_faces": target_faces} if target_faces is not None else {}),
                                  **({"target_ratio": target_ratio} if target_ratio is not None else {}),
                                  "hausdorff_samples": hausdorff_samples, "hausdorff_eps": hausdorff_eps}},
                        problems=P)


def eval_entries(entries: list[dict], out, hausdorff_samples: int = 20000, config: dict | None = None,
                 problems=(), hausdorff_eps: float = 1e-3) -> dict:
    """Score each ``{file, clean, noisy, task, label, target_faces, target_ratio}`` entry (paths;
    all but ``file`` and ``clean`` optional) and write one run folder at ``out`` with its report;
    ``problems`` (the caller's) join this function's in one `problems_error`, nothing written."""
    from . import datasets
    from .report import build_report
    if not str(out).strip():                 # Path("") would be the current folder
        raise problems_error(list(problems) + ["--out: an empty path; give the folder to write"])
    out = Path(out)
    folder = RunFolder(out)
    P = list(problems) + out_dir_problems(out)   # nothing of the user's is replaced or deleted
    if samples_problem(hausdorff_samples):
        P.append(f"--hausdorff-samples: {samples_problem(hausdorff_samples)}")
    if eps_problem(hausdorff_eps):
        P.append(f"--hausdorff-eps: {eps_problem(hausdorff_eps)}")
    for e in entries:
        for p in [e["file"], e["clean"]] + ([e["noisy"]] if e.get("noisy") else []):
            why = missing_file_problem(p)
            if why:
                P.append(f"{p}: {why}")
    if P:                                        # every problem at once, nothing written
        raise problems_error(list(dict.fromkeys(P)))
    auto = default_labels([e["file"] for e in entries])
    cleans_given = list(dict.fromkeys(str(Path(e["clean"])) for e in entries))
    mesh_names = dict(zip(cleans_given, default_labels(cleans_given)))   # two clean files named alike: their folders
    entries = [e if e.get("label") else {**e, "label": auto[i]} for i, e in enumerate(entries)]
    rows: list[tuple[dict, bool]] = []          # each file's row, and whether its task is known (given or read)
    cleans: dict = {}
    seen_ids: set = set()
    for i, e in enumerate(entries):
        clean, noisy, rp = Path(e["clean"]), e.get("noisy"), Path(e["file"])
        key = (str(clean), str(noisy))
        if key not in cleans:
            try:
                raw = read_mesh(clean, repair=False)
                if noisy:
                    src = datasets.cached({"file": str(Path(noisy).resolve()), "clean": str(clean.resolve())})
                    cleans[key] = (src.clean, src.noisy_V, raw)
                else:
                    cleans[key] = (read_mesh(clean), None, raw)
            except ShootoutError as exc:         # a reference that cannot be read costs its results' rows
                cleans[key] = exc
        got = cleans[key]
        targeted = any(e.get(k) is not None for k in ("target_faces", "target_ratio"))
        known = bool(e.get("task")) or targeted   # else known once the file is read: its counts decide
        base = {"case_id": None, "task": e.get("task") or ("simplification" if targeted else "smoothing"),
                "noise_model": "given" if noisy else "none", "noise_level": None, "seed": None,
                "method": e.get("label") or rp.stem, "library": "external", "params": json.dumps({"file": str(rp)})}
        if isinstance(got, Exception):
            what = "the clean mesh" if not noisy else "the clean and noisy pair"
            rows.append(({**base, "mesh": mesh_names[str(clean)], "status": "error",
                          "error": f"{what} ({clean}{f', {noisy}' if noisy else ''}): {got}"[:2000]},
                         known))
            continue
        cmesh, V_in, raw = got
        n_raw, m_raw = len(raw.V), len(raw.F)
        notes = [f"input repaired: {'; '.join(cmesh.repairs)}"] if cmesh.repairs else []
        row = {**base, "mesh": mesh_names[str(clean)], "n_vertices": cmesh.n_vertices, "n_faces": cmesh.n_faces,
               "status": "ok", "error": ""}
        try:                                     # a bad result file costs its row, as a crashing method does
            r = read_mesh(rp, repair=False, finite=False)     # NaN: scored as the task scores it (diverged)
            if r.repairs:
                notes.append(f"result read with repairs: {'; '.join(r.repairs)}")
            same_faces = len(r.F) in (cmesh.n_faces, m_raw)
            detected = "smoothing" if len(r.V) in (cmesh.n_vertices, n_raw) and same_faces else "simplification"
            t = row["task"] = e.get("task") or ("simplification" if targeted else detected)
            known = True                         # a failure from here on stays under this task (and case id)
            if t == "smoothing" and not same_faces:
                raise ShootoutError(f"{rp.name}: {len(r.F)} faces, but the clean mesh has {cmesh.n_faces}: a "
                                    "smoothing result keeps the clean mesh's faces (use --task simplification to "
                                    "compare surfaces)")
            target = {k: e.get(k) for k in ("target_faces", "target_ratio")} if t == "simplification" else {}
            if t == "simplification" and not any(v is not None for v in target.values()):
                notes.append("no target given (--target-faces or --target-ratio): over_target is not judged")
            row.update(evaluate(r.V, r.F, raw.V, raw.F, task=t, V_noisy=V_in, hausdorff_samples=hausdorff_samples,
                                hausdorff_eps=hausdorff_eps, **target, what=rp.name))
            row["error"] = "; ".join(notes)
        except Exception as exc:  # noqa: BLE001 - any failure scoring one file is that file's error row
            row.update(status="error", error=(f"{type(exc).__name__}: {exc}" if not isinstance(exc, ShootoutError)
                                              else str(exc))[:2000])
        rows.append((row, known))
    scored = {r["task"] for r, _ in rows if r["status"] == "ok"}
    if len(scored) == 1:              # a file that could not be read goes beside the others it was scored with
        for r, known in rows:
            if r["status"] != "ok" and not known:
                r["task"] = next(iter(scored))
    for e, (r, _) in zip(entries, rows):
        r["case_id"] = _eval_id(e, r["task"], seen_ids)
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


RESULTS_KEYS = {"file", "clean", "noisy", "label", "task", "target_faces", "target_ratio"}


def results_config(raw: dict, base_dir: Path, source: str = "<config>") -> tuple[list[dict], int]:
    """Validate a ``results:`` config (``name``, ``hausdorff_samples``, ``results: [{file, clean,
    noisy, label, task, target_faces | target_ratio}]``): the entries with resolved paths, or
    `ConfigError` from ``source`` listing every problem with its key path."""
    from .errors import ConfigError
    P = []
    for k in sorted(set(raw) - {"name", "results", "hausdorff_samples", "hausdorff_eps"}):
        P.append(f"{k}: unknown key in a results config; expected name, results, hausdorff_samples, hausdorff_eps")
    if eps_problem(raw.get("hausdorff_eps", 1e-3)):
        P.append(f"hausdorff_eps: {eps_problem(raw.get('hausdorff_eps'))}")
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
        entry = {"label": e.get("label"), "task": e.get("task"), "noisy": None,
                 "target_faces": e.get("target_faces"), "target_ratio": e.get("target_ratio")}
        P += target_problems(entry["target_faces"], entry["target_ratio"], at=f"{at}.")
        if entry["task"] == "smoothing" and (entry["target_faces"] is not None or entry["target_ratio"] is not None):
            P.append(f"{at}.task: a smoothing result has no target_faces or target_ratio")
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
        raise ConfigError(source, P)
    return entries, hs
