"""PyMeshLab curvature adapters (task ``curvature``; conventions in `harness.tasks.curvature`).

``meshlab.discrete_curvature``: ``compute_scalar_by_discrete_curvature_per_vertex`` with
``Gaussian Curvature`` and ``Mean Curvature`` (VCGLib's discrete operators of Meyer et al. 2003:
angle defect and cotangent mean curvature over mixed Voronoi areas); pointwise values, H > 0 on a
sphere with outward normals, as the task's (checked in tests on a sphere and a torus). Its H is
the *length* of the mean-curvature vector ``|Hn|``, signed by ``Hn . n``, not the normal
component ``Hn . n`` of ``scratch.cotan_mean``: the two agree where the vector is along the normal
and differ most where it is not (up to 0.16 relative on bunny, 0.5 on camelhead, far more on
noisy meshes; 7.7 against 150 at a bunny vertex whose vector is 88 degrees off the normal), and
VCG's own computation rounds about as single precision would, although PyMeshLab 2025.7 passes
coordinates and vertex quality in double precision: its K and H agree with an independent
double-precision computation of the same formulas to 3e-7 to 5e-6 of their largest values
(bunny, camelhead), and on a flat non-Delaunay plane (exactly 0) it leaves H nonzero at every
interior vertex, up to 5.2e-3 / (mean edge length), and K up to 4.4e-6 / (mean edge
length)^2, against 1e-13 for `scratch.angle_defect`. At boundary vertices its K follows another convention than the task's
``(pi - sum theta) / A`` or libigl's ``(2 pi - sum theta) / A`` (twice the former at a plane's
corner, unrelated elsewhere). Zero-area faces are refused (their values reach 1e7).
``meshlab.principal_curvature``: ``compute_curvature_principal_directions_per_vertex`` with the
chosen ``method`` (VCGLib's quadric fitting or scale-dependent quadric fitting), reading its two principal values through ``curvcolormethod`` ``Min Curvature`` and
``Max Curvature`` (VCGLib's labels do not follow the sign order: the adapter sorts them,
``k1 >= k2``). ``scale`` (the neighbourhood radius, percent of the bounding-box diagonal) is read
by scale-dependent quadric fitting alone: the filter ignores it otherwise (results equal for every
scale), so a setting giving it with the other method is refused (a config naming one, when it loads). PyMeshLab's three other labels are left out: its
"Normal Cycles" values are curvature integrated over a vertex's area (they grow with the
radius of a sphere and shrink as it is refined), its "Principal Component Analysis" values
have another sign and a scale that depends on the resolution (neither is the task's pointwise
curvature), and "Taubin approximation" corrupts the heap (a double free aborts about half of
its calls on an icosphere in PyMeshLab 2025.7, so the values of the other half are not to be
trusted either).
``meshlab.apss_curvature``: ``compute_curvature_and_color_apss_per_vertex`` (Guennebaud & Gross
2007, algebraic point set surfaces: a sphere fitted by moving least squares to the points within
``filter_scale`` times the local point spacing, its curvature read at each vertex): ``Mean``
(VCG's value is ``k1 + k2``: halved here) and ``Gauss``; H > 0 on a sphere with outward normals.
On closed meshes it is close to the analytic values (relative L2 of H and K: sphere 0.5% and 1.0%
at 4 subdivisions, 0.7% and 1.5% at the default 3; torus 0.7% and 1.3% at resolution 48;
ellipsoid 0.6% and 1.1%); on the irregular open saddle it is far off. Its
``K1`` and ``K2`` types abort the process (a double free) in PyMeshLab 2025.7: not read. MeshLab's
RIMLS filter returned 0 at every vertex with its defaults: no adapter.
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


def _refuse_flat(V, F, name) -> None:
    """``precheck`` of the discrete curvature: no zero-area faces (values reach 1e7 there)."""
    _no_zero_area(V, F, name, "its mean curvature reaches 1e7 there")


@register("meshlab.discrete_curvature", task="curvature", library="pymeshlab", requires=("pymeshlab",),
          precheck=_refuse_flat,
          cite="Meyer, Desbrun, Schroeder, Barr 2003 (VCGLib discrete curvature)")
def discrete_curvature(V, F):
    """Gaussian and mean curvature from MeshLab's discrete operators (module docstring)."""
    out = {}
    ms = _meshset(V, F)                  # one mesh: the filter writes quality only
    for q, kind in (("K", "Gaussian Curvature"), ("H", "Mean Curvature")):
        ms.compute_scalar_by_discrete_curvature_per_vertex(curvaturetype=kind)
        out[q] = _quality(V, ms)
    return CurvatureResult(K=out["K"], H=out["H"])


