"""Task ``smoothing``: new vertex positions for the noisy input (same vertices, same faces),
measured against the clean mesh. Lengths are fractions of the clean mesh's bounding-box
diagonal, angles in degrees."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.geometry import zero_area_faces
from ..errors import MethodFailed
from ..metrics.hausdorff import hausdorff
from ..metrics.normal_error import angle_summary
from ..metrics.surface_distance import cached_surface, point_surface_distance, surface_distance
from ..metrics.triangle_quality import triangle_quality, warm as _warm_metrics
from ..metrics.vertex_error import vertex_error
from .base import Invalid, Metric, Task, float_array


@dataclass
class SmoothingResult:
    """Smoothed vertex positions ``V`` (n, 3) float64, same order as the input; faces unchanged."""

    V: np.ndarray


def _check(result: SmoothingResult, V, F):
    result.V = float_array("", "V", result.V, (V.shape[0], 3))
    return result


def diverged(V_out: np.ndarray, V_in: np.ndarray) -> bool:
    """True when coordinates are non-finite or leave 100x the input bounding box (about its centre),
    each half-extent taken at least 1e-3 of the box diagonal (a flat input has a zero extent, and
    rounding-level motion across it is no divergence)."""
    if not np.isfinite(V_out).all():
        return True
    lo, hi = V_in.min(0), V_in.max(0)
    c = (lo + hi) / 2
    half = np.maximum((hi - lo) / 2, max(1e-3 * float(np.linalg.norm(hi - lo)), 1e-300))
    return bool((np.abs(V_out - c) > 100 * half).any())


def bounds_volume(F, n: int) -> bool:
    """Every edge of the triangles ``F`` (on ``n`` vertices) has exactly two faces, which traverse
    it in opposite directions (closed, edge-manifold, consistently oriented): the signed volume
    is then the enclosed one."""
    F = np.asarray(F, dtype=np.int64)
    a, b = F.ravel(), F[:, [1, 2, 0]].ravel()
    d, r = np.sort(a * np.int64(n) + b), np.sort(b * np.int64(n) + a)
    return bool(d.size and np.array_equal(d, r) and (d[1:] != d[:-1]).all())


def _closed(inp) -> bool:
    """`bounds_volume` of the clean mesh, once per input."""
    if "closed" not in inp.cache:
        inp.cache["closed"] = bounds_volume(inp.clean.F, len(inp.clean.V))
    return inp.cache["closed"]


def _clean_surface(inp):
    """The clean mesh's AABB surface, built once per input and shared by every distance metric."""
    return cached_surface(inp.cache, "clean_surface", inp.clean.V, inp.F)


def _face_terms(V, F, o, C=None):
    """Unit normals, double areas, volume terms about ``o`` and (with reference normals ``C``)
    angles to ``C`` of the faces of (V, F) (`harness.metrics._quality_kernel.face_terms`)."""
    from ..metrics._quality_kernel import face_terms
    return face_terms(np.ascontiguousarray(V, dtype=np.float64), np.ascontiguousarray(F, dtype=np.int64),
                      np.asarray(o, dtype=np.float64), np.zeros((0, 3)) if C is None else C)


def _clean_terms(inp) -> dict:
    """The clean mesh's unit face normals, area, centroid and volume about it, once per input."""
    if "clean_terms" not in inp.cache:
        o = inp.clean.V.mean(0)
        N, dbl, vol, _ = _face_terms(inp.clean.V, inp.F, o)
        inp.cache["clean_terms"] = {"normals": N, "area": float(dbl.sum() / 2), "centroid": o,
                                    "volume": float(vol.sum() / 6.0) if _closed(inp) else None}
    return inp.cache["clean_terms"]


def _back(S, SV) -> float:
    """``dist_mean_back``: mean over the clean vertices of their exact distance to ``SV``, the
    surface of the same faces on other positions (``S.displaced(V)``, ``S`` the clean `Surface`)."""
    return float(SV.corresponding_distances(S.V, S.walk()).mean()) if len(S.V) else float("nan")


