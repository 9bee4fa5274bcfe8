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
(tiny but non-zero area) are kept: their weights are large but finite. Edges of zero length
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
    exactly on (intrinsic) Delaunay meshes. Zero-area faces contribute nothing (module docstring).
    """
    W = op.cotan_weights(V, F)
    return LaplacianResult(W=W, M=op.mass_matrix(V, F, mass))
