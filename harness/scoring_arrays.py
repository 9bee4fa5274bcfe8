"""The task's metrics of a result given as arrays (`evaluate`), with the checks of what it is given:
``(n, 3)`` coordinate and face arrays (`_array`), a simplification target (`target_problems`) and a
smoothing result's vertex order against the clean mesh's (`in_clean_order`, faces compared in any
order and from any starting corner by `_same_faces`).
"""
from __future__ import annotations

import numpy as np

from . import tasks
from . import yaml_input
from .config import eps_problem, samples_problem
from .core.geometry import referenced
from .errors import ShootoutError, problems_error
from .mesh import Mesh, validate
from .tasks.base import CaseInput


def _result(task_name: str, V, F):
    task = tasks.get(task_name)
    if task_name == "smoothing":
        return task.result_type(V=np.asarray(V, dtype=np.float64))
    if task_name == "simplification":
        return task.result_type(V=np.asarray(V, dtype=np.float64), F=np.asarray(F, dtype=np.int64))
    raise ShootoutError(f"eval scores smoothing and simplification results, not {task_name!r}")


def evaluate(V, F, V_clean, F_clean, task: str = "smoothing", V_noisy=None, hausdorff_samples: int = 20000,
             target_faces: int | None = None, target_ratio: float | None = None, what: str = "result",
             hausdorff_eps: float = 1e-3) -> dict:
    """The task's metrics of a result ``(V, F)`` against the clean mesh ``(V_clean, F_clean)``.

    The clean mesh gets a run's documented repairs first (faces with a repeated vertex,
    duplicate faces and unreferenced vertices removed: `harness.mesh.validate`), so the
    diagonal, the surface and the per-vertex means are a run's. ``task``: ``smoothing`` (``V``
    has the clean mesh's vertices in order, as given or as repaired; ``F`` is None or the
    matching faces, in any order and from any starting corner) or ``simplification`` (``(V,
    F)`` is compared to the input surface: ``V_noisy`` with the clean faces when given, else the
    clean mesh; ``target_faces``, or ``target_ratio`` of the repaired clean mesh's faces, is the
    face count it was asked for: without either, ``target_faces`` and ``over_target`` are blank,
    not judged; a smoothing result has no target). ``V_noisy``: the input the result was made
    from (smoothing: gives the ``input_*`` columns; blank without it), finite, in either vertex
    order. ``V``, ``V_clean``, ``V_noisy``: ``(n, 3)`` arrays of real numbers; ``F``,
    ``F_clean``: ``(m, 3)`` arrays of integer indices (floats only with integer values). Numbers
    may be numpy scalars. Lengths are fractions of the clean mesh's bounding-box diagonal, as in a run.
    ``hausdorff_samples``, ``hausdorff_eps``: a config's settings of those names. `ShootoutError`
    listing every problem on input that breaks these preconditions (``what`` names the result in
    its messages).
    """
    hausdorff_samples, hausdorff_eps, target_faces, target_ratio = (
        x.item() if isinstance(x, np.generic) else x
        for x in (hausdorff_samples, hausdorff_eps, target_faces, target_ratio))     # numpy scalars as Python's
    P = []
    if task not in ("smoothing", "simplification"):
        P.append(f"task: eval scores smoothing and simplification results, not {task!r}")
    if samples_problem(hausdorff_samples):
        P.append(f"hausdorff_samples: {samples_problem(hausdorff_samples)}")
    if eps_problem(hausdorff_eps):
        P.append(f"hausdorff_eps: {eps_problem(hausdorff_eps)}")
    P += target_problems(target_faces, target_ratio)
    given = [k for k, v in (("target_faces", target_faces), ("target_ratio", target_ratio)) if v is not None]
    if task == "smoothing" and given:
        P.append(f"{', '.join(given)}: a smoothing result has no target (drop it, or task='simplification')")
    arrays = {}
    for name, x, kind in (("V", V, "coords"), ("F", F, "faces"), ("V_clean", V_clean, "coords"),
                          ("F_clean", F_clean, "faces"), ("V_noisy", V_noisy, "coords")):
        if x is None and name in ("F", "V_noisy"):
            continue
        a, why = _array(x, kind)
        if why:
            P.append(f"{name}: {why}")
        arrays[name] = a
    if task == "simplification" and F is None:
        P.append("F: a simplification result needs its faces")
    in_range = {}
    for f, v in (("F", "V"), ("F_clean", "V_clean")):
        a, n = arrays.get(f), arrays.get(v)
        in_range[f] = a is not None and n is not None and (not a.size or (a.min() >= 0 and a.max() < len(n)))
        if a is not None and n is not None and not in_range[f]:
            P.append(f"{f}: vertex indices out of range (from {int(a.min())} to {int(a.max())}; {v} has {len(n)} "
                     "vertices)")
    if in_range["F_clean"]:                      # over the vertices the clean faces use (a dropped one is repaired);
        used = referenced(arrays["F_clean"], len(arrays["V_clean"]))   # the result's own may diverge: measured
        for name in ("V_clean", "V_noisy"):
            a = arrays.get(name)
            if a is not None and len(a) == len(arrays["V_clean"]) and not np.isfinite(a[used]).all():
                P.append(f"{name}: {int((~np.isfinite(a[used]).all(axis=1)).sum())} vertices with NaN or inf "
                         "coordinates")
    if P:
        raise problems_error(P)
    V, F, V_clean, F_clean, V_noisy = (arrays.get(k) for k in ("V", "F", "V_clean", "F_clean", "V_noisy"))
    n_raw, F_raw = len(V_clean), F_clean
    clean = validate(V_clean, F_clean, name="clean")
    V_in = clean.V
    if V_noisy is not None:
        V_in = V_noisy
        if len(V_in) not in (clean.n_vertices, n_raw):
            raise ShootoutError(f"V_noisy: {len(V_in)} vertices, the clean mesh {len(clean.V)}"
                                + (f" ({n_raw} before its repairs)" if n_raw != clean.n_vertices else ""))
        if len(V_in) != clean.n_vertices:
            V_in = V_in[clean.vertex_map]
        if not np.isfinite(V_in).all():
            raise ShootoutError(f"V_noisy: {int((~np.isfinite(V_in).all(axis=1)).sum())} vertices with "
                                "NaN or inf coordinates")
    if task == "smoothing":
        V = in_clean_order(V, F, clean, n_raw, F_raw, what)
        F = None
    inp = CaseInput(clean, V_in, clean.F, clean.diagonal(), {"hausdorff_samples": hausdorff_samples,
                                                              "hausdorff_eps": hausdorff_eps})
    res = _result(task, V, F)
    t = tasks.get(task)
    res = t.validate_result("result", res, inp.V, inp.F)
    params = {}
    if task == "simplification":
        params = {"target_ratio": target_ratio, "target_faces": target_faces}
    row = t.measured(inp, res, params)
    if V_noisy is None:
        for k in [k for k in row if k.startswith("input_")]:
            row[k] = None
    return row


