"""libigl geodesic distance adapters (task ``geodesics``).

``libigl.exact_geodesic``: ``igl.exact_geodesic`` (the exact polyhedral geodesic algorithm of
Mitchell, Mount & Papadimitriou in the implementation of Surazhsky et al. 2005), vertex sources
to all vertices, input units.
``libigl.heat``: ``igl.heat_geodesics_precompute(V, F, t)`` + ``heat_geodesics_solve``: the heat
method (Crane et al. 2013) with the cotangent Laplacian, the Voronoi mass, the average of
Neumann and Dirichlet heat solutions on open meshes, ``t = t_factor * h^2``; with
``intrinsic_delaunay`` its operators live on the intrinsic Delaunay triangulation
(``data.use_intrinsic_delaunay``). Distances are shifted to 0 at the source.
"""
from __future__ import annotations

import time

import numpy as np

from harness.core.geometry import mean_edge_length
from harness.tasks.geodesics import exact_precheck
from methods import GeodesicResult, Param, register
from methods.libigl import reject_zero_area_or_unreferenced


@register("libigl.exact_geodesic", task="geodesics", library="libigl", requires=("igl",), precheck=exact_precheck,
          cite="Surazhsky, Surazhsky, Kirsanov, Gortler, Hoppe, Fast exact and approximate geodesics on meshes, "
               "SIGGRAPH 2005")
def exact_geodesic(V, F, *, sources):
    """Exact polyhedral distance, one ``igl.exact_geodesic`` call per source (no precomputation)."""
    import igl
    t0 = time.perf_counter()
    VT = np.arange(len(V), dtype=np.int64)
    D = np.stack([np.asarray(igl.exact_geodesic(V, F, VS=np.array([s], np.int64), VT=VT), dtype=np.float64)
                  for s in sources])
    return GeodesicResult(D=D, precompute_s=0.0, per_source_s=(time.perf_counter() - t0) / max(len(sources), 1))


@register("libigl.heat", task="geodesics", library="libigl", requires=("igl",),
          cite="Crane, Weischedel, Wardetzky, Geodesics in heat, 2013 (libigl heat_geodesics)",
          params={"t_factor": Param("t_factor", 1.0, "float", low=1e-4, high=1e4,
                                    doc="t = t_factor * (mean edge length)^2"),
                  "laplacian": Param("laplacian", "cotan", choices=("cotan", "intrinsic_delaunay"),
                                     doc="data.use_intrinsic_delaunay")},
          precheck=reject_zero_area_or_unreferenced)
def heat(V, F, *, sources, t_factor=1.0, laplacian="cotan"):
    """libigl's heat method (module docstring); one precomputation for all sources."""
    import igl
    t0 = time.perf_counter()
    data = igl.HeatGeodesicsData()
    data.use_intrinsic_delaunay = laplacian == "intrinsic_delaunay"
    igl.heat_geodesics_precompute(V, F, float(t_factor) * mean_edge_length(V, F) ** 2, data)
    t1 = time.perf_counter()
    D = []
    for s in sources:
        d = np.asarray(igl.heat_geodesics_solve(data, np.array([s], np.int64)), dtype=np.float64).ravel()
        D.append(d - d[s])
    t2 = time.perf_counter()
    return GeodesicResult(D=np.stack(D), precompute_s=t1 - t0, per_source_s=(t2 - t1) / max(len(sources), 1))
