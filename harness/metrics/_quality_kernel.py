"""Compiled per-face passes of the metrics: angles and radius ratio (`harness.metrics.triangle_quality`
on large meshes) and the smoothing task's normals, areas, volume terms and normal angles."""
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


@njit(cache=True)
def face_terms(V, F, o, C):
    """One pass over the faces (normals and double areas equal the numpy definitions bit for bit;
    volume terms and angles to the last bit: numpy sums the products in another order):

    - ``N`` (m, 3): unit normals ``X / |X|``, ``X = (v1 - v0) x (v2 - v0)`` (zero rows where
      ``|X| = 0``; `harness.core.geometry.face_normals`);
    - ``dbl`` (m,): ``|X|``, twice the area;
    - ``vol`` (m,): ``(v0 - o) . ((v1 - o) x (v2 - o))``, six times the signed volume of the
      tetrahedron on the face and ``o`` (`harness.core.geometry.volume` of ``V - o`` sums them / 6);
    - ``ang`` (m,) when ``C`` (m, 3) holds reference unit normals (else empty): the angle in
      degrees ``atan2(|N x C|, N . C)``; NaN where the reference normal is zero (no angle to
      measure), else 90 where this face's is (`harness.metrics.normal_error`)."""
    m = F.shape[0]
    N = np.empty((m, 3))
    dbl = np.empty(m)
    vol = np.empty(m)
    want = C.shape[0] == m
    ang = np.empty(m if want else 0)
    deg = 180.0 / math.pi
    for f in range(m):
        i0, i1, i2 = F[f, 0], F[f, 1], F[f, 2]
        p0x, p0y, p0z = V[i0, 0], V[i0, 1], V[i0, 2]
        ax, ay, az = V[i1, 0] - p0x, V[i1, 1] - p0y, V[i1, 2] - p0z
        bx, by, bz = V[i2, 0] - p0x, V[i2, 1] - p0y, V[i2, 2] - p0z
        x0 = ay * bz - az * by
        x1 = az * bx - ax * bz
        x2 = ax * by - ay * bx
        r = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
        dbl[f] = r
        if r > 0:
            n0, n1, n2 = x0 / r, x1 / r, x2 / r
        else:
            n0, n1, n2 = 0.0, 0.0, 0.0
        N[f, 0], N[f, 1], N[f, 2] = n0, n1, n2
        q0x, q0y, q0z = p0x - o[0], p0y - o[1], p0z - o[2]
        q1x, q1y, q1z = V[i1, 0] - o[0], V[i1, 1] - o[1], V[i1, 2] - o[2]
        q2x, q2y, q2z = V[i2, 0] - o[0], V[i2, 1] - o[1], V[i2, 2] - o[2]
        vol[f] = (q0x * (q1y * q2z - q1z * q2y) + q0y * (q1z * q2x - q1x * q2z)) + q0z * (q1x * q2y - q1y * q2x)
        if want:
            c0, c1, c2 = C[f, 0], C[f, 1], C[f, 2]
            if math.sqrt(c0 * c0 + c1 * c1 + c2 * c2) == 0.0:
                ang[f] = math.nan                     # no reference normal: no angle to measure
            elif r == 0.0:
                ang[f] = 90.0                         # the result's face collapsed: it has no normal
            else:
                y0 = n1 * c2 - n2 * c1
                y1 = n2 * c0 - n0 * c2
                y2 = n0 * c1 - n1 * c0
                ang[f] = math.atan2(math.sqrt(y0 * y0 + y1 * y1 + y2 * y2), (n0 * c0 + n1 * c1) + n2 * c2) * deg
    return N, dbl, vol, ang
