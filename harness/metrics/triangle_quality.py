"""Triangle quality: angles, radius ratio, obtuse fraction, min-angle histogram."""
import json

import numpy as np

from ..core.geometry import corner_angles, edge_lengths

HIST_EDGES = np.arange(0, 65, 5.0)       # min angle of a triangle is at most 60 degrees


def triangle_quality(V: np.ndarray, F: np.ndarray) -> dict:
    """``min_angle``/``max_angle``: smallest/largest interior angle over all faces (degrees);
    ``radius_ratio_mean``: mean of 2 r_in / r_circ (1 = equilateral, 0 = degenerate);
    ``obtuse_fraction``: fraction of faces with an angle > 90 degrees;
    ``min_angle_hist``: JSON counts of per-face minimum angles in 5-degree bins over [0, 60].
    """
    ang = corner_angles(V, F)
    l = edge_lengths(V, F)
    a, b, c = l[:, 0], l[:, 1], l[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        # 2 r_in / R = 8 (s-a)(s-b)(s-c) / (abc), s the semi-perimeter
        s = (a + b + c) / 2
        rr = np.where(a * b * c > 0, 8 * (s - a) * (s - b) * (s - c) / (a * b * c), 0.0)
    rr = np.clip(np.nan_to_num(rr), 0.0, 1.0)
    fmin = ang.min(1)
    hist, _ = np.histogram(fmin, bins=HIST_EDGES)
    return {"min_angle": float(fmin.min()), "max_angle": float(ang.max()),
            "radius_ratio_mean": float(rr.mean()), "obtuse_fraction": float((ang.max(1) > 90.0 + 1e-9).mean()),
            "min_angle_hist": json.dumps(hist.tolist())}
