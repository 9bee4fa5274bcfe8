"""The heat method for geodesic distance (Crane, Weischedel & Wardetzky 2013, "Geodesics in
heat", ACM TOG 32(5)), on our own operators, prefactored.

With ``W`` the cotangent Laplacian (libigl's sign: negative semi-definite), ``M`` the vertex
mass and ``t = t_factor * h^2`` (``h`` the mean edge length). The default mass is the mixed
Voronoi one of libigl's ``heat_geodesics`` (which the default settings reproduce to 1e-13);
geometry-central, the authors' implementation, lumps barycentric areas (``mass: barycentric``;
mean relative error barycentric 0.0227 and Voronoi 0.0247 on bunny, 0.110 and 0.116 on the
non-Delaunay plane, within 0.3% of each other on the sphere, camelhead and woody):

1. heat: ``(M - t W) u = delta_s`` (1 at the source). With a boundary, ``boundary: average``
   averages the Neumann solution and the Dirichlet one (``u = 0`` on the boundary), as the paper
   recommends; ``neumann``/``dirichlet`` use one of them. The boundary is the input mesh's, also
   with ``laplacian: tufted`` (whose cover has none: there the Neumann solution is the cover's
   natural one, and the Dirichlet one fixes ``u = 0`` at the input's boundary vertices), so that
   one ``boundary`` setting compares the three operators under the same condition;
2. ``X = grad u / |grad u|`` per face;
3. Poisson: ``-W phi = b``, ``b_i = sum_f A_f grad(phi_i) . X_f`` (one vertex of each connected
   component pinned), then ``phi`` shifted to 0 at the source (and negated if its mean over the
   source's component is negative, so distances are positive); ``+inf`` on the other components.

``boundary: dirichlet`` with a source on the boundary is a ValueError (the heat step is zero).

Everything is computed from edge lengths only (per face: ``e . grad u`` is the difference of
``u`` along the edge, ``|grad u|`` comes from the Gram matrix of two edges, and
``A_f grad(phi_i) . grad u = -1/2 sum cot * (u_j - u_i)``), so the same code runs on the mesh
(``laplacian: cotan``) and on its intrinsic Delaunay triangulation (``laplacian:
intrinsic_delaunay``, Sharp, Soliman & Crane 2019 / Sharp & Crane 2020: positive weights, hence
a maximum principle for ``u``). The two matrices are factored once per call and reused for every
source; the result reports that split (``precompute_s``, ``per_source_s``).
"""
from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from harness.core.geometry import (boundary_vertices, cotangents_from_lengths, edge_lengths, mean_edge_length,
                                   referenced, vertex_components)
from harness.core.solvers import factorize
from methods import GeodesicResult, Param, register
from methods.scratch import operators as op
from methods.vocabulary import solver_param


def _operators(V, F, laplacian: str, mass: str):
    """(l, F, W, M diagonal, cot) on the chosen triangulation."""
    n = len(V)
    if laplacian == "intrinsic_delaunay":
        from methods.scratch.intrinsic_delaunay import intrinsic_delaunay_triangulation
        l, F, _ = intrinsic_delaunay_triangulation(V, F)
    elif laplacian == "tufted":
        from methods.scratch.tufted import tufted_triangulation
        l, F, _ = tufted_triangulation(V, F, mollify_factor=1e-5)
    else:
        l = edge_lengths(V, F)
    C, dbl = cotangents_from_lengths(l)
    W = op.assemble_weights(F, 0.5 * C, n)
    if mass == "voronoi":
        m = op.mixed_voronoi_from_cotangents(F, C, l * l, dbl, n)
    else:
        m = np.bincount(F.ravel(), weights=np.repeat(dbl / 6.0, 3), minlength=n)
    return l, F, W, m, C, dbl


def _unit_gradient_divergence(u: np.ndarray, F: np.ndarray, l: np.ndarray, C: np.ndarray, n: int) -> np.ndarray:
    """``b_i = sum_f A_f grad(phi_i) . X_f`` for ``X = grad u / |grad u|`` (module docstring)."""
    a, b, c = F[:, 0], F[:, 1], F[:, 2]
    du1, du2 = u[b] - u[a], u[c] - u[a]                   # along edges ab, ac
    s = np.maximum(np.abs(du1), np.abs(du2))
    s = np.where(s > 0, s, 1.0)                             # scale first: u can be ~1e-300 far away
    x1, x2 = du1 / s, du2 / s
    lab2, lac2, lbc2 = l[:, 2] ** 2, l[:, 1] ** 2, l[:, 0] ** 2
    g12 = 0.5 * (lab2 + lac2 - lbc2)
    det = lab2 * lac2 - g12 * g12
    q = (lac2 * x1 * x1 - 2 * g12 * x1 * x2 + lab2 * x2 * x2) / np.where(det > 0, det, 1.0)
    g = s * np.sqrt(np.maximum(q, 0.0))                     # |grad u| per face
    inv = np.where((g > 0) & (det > 0), 1.0 / np.where(g > 0, g, 1.0), 0.0)
    # corner k weights the edge opposite it: A grad(phi_i) . grad u = -1/2 sum_k cot_k (u_j - u_i)
    out = np.zeros(n)
    for k in range(3):
        i, j = F[:, (k + 1) % 3], F[:, (k + 2) % 3]
        w = -0.5 * C[:, k] * inv * (u[j] - u[i])
        out += np.bincount(i, weights=w, minlength=n) - np.bincount(j, weights=w, minlength=n)
    return out


