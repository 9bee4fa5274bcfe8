"""Vectorized building blocks of the discrete Laplacians: edges, cotangents, weights, masses.

All functions take ``V`` (n, 3) float64 and ``F`` (m, 3) int64 and return numpy arrays or
scipy sparse CSR matrices in libigl's sign convention (off-diagonal weights positive where
POS holds, diagonal = minus the row's off-diagonal sum).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp


def unique_edges(F: np.ndarray) -> np.ndarray:
    """Undirected edges (e, 2) int64 with ``E[:, 0] < E[:, 1]``, sorted lexicographically."""
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    E.sort(axis=1)
    return np.unique(E, axis=0)


def double_areas(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Twice the area of each face (m,): ``|(v1 - v0) x (v2 - v0)|``."""
    return np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)


def face_normals(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Unit face normals (m, 3) by the right-hand rule; zero rows for zero-area faces."""
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    nrm = np.linalg.norm(N, axis=1, keepdims=True)
    return np.divide(N, nrm, out=np.zeros_like(N), where=nrm > 0)


def corner_cotangents(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cotangent of each corner angle (m, 3) and the face double areas (m,).

    Corner k's angle is opposite the edge (F[:, k+1], F[:, k+2]).
    ``cot = (a . b) / |a x b|`` for the two edge vectors leaving the corner. Faces of zero
    area get cotangent 0 (they contribute nothing: the policy of PMP's clamped weights,
    which keeps W finite; libigl would produce inf/NaN there).
    """
    p0, p1, p2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    e0, e1, e2 = p2 - p1, p0 - p2, p1 - p0          # edge opposite corner k
    dbl = np.linalg.norm(np.cross(e1, e2), axis=1)
    dots = np.stack([-(e1 * e2).sum(1), -(e2 * e0).sum(1), -(e0 * e1).sum(1)], axis=1)
    safe = np.where(dbl > 0, dbl, 1.0)
    C = np.where((dbl > 0)[:, None], dots / safe[:, None], 0.0)
    return C, dbl


def assemble_weights(F: np.ndarray, half_w: np.ndarray, n: int) -> sp.csr_matrix:
    """Symmetric W from per-corner weights: corner k adds ``half_w[:, k]`` to the edge opposite.

    Off-diagonals are summed over the faces sharing an edge; diagonal = minus the row sum.
    """
    i = np.concatenate([F[:, 1], F[:, 2], F[:, 0]])
    j = np.concatenate([F[:, 2], F[:, 0], F[:, 1]])
    w = np.concatenate([half_w[:, 0], half_w[:, 1], half_w[:, 2]])
    rows = np.concatenate([i, j])
    cols = np.concatenate([j, i])
    vals = np.concatenate([w, w])
    W = sp.coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsr()
    W = W - sp.diags(np.asarray(W.sum(axis=1)).ravel())
    W.sum_duplicates()
    return W.tocsr()


def cotan_weights(V: np.ndarray, F: np.ndarray) -> sp.csr_matrix:
    """Cotangent weights ``W_ij = (cot a_ij + cot b_ij) / 2``; boundary edges carry one cotangent.

    Equals ``igl.cotmatrix(V, F)`` (Pinkall & Polthier 1993; Meyer et al. 2003).
    """
    C, _ = corner_cotangents(V, F)
    return assemble_weights(F, 0.5 * C, V.shape[0])


def adjacency(F: np.ndarray, n: int) -> sp.csr_matrix:
    """Symmetric 0/1 vertex adjacency matrix (n, n) of the mesh edges."""
    E = unique_edges(F)
    ones = np.ones(2 * len(E))
    A = sp.coo_matrix((ones, (np.r_[E[:, 0], E[:, 1]], np.r_[E[:, 1], E[:, 0]])), shape=(n, n))
    return A.tocsr()


def uniform_weights(F: np.ndarray, n: int) -> sp.csr_matrix:
    """Graph Laplacian ``W = A - diag(deg)`` (all edge weights 1)."""
    A = adjacency(F, n)
    return (A - sp.diags(np.asarray(A.sum(axis=1)).ravel())).tocsr()


def barycentric_areas(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Per-vertex barycentric area (n,): one third of each incident face's area."""
    dbl = double_areas(V, F)
    return np.bincount(F.ravel(), weights=np.repeat(dbl / 6.0, 3), minlength=V.shape[0])


def voronoi_areas(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Per-vertex mixed Voronoi area (n,) of Meyer et al. 2003, as libigl's VORONOI mass.

    Non-obtuse face: corner i gets ``(|e_ij|^2 cot_k + |e_ik|^2 cot_j) / 8`` (its part of the
    circumcentric cell). Obtuse face: the obtuse corner gets area/2, the other two area/4.
    """
    C, dbl = corner_cotangents(V, F)
    p0, p1, p2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    sq = np.stack([((p2 - p1) ** 2).sum(1), ((p0 - p2) ** 2).sum(1), ((p1 - p0) ** 2).sum(1)], 1)
    return mixed_voronoi_from_cotangents(F, C, sq, dbl, V.shape[0])


def mixed_voronoi_from_cotangents(F: np.ndarray, C: np.ndarray, sq: np.ndarray, dbl: np.ndarray,
                                  n: int) -> np.ndarray:
    """Mixed Voronoi vertex areas (n,) from corner cotangents ``C`` (m, 3), squared
    corner-opposite edge lengths ``sq`` (m, 3) and face double areas ``dbl`` (m,).

    Shared by `voronoi_areas` (extrinsic) and the intrinsic triangulation's mass.
    """
    # corner 0 touches edges opposite corners 1 (to p2) and 2 (to p1)
    vor = np.stack([sq[:, 1] * C[:, 1] + sq[:, 2] * C[:, 2],
                    sq[:, 2] * C[:, 2] + sq[:, 0] * C[:, 0],
                    sq[:, 0] * C[:, 0] + sq[:, 1] * C[:, 1]], axis=1) / 8.0
    area = dbl / 2.0
    obtuse = C < 0
    any_obtuse = obtuse.any(axis=1)
    mixed = np.where(obtuse, area[:, None] / 2.0, area[:, None] / 4.0)
    A = np.where(any_obtuse[:, None], mixed, vor)
    return np.bincount(F.ravel(), weights=A.ravel(), minlength=n)


def mass_matrix(V: np.ndarray, F: np.ndarray, kind: str = "voronoi") -> sp.csr_matrix | None:
    """Diagonal mass matrix: ``barycentric`` | ``voronoi`` (mixed, Meyer 2003) | ``none``."""
    if kind == "none":
        return None
    if kind == "barycentric":
        a = barycentric_areas(V, F)
    elif kind == "voronoi":
        a = voronoi_areas(V, F)
    else:
        raise ValueError(f"unknown mass {kind!r}; expected barycentric, voronoi or none")
    return sp.diags(a).tocsr()
