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
measure from the other copy.

``meshlab.heat_geodesic``: ``compute_scalar_by_heat_geodesic_distance_from_selection_per_vertex``
(VCGLib's heat method, Crane, Weischedel & Wardetzky 2013: ``(M - t W) u = delta``, ``t = m h^2``
with ``h`` the mean edge length, ``m`` our ``t_factor``), one call per source with that vertex
alone selected (its vertex quality set to 1 and selected by ``q > 0.5``; the filter's expression
parser crashes the process when the mesh carries a custom vertex attribute, as the other
adapters' meshes do), so every call factors again. It equals
``scratch.heat`` with ``mass: barycentric`` on closed meshes (max difference over the largest
distance: 6e-10 on knight, 5e-8 to 1.3e-7 on bunny and noisy bunny (over source seeds 0-3),
1.4e-7 on fandisk, 2e-7 on noisy fandisk, at
``t_factor`` 1 and 4); on an open mesh it is nearest ``boundary: neumann`` and differs near the
boundary (two interior sources: camelhead 1.9e-4, the obtuse plane 8e-4, against 1e-2 and 4e-2
to ``average``; a source on the plane's boundary 1.3e-2).
"""
from __future__ import annotations

import time

import numpy as np

from methods import GeodesicResult, Param, register
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


@register("meshlab.heat_geodesic", task="geodesics", library="pymeshlab", requires=("pymeshlab",),
          params={"t_factor": Param("t_factor", 1.0, low=1e-6, high=1e6,
                                    doc="heat time t = t_factor * h^2, h the mean edge length (MeshLab's m)")},
          cite="Crane, Weischedel & Wardetzky 2013 (VCGLib, MeshLab)")
def heat_geodesic(V, F, *, sources, t_factor=1.0):
    """VCGLib's heat-method distance from each source in turn (module docstring)."""
    import pymeshlab
    t0 = time.perf_counter()
    keep, Fc = np.unique(F, return_inverse=True)      # the referenced vertices (a filter may refuse others)
    Fc = Fc.reshape(F.shape).astype(np.int32)
    D = np.full((len(sources), len(V)), np.inf)        # an unreferenced vertex: unreachable
    missing = [int(s) for s in sources if not np.isin(int(s), keep)]
    if missing:                                        # nothing would be selected: the filter returns 0 everywhere
        raise ValueError(f"meshlab.heat_geodesic: source vertex {missing[0]} is in no face")
    for i, s in enumerate(sources):
        mark = (keep == int(s)).astype(np.float64)
        ms = pymeshlab.MeshSet()        # no custom attribute: the selection's expression parser crashes on one
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V[keep], face_matrix=Fc, v_scalar_array=mark))
        ms.compute_selection_by_condition_per_vertex(condselect="q > 0.5")
        ms.compute_scalar_by_heat_geodesic_distance_from_selection_per_vertex(m=float(t_factor))
        d = ms.current_mesh().vertex_scalar_array()     # the filter keeps the vertices and their order
        D[i, keep] = np.where(np.isfinite(d), d, np.inf)  # NaN in another component than the source: unreachable
    return GeodesicResult(D=D, per_source_s=(time.perf_counter() - t0) / max(len(sources), 1))
