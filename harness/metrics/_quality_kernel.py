"""Compiled per-face angles and radius ratio (`harness.metrics.triangle_quality` on large meshes)."""
from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def face_quality(V, F):
    """Per face (m,) each: smallest and largest interior angle (degrees, ``atan2(|a x b|, a . b)``
    at each corner, as `harness.core.geometry.corner_angles`: 0 at a corner with a zero-length
    edge) and ``2 r_in / r_circ``
    (``8 (s-a)(s-b)(s-c) / (abc)``, clipped to [0, 1]; 0 when an edge has zero length)."""
    m = F.shape[0]
    amin = np.empty(m)
    amax = np.empty(m)
    rr = np.empty(m)
    deg = 180.0 / math.pi
    for f in range(m):
        lo = np.inf
        hi = -np.inf
        nan = False
        for k in range(3):
            i, j, l = F[f, k], F[f, (k + 1) % 3], F[f, (k + 2) % 3]
            ax, ay, az = V[j, 0] - V[i, 0], V[j, 1] - V[i, 1], V[j, 2] - V[i, 2]
            bx, by, bz = V[l, 0] - V[i, 0], V[l, 1] - V[i, 1], V[l, 2] - V[i, 2]
            cx = ay * bz - az * by
            cy = az * bx - ax * bz
            cz = ax * by - ay * bx
            dot = ax * bx + ay * by + az * bz + 0.0        # never -0.0: angle 0 at a zero-length edge
            t = math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), dot) * deg
            nan = nan or t != t
            lo = min(lo, t)
            hi = max(hi, t)
        amin[f] = np.nan if nan else lo            # NaN propagates, as in numpy's min / max
        amax[f] = np.nan if nan else hi
        p0, p1, p2 = F[f, 0], F[f, 1], F[f, 2]
        a = math.sqrt((V[p2, 0] - V[p1, 0]) ** 2 + (V[p2, 1] - V[p1, 1]) ** 2 + (V[p2, 2] - V[p1, 2]) ** 2)
        b = math.sqrt((V[p0, 0] - V[p2, 0]) ** 2 + (V[p0, 1] - V[p2, 1]) ** 2 + (V[p0, 2] - V[p2, 2]) ** 2)
        c = math.sqrt((V[p1, 0] - V[p0, 0]) ** 2 + (V[p1, 1] - V[p0, 1]) ** 2 + (V[p1, 2] - V[p0, 2]) ** 2)
        s = (a + b + c) / 2
        r = 0.0
        if a * b * c > 0:
            r = 8 * (s - a) * (s - b) * (s - c) / (a * b * c)
            if not (r > 0.0):          # also NaN
                r = 0.0
            elif r > 1.0:
                r = 1.0
        rr[f] = r
    return amin, amax, rr