class HeatSolver:
    """The factored heat method on one mesh: ``distance(s)`` for any source vertex ``s``."""

    def __init__(self, V, F, t_factor=1.0, laplacian="cotan", mass="voronoi", boundary="average", solver="auto"):
        n = len(V)
        self.n = n
        unused = np.flatnonzero(~referenced(np.asarray(F), n))
        if unused.size:        # no mass, an empty row: the heat step is singular there
            raise ValueError(f"{unused.size} vertices no face uses (first: {unused[:5].tolist()}): drop them first "
                             "(harness.core.geometry.compact)")
        self.l, self.F, W, m, self.C, _ = _operators(V, F, laplacian, mass)
        lone = np.flatnonzero(referenced(np.asarray(F), n) & ~(m > 0))
        if lone.size:          # only on zero-area faces of the triangulation used: an empty row, a singular step
            raise ValueError(f"{lone.size} vertices lie only on zero-area faces (first: {lone[:5].tolist()}): they "
                             f"have no mass with laplacian: {laplacian}, and the heat step is singular there")
        t = float(t_factor) * mean_edge_length(V, F) ** 2
        Q = (sp.diags(m) - t * W).tocsr()
        bnd = boundary_vertices(F, n)      # the input's boundary, whatever triangulation the operators use
        use_n = boundary in ("neumann", "average") or not bnd.any()
        use_d = boundary in ("dirichlet", "average") and bnd.any()
        self.neumann = factorize(Q, solver) if use_n else None
        self.free = np.flatnonzero(~bnd)
        self.use_d = use_d            # every vertex on the boundary: the Dirichlet solution is u = 0
        self.dirichlet = factorize(Q[self.free][:, self.free].tocsr(), solver) if use_d and self.free.size else None
        self.boundary = bnd if boundary == "dirichlet" else None
        self.comp = vertex_components(F, n)
        pinned = np.zeros(n, bool)
        pinned[np.unique(self.comp, return_index=True)[1]] = True   # one vertex per connected component
        self.unpinned = np.flatnonzero(~pinned)
        K = (-W).tocsr()[self.unpinned][:, self.unpinned]
        self.poisson = factorize(K.tocsr(), solver)

    def heat(self, s: int) -> np.ndarray:
        delta = np.zeros(self.n)
        delta[s] = 1.0
        parts = []
        if self.neumann is not None:
            parts.append(self.neumann.solve(delta))
        if self.use_d:
            ud = np.zeros(self.n)
            if self.dirichlet is not None:
                ud[self.free] = self.dirichlet.solve(delta[self.free])
            parts.append(ud)
        return sum(parts) / len(parts)

    def distance(self, s: int) -> np.ndarray:
        if self.boundary is not None and self.boundary[s]:
            raise ValueError(f"boundary: dirichlet with source vertex {s} on the boundary: the heat step is zero "
                             "there (u = 0 on the boundary); use boundary: average or neumann")
        u = self.heat(s)
        b = _unit_gradient_divergence(u, self.F, self.l, self.C, self.n)
        phi = np.zeros(self.n)
        phi[self.unpinned] = self.poisson.solve(b[self.unpinned])
        mine = self.comp == self.comp[s]
        phi -= phi[s]
        if phi[mine].mean() < 0:
            phi = -phi
        phi[~mine] = np.inf                                 # not reachable from the source
        return phi


@register("scratch.heat", task="geodesics", library="scratch",
          cite="Crane, Weischedel, Wardetzky, Geodesics in heat, ACM TOG 32(5), 2013",
          params={"t_factor": Param("t_factor", 1.0, "float", low=1e-4, high=1e4,
                                    doc="heat time t = t_factor * (mean edge length)^2 (the paper's m)"),
                  "laplacian": Param("laplacian", "cotan", choices=("cotan", "intrinsic_delaunay", "tufted"),
                                     doc="operators on the mesh, on its intrinsic Delaunay triangulation, or on "
                                         "the intrinsic Delaunay triangulation of its tufted cover"),
                  "mass": Param("mass", "voronoi", choices=("voronoi", "barycentric"),
                                doc="vertex mass of the heat step: voronoi (libigl's heat_geodesics, the default "
                                    "here) or barycentric (one third of the incident triangles' areas: the "
                                    "paper's reference implementation, geometry-central)"),
                  "boundary": Param("boundary", "average", choices=("average", "neumann", "dirichlet"),
                                    doc="heat-step boundary condition on open meshes (the paper: average)"),
                  "solver": solver_param()})
def heat(V, F, *, sources, t_factor=1.0, laplacian="cotan", mass="voronoi", boundary="average", solver="auto"):
    """Geodesic distance by the heat method (module docstring); one factorization for all sources."""
    t0 = time.perf_counter()
    hs = HeatSolver(V, F, t_factor, laplacian, mass, boundary, solver)
    t1 = time.perf_counter()
    D = np.stack([hs.distance(int(s)) for s in sources])
    t2 = time.perf_counter()
    return GeodesicResult(D=D, precompute_s=t1 - t0, per_source_s=(t2 - t1) / max(len(sources), 1))
