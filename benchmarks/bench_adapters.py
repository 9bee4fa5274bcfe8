"""Benchmark: every library adapter (a registered method wrapping a third-party library) as the
harness times it, against the plain call(s) a user would write to get the same numbers.

Run:  .venv/bin/python benchmarks/bench_adapters.py [--mesh armadillo] [--pairs 7] [--only NAME[,NAME]]
      [--quick] [--budget 30] [--list]

A = what the runner times: ``run()`` of ``run, finish = method.bind(V.copy(), F.copy())`` with the
adapter's defaults and the task's default parameters (a fresh ``bind`` before every call, untimed;
before it, as in `harness.runner.run_case`, the solvers' symbolic cache is cleared
(`harness.runner.forget_inputs`) and the heap trimmed). B = the plain pipeline below, on copies
of the same arrays, with the same library calls and settings and the same target (simplification:
``target_faces`` as the task's ``prepare`` computes it, ``round(0.5 m)``; geodesics: the task's
seeded source vertex, one source). B does none of the adapter's by-design extras (input screens,
finiteness checks, dtype conversions, compaction, mapping vertices back to the input order, K/H
from k1/k2); a screen the adapter declares as ``precheck`` (libigl's zero-area faces) runs in
``bind``, untimed, as in the runner. Both run warm in one process: one untimed call each (whose outputs are the ones
compared), then the pairs in alternating order (A B, B A, A B, ...); ``time.perf_counter`` around the call only. Per adapter:
the median, min and max of the per-pair ratio A/B and the median times; ``os.getloadavg()`` at
start and end. Pairs: ``--pairs`` (default 7), fewer (at least 3) where the timed pairs pass
``--budget`` seconds (default 30) per adapter first (on armadillo libigl.exact_geodesic, ~15 s a
call, and trimesh.curvature_measure, ~7 s, run 3); ``--quick`` runs 3 pairs and skips those two
unless named in ``--only``. The whole default run takes about 6 minutes on 2 cores.

Output cross-check (always): the adapter's validated output ``finish(run())`` against B's output,
max absolute difference relative to the scale named in the row (bounding-box diagonal for
positions, max |value| otherwise), against the row's tolerance; rows beyond it are marked
MISMATCH (their ratio compares different computations). What is compared:
- laplacian: W and M (dense max of the sparse difference; robust.tufted: W = -L).
- smoothing: V in the caller's order. MeshLab keeps the order (all vertices referenced); PyGEL
  reorders, so B's positions are mapped through the adapter's own ``build_manifold`` index
  (computed untimed, from_triangles is deterministic).
- curvature: K, H (and k1 >= k2 where the adapter has them; B's two arrays sorted per vertex).
- geodesics: the distance row; spectrum: the sorted eigenvalues (ARPACK, same v0 and shift).
- simplification: B's output compacted (untimed, `harness.core.geometry.compact`), then face
  arrays must be equal and V is compared.
Expected differences, stated per row: ``lbar`` (mean length of the unique edges) comes from
``igl.avg_edge_length`` in B (libigl.heat, libigl.implicit, meshlab.scale_dependent) and from
trimesh's ``edges_unique_length`` (trimesh.curvature_measure), the adapters compute it with numpy:
the last bits of ``h`` may differ (tolerance 1e-12). libigl.implicit: the adapter factors with the
harness's automatic solver choice (printed at the end: PARDISO with SPD settings, upper triangle
and nested dissection on armadillo; qdldl on small meshes such as bunny) where B calls
``pypardiso.spsolve`` (its defaults, real nonsymmetric): equal to solver precision (1e-9);
pypardiso's stored factorization is freed before every B call (untimed), as the runner clears the
adapter's. PyGEL has no bulk face accessor: pygel.qem's B reads faces through an ``off_save``
round trip, as the adapter does (a ``circulate_face`` loop costs ~0.14 s more at 43k faces), and
runs one ``quadric_simplify`` pass (the adapter repeats passes while it is 1% + 2 faces above the
target: on armadillo one pass reaches it; where it does not, the row says MISMATCH).
open3d.qem needs the optional ``open3d`` extra: skipped when it does not import.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

SLOW = ("libigl.exact_geodesic", "trimesh.curvature_measure")   # skipped by --quick unless --only
EXACT = 1e-12          # same library, same call: identical up to the last bits of a derived scale


# ------------------------------------------------------------------------------ plain pipelines
# Each takes (V, F, p) with p.target (faces) and p.source (vertex) from the task's defaults.

def p_fast_simplification(V, F, p):
    import fast_simplification
    return fast_simplification.simplify(V, F, target_count=p.target, agg=7.0, preserve_border=False)


def p_pyfqmr(V, F, p):
    import pyfqmr
    s = pyfqmr.Simplify()
    s.setMesh(V, F)
    s.simplify_mesh(target_count=p.target, aggressiveness=7.0, preserve_border=False, max_iterations=100,
                    verbose=False)
    Vo, Fo, _ = s.getMesh()
    return Vo, Fo


def p_meshoptimizer(V, F, p):
    import meshoptimizer as mo
    dest = np.zeros(F.size, dtype=np.uint32)
    count = mo.simplify(dest, F.ravel(), V, target_index_count=3 * p.target, target_error=1.0)
    return V, dest[:count].reshape(-1, 3)


def p_open3d(V, F, p):
    import open3d as o3d
    mesh = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(V), o3d.utility.Vector3iVector(F))
    out = mesh.simplify_quadric_decimation(target_number_of_triangles=p.target)
    return np.asarray(out.vertices), np.asarray(out.triangles)


def p_qslim(V, F, p):
    import igl
    U, G, _, _ = igl.qslim(V, F, p.target)
    return U, G


def p_decimate(V, F, p):
    import igl
    U, G, _, _ = igl.decimate(V, F, p.target)
    return U, G


def p_meshlab_qem(V, F, p):
    import pymeshlab
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F))
    ms.meshing_decimation_quadric_edge_collapse(targetfacenum=p.target)   # every other setting: MeshLab's default
    m = ms.current_mesh()
    return m.vertex_matrix(), m.face_matrix()


def p_pygel_qem(V, F, p):
    from pygel3d import hmesh
    m = hmesh.Manifold.from_triangles(V, F)
    nv, nf = len(V), len(F)
    hmesh.quadric_simplify(m, (nv - (nf - p.target) / 2.0) / nv, singular_thresh=1e-4, error_thresh=1e30)
    m.cleanup()
    P = np.array(m.positions())
    with tempfile.TemporaryDirectory() as d:          # no bulk face accessor: the OFF export
        path = os.path.join(d, "m.off")
        hmesh.off_save(path, m)
        with open(path) as fh:
            tok = fh.read().split()
    n, k = int(tok[1]), int(tok[2])
    G = np.asarray(tok[4 + 3 * n:4 + 3 * n + 4 * k], dtype=np.int64).reshape(k, 4)[:, 1:]
    return P, G


def _pygel_smooth(apply):
    def plain(V, F, p):
        from pygel3d import hmesh
        m = hmesh.Manifold.from_triangles(V, F)
        apply(hmesh, m)
        return np.array(m.positions())               # PyGEL's vertex order
    return plain


p_pygel_laplacian = _pygel_smooth(lambda h, m: h.laplacian_smooth(m, 0.25, 10))
p_pygel_taubin = _pygel_smooth(lambda h, m: h.taubin_smooth(m, 10))
p_pygel_anisotropic = _pygel_smooth(lambda h, m: h.anisotropic_smooth(m, 0.5, 1))


def _meshlab(apply):
    def plain(V, F, p):
        import pymeshlab
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(V, F))
        return apply(ms, pymeshlab, V, F, p)
    return plain


def _ml_smooth(filt):
    def apply(ms, pm, V, F, p):
        filt(ms, pm, V, F)
        return ms.current_mesh().vertex_matrix()
    return _meshlab(apply)


p_ml_laplacian = _ml_smooth(lambda ms, pm, V, F: ms.apply_coord_laplacian_smoothing(
    stepsmoothnum=10, cotangentweight=True, boundary=True))
p_ml_taubin = _ml_smooth(lambda ms, pm, V, F: ms.apply_coord_taubin_smoothing(lambda_=0.5, mu=-0.53, stepsmoothnum=10))
p_ml_hc = _ml_smooth(lambda ms, pm, V, F: ms.apply_coord_hc_laplacian_smoothing())
p_ml_two_steps = _ml_smooth(lambda ms, pm, V, F: ms.apply_coord_two_steps_smoothing(
    stepsmoothnum=3, normalthr=60.0, stepnormalnum=20, stepfitnum=20))
p_ml_surface = _ml_smooth(lambda ms, pm, V, F: ms.apply_coord_laplacian_smoothing_surface_preserving(
    angledeg=0.5, iterations=1))


def _ml_scale(ms, pm, V, F):
    import igl
    ms.apply_coord_laplacian_smoothing_scale_dependent(
        stepsmoothnum=10, delta=pm.PureValue(0.25 * igl.avg_edge_length(V, F) ** 2))


p_ml_scale_dependent = _ml_smooth(_ml_scale)


def _ml_discrete(ms, pm, V, F, p):
    out = []
    for kind in ("Gaussian Curvature", "Mean Curvature"):
        ms.compute_scalar_by_discrete_curvature_per_vertex(curvaturetype=kind)
        out.append(ms.current_mesh().vertex_scalar_array())
    return out


def _ml_principal(ms, pm, V, F, p):
    out = []
    for kind in ("Min Curvature", "Max Curvature"):
        ms.compute_curvature_principal_directions_per_vertex(method="Quadric Fitting", curvcolormethod=kind,
                                                             scale=pm.PercentageValue(10.0), autoclean=False)
        out.append(ms.current_mesh().vertex_scalar_array())
    return out


def _ml_geodesic(ms, pm, V, F, p):
    ms.compute_scalar_by_geodesic_distance_from_given_point_per_vertex(
        startpoint=V[p.source], maxdistance=pm.PureValue(1e300))
    return ms.current_mesh().vertex_scalar_array()


def p_ml_heat_geodesic(V, F, p):
    import pymeshlab
    mark = np.zeros(len(V))
    mark[p.source] = 1.0
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F, v_scalar_array=mark))
    ms.compute_selection_by_condition_per_vertex(condselect="q > 0.5")
    ms.compute_scalar_by_heat_geodesic_distance_from_selection_per_vertex(m=1.0)
    return ms.current_mesh().vertex_scalar_array()


def p_ml_apss(V, F, p):
    import pymeshlab
    out = []
    for kind in (1, 0):                                 # Gauss, Mean (k1 + k2: halved)
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(V, F))
        ms.compute_curvature_and_color_apss_per_vertex(filterscale=2.0, curvaturetype=kind)
        out.append(ms.current_mesh().vertex_scalar_array() * (0.5 if kind == 0 else 1.0))
    return out


p_ml_discrete_curvature = _meshlab(_ml_discrete)
p_ml_principal_curvature = _meshlab(_ml_principal)
p_ml_geodesic = _meshlab(_ml_geodesic)


def p_cotan(V, F, p):
    import igl
    return igl.cotmatrix(V, F), igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI)


def p_intrinsic_delaunay(V, F, p):
    import igl
    L, l, Fi = igl.intrinsic_delaunay_cotmatrix(V, F)
    return L, igl.massmatrix_intrinsic(l, Fi, igl.MASSMATRIX_TYPE_VORONOI)


def p_gaussian_curvature(V, F, p):
    import igl
    return igl.gaussian_curvature(V, F) / igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI).diagonal()


def p_principal_curvature(V, F, p):
    import igl
    _, _, pv1, pv2, _ = igl.principal_curvature(V, F, 5)
    return pv1, pv2


def p_heat(V, F, p):
    import igl
    data = igl.HeatGeodesicsData()
    igl.heat_geodesics_precompute(V, F, igl.avg_edge_length(V, F) ** 2, data)
    d = igl.heat_geodesics_solve(data, np.array([p.source]))
    return d - d[p.source]


def p_exact_geodesic(V, F, p):
    import igl
    return igl.exact_geodesic(V, F, VS=np.array([p.source]), VT=np.arange(len(V)))


def p_eigsh(V, F, p):
    import igl
    from scipy.sparse.linalg import eigsh
    L = igl.cotmatrix(V, F)
    M = igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI)
    d = -L.diagonal() / M.diagonal()
    sigma = -1e-8 * np.median(d[d > 0])                  # the adapter's shift (scratch.spectrum's)
    return eigsh(-L, k=20, M=M, sigma=sigma, which="LM", v0=np.random.default_rng(0).standard_normal(len(V)))


def p_implicit(V, F, p):
    import igl
    import pypardiso
    L = igl.cotmatrix(V, F)
    M = igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI)
    h = igl.avg_edge_length(V, F) ** 2
    return pypardiso.spsolve((M - h * L).tocsr(), M @ V)


def _free_pardiso():
    import pypardiso
    pypardiso.ps.free_memory(everything=True)          # its stored factor of the same matrix: a first call


def p_pp3d_heat(V, F, p):
    import potpourri3d as pp3d
    return pp3d.MeshHeatMethodDistanceSolver(V, F).compute_distance(p.source)


def p_pygeodesic(V, F, p):
    from pygeodesic.geodesic import PyGeodesicAlgorithmExact
    return PyGeodesicAlgorithmExact(V, F).geodesicDistances(np.array([p.source]))[0]


def p_robust(V, F, p):
    import robust_laplacian
    return robust_laplacian.mesh_laplacian(V, F)


def p_trimesh(V, F, p):
    import trimesh
    m = trimesh.Trimesh(vertices=V, faces=F, process=False)
    r = 3.0 * m.edges_unique_length.mean()
    a = np.pi * r * r
    return (trimesh.curvature.discrete_gaussian_curvature_measure(m, V, r) / a,
            trimesh.curvature.discrete_mean_curvature_measure(m, V, r) / a)


# ------------------------------------------------------------------------------ comparisons
# Each returns (relative max difference, what was compared); inf when shapes/faces differ.

def _rel(a, b, scale):
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if a.shape != b.shape:
        return np.inf
    return float(np.abs(a - b).max() / scale) if a.size else 0.0


def _sparse_rel(A, B):
    import scipy.sparse as sp
    A, B = sp.csr_matrix(A), sp.csr_matrix(B)
    if A.shape != B.shape:
        return np.inf
    return float(abs(A - B).max() / max(abs(A).max(), 1e-300))


def c_laplacian(R, out, V, F):
    return max(_sparse_rel(R.W, out[0]), _sparse_rel(R.M, out[1])), "W, M / max|.|"


def c_robust(R, out, V, F):
    return max(_sparse_rel(R.W, -out[0]), _sparse_rel(R.M, out[1])), "W=-L, M / max|.|"


def _diag(V):
    return float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))


def c_smooth(R, out, V, F):
    return _rel(R.V, out, _diag(V)), "V / diagonal"


def c_pygel_smooth(R, out, V, F):
    from methods.pygel.smoothing import build_manifold
    _, index = build_manifold(V, F)                     # the adapter's map to the caller's order
    mapped, ok = V.copy(), index >= 0
    mapped[ok] = np.asarray(out)[index[ok]]
    return _rel(R.V, mapped, _diag(V)), "V mapped to input order / diag"


def c_simplify(R, out, V, F):
    from harness.core.geometry import compact
    Vb, Fb = compact(np.asarray(out[0]), np.asarray(out[1]))
    if R.F.shape != Fb.shape or not np.array_equal(R.F, Fb):
        return np.inf, f"faces {len(R.F)} vs {len(Fb)}, F differ"
    return _rel(R.V, Vb, _diag(V)), f"F equal ({len(Fb)}), V / diag"


def c_K(R, out, V, F):
    return _rel(R.K, out, np.abs(R.K).max()), "K / max|K|"


def c_KH(R, out, V, F):
    return max(_rel(R.K, out[0], np.abs(R.K).max()), _rel(R.H, out[1], np.abs(R.H).max())), "K, H / max|.|"


def c_k12(R, out, V, F):
    a, b = np.asarray(out[0], dtype=np.float64), np.asarray(out[1], dtype=np.float64)
    s = max(np.abs(R.k1).max(), np.abs(R.k2).max())
    return max(_rel(R.k1, np.maximum(a, b), s), _rel(R.k2, np.minimum(a, b), s)), "k1, k2 / max|k|"


def c_geo(R, out, V, F):
    return _rel(R.D[0], np.ravel(out), np.abs(R.D[0]).max()), "D / max D"


def c_spectrum(R, out, V, F):
    return _rel(R.values, np.sort(out[0]), np.abs(R.values).max()), "eigenvalues / max"


# name -> (plain, compare, tolerance, before each B call or None, note)
CASES = {
    "fast_simplification.qem": (p_fast_simplification, c_simplify, EXACT, None, ""),
    "pyfqmr.qem": (p_pyfqmr, c_simplify, EXACT, None, ""),
    "meshoptimizer.qem": (p_meshoptimizer, c_simplify, EXACT, None, ""),
    "open3d.qem": (p_open3d, c_simplify, EXACT, None, ""),
    "libigl.qslim": (p_qslim, c_simplify, EXACT, None, ""),
    "libigl.decimate": (p_decimate, c_simplify, EXACT, None, ""),
    "meshlab.qem": (p_meshlab_qem, c_simplify, EXACT, None, ""),
    "pygel.qem": (p_pygel_qem, c_simplify, EXACT, None, "B: one quadric_simplify pass; faces via off_save"),
    "pygel.laplacian": (p_pygel_laplacian, c_pygel_smooth, EXACT, None, "B in PyGEL's order, mapped for the check"),
    "pygel.taubin": (p_pygel_taubin, c_pygel_smooth, EXACT, None, "B in PyGEL's order, mapped for the check"),
    "pygel.anisotropic": (p_pygel_anisotropic, c_pygel_smooth, EXACT, None, "B in PyGEL's order, mapped for the check"),
    "meshlab.laplacian": (p_ml_laplacian, c_smooth, EXACT, None, ""),
    "meshlab.taubin": (p_ml_taubin, c_smooth, EXACT, None, ""),
    "meshlab.hc": (p_ml_hc, c_smooth, EXACT, None, ""),
    "meshlab.two_steps": (p_ml_two_steps, c_smooth, EXACT, None, ""),
    "meshlab.surface_preserving": (p_ml_surface, c_smooth, EXACT, None, ""),
    "meshlab.scale_dependent": (p_ml_scale_dependent, c_smooth, EXACT, None, "lbar: igl.avg_edge_length in B"),
    "meshlab.discrete_curvature": (p_ml_discrete_curvature, c_KH, EXACT, None, ""),
    "meshlab.principal_curvature": (p_ml_principal_curvature, c_k12, EXACT, None, ""),
    "meshlab.apss_curvature": (p_ml_apss, c_KH, EXACT, None, ""),
    "meshlab.geodesic": (p_ml_geodesic, c_geo, EXACT, None, ""),
    "meshlab.heat_geodesic": (p_ml_heat_geodesic, c_geo, EXACT, None, ""),
    "libigl.cotan": (p_cotan, c_laplacian, EXACT, None, ""),
    "libigl.intrinsic_delaunay": (p_intrinsic_delaunay, c_laplacian, EXACT, None, ""),
    "libigl.gaussian_curvature": (p_gaussian_curvature, c_K, EXACT, None, ""),
    "libigl.principal_curvature": (p_principal_curvature, c_k12, EXACT, None, ""),
    "libigl.heat": (p_heat, c_geo, EXACT, None, "lbar: igl.avg_edge_length in B"),
    "libigl.exact_geodesic": (p_exact_geodesic, c_geo, EXACT, None, ""),
    "libigl.eigsh": (p_eigsh, c_spectrum, 1e-8, None, "ARPACK shift-invert, same v0 and sigma"),
    "libigl.implicit": (p_implicit, c_smooth, 1e-9, _free_pardiso,
                        "A: the harness's automatic solver (named below), B: pypardiso.spsolve defaults"),
    "potpourri3d.heat": (p_pp3d_heat, c_geo, EXACT, None, ""),
    "pygeodesic.exact": (p_pygeodesic, c_geo, EXACT, None, ""),
    "robust.tufted": (p_robust, c_robust, EXACT, None, ""),
    "trimesh.curvature_measure": (p_trimesh, c_KH, EXACT, None, "r from trimesh edges_unique_length in B"),
}


class _Setup:
    def __init__(self, target, source):
        self.target, self.source = target, source


def _setup(method, V, F) -> _Setup:
    """The target / source the adapter receives: its defaults through the task's ``prepare``."""
    from harness import tasks
    full = method.resolve_params({})
    task = tasks.get(method.task)
    if task.prepare is not None:
        full = task.prepare(full, V, F)
    src = full.get("sources")
    return _Setup(full.get("target_faces"), int(src[0]) if src is not None else None)


