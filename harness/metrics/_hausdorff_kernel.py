"""Compiled per-triangle upper bounds of the certified Hausdorff distance (`harness.metrics.hausdorff`)."""
from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def _seg(px, py, pz, ax, ay, az, bx, by, bz):
    ux, uy, uz = bx - ax, by - ay, bz - az
    den = ux * ux + uy * uy + uz * uz
    t = 0.0
    if den > 0.0:
        t = ((px - ax) * ux + (py - ay) * uy + (pz - az) * uz) / den
        t = min(max(t, 0.0), 1.0)
    dx, dy, dz = px - (ax + t * ux), py - (ay + t * uy), pz - (az + t * uz)
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@njit(cache=True)
def point_triangle(px, py, pz, A, B, C):
    """Exact distance from a point to the closed triangle (A, B, C): the nearest edge, or the
    plane when the point projects inside."""
    d = min(_seg(px, py, pz, A[0], A[1], A[2], B[0], B[1], B[2]),
            _seg(px, py, pz, B[0], B[1], B[2], C[0], C[1], C[2]),
            _seg(px, py, pz, C[0], C[1], C[2], A[0], A[1], A[2]))
    e1x, e1y, e1z = B[0] - A[0], B[1] - A[1], B[2] - A[2]
    e2x, e2y, e2z = C[0] - A[0], C[1] - A[1], C[2] - A[2]
    nx, ny, nz = e1y * e2z - e1z * e2y, e1z * e2x - e1x * e2z, e1x * e2y - e1y * e2x
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    if nn == 0.0:
        return d
    inside = True
    for (ox, oy, oz, qx, qy, qz) in ((A[0], A[1], A[2], B[0], B[1], B[2]), (B[0], B[1], B[2], C[0], C[1], C[2]),
                                     (C[0], C[1], C[2], A[0], A[1], A[2])):
        ex, ey, ez = qx - ox, qy - oy, qz - oz
        wx, wy, wz = px - ox, py - oy, pz - oz
        cx, cy, cz = ey * wz - ez * wy, ez * wx - ex * wz, ex * wy - ey * wx
        if cx * nx + cy * ny + cz * nz < 0.0:
            inside = False
    if inside:
        d = min(d, abs((px - A[0]) * nx + (py - A[1]) * ny + (pz - A[2]) * nz) / nn)
    return d


@njit(cache=True)
def _worst_corner(P, k, VY, FY, t):
    T = FY[t]
    w = 0.0
    for i in range(3):
        w = max(w, point_triangle(P[k, i, 0], P[k, i, 1], P[k, i, 2], VY[T[0]], VY[T[1]], VY[T[2]]))
    return w


@njit(cache=True)
def corner_bounds(P, D, I, VY, FY, thr):
    """Upper bound (k,) of max over each triangle ``P[k]`` of the distance to surface (VY, FY),
    from its corners only (no query): the Lipschitz bound ``max(D) + rho`` (``rho`` = the
    largest distance from a point of the triangle to its nearest corner: the circumradius of an
    acute triangle, at most ``longest edge / sqrt(2)`` otherwise) and ``D_i + (farthest corner
    from i)``, then, while above ``thr``, the convexity bound ``max_i d(p_i, t)`` for the face
    ``t`` closest to each corner (``I``)."""
    n = P.shape[0]
    ub = np.empty(n)
    for k in range(n):
        a2 = 0.0
        b2 = 0.0
        c2 = 0.0
        for d in range(3):
            a2 += (P[k, 1, d] - P[k, 2, d]) ** 2     # opposite corner 0
            b2 += (P[k, 2, d] - P[k, 0, d]) ** 2     # opposite corner 1
            c2 += (P[k, 0, d] - P[k, 1, d]) ** 2     # opposite corner 2
        a, b, c = math.sqrt(a2), math.sqrt(b2), math.sqrt(c2)
        longest2 = max(a2, b2, c2)
        acute = 2.0 * longest2 < a2 + b2 + c2
        s = 0.5 * (a + b + c)
        area2 = s * (s - a) * (s - b) * (s - c)
        if acute and area2 > 0.0:
            rho = min(a * b * c / (4.0 * math.sqrt(area2)), math.sqrt(longest2 / 2.0))
        else:
            rho = math.sqrt(longest2 / 2.0)
        dmax = max(D[k, 0], D[k, 1], D[k, 2])
        u = dmax + rho
        u = min(u, D[k, 0] + max(c, b), D[k, 1] + max(c, a), D[k, 2] + max(a, b))
        for j in range(3):
            if u <= thr:
                break
            u = min(u, _worst_corner(P, k, VY, FY, I[k, j]))
        ub[k] = max(u, dmax)
    return ub


@njit(cache=True)
def centroid_bounds(P, c, dc, ic, VY, FY):
    """Upper bound (k,): ``d(c) + max_i |p_i - c|`` (Lipschitz from the centroid) and the
    convexity bound with the face closest to the centroid."""
    n = P.shape[0]
    ub = np.empty(n)
    for k in range(n):
        r = 0.0
        for i in range(3):
            r = max(r, math.sqrt((P[k, i, 0] - c[k, 0]) ** 2 + (P[k, i, 1] - c[k, 1]) ** 2
                                 + (P[k, i, 2] - c[k, 2]) ** 2))
        ub[k] = min(dc[k] + r, _worst_corner(P, k, VY, FY, ic[k]))
    return ub
