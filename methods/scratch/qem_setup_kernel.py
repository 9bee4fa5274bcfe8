"""Compiled set-up of `scratch.qem` (numba, ``cache=True``): vertex quadrics in one pass over
the faces and a stable counting sort of faces by their smallest vertex."""
from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def vertex_quadrics(V, F, n):
    """``Q`` (n, 10): the sum over the faces at each vertex of the area-weighted plane quadric
    ``A [n n^T, d n; d n^T, d^2]`` (coefficients ``a11 a12 a13 a22 a23 a33 b1 b2 b3 c``); faces
    of zero area add nothing (see `methods.scratch.qem.face_quadrics`)."""
    Q = np.zeros((n, 10))
    g = np.empty(4)
    q = np.empty(10)
    for f in range(F.shape[0]):
        a, b, c = F[f, 0], F[f, 1], F[f, 2]
        e1x, e1y, e1z = V[b, 0] - V[a, 0], V[b, 1] - V[a, 1], V[b, 2] - V[a, 2]
        e2x, e2y, e2z = V[c, 0] - V[a, 0], V[c, 1] - V[a, 1], V[c, 2] - V[a, 2]
        nx, ny, nz = e1y * e2z - e1z * e2y, e1z * e2x - e1x * e2z, e1x * e2y - e1y * e2x
        dbl = math.sqrt(nx * nx + ny * ny + nz * nz)
        if not dbl > 0.0:
            continue
        g[0], g[1], g[2] = nx / dbl, ny / dbl, nz / dbl
        g[3] = -(g[0] * V[a, 0] + g[1] * V[a, 1] + g[2] * V[a, 2])
        w = 0.5 * dbl
        q[0], q[1], q[2] = w * g[0] * g[0], w * g[0] * g[1], w * g[0] * g[2]
        q[3], q[4], q[5] = w * g[1] * g[1], w * g[1] * g[2], w * g[2] * g[2]
        q[6], q[7], q[8], q[9] = w * g[0] * g[3], w * g[1] * g[3], w * g[2] * g[3], w * g[3] * g[3]
        for j in range(10):
            Q[a, j] += q[j]
            Q[b, j] += q[j]
            Q[c, j] += q[j]
    return Q


@njit(cache=True)
def faces_by_min_vertex(F, n):
    """Stable counting sort of the rows of ``F`` by their smallest entry (values in [0, n))."""
    m = F.shape[0]
    start = np.zeros(n + 1, np.int64)
    for f in range(m):
        start[min(F[f, 0], F[f, 1], F[f, 2]) + 1] += 1
    for i in range(n):
        start[i + 1] += start[i]
    out = np.empty_like(F)
    for f in range(m):
        k = min(F[f, 0], F[f, 1], F[f, 2])
        p = start[k]
        start[k] += 1
        out[p, 0], out[p, 1], out[p, 2] = F[f, 0], F[f, 1], F[f, 2]
    return out
