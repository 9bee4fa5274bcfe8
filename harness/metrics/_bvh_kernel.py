"""Compiled exact point-to-triangle-mesh distance (a bounding-volume hierarchy); the best-first
branch and bound of the certified Hausdorff distance that uses it is `_bracket_kernel`.

BVH: built top-down, each node split at the median centroid along the longest axis of its
centroids' box, down to leaves of at most ``LEAF`` triangles; each node keeps the axis-aligned
box of its triangles (computed bottom-up). A query starts from a hint triangle's distance (the
closest triangle of a nearby point), visits nodes nearest box first and prunes any box farther
than the best distance so far; the distance to a triangle is the exact closest-point distance
(Ericson, Real-Time Collision Detection, 5.1.5). Squared distances throughout; results are
exact up to rounding.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit



LEAF = 4


SLIVER2 = 256.0
"""``(|ab| |ac| / |ab x ac|)^2`` above which `_tri_dist2` measures in double-double arithmetic
(`_tri_dist2_dd`): the angle at the first corner below about 3.6 degrees. Below it, the plane
distance's error is at most about ``(3.5 * 16 + 2) eps |ap|`` (the normal's direction is known to
``3.5 eps |ab||ac| / |ab x ac|``), which `harness.metrics.hausdorff.ROUND` covers."""


@njit(cache=True, inline="always")
def _ts(a, b):
    """Knuth's two-sum: ``s + e == a + b`` exactly."""
    s = a + b
    z = s - a
    return s, (a - (s - z)) + (b - z)


@njit(cache=True, inline="always")
def _tp(a, b):
    """Dekker's two-product: ``p + e == a * b`` exactly for |a|, |b| below about 1e300 (the
    split overflows beyond) and products above about 1e-290 (the correction term is subnormal
    below)."""
    p = a * b
    c = 134217729.0 * a
    ah = c - (c - a)
    al = a - ah
    c = 134217729.0 * b
    bh = c - (c - b)
    bl = b - bh
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


@njit(cache=True, inline="always")
def _dd(h, e):
    s = h + e
    return s, e - (s - h)


@njit(cache=True, inline="always")
def _dmul(xh, xl, yh, yl):
    p, e = _tp(xh, yh)
    return _dd(p, e + (xh * yl + xl * yh))


@njit(cache=True, inline="always")
def _dsub(xh, xl, yh, yl):
    s, e = _ts(xh, -yh)
    return _dd(s, e + (xl - yl))


@njit(cache=True, inline="always")
def _dadd3(ah, al, bh, bl, ch, cl):
    s, e = _ts(ah, bh)
    s, e = _dd(s, e + (al + bl))
    t, f = _ts(s, ch)
    return _dd(t, f + (e + cl))


@njit(cache=True, inline="always")
def _dpdiff(px, py, pz, V, j):
    """``p - V[j]`` exactly, as three double-double pairs."""
    xh, xl = _ts(px, -V[j, 0])
    yh, yl = _ts(py, -V[j, 1])
    zh, zl = _ts(pz, -V[j, 2])
    return xh, xl, yh, yl, zh, zl


@njit(cache=True, inline="always")
def _ddiff(V, i, j):
    """``V[i] - V[j]`` exactly (`_dpdiff` of the point ``V[i]``)."""
    return _dpdiff(V[i, 0], V[i, 1], V[i, 2], V, j)


@njit(cache=True, inline="always")
def _dcross(u, v):
    """``u x v`` of double-double 3-vectors (6-tuples hi, lo per component)."""
    p1h, p1l = _dmul(u[2], u[3], v[4], v[5])
    p2h, p2l = _dmul(u[4], u[5], v[2], v[3])
    xh, xl = _dsub(p1h, p1l, p2h, p2l)
    p1h, p1l = _dmul(u[4], u[5], v[0], v[1])
    p2h, p2l = _dmul(u[0], u[1], v[4], v[5])
    yh, yl = _dsub(p1h, p1l, p2h, p2l)
    p1h, p1l = _dmul(u[0], u[1], v[2], v[3])
    p2h, p2l = _dmul(u[2], u[3], v[0], v[1])
    zh, zl = _dsub(p1h, p1l, p2h, p2l)
    return xh, xl, yh, yl, zh, zl


@njit(cache=True, inline="always")
def _ddot(u, v):
    """``u . v`` of double-double 3-vectors, its high part."""
    p1h, p1l = _dmul(u[0], u[1], v[0], v[1])
    p2h, p2l = _dmul(u[2], u[3], v[2], v[3])
    p3h, p3l = _dmul(u[4], u[5], v[4], v[5])
    return _dadd3(p1h, p1l, p2h, p2l, p3h, p3l)[0]


