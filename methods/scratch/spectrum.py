"""Laplace-Beltrami eigenpairs (task ``spectrum``): an operator, a mass and an eigensolver.

Operators (``W``, libigl's sign): ``cotan`` (cotangent weights), ``intrinsic_delaunay`` (cotangent
weights of the intrinsic Delaunay triangulation, with its own areas for the mass), ``tufted``
(our tufted-cover intrinsic Delaunay Laplacian, `methods.scratch.tufted`, Sharp & Crane 2020,
with the cover's own areas for the mass; barycentric equals robust-laplacian's), ``uniform``
(graph Laplacian ``A - D``, with the chosen mass). Masses: ``voronoi`` (mixed Voronoi, lumped), ``barycentric`` (lumped), ``fem`` (the consistent linear-FEM mass:
``M_ij = sum_f A_f (1 + delta_ij) / 12`` over the faces containing both). Solvers for the k
smallest eigenpairs of ``-W x = lambda M x``:

- ``shift_invert``: ARPACK (``scipy.sparse.linalg.eigsh``) in shift-invert mode at
  ``sigma = -1e-8 * s`` (``s`` the median of ``-W_ii / M_ii``, so ``-W - sigma M`` is SPD),
  with ``OPinv`` our prefactored SPD solve (`harness.core.solvers.factorize`; ``auto`` prefers
  the backends with the cheapest repeated solves, `many_solves_solver`); ``k + max(8, k/20)``
  pairs are computed and the smallest ``k`` kept, as ARPACK can miss members of an exactly
  degenerate multiplet (the sphere's) cut at ``k``;
- ``bands``: band-by-band shift-invert (Vallet & Levy 2008; `methods.scratch.bands`): ARPACK
  runs of 50 pairs at successive shifts through the spectrum, each shifted indefinite matrix
  factored by QDLDL, completeness certified by Sylvester inertia (the count of negative pivots);
  falls back to ``shift_invert`` when a band cannot be certified;
- ``auto``: ``bands`` for k > 100, else ``shift_invert``;
- ``dense``: LAPACK's symmetric-definite ``eigh`` on dense matrices (reference; n <= 6000).

Eigenvectors are returned M-orthonormal, eigenvalues ascending.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from harness.core.solvers import factorize
from methods import Param, SpectrumResult, register
from methods.scratch import operators as op
from methods.vocabulary import solver_param

DENSE_MAX = 6000
BAND = 50            # eigenpairs per band of the band-by-band solver
BANDS_FROM = 100     # ``auto`` uses bands above this k, one ARPACK run up to it


def fem_mass(V: np.ndarray, F: np.ndarray) -> sp.csr_matrix:
    """Consistent (full) linear-FEM mass matrix: ``A_f / 6`` on the diagonal, ``A_f / 12`` off it."""
    from harness.core.geometry import double_areas
    n = len(V)
    a = double_areas(V, F) / 2.0
    rows = np.concatenate([F[:, i] for i in range(3) for _ in range(3)])
    cols = np.concatenate([F[:, j] for _ in range(3) for j in range(3)])
    vals = np.concatenate([a * (2.0 if i == j else 1.0) / 12.0 for i in range(3) for j in range(3)])
    return sp.coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsr()


def operator_and_mass(V, F, operator: str, mass: str) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """``(W, M)`` for the chosen operator and mass (module docstring)."""
    n = len(V)
    if operator == "tufted":
        from methods.scratch.tufted import tufted_laplacian
        if mass == "fem":
            raise ValueError("mass fem is defined on the input triangulation; use voronoi or barycentric with tufted")
        return tufted_laplacian(V, F, mass)
    if operator == "intrinsic_delaunay":
        from methods.scratch.intrinsic_delaunay import intrinsic_delaunay_cotmatrix, intrinsic_mass
        W, l, Fi = intrinsic_delaunay_cotmatrix(V, F)
        if mass == "fem":
            raise ValueError("mass fem is defined on the input triangulation; use voronoi or barycentric with "
                             "intrinsic_delaunay")
        return W.tocsr(), intrinsic_mass(l, Fi, n, mass)
    W = op.uniform_weights(F, n) if operator == "uniform" else op.cotan_weights(V, F)
    M = fem_mass(V, F) if mass == "fem" else op.mass_matrix(V, F, mass)
    return W.tocsr(), M.tocsr()


SOLVE_HEAVY = ("cholespy", "qdldl", "scipy")


def many_solves_solver() -> str:
    """The backend ``auto`` means for ARPACK's OPinv: hundreds of single-vector solves per
    factorization make the per-solve cost decide, and there CHOLMOD (cholespy) and QDLDL beat
    PARDISO's multi-threaded solve (the figures: benchmarks/HISTORY.md)."""
    from harness.core.solvers import installed_solvers
    have = installed_solvers()
    return next((s for s in SOLVE_HEAVY if s in have), "auto")


def inversion_shift(W, M) -> float:
    """``sigma = -1e-8 * median(-W_ii / M_ii)``: ``-W - sigma M`` is SPD and ``sigma`` far below lambda_1."""
    d = -W.diagonal() / np.maximum(M.diagonal(), 1e-300)
    return -1e-8 * float(np.median(d[d > 0])) if (d > 0).any() else -1e-8


