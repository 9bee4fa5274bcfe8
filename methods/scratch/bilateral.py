"""Bilateral normal filtering (Zheng et al. 2011) with Sun et al. (2007) vertex updates."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from methods import Param, SmoothingResult, register


def face_neighbour_pairs(F: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Pairs ``(i, j)`` of faces sharing at least one vertex, ``i == j`` included (CSR order)."""
    m = F.shape[0]
    FV = sp.csr_matrix((np.ones(3 * m), (np.repeat(np.arange(m), 3), F.ravel())), shape=(m, n))
    FF = (FV @ FV.T).tocsr()
    FF.sort_indices()
    rows = np.repeat(np.arange(m), np.diff(FF.indptr))
    return rows, FF.indices.astype(np.int64)


def face_geometry(X: np.ndarray, F: np.ndarray):
    """Unit normals (m, 3), areas (m,) and centroids (m, 3) of the faces."""
    P0, P1, P2 = X[F[:, 0]], X[F[:, 1]], X[F[:, 2]]
    N = np.cross(P1 - P0, P2 - P0)
    dbl = np.linalg.norm(N, axis=1)
    N = np.divide(N, dbl[:, None], out=np.zeros_like(N), where=dbl[:, None] > 0)
    return N, 0.5 * dbl, (P0 + P1 + P2) / 3.0


def mean_adjacent_centroid_distance(C: np.ndarray, F: np.ndarray) -> float:
    """Mean distance between centroids of faces sharing an edge (Zheng et al.'s sigma_s)."""
    m = F.shape[0]
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    fid = np.tile(np.arange(m), 3)
    order = np.lexsort((E[:, 1], E[:, 0]))
    Es, fs = E[order], fid[order]
    same = np.all(Es[1:] == Es[:-1], axis=1)
    a, b = fs[:-1][same], fs[1:][same]
    if len(a) == 0:
        return float(np.linalg.norm(C - C.mean(0), axis=1).mean() + 1e-300)
    return float(np.linalg.norm(C[a] - C[b], axis=1).mean())


def sun_vertex_update(X: np.ndarray, F: np.ndarray, N: np.ndarray, iterations: int) -> np.ndarray:
    """Sun et al. 2007: ``x_i += 1/|F_i| sum_{f in F_i} n_f (n_f . (c_f - x_i))``, repeated.

    ``N`` are the target (filtered) face normals, kept fixed; centroids ``c_f`` are
    recomputed from the current positions each iteration.
    """
    n = X.shape[0]
    count = np.bincount(F.ravel(), minlength=n).astype(np.float64)
    count[count == 0] = 1.0
    corner_n = np.repeat(N, 3, axis=0)                       # (3m, 3), face of each corner
    vid = F.ravel()
    for _ in range(iterations):
        C = (X[F[:, 0]] + X[F[:, 1]] + X[F[:, 2]]) / 3.0
        d = np.repeat(C, 3, axis=0) - X[vid]                 # c_f - x_i per corner
        move = corner_n * np.einsum("ij,ij->i", corner_n, d)[:, None]
        delta = np.stack([np.bincount(vid, weights=move[:, k], minlength=n) for k in range(3)], 1)
        X = X + delta / count[:, None]
    return X


@register("scratch.bilateral", task="smoothing", library="scratch",
          params={"sigma_r": Param("sigma_r", 0.35, "float", low=1e-6, high=10.0,
                                   doc="range (normal difference) Gaussian width"),
                  "sigma_s": Param("sigma_s", 1.0, "float", low=1e-6, high=100.0,
                                   doc="spatial Gaussian width in units of the mean "
                                       "adjacent-centroid distance"),
                  "normal_iterations": Param("normal_iterations", 10, "int", low=0, high=1000,
                                             doc="normal filtering passes per iteration"),
                  "vertex_iterations": Param("vertex_iterations", 10, "int", low=0, high=1000,
                                             doc="Sun et al. vertex updates per iteration"),
                  "iterations": Param("iterations", 2, "int", low=0, high=1000,
                                      doc="outer iterations (filter normals, then fit)")})
def bilateral(V, F, *, sigma_r=0.35, sigma_s=1.0, normal_iterations=10, vertex_iterations=10,
              iterations=2):
    """Bilateral normal filtering (Zheng, Fu, Au, Tai, "Bilateral normal filtering for mesh
    denoising", IEEE TVCG 2011), local iterative scheme, vectorized.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    sigma_r : float
        Range kernel width on ``|n_i - n_j|`` (unit normals, so dimensionless; Zheng et al.
        use 0.2-0.6: smaller keeps sharper features).
    sigma_s : float
        Spatial kernel width as a multiple of the mean distance between centroids of
        edge-adjacent faces (Zheng et al.'s default choice for ``sigma_c``).
    normal_iterations : int
        Normal filtering passes per outer iteration.
    vertex_iterations : int
        Vertex position updates per outer iteration.
    iterations : int
        Outer iterations; each recomputes normals, areas and centroids from the current mesh.

    Returns
    -------
    SmoothingResult

    Notes
    -----
    Normal filter on the faces ``j`` sharing a vertex with face ``i`` (``i`` included)::

        n_i <- normalize( sum_j A_j W_s(|c_i - c_j|) W_r(|n_i - n_j|) n_j ),
        W_s(x) = exp(-x^2 / (2 sigma_s^2)),  W_r(x) = exp(-x^2 / (2 sigma_r^2)),

    with areas ``A`` and centroids ``c`` fixed within an outer iteration. Vertices are then
    moved to agree with the filtered normals by the iterative scheme of Sun, Rosin, Martin,
    Langbein ("Fast and effective feature-preserving mesh denoising", IEEE TVCG 2007):
    ``x_i += 1/|F_i| sum_{f in F_i} n_f (n_f . (c_f - x_i))``.
    """
    X = V.copy()
    n = V.shape[0]
    I, J = face_neighbour_pairs(F, n)
    m = F.shape[0]
    for _ in range(iterations):
        N, A, C = face_geometry(X, F)
        s = sigma_s * mean_adjacent_centroid_distance(C, F)
        ws = A[J] * np.exp(-np.sum((C[I] - C[J]) ** 2, axis=1) / (2.0 * s * s))
        Nf = N
        for _ in range(normal_iterations):
            wr = np.exp(-np.sum((Nf[I] - Nf[J]) ** 2, axis=1) / (2.0 * sigma_r * sigma_r))
            w = ws * wr
            S = sp.csr_matrix((w, (I, J)), shape=(m, m))
            acc = S @ Nf
            nrm = np.linalg.norm(acc, axis=1, keepdims=True)
            Nf = np.divide(acc, nrm, out=Nf.copy(), where=nrm > 0)
        X = sun_vertex_update(X, F, Nf, vertex_iterations)
    return SmoothingResult(V=X)