@njit(cache=True)
def _tri_dist2_dd(px, py, pz, V, a, b, c):
    """`_tri_dist2` of a sliver, in double-double arithmetic: the differences exact, the normal
    ``n = ab x ac``, the side tests ``n . (e x (p - e_0))`` of the three edges and ``ap . n`` to
    about eps^2 relative. p over the inside: ``(ap . n)^2 / |n|^2``; else, or when the corners
    are exactly collinear (``n`` is 0 though the rounded differences' cross product is not), the
    nearest edge."""
    ab, ac, bc = _ddiff(V, b, a), _ddiff(V, c, a), _ddiff(V, c, b)
    ca = _ddiff(V, a, c)
    ap, bp, cp = _dpdiff(px, py, pz, V, a), _dpdiff(px, py, pz, V, b), _dpdiff(px, py, pz, V, c)
    n = _dcross(ab, ac)
    ta = _ddot(n, _dcross(ab, ap))
    tb = _ddot(n, _dcross(bc, bp))
    tc = _ddot(n, _dcross(ca, cp))
    nn = _ddot(n, n)
    if nn > 0.0 and ta >= 0.0 and tb >= 0.0 and tc >= 0.0:    # (nn 0: corners exactly collinear)
        s = _ddot(ap, n)
        return s * s / nn
    return min(_seg2(px, py, pz, V, a, b), _seg2(px, py, pz, V, b, c), _seg2(px, py, pz, V, c, a))


@njit(cache=True, inline="always", error_model="numpy")
def _tri_dist2(px, py, pz, V, a, b, c):
    """Squared distance from p to the closed triangle (V[a], V[b], V[c]) (Ericson's regions).
    Every difference is taken from p to a vertex (never from p to a point rebuilt in absolute
    coordinates, whose rounding grows with the distance from the origin), and a point over the
    inside is at the distance to the plane, ``(ap . n)^2 / |n|^2`` (barycentric coordinates lose
    their digits to cancellation). A sliver (`SLIVER2`) is measured in double-double arithmetic
    (`_tri_dist2_dd`)."""
    ax, ay, az = V[a, 0], V[a, 1], V[a, 2]
    abx, aby, abz = V[b, 0] - ax, V[b, 1] - ay, V[b, 2] - az
    acx, acy, acz = V[c, 0] - ax, V[c, 1] - ay, V[c, 2] - az
    nx, ny, nz = aby * acz - abz * acy, abz * acx - abx * acz, abx * acy - aby * acx
    nn = nx * nx + ny * ny + nz * nz
    if nn == 0.0:                                   # degenerate triangle: nearest of its edges
        return min(_seg2(px, py, pz, V, a, b), _seg2(px, py, pz, V, b, c), _seg2(px, py, pz, V, c, a))
    if (abx * abx + aby * aby + abz * abz) * (acx * acx + acy * acy + acz * acz) > SLIVER2 * nn:
        return _tri_dist2_dd(px, py, pz, V, a, b, c)  # a sliver: its normal needs more digits
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:
        return apx * apx + apy * apy + apz * apz
    bpx, bpy, bpz = px - V[b, 0], py - V[b, 1], pz - V[b, 2]
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0.0 and d4 <= d3:
        return bpx * bpx + bpy * bpy + bpz * bpz
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        t = d1 / (d1 - d3)
        dx, dy, dz = apx - t * abx, apy - t * aby, apz - t * abz
        return dx * dx + dy * dy + dz * dz
    cpx, cpy, cpz = px - V[c, 0], py - V[c, 1], pz - V[c, 2]
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0.0 and d5 <= d6:
        return cpx * cpx + cpy * cpy + cpz * cpz
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        t = d2 / (d2 - d6)
        dx, dy, dz = apx - t * acx, apy - t * acy, apz - t * acz
        return dx * dx + dy * dy + dz * dz
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        dx = bpx - t * (V[c, 0] - V[b, 0])
        dy = bpy - t * (V[c, 1] - V[b, 1])
        dz = bpz - t * (V[c, 2] - V[b, 2])
        return dx * dx + dy * dy + dz * dz
    s = apx * nx + apy * ny + apz * nz
    return s * s / nn


@njit(cache=True, inline="always")
def _seg2(px, py, pz, V, a, b):
    ux, uy, uz = V[b, 0] - V[a, 0], V[b, 1] - V[a, 1], V[b, 2] - V[a, 2]
    den = ux * ux + uy * uy + uz * uz
    t = 0.0
    if den > 0.0:
        t = min(max(((px - V[a, 0]) * ux + (py - V[a, 1]) * uy + (pz - V[a, 2]) * uz) / den, 0.0), 1.0)
    dx, dy, dz = px - V[a, 0] - t * ux, py - V[a, 1] - t * uy, pz - V[a, 2] - t * uz
    return dx * dx + dy * dy + dz * dz


