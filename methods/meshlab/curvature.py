"""PyMeshLab curvature adapters (task ``curvature``; conventions in `harness.tasks.curvature`).

``meshlab.discrete_curvature``: ``compute_scalar_by_discrete_curvature_per_vertex`` with
``Gaussian Curvature`` and ``Mean Curvature`` (VCGLib's discrete operators of Meyer et al. 2003:
angle defect and cotangent mean curvature over mixed Voronoi areas); pointwise values, H > 0 on a
sphere with outward normals, as the task's (checked in tests on a sphere and a torus).
``meshlab.principal_curvature``: ``compute_curvature_principal_directions_per_vertex`` with the
chosen ``method`` (VCGLib's quadric fitting, Taubin's approximation, PCA, normal cycles or
scale-dependent quadric fitting: the labels PyMeshLab 2025.7 accepts) and neighbourhood
``scale`` (percent of the bounding-box diagonal), reading its two principal values through ``curvcolormethod`` ``Min Curvature`` and
``Max Curvature`` (VCGLib's labels do not follow the sign order: the adapter sorts them,
``k1 >= k2``). MeshLab holds vertex quality in single precision.
"""
from __future__ import annotations

import numpy as np

from methods import CurvatureResult, Param, register
from methods.meshlab.smoothing import _INDEX, _meshset


def _quality(V, ms) -> np.ndarray:
    """The current mesh's vertex quality scattered into the caller's order (0 where a vertex is missing)."""
    m = ms.current_mesh()
    q = np.asarray(m.vertex_scalar_array(), dtype=np.float64)
    idx = np.rint(np.asarray(m.vertex_custom_scalar_attribute_array(_INDEX))).astype(np.int64)
    out = np.zeros(len(V))
    out[idx] = q
    return out


@register("meshlab.discrete_curvature", task="curvature", library="pymeshlab", requires=("pymeshlab",),
          cite="Meyer, Desbrun, Schroeder, Barr 2003 (VCGLib discrete curvature)")
def discrete_curvature(V, F):
    """Gaussian and mean curvature from MeshLab's discrete operators (module docstring)."""
    out = {}
    ms = _meshset(V, F)                  # one mesh: the filter writes quality only
    for q, kind in (("K", "Gaussian Curvature"), ("H", "Mean Curvature")):
        ms.compute_scalar_by_discrete_curvature_per_vertex(curvaturetype=kind)
        out[q] = _quality(V, ms)
    return CurvatureResult(K=out["K"], H=out["H"])


_METHODS = ("Quadric Fitting", "Taubin approximation", "Principal Component Analysis", "Normal Cycles",
            "Scale Dependent Quadric Fitting")


def _no_zero_area(V, F, name) -> None:
    """``precheck``: VCGLib's principal-curvature filter aborts the process (a double free) on a
    mesh with zero-area faces."""
    from methods.libigl import refuse_zero_area
    refuse_zero_area(V, F, name, "VCGLib's principal-curvature filter aborts on them")


@register("meshlab.principal_curvature", task="curvature", library="pymeshlab", requires=("pymeshlab",),
          precheck=_no_zero_area,
          params={"method": Param("method", "Quadric Fitting", choices=_METHODS, doc="VCGLib's estimator"),
                  "scale": Param("scale", 10.0, "float", low=0.01, high=100.0,
                                 doc="neighbourhood radius, percent of the bounding-box diagonal")})
def principal_curvature(V, F, *, method="Quadric Fitting", scale=10.0):
    """Principal curvatures from MeshLab's principal-directions filter (module docstring)."""
    import pymeshlab
    vals = []
    ms = _meshset(V, F)                  # one mesh: the filter writes directions and quality only
    for kind in ("Min Curvature", "Max Curvature"):
        ms.compute_curvature_principal_directions_per_vertex(method=method, curvcolormethod=kind,
                                                             scale=pymeshlab.PercentageValue(float(scale)),
                                                             autoclean=False)
        vals.append(_quality(V, ms))
    k1, k2 = np.maximum(vals[0], vals[1]), np.minimum(vals[0], vals[1])
    return CurvatureResult(K=k1 * k2, H=(k1 + k2) / 2, k1=k1, k2=k2)
