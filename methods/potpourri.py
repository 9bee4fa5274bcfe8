"""potpourri3d adapters (geometry-central; task ``geodesics``).

``potpourri3d.heat``: ``MeshHeatMethodDistanceSolver(V, F, t_coef, use_robust)``: the heat method
(Crane et al. 2013) as geometry-central implements it; with ``use_robust`` (default) its
operators are built on the intrinsic Delaunay triangulation of the tufted cover (Sharp & Crane
2020, "A Laplacian for nonmanifold triangle meshes"), ``t = t_coef * h^2``. Input units. On an
open mesh it uses the Neumann heat solution alone (the lumped barycentric mass), not the paper's
average of the Neumann and Dirichlet ones that ``scratch.heat`` and ``libigl.heat`` use by
default. Its Poisson step solves with ``L + 1e-6 I`` (geometry-central's
``heat_method_distance.cpp``: a fixed shift, not pinned at a vertex as ``scratch.heat`` does),
whose effect grows as L's smallest non-zero eigenvalue shrinks with the vertex count: 2.5e-3 of
the largest distance from ``scratch.heat`` on a 327k-face icosphere (1.3e-3 mean), 4e-4 at 20k
faces. So with ``use_robust`` off it is ``scratch.heat`` with ``boundary: neumann, mass:
barycentric`` up to that shift (to 2e-5 of the largest distance on 300-point Delaunay and
non-Delaunay planes and 1e-4 on a cylinder, `tests/test_geodesics.py`; 2.2e-4 on the 3000-point
planes of ``configs/geodesics.yaml``, 2.8e-4 on bunny, 9e-4 on camelhead, 8e-4 on camelhead with
noise); with it on, the nearest setting is
``scratch.heat`` with ``laplacian: tufted, boundary: neumann, mass: barycentric`` (2e-5 to 6e-3
of the largest distance apart on those meshes, woody and noisy ones): the same operator, but
geometry-central takes h from the intrinsic Delaunay mesh (t 0.948 of ours on bunny) besides the
shift. That t and the shift, set by hand, reproduce both settings to 1e-13 of the largest
distance on bunny and on icospheres. On fine meshes far from the source it fails: it normalises
each face's heat gradient as ``v / sqrt(x*x + y*y)``, whose squares underflow where the heat
solution is below about 1e-154 (at ``t = h^2``, beyond geodesic 1.75 on a unit icosphere of 1.31M
faces: 41% of the vertices), and such faces add nothing to the divergence: 0.43 of the largest
distance off the exact geodesic there, ``use_robust`` on or off (``scratch.heat``: 7.2e-3).
``pygeodesic.exact``: ``pygeodesic.geodesic.PyGeodesicAlgorithmExact`` (the exact MMP algorithm
of Surazhsky et al. 2005, the ``geodesic`` C++ library by Kirsanov), distances to all vertices.
"""
from __future__ import annotations

import time

import numpy as np

from harness.tasks.geodesics import manifold_precheck
from methods import GeodesicResult, Param, register


@register("potpourri3d.heat", task="geodesics", library="potpourri3d", requires=("potpourri3d",),
          cite="Crane, Weischedel, Wardetzky 2013; Sharp & Crane 2020 (geometry-central)",
          params={"t_factor": Param("t_factor", 1.0, "float", low=1e-4, high=1e4, doc="t_coef: t = t_coef * h^2"),
                  "robust": Param("robust", True, "bool", doc="use_robust: tufted intrinsic Delaunay operators")})
def heat(V, F, *, sources, t_factor=1.0, robust=True):
    """geometry-central's heat method through potpourri3d (module docstring)."""
    import potpourri3d as pp3d
    t0 = time.perf_counter()
    solver = pp3d.MeshHeatMethodDistanceSolver(V, F, t_coef=float(t_factor), use_robust=bool(robust))
    t1 = time.perf_counter()
    D = np.stack([np.asarray(solver.compute_distance(int(s)), dtype=np.float64) for s in sources])
    t2 = time.perf_counter()
    return GeodesicResult(D=D, precompute_s=t1 - t0, per_source_s=(t2 - t1) / max(len(sources), 1))


@register("pygeodesic.exact", task="geodesics", library="pygeodesic", requires=("pygeodesic",), precheck=manifold_precheck,
          cite="Surazhsky et al. 2005 (Kirsanov's geodesic library)")
def exact(V, F, *, sources):
    """Exact polyhedral distance from each source to all vertices (module docstring); ``inf`` at
    vertices of another connected component than the source's. The library fails on a vertex
    it cannot reach (an integer overflow), so on a mesh of several components each source's
    component is solved on its own (its own precompute)."""
    from pygeodesic.geodesic import PyGeodesicAlgorithmExact
    from harness.core.geometry import vertex_components
    F = np.asarray(F, dtype=np.int64)
    comp = vertex_components(F, len(V))
    D = np.full((len(sources), len(V)), np.inf)
    pre = per = 0.0
    for c in np.unique(comp[np.asarray(sources)]):
        keep = comp == c
        Fc = F[keep[F[:, 0]]]
        new = np.cumsum(keep) - 1                     # old vertex index -> index in the component
        t0 = time.perf_counter()
        algo = PyGeodesicAlgorithmExact(np.ascontiguousarray(V[keep]), np.ascontiguousarray(new[Fc], dtype=np.int32))
        t1 = time.perf_counter()
        for i, s in enumerate(sources):
            if comp[s] == c:
                D[i, keep] = np.asarray(algo.geodesicDistances(np.array([new[s]], np.int32))[0], dtype=np.float64)
        pre, per = pre + t1 - t0, per + time.perf_counter() - t1
    return GeodesicResult(D=D, precompute_s=pre, per_source_s=per / max(len(sources), 1))
