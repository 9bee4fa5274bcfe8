"""Procedural meshes with exact ground truth: one generator per kind, each returning ``(V, F)``.

`GENERATORS` maps a kind's name (a config's ``procedural:``) to its generator; the defaults and
bounds of their parameters are `harness.datasets.PROCEDURAL` and `PROCEDURAL_BOUNDS`. Seeded
generators give the same mesh for the same parameters.
"""
from __future__ import annotations

import numpy as np

from .core.geometry import face_cross


def icosphere(subdivisions: int = 3, radius: float = 1.0):
    """Icosahedron subdivided ``subdivisions`` times (4x faces each), projected to the sphere.

    Faces: 20 * 4^s. Every vertex lies exactly (to rounding) on the sphere of ``radius``.
    """
    t = (1 + 5 ** 0.5) / 2
    V = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
                  [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], float)
    F = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
                  [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
                  [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]], np.int64)
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    for _ in range(int(subdivisions)):
        E = np.sort(np.concatenate([F[:, [1, 2]], F[:, [2, 0]], F[:, [0, 1]]]), axis=1)
        uniq, inv = np.unique(E, axis=0, return_inverse=True)
        mid = V[uniq[:, 0]] + V[uniq[:, 1]]
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        m = len(F)
        e = inv.ravel().reshape(3, m) + len(V)          # midpoint opposite corner k
        a, b, c = F[:, 0], F[:, 1], F[:, 2]
        F = np.concatenate([np.stack([a, e[2], e[1]], 1), np.stack([b, e[0], e[2]], 1),
                            np.stack([c, e[1], e[0]], 1), np.stack([e[0], e[1], e[2]], 1)])
        V = np.concatenate([V, mid])
    return V * radius, F


