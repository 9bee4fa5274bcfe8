"""libigl curvature adapters (task ``curvature``; conventions in `harness.tasks.curvature`).

``libigl.gaussian_curvature``: ``igl.gaussian_curvature`` returns the *integrated* angle defect
``2 pi - sum theta`` at every vertex (boundary vertices included, measured against 2 pi, so it is
not a curvature there); the adapter divides it by the mixed Voronoi area of
``igl.massmatrix(VORONOI)`` to give the pointwise K of the task.
``libigl.principal_curvature``: ``igl.principal_curvature`` (quadric fitting over the
``radius``-ring of each vertex: libigl's default ``useKring``, under which ``radius`` counts
rings of edges, not edge lengths; Panozzo, Puppo & Rocca 2010) returns the maximal and
minimal principal curvature values ``PV1 >= PV2`` with the sign of the vertex normals (positive
on a sphere with outward normals, as the task's); ``K = PV1 PV2``, ``H = (PV1 + PV2) / 2``.
Vertices libigl reports as bad (no fit) make the call fail, naming them.
"""
from __future__ import annotations

import numpy as np

from methods import CurvatureResult, Param, register
from methods.libigl import reject_zero_area


@register("libigl.gaussian_curvature", task="curvature", library="libigl", requires=("igl",),
          precheck=reject_zero_area)
def gaussian_curvature(V, F):
    """``igl.gaussian_curvature(V, F) / diag(igl.massmatrix(V, F, VORONOI))`` (module docstring)."""
    import igl
    k = np.asarray(igl.gaussian_curvature(V, F), dtype=np.float64)
    A = np.asarray(igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI).diagonal(), dtype=np.float64)
    A = np.pad(A, (0, len(V) - len(A)), constant_values=1.0)
    k = np.pad(k, (0, len(V) - len(k)))
    A = np.where(A > 0, A, 1.0)
    return CurvatureResult(K=k / A, area=A)


@register("libigl.principal_curvature", task="curvature", library="libigl", requires=("igl",),
          params={"radius": Param("radius", 5, "int", low=2, high=100,
                                  doc="neighbourhood: the k-ring of each vertex, k = radius (igl's radius, useKring)")})
def principal_curvature(V, F, *, radius=5):
    """``igl.principal_curvature(V, F, radius)`` values (module docstring).

    A quadric ``a u^2 + b uv + c v^2 + d u + e v`` fitted over the ``radius``-ring (neighbours whose
    normal faces away left out where 6 remain with the vertex), its principal curvatures the
    eigenvalues of ``I^-1 II`` with the (0,1) entry replaced by the (1,0) one (libigl's
    ``finalEigenStuff``): H, the trace, is exact; K, k1, k2 are off where the slope ``(d, e)`` is
    large. `scratch.quadric_fit` with ``rings = radius`` is the same fit with the exact operator:
    the same H to 5e-10 (its docstring). The default neighbourhoods differ (5 here, 2 rings
    there)."""
    import igl
    _, _, pv1, pv2, bad = igl.principal_curvature(V, F, int(radius))
    pv1, pv2 = np.asarray(pv1, dtype=np.float64), np.asarray(pv2, dtype=np.float64)
    nonfinite = np.flatnonzero(~(np.isfinite(pv1) & np.isfinite(pv2)))
    if len(bad) or nonfinite.size:
        where = sorted(set(map(int, bad)) | set(nonfinite.tolist()))
        raise ValueError(f"libigl.principal_curvature: no fit at {len(where)} vertex(es) (first: {where[:5]})")
    k1, k2 = np.maximum(pv1, pv2), np.minimum(pv1, pv2)
    return CurvatureResult(K=k1 * k2, H=(k1 + k2) / 2, k1=k1, k2=k2)
