"""Discrete Laplace operators written from scratch (task ``laplacian``).

Every method returns ``LaplacianResult(W, M)`` in libigl's sign convention: ``W`` is scipy
sparse CSR (n, n) whose off-diagonal entries are the edge weights (positive where Wardetzky
et al.'s POS holds) and whose rows sum to zero; ``M`` is a diagonal mass matrix or None.
The pointwise operator is ``M^-1 W`` (``W`` itself when ``M`` is None).

Degenerate triangles (policy shared by every operator here)
-----------------------------------------------------------
A face of zero area (collinear corners or a repeated vertex) contributes nothing: its
cotangents, its mean-value half-angle tangents and its area are set to 0, so ``W`` and ``M``
stay finite (the clamping policy of PMP; libigl returns inf/NaN on such faces). Needles
(tiny but non-zero area) are kept: their weights are large but finite. Zero here means a cross
product of exactly 0: a numerically flat face (a corner at the rounded midpoint of the opposite
edge: a cross product of rounding size, 1e-18, and a Heron area of exactly 0, which libigl and
`harness.core.geometry.zero_area_faces` count as zero-area) is kept as a needle, with weights
up to ~1e15 that make every solve with the operator ill-conditioned. Edges of zero length
contribute nothing to the mean value weights (the ``1/|x_i - x_j|`` factor would be inf).
Unreferenced vertices get an empty row/column (and zero mass).

References
----------
Pinkall & Polthier 1993, "Computing discrete minimal surfaces and their conjugates".
Meyer, Desbrun, Schroeder & Barr 2003, "Discrete differential-geometry operators for
triangulated 2-manifolds" (mixed Voronoi areas).
Floater 2003, "Mean value coordinates".
Bobenko & Springborn 2007, "A discrete Laplace-Beltrami operator for simplicial surfaces";
Fisher, Springborn, Bobenko & Schroeder 2006, "An algorithm for the construction of intrinsic
Delaunay triangulations with applications to digital geometry processing".
Wardetzky, Mathur, Kaelberer & Grinspun 2007, "Discrete Laplace operators: no free lunch".
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from methods import LaplacianResult, Param, register
from methods.scratch import operators as op

# scratch.cotan switches to the compiled single-pass assembly from this many faces on
FAST_MIN_FACES = 20_000

_MASS = Param("mass", "voronoi", choices=("barycentric", "voronoi", "none"),
              doc="diagonal mass matrix: barycentric (1/3 of incident face areas), voronoi "
                  "(mixed Voronoi area, Meyer et al. 2003, = libigl VORONOI) or none (M=None)")


@register("scratch.uniform", task="laplacian", library="scratch")
def uniform(V, F):
    """Graph (combinatorial) Laplacian: ``W = A - diag(deg)``, ``M = I``.

    Parameters
    ----------
    V : (n, 3) float64
        Vertex positions (only n is used).
    F : (m, 3) int64
        Triangles.

    Returns
    -------
    LaplacianResult
        ``W_ij = 1`` for every mesh edge ij, ``W_ii = -deg(i)``; ``M`` the identity.

    Notes
    -----
    The weights are symmetric (SYM holds) and positive (POS), local (LOC), but the operator
    is not linear-precise (LIN fails on irregular planar meshes: ``sum_j (x_j - x_i)`` is the
    difference between the centroid of the one-ring and ``x_i``, zero only for symmetric rings).
    """
    n = V.shape[0]
    return LaplacianResult(W=op.uniform_weights(F, n), M=sp.identity(n, format="csr"))


@register("scratch.umbrella", task="laplacian", library="scratch")
def umbrella(V, F):
    """Umbrella operator: uniform weights with ``M = diag(deg)``, i.e. ``L = D W``, ``D = 1/N_i``.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64

    Returns
    -------
    LaplacianResult
        ``W`` as in `uniform` (symmetric), ``M = diag(deg(i))``. Isolated (unreferenced)
        vertices get mass 1 so that ``M`` stays invertible.

    Notes
    -----
    ``(M^-1 W f)_i = (1/N_i) sum_j (f_j - f_i)``, the "uniform Laplacian" of the lecture notes.
    The weights ``W`` are symmetric; only the pointwise operator ``M^-1 W`` is not
    (``operator_symmetric`` false on irregular meshes). This is why lecture tables list the
    uniform Laplacian as "not symmetric".
    """
    n = V.shape[0]
    W = op.uniform_weights(F, n)
    deg = -W.diagonal()
    deg = np.where(deg > 0, deg, 1.0)
    return LaplacianResult(W=W, M=sp.diags(deg).tocsr())


@register("scratch.cotan", task="laplacian", library="scratch", params={"mass": _MASS})
def cotan(V, F, *, mass="voronoi"):
    """Cotangent Laplacian: ``W_ij = (cot a_ij + cot b_ij) / 2``; boundary edges carry one cotangent.

    Parameters
    ----------
    V : (n, 3) float64
        Vertex positions.
    F : (m, 3) int64
        Triangles.
    mass : {"voronoi", "barycentric", "none"}
        Diagonal mass matrix (area units): mixed Voronoi (Meyer et al. 2003, equal to
        ``igl.massmatrix(..., MASSMATRIX_TYPE_VORONOI)``), barycentric (a third of each incident
        face's area) or none (``M = None``).

    Returns
    -------
    LaplacianResult
        ``W == igl.cotmatrix(V, F)`` (to ~1e-12 relative on the bundled meshes), ``M`` as chosen.

    Notes
    -----
    a_ij, b_ij are the angles opposite edge ij in its two faces (Pinkall & Polthier 1993).
    Weights are dimensionless; ``M^-1 W`` has units 1/length^2. SYM, LOC, LIN hold; POS holds
    exactly on Delaunay meshes without obtuse boundary angles (a boundary edge's weight is one
    cotangent: negative opposite an obtuse angle, e.g. woody, Delaunay but with 178 obtuse
    corners on its boundary). Zero-area faces contribute nothing (module docstring).

    Implementation: below ``FAST_MIN_FACES`` faces, vectorized numpy (`operators.cotan_weights`,
    `operators.mass_matrix`); from there on, one compiled assembly that writes the CSR rows and
    the Voronoi areas directly (`operators.cotan_laplacian`; benchmarks/bench_laplacian.py
    compares it with libigl). Both agree to ~1e-15 relative. The threshold keeps the one-off
    numba compilation away from small meshes.
    """
    m = F.shape[0]
    if m >= FAST_MIN_FACES and 6 * m + V.shape[0] < 2**31 - 1:
        W, M = op.cotan_laplacian(V, F, mass)
        return LaplacianResult(W=W, M=M)
    W = op.cotan_weights(V, F)
    return LaplacianResult(W=W, M=op.mass_matrix(V, F, mass))


@register("scratch.cotan_normalized", task="laplacian", library="scratch")
def cotan_normalized(V, F):
    """Row-normalized cotangent weights: ``W_ij = w_ij / sum_k w_ik``, ``W_ii = -1``, ``M = None``.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64

    Returns
    -------
    LaplacianResult
        ``(W f)_i = sum_j w_ij (f_j - f_i) / sum_j w_ij`` with ``w_ij`` the cotangent weights,
        the update direction of explicit smoothing with "normalized weights and no area term"
        (Bommes' geometry processing lecture); ``M = None``.

    Notes
    -----
    Not symmetric (rows are scaled differently); LIN holds (a scaled row of the cotangent
    operator still annihilates linear functions); POS fails wherever cotangent weights are
    negative. Policy for rows whose weight sum is not positive (``sum <= 1e-12 * max|w|``: an
    isolated vertex, or negative cotangents cancelling the positive ones): the row is left as
    the plain cotangent row (no scaling), so W stays finite and its rows still sum to zero.
    """
    W = op.cotan_weights(V, F)
    s = -W.diagonal()
    wmax = float(abs(W).max()) if W.nnz else 0.0
    ok = s > 1e-12 * wmax
    scale = np.where(ok, 1.0 / np.where(ok, s, 1.0), 1.0)
    return LaplacianResult(W=sp.diags(scale) @ W, M=None)


def mean_value_weights(V: np.ndarray, F: np.ndarray) -> sp.csr_matrix:
    """Floater's mean value weights ``w_ij = (tan(d_ij/2) + tan(g_ij/2)) / |x_i - x_j|``.

    ``d_ij`` and ``g_ij`` are the angles at ``x_i`` of the two faces sharing edge ij (one on the
    boundary). ``tan(a/2) = |u x v| / (|u||v| + u . v)`` for the edge vectors u, v leaving the
    corner, which avoids evaluating the angle. Zero-area corners (angle 0 or pi, or a
    repeated vertex) and zero-length edges contribute 0. Rows sum to zero (diagonal = minus
    the row sum); the matrix is not symmetric.
    """
    n = V.shape[0]
    i = np.concatenate([F[:, 0], F[:, 1], F[:, 2]])
    j = np.concatenate([F[:, 1], F[:, 2], F[:, 0]])
    k = np.concatenate([F[:, 2], F[:, 0], F[:, 1]])
    u = V[j] - V[i]
    v = V[k] - V[i]
    lu = np.linalg.norm(u, axis=1)
    lv = np.linalg.norm(v, axis=1)
    cr = np.linalg.norm(np.cross(u, v), axis=1)
    den = lu * lv + (u * v).sum(1)
    ok = (cr > 0) & (den > 0)
    t = np.where(ok, cr / np.where(ok, den, 1.0), 0.0)          # tan(angle_i / 2)
    wu = np.where(lu > 0, t / np.where(lu > 0, lu, 1.0), 0.0)   # to j
    wv = np.where(lv > 0, t / np.where(lv > 0, lv, 1.0), 0.0)   # to k
    rows = np.concatenate([i, i])
    cols = np.concatenate([j, k])
    vals = np.concatenate([wu, wv])
    keep = rows != cols
    W = sp.csr_matrix((vals[keep], (rows[keep], cols[keep])), shape=(n, n))
    W = W - sp.diags(np.asarray(W.sum(axis=1)).ravel())
    return W.tocsr()


@register("scratch.mean_value", task="laplacian", library="scratch")
def mean_value(V, F):
    """Floater's mean value Laplacian (Floater 2003), ``M = None``.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64

    Returns
    -------
    LaplacianResult
        ``W_ij = (tan(d_ij/2) + tan(g_ij/2)) / |x_i - x_j|`` (units 1/length), see
        `mean_value_weights`; ``M = None``.

    Notes
    -----
    On a planar mesh the weights reproduce linear functions (LIN) and are positive (POS,
    half-angles below pi/2), they are local (LOC), but not symmetric (no SYM): Wardetzky et
    al. 2007's example that LIN + POS + LOC can be had without SYM.
    """
    return LaplacianResult(W=mean_value_weights(V, F), M=None)


@register("scratch.intrinsic_delaunay", task="laplacian", library="scratch",
          params={"mass": _MASS})
def intrinsic_delaunay(V, F, *, mass="voronoi"):
    """Cotangent Laplacian of the intrinsic Delaunay triangulation (own edge-flip implementation).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    mass : {"voronoi", "barycentric", "none"}
        Mass of the intrinsic triangulation (from its edge lengths), as
        ``igl.massmatrix_intrinsic``.

    Returns
    -------
    LaplacianResult
        ``W`` equal to ``igl.intrinsic_delaunay_cotmatrix(V, F)`` (1e-14 to 3.5e-10 relative on
        the bundled meshes, the largest on camelhead); ``M`` as chosen. Where the intrinsic Delaunay triangulation is not
        unique (cocircular quads: regular, stretched or sheared grids) the cotangent weights do
        not depend on which diagonal is chosen but the masses do (the triangle areas change):
        ``M`` may then differ from libigl's, whose flips break the ties otherwise, while each
        is the mass of its own triangulation.

    Notes
    -----
    Fisher et al. 2006 edge flips on lengths until every interior edge has opposite angles
    summing to at most pi (`methods.scratch.intrinsic_delaunay`); then cotangent weights
    (Bobenko & Springborn 2007). All interior weights are >= 0 (POS), SYM and LIN hold, but
    flipped edges join vertices that share no mesh edge (LOC fails). Boundary edges are never
    flipped, so a boundary edge with an obtuse opposite angle keeps a negative weight; nor is an
    edge between inconsistently oriented faces, so POS holds on consistently oriented meshes
    only (10% of a non-Delaunay plane's faces reversed: weights down to -29.5, and libigl's
    result differs from ours and from its own on the oriented mesh; ``scratch.tufted`` does not
    depend on the orientation).
    Degenerate faces: a flat (zero-area) triangle has an angle of pi, so its longest edge is
    flipped away when the neighbour allows; remaining zero-area faces contribute 0.
    """
    from methods.scratch.intrinsic_delaunay import intrinsic_delaunay_cotmatrix, intrinsic_mass
    W, l_int, F_int = intrinsic_delaunay_cotmatrix(V, F)
    return LaplacianResult(W=W, M=intrinsic_mass(l_int, F_int, V.shape[0], mass))


@register("scratch.tufted", task="laplacian", library="scratch",
          cite="Sharp & Crane, A Laplacian for nonmanifold triangle meshes, SGP 2020",
          params={"mass": Param("mass", "barycentric", choices=("barycentric", "voronoi"),
                                doc="lumped mass from the cover's intrinsic triangulation"),
                  "mollify_factor": Param("mollify_factor", 1e-5, low=0.0, high=1.0,
                                          doc="intrinsic mollification: edge lengths grow by the least "
                                              "amount giving every triangle inequality a margin of this "
                                              "factor times the mean edge length (0 on valid meshes)")})
def tufted(V, F, *, mass="barycentric", mollify_factor=1e-5):
    """Tufted-cover intrinsic Delaunay Laplacian (own implementation, `methods.scratch.tufted`).

    Returns
    -------
    LaplacianResult
        ``W`` with non-negative off-diagonal weights on any input (manifold or not), rows
        summing to zero; with ``mass: barycentric`` ``(-W, M)`` equals
        ``robust_laplacian.mesh_laplacian(V, F, mollify_factor)`` (to ~1e-12 relative on bunny,
        camelhead, woody, knight and noisy and obtuse meshes; where an edge is non-Delaunay by
        less than geometry-central's flip tolerance, a cotangent weight of -1e-6, that library
        keeps it and this flips it: stanford-bunny ``W`` 4.5e-8 apart and 3% in the masses of 4
        vertices, fandisk 1e-8 and 4%, where the library's ``W`` has negative weights).

    Notes
    -----
    Each face is doubled, sides are glued around every edge in angular order, and the closed
    cover is flipped to intrinsic Delaunay; weights and masses are halved. POS, SYM and PSD hold;
    LOC does not. LIN holds at interior vertices of a planar mesh as long as the lengths are the
    mesh's own and no flip crosses the fold where an open mesh's two sheets are glued.
    Mollification adds ``delta = max(0, max_f (eps - (l_i + l_j - l_k)))``, ``eps =
    mollify_factor * mean edge length``, to every length, which is 0 unless some triangle is that
    close to degenerate, and then the LIN error is of order ``delta`` (the procedural
    ``plane_nondelaunay``, whose thinnest triangle has a slack of 5.5e-6 mean edges: ``lin_error``
    2.1e-6 at the default factor, 9e-17 at 0; ``plane_delaunay``: 1e-16). On woody 5 of 575
    interior vertices, next to the boundary, fail at any factor (``lin_error`` 1.7e-3): the
    cover's flips cross the fold there. Sharp & Crane's ``robust_laplacian`` gives the same
    values.
    Unreferenced vertices get zero rows.
    """
    from methods.scratch.tufted import tufted_laplacian
    W, M = tufted_laplacian(V, F, mass, float(mollify_factor))
    return LaplacianResult(W=W, M=M)
