"""Triangle quality: angles, radius ratio, obtuse fraction, min-angle histogram."""
import json

import numpy as np

from ..core.geometry import corner_angles, edge_lengths

HIST_EDGES = np.arange(0, 65, 5.0)       # min angle of a triangle is at most 60 degrees
COMPILED_FROM = 20_000                   # faces; below, numpy (no numba import)


def triangle_quality(V: np.ndarray, F: np.ndarray) -> dict:
    """``min_angle``/``max_angle``: smallest/largest interior angle over all faces (degrees);
    ``radius_ratio_mean``: mean of 2 r_in / r_circ (1 = equilateral, 0 = degenerate);
    ``obtuse_fraction``: fraction of faces with an angle > 90 degrees;
    ``min_angle_hist``: JSON counts of per-face minimum angles in 5-degree bins over [0, 60].
    """
    if len(F) >= COMPILED_FROM:
        from ._quality_kernel import face_quality
        fmin, fmax, rr = face_quality(np.ascontiguousarray(V, dtype=np.float64),
                                      np.ascontiguousarray(F, dtype=np.int64))
    else:
        fmin, fmax, rr = _face_quality(V, F)
    hist, _ = np.histogram(fmin, bins=HIST_EDGES)
    return {"min_angle": float(fmin.min()), "max_angle": float(fmax.max()),
            "radius_ratio_mean": float(rr.mean()), "obtuse_fraction": float((fmax > 90.0 + 1e-9).mean()),
            "min_angle_hist": json.dumps(hist.tolist())}


def _face_quality(V: np.ndarray, F: np.ndarray):
    """Per face: smallest and largest angle (degrees) and ``2 r_in / r_circ`` (numpy; the
    compiled `_quality_kernel.face_quality` computes the same)."""
    ang = corner_angles(V, F)
    l = edge_lengths(V, F)
    a, b, c = l[:, 0], l[:, 1], l[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        # 2 r_in / R = 8 (s-a)(s-b)(s-c) / (abc), s the semi-perimeter
        s = (a + b + c) / 2
        rr = np.where(a * b * c > 0, 8 * (s - a) * (s - b) * (s - c) / (a * b * c), 0.0)
    rr = np.clip(np.nan_to_num(rr), 0.0, 1.0)
    return ang.min(1), ang.max(1), rr


def warm() -> None:
    """Load (or compile) the compiled pass and the Hausdorff bounds once, e.g. in a driver before
    it forks case processes (the measuring code of the tasks with an output mesh)."""
    from ._quality_kernel import face_quality, face_terms
    from .hausdorff import warm as warm_hausdorff
    face_quality(np.eye(3), np.array([[0, 1, 2]], dtype=np.int64))
    face_terms(np.eye(3), np.array([[0, 1, 2]], dtype=np.int64), np.zeros(3), np.eye(3)[:1])
    warm_hausdorff()
