"""Benchmark: the harness's measuring of one case's output at 86k faces (part of the fixed cost
per case), against the measuring it replaced.

Run:  .venv/bin/python benchmarks/bench_measure.py [--mesh armadillo] [--repeats 9]

Everything runs in one process, A and B alternating, each warm (its compiled code loaded and one
untimed call first); per pair the ratio A / B, and the median (min-max) over the pairs.

- Laplacian PSD column (`harness.metrics.laplacian_properties`, whole measure) on the W of
  scratch.cotan, libigl.cotan, scratch.uniform and scratch.intrinsic_delaunay:
  A = the exact certificates (diagonal dominance, triangle split) before the factorisation,
  B = LDL^T inertia and Lanczos alone (the certificate switched off). Values are compared first:
  the same ``psd``, ``min_eig`` within its 1e-10 tolerance.
- Smoothing Hausdorff bracket (`harness.metrics.hausdorff`, corresponding vertices) of a
  scratch.taubin result against the clean mesh, the clean surface's hierarchy built once:
  A = the result's hierarchy refitted from the clean one (`Surface.displaced`), B = built afresh.
  Compared first: each bracket contains the other's lower bound, the clean-to-result lower bounds
  agree, and clean points' distances to the result are the same through either hierarchy.
- Simplification Hausdorff bracket and the sampled mean distance (20,000 points each way) of a
  fast_simplification result at 10% against the input, its hierarchy built once: A = the sample
  points queried along a Morton curve, B = the result's samples sorted by the face they were
  drawn on and the input's (drawn once per surface) in their drawing order. Compared
  first: the same bracket and one-sided bounds, the mean distance to 1e-12.
- Simplification Hausdorff bracket of fast_simplification and scratch.qem results at 10% of the
  clean mesh and of a noisy copy (gaussian_normal 0.3, the fixed-cost configs' input), with
  their samples: A = the direction with the larger sampled maximum first, its lower bound closing
  the other direction's triangles (``floor``), B = each direction bracketed on its own. Compared
  first: both certified, the same ``hausdorff``, each bracket holding the other's lower bound.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def _pairs(a, b, repeats):
    a(), b()
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        a()
        t1 = time.perf_counter()
        b()
        t2 = time.perf_counter()
        out.append((t1 - t0, t2 - t1))
    return out


def _report(label, pairs):
    ta, tb = [p[0] for p in pairs], [p[1] for p in pairs]
    r = [x / y for x, y in pairs]
    print(f"{label:70s} A {statistics.median(ta) * 1e3:7.1f} ms  B {statistics.median(tb) * 1e3:7.1f} ms  "
          f"A/B {statistics.median(r):.3f} ({min(r):.3f}-{max(r):.3f})")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default="armadillo")
    ap.add_argument("--repeats", type=int, default=9)
    args = ap.parse_args(argv)
    import harness.metrics.laplacian_properties as lp
    from harness import datasets
    from harness.metrics import surface_distance
    from harness.metrics.hausdorff import hausdorff
    from harness.noise import apply_noise
    from harness.plugins import import_methods
    methods = import_methods()
    m = datasets.load(args.mesh).clean
    print(f"mesh {args.mesh}: {len(m.V)} vertices, {len(m.F)} faces; load average {os.getloadavg()}")
    real = lp._certificate

    def off(S, V, F):
        return None, False
    for name in ("scratch.cotan", "libigl.cotan", "scratch.uniform", "scratch.intrinsic_delaunay"):
        W = methods.get(name)(m.V, m.F).W

        def a(W=W):
            lp._certificate = real
            return lp.laplacian_properties(W, None, m.V, m.F)

        def b(W=W):
            lp._certificate = off
            try:
                return lp.laplacian_properties(W, None, m.V, m.F)
            finally:
                lp._certificate = real
        ra, rb = a(), b()
        assert ra["psd"] == rb["psd"], (name, ra["psd"], rb["psd"])
        assert abs(ra["min_eig"] - rb["min_eig"]) <= 1e-10, (name, ra["min_eig"], rb["min_eig"])
        _report(f"laplacian_properties, {name}", _pairs(a, b, args.repeats))

    V_in = apply_noise(m.V, m.F, "gaussian_normal", 0.3, 0, mesh_key=args.mesh)
    V_out = methods.get("scratch.taubin")(V_in, m.F).V
    S = surface_distance.Surface(m.V, m.F)
    S.neighbours()
    fresh = surface_distance.Surface.displaced

    def rebuilt(self, V):
        return surface_distance.Surface(V, self.F)

    def run(displaced):
        surface_distance.Surface.displaced = displaced
        try:
            return hausdorff(V_out, m.F, m.V, m.F, n_samples=0, surface_b=S, corresponding=True, vertex_distances=True)
        finally:
            surface_distance.Surface.displaced = fresh
    ha, hb = run(fresh), run(rebuilt)
    assert ha["hausdorff"] <= hb["hausdorff_upper"] * (1 + 1e-12) and hb["hausdorff"] <= ha["hausdorff_upper"] * (1 + 1e-12)
    assert abs(ha["hausdorff_ba"] - hb["hausdorff_ba"]) <= 1e-12 * hb["hausdorff_ba"]   # the side the refit serves
    from harness.core.geometry import sample_surface
    from harness.metrics._bvh_kernel import query_many
    P = np.concatenate([sample_surface(m.V, m.F, 20000, 1), m.V])       # clean points against the result
    none = np.full(len(P), -1, np.int64)
    da = query_many(P, none, *S.displaced(V_out).bvh())[0]
    db = query_many(P, none, *surface_distance.Surface(V_out, m.F).bvh())[0]
    assert np.abs(da - db).max() <= 1e-15 * m.diagonal()
    _report("smoothing Hausdorff bracket (taubin, 0.3)", _pairs(lambda: run(fresh), lambda: run(rebuilt), args.repeats))

    from harness.metrics import hausdorff as H
    r = methods.get("fast_simplification.qem")(m.V, m.F, target_ratio=0.1)
    SI = surface_distance.Surface(m.V, m.F)
    SI.neighbours()
    spatial, sampler = H._in_spatial_order, H.sample_surface

    def by_face(V, F, n, seed=0):                  # the former order: the points sorted by their face
        P, f = sampler(V, F, n, seed, return_faces=True)
        return P[np.argsort(f, kind="stable")]

    def as_given(P, Y, order=None):
        d = query_many(np.ascontiguousarray(P), np.full(len(P), -1, np.int64), *Y.bvh())[0]
        Y.count += len(P)
        return d

    def simp(morton):
        H._in_spatial_order, H.sample_surface = (spatial, sampler) if morton else (as_given, by_face)
        try:
            return H.hausdorff(r.V, r.F, m.V, m.F, surface_b=SI)
        finally:
            H._in_spatial_order, H.sample_surface = spatial, sampler
    sa, sb = simp(True), simp(False)
    for key in ("hausdorff", "hausdorff_upper", "hausdorff_ab", "hausdorff_ba"):
        assert sa[key] == sb[key], (key, sa[key], sb[key])
    assert abs(sa["surface_dist_mean"] - sb["surface_dist_mean"]) <= 1e-12 * sb["surface_dist_mean"]
    _report("simplification Hausdorff + 2x20k samples (10%)", _pairs(lambda: simp(True), lambda: simp(False), args.repeats))

    alone = H.one_sided

    def unfloored(*a, **k):                       # each direction bracketed on its own
        k.pop("floor", None)
        return alone(*a, **k)

    def bracket(floor, res, VI, SI):
        H.one_sided = alone if floor else unfloored
        try:
            return H.hausdorff(res.V, res.F, VI, m.F, surface_b=SI)
        finally:
            H.one_sided = alone
    from harness.noise import apply_noise
    Vn = apply_noise(m.V, m.F, "gaussian_normal", 0.3, 0, mesh_key=args.mesh)
    SN = surface_distance.Surface(Vn, m.F)
    SN.neighbours()
    for name, noisy in (("fast_simplification.qem", False), ("scratch.qem", False),
                        ("fast_simplification.qem", True), ("scratch.qem", True)):
        VI, SI = (Vn, SN) if noisy else (m.V, surface_distance.Surface(m.V, m.F))
        res = methods.get(name)(VI, m.F, target_ratio=0.1)
        fa, fb = bracket(True, res, VI, SI), bracket(False, res, VI, SI)
        assert fa["hausdorff_certified"] and fb["hausdorff_certified"] and fa["hausdorff"] == fb["hausdorff"]
        assert fa["hausdorff"] <= fb["hausdorff_upper"] and fb["hausdorff"] <= fa["hausdorff_upper"]
        _report(f"simplification bracket, floor / alone: {name.split('.')[0]}{', noise 0.3' if noisy else ''}",
                _pairs(lambda: bracket(True, res, VI, SI), lambda: bracket(False, res, VI, SI), args.repeats))
    print(f"load average {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    try:
        raise SystemExit(main())
    except AssertionError as exc:       # the two measurements disagree: their ratio compares nothing
        import traceback
        where = traceback.extract_tb(exc.__traceback__)[-1]
        print(f"MISMATCH: line {where.lineno}: {where.line} {exc}")
        raise SystemExit(1) from None
