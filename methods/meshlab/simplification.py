"""PyMeshLab's quadric edge collapse (``meshing_decimation_quadric_edge_collapse``).

The library is imported lazily so a missing install makes the method `unavailable`.
"""
from __future__ import annotations

import numpy as np

from methods import Param, SimplificationResult, register


@register(
    "meshlab.qem",
    task="simplification",
    library="pymeshlab",
    params={
        "preserve_boundary": Param("preserve_boundary", False,
                                  doc="keep open-boundary edges in place (MeshLab's boundary "
                                      "penalty, weight boundary_weight)"),
        "boundary_weight": Param("boundary_weight", 1.0, "float", low=0.0, high=1e6,
                                doc="weight of the boundary-preserving quadrics"),
        "optimal_placement": Param("optimal_placement", True,
                                  doc="place the new vertex at the quadric minimiser "
                                      "(false: at one of the endpoints)"),
        "quality_threshold": Param("quality_threshold", 0.3, "float", low=0.0, high=1.0,
                            doc="penalise collapses creating triangles with quality "
                                "(2 inradius/circumradius) below this"),
        "planar_quadric": Param("planar_quadric", False,
                               doc="add small planar quadrics per face to improve triangle "
                                   "shape on flat regions"),
        "preserve_normal": Param("preserve_normal", False,
                                doc="forbid collapses that flip a face normal"),
        "preserve_topology": Param("preserve_topology", False,
                                  doc="forbid collapses that change the topology"),
    },
    requires=("pymeshlab",),
)
def qem(V, F, *, target_faces, preserve_boundary=False, boundary_weight=1.0,
        optimal_placement=True, quality_threshold=0.3, planar_quadric=False, preserve_normal=False,
        preserve_topology=False):
    """MeshLab quadric edge collapse decimation (Garland & Heckbert 1997, VCGLib's version).

    VCGLib keeps a heap of edge collapses ordered by quadric error, penalised by triangle
    quality. Its face-plane quadrics are built on the unnormalised normal ``(p1 - p0) x (p2 -
    p0)`` (``UseArea``, VCGLib's default, which the filter does not change), so each face's
    quadric is weighted by its doubled area squared, ``(2 A)^2``, where QSlim weights by area
    (the 1997 paper does not weight); the optional boundary and planar quadrics are built on that normal too.

    Parameters
    ----------
    V : (n, 3) float64 array
    F : (m, 3) int64 array
    target_faces : int
        Passed as ``targetfacenum``.
    preserve_boundary, boundary_weight, optimal_placement, quality_threshold, planar_quadric,
    preserve_normal, preserve_topology
        The filter's ``preserveboundary``, ``boundaryweight``, ``optimalplacement``,
        ``qualitythr``, ``planarquadric``, ``preservenormal``, ``preservetopology`` (MeshLab
        defaults), under the names the other adapters use.

    Returns
    -------
    SimplificationResult
        MeshLab's mesh (``autoclean`` on, MeshLab's default); the task drops any unreferenced
        vertices (untimed).
    """
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32)))
    ms.meshing_decimation_quadric_edge_collapse(
        targetfacenum=int(target_faces), preserveboundary=bool(preserve_boundary),
        boundaryweight=float(boundary_weight), optimalplacement=bool(optimal_placement),
        qualitythr=float(quality_threshold), planarquadric=bool(planar_quadric),
        preservenormal=bool(preserve_normal), preservetopology=bool(preserve_topology),
        autoclean=True)
    m = ms.current_mesh()
    return SimplificationResult(V=m.vertex_matrix(), F=m.face_matrix())