def _bench(method, case, V, F, pairs, budget, min_pairs):
    from harness.runner import _trim_heap, forget_inputs     # the runner's own steps before a call
    plain, compare, tol, before, note = case
    p = _setup(method, V, F)

    def run_a():
        run, finish = method.bind(V.copy(), F.copy())        # untimed, as the runner
        forget_inputs()
        _trim_heap()
        t0 = time.perf_counter()
        r = run()
        return time.perf_counter() - t0, r, finish

    def run_b():
        Vb, Fb = V.copy(), F.copy()
        if before is not None:
            before()
        _trim_heap()
        t0 = time.perf_counter()
        out = plain(Vb, Fb, p)
        return time.perf_counter() - t0, out

    ta0, r, finish = run_a()                                 # warm-up (and the outputs compared)
    R = finish(r)
    tb0, out = run_b()
    diff, what = compare(R, out, V, F)
    del r, R, out
    ta, tb = [], []
    while len(ta) < pairs and not (len(ta) >= min_pairs and sum(ta) + sum(tb) > budget):
        for side in ("ab" if len(ta) % 2 == 0 else "ba"):      # A B, B A, A B, ...: no order effect
            if side == "a":
                t, r, _ = run_a()
                ta.append(t)
                del r
            else:
                t, out = run_b()
                tb.append(t)
                del out
    ratios = [a / b for a, b in zip(ta, tb)]
    return dict(n=len(ta), ta=statistics.median(ta), tb=statistics.median(tb), r=statistics.median(ratios),
                rmin=min(ratios), rmax=max(ratios), diff=diff, what=what, tol=tol, note=note)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default="armadillo")
    ap.add_argument("--pairs", type=int, default=7)
    ap.add_argument("--budget", type=float, default=30.0,
                    help="timed seconds per adapter after which no further pair starts (at least 3 pairs)")
    ap.add_argument("--only", default="", help="comma-separated adapter names")
    ap.add_argument("--quick", action="store_true", help=f"3 pairs; skip {', '.join(SLOW)} unless in --only")
    ap.add_argument("--list", action="store_true", help="list the adapters and exit")
    a = ap.parse_args(argv)

    from harness import datasets
    from harness.plugins import import_methods
    methods = import_methods()
    adapters = [m for m in methods.all_methods() if m.library != "scratch"]
    if a.list:
        for m in adapters:
            why = m.unavailable_reason()
            plain = CASES.get(m.name, (None,))[0]
            name = next((k for k, v in globals().items() if v is plain and k.startswith("p_")), "-")
            print(f"{m.name:28s} {m.task:15s} {m.library:20s} plain {name:26s}"
                  f"{'' if why is None else ' unavailable'}")
        return 0
    only = [s.strip() for s in a.only.split(",") if s.strip()]
    unknown = [s for s in only if s not in {m.name for m in adapters}]
    if unknown:
        ap.error(f"unknown adapter(s) {unknown}; see --list")
    if only:
        adapters = [m for m in adapters if m.name in only]
    elif a.quick:
        adapters = [m for m in adapters if m.name not in SLOW]
    pairs = 3 if a.quick else a.pairs

    src = datasets.load(a.mesh)
    V = np.ascontiguousarray(src.clean.V, dtype=np.float64)
    F = np.ascontiguousarray(src.clean.F, dtype=np.int64)
    print(f"mesh {a.mesh}: {len(V):,} vertices, {len(F):,} faces; pairs {pairs} (budget {a.budget:g} s per "
          f"adapter, at least 3); cpus {os.cpu_count()}; load average {os.getloadavg()}", flush=True)
    head = (f"{'adapter':28s} {'pairs':>5s} {'A ms':>9s} {'B ms':>9s}  {'A/B med (min-max)':22s} "
            f"{'output diff (tol)':27s} compared")
    print(head)
    print("-" * len(head))
    rows, errors = {}, []
    for m in adapters:
        why = m.unavailable_reason()
        if m.name not in CASES:
            print(f"{m.name:28s} skipped: no plain pipeline in this benchmark", flush=True)
            errors += [m.name] if m.name in only else []         # asked for by name: not measured
            continue
        if why:
            print(f"{m.name:28s} skipped: unavailable ({why.split(';')[0]})", flush=True)
            errors += [m.name] if m.name in only else []
            continue
        try:
            r = _bench(m, CASES[m.name], V, F, pairs, a.budget, 3)
        except Exception as exc:      # one adapter failing must not end the run
            print(f"{m.name:28s} error: {type(exc).__name__}: {str(exc)[:200]}", flush=True)
            errors.append(m.name)
            continue
        rows[m.name] = r
        bad = not (r["diff"] <= r["tol"])
        ratio = f"{r['r']:.3f} ({r['rmin']:.3f}-{r['rmax']:.3f})"
        out = f"{r['diff']:.1e} ({r['tol']:.0e}) {'MISMATCH' if bad else 'ok'}"
        print(f"{m.name:28s} {r['n']:5d} {r['ta'] * 1e3:9.1f} {r['tb'] * 1e3:9.1f}  {ratio:22s} {out:27s} {r['what']}"
              f"{'; ' + r['note'] if r['note'] else ''}", flush=True)
    if "libigl.implicit" in rows:
        from harness.core.solvers import used
        print(f"the harness's solver layer factored with: {', '.join(used()) or 'none'} in this process (libigl.implicit: the automatic choice)")
    over = [k for k, r in rows.items() if r["r"] > 1.05]
    bad = [k for k, r in rows.items() if not (r["diff"] <= r["tol"])]
    print(f"\nA/B median > 1.05: {', '.join(over) or 'none'}")
    print(f"outputs not matching: {', '.join(bad) or 'none'}")
    print(f"adapters that failed (or, asked for by --only, could not run): {', '.join(errors) or 'none'}")
    print(f"load average {os.getloadavg()}")
    return 1 if bad or errors else 0


if __name__ == "__main__":
    raise SystemExit(main())
