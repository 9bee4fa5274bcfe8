"""Wardetzky et al. (2007) properties of a discrete Laplacian, measured on its weights.

One public function, `laplacian_properties`. Definitions, for ``W`` in libigl's sign convention (off-diagonal weights, rows sum to zero)
and ``M`` diagonal (or None):

``sym_error``
    ``max |W - W^T| / max |W|``. ``SYM`` is ``sym_error <= SYM_TOL``.
``loc_violations``
    number of stored off-diagonal entries ``(i, j)`` (directed, so a symmetric pair counts
    twice) with ``|W_ij| > ZERO_TOL * max|W|`` between vertices that share no edge of ``F``.
    ``LOC`` is ``loc_violations == 0``.
``lin_error``
    only for planar meshes: ``max_i |(W X)_i| / (max|W| * diag)`` over interior vertices i
    (referenced, not on a boundary or non-manifold edge), with ``X`` (n, 2) the coordinates
    in the mesh plane (principal axes of the referenced vertices) and ``diag`` the bounding
    box diagonal of the referenced vertices (world axes, as everywhere in the contract: a
    rotation of the mesh changes ``lin_error`` by the ratio of the diagonals, never the LIN
    flag); ``|.|`` is the Euclidean norm of the 2-vector.
    ``LIN`` is ``lin_error <= LIN_TOL``. Both None (blank) for non-planar meshes.
``neg_weights``
    fraction of off-diagonal weights with ``W_ij < -ZERO_TOL * max|W|``, out of the directed
    vertex pairs that are mesh edges or carry a significant weight (``2 * #edges +
    loc_violations``), so explicit zeros in the storage (libigl keeps them, scipy
    arithmetic drops them) do not change the value.
    ``POS`` is "no such entry" (Wardetzky's w_ij >= 0).
``min_eig``
    for a symmetric W (SYM): smallest eigenvalue of ``S = -(W + W^T) / 2`` divided by the largest
    eigenvalue magnitude of ``S`` (dimensionless, so meshes and operators compare), and ``psd``
    is ``min_eig >= -PSD_TOL``. For a non-symmetric W, ``psd`` means that every eigenvalue of
    ``-W`` has a non-negative real part (what keeps diffusion ``x' = W x`` stable), decided by an
    exact certificate or left blank (see `_nonsymmetric_psd`): the symmetric part alone would
    call a stable operator indefinite. How the symmetric case is computed (no dense eigensolver):

    0. Two cheap exact certificates come first, at any size. Diagonal dominance: if ``S`` has a
       non-negative diagonal and ``S_ii >= sum_j |S_ij|`` to rounding (e.g. any symmetric W with
       POS), Gershgorin gives ``psd`` True. Triangle split: ``S`` is written as a sum of 3x3
       triangle Laplacians plus remainders, and ``lambda_min(S) >= -max_i sigma_i`` with
       ``sigma_i`` the negative parts of the pieces at vertex i and their rounding
       (`harness.metrics._psd_kernel`; exactly semi-definite pieces for any cotangent
       Laplacian); ``psd`` is True when ``max sigma <= PSD_TOL * max_i S_ii`` (a lower bound of
       the largest eigenvalue). Either certificate settles ``min_eig`` only when, moreover,
       ``S 1 = 0`` (every row sums to zero within ``1e-10 * max |S_ii|``): then the constant
       vector bounds it from above, so ``min_eig`` lies within ``[-PSD_TOL, 1e-10]`` and is
       reported as 0. Otherwise the steps below run.
    1. ``lam_max = max |eig(S)|`` by ARPACK Lanczos (``eigsh``, ``which='LM'``, tol 1e-6; fast,
       extreme eigenvalue). Small Krylov spaces (``ncv=8``) are used throughout; where this one
       does not converge (nearly tied extreme eigenvalues), 32 vectors, then a dense solver up
       to `DENSE_N` vertices; beyond, ``min_eig`` is blank and ``lam_max`` is replaced by its
       Gershgorin bound in ``sigma`` only.
    2. ``A = S - sigma I`` with ``sigma = -PSD_TOL * lam_max`` is factorised as
       ``P A P^T = L D L^T`` without pivoting (QDLDL, AMD ordering; SuperLU in ``SymmetricMode``
       with ``diag_pivot_thresh=0`` if QDLDL is missing). By Sylvester's law of inertia the
       number of negative pivots is the number of eigenvalues of ``S`` below ``sigma``, so
       ``psd`` is exact up to rounding of the factorisation, not an iterative guess.
    3. If no pivot is negative, the smallest eigenvalue is the one nearest ``sigma``:
       shift-invert ``eigsh`` reusing the factorisation. Otherwise the most negative
       eigenvalue is found with ``eigsh(which='SA')`` (Lanczos), falling back to LOBPCG.
    If the factorisation is not symmetric (SuperLU had to pivot off the diagonal), fails, or
    the iteration does not converge, the unmeasurable values are None (blank), never guessed.
    Above ``EIG_MAX_N`` vertices (200k) steps 1-3 are not attempted (the factorisation's fill
    grows too large: see benchmarks/bench_laplacian.py): there a matrix that a certificate of
    step 0 finds semi-definite but whose rows do not sum to zero gets ``psd`` True and
    ``min_eig`` None; any other gets both None (not measured, never guessed).
    Every Lanczos iteration starts from a seeded vector, so ``min_eig`` is reproducible.
``nnz``
    number of stored entries of ``W`` that are non-zero (explicit zeros not counted).
``operator_symmetric``
    whether the pointwise operator ``M^-1 W`` is symmetric: ``max |W_ij/m_i - W_ji/m_j|``
    over stored entries, divided by ``max |M^-1 W|``, is ``<= SYM_TOL``. ``M = None`` means
    the identity. Vertices with ``m_i = 0`` and an all-zero row are ignored (unreferenced);
    ``m_i = 0`` with a non-zero row makes it None (``M^-1 W`` undefined).

Tolerances (all relative, see the constants below): ``SYM_TOL = 1e-10`` (assembly sums the
two half-edge contributions in different orders: differences ~1e-16 relative),
``ZERO_TOL = 1e-12`` (a weight whose magnitude is below this fraction of the largest is
rounding noise, e.g. the cotangent of an exact right angle on a cocircular quad),
``LIN_TOL = 1e-9`` (W X at an interior vertex of an exactly planar cotangent mesh is
~1e-15 relative; needle triangles raise it but far below 1e-9), ``PSD_TOL = 1e-10``,
planarity: every referenced vertex within ``PLANAR_TOL = 1e-9 * diag`` of its best-fit plane.

A ``W`` holding NaN or inf (e.g. libigl on a zero-area face) gets ``nnz``, ``loc_violations``
and ``LOC`` from its pattern and None for every value-based column.

Reference: Wardetzky, Mathur, Kaelberer & Grinspun 2007, "Discrete Laplace operators: no free
lunch", Symposium on Geometry Processing.
"""
from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from ..core.geometry import referenced
from ._edge_pattern import _boundary_vertices, _edge_keys, _isin_sorted
from ._eig_solvers import DENSE_N, _largest_magnitude, _ldlt, _most_negative, _v0  # noqa: F401