@njit(cache=True)
def _select(order, C, ax, lo, hi, k):
    """Rearrange ``order[lo:hi+1]`` so that ``order[k]`` has the k-th smallest ``C[., ax]``, with
    no larger key before it and no smaller one after it (quickselect, middle pivot)."""
    while lo < hi:
        pivot = C[order[(lo + hi) // 2], ax]
        i, j = lo, hi
        while i <= j:
            while C[order[i], ax] < pivot:
                i += 1
            while C[order[j], ax] > pivot:
                j -= 1
            if i <= j:
                order[i], order[j] = order[j], order[i]
                i += 1
                j -= 1
        if k <= j:
            hi = j
        elif k >= i:
            lo = i
        else:
            return


@njit(cache=True)
def build(V, F, C, order):
    """Nodes of the BVH over the triangles (centroids ``C``), splitting each node at the median
    centroid along its longest axis; ``order`` (a permutation of the faces) is rearranged in
    place. Returns the nodes packed in ``B`` (N, 8): the box's low and high corners
    ``B[k, 0:3]``, ``B[k, 3:6]``, then for an inner node its children ``B[k, 6]`` and
    ``B[k, 7] = B[k, 6] + 1``, for a leaf ``-1 - start`` and ``end``, its range of ``order``
    (so ``B[k, 6] < 0`` marks a leaf). Node 0 is the root."""
    m = order.size
    cap = 2 * m + 1                      # leaves hold >= 1 triangle: at most 2m - 1 nodes
    left = np.full(cap, -1, np.int64)
    right = np.full(cap, -1, np.int64)
    start = np.zeros(cap, np.int64)
    end = np.zeros(cap, np.int64)
    stack = np.empty(128, np.int64)
    n = 1
    start[0], end[0] = 0, m
    top = 0
    stack[0] = 0
    top = 1
    while top > 0:
        top -= 1
        k = stack[top]
        if end[k] - start[k] > LEAF:
            # split at the median centroid along the longest axis of the centroids' box
            s0, e0 = start[k], end[k]
            cl0, cl1, cl2 = np.inf, np.inf, np.inf
            ch0, ch1, ch2 = -np.inf, -np.inf, -np.inf
            for i in range(s0, e0):
                f = order[i]
                cl0, ch0 = min(cl0, C[f, 0]), max(ch0, C[f, 0])
                cl1, ch1 = min(cl1, C[f, 1]), max(ch1, C[f, 1])
                cl2, ch2 = min(cl2, C[f, 2]), max(ch2, C[f, 2])
            ax = 0
            if ch1 - cl1 > ch0 - cl0:
                ax = 1
            if ch2 - cl2 > max(ch0 - cl0, ch1 - cl1):
                ax = 2
            mid = (s0 + e0) // 2
            _select(order, C, ax, s0, e0 - 1, mid)
            left[k], right[k] = n, n + 1
            start[n], end[n] = start[k], mid
            start[n + 1], end[n + 1] = mid, end[k]
            stack[top] = n
            stack[top + 1] = n + 1
            top += 2
            n += 2
    B = np.empty((n, 8))                     # packed: one node per 64 bytes
    for k in range(n):
        if left[k] < 0:
            B[k, 6] = -1.0 - start[k]
            B[k, 7] = end[k]
        else:
            B[k, 6] = left[k]                # right[k] == left[k] + 1
            B[k, 7] = right[k]
    _fit(B, V, F, order)
    return B


@njit(cache=True)
def _fit(B, V, F, order):
    """Set every box of the packed nodes ``B`` bottom-up (children have larger indices): a leaf's
    box holds the corners of its triangles ``F[order[start:end]]``, an inner box its children's."""
    for k in range(B.shape[0] - 1, -1, -1):
        if B[k, 6] < 0:
            for d in range(3):
                B[k, d] = np.inf
                B[k, 3 + d] = -np.inf
            for i in range(int(-1.0 - B[k, 6]), int(B[k, 7])):
                f = order[i]
                for j in range(3):
                    v = F[f, j]
                    for d in range(3):
                        x = V[v, d]
                        if x < B[k, d]:
                            B[k, d] = x
                        if x > B[k, 3 + d]:
                            B[k, 3 + d] = x
        else:
            a, b = int(B[k, 6]), int(B[k, 7])
            for d in range(3):
                B[k, d] = min(B[a, d], B[b, d])
                B[k, 3 + d] = max(B[a, 3 + d], B[b, 3 + d])


@njit(cache=True)
def refit(B, V, F):
    """The nodes ``B`` (`build`'s packing) with every box recomputed for the vertex positions
    ``V`` of the same triangles ``F`` (leaf order): the same tree over a displaced copy of the
    surface. Any positions give a valid hierarchy (each box holds its triangles); the closer
    they are to the built ones, the tighter the boxes."""
    out = B.copy()
    _fit(out, V, F, np.arange(F.shape[0]))
    return out


@njit(cache=True)
def centroids(V, F):
    """Centroids (m, 3) of the triangles."""
    C = np.empty((F.shape[0], 3))
    for f in range(F.shape[0]):
        for d in range(3):
            C[f, d] = (V[F[f, 0], d] + V[F[f, 1], d] + V[F[f, 2], d]) / 3.0
    return C


@njit(cache=True)
def leaf_order(V, F, order):
    """``(V', F')``: the triangles in ``order`` and the vertices renumbered in order of first
    use (unused vertices dropped), so that queries read contiguous memory."""
    m = order.size
    remap = np.full(V.shape[0], -1, np.int64)
    Fo = np.empty((m, 3), np.int64)
    used = np.empty(V.shape[0], np.int64)
    nu = 0
    for i in range(m):
        for j in range(3):
            v = F[order[i], j]
            if remap[v] < 0:
                remap[v] = nu
                used[nu] = v
                nu += 1
            Fo[i, j] = remap[v]
    Vo = np.empty((nu, 3))
    for i in range(nu):
        for d in range(3):
            Vo[i, d] = V[used[i], d]
    return Vo, Fo


@njit(cache=True, inline="always")
def _gap2(lo, hi, p):
    t = max(lo - p, p - hi, 0.0)
    return t * t


@njit(cache=True, inline="always")
def _box2(px, py, pz, B, k):
    """Squared distance from p to the box of node k."""
    return _gap2(B[k, 0], B[k, 3], px) + _gap2(B[k, 1], B[k, 4], py) + _gap2(B[k, 2], B[k, 5], pz)


@njit(cache=True)
def closest(px, py, pz, V, F, B, hint, stack, dstack):
    """``(squared distance, face)`` of the closest triangle to p; ``hint`` a face to start from
    (or -1). ``stack``/``dstack`` (256,): scratch for the nodes to visit and their box
    distances."""
    best = np.inf
    bf = -1
    if hint >= 0:
        best = _tri_dist2(px, py, pz, V, F[hint, 0], F[hint, 1], F[hint, 2])
        bf = hint
    stack[0] = 0
    dstack[0] = 0.0
    top = 1
    while top > 0:
        top -= 1
        if dstack[top] >= best:                # pruned by a triangle found since it was pushed
            continue
        k = stack[top]
        c = B[k, 6]
        if c < 0.0:                            # a leaf: its triangles F[start:end]
            for f in range(int(-1.0 - c), int(B[k, 7])):
                d = _tri_dist2(px, py, pz, V, F[f, 0], F[f, 1], F[f, 2])
                if d < best:
                    best = d
                    bf = f
        else:                                  # children a and a + 1, nearer box on top
            a = int(c)
            da, db = _box2(px, py, pz, B, a), _box2(px, py, pz, B, a + 1)
            if da < db:
                if db < best:
                    stack[top] = a + 1
                    dstack[top] = db
                    top += 1
                if da < best:
                    stack[top] = a
                    dstack[top] = da
                    top += 1
            else:
                if da < best:
                    stack[top] = a
                    dstack[top] = da
                    top += 1
                if db < best:
                    stack[top] = a + 1
                    dstack[top] = db
                    top += 1
    return best, bf


@njit(cache=True, nogil=True)
def query_many(P, hints, V, F, B):
    """Distances (k,) and closest faces (k,) of points P (k, 3); a point without a hint (-1)
    starts from the previous point's closest face (consecutive points are often near). It
    releases the GIL: `harness.metrics._queries` runs blocks of points on several threads."""
    k = P.shape[0]
    d = np.empty(k)
    f = np.empty(k, np.int64)
    stack = np.empty(256, np.int64)
    dstack = np.empty(256)
    for i in range(k):
        h = hints[i] if (hints[i] >= 0 or i == 0) else f[i - 1]
        d2, fi = closest(P[i, 0], P[i, 1], P[i, 2], V, F, B, h, stack, dstack)
        d[i] = math.sqrt(d2)
        f[i] = fi
    return d, f