def torus(R: float = 1.0, r: float = 0.4, resolution: int = 48):
    """Torus of major radius R, minor radius r; ``resolution`` x ``resolution // 2`` quads split in two."""
    n, m = int(resolution), max(3, int(resolution) // 2)
    u, v = np.meshgrid(np.arange(n) * 2 * np.pi / n, np.arange(m) * 2 * np.pi / m, indexing="ij")
    V = np.stack([(R + r * np.cos(v)) * np.cos(u), (R + r * np.cos(v)) * np.sin(u), r * np.sin(v)], -1)
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    a = i * m + j
    b = ((i + 1) % n) * m + j
    c = ((i + 1) % n) * m + (j + 1) % m
    d = i * m + (j + 1) % m
    F = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return V.reshape(-1, 3), F.astype(np.int64)


def _plane_points(n_points: int, seed: int):
    rng = np.random.default_rng(int(seed))
    k = max(2, int(round(np.sqrt(n_points) / 2)))
    s = np.linspace(0, 1, k + 1)[:-1]
    border = np.concatenate([np.stack([s, 0 * s], 1), np.stack([1 + 0 * s, s], 1),
                             np.stack([1 - s, 1 + 0 * s], 1), np.stack([0 * s, 1 - s], 1)])
    # interior points keep one border spacing away from the sides, so the angle opposite a
    # boundary edge stays below 2 atan(1/2) = 53 degrees (no negative boundary cotangent)
    inner = rng.uniform(1.0 / k, 1 - 1.0 / k, size=(max(1, n_points - len(border)), 2))
    return np.concatenate([border, inner])


def plane_delaunay(n_points: int = 300, seed: int = 0):
    """Delaunay triangulation of seeded random points in the unit square (z = 0)."""
    from scipy.spatial import Delaunay
    P = _plane_points(n_points, seed)
    F = Delaunay(P).simplices.astype(np.int64)
    V = np.column_stack([P, np.zeros(len(P))])
    return V, _orient_up(V, F)


def _orient_up(V, F):
    n = face_cross(V, F)[:, 2]
    F = F.copy()
    F[n < 0] = F[n < 0][:, [0, 2, 1]]
    return F


def plane_nondelaunay(n_points: int = 300, seed: int = 0, flip_fraction: float = 0.3):
    """`plane_delaunay` with a seeded fraction of interior edges flipped.

    Only edges whose quad is strictly convex are flipped, and no two flipped edges share a
    face, so every flipped edge has opposite angles summing above pi (non-Delaunay) and the
    triangulation stays valid and planar.
    """
    V, F = plane_delaunay(n_points, seed)
    rng = np.random.default_rng(int(seed) + 1)
    m = len(F)
    he = np.concatenate([F[:, [1, 2]], F[:, [2, 0]], F[:, [0, 1]]])   # edge opposite corner k
    fid = np.tile(np.arange(m), 3)
    opp = np.concatenate([F[:, 0], F[:, 1], F[:, 2]])
    key = np.sort(he, axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    k_sorted = key[order]
    same = np.all(k_sorted[1:] == k_sorted[:-1], axis=1)
    h1, h2 = order[:-1][same], order[1:][same]                        # the two halves of interior edges
    sel = rng.permutation(len(h1))[: int(round(flip_fraction * len(h1)))]
    used = np.zeros(m, bool)
    F = F.copy()
    P = V[:, :2]

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    for s in sel:                       # a few hundred edges: generation, not a hot path
        a, b = h1[s], h2[s]
        f1, f2 = fid[a], fid[b]
        if used[f1] or used[f2]:
            continue
        p, q = he[a]
        x, y = opp[a], opp[b]
        # convex quad x-p-y-q: x and y on opposite sides of pq, p and q on opposite sides of xy
        if cross(P[p], P[q], P[x]) * cross(P[p], P[q], P[y]) >= 0:
            continue
        if cross(P[x], P[y], P[p]) * cross(P[x], P[y], P[q]) >= -1e-12:
            continue
        F[f1] = [x, p, y]
        F[f2] = [y, q, x]
        used[f1] = used[f2] = True
    return V, _orient_up(V, F)


def cylinder(radius: float = 1.0, height: float = 2.0, resolution: int = 32):
    """Open cylinder ``x^2 + y^2 = radius^2``, ``0 <= z <= height`` (two boundary circles).

    ``resolution`` vertices per ring; rings spaced so triangles are close to equilateral
    (alternate rings rotated by half a step). Every vertex lies exactly on the cylinder.
    K = 0, H = 1 / (2 radius) (outward normals), geodesics are straight lines once unrolled.
    """
    n = int(resolution)
    step = 2 * np.pi * radius / n
    rings = max(1, int(round(height / (step * np.sqrt(3) / 2))))
    j, i = np.meshgrid(np.arange(rings + 1), np.arange(n), indexing="ij")
    theta = (i + 0.5 * (j % 2)) * 2 * np.pi / n
    V = np.stack([radius * np.cos(theta), radius * np.sin(theta), j * height / rings], -1).reshape(-1, 3)
    j, i = np.meshgrid(np.arange(rings), np.arange(n), indexing="ij")
    a = j * n + i
    b = j * n + (i + 1) % n
    c = (j + 1) * n + i
    d = (j + 1) * n + (i + 1) % n
    even = (j % 2 == 0)
    # even rows: the ring above is shifted +half a step, so split quads along b-c; odd rows along a-d
    T1 = np.where(even[..., None], np.stack([a, b, c], -1), np.stack([a, b, d], -1))
    T2 = np.where(even[..., None], np.stack([b, d, c], -1), np.stack([a, d, c], -1))
    F = np.concatenate([T1.reshape(-1, 3), T2.reshape(-1, 3)]).astype(np.int64)
    return V, F


def ellipsoid(rx: float = 1.0, ry: float = 0.75, rz: float = 0.5, subdivisions: int = 4):
    """Ellipsoid with semi-axes rx, ry, rz: an icosphere scaled per axis (vertices exactly on it).

    ``x^2/rx^2 + y^2/ry^2 + z^2/rz^2 = 1``; the triangulation is the icosphere's, stretched.
    """
    V, F = icosphere(subdivisions, 1.0)
    return V * np.array([rx, ry, rz], dtype=np.float64), F


def saddle(a: float = 0.5, n_points: int = 2000, seed: int = 0):
    """Open saddle height field ``z = a (x^2 - y^2)`` over ``[-1/2, 1/2]^2`` (irregular).

    The Delaunay triangulation of `plane_delaunay`'s seeded points, normals up (+z side).
    """
    V, F = plane_delaunay(n_points, seed)
    x, y = V[:, 0] - 0.5, V[:, 1] - 0.5
    return np.column_stack([x, y, a * (x * x - y * y)]), F


def plane_skinny(n_points: int = 300, seed: int = 0, split_fraction: float = 0.5, offset: float = 0.02):
    """`plane_delaunay` remeshed with slivers: a seeded ``split_fraction`` of its faces split in
    three at a point next to their longest edge (barycentric ``offset`` toward the opposite corner),
    each giving a sliver whose angle at the new vertex approaches 180 degrees.

    The same unit square (z = 0, every point in it), so the plane's analytic references hold; no
    edge of the plane is split, so no vertex hangs on a neighbour's edge.
    """
    V, F = plane_delaunay(n_points, seed)
    rng = np.random.default_rng(int(seed) + 2)
    pick = np.flatnonzero(rng.random(len(F)) < float(split_fraction))
    T = F[pick]
    L = np.stack([np.linalg.norm(V[T[:, (k + 1) % 3]] - V[T[:, (k + 2) % 3]], axis=1) for k in range(3)], 1)
    k = L.argmax(axis=1)                              # the corner opposite the longest edge
    c = T[np.arange(len(T)), k]
    a, b = T[np.arange(len(T)), (k + 1) % 3], T[np.arange(len(T)), (k + 2) % 3]
    w = float(offset)
    P = (1 - w) * 0.5 * (V[a] + V[b]) + w * V[c]
    n = len(V) + np.arange(len(T))
    V = np.vstack([V, P])
    keep = np.ones(len(F), bool)
    keep[pick] = False
    F = np.vstack([F[keep], np.stack([a, b, n], 1), np.stack([b, c, n], 1), np.stack([c, a, n], 1)])
    return V, _orient_up(V, F)


def sphere_random(n_points: int = 2000, seed: int = 0, radius: float = 1.0):
    """Irregular sphere: the convex hull of seeded uniform random points on the sphere.

    ``n_points`` points of the sphere of ``radius`` (every vertex exactly on it), faces outward.
    """
    from scipy.spatial import ConvexHull
    rng = np.random.default_rng(int(seed))
    P = rng.normal(size=(max(4, int(n_points)), 3))
    P /= np.linalg.norm(P, axis=1, keepdims=True)
    F = ConvexHull(P).simplices.astype(np.int64)
    C = P[F].mean(axis=1) - P[np.unique(F)].mean(axis=0)   # from a point inside the hull (the origin may not be)
    flip = np.einsum("ij,ij->i", face_cross(P, F), C) < 0
    F[flip] = F[flip][:, [0, 2, 1]]
    return P * radius, F


GENERATORS = {"sphere": icosphere, "torus": torus, "plane_delaunay": plane_delaunay,
              "plane_nondelaunay": plane_nondelaunay, "plane_skinny": plane_skinny, "cylinder": cylinder, "ellipsoid": ellipsoid,
              "saddle": saddle, "sphere_random": sphere_random}
