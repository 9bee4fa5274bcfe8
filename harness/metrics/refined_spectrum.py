"""A reference spectrum for a mesh without an analytic one: the same surface, refined.

The piecewise-linear surface of a mesh is a surface of its own (flat triangles, cone points at
the vertices). Midpoint subdivision (every triangle into four, new vertices at the edge
midpoints) leaves that surface unchanged and nests the spaces of continuous piecewise-linear
functions. The eigenvalues of the conforming linear finite elements, ``K x = lambda M x`` with
``K`` the cotangent stiffness (``-W``) and ``M`` the full (consistent) FEM mass matrix
(``M_ij = A_f / 12`` per shared face off the diagonal, ``A_f / 6`` on it), are Rayleigh-Ritz
values of the surface's Laplace-Beltrami operator: by the min-max principle each is an upper
bound of the surface's exact eigenvalue of the same index, and it does not grow under a
refinement. With second-order convergence in the edge length (smooth eigenfunctions; lower
near reentrant cone points), ``lambda_L - lambda ~ (lambda_{L-1} - lambda_L) / 3``.

`refined_reference` computes the ``k`` smallest eigenvalues on the mesh refined ``L``, ``L - 1``
and (when ``L >= 2``) ``L - 2`` times, ``L`` the most levels (at least 1) whose mesh has at most
`MAX_FACES` faces, and returns the level-``L`` values as the reference with an estimate of their
own relative error, ``max_i d_i / ((q_i - 1) lambda_{L,i})`` over ``i >= 1`` (``lambda_0 = 0``:
constants), ``d_i = lambda_{L-1,i} - lambda_{L,i}``: with a convergence ratio ``q_i`` the error
left after level ``L`` is ``d_i (1/q_i + 1/q_i^2 + ...) = d_i / (q_i - 1)``. ``q_i`` is the ratio
observed for that eigenvalue, ``(lambda_{L-2,i} - lambda_{L-1,i}) / d_i``, kept within [1.25, 4]
(4 is the h^2 rate; cone points and reentrant corners lower it: a median of 3.0 on knight at k =
20, 3.2 at 200, 2.2 on an
L-shaped plane); with two levels only it is taken as 1.5 for every ``i`` (``2 d_i``), and an
eigenvalue already converged to rounding (``d_i <= 1e-12 lambda_i``) adds nothing. Eigenvalues in
1/length^2 (input units); matched to a method's by index, as the analytic spectra are. Solver:
ARPACK shift-invert below the spectrum (``sigma = -s``, ``s`` a small multiple of the smallest
positive ``K_ii / M_ii``) for ``k`` plus a margin of pairs (ARPACK may return fewer copies of an
eigenvalue of exact multiplicity than it has, e.g. on a symmetric mesh), with a single-threaded
SPD factorization of ``K + s M`` (`harness.core.solvers.factorize` with qdldl, else scipy's: the
same digits on any thread count, and no OpenMP runtime started in a forked case process, which
hangs when its parent used one), tolerance 1e-10; then Sylvester's inertia of ``K - t M`` (``t``
just below the ``k``-th value) must count exactly the values returned below ``t``, at every
level, else there is no reference. Not for a mesh of several connected pieces (each adds a zero
eigenvalue, and the matching by index would divide by rounding noise) nor when the level-``L``
values fail a sanity check (``lambda_0`` not zero to 1e-8 of ``lambda_1``, or not finite): both
give None.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

MAX_FACES = 50_000    # the finest refinement computed
MAX_K = 200           # references for at most this many eigenpairs (ARPACK keeps 2k + 1 vectors)


def midpoint_subdivide(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(V', F')``: every triangle split into four at its edge midpoints (one new vertex per
    edge, shared by its faces); the first ``len(V)`` vertices are ``V``; the surface is the same."""
    from ..core.geometry import edge_keys
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    m, n = len(F), len(V)
    keys, _ = edge_keys(F, n)                          # half-edges (0,1), (1,2), (2,0) of every face
    uniq, inv = np.unique(keys, return_inverse=True)
    mid = n + inv.reshape(3, m).T                      # (m, 3): the midpoint of edge (0,1), (1,2), (2,0)
    a, b = uniq // n, uniq % n
    Vn = np.concatenate([V, 0.5 * (V[a] + V[b])])
    e01, e12, e20 = mid[:, 0], mid[:, 1], mid[:, 2]
    Fn = np.concatenate([np.stack([F[:, 0], e01, e20], 1), np.stack([e01, F[:, 1], e12], 1),
                         np.stack([e20, e12, F[:, 2]], 1), np.stack([e01, e12, e20], 1)])
    return Vn, Fn


