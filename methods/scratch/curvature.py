"""Discrete curvature estimators (task ``curvature``; conventions in `harness.tasks.curvature`).

- ``scratch.angle_defect``: Gaussian curvature as the angle defect over a vertex area
  (Meyer, Desbrun, Schroeder & Barr 2003, "Discrete differential-geometry operators for
  triangulated 2-manifolds"): ``K_i = (2 pi - sum_j theta_ij) / A_i`` at interior vertices and
  ``(pi - sum_j theta_ij) / A_i`` at boundary vertices (the angle defect of a boundary vertex is
  measured against a straight boundary). Summed with the same areas it satisfies the discrete
  Gauss-Bonnet theorem exactly on closed meshes: ``sum_i K_i A_i = 2 pi chi``.
- ``scratch.cotan_mean``: mean curvature from the cotan Laplacian of the positions,
  ``H n = -1/2 M^-1 W x`` (Meyer et al. 2003; ``W`` in libigl's sign convention, ``M`` the
  vertex areas), signed by the area-weighted vertex normal: ``H_i = -1/2 (M^-1 W x)_i . n_i``.
- ``scratch.quadric_fit``: principal curvatures of a least-squares quadric
  ``h(u, v) = a u^2 + b u v + c v^2 + d u + e v`` over the k-ring, in the tangent frame of the
  vertex normal, at the vertex (the origin): with the graph's fundamental forms
  ``I = [[1 + d^2, d e], [d e, 1 + e^2]]`` and ``II = [[2a, b], [b, 2c]] / sqrt(1 + d^2 + e^2)``
  the shape operator is ``-I^-1 II`` (sign: H > 0 on a sphere with outward normals), whose
  eigenvalues are ``k1 >= k2``; ``K = k1 k2``, ``H = (k1 + k2) / 2``. Neighbours whose vertex
  normal faces away from the vertex's (``n_j . n_i <= 0``, a fold) are left out when at least 5
  others remain. This is the fit of libigl's ``principal_curvature`` (Panozzo, Puppo & Rocca
  2010), whose check of facing normals it shares; libigl's eigenvalues come from a symmetrized
  ``I^-1 II`` (its (1,0) entry mirrored), so its H is the same and its K, k1, k2 differ at second
  order in the slope ``(d, e)``. Goldfeather & Interrante 2004 compare this family of fits.
  Vectorized over vertices with padded neighbourhoods.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from harness.core.geometry import boundary_vertices, corner_angles, vertex_normals
from methods import CurvatureResult, Param, register
from methods.scratch.operators import barycentric_areas, cotan_weights, voronoi_areas

_AREA = Param("area", "voronoi", choices=("voronoi", "barycentric"),
              doc="vertex area: mixed Voronoi (Meyer et al. 2003) or barycentric (one third of the incident faces)")


def _areas(V, F, kind):
    return voronoi_areas(V, F) if kind == "voronoi" else barycentric_areas(V, F)


@register("scratch.angle_defect", task="curvature", library="scratch", params={"area": _AREA},
          cite="Meyer, Desbrun, Schroeder, Barr, Discrete differential-geometry operators for triangulated "
               "2-manifolds, VisMath 2002/2003")
def angle_defect(V, F, *, area="voronoi"):
    """Gaussian curvature ``K_i = (2 pi - sum theta) / A_i`` (``pi - sum theta`` on the boundary).

    Returns ``CurvatureResult(K, area)``; ``K * area`` are the integrated angle defects.
    """
    n = V.shape[0]
    theta = np.radians(corner_angles(V, F))
    total = np.bincount(F.ravel(), weights=theta.ravel(), minlength=n)
    full = np.where(boundary_vertices(F, n), np.pi, 2 * np.pi)
    A = _areas(V, F, area)
    A = np.where(A > 0, A, 1.0)
    return CurvatureResult(K=(full - total) / A, area=A)


@register("scratch.cotan_mean", task="curvature", library="scratch",
          params={"area": _AREA,
                  "signed": Param("signed", True, id_omit_default=True, doc="H signed by the vertex normal; false: |H|, the length of "
                                                      "the mean curvature normal (no normal needed)")},
          cite="Meyer, Desbrun, Schroeder, Barr 2003 (mean curvature normal from the cotan Laplacian)")
def cotan_mean(V, F, *, area="voronoi", signed=True):
    """Signed mean curvature ``H_i = -1/2 (M^-1 W x)_i . n_i`` (module docstring), or with
    ``signed: false`` its magnitude ``|H_i| = 1/2 |(M^-1 W x)_i|``, which the task scores against
    the signed truth as any H: equal where H >= 0 (a sphere), not where H changes sign (a saddle).

    Boundary vertices get the same formula; their one-sided neighbourhoods make it unreliable
    there (the task reports boundary errors separately).
    """
    W = cotan_weights(V, F)
    A = _areas(V, F, area)
    A = np.where(A > 0, A, 1.0)
    Hn = -0.5 * (W @ V) / A[:, None]
    H = np.einsum("ij,ij->i", Hn, vertex_normals(V, F)) if signed else np.linalg.norm(Hn, axis=1)
    return CurvatureResult(H=H, area=A)


def _adjacency(F: np.ndarray, n: int) -> sp.csr_matrix:
    """Vertex adjacency (n, n) of the faces, entries 1."""
    A = sp.csr_matrix((np.ones(6 * len(F)), (np.r_[F[:, 0], F[:, 1], F[:, 2], F[:, 1], F[:, 2], F[:, 0]],
                                              np.r_[F[:, 1], F[:, 2], F[:, 0], F[:, 0], F[:, 1], F[:, 2]])),
                      shape=(n, n))
    A.data[:] = 1.0
    return A


def _grow(R: sp.csr_matrix, A: sp.csr_matrix) -> sp.csr_matrix:
    """The rows ``R`` of a k-ring reach (entries 1) grown by one ring."""
    R = (R + R @ A).tocsr()
    R.data[:] = 1.0
    return R


def _padded(R: sp.csr_matrix, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Padded neighbour indices (k, w) and validity mask of the reach rows ``R`` of the vertices
    ``rows``, each vertex itself excluded."""
    R = R.tocoo()
    keep = R.col != rows[R.row]
    R = sp.csr_matrix((np.ones(int(keep.sum())), (R.row[keep], R.col[keep])), shape=R.shape)
    counts = np.diff(R.indptr)
    w = int(counts.max()) if len(counts) else 0
    mask = np.arange(w)[None, :] < counts[:, None]
    idx = np.zeros((len(rows), w), np.int64)
    idx[mask] = R.indices
    return idx, mask