_METHODS = ("Quadric Fitting", "Scale Dependent Quadric Fitting")
_SCALED = "Scale Dependent Quadric Fitting"        # the one label that reads ``scale``
_SCALE = 10.0                                      # its default: percent of the bounding-box diagonal


def _no_zero_area(V, F, name, why: str = "VCGLib's principal-curvature filter aborts on them") -> None:
    """``precheck``: VCGLib's principal-curvature filter aborts the process (a double free) on a
    mesh with zero-area faces, and its discrete curvature is meaningless there."""
    from methods.libigl import refuse_zero_area
    refuse_zero_area(V, F, name, why)


def _scale_read(params) -> str | None:
    """``setting_check``: ``scale`` given with a method that ignores it."""
    if params.get("scale") is not None and params.get("method") != _SCALED:
        return (f"scale is read by method {_SCALED!r} alone; {params.get('method')!r} ignores it (every scale "
                "gives the same values): leave it out")
    return None


@register("meshlab.principal_curvature", task="curvature", library="pymeshlab", requires=("pymeshlab",),
          precheck=_no_zero_area, setting_check=_scale_read,
          params={"method": Param("method", "Quadric Fitting", choices=_METHODS, doc="VCGLib's estimator"),
                  "scale": Param("scale", None, "float", low=0.01, high=100.0, optional=True,
                                 doc="neighbourhood radius, percent of the bounding-box diagonal; read by "
                                     f"{_SCALED!r} alone ({_SCALE:g} when not given)")})
def principal_curvature(V, F, *, method="Quadric Fitting", scale=None):
    """Principal curvatures from MeshLab's principal-directions filter (module docstring)."""
    import pymeshlab
    why = _scale_read({"method": method, "scale": scale})
    if why:
        raise ValueError(f"meshlab.principal_curvature: {why}")
    scale = _SCALE if scale is None else scale
    vals = []
    ms = _meshset(V, F)                  # one mesh: the filter writes directions and quality only
    for kind in ("Min Curvature", "Max Curvature"):
        ms.compute_curvature_principal_directions_per_vertex(method=method, curvcolormethod=kind,
                                                             scale=pymeshlab.PercentageValue(float(scale)),
                                                             autoclean=False)
        vals.append(_quality(V, ms))
    k1, k2 = np.maximum(vals[0], vals[1]), np.minimum(vals[0], vals[1])
    return CurvatureResult(K=k1 * k2, H=(k1 + k2) / 2, k1=k1, k2=k2)


@register("meshlab.apss_curvature", task="curvature", library="pymeshlab", requires=("pymeshlab",),
          params={"filter_scale": Param("filter_scale", 2.0, low=0.1, high=100.0,
                                        doc="the fit's neighbourhood, a multiple of the local point spacing "
                                            "(MeshLab's filterscale)")},
          cite="Guennebaud & Gross 2007, Algebraic point set surfaces (VCGLib, MeshLab)")
def apss_curvature(V, F, *, filter_scale=2.0):
    """Mean and Gaussian curvature of MeshLab's APSS fit (module docstring)."""
    out = {}
    ms = _meshset(V, F)                                 # one mesh: the filter writes quality only
    for q, kind in (("H", 0), ("K", 1)):                # Mean, Gauss (2 and 3, K1 and K2, abort the process)
        ms.compute_curvature_and_color_apss_per_vertex(filterscale=float(filter_scale), curvaturetype=kind)
        out[q] = _quality(V, ms)
    return CurvatureResult(K=out["K"], H=0.5 * out["H"])