def smallest_eigenpairs(W, M, k: int, solver: str = "auto", linear_solver: str = "auto", seed: int = 0,
                        zeros: int | None = None):
    """(values ascending (k,), M-orthonormal vectors (n, k)) of ``-W x = lambda M x``; ``zeros``:
    the dimension of W's kernel where known (the mesh's connected components), for the bands'
    final inertia check (`methods.scratch.bands.band_eigenpairs`)."""
    from scipy.sparse.linalg import LinearOperator, eigsh
    n = W.shape[0]
    k = int(min(k, n - 1 if solver != "dense" else n))
    A = (-W).tocsr()
    sigma = inversion_shift(W, M)
    if solver == "dense":
        if n > DENSE_MAX:
            raise ValueError(f"dense eigensolver refused for n = {n} > {DENSE_MAX} vertices")
        from scipy.linalg import eigh
        lam, X = eigh(A.toarray(), M.toarray(), subset_by_index=[0, k - 1])
    elif solver == "bands" or (solver == "auto" and k > BANDS_FROM):
        from methods.scratch.bands import BandFailure, band_eigenpairs
        try:
            lam, X = band_eigenpairs(A, M, k, sigma, band=BAND, seed=seed, zeros=zeros)
        except (BandFailure, ImportError):
            return smallest_eigenpairs(W, M, k, "shift_invert", linear_solver, seed, zeros)
    elif solver in ("shift_invert", "auto"):
        fac = factorize((A - sigma * M).tocsr(), many_solves_solver() if linear_solver == "auto" else linear_solver)
        OPinv = LinearOperator((n, n), matvec=fac.solve, dtype=np.float64)
        extra = min(max(8, k // 20), n - 1 - k)       # ARPACK can miss members of a multiplet cut at k:
        lam, X = eigsh(A, k=k + extra, M=M, sigma=sigma, which="LM", OPinv=OPinv,   # ask for more, keep k
                       v0=np.random.default_rng(seed).standard_normal(n))
        order = np.argsort(lam)[:k]
        lam, X = lam[order], X[:, order]
    else:
        raise ValueError(f"unknown solver {solver!r}; expected auto, shift_invert, bands or dense")
    order = np.argsort(lam)
    lam, X = np.asarray(lam)[order], np.asarray(X)[:, order]
    X = X / np.sqrt(np.maximum(np.einsum("ij,ij->j", X, M @ X), 1e-300))
    return lam, X


@register("scratch.spectrum", task="spectrum", library="scratch",
          cite="Vallet & Levy, Spectral geometry processing with manifold harmonics, 2008 (shift-invert)",
          params={"operator": Param("operator", "cotan", choices=("cotan", "intrinsic_delaunay", "tufted", "uniform"),
                                    doc="the stiffness W (module docstring)"),
                  "mass": Param("mass", "voronoi", choices=("voronoi", "barycentric", "fem"),
                                doc="lumped mixed Voronoi, lumped barycentric, or the consistent FEM mass"),
                  "solver": Param("solver", "auto", choices=("auto", "shift_invert", "bands", "dense"),
                                  doc="eigensolver (module docstring)"),
                  "linear_solver": solver_param()})
def spectrum(V, F, *, k=20, operator="cotan", mass="voronoi", solver="auto", linear_solver="auto"):
    """The k smallest eigenpairs of the chosen operator and mass (module docstring). With the
    input triangulation's cotangents (``operator: cotan`` or ``mass: voronoi``) a zero-area face
    (cross product or Heron, `harness.core.geometry.zero_area_faces`) is a ValueError: a face
    whose cross product is 1e-18 but whose Heron area is 0 has cotangents of 1e15, and the
    factorization fails or the spectrum is meaningless; the intrinsic operators handle it."""
    if operator in ("cotan", "uniform") and (operator == "cotan" or mass == "voronoi"):
        from harness.core.geometry import zero_area_faces
        bad = zero_area_faces(V, F)
        if bad.size:
            raise ValueError(f"{bad.size} zero-area face(s) (first: {bad[:5].tolist()}): their cotangents are not "
                             "finite; use operator: intrinsic_delaunay or tufted, or remove them")
    from harness.core.geometry import referenced
    unused = np.flatnonzero(~referenced(np.asarray(F), len(V)))
    if unused.size:                     # no mass there: M is singular and the factorization fails
        raise ValueError(f"{unused.size} vertices no face uses (first: {unused[:5].tolist()}): they have no mass; "
                         "drop them first (harness.core.geometry.compact)")
    W, M = operator_and_mass(V, F, operator, mass)
    from harness.core.geometry import vertex_components
    zeros = int(len(np.unique(vertex_components(F, len(V)))))      # every vertex is in a face (above)
    lam, X = smallest_eigenpairs(W, M, k, solver, linear_solver, zeros=zeros)
    return SpectrumResult(values=lam, vectors=X, W=W, M=M)
