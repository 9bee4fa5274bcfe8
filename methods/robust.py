"""The robust-laplacian package (Sharp & Crane 2020), task ``laplacian``; imported lazily."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from harness.core.geometry import referenced
from methods import LaplacianResult, Param, register


@register("robust.tufted", task="laplacian", library="robust_laplacian",
          params={"mollify_factor": Param("mollify_factor", 1e-5, low=0.0, high=1.0,
                                          doc="intrinsic mollification (Sharp & Crane 2020): "
                                              "edge lengths are increased by the least amount "
                                              "that makes every triangle inequality hold with "
                                              "a margin of this factor times the mean edge "
                                              "length (0 on already valid meshes)")},
          requires=("robust_laplacian",))
def tufted(V, F, *, mollify_factor=1e-5):
    """Tufted-cover intrinsic Delaunay Laplacian, ``robust_laplacian.mesh_laplacian``.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    mollify_factor : float
        Relative intrinsic mollification (see the package; 0 disables it).

    Returns
    -------
    LaplacianResult
        ``W = -L`` where ``L`` is the package's positive semi-definite Laplacian (converted to
        libigl's sign convention: positive off-diagonal weights, negative diagonal) and ``M``
        its lumped barycentric mass matrix: a third of the area of each intrinsic Delaunay
        triangle at each of its corners (equal to ``scratch.tufted`` with ``mass: barycentric``).
        The package puts ``L_ii = 1`` on unreferenced vertices (an isolated row that does not
        sum to zero); those diagonal entries are set to 0 here so every row of ``W`` sums to
        zero, as the contract requires. ``M`` is returned unchanged.

    Notes
    -----
    Sharp & Crane 2020, "A Laplacian for nonmanifold triangle meshes": intrinsic Delaunay
    triangulation of the tufted cover (each face doubled), which handles non-manifold and
    degenerate input; PSD holds, LOC does not. Weights are non-negative (POS) up to
    geometry-central's flip tolerance: ``flipToDelaunay`` flips an edge only when its cotangent
    weight is below -1e-6, so a slightly non-Delaunay edge stays and its weight can be slightly
    negative (stanford-bunny: 9.4e-6, fandisk: 5.0e-5 of the scale; POS false), where
    `scratch.tufted`, flipping at a relative 1e-12, gives the Delaunay triangulation.
    """
    import robust_laplacian
    L, M = robust_laplacian.mesh_laplacian(V, F, mollify_factor=float(mollify_factor))
    W = -sp.csr_matrix(L)
    used = referenced(F, V.shape[0])
    if not used.all():
        W = (W + sp.diags(np.where(used, 0.0, -W.diagonal()))).tocsr()
        W.eliminate_zeros()
    return LaplacianResult(W=W, M=sp.csr_matrix(M))