def _fit(N: np.ndarray, D: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Principal curvatures ``(k1, k2)`` (k,) of the quadric fit (`quadric_fit`) at k vertices
    with unit normals ``N`` (k, 3), over their neighbours' offsets ``D`` (k, w, 3) from the
    vertex, ``mask`` (k, w) the valid ones; 0 where fewer than 5 are valid."""
    ref = np.where(np.abs(N[:, [0]]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
    t1 = np.cross(N, ref)
    t1 /= np.maximum(np.linalg.norm(t1, axis=1, keepdims=True), 1e-300)
    t2 = np.cross(N, t1)
    u = np.einsum("nwk,nk->nw", D, t1)
    v = np.einsum("nwk,nk->nw", D, t2)
    h = np.einsum("nwk,nk->nw", D, N)
    X = np.stack([u * u, u * v, v * v, u, v], -1) * mask[..., None]   # (k, w, 5), padded rows zero
    scale = np.maximum(np.sqrt((u * u + v * v) * mask).max(axis=1), 1e-300)
    S = np.array([2.0, 2.0, 2.0, 1.0, 1.0])                          # column scaling for conditioning
    Xs = X / (scale[:, None, None] ** S)
    AtA = np.einsum("nwi,nwj->nij", Xs, Xs) + 1e-12 * np.eye(5)
    Atb = np.einsum("nwi,nw->ni", Xs, h * mask)
    coef = np.linalg.solve(AtA, Atb[..., None])[..., 0] / scale[:, None] ** S
    a, b, c, d, e = coef.T
    # the graph's fundamental forms at the origin (module docstring); det I = 1 + d^2 + e^2 = w^2.
    # Towards +N the normal curvatures are those of I^-1 II; the task's sign is their negative.
    w2 = 1.0 + d * d + e * e
    w = np.sqrt(w2)
    E, Fm, G = 1.0 + d * d, d * e, 1.0 + e * e
    L, M, Nn = 2.0 * a / w, b / w, 2.0 * c / w
    S11, S12 = (G * L - Fm * M) / w2, (G * M - Fm * Nn) / w2         # I^-1 II
    S21, S22 = (E * M - Fm * L) / w2, (E * Nn - Fm * M) / w2
    Hm = -(S11 + S22) / 2.0
    # (k1 - k2)^2 / 4 from the entries, not H^2 - K (which cancels near an umbilic point)
    disc = np.sqrt(np.maximum(0.25 * (S11 - S22) ** 2 + S12 * S21, 0.0))
    ok = mask.sum(1) >= 5
    return np.where(ok, Hm + disc, 0.0), np.where(ok, Hm - disc, 0.0)


def _facing(N: np.ndarray, idx: np.ndarray, mask: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """``mask`` without the neighbours whose normal faces away from their vertex's
    (``N[j] . N[i] <= 0``) in the rows where at least 5 others remain (libigl's check)."""
    keep = mask & (np.einsum("nwk,nk->nw", N[idx], N[rows]) > 0)
    use = keep.sum(1) >= 5
    return np.where(use[:, None], keep, mask)


@register("scratch.quadric_fit", task="curvature", library="scratch",
          params={"rings": Param("rings", 2, "int", low=1, high=5, doc="neighbourhood: k-ring of each vertex")},
          cite="Panozzo, Puppo, Rocca, Efficient multi-scale curvature and crease estimation, 2010 (the fit of "
               "libigl's principal_curvature); Goldfeather & Interrante, ACM TOG 2004, compare such fits")
def quadric_fit(V, F, *, rings=2):
    """Principal curvatures of a local quadric fitted over the ``rings``-ring (module docstring).

    ``libigl.principal_curvature`` fits the same quadric over the same k-ring (its ``radius`` =
    ``rings``) with the same check of facing normals: H, the trace of the shape operator, is the
    same at every vertex (to 5e-10 of max |H| on the knight and the noisy bunny; 6e-7 on the open
    camelhead, whose fits are ill-conditioned: normal equations here, an SVD there). Its K, k1 and
    k2 come from a symmetrized ``I^-1 II`` and differ where the fitted slope is large (up to 0.5 of
    max |K| on the knight at radius 5; 2e-10 on an icosphere); ours are the fitted graph's own
    (Monge-patch formulas, tested). The defaults differ (2 rings here, radius 5 there): default
    rows compare neighbourhood sizes as much as implementations (``configs/curvature.yaml`` runs
    both at 2 and 5).

    A vertex with fewer than 5 neighbours in its ``rings``-ring (too few for the fit) gets the
    fit of the ring widened one step at a time until it has them. Precondition: every vertex in
    a face has 5 other vertices in its connected component (a smaller component, e.g. a lone
    tetrahedron, raises ValueError: no fit exists there). Vertices in no face get 0.
    """
    n = V.shape[0]
    N = vertex_normals(V, F)
    A = _adjacency(F, n)
    R = A.copy()
    for _ in range(int(rings) - 1):
        R = _grow(R, A)
    idx, mask = _padded(R, np.arange(n))
    k1, k2 = _fit(N, V[idx] - V[:, None, :], _facing(N, idx, mask, np.arange(n)))
    few = np.flatnonzero(mask.sum(1) < 5)
    if few.size:                        # widen the ring of those rows alone until the fit is determined
        used = np.zeros(n, bool)
        used[np.asarray(F).ravel()] = True
        few = few[used[few]]                          # vertices in no face: 0
        Rf = R[few]
        while few.size:
            count = np.diff(Rf.indptr)
            Rf = _grow(Rf, A)
            grown = np.diff(Rf.indptr)
            done = grown - 1 >= 5                     # (the vertex itself is in its reach)
            stuck = ~done & (grown == count)
            if stuck.any():
                raise ValueError(f"{int(stuck.sum())} vertices lie in connected components of fewer than 6 "
                                 "vertices: a quadric fit needs 5 neighbours")
            if done.any():
                i, m = _padded(Rf[done], few[done])
                k1[few[done]], k2[few[done]] = _fit(N[few[done]], V[i] - V[few[done]][:, None, :],
                                                    _facing(N, i, m, few[done]))
            few, Rf = few[~done], Rf[~done]
    return CurvatureResult(K=k1 * k2, H=(k1 + k2) / 2, k1=k1, k2=k2)
