"""PyMeshLab's quadric edge collapse (``meshing_decimation_quadric_edge_collapse``).

The library is imported lazily so a missing install makes the method `unavailable`.
"""
from __future__ import annotations

import numpy as np

from methods import Param, SimplificationResult, register
from harness.core.geometry import compact


@register(
    "meshlab.qem",
    task="simplification",
    library="pymeshlab",
    params={
        "preserveboundary": Param("preserveboundary", False,
                                  doc="keep open-boundary edges in place (MeshLab's boundary "
                                      "penalty, weight boundaryweight)"),
        "boundaryweight": Param("boundaryweight", 1.0, "float", low=0.0, high=1e6,
                                doc="weight of the boundary-preserving quadrics"),
        "optimalplacement": Param("optimalplacement", True,
                                  doc="place the new vertex at the quadric minimiser "
                                      "(false: at one of the endpoints)"),
        "qualitythr": Param("qualitythr", 0.3, "float", low=0.0, high=1.0,
                            doc="penalise collapses creating triangles with quality "
                                "(2 inradius/circumradius) below this"),
        "planarquadric": Param("planarquadric", False,
                               doc="add small planar quadrics per face to improve triangle "
                                   "shape on flat regions"),
        "preservenormal": Param("preservenormal", False,
                                doc="forbid collapses that flip a face normal"),
        "preservetopology": Param("preservetopology", False,
                                  doc="forbid collapses that change the topology"),
    },
    requires=("pymeshlab",),
)
def qem(V, F, *, target_faces, preserveboundary=False, boundaryweight=1.0,
        optimalplacement=True, qualitythr=0.3, planarquadric=False, preservenormal=False,
        preservetopology=False):
    """MeshLab quadric edge collapse decimation (Garland & Heckbert 1997, VCGLib's version).

    VCGLib keeps a heap of edge collapses ordered by quadric error (unweighted face-plane
    quadrics, optional boundary and planar quadrics), penalised by triangle quality.

    Parameters
    ----------
    V : (n, 3) float64 array
    F : (m, 3) int64 array
    target_faces : int
        Passed as ``targetfacenum``.
    preserveboundary, boundaryweight, optimalplacement, qualitythr, planarquadric,
    preservenormal, preservetopology
        The filter's parameters of the same names (MeshLab defaults).

    Returns
    -------
    SimplificationResult
        Compacted (no unreferenced vertices); ``autoclean`` is on (MeshLab default).
    """
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32)))
    ms.meshing_decimation_quadric_edge_collapse(
        targetfacenum=int(target_faces), preserveboundary=bool(preserveboundary),
        boundaryweight=float(boundaryweight), optimalplacement=bool(optimalplacement),
        qualitythr=float(qualitythr), planarquadric=bool(planarquadric),
        preservenormal=bool(preservenormal), preservetopology=bool(preservetopology),
        autoclean=True)
    m = ms.current_mesh()
    Vo, Fo = compact(m.vertex_matrix(), m.face_matrix())
    return SimplificationResult(V=Vo, F=Fo)
