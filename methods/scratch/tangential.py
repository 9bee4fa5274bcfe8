"""Tangential relaxation: area-weighted Laplacian projected onto the tangent plane."""
from __future__ import annotations

import numpy as np

from methods import Param, SmoothingResult, register
from harness.core.geometry import boundary_vertices


@register("scratch.tangential", task="smoothing", library="scratch",
          params={"step": Param("step", 0.5, "float", low=0.0, high=1.0,
                                doc="fraction of the tangential move applied per iteration"),
                  "iterations": Param("iterations", 10, "int", low=0, high=100000)})
def tangential(V, F, *, step=0.5, iterations=10):
    """Tangential area-weighted relaxation for triangle quality (shape barely changes).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    step : float
        Fraction in [0, 1] of the tangential displacement applied each iteration.
    iterations : int

    Returns
    -------
    SmoothingResult

    Notes
    -----
    Per iteration, for every interior vertex ``i`` with incident faces ``F_i``::

        g_i = sum_{f in F_i} A_f c_f / sum_{f in F_i} A_f       (area-weighted centroid)
        d_i = g_i - x_i,  n_i = normalize(sum_{f in F_i} A_f n_f)
        x_i <- x_i + step (I - n_i n_i^T) d_i

    This is the tangential relaxation step of isotropic remeshing (Botsch & Kobbelt 2004;
    Botsch et al., *Polygon Mesh Processing*, Sec. 6.5.3) with one particular target: ``g_i``
    is pmp-library's ``Remeshing::weighted_centroid`` at uniform sizing (the mean of the
    incident faces' centroids weighted by their areas; pmp weights a zero-area face 1, this
    0). It is not the neighbours' mean weighted by vertex areas (on knight, 10 iterations
    at step 0.5, the two targets end 1.5e-2 of the diagonal apart, with equal angle gains),
    nor the point minimising the incident faces' squared areas, which newer pmp releases
    move to first. The normal ``n_i`` is the area-weighted face normal, where pmp's
    (``Normals::compute_vertex_normal``) is angle-weighted (10 iterations at step 0.5: 1.5e-3 of
    the diagonal apart on camelhead, 1.5e-2 to 2.7e-2 on noisy bunny, knight and a noisy obtuse
    plane); pmp applies the whole move (``step 1``) and, in remeshing, projects each vertex back
    onto the input surface, which this does not. Removing the normal component makes it a redistribution of
    vertices within the surface: it improves angles while the distance to the input stays
    second order. Boundary vertices are fixed.
    """
    X = V.copy()
    n = V.shape[0]
    fixed = boundary_vertices(F, n)
    vid = F.ravel()
    for _ in range(iterations):
        P0, P1, P2 = X[F[:, 0]], X[F[:, 1]], X[F[:, 2]]
        Nf = np.cross(P1 - P0, P2 - P0)                      # |Nf| = 2 A_f
        A2 = np.linalg.norm(Nf, axis=1)
        C = (P0 + P1 + P2) / 3.0
        wsum = np.bincount(vid, weights=np.repeat(A2, 3), minlength=n)
        g = np.stack([np.bincount(vid, weights=np.repeat(A2 * C[:, k], 3), minlength=n)
                      for k in range(3)], 1)
        nv = np.stack([np.bincount(vid, weights=np.repeat(Nf[:, k], 3), minlength=n)
                       for k in range(3)], 1)
        ok = (wsum > 0) & ~fixed
        g = np.divide(g, wsum[:, None], out=X.copy(), where=ok[:, None])
        nn = np.linalg.norm(nv, axis=1, keepdims=True)
        nv = np.divide(nv, nn, out=np.zeros_like(nv), where=nn > 0)
        d = g - X
        d = d - nv * np.einsum("ij,ij->i", nv, d)[:, None]
        d[~ok] = 0.0
        X = X + step * d
    return SmoothingResult(V=X)
