"""Intrinsic Delaunay triangulation by edge flips on edge lengths (Fisher et al. 2006).

The surface is kept as a metric: faces ``F`` (m, 3) and per-face-corner edge lengths ``l``
(m, 3), ``l[f, c]`` the length of the edge opposite corner ``c`` (libigl's layout). An edge
is flipped when its two opposite angles sum above pi; the new edge's length comes from laying
the two triangles out in the plane. Flips never move vertices, so the result is the same
piecewise flat surface with a different (intrinsic) triangulation; its cotangent weights are
the Laplacian of Bobenko & Springborn 2007, which has non-negative weights (POS) but couples
vertices that share no mesh edge (no LOC).

The flip loop is inherently sequential and runs in numba (``cache=True``: compiled once per
machine, ~1-2 s; later processes load it from the cache).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from harness.core.geometry import cotangents_from_lengths, edge_lengths  # noqa: F401
from methods.scratch import operators as op

_COMPILED = False


def _compile() -> None:
    """Replace the three kernels by their numba versions (lazily, so importing this module
    does not import numba; ``cache=True``). Without numba they stay plain Python (slow)."""
    global _area, _needs_flip, _flip_to_delaunay, _COMPILED
    if _COMPILED:
        return
    _COMPILED = True
    try:
        from numba import njit
    except ImportError:  # pragma: no cover - numba is a project dependency
        return
    _area = njit(cache=True)(_area)
    _needs_flip = njit(cache=True)(_needs_flip)
    _flip_to_delaunay = njit(cache=True)(_flip_to_delaunay)

# Flip only when the Delaunay criterion fails by more than this relative margin: avoids
# flipping back and forth on (numerically) cocircular quads, where both diagonals give the
# same Laplacian (a zero weight) anyway.
FLIP_RTOL = 1e-12


def halfedge_twins(F: np.ndarray) -> np.ndarray:
    """Twin of each halfedge ``h = 3 f + c`` (the edge opposite corner c of face f).

    ``-1`` on the boundary; ``-2`` where the edge is not flippable (more than two faces, or
    two faces with the same orientation of the edge).
    """
    m = F.shape[0]
    src = np.stack([F[:, 1], F[:, 2], F[:, 0]], axis=1).ravel()   # h = 3f + c: F[c+1] -> F[c+2]
    dst = np.stack([F[:, 2], F[:, 0], F[:, 1]], axis=1).ravel()
    lo, hi = np.minimum(src, dst), np.maximum(src, dst)
    n = int(F.max()) + 1 if m else 0
    key = lo * np.int64(n) + hi
    order = np.argsort(key, kind="stable")
    ks = key[order]
    start = np.flatnonzero(np.r_[True, ks[1:] != ks[:-1]])
    count = np.diff(np.r_[start, ks.size])
    twin = np.full(3 * m, -1, dtype=np.int64)
    two = start[count == 2]
    a, b = order[two], order[two + 1]
    opposite = src[a] == dst[b]           # consistently oriented pair
    twin[a[opposite]] = b[opposite]
    twin[b[opposite]] = a[opposite]
    twin[a[~opposite]] = -2
    twin[b[~opposite]] = -2
    for s, c in zip(start[count > 2], count[count > 2]):
        twin[order[s:s + c]] = -2
    return twin


def _area(a, b, c):
    """Triangle area from side lengths (Kahan's stable Heron); 0 for violated inequality."""
    # sort descending: x >= y >= z
    x, y, z = a, b, c
    if x < y:
        x, y = y, x
    if y < z:
        y, z = z, y
    if x < y:
        x, y = y, x
    p = (x + (y + z)) * (z - (x - y)) * (z + (x - y)) * (x + (y - z))
    if p <= 0.0:
        return 0.0
    return 0.25 * np.sqrt(p)


def _needs_flip(e, a, b, c, d):
    """True if the edge e (apex angle alpha opposite e in triangle (e, a, b), delta in (e, c, d))
    has alpha + delta > pi (beyond the relative margin ``FLIP_RTOL``).

    alpha + delta > pi  <=>  tan(alpha/2) tan(delta/2) > 1, and with semi-perimeters s1, s2,
    tan(alpha/2)^2 = (s1-a)(s1-b) / (s1 (s1-e)): a polynomial test without divisions, which
    also handles a flat angle (alpha = pi, s1 = e) on a zero-area face.
    """
    s1 = 0.5 * (e + a + b)
    s2 = 0.5 * (e + c + d)
    lhs = (s1 - a) * (s1 - b) * (s2 - c) * (s2 - d)
    rhs = s1 * (s1 - e) * s2 * (s2 - e)
    return lhs > rhs * (1.0 + FLIP_RTOL) + 1e-300


def _flip_to_delaunay(F, L, twin, max_flips):
    """Flip edges in place until every flippable interior edge is intrinsic Delaunay.

    Halfedge ``h = 3 f + c`` is the edge of face f opposite corner c, from F[f, c+1] to
    F[f, c+2]. Returns the number of flips (``-1`` if ``max_flips`` was reached).
    """
    m = F.shape[0]
    stack = np.empty(3 * m + 4 * max_flips + 4, dtype=np.int64)
    top = 0
    for h in range(3 * m):
        t = twin[h]
        if t >= 0 and h < t:
            stack[top] = h
            top += 1
    flips = 0
    oldh = np.empty(4, dtype=np.int64)
    newh = np.empty(4, dtype=np.int64)
    tw = np.empty(4, dtype=np.int64)
    while top > 0:
        top -= 1
        h = stack[top]
        t = twin[h]
        if t < 0:
            continue
        f1, c1 = h // 3, h % 3
        f2, c2 = t // 3, t % 3
        if f1 == f2:
            continue
        i1, i2 = (c1 + 1) % 3, (c1 + 2) % 3
        j1, j2 = (c2 + 1) % 3, (c2 + 2) % 3
        e = L[f1, c1]
        a = L[f1, i1]      # |v2 v4|
        b = L[f1, i2]      # |v4 v1|
        c = L[f2, j1]      # |v1 v3|
        d = L[f2, j2]      # |v3 v2|
        if not _needs_flip(e, a, b, c, d):
            continue
        if flips >= max_flips:
            return -1
        v4 = F[f1, c1]
        v1 = F[f1, i1]
        v2 = F[f1, i2]
        v3 = F[f2, c2]
        # lay out: v1 = (0, 0), v2 = (e, 0), v4 above (dist b to v1, a to v2), v3 below
        if e <= 0.0:
            continue
        x4 = (b * b - a * a + e * e) / (2.0 * e)
        y4 = 2.0 * _area(e, a, b) / e
        x3 = (c * c - d * d + e * e) / (2.0 * e)
        y3 = -2.0 * _area(e, c, d) / e
        fl = np.sqrt((x4 - x3) ** 2 + (y4 - y3) ** 2)
        # outer halfedges before the flip and where they go
        oldh[0] = 3 * f1 + i1   # v2 -> v4  -> new (f2, 0)
        oldh[1] = 3 * f1 + i2   # v4 -> v1  -> new (f1, 2)
        oldh[2] = 3 * f2 + j1   # v1 -> v3  -> new (f1, 0)
        oldh[3] = 3 * f2 + j2   # v3 -> v2  -> new (f2, 2)
        newh[0] = 3 * f2 + 0
        newh[1] = 3 * f1 + 2
        newh[2] = 3 * f1 + 0
        newh[3] = 3 * f2 + 2
        for k in range(4):
            x = twin[oldh[k]]
            for q in range(4):          # a twin inside the quad itself (self-adjacent faces)
                if x == oldh[q]:
                    x = newh[q]
                    break
            tw[k] = x
        F[f1, 0] = v4
        F[f1, 1] = v1
        F[f1, 2] = v3
        F[f2, 0] = v3
        F[f2, 1] = v2
        F[f2, 2] = v4
        L[f1, 0] = c
        L[f1, 1] = fl
        L[f1, 2] = b
        L[f2, 0] = a
        L[f2, 1] = fl
        L[f2, 2] = d
        twin[3 * f1 + 1] = 3 * f2 + 1
        twin[3 * f2 + 1] = 3 * f1 + 1
        for k in range(4):
            twin[newh[k]] = tw[k]
            if tw[k] >= 0:
                twin[tw[k]] = newh[k]
        flips += 1
        for k in range(4):
            if tw[k] >= 0:
                stack[top] = newh[k]
                top += 1
    return flips


def intrinsic_delaunay_triangulation(V: np.ndarray, F: np.ndarray, l: np.ndarray | None = None):
    """Intrinsic Delaunay triangulation of the mesh's metric.

    Parameters
    ----------
    V : (n, 3) float64
        Vertex positions (used for the edge lengths when ``l`` is None).
    F : (m, 3) int64
        Triangles.
    l : (m, 3) float64, optional
        Corner-opposite edge lengths (libigl layout); computed from V when None.

    Returns
    -------
    l_int : (m, 3) float64
        Edge lengths of the intrinsic triangulation.
    F_int : (m, 3) int64
        Its faces (same vertex indices; an intrinsic triangulation can have edges that join a
        vertex to itself or two edges between the same pair).
    flips : int
        Number of flips performed.

    Notes
    -----
    Fisher, Springborn, Bobenko & Schroeder 2006: pop an edge from a stack; if its opposite
    angles sum above pi, flip it (new length from the planar layout of its two triangles) and
    push the four edges of its quad. Terminates (Bobenko & Springborn 2007). Boundary edges,
    non-manifold edges and inconsistently oriented pairs are never flipped.
    """
    F_int = np.array(F, dtype=np.int64, order="C", copy=True)
    L = edge_lengths(V, F) if l is None else np.array(l, dtype=np.float64, order="C", copy=True)
    if F_int.shape[0] == 0:
        return L, F_int, 0
    twin = halfedge_twins(F_int)
    max_flips = 50 * F_int.shape[0] + 1000
    _compile()
    flips = _flip_to_delaunay(F_int, L, twin, max_flips)
    if flips < 0:
        raise RuntimeError(f"intrinsic Delaunay flips did not terminate after {max_flips} flips")
    return L, F_int, int(flips)


def intrinsic_delaunay_cotmatrix(V: np.ndarray, F: np.ndarray):
    """Cotangent weights of the intrinsic Delaunay triangulation (== igl.intrinsic_delaunay_cotmatrix).

    Returns
    -------
    W : scipy.sparse.csr_matrix (n, n)
        ``W_ij = sum over intrinsic edges ij of (cot a + cot b) / 2``; rows sum to zero.
    l_int, F_int : the intrinsic triangulation (see `intrinsic_delaunay_triangulation`).
    """
    l_int, F_int, _ = intrinsic_delaunay_triangulation(V, F)
    C, _ = cotangents_from_lengths(l_int)
    W = op.assemble_weights(F_int, 0.5 * C, V.shape[0])
    return W, l_int, F_int


def intrinsic_mass(l: np.ndarray, F: np.ndarray, n: int, kind: str) -> sp.csr_matrix | None:
    """Diagonal mass of an intrinsic triangulation (``igl.massmatrix_intrinsic``).

    ``barycentric``: a third of each incident face's area; ``voronoi``: mixed Voronoi areas
    (Meyer et al. 2003) from the lengths; ``none``: None.
    """
    if kind == "none":
        return None
    C, dbl = cotangents_from_lengths(l)
    if kind == "barycentric":
        a = np.bincount(F.ravel(), weights=np.repeat(dbl / 6.0, 3), minlength=n)
    elif kind == "voronoi":
        a = op.mixed_voronoi_from_cotangents(F, C, l * l, dbl, n)
    else:
        raise ValueError(f"unknown mass {kind!r}; expected barycentric, voronoi or none")
    return sp.diags(a).tocsr()
