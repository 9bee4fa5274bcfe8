"""The tufted cover and its intrinsic Delaunay Laplacian (Sharp & Crane 2020, "A Laplacian for
nonmanifold triangle meshes", SGP).

The tufted cover replaces each face ``f`` by two sides, ``f`` itself (front) and ``f`` reversed
(back), on the same vertices. Around each edge the ``k`` incident faces are ordered by angle
(right-hand rule about the edge ``lo -> hi``); in each of the ``k`` gaps between consecutive
faces ``a -> b`` the side of ``a`` facing the gap (the one traversing ``lo -> hi``) is glued to
the side of ``b`` facing it (traversing ``hi -> lo``). The result is a closed, oriented,
edge-manifold intrinsic surface for any input: two copies of a closed manifold mesh, the double
of a mesh with boundary (glued along the boundary), and a valid cover of non-manifold edges.
Its intrinsic Delaunay triangulation (edge flips, `methods.scratch.intrinsic_delaunay`) gives
cotangent weights that are all non-negative; halving the cover's ``W`` and lumped mass (each
face is counted twice) gives the tufted Laplacian: ``W_ij = sum over cover edges ij of
(cot a + cot b) / 4``, mass ``M_ii = sum over cover faces at i of A_f / 6`` (barycentric) or
half the cover's mixed Voronoi area. On a closed manifold mesh it equals the intrinsic
Delaunay Laplacian; at a boundary edge whose opposite angle is obtuse it differs (the flip joins
the vertex to itself across the boundary, a self-edge that carries no weight).

Intrinsic mollification (same paper, Sec. 4.5): every edge length grows by ``delta = max(0,
max_f (eps - (l_i + l_j - l_k)))`` with ``eps = mollify_factor * mean edge length``, so every
triangle inequality holds with margin ``eps`` (0 on well-shaped meshes), the mean taken over
the input's edges, before the cover is built (as robust-laplacian does).
"""
from __future__ import annotations

import numpy as np

from harness.core.geometry import edge_lengths

_BACK = np.array([0, 2, 1])       # corner c of a front face is corner _BACK[c] of its back face


def tufted_cover(V: np.ndarray, F: np.ndarray, mollify_factor: float = 0.0):
    """``(l, F2, twin)``: the tufted cover's corner-opposite edge lengths (2m, 3), faces (2m, 3)
    (fronts ``0..m-1``, backs ``m..2m-1`` as ``(a, c, b)``) and halfedge twins (6m,), halfedge
    ``h = 3 s + c`` being the edge of side ``s`` opposite corner ``c`` (module docstring)."""
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    m, n = len(F), len(V)
    l = edge_lengths(V, F)
    F2 = np.concatenate([F, F[:, _BACK]])
    if not m:
        return np.concatenate([l, l[:, _BACK]]), F2, np.zeros(0, np.int64)
    f = np.repeat(np.arange(m), 3)
    c = np.tile(np.arange(3), m)
    u, v = F[f, (c + 1) % 3], F[f, (c + 2) % 3]               # front halfedge 3f + c runs u -> v
    lo, hi = np.minimum(u, v), np.maximum(u, v)
    front, back = 3 * f + c, 3 * (m + f) + _BACK[c]
    fwd = u == lo
    plus = np.where(fwd, front, back)                          # the side traversing lo -> hi
    minus = np.where(fwd, back, front)
    key = lo * np.int64(n) + hi
    order = np.argsort(key, kind="stable")
    ks = key[order]
    start = np.flatnonzero(np.r_[True, ks[1:] != ks[:-1]])
    count = np.diff(np.r_[start, ks.size])
    group = np.repeat(np.arange(start.size), count)
    if mollify_factor > 0:                                     # on the input's edges, before the cover
        eps = mollify_factor * float(l.ravel()[order[start]].mean())
        slack = l.sum(axis=1, keepdims=True) - 2.0 * l          # l_i + l_j - l_k per corner
        l = l + max(0.0, float((eps - slack).max()))
    l2 = np.concatenate([l, l[:, _BACK]])
    many = np.repeat(count > 2, count)
    if many.any():                                             # order non-manifold fans by angle
        idx = order[many]
        e = V[hi[idx]] - V[lo[idx]]
        e /= np.maximum(np.linalg.norm(e, axis=1, keepdims=True), 1e-300)
        ref = np.where(np.abs(e[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
        x = np.cross(e, ref)
        x /= np.linalg.norm(x, axis=1, keepdims=True)
        y = np.cross(e, x)
        r = V[F[f[idx], c[idx]]] - V[lo[idx]]
        theta = np.zeros(order.size)
        theta[many] = np.arctan2(np.einsum("ij,ij->i", r, y), np.einsum("ij,ij->i", r, x))
        # the frame is per entry but depends only on the edge, so angles are comparable in a group
        order = order[np.lexsort((theta, group))]
    pos = np.arange(order.size)
    nxt = np.where(pos + 1 < np.repeat(start + count, count), pos + 1, np.repeat(start, count))
    a, b = order, order[nxt]
    twin = np.empty(6 * m, dtype=np.int64)
    twin[plus[a]] = minus[b]
    twin[minus[b]] = plus[a]
    return l2, F2, twin


def tufted_triangulation(V: np.ndarray, F: np.ndarray, mollify_factor: float = 0.0):
    """``(l, F2, flips)``: the intrinsic Delaunay triangulation of the tufted cover (its faces
    index the input's vertices; self-edges and repeated vertices in a face are allowed)."""
    from methods.scratch import intrinsic_delaunay as idt
    l2, F2, twin = tufted_cover(V, F, mollify_factor)
    if not len(F2):
        return l2, F2, 0
    idt._compile()
    max_flips = 50 * F2.shape[0] + 1000
    flips = idt._flip_to_delaunay(F2, l2, twin, max_flips)
    if flips < 0:
        raise RuntimeError(f"tufted-cover Delaunay flips did not terminate after {max_flips} flips")
    return l2, F2, int(flips)


def tufted_laplacian(V: np.ndarray, F: np.ndarray, mass: str = "barycentric", mollify_factor: float = 1e-5):
    """``(W, M)``: the tufted Laplacian (libigl's sign: ``W`` negative semi-definite) and its
    diagonal mass, ``barycentric`` (= ``robust_laplacian.mesh_laplacian``'s ``-L, M``) or
    ``voronoi`` (module docstring)."""
    import scipy.sparse as sp

    from harness.core.geometry import cotangents_from_lengths
    from methods.scratch import operators as op
    n = len(V)
    l, F2, _ = tufted_triangulation(V, F, mollify_factor)
    C, dbl = cotangents_from_lengths(l)
    W = op.assemble_weights(F2, 0.25 * C, n)
    if mass == "barycentric":
        a = np.bincount(F2.ravel(), weights=np.repeat(dbl / 12.0, 3), minlength=n)
    elif mass == "voronoi":
        a = 0.5 * op.mixed_voronoi_from_cotangents(F2, C, l * l, dbl, n)
    else:
        raise ValueError(f"unknown mass {mass!r} for the tufted Laplacian; expected barycentric or voronoi")
    return W.tocsr(), sp.diags(a).tocsr()