__all__ = ["COLUMNS", "DENSE_N", "EIG_MAX_N", "LIN_TOL", "PLANAR_TOL", "PSD_TOL", "SYM_TOL", "ZERO_TOL",
           "laplacian_properties"]

SYM_TOL = 1e-10
ZERO_TOL = 1e-12
LIN_TOL = 1e-9
PSD_TOL = 1e-10
PLANAR_TOL = 1e-9
EIG_MAX_N = 200_000

COLUMNS = ("sym_error", "loc_violations", "lin_error", "neg_weights", "min_eig", "psd", "nnz",
           "SYM", "LOC", "LIN", "POS", "operator_symmetric")


def laplacian_properties(W, M, V, F, planar: bool | None = None, mesh: dict | None = None) -> dict:
    """Measure SYM, LOC, LIN, POS, PSD and pointwise symmetry of a Laplacian.

    Parameters
    ----------
    W : scipy sparse (n, n)
        Weights, libigl's sign convention.
    M : scipy sparse (n, n) diagonal, or None
        Mass matrix; None means the identity.
    V : (n, 3) float64
        Vertex positions (LIN uses them on planar meshes; lengths relative to the bbox diagonal).
    F : (m, 3) int
        Triangles of the input mesh (define the edges for LOC and the boundary for LIN).
    planar : bool or None
        True/False to force; None detects planarity (see module docstring).
    mesh : dict or None
        Terms of F alone (the sorted directed edge keys), kept in this dict: pass the same dict
        for every Laplacian of one mesh (e.g. a per-input fact) and they are computed once.

    Returns
    -------
    dict
        Exactly the keys in `COLUMNS`; numbers as Python floats/ints, flags as bool, None
        where a value could not be measured or does not apply. Definitions and tolerances:
        module docstring.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    n = V.shape[0]
    W = sp.csr_matrix(W, dtype=np.float64)
    if W.shape != (n, n):
        raise ValueError(f"W has shape {W.shape}, expected ({n}, {n})")
    W.sum_duplicates()
    out = dict.fromkeys(COLUMNS)
    finite = bool(np.isfinite(W.data).all())

    # ---- pattern: nnz and locality (structure of W vs the mesh edges)
    rows = np.repeat(np.arange(n), np.diff(W.indptr))
    cols = W.indices
    vals = W.data
    offd = rows != cols
    wmax = float(np.abs(vals[np.isfinite(vals)]).max()) if vals.size and np.isfinite(vals).any() else 0.0
    out["nnz"] = int(np.count_nonzero(vals))
    significant = ~np.isfinite(vals) | (np.abs(vals) > ZERO_TOL * wmax)
    mesh = {} if mesh is None else mesh
    if "edge_keys" not in mesh:
        mesh["edge_keys"] = _edge_keys(F, n)
    edge_keys = mesh["edge_keys"]
    cand = offd & significant
    keys = rows[cand] * np.int64(n) + cols[cand]
    out["loc_violations"] = int(np.count_nonzero(~_isin_sorted(keys, edge_keys)))
    out["LOC"] = out["loc_violations"] == 0
    if not finite or wmax == 0.0:
        if finite:  # the zero matrix: symmetric, positive, local, linear-precise trivially
            out.update(sym_error=0.0, neg_weights=0.0, SYM=True, POS=True)
        return out

    # ---- symmetry of the weights
    WT = W.T.tocsr()                         # the transpose once, for SYM, the operator and S
    D = W - WT
    out["sym_error"] = float(abs(D).max()) / wmax if D.nnz else 0.0
    out["SYM"] = out["sym_error"] <= SYM_TOL

    # ---- positivity (denominator independent of explicit zeros in the storage)
    n_mesh_edges = int(np.count_nonzero((edge_keys // n) != (edge_keys % n)))   # directed, no self-loops
    n_off = n_mesh_edges + out["loc_violations"]
    n_neg = int(np.count_nonzero(offd & (vals < -ZERO_TOL * wmax)))
    out["neg_weights"] = n_neg / n_off if n_off else 0.0
    out["POS"] = n_neg == 0

    # ---- linear precision on planar meshes
    used = referenced(F, n)
    P = V[used]
    lo, hi = P.min(0), P.max(0)
    diag = float(np.linalg.norm(hi - lo))
    if diag > 0 and P.shape[0] >= 3:
        c = P.mean(0)
        _, s, vt = np.linalg.svd(P - c, full_matrices=False)
        dist = np.abs((P - c) @ vt[2])
        is_planar = bool(dist.max() <= PLANAR_TOL * diag) if planar is None else bool(planar)
        if is_planar:
            X = (V - c) @ vt[:2].T
            X[~used] = 0.0
            interior = used & ~_boundary_vertices(F, n)
            if interior.any():
                R = W @ X
                err = np.linalg.norm(R[interior], axis=1).max()
                out["lin_error"] = float(err) / (wmax * diag)
                out["LIN"] = out["lin_error"] <= LIN_TOL

    # ---- pointwise operator symmetry
    out["operator_symmetric"] = _operator_symmetric(W, M, rows, cols, vals, WT)

    # ---- semi-definiteness
    if out["SYM"]:
        out["min_eig"], out["psd"] = _min_eig(W, V, F, WT)
    else:
        out["min_eig"], out["psd"] = _nonsymmetric_psd(W, n, V, F)
    return out


def _nonsymmetric_psd(W, n, V, F):
    """(min_eig, psd) for a non-symmetric W: psd means every eigenvalue of -W has a non-negative
    real part. Two exact certificates, else (None, None):

    1. ``W = D^-1 S`` with D positive diagonal and S symmetric (e.g. row-normalised cotangent
       weights): -W is similar to ``-D^-1/2 S D^-1/2``, so its eigenvalues are real and have the
       inertia of -S; ``min_eig`` is then that of S (same sign, relative to S's scale).
    2. -W has a non-negative diagonal and is row diagonally dominant (e.g. positive mean value
       weights): by Gershgorin every eigenvalue has a non-negative real part; ``min_eig`` is 0
       when the rows sum to zero (the constant vector), else None.
    """
    d = _symmetrizer(W, n)
    if d is not None:
        S = sp.diags(d) @ W
        S = ((S + S.T) * 0.5).tocsr()
        return _min_eig(S, V, F)
    A = (-W).tocsr()
    diag = A.diagonal()
    off = np.asarray(abs(A).sum(axis=1)).ravel() - np.abs(diag)
    scale = float(np.abs(diag).max()) if diag.size else 0.0
    if scale == 0.0:
        return 0.0, True
    tol = 1e-12 * scale
    if np.all(diag >= -tol) and np.all(diag - off >= -tol * np.maximum(1.0, off / scale)):
        rowsum = float(np.abs(np.asarray(A.sum(axis=1)).ravel()).max())
        return (0.0 if rowsum <= 1e-10 * scale else None), True
    return None, None


def _symmetrizer(W, n):
    """Positive ``d`` (n,) with ``diag(d) W`` symmetric to SYM_TOL, or None.

    ``d_i W_ij = d_j W_ji`` on every stored pair fixes ``log d_j - log d_i = log(W_ij / W_ji)``:
    solved by least squares on the pairs' graph and accepted only if ``diag(d) W`` is symmetric.
    """
    C = sp.coo_matrix(W)
    off = C.row != C.col
    i, j, v = C.row[off], C.col[off], C.data[off]
    wmax = float(np.abs(v).max()) if v.size else 0.0
    if wmax == 0.0:
        return None
    sig = np.abs(v) > ZERO_TOL * wmax
    i, j, v = i[sig], j[sig], v[sig]
    T = sp.csr_matrix((v, (j, i)), shape=(n, n))             # T[i, j] = W[j, i]
    vt = np.asarray(T[i, j]).ravel()
    if np.any(vt == 0) or np.any(np.sign(vt) != np.sign(v)):
        return None                                           # W_ij and W_ji must share sign and support
    up = i < j
    i, j, r = i[up], j[up], np.log(v[up] / vt[up])
    G = sp.csr_matrix((np.r_[-np.ones(i.size), np.ones(i.size)],
                       (np.r_[np.arange(i.size), np.arange(i.size)], np.r_[i, j])), shape=(i.size, n))
    G = sp.vstack([G, sp.csr_matrix((np.ones(1), ([0], [0])), shape=(1, n))]).tocsr()   # gauge: log d_0 = 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        x = sla.lsqr(G, np.r_[r, 0.0], atol=1e-14, btol=1e-14, iter_lim=20 * n)[0]
    d = np.exp(x - x.max())
    S = sp.diags(d) @ W
    smax = float(abs(S).max())
    D = S - S.T
    if smax == 0 or (D.nnz and float(abs(D).max()) > SYM_TOL * smax):
        return None
    return d


def _operator_symmetric(W, M, rows, cols, vals, WT):
    if M is None:
        m = np.ones(W.shape[0])
    else:
        m = np.asarray(sp.csr_matrix(M).diagonal(), dtype=np.float64)
        if not np.isfinite(m).all():
            return None
    zero_mass = m == 0
    if zero_mass.any():
        row_nz = np.diff(W.indptr) > 0
        if (zero_mass & row_nz).any() and np.any(np.abs(vals[zero_mass[rows]]) > 0):
            return None
    minv = np.divide(1.0, m, out=np.zeros_like(m), where=~zero_mass)
    Lop = sp.csr_matrix((vals * minv[rows], cols, W.indptr), shape=W.shape)      # diag(minv) W, same pattern
    lmax = float(abs(Lop).max()) if Lop.nnz else 0.0
    if lmax == 0.0:
        return True
    LopT = sp.csr_matrix((WT.data * minv[WT.indices], WT.indices, WT.indptr), shape=W.shape)   # (M^-1 W)^T
    D = Lop - LopT
    err = float(abs(D).max()) / lmax if D.nnz else 0.0
    return bool(err <= SYM_TOL)


def _certificate(S, V, F):
    """Step 0 of the module docstring for ``S`` (CSR, symmetric, explicit zeros removed):
    ``(psd, rows_sum_to_zero)``, ``psd`` True when diagonal dominance or the triangle split
    proves ``lambda_min(S) >= -PSD_TOL * lambda_max(S)``, else None."""
    d = S.diagonal()
    scale = float(np.abs(d).max()) if d.size else 0.0
    if scale == 0.0 or not np.isfinite(S.data).all():
        return None, False
    rowsum = np.abs(np.asarray(S.sum(axis=1)).ravel()).max()
    zero_rows = bool(rowsum <= 1e-10 * scale)
    absrow = np.asarray(abs(S).sum(axis=1)).ravel() - np.abs(d)
    tol = 1e-12 * scale
    if np.all(d >= -tol) and np.all(d - absrow >= -tol * np.maximum(1.0, absrow / scale)):
        return True, zero_rows
    dmax = float(d.max())
    if dmax <= 0.0 or len(F) == 0:
        return None, zero_rows
    from ._psd_kernel import face_split_bound
    S = S.tocsr()
    if not S.has_sorted_indices:
        S = S.sorted_indices()
    k = np.frexp(dmax)[1]                   # S 2^-k: diagonal near 1, scaled exactly
    sigma, _ = face_split_bound(S.indptr.astype(np.int64, copy=False), S.indices.astype(np.int64, copy=False),
                                np.ldexp(S.data, -k), np.ascontiguousarray(V, dtype=np.float64),
                                np.ascontiguousarray(F, dtype=np.int64))
    return (True if float(sigma.max()) <= PSD_TOL * np.ldexp(dmax, -k) else None), zero_rows


def _min_eig(W, V, F, WT=None):
    """(min_eig relative, psd) of S = -(W + W^T)/2 (``WT``: W^T in CSR, when known); None where
    not measurable."""
    n = W.shape[0]
    S = (-(W + (W.T if WT is None else WT)) * 0.5).tocsr()
    S.eliminate_zeros()
    if S.nnz == 0:
        return 0.0, True
    psd, zero_rows = _certificate(S, V, F)
    if psd and zero_rows:
        return 0.0, True
    if n > EIG_MAX_N:
        return None, psd
    S = S.tocsc()
    if n < 3:  # ARPACK needs k < n; tiny matrices are done densely
        ev = np.linalg.eigvalsh(S.toarray())
        lam = np.abs(ev).max()
        return float(ev.min() / lam), bool(ev.min() >= -PSD_TOL * lam)
    lam_max = _largest_magnitude(S, n)
    scale = lam_max if lam_max is not None else float(abs(S).sum(axis=1).max())   # Gershgorin: >= the true one
    if scale == 0.0:
        return 0.0, True
    sigma = -PSD_TOL * scale
    A = (S - sigma * sp.identity(n, format="csc")).tocsc()
    factored = _ldlt(A)
    if factored is None:            # singular pivot or a non-symmetric pivot order: inertia unknown
        return None, None
    solve, piv = factored
    if not np.isfinite(piv).all():
        return None, None
    n_below = int(np.count_nonzero(piv < 0))
    psd = n_below == 0
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if psd:
                op = sla.LinearOperator(A.shape, matvec=solve, dtype=np.float64)
                ev = sla.eigsh(S, k=1, sigma=sigma, OPinv=op, which="LM", ncv=min(n - 1, 8), v0=_v0(n),
                               return_eigenvectors=False, tol=1e-10, maxiter=1000)
            else:
                ev = _most_negative(S, n, scale)
    except (sla.ArpackNoConvergence, RuntimeError, ValueError, np.linalg.LinAlgError):
        return None, psd
    if ev is None:
        return None, psd
    lam_min = float(np.min(ev))
    if not psd and lam_min >= sigma:  # iteration disagrees with the exact inertia count
        return None, psd
    return (lam_min / lam_max if lam_max is not None else None), psd
