"""Open3D's quadric decimation (task ``simplification``; optional extra ``open3d``, PyPI
``open3d-cpu``: about 105 MB plus a web and notebook dependency tree, so not in the default
install; without it the rows say ``unavailable``).

``open3d.qem``: ``TriangleMesh.simplify_quadric_decimation`` (Garland & Heckbert 1997 as
implemented in Open3D's ``TriangleMeshSimplification.cpp``): per-vertex sums of area-weighted
plane quadrics, plus a perpendicular-plane quadric on each boundary edge; an edge collapses to
the quadric's minimiser when its 3x3 system is invertible, else to the cheapest of its ends and
midpoint; collapses that flip a neighbouring triangle's normal are skipped. There is no link
condition, so the output may be non-manifold or change topology (the row's ``manifold`` and
``topology_changed`` columns say so). It may stop above the target when no valid collapse is
left. Double precision throughout.
"""
from __future__ import annotations

import numpy as np

from methods import SimplificationResult, register


@register("open3d.qem", task="simplification", library="open3d", requires=("open3d",), extra="open3d",
          cite="Garland & Heckbert 1997; Open3D (TriangleMesh::SimplifyQuadricDecimation)")
def qem(V, F, *, target_faces):
    """``simplify_quadric_decimation`` to ``target_faces`` (module docstring)."""
    import open3d as o3d
    mesh = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(np.ascontiguousarray(V, dtype=np.float64)),
                                     o3d.utility.Vector3iVector(np.ascontiguousarray(F, dtype=np.int32)))
    out = mesh.simplify_quadric_decimation(target_number_of_triangles=int(target_faces))
    Vo = np.array(out.vertices, dtype=np.float64)      # a copy: no view of memory that `out` owns
    Fo = np.asarray(out.triangles, dtype=np.int64).reshape(-1, 3)
    return SimplificationResult(V=Vo, F=Fo)
