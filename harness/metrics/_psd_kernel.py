"""Compiled lower bound on the smallest eigenvalue of a symmetric matrix ``S`` on a triangle mesh,
by splitting ``S`` into per-triangle Laplacians (`harness.metrics.laplacian_properties`).

Write ``c_ij = -S_ij`` for the off-diagonal entries and ``d_i = S_ii``. Every split of the weight
``c_e`` of a mesh edge ``e`` among its triangles, ``c_e = sum_{f owns e} p_{f,e} + r_e``, gives

    S = sum_f L_f + L(r) + R + diag(e),

``L_f`` the 3x3 Laplacian of triangle ``f`` with edge weights ``p_f = (a, b, c)``, ``L(r)`` the
graph Laplacian of the residuals ``r``, ``R`` the off-diagonal entries of ``S`` between vertices
that share no edge of a triangle, ``e_i = d_i - sum_{mesh edges ij} c_ij``. Then

- ``L_f`` has eigenvalues 0 and ``t -+ sqrt(t^2 - 3q)``, ``t = a + b + c``, ``q = ab + bc + ca``:
  it is positive semi-definite iff ``t >= 0`` and ``q >= 0``, and ``L_f >= -neg_f I`` on its three
  vertices with ``neg_f = max(0, sqrt(t^2 - 3q) - t)``;
- ``L(r) >= -2 diag(sum_{e at i} |r_e|)`` (from ``(x_i - x_j)^2 <= 2 x_i^2 + 2 x_j^2``);
- ``R >= -diag(sum_j |R_ij|)`` and ``diag(e) >= -diag(max(0, -e_i))``;

so ``lambda_min(S) >= -max_i sigma_i`` with ``sigma_i`` the sum of those per-vertex terms. Rounding
of every computed quantity (``t``, ``q``, ``r``, ``e``) is bounded with ``u = 2^-53`` and added to
``sigma``, so the bound holds for the exact eigenvalue. The split is free; the one used is the
geometric one, which makes every ``L_f`` exactly semi-definite for a cotangent Laplacian (a
triangle's half cotangents satisfy ``q = 1/4``): ``p_{f,e} = s g_{f,e} + (c_e - s G_e) / k_e`` with
``g_{f,e}`` half the cotangent of the angle of ``f`` opposite ``e`` (0 on a zero-area triangle),
``G_e`` their sum over the ``k_e`` triangles of ``e`` and ``s`` the least-squares scale of ``c``
on ``G``. An edge with no stored entry in ``S`` (weight 0) gets ``p = 0``.
"""
from __future__ import annotations

import numpy as np
from numba import njit

U = 2.0 ** -53


@njit(cache=True, inline="always")
def _find(indptr, indices, i, j):
    lo, hi = indptr[i], indptr[i + 1]
    while lo < hi:
        mid = (lo + hi) // 2
        if indices[mid] < j:
            lo = mid + 1
        else:
            hi = mid
    if lo < indptr[i + 1] and indices[lo] == j:
        return lo
    return -1


@njit(cache=True, inline="always")
def _half_cot(V, o, a, b):
    """Half the cotangent of the angle at vertex o of triangle (o, a, b); 0 when undefined."""
    x0, x1, x2 = V[a, 0] - V[o, 0], V[a, 1] - V[o, 1], V[a, 2] - V[o, 2]
    y0, y1, y2 = V[b, 0] - V[o, 0], V[b, 1] - V[o, 1], V[b, 2] - V[o, 2]
    c0, c1, c2 = x1 * y2 - x2 * y1, x2 * y0 - x0 * y2, x0 * y1 - x1 * y0
    cr = np.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
    if not cr > 0.0:
        return 0.0
    g = 0.5 * (x0 * y0 + x1 * y1 + x2 * y2) / cr
    return g if np.isfinite(g) else 0.0


@njit(cache=True, inline="always")
def _neg_part(a, b, c):
    """An upper bound of ``max(0, -lambda_min)`` of the triangle Laplacian with weights a, b, c,
    rounding of ``t`` and ``q`` included."""
    t = a + b + c
    q = a * b + b * c + c * a
    et = 3.0 * U * (abs(a) + abs(b) + abs(c))
    eq = 5.0 * U * (abs(a * b) + abs(b * c) + abs(c * a)) + 1e-300
    tlo, qlo = t - et, q - eq
    if not (np.isfinite(tlo) and np.isfinite(qlo)):
        return np.inf                      # overflow: nothing is proved
    if tlo >= 0.0 and qlo >= 0.0:
        return 0.0
    disc = tlo * tlo - 3.0 * qlo
    if disc < 0.0:
        disc = 0.0
    if tlo >= 0.0:                         # qlo < 0: 3|q| / (t + sqrt(t^2 - 3q)), no cancellation
        neg = -3.0 * qlo / (tlo + np.sqrt(disc))
    else:
        neg = np.sqrt(disc) - tlo
    neg *= 1.0 + 16.0 * U
    return neg if neg >= 0.0 else np.inf   # NaN: nothing is proved