def _input_metrics(inp) -> dict:
    if "input_metrics" not in inp.cache:
        V_clean, F, diag = inp.clean.V, inp.F, inp.diag
        clean = _clean_terms(inp)
        _, dbl, _, ang = _face_terms(inp.V, F, clean["centroid"], clean["normals"])
        S = _clean_surface(inp)
        d = S.corresponding_distances(inp.V)
        dm = surface_distance(inp.V, F, V_clean, F, d=d, double_areas_=dbl)["dist_mean"] / diag
        inp.cache["input_metrics"] = {
            "input_ev_mean": vertex_error(inp.V, V_clean)["ev_mean"] / diag,
            "input_dist_mean": dm,
            "input_dist_mean_sym": (dm + _back(S, S.displaced(inp.V)) / diag) / 2,
            "input_normal_error_deg": angle_summary(ang)["normal_error_deg"]}
    return dict(inp.cache["input_metrics"])


def measure(inp, result, params) -> dict:
    """Accuracy of the smoothed positions against the clean mesh (same vertices and faces)."""
    V_out, V_in, V_clean, F, diag = result.V, inp.V, inp.clean.V, inp.F, inp.diag
    if not np.isfinite(V_out).all():
        # non-finite output is instability (diverged, kept as data) on a sound mesh, but a
        # library dividing by zero on a degenerate one: that is an error row naming the faces
        bad = zero_area_faces(V_in, F)
        if bad.size:
            raise MethodFailed(f"returned non-finite coordinates on an input with {bad.size} zero-area "
                               f"face(s) (first: {bad[:5].tolist()})")
    row = _input_metrics(inp)
    row["diverged"] = diverged(V_out, V_in)
    if row["diverged"]:
        return row
    ve = vertex_error(V_out, V_clean)
    S = _clean_surface(inp)
    S_out = S.displaced(V_out)
    hd = hausdorff(V_out, F, V_clean, F, eps=inp.settings.get("hausdorff_eps", 1e-3), n_samples=0, surface_b=S,
                   corresponding=True, vertex_distances=True, surface_a=S_out)
    clean = _clean_terms(inp)
    _, dbl, vol, ang = _face_terms(V_out, F, clean["centroid"], clean["normals"])
    sd = surface_distance(V_out, F, V_clean, F, d=hd["vertex_distances_ab"], double_areas_=dbl)
    row.update({"ev_mean": ve["ev_mean"] / diag, "ev_rms": ve["ev_rms"] / diag,
                "dist_mean": sd["dist_mean"] / diag, "dist_mean_back": _back(S, S_out) / diag,
                "ev_sun": sd["ev_sun"] / diag,
                "hausdorff": hd["hausdorff"] / diag, "hausdorff_gap": hd["hausdorff_gap"],
                "hausdorff_upper": hd["hausdorff_upper"] / diag})
    row["dist_mean_sym"] = (row["dist_mean"] + row["dist_mean_back"]) / 2
    row.update(angle_summary(ang))
    a0 = clean["area"]
    row["area_ratio"] = float(dbl.sum() / 2) / a0 if a0 > 0 else None
    if _closed(inp):
        v0 = clean["volume"]        # both about the clean centroid: no cancellation far from the origin
        row["volume_ratio"] = float(vol.sum() / 6.0) / v0 if v0 != 0 else None
    row.update(triangle_quality(V_out, F))
    return row


def output_mesh(inp, result):
    return result.V, inp.F


def view(inp, result) -> list:
    """Meshes of the 3D view: coloured by the distance of each vertex to the clean surface."""
    S = _clean_surface(inp)
    e_in = point_surface_distance(inp.V, inp.clean.V, inp.F, S) / inp.diag
    e_out = point_surface_distance(result.V, inp.clean.V, inp.F, S) / inp.diag
    what = "distance of each vertex to the clean surface"
    return [("clean", inp.clean.V, inp.F, None, "reference mesh"),
            ("noisy input", inp.V, inp.F, e_in, what), ("result", result.V, inp.F, e_out, what)]


