"""Angle between each face normal of the result and of the clean mesh (same faces)."""
import numpy as np

from harness.core.geometry import cross_rows, face_normals


def normal_error(V: np.ndarray, V_clean: np.ndarray, F: np.ndarray) -> dict:
    """``normal_error_deg`` = mean_f angle(n_f, n_f^clean), ``normal_error_rms_deg`` = RMS of it.

    Angles via atan2(|n x m|, n . m), accurate near 0 and 180 degrees. A face that is degenerate
    in the clean mesh (zero normal) has no reference angle and is left out of the mean; one
    that collapsed in the result only counts as 90 degrees (its normal is undefined).
    """
    N, C = face_normals(V, F), face_normals(V_clean, F)
    ang = np.degrees(np.arctan2(np.linalg.norm(cross_rows(N, C), axis=1), (N * C).sum(1)))
    ang[np.linalg.norm(N, axis=1) == 0] = 90.0
    ang[np.linalg.norm(C, axis=1) == 0] = np.nan
    return angle_summary(ang)


def angle_summary(ang: np.ndarray) -> dict:
    """``normal_error_deg`` and ``normal_error_rms_deg`` of the per-face angles ``ang`` (m,)
    (degrees; e.g. `harness.metrics._quality_kernel.face_terms`), over the faces that have one
    (NaN: no reference normal); NaN when none has."""
    ang = ang[~np.isnan(ang)]
    if not len(ang):
        return {"normal_error_deg": float("nan"), "normal_error_rms_deg": float("nan")}
    return {"normal_error_deg": float(ang.mean()), "normal_error_rms_deg": float(np.sqrt((ang ** 2).mean()))}
