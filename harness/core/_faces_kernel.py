"""Compiled per-face screens (`harness.core.geometry.zero_area_faces` on large meshes)."""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def near_degenerate(V, F, rel):
    """Indices of the faces whose cross-product norm ``|(v1 - v0) x (v2 - v0)|`` is at most
    ``rel`` times their longest squared edge length L^2, or is not a number, or whose L^2 lies
    outside [1e-100, 1e100] (where squares of squares under- or overflow): a superset of the
    faces of zero area by any floating-point measure when ``rel`` is far above the rounding
    error of these quantities (~1e-15)."""
    m = F.shape[0]
    out = np.empty(m, np.int64)
    k = 0
    for f in range(m):
        i0, i1, i2 = F[f, 0], F[f, 1], F[f, 2]
        ax = V[i1, 0] - V[i0, 0]
        ay = V[i1, 1] - V[i0, 1]
        az = V[i1, 2] - V[i0, 2]
        bx = V[i2, 0] - V[i0, 0]
        by = V[i2, 1] - V[i0, 1]
        bz = V[i2, 2] - V[i0, 2]
        cx = ay * bz - az * by
        cy = az * bx - ax * bz
        cz = ax * by - ay * bx
        c2 = cx * cx + cy * cy + cz * cz
        dx = bx - ax
        dy = by - ay
        dz = bz - az
        l2 = max(ax * ax + ay * ay + az * az, bx * bx + by * by + bz * bz, dx * dx + dy * dy + dz * dz)
        if not (c2 > rel * rel * l2 * l2) or not (1e-100 <= l2 <= 1e100):
            out[k] = f
            k += 1
    return out[:k].copy()