_LEN = dict(unit="diag", rel=0.01, abs=1e-6)
_DEG = dict(unit="deg", rel=0.01, abs=0.01)
TASK = Task(
    name="smoothing", title="Smoothing", result_type=SmoothingResult,
    intro="Smoothed meshes against the clean mesh. Lengths are fractions of the clean mesh's bounding-box "
          "diagonal; lower is better.",
    metrics=(
        Metric("ev_mean", "lower", "mean distance of each vertex to its clean position", rank=True, **_LEN),
        Metric("ev_rms", "lower", "RMS distance of each vertex to its clean position", **_LEN),
        Metric("dist_mean", "lower", "mean over the result's vertices of their distance to the clean surface "
               "(vertex-to-surface; simplification's surface_dist_mean is surface-to-surface)", rank=True, **_LEN),
        Metric("dist_mean_back", "lower", "mean over the clean mesh's vertices of their distance to the result's "
               "surface: the direction dist_mean, ev_sun and normal_error_deg do not see (a result that shrinks or "
               "slides along the clean surface)", **_LEN),
        Metric("dist_mean_sym", "lower", "(dist_mean + dist_mean_back) / 2, the two-sided vertex-to-surface mean; a "
               "result above the noisy input's is invalid", rank=True, **_LEN),
        Metric("ev_sun", "lower", "area-weighted RMS vertex-to-clean-surface distance (Sun et al. 2007)",
               rank=True, **_LEN),
        Metric("hausdorff", "lower", "symmetric Hausdorff distance between the result and the clean surface, "
               "certified by branch and bound within hausdorff_gap", upper="hausdorff_upper", **_LEN),
        Metric("hausdorff_gap", "info", "relative gap of the Hausdorff bracket (<= hausdorff_eps, default 1e-3, unless a budget ran out)",
               rel=1.0, abs=1e-3),
        Metric("hausdorff_upper", "info", "certified upper bound of the Hausdorff distance", **_LEN),
        Metric("normal_error_deg", "lower", "mean angle between result and clean face normals (faces degenerate "
               "in the clean mesh left out; a face the result collapsed counts 90)", rank=True, **_DEG),
        Metric("normal_error_rms_deg", "lower", "RMS angle between result and clean face normals", **_DEG),
        Metric("volume_ratio", "one", "enclosed volume / clean volume (closed, consistently oriented clean "
               "meshes; blank otherwise)", rel=0.01, abs=1e-4),
        Metric("area_ratio", "one", "surface area / clean area", rel=0.01, abs=1e-4),
        Metric("min_angle", "higher", "smallest triangle angle", unit="deg", rel=0.01, abs=0.01),
        Metric("max_angle", "lower", "largest triangle angle", unit="deg", rel=0.01, abs=0.01),
        Metric("radius_ratio_mean", "higher", "mean of 2 r_in / r_circ over faces (1 = equilateral)",
               rel=0.01, abs=1e-3),
        Metric("obtuse_fraction", "lower", "fraction of faces with an angle above 90 degrees", rel=0.01, abs=2e-3),
        Metric("diverged", "false", "non-finite or left 100x the input's bounding box", kind="bool"),
        Metric("input_ev_mean", "input", "ev_mean of the noisy input", unit="diag"),
        Metric("input_dist_mean", "input", "dist_mean of the noisy input", unit="diag"),
        Metric("input_dist_mean_sym", "input", "dist_mean_sym of the noisy input", unit="diag"),
        Metric("input_normal_error_deg", "input", "normal_error_deg of the noisy input", unit="deg"),
        Metric("min_angle_hist", "info", "histogram of the smallest angle per face (12 bins of 5 degrees over [0, 60])",
               kind="json"),
    ),
    measure=measure, check_result=_check, output_mesh=output_mesh, view=view, view_metric="dist_mean", order=20,
    preload=_warm_metrics, input_facts=("closed", "input_metrics", "clean_surface", "clean_terms"),
    invalid_when=(Invalid("diverged", "==", "diverged", value=True),
                  Invalid("dist_mean", ">", "worse than the noisy input", than="input_dist_mean"),
                  Invalid("dist_mean_sym", ">", "farther from the clean surface than the noisy input, both ways on "
                          "average", than="input_dist_mean_sym")))
