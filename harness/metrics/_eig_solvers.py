"""Sparse symmetric eigenvalue and inertia primitives of the PSD measure (`laplacian_properties`).

The matrices are symmetric and sparse (CSC). `_ldlt`: ``P A P^T = L D L^T`` without pivoting
(QDLDL with an AMD ordering, else SuperLU in symmetric mode), whose pivots give the inertia
(Sylvester's law); `_largest_magnitude`: ``max |eig(S)|`` (Lanczos, then a dense solver up to
`DENSE_N`); `_most_negative`: the smallest eigenvalue (Lanczos, then LOBPCG with a residual
check). Every Lanczos iteration starts from the seeded vector `_v0`, so the values are
reproducible.
"""
from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

DENSE_N = 2000           # lam_max falls back to a dense eigensolver up to this size


def _v0(n):
    return np.random.default_rng(0).standard_normal(n)


def _ldlt(A):
    """``(solve, pivots)`` of ``P A P^T = L D L^T`` without pivoting (QDLDL with an AMD ordering;
    SuperLU in symmetric mode with diagonal pivots where QDLDL is missing), or None when a pivot
    is exactly zero or SuperLU left the diagonal."""
    try:
        import qdldl
    except ImportError:
        qdldl = None
    if qdldl is not None:
        try:
            f = qdldl.Solver(sp.csc_matrix(A))
        except (ValueError, RuntimeError):
            return None
        D = f.factors()[1]
        return (None if (D == 0).any() else (f.solve, D))
    try:
        lu = sla.splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    except RuntimeError:
        return None
    if not np.array_equal(lu.perm_r, lu.perm_c):
        return None
    return lu.solve, lu.U.diagonal()



def _largest_magnitude(S, n):
    """``max |eig(S)|`` of symmetric S (CSC): Lanczos with 8 vectors, then with 32 (nearly tied
    extreme eigenvalues of opposite sign can stall the small space), then a dense solver up to
    `DENSE_N`; None when none of them gives it."""
    for ncv in dict.fromkeys((min(n - 1, 8), min(n - 1, 32))):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return float(np.abs(sla.eigsh(S, k=1, which="LM", ncv=ncv, v0=_v0(n), return_eigenvectors=False,
                                              tol=1e-6, maxiter=max(1000, 10 * n))).max())
        except (sla.ArpackNoConvergence, RuntimeError, ValueError):
            pass
    if n <= DENSE_N:
        return float(np.abs(np.linalg.eigvalsh(S.toarray())).max())
    return None


def _most_negative(S, n, lam_max):
    """Smallest (most negative) eigenvalue of symmetric S by Lanczos, then LOBPCG.

    The LOBPCG value is accepted only if its residual ``|S x - lam x|`` is below
    ``1e-6 * lam_max`` (an unconverged Rayleigh quotient is only an upper bound); else None.
    """
    try:
        return sla.eigsh(S, k=1, which="SA", ncv=min(n - 1, 8), v0=_v0(n), return_eigenvectors=False,
                         tol=1e-8, maxiter=max(2000, 20 * n))
    except sla.ArpackNoConvergence:
        pass
    rng = np.random.default_rng(0)
    X = rng.standard_normal((n, 1))
    vals, vecs = sla.lobpcg(S, X, largest=False, tol=1e-8, maxiter=2000)
    x = vecs[:, 0] / np.linalg.norm(vecs[:, 0])
    if np.linalg.norm(S @ x - vals[0] * x) > 1e-6 * lam_max:
        return None
    return vals