@njit(cache=True)
def face_split_bound(indptr, indices, data, V, F):
    """``(sigma, rowsum)`` for the symmetric ``S`` in CSR (sorted column indices) on the mesh
    ``(V, F)`` (indices in range): ``lambda_min(S) >= -max(sigma)`` (module docstring), and
    ``rowsum`` (n,) the computed ``S 1``. Scale ``S`` so that its largest diagonal entry is
    about 1 (by a power of two, exactly): products of weights must neither overflow nor reach
    the absolute floor of the rounding bounds; an overflow makes ``sigma`` infinite."""
    n = indptr.shape[0] - 1
    m = F.shape[0]
    nnz = data.shape[0]
    G = np.zeros(nnz)
    k = np.zeros(nnz, np.int64)
    pos = np.full((m, 3), -1, np.int64)
    g = np.zeros((m, 3))
    for f in range(m):
        v0, v1, v2 = F[f, 0], F[f, 1], F[f, 2]
        if v0 == v1 or v1 == v2 or v2 == v0:
            continue
        for c in range(3):
            o, x, y = F[f, c], F[f, (c + 1) % 3], F[f, (c + 2) % 3]
            p = _find(indptr, indices, min(x, y), max(x, y))
            pos[f, c] = p
            if p >= 0:
                g[f, c] = _half_cot(V, o, x, y)
                G[p] += g[f, c]
                k[p] += 1
    num = 0.0
    den = 0.0
    for p in range(nnz):
        if k[p] > 0:
            num += -data[p] * G[p]
            den += G[p] * G[p]
    s = num / den if den > 0.0 else 0.0
    P = np.zeros(nnz)
    Pabs = np.zeros(nnz)
    sigma = np.zeros(n)
    for f in range(m):
        p0, p1, p2 = pos[f, 0], pos[f, 1], pos[f, 2]
        w0 = s * g[f, 0] + (-data[p0] - s * G[p0]) / k[p0] if p0 >= 0 else 0.0
        w1 = s * g[f, 1] + (-data[p1] - s * G[p1]) / k[p1] if p1 >= 0 else 0.0
        w2 = s * g[f, 2] + (-data[p2] - s * G[p2]) / k[p2] if p2 >= 0 else 0.0
        if p0 >= 0:
            P[p0] += w0
            Pabs[p0] += abs(w0)
        if p1 >= 0:
            P[p1] += w1
            Pabs[p1] += abs(w1)
        if p2 >= 0:
            P[p2] += w2
            Pabs[p2] += abs(w2)
        neg = _neg_part(w0, w1, w2)
        if not neg <= 0.0:                 # NaN or inf counts against the certificate
            sigma[F[f, 0]] += neg
            sigma[F[f, 1]] += neg
            sigma[F[f, 2]] += neg
    diag = np.zeros(n)
    csum = np.zeros(n)          # sum of c over the mesh edges of each row
    cabs = np.zeros(n)
    osum = np.zeros(n)          # sum of c over every off-diagonal entry of each row
    deg = np.zeros(n)
    for i in range(n):
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            if j == i:
                diag[i] += data[p]
                continue
            cij = -data[p]
            osum[i] += cij
            cabs[i] += abs(cij)
            deg[i] += 1.0
            if j < i:
                continue
            if k[p] > 0:            # a mesh edge: residual of its split, both ends
                r = abs(cij - P[p]) + 4.0 * U * (abs(cij) + Pabs[p]) * (k[p] + 1)
                sigma[i] += 2.0 * r
                sigma[j] += 2.0 * r
                csum[i] += cij
                csum[j] += cij
            else:                   # no triangle owns it: R
                sigma[i] += abs(cij)
                sigma[j] += abs(cij)
    rowsum = np.empty(n)
    for i in range(n):
        e = diag[i] - csum[i]
        err = (deg[i] + 2.0) * U * (abs(diag[i]) + cabs[i])
        if e < 0.0:
            sigma[i] += -e
        sigma[i] += err
        rowsum[i] = diag[i] - osum[i]
    return sigma, rowsum


def warm() -> None:
    """Load (or compile) the kernel once, e.g. in a driver before it forks."""
    F = np.array([[0, 1, 2]], dtype=np.int64)
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    indptr = np.array([0, 3, 6, 9], dtype=np.int64)
    indices = np.array([0, 1, 2, 0, 1, 2, 0, 1, 2], dtype=np.int64)
    data = np.array([2.0, -1, -1, -1, 2, -1, -1, -1, 2])
    face_split_bound(indptr, indices, data, V, F)
