"""trimesh's discrete curvature measures (task ``curvature``; PyPI ``trimesh``, which needs ``rtree``).

``trimesh.curvature_measure``: ``trimesh.curvature.discrete_gaussian_curvature_measure`` and
``discrete_mean_curvature_measure`` (Cohen-Steiner & Morvan 2003, "Restricted Delaunay
triangulations and normal cycle") integrate K and H over the ball of radius ``r`` around each
vertex; the adapter divides by the ball's area on a flat surface, ``pi r^2``, to give pointwise
values in the task's conventions (H > 0 on a sphere with outward normals). ``r = radius * h``
with ``h`` the mean edge length. Large radii smooth the field. trimesh's geometric tests use
absolute tolerances (``trimesh.tol``, 1e-8 and the like) that assume unit-sized input, so the
adapter calls it on the mesh centred and scaled to unit mean edge length and returns
``K / h^2`` and ``H / h``: the result is invariant under translation and scaling.

Near a boundary K is far too large, as trimesh computes it: trimesh takes every vertex's angle
defect against ``2 pi``, also at boundary vertices (whose defect is against ``pi``), so each
boundary vertex inside a ball adds about ``pi`` to that ball's K (on a flat square, exact K = 0,
interior vertices within ``r`` of the boundary read a median K h^2 of about 0.22 at the default
radius, ``h`` the mean edge length: K = 174 on ``plane_delaunay`` with 1000 points, 52 with 300).
The adapter keeps trimesh's values; the task's interior errors (``K_rel_l2``, ``K_max``) include
those vertices. The division by ``pi r^2`` also assumes a full disc, which a boundary cuts.
"""
from __future__ import annotations

import numpy as np

from harness.core.geometry import mean_edge_length
from methods import CurvatureResult, Param, register


@register("trimesh.curvature_measure", task="curvature", library="trimesh", requires=("trimesh", "rtree"),
          cite="Cohen-Steiner & Morvan, Restricted Delaunay triangulations and normal cycle, SoCG 2003 (trimesh)",
          params={"radius": Param("radius", 3.0, "float", low=0.1, high=100.0,
                                  doc="ball radius in mean edge lengths")})
def curvature_measure(V, F, *, radius=3.0):
    """Pointwise K and H from trimesh's curvature measures over balls (module docstring)."""
    import trimesh
    h = mean_edge_length(V, F)
    U = (V - V.mean(axis=0)) / h        # trimesh's absolute tolerances (1e-8) assume unit-sized meshes
    m = trimesh.Trimesh(vertices=U, faces=F, process=False, validate=False)
    r = float(radius)
    area = np.pi * r * r
    K = np.asarray(trimesh.curvature.discrete_gaussian_curvature_measure(m, U, r), dtype=np.float64) / area
    H = np.asarray(trimesh.curvature.discrete_mean_curvature_measure(m, U, r), dtype=np.float64) / area
    return CurvatureResult(K=K / (h * h), H=H / h)
