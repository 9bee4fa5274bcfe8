"""Compiled Gauss-Seidel vertex pass of Sun et al. 2007, as the authors' code runs it."""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def _passes(X, F, N, ptr, faces, iterations, fixed):
    for _ in range(iterations):
        for i in range(X.shape[0]):
            k = ptr[i + 1] - ptr[i]
            if k == 0 or fixed[i]:
                continue
            mx = my = mz = 0.0
            for j in range(ptr[i], ptr[i + 1]):
                f = faces[j]
                a, b, c = F[f, 0], F[f, 1], F[f, 2]
                dx = (X[a, 0] + X[b, 0] + X[c, 0]) / 3.0 - X[i, 0]
                dy = (X[a, 1] + X[b, 1] + X[c, 1]) / 3.0 - X[i, 1]
                dz = (X[a, 2] + X[b, 2] + X[c, 2]) / 3.0 - X[i, 2]
                t = N[f, 0] * dx + N[f, 1] * dy + N[f, 2] * dz
                mx += N[f, 0] * t
                my += N[f, 1] * t
                mz += N[f, 2] * t
            X[i, 0] += mx / k
            X[i, 1] += my / k
            X[i, 2] += mz / k
    return X


def sun_vertex_update_in_place(X: np.ndarray, F: np.ndarray, N: np.ndarray, iterations: int,
                               fixed: np.ndarray | None = None) -> np.ndarray:
    """``x_i += 1/|F_i| sum_{f in F_i} n_f (n_f . (c_f - x_i))`` for i = 0, 1, ... in turn, each
    vertex from the positions as they are when its turn comes (Gauss-Seidel: the centroids
    ``c_f`` see the vertices already moved in this pass), ``iterations`` passes; the faces of a
    vertex summed in increasing index. Xianfang Sun's ``mdenoise`` (``VertexUpdate``) runs the
    pass this way. ``N`` (m, 3) fixed filtered normals; ``fixed``: the vertices that do not move,
    a mask (n,) or their indices.
    Returns ``X`` (n, 3) float64, updated in place."""
    X = np.ascontiguousarray(X, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    n, m = len(X), len(F)
    vid = F.ravel()
    order = np.argsort(vid, kind="stable")                 # corners by vertex, faces ascending
    faces = np.ascontiguousarray(np.repeat(np.arange(m, dtype=np.int64), 3)[order])
    ptr = np.zeros(n + 1, np.int64)
    np.cumsum(np.bincount(vid, minlength=n), out=ptr[1:])
    keep = np.zeros(n, np.bool_)
    if fixed is not None:
        fixed = np.asarray(fixed)
        if fixed.dtype == np.bool_:
            if fixed.shape != (n,):
                raise ValueError(f"fixed: a mask of {fixed.shape} for {n} vertices")
            keep[:] = fixed
        else:
            keep[fixed.astype(np.int64)] = True                # vertex indices
    return _passes(X, F, np.ascontiguousarray(N, dtype=np.float64), ptr, faces, int(iterations), keep)
