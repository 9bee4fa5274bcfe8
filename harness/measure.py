"""Turn a method's output into the contract's task columns.

Lengths are divided by the clean mesh's bounding-box diagonal; angles are in degrees.
"""
from __future__ import annotations

import numpy as np

from .mesh import topology
from .metrics.hausdorff import hausdorff
from .metrics.laplacian_properties import laplacian_properties
from .metrics.normal_error import normal_error
from .metrics.surface_distance import surface_distance
from .metrics.triangle_quality import triangle_quality
from .metrics.vertex_error import vertex_error
from .metrics.volume_area import area, volume

LAPLACIAN_COLUMNS = ["sym_error", "loc_violations", "lin_error", "neg_weights", "min_eig", "psd", "nnz",
                     "SYM", "LOC", "LIN", "POS", "operator_symmetric"]
SMOOTHING_COLUMNS = ["ev_mean", "ev_rms", "dist_mean", "ev_sun", "hausdorff", "normal_error_deg",
                     "normal_error_rms_deg", "volume_ratio", "area_ratio", "min_angle", "max_angle",
                     "radius_ratio_mean", "obtuse_fraction", "diverged", "input_ev_mean",
                     "input_dist_mean", "input_normal_error_deg", "min_angle_hist"]
SIMPLIFICATION_COLUMNS = ["target_faces", "out_faces", "hausdorff", "dist_mean", "manifold",
                          "topology_changed", "genus_change", "boundary_loops_change", "min_angle",
                          "radius_ratio_mean", "obtuse_fraction", "min_angle_hist"]
TASK_COLUMNS = {"laplacian": LAPLACIAN_COLUMNS, "smoothing": SMOOTHING_COLUMNS,
                "simplification": SIMPLIFICATION_COLUMNS}


def measure_laplacian(result, V, F) -> dict:
    """Wardetzky et al. 2007 properties of ``result.W`` (see metrics.laplacian_properties)."""
    return laplacian_properties(result.W, result.M, V, F)


def diverged(V_out: np.ndarray, V_in: np.ndarray) -> bool:
    """True when coordinates are non-finite or leave 100x the input bounding box (about its centre)."""
    if not np.isfinite(V_out).all():
        return True
    lo, hi = V_in.min(0), V_in.max(0)
    c, half = (lo + hi) / 2, np.maximum((hi - lo) / 2, 1e-300)
    return bool((np.abs(V_out - c) > 100 * half).any())


def measure_smoothing(V_out, V_noisy, V_clean, F, closed: bool, diag: float, n_samples: int) -> dict:
    """Accuracy of smoothed positions against the clean mesh (same vertices and faces)."""
    row = {"input_ev_mean": vertex_error(V_noisy, V_clean)["ev_mean"] / diag,
           "input_dist_mean": surface_distance(V_noisy, F, V_clean, F)["dist_mean"] / diag,
           "input_normal_error_deg": normal_error(V_noisy, V_clean, F)["normal_error_deg"]}
    row["diverged"] = diverged(V_out, V_noisy)
    if row["diverged"]:
        return row
    ve = vertex_error(V_out, V_clean)
    sd = surface_distance(V_out, F, V_clean, F)
    hd = hausdorff(V_out, F, V_clean, F, n_samples=n_samples)
    row.update({"ev_mean": ve["ev_mean"] / diag, "ev_rms": ve["ev_rms"] / diag,
                "dist_mean": sd["dist_mean"] / diag, "ev_sun": sd["ev_sun"] / diag,
                "hausdorff": hd["hausdorff"] / diag})
    row.update(normal_error(V_out, V_clean, F))
    a0 = area(V_clean, F)
    row["area_ratio"] = area(V_out, F) / a0 if a0 > 0 else None
    if closed:
        v0 = volume(V_clean, F)
        row["volume_ratio"] = volume(V_out, F) / v0 if v0 != 0 else None
    row.update(triangle_quality(V_out, F))
    return row


def measure_simplification(V_out, F_out, V_in, F_in, target_faces: int, diag: float,
                           n_samples: int, topo_in: dict | None = None) -> dict:
    """Output size, symmetric Hausdorff to the input surface, manifoldness and topology change."""
    topo_in = topo_in or topology(V_in, F_in)
    row = {"target_faces": int(target_faces), "out_faces": int(len(F_out))}
    if len(F_out) == 0:
        row.update({"manifold": False, "topology_changed": True})
        return row
    hd = hausdorff(V_out, F_out, V_in, F_in, n_samples=n_samples)
    topo = topology(V_out, F_out)
    row.update({"hausdorff": hd["hausdorff"] / diag, "dist_mean": hd["dist_mean"] / diag,
                "manifold": topo["manifold"],
                "genus_change": topo["genus"] - topo_in["genus"],
                "boundary_loops_change": topo["boundary_loops"] - topo_in["boundary_loops"]})
    row["topology_changed"] = bool(row["genus_change"] != 0 or row["boundary_loops_change"] != 0)
    q = triangle_quality(V_out, F_out)
    row.update({k: q[k] for k in ("min_angle", "radius_ratio_mean", "obtuse_fraction", "min_angle_hist")})
    return row
