"""PyMeshLab geodesic distance adapters (task ``geodesics``).

``meshlab.geodesic``: ``compute_scalar_by_geodesic_distance_from_given_point_per_vertex`` from
the source vertex's position, with no distance cap (VCGLib's ``tri::Geodesic``: a Dijkstra-like
front propagation whose updates go across triangles, not only along edges, so it is close to the
polyhedral distance: 6e-7 relative on average on a flat Delaunay mesh of 2,000 points, at most
7e-5 at 3,000; 0.25% on average on an icosphere).
It recomputes everything per source
(``precompute_s`` is not split out). The filter takes the source as a point and starts from the
vertex nearest to it: a source vertex that shares its position with another vertex (a seam) is
ambiguous (positions within ``2^-23 max|coordinate|`` count as shared: a margin, as PyMeshLab
2025.7 passes positions in double precision), and the case fails saying so rather than
measure from the other copy. MeshLab's heat-method filter
(``compute_scalar_by_heat_geodesic_distance_from_selection_per_vertex``) has no adapter: it
crashed the process (segmentation fault) on the bundled knight mesh.
"""
from __future__ import annotations

import time

import numpy as np

from methods import GeodesicResult, register
from methods.meshlab.curvature import _quality
from methods.meshlab.smoothing import _meshset


@register("meshlab.geodesic", task="geodesics", library="pymeshlab", requires=("pymeshlab",),
          cite="VCGLib tri::Geodesic (MeshLab)")
def geodesic(V, F, *, sources):
    """VCGLib's front-propagation geodesic distance from each source (module docstring)."""
    import pymeshlab
    t0 = time.perf_counter()
    ms = _meshset(V, F)                  # one mesh for every source: the filter writes quality only
    tol = 2.0 ** -23 * float(np.abs(V).max(initial=0.0))   # a margin: positions this close count as one
    for s in sources:
        twins = np.flatnonzero((np.abs(V - V[int(s)]) <= tol).all(axis=1))
        if len(twins) > 1:
            raise ValueError(f"meshlab.geodesic: source vertex {int(s)} shares its position with vertex/vertices "
                             f"{[int(t) for t in twins if t != s][:5]}; the filter starts from a point, so it "
                             "could start from another copy")
    D = []
    for s in sources:
        ms.compute_scalar_by_geodesic_distance_from_given_point_per_vertex(
            startpoint=np.asarray(V[int(s)], dtype=np.float64), maxdistance=pymeshlab.PureValue(1e300))
        D.append(_quality(V, ms))
    return GeodesicResult(D=np.stack(D), per_source_s=(time.perf_counter() - t0) / max(len(sources), 1))
