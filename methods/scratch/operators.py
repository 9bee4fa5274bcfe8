"""Vectorized building blocks of the discrete Laplacians: edges, cotangents, weights, masses.

All functions take ``V`` (n, 3) float64 and ``F`` (m, 3) int64 and return numpy arrays or
scipy sparse CSR matrices in libigl's sign convention (off-diagonal weights positive where
POS holds, diagonal = minus the row's off-diagonal sum).

Three assembly paths give the same matrices (to ~1e-15 relative): the vectorized numpy
functions (`cotan_weights`, `mass_matrix`, ...), a compiled one-off assembly
(`cotan_laplacian`) for large meshes, and `CotanPattern` (CSR pattern built once per
connectivity, then weights and mixed Voronoi areas written straight into it) for re-assembly.
numba is imported lazily, on the first compiled call.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from harness.core.geometry import corner_cotangents, double_areas, unique_edges
from methods.scratch.cotan_kernels import _kernel, _single_pass


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


_OUT_OF_RANGE = "face indices must lie in [0, {n}) (the number of vertices)"


class CotanPattern:
    """Sparsity pattern of the cotangent Laplacian for one connectivity ``F`` (n vertices).

    Build once (``CotanPattern(F, n)``), then `assemble` for any vertex positions with the
    same faces: only the numeric pass runs (the re-assembly benchmark). ``W`` has an entry
    for every mesh edge and every diagonal (explicit zeros where weights cancel, like
    libigl's), rows sorted by column.
    """

    def __init__(self, F: np.ndarray, n: int):
        self.F = np.ascontiguousarray(F, dtype=np.int64)
        self.n = int(n)
        if 6 * self.F.shape[0] + self.n >= 2**31 - 1:
            raise ValueError("CotanPattern uses int32 indices: at most ~357M faces; "
                             "use cotan_weights / mass_matrix for larger meshes")
        self.indptr, self.indices, self.slot, self.diag, self.Fp = _kernel("_pattern_kernel")(self.F, self.n)
        if self.indptr.size == 0:
            raise ValueError(_OUT_OF_RANGE.format(n=self.n))
        if self.indices.size < np.iinfo(np.int32).max:
            self.indptr = self.indptr.astype(np.int32)

    def assemble(self, V: np.ndarray, mass: str = "voronoi"):
        """``(W, M)``: cotangent weights (CSR) and the mass (``voronoi``/``barycentric``/``none``).

        Equal to ``cotan_weights(V, F)`` and ``mass_matrix(V, F, mass)`` to ~1e-15 relative
        (only the summation order differs). ``V`` must be (n, 3) for the pattern's n (ValueError).
        """
        V = np.ascontiguousarray(V, dtype=np.float64)
        if V.ndim != 2 or V.shape != (self.n, 3):
            raise ValueError(f"this pattern is for {self.n} vertices: V must be ({self.n}, 3), "
                             f"got {V.shape}")
        want = mass == "voronoi"
        data, area = _kernel("_numeric_kernel")(V, self.Fp, self.slot, self.diag, self.indptr,
                                                 self.indices.size, want)
        W = sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n), copy=False)
        if mass == "voronoi":
            M = _diag_csr(area)
        else:
            M = mass_matrix(V, self.F, mass)
        return W, M


def _diag_csr(a: np.ndarray) -> sp.csr_matrix:
    n = a.size
    idx = np.arange(n, dtype=np.int32)
    return sp.csr_matrix((a, idx, np.arange(n + 1, dtype=np.int32)), shape=(n, n), copy=False)


def cotan_laplacian(V: np.ndarray, F: np.ndarray, mass: str = "voronoi", pattern: CotanPattern | None = None):
    """Cotangent weights and mass matrix ``(W, M)`` from compiled passes; numba is required.

    Without ``pattern``: one assembly (`_single_pass`); with a `CotanPattern` built for
    the same ``F``: its numeric pass only. Both equal ``cotan_weights(V, F)`` and
    ``mass_matrix(V, F, mass)`` to ~1e-15 relative (summation order), rows sorted by column.
    At most ~357M faces (int32 indices). Raises ValueError for a face index outside [0, n),
    or, with ``pattern``, for a ``V`` that is not (pattern.n, 3).
    """
    if pattern is not None:
        return pattern.assemble(V, mass)
    F = np.ascontiguousarray(F, dtype=np.int64)
    n = V.shape[0]
    if 6 * F.shape[0] + n >= 2**31 - 1:
        raise ValueError("the compiled assembly uses int32 indices: at most ~357M faces; "
                         "use cotan_weights / mass_matrix for larger meshes")
    V = np.ascontiguousarray(V, dtype=np.float64)
    want = mass == "voronoi"
    csr = _single_pass(V, F, n, want)
    if csr is None:
        raise ValueError(_OUT_OF_RANGE.format(n=n))
    indptr, indices, data, area = csr
    W = sp.csr_matrix((data, indices, indptr), shape=(n, n), copy=False)
    M = _diag_csr(area) if want else mass_matrix(V, F, mass)
    return W, M