def _array(x, kind: str):
    """``(array, None)`` for an ``(n, 3)`` array of real coordinates (``kind`` ``coords``, as
    float64) or of integer vertex indices (``faces``: integers, or floats with integer values, as
    int64); else ``(None, what is wrong)``."""
    what = "an (n, 3) array of vertex coordinates" if kind == "coords" else "an (m, 3) array of vertex indices"
    if x is None or isinstance(x, (str, bytes)):
        return None, f"expected {what}, got {yaml_input.short(x, 60)}"
    try:
        a = np.asarray(x)
    except Exception as exc:  # noqa: BLE001 - e.g. rows of different lengths
        return None, f"expected {what}, got a {type(x).__name__} numpy cannot read as one ({exc})"[:300]
    if a.dtype.kind == "c":
        return None, f"expected real numbers, got complex values (dtype {a.dtype})"
    if a.dtype.kind not in "iuf" or a.ndim != 2 or a.shape[1] != 3:
        got = f"shape {a.shape}" if a.dtype.kind in "iuf" else f"dtype {a.dtype}"
        return None, f"expected {what}, got {got}"
    if kind == "coords":
        return a.astype(np.float64), None
    if a.dtype.kind == "f" and not np.array_equal(a, np.round(a)):
        return None, f"expected integer vertex indices, got dtype {a.dtype} with non-integer values"
    return a.astype(np.int64), None


def target_problems(target_faces, target_ratio, at: str = "") -> list[str]:
    """What is wrong with a simplification result's target: an integer ``target_faces >= 1`` or a
    ``target_ratio`` in (0, 1], not both."""
    P = []
    if target_faces is not None and (isinstance(target_faces, bool) or not isinstance(target_faces, (int, np.integer))
                                     or target_faces < 1):
        P.append(f"{at}target_faces: expected an integer >= 1 (the face count the simplification was asked for), "
                 f"got {target_faces!r}")
    if target_ratio is not None and (isinstance(target_ratio, bool) or not isinstance(target_ratio, (int, float))
                                     or not 0 < target_ratio <= 1):
        P.append(f"{at}target_ratio: expected a number in (0, 1] (the fraction of the clean mesh's faces asked "
                 f"for), got {target_ratio!r}")
    if target_faces is not None and target_ratio is not None:
        P.append(f"{at}target_faces, {at}target_ratio: give one of the two")
    return P


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


def in_clean_order(V: np.ndarray, F, clean: Mesh, n_raw: int, F_raw: np.ndarray, what: str) -> np.ndarray:
    """A smoothing result's positions in the clean mesh's (repaired) vertex order: the result has
    either the repaired mesh's vertices (and faces, when given) or the clean file's own (then
    the repair's vertex map applies), faces in any order and from any starting corner. Equal
    counts with other faces (e.g. an STL, whose reader welds and re-sorts the corners) are an
    error: per-vertex errors would pair unrelated vertices."""
    F = None if F is None else np.asarray(F, np.int64)
    if len(V) == clean.n_vertices and (F is None or _same_faces(F, clean.F)):
        return V
    if len(V) == n_raw and (F is None or _same_faces(F, F_raw)):
        return V[clean.vertex_map]
    if len(V) in (clean.n_vertices, n_raw):
        raise ShootoutError(f"{what}: as many vertices as the clean mesh, but other faces: a smoothing result "
                            "must keep the clean mesh's vertices in order and its faces (STL loses the order: save "
                            "OBJ, OFF or PLY; or use --task simplification to compare surfaces instead)")
    raise ShootoutError(f"{what}: {len(V)} vertices, but the clean mesh has {clean.n_vertices}"
                        + (f" ({n_raw} before its repairs)" if n_raw != clean.n_vertices else "")
                        + ": a smoothing result must keep the clean mesh's vertices in order (use --task "
                        "simplification to compare surfaces instead)")
