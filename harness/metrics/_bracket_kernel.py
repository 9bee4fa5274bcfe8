"""Compiled best-first branch and bound of the certified one-sided Hausdorff distance from a
triangle mesh X to a surface Y (`harness.metrics.hausdorff`), over Y's hierarchy
(`_bvh_kernel`).

Every triangle of X gets an upper bound of the distance to Y over it (`roots`, `_upper`:
Lipschitz bounds from its corners' distances, convexity of the distance to one triangle of Y, a
centroid query, the covering bound of `_cover_bound`); `best_first` splits the open triangle of
largest bound into four until every open bound is within ``(1 + eps) max(L, floor) + atol`` of
the lower bound ``L`` (the largest distance found at a point of X).

It compiles `_bvh_kernel`'s and `_cover_bound`'s functions into its own, so its numba cache is
dropped when either file changes (`_kernel_cache.drop_stale_cache`).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from numba import njit

from ._bvh_kernel import _tri_dist2, closest
from ._cover_bound import cover_bound
from ._kernel_cache import drop_stale_cache

drop_stale_cache(Path(__file__), ("_bvh_kernel.py", "_cover_bound.py"))

COVER = 1.5          # the covering bound keeps Y's triangles with b_t up to COVER times the threshold


@njit(cache=True, inline="always")
def _dist_to_face(px, py, pz, VY, FY, f):
    return math.sqrt(_tri_dist2(px, py, pz, VY, FY[f, 0], FY[f, 1], FY[f, 2]))


@njit(cache=True)
def _convex(P, VY, FY, f):
    """max over the corners of P (3, 3) of the distance to face f: an upper bound of the
    distance to the surface over the whole triangle (convexity of the distance to a triangle)."""
    w = 0.0
    for i in range(3):
        w = max(w, _dist_to_face(P[i, 0], P[i, 1], P[i, 2], VY, FY, f))
    return w


@njit(cache=True)
def _upper(P, D, I, VY, FY, NY, B, stack, dstack, thr, state, W, seeds):
    """Upper bound of the distance to the surface over triangle P (3, 3) with corner distances
    D (3,) and closest faces I (3,), the first that settles it (``<= thr``) of: Lipschitz bounds
    from the corners (``max D + rho``, rho the largest distance from a point of the triangle to
    its nearest corner, and ``D_i + farthest corner``); convexity with the corners' closest
    faces; the centroid (one query: Lipschitz and convexity with its closest face; its distance
    raises the lower bound ``state[0]``, ``state[1]`` counts queries); the covering bound
    (`harness.metrics._cover_bound`) over Y's triangles grown from those four faces (``NY``
    its face neighbours, ``W`` its scratch, ``seeds`` (4,) scratch)."""
    a2 = (P[1, 0] - P[2, 0]) ** 2 + (P[1, 1] - P[2, 1]) ** 2 + (P[1, 2] - P[2, 2]) ** 2
    b2 = (P[2, 0] - P[0, 0]) ** 2 + (P[2, 1] - P[0, 1]) ** 2 + (P[2, 2] - P[0, 2]) ** 2
    c2 = (P[0, 0] - P[1, 0]) ** 2 + (P[0, 1] - P[1, 1]) ** 2 + (P[0, 2] - P[1, 2]) ** 2
    a, b, c = math.sqrt(a2), math.sqrt(b2), math.sqrt(c2)
    longest2 = max(a2, b2, c2)
    s = 0.5 * (a + b + c)
    area2 = s * (s - a) * (s - b) * (s - c)
    if 2.0 * longest2 < a2 + b2 + c2 and area2 > 0.0:
        rho = min(a * b * c / (4.0 * math.sqrt(area2)), math.sqrt(longest2 / 2.0))
    else:
        rho = math.sqrt(longest2 / 2.0)
    dmax = max(D[0], D[1], D[2])
    u = min(dmax + rho, D[0] + max(c, b), D[1] + max(c, a), D[2] + max(a, b))
    for j in range(3):
        if u <= thr:
            return max(u, dmax)
        if (j == 1 and I[1] == I[0]) or (j == 2 and (I[2] == I[0] or I[2] == I[1])):
            continue                                 # the same face: the same bound
        u = min(u, _convex(P, VY, FY, I[j]))
    if u <= thr:
        return max(u, dmax)
    seeds[0], seeds[1], seeds[2], seeds[3] = I[0], I[1], I[2], -1
    u = min(u, cover_bound(P, seeds, VY, FY, NY, COVER * thr, W))
    if u <= thr:
        return max(u, dmax)
    cx = (P[0, 0] + P[1, 0] + P[2, 0]) / 3.0
    cy = (P[0, 1] + P[1, 1] + P[2, 1]) / 3.0
    cz = (P[0, 2] + P[1, 2] + P[2, 2]) / 3.0
    d2, fc = closest(cx, cy, cz, VY, FY, B, I[0], stack, dstack)
    dc = math.sqrt(d2)
    state[1] += 1.0
    if dc > state[0]:
        state[0] = dc
    r = 0.0
    for i in range(3):
        r = max(r, math.sqrt((P[i, 0] - cx) ** 2 + (P[i, 1] - cy) ** 2 + (P[i, 2] - cz) ** 2))
    u = min(u, dc + r, _convex(P, VY, FY, fc))
    return max(u, dmax)


@njit(cache=True, inline="always")
def _closing(state, eps, atol):
    """The bound below which a (sub-)triangle closes: ``(1 + eps) max(L, floor) + atol``."""
    return (1.0 + eps) * max(state[0], state[8]) + atol


@njit(cache=True)
def roots(VX, FX, dV, iV, VY, FY, B, NY, W, eps, atol, state, cap):
    """Upper bound (m,) of every triangle of X (`_upper`, and ``cap[f]``, a bound known a
    priori: when it already closes the triangle no query is made); raises the lower bound
    state[0]; a triangle closes at ``(1 + eps) max(state[0], state[8]) + atol`` (`best_first`)."""
    m = FX.shape[0]
    ub = np.empty(m)
    P = np.empty((3, 3))
    D = np.empty(3)
    I = np.empty(3, np.int64)
    stack = np.empty(256, np.int64)
    dstack = np.empty(256)
    seeds = np.empty(4, np.int64)
    for f in range(m):
        for i in range(3):
            v = FX[f, i]
            P[i, 0], P[i, 1], P[i, 2] = VX[v, 0], VX[v, 1], VX[v, 2]
            D[i], I[i] = dV[v], iV[v]
        thr = _closing(state, eps, atol)
        if cap[f] <= thr:
            ub[f] = max(cap[f], D[0], D[1], D[2])
        else:
            ub[f] = min(_upper(P, D, I, VY, FY, NY, B, stack, dstack, thr, state, W, seeds),
                        max(cap[f], D[0], D[1], D[2]))
    return ub


@njit(cache=True, inline="always")
def _sift_up(H, K, i):
    x, kx = H[i], K[i]
    while i > 0:
        p = (i - 1) >> 1
        if K[p] >= kx:
            break
        H[i], K[i] = H[p], K[p]
        i = p
    H[i], K[i] = x, kx


@njit(cache=True, inline="always")
def _sift_down(H, K, n, i):
    x, kx = H[i], K[i]
    while True:
        c = 2 * i + 1
        if c >= n:
            break
        if c + 1 < n and K[c + 1] > K[c]:
            c += 1
        if K[c] <= kx:
            break
        H[i], K[i] = H[c], K[c]
        i = c
    H[i], K[i] = x, kx


@njit(cache=True)
def best_first(tris, ub0, VX, FX, dV, iV, VY, FY, B, NY, W, eps, atol,
               max_points, max_pops, store, state):
    """Best-first branch and bound: always split the open sub-triangle with the largest upper
    bound (a max-heap), so the lower bound rises as fast as possible and no sub-triangle is split
    whose bound is below ``(1 + eps) max(L_final, floor) + atol``. ``store`` = (SP, SD, SI, SU, H, free) is
    the open set, carried between calls (``max_pops`` splits per call, so the caller can check a
    clock; ``SU`` holds the heap's keys, aligned with ``H``); ``tris``/``ub0`` (open root
    triangles) are added on the first call (``state[4] == 0``).
    ``state``: [L, queries, settled, open, initialised, heap size, free count, done, floor]
    (``floor``: a lower bound of the distance being certified found elsewhere, e.g. the other
    direction of a symmetric distance; bounds within ``(1 + eps) floor + atol`` close too).
    Returns the (possibly grown) store."""
    SP, SD, SI, SU, H, free = store
    n = int(state[5])
    nfree = int(state[6])
    if state[4] == 0.0:
        state[4] = 1.0
        for t in range(tris.size):
            f = tris[t]
            if n >= SU.size or nfree == 0:
                break
            nfree -= 1
            s = free[nfree]
            for i in range(3):
                v = FX[f, i]
                SP[s, i, 0], SP[s, i, 1], SP[s, i, 2] = VX[v, 0], VX[v, 1], VX[v, 2]
                SD[s, i], SI[s, i] = dV[v], iV[v]
            H[n] = s
            SU[n] = ub0[t]
            _sift_up(H, SU, n)
            n += 1
    M = np.empty((3, 3))
    MD = np.empty(3)
    MI = np.empty(3, np.int64)
    CP = np.empty((3, 3))
    CD = np.empty(3)
    CI = np.empty(3, np.int64)
    stack = np.empty(256, np.int64)
    dstack = np.empty(256)
    seeds = np.empty(4, np.int64)
    pops = 0
    while n > 0 and pops < max_pops:
        s = H[0]
        u = SU[0]
        thr = _closing(state, eps, atol)
        if u <= thr:                                 # the largest open bound is closed: done
            state[2] = max(state[2], u)
            break
        if state[1] + 7.0 > max_points:
            break
        if nfree < 3:                                # grow the store
            cap = SU.size
            SP2 = np.empty((2 * cap, 3, 3))
            SD2 = np.empty((2 * cap, 3))
            SI2 = np.empty((2 * cap, 3), np.int64)
            SU2 = np.empty(2 * cap)
            H2 = np.empty(2 * cap, np.int64)
            F2 = np.empty(2 * cap, np.int64)
            SP2[:cap], SD2[:cap], SI2[:cap], SU2[:n], H2[:n] = SP, SD, SI, SU[:n], H[:n]
            F2[:nfree] = free[:nfree]
            for k in range(cap, 2 * cap):
                F2[nfree] = k
                nfree += 1
            SP, SD, SI, SU, H, free = SP2, SD2, SI2, SU2, H2, F2
        pops += 1
        n -= 1                                       # pop the top
        H[0], SU[0] = H[n], SU[n]
        if n > 0:
            _sift_down(H, SU, n, 0)
        P = SP[s]
        for e in range(3):                           # midpoint of the edge opposite corner e
            i, j = (e + 1) % 3, (e + 2) % 3
            mx = 0.5 * (P[i, 0] + P[j, 0])
            my = 0.5 * (P[i, 1] + P[j, 1])
            mz = 0.5 * (P[i, 2] + P[j, 2])
            hint = SI[s, i] if SD[s, i] <= SD[s, j] else SI[s, j]
            d2, fm = closest(mx, my, mz, VY, FY, B, hint, stack, dstack)
            M[e, 0], M[e, 1], M[e, 2] = mx, my, mz
            MD[e] = math.sqrt(d2)
            MI[e] = fm
            state[1] += 1.0
            if MD[e] > state[0]:
                state[0] = MD[e]
        thr = _closing(state, eps, atol)
        # children: corner ci with the midpoints of its two edges, then the middle triangle; the
        # parent's slot is reused by the last child
        for q in range(4):
            if q < 3:
                i1, i2 = (q + 1) % 3, (q + 2) % 3
                for d in range(3):
                    CP[0, d], CP[1, d], CP[2, d] = SP[s, q, d], M[i2, d], M[i1, d]
                CD[0], CD[1], CD[2] = SD[s, q], MD[i2], MD[i1]
                CI[0], CI[1], CI[2] = SI[s, q], MI[i2], MI[i1]
            else:
                for d in range(3):
                    CP[0, d], CP[1, d], CP[2, d] = M[0, d], M[1, d], M[2, d]
                CD[0], CD[1], CD[2] = MD[0], MD[1], MD[2]
                CI[0], CI[1], CI[2] = MI[0], MI[1], MI[2]
            cu = _upper(CP, CD, CI, VY, FY, NY, B, stack, dstack, thr, state, W, seeds)
            if cu <= _closing(state, eps, atol):
                state[2] = max(state[2], cu)
                if q == 3:
                    free[nfree] = s
                    nfree += 1
                continue
            if q == 3:
                t = s
            else:
                nfree -= 1
                t = free[nfree]
            for a in range(3):
                SP[t, a, 0], SP[t, a, 1], SP[t, a, 2] = CP[a, 0], CP[a, 1], CP[a, 2]
                SD[t, a], SI[t, a] = CD[a], CI[a]
            H[n] = t
            SU[n] = cu
            _sift_up(H, SU, n)
            n += 1
    state[5] = n
    state[6] = nfree
    state[3] = SU[0] if n > 0 else 0.0
    state[7] = 1.0 if (n == 0 or SU[0] <= _closing(state, eps, atol)) else 0.0
    return SP, SD, SI, SU, H, free
