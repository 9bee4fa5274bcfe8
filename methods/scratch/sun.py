"""Fast and effective feature-preserving mesh denoising (Sun et al. 2007): one small adapter."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from methods import Param, SmoothingResult, register
from methods.scratch.bilateral import (FACE_NEIGHBOURHOOD, FIXED_BOUNDARY, face_geometry, face_neighbour_pairs,
                                      sun_vertex_update)


@register("scratch.sun", task="smoothing", library="scratch",
          params={"threshold": Param("threshold", 0.5, "float", low=1e-10, high=1.0,
                                     doc="T: neighbours whose normals make cos <= T with the face's are "
                                         "ignored (0.5: 60 degrees; the reference code's default; 1 "
                                         "keeps every normal, and so the mesh)"),
                  "normal_iterations": Param("normal_iterations", 20, "int", low=0, high=1000,
                                             doc="normal filtering passes"),
                  "vertex_iterations": Param("vertex_iterations", 50, "int", low=0, high=1000,
                                             doc="vertex update passes"),
                  "neighbourhood": FACE_NEIGHBOURHOOD, "boundary": FIXED_BOUNDARY})
def sun(V, F, *, threshold=0.5, normal_iterations=20, vertex_iterations=50, neighbourhood="vertex",
        boundary="fixed"):
    """Sun, Rosin, Martin, Langbein, "Fast and effective feature-preserving mesh denoising",
    IEEE TVCG 2007, as the reference code of Zhang et al. 2015 (GuidedDenoising,
    ``FastAndEffectiveFeaturePreservingMeshDenoising.cpp``) runs it.

    1. ``normal_iterations`` Jacobi passes over the unit face normals, the face itself among its
       neighbours ``N(i)`` (faces sharing a vertex, or an edge)::

           n_i <- normalize( sum_{j in N(i) + i} w_ij n_j ),  w_ij = (n_i . n_j - T)^2 if n_i . n_j > T else 0

       (no area weights; dimensionless).
    2. ``vertex_iterations`` Jacobi passes moving each vertex toward the planes of its faces
       through their current centroids ``c_f``, with the filtered normals fixed::

           x_i += 1/|F_i| sum_{f in F_i} n_f (n_f . (c_f - x_i))

       Boundary vertices stay (``boundary: fixed``, as the reference) or move (``free``).

    ``meshlab.two_steps`` runs these formulas per outer iteration, but VCG's normal pass sees
    only part of each face's ring (its docstring); with ``iterations 1`` and a full ring it
    would be this method with ``boundary: free``. A zero-area face has a zero normal: it
    weighs nothing and is left with a zero normal.
    """
    from harness.core.geometry import boundary_vertices
    n, m = V.shape[0], F.shape[0]
    I, J = face_neighbour_pairs(F, n, neighbourhood)
    I, J = np.concatenate([I, np.arange(m)]), np.concatenate([J, np.arange(m)])   # the face itself
    N, _, _ = face_geometry(V, F)
    for _ in range(int(normal_iterations)):
        c = np.einsum("ij,ij->i", N[I], N[J]) - float(threshold)
        w = np.where(c > 0, c * c, 0.0)
        acc = sp.csr_matrix((w, (I, J)), shape=(m, m)) @ N
        nrm = np.linalg.norm(acc, axis=1, keepdims=True)
        N = np.divide(acc, nrm, out=np.zeros_like(acc), where=nrm > 0)
    fixed = boundary_vertices(F, n) if boundary == "fixed" else None
    return SmoothingResult(V=sun_vertex_update(V.copy(), F, N, int(vertex_iterations), fixed))