def fem_matrices(V: np.ndarray, F: np.ndarray) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """``(K, M)``: the cotangent stiffness (positive semi-definite, ``K = -W``) and the consistent
    FEM mass matrix of the linear elements on ``(V, F)``."""
    from ..core.geometry import corner_cotangents
    n = len(V)
    C, dbl = corner_cotangents(V, F)
    i = np.concatenate([F[:, 1], F[:, 2], F[:, 0]])   # edge opposite corner 0, 1, 2
    j = np.concatenate([F[:, 2], F[:, 0], F[:, 1]])
    w = 0.5 * np.concatenate([C[:, 0], C[:, 1], C[:, 2]])
    W = sp.coo_matrix((np.concatenate([w, w]), (np.concatenate([i, j]), np.concatenate([j, i]))), shape=(n, n)).tocsr()
    K = (sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W).tocsr()
    area = dbl / 2.0
    off = np.concatenate([area, area, area]) / 12.0
    M = sp.coo_matrix((np.concatenate([off, off]), (np.concatenate([i, j]), np.concatenate([j, i]))), shape=(n, n)).tocsr()
    diag = np.bincount(F.ravel(), weights=np.repeat(area / 6.0, 3), minlength=n)
    return K, (M + sp.diags(diag)).tocsr()


def fem_eigenvalues(V: np.ndarray, F: np.ndarray, k: int) -> np.ndarray | None:
    """The ``k`` smallest eigenvalues of ``K x = lambda M x`` (`fem_matrices`), ascending, or None
    when the inertia count says one below the ``k``-th was skipped (module docstring)."""
    from scipy.sparse.linalg import LinearOperator, eigsh

    from ..core.solvers import factorize, installed_solvers
    from ._eig_solvers import _ldlt
    K, M = fem_matrices(V, F)
    n = K.shape[0]
    d = K.diagonal() / np.maximum(M.diagonal(), 1e-300)
    s = 1e-3 * float(d[d > 0].min()) if (d > 0).any() else 1.0
    fac = factorize((K + s * M).tocsc(), "qdldl" if "qdldl" in installed_solvers() else "scipy",
                    reuse_symbolic=False)
    op = LinearOperator((n, n), matvec=lambda x: fac.solve(np.asarray(x, dtype=np.float64)).ravel(), dtype=np.float64)
    v0 = np.random.default_rng(0).standard_normal(n)
    want = min(k + max(5, k // 5), n - 2)
    lam = np.sort(eigsh(K, k=want, M=M, sigma=-s, which="LM", OPinv=op, tol=1e-10, v0=v0,
                        return_eigenvectors=False))[:k]
    t = float(lam[-1]) * (1.0 - 1e-6)
    f = _ldlt(sp.csc_matrix(K - t * M))
    if len(lam) < k or f is None or int(np.count_nonzero(f[1] < 0)) != int(np.count_nonzero(lam < t)):
        return None
    return lam


def refined_reference(V: np.ndarray, F: np.ndarray, k: int) -> dict | None:
    """``{"values", "levels", "faces", "error_est", "ratio", "observed"}`` (module docstring;
    ``ratio``: the median ``q_i``, ``observed``: whether the ratios were observed over three
    levels or taken as 1.5), or None when ``k`` is below 2 or exceeds `MAX_K`, the mesh cannot be
    refined once within `MAX_FACES` faces, ``k`` is not below the coarser refinement's vertex
    count less 2, the mesh has several connected pieces, an inertia count finds a skipped
    eigenvalue, or the values fail the sanity check."""
    from ..core.geometry import vertex_components
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    if k < 2 or k > MAX_K or 4 * len(F) > MAX_FACES or len(np.unique(vertex_components(F, len(V)))) != 1:
        return None
    levels, meshes = 0, [(V, F)]
    while 4 * len(meshes[-1][1]) <= MAX_FACES:
        meshes.append(midpoint_subdivide(*meshes[-1]))
        levels += 1
    if k >= len(meshes[-2][0]) - 2:
        return None
    used = meshes[-3:] if levels >= 2 and k < len(meshes[-3][0]) - 2 else meshes[-2:]
    lams = [fem_eigenvalues(Vi, Fi, k) for Vi, Fi in used]
    if any(lam is None for lam in lams):
        return None
    fine = lams[-1]
    if not np.isfinite(fine).all() or not (fine[1] > 0 and abs(fine[0]) <= 1e-8 * fine[1]):
        return None
    d = np.maximum(lams[-2][1:] - fine[1:], 0.0)
    q = np.full(len(d), 1.5)
    if len(lams) == 3:
        prev = lams[0][1:] - lams[1][1:]
        q = np.clip(np.divide(prev, d, out=np.full(len(d), 4.0), where=d > 0), 1.25, 4.0)
    moving = d > 1e-12 * fine[1:]
    est = float(np.max(np.where(moving, d / ((q - 1.0) * fine[1:]), 0.0)))
    ratio = float(np.median(q[moving])) if moving.any() else 4.0
    return {"values": fine, "levels": levels, "faces": int(len(meshes[-1][1])), "error_est": est, "ratio": ratio,
            "observed": len(lams) == 3}
