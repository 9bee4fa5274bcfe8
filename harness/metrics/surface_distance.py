"""Exact point-to-surface distance (closest point on any triangle, libigl's AABB tree)."""
import numpy as np

from ..core.geometry import double_areas


def point_surface_distance(P: np.ndarray, V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Unsigned distance (k,) from each point of ``P`` (k, 3) to the triangle mesh (V, F)."""
    import igl
    d2, _, _ = igl.point_mesh_squared_distance(np.ascontiguousarray(P, dtype=np.float64),
                                               np.ascontiguousarray(V, dtype=np.float64),
                                               np.ascontiguousarray(F, dtype=np.int64))
    return np.sqrt(np.maximum(np.asarray(d2).ravel(), 0.0))


def surface_distance(V: np.ndarray, F: np.ndarray, V_clean: np.ndarray, F_clean: np.ndarray) -> dict:
    """Distances of the result's vertices to the clean surface.

    ``dist_mean`` = mean_i d(v_i, S_clean). ``ev_sun`` (Sun et al. 2007) =
    sqrt( sum_i A_i d(v_i, S_clean)^2 / sum_i A_i ), A_i the barycentric area of vertex i on
    the result mesh (one third of its incident faces' areas).
    """
    d = point_surface_distance(V, V_clean, F_clean)
    dbl = double_areas(V, F)
    A = np.bincount(F.ravel(), weights=np.repeat(dbl / 6.0, 3), minlength=len(V))
    tot = A.sum()
    ev_sun = float(np.sqrt((A * d ** 2).sum() / tot)) if tot > 0 else float("nan")
    return {"dist_mean": float(d.mean()), "ev_sun": ev_sun}
