"""Benchmark: heat-method geodesics at large sizes, scratch.heat against libigl's and
geometry-central's (potpourri3d) heat methods, precomputation and per-source cost.

Run:  .venv/bin/python benchmarks/bench_geodesics.py [--subdivisions 7,8] [--pairs 3] [--sources 4] [--threads 1]

Meshes: icosphere subdivisions 7 (327,680 faces) and 8 (1,310,720 faces). All three are run in
one process, alternating (scratch, libigl, potpourri3d) per round, after a warm-up of each at
each size (one source: the same code path as the timed calls' several); each prints the median over rounds of its precomputation time and
per-source time (each method's own split), the min-max of the per-round ratios to scratch.heat,
how far its distances are from scratch.heat's (libigl's must agree to 1e-8: MISMATCH and exit 1
otherwise; potpourri3d differs: geometry-central solves its Poisson step with ``L + 1e-6 I``, a
fixed shift whose effect grows with the vertex count, and lumps the mass barycentrically; its
robust intrinsic operator changes nothing on an icosphere, already intrinsic Delaunay), with the load average and the math libraries' thread counts: ``--threads`` (default
1, as libigl's and geometry-central's solvers use one; scratch.heat's PARDISO would otherwise
take every core, which a ratio would count as the method's).
Before every call the harness's solver helpers forget the symbolic analyses of earlier calls
(`harness.runner.forget_inputs`, as a run does before every sample): every call pays for its
ordering like a first call, as the libraries' do.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--subdivisions", default="7,8")
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--sources", type=int, default=4)
    ap.add_argument("--threads", type=int, default=1, help="math-library threads for every method (default 1)")
    a = ap.parse_args(argv)
    from _threads import limit_threads
    import methods
    from harness import datasets
    from harness.runner import forget_inputs
    names = ["scratch.heat", "libigl.heat", "potpourri3d.heat"]
    import numpy as np
    print(f"load average {os.getloadavg()}")
    bad = 0
    for s in map(int, a.subdivisions.split(",")):
        V, F = datasets.icosphere(s)
        for m in names:                          # warm-up at this size: one-off costs of a first call
            forget_inputs()
            methods.get(m)(V, F, sources=1)
        threads = limit_threads(a.threads)       # after the warm-up: it may have loaded MKL
        pre = {m: [] for m in names}
        per = {m: [] for m in names}
        for _ in range(a.pairs):
            D = {}
            for m in names:
                forget_inputs()
                r = methods.get(m)(V, F, sources=a.sources)
                pre[m].append(r.precompute_s)
                per[m].append(r.per_source_s)
                D[m] = np.asarray(r.D)
        # the same operator and time step: libigl equals ours to rounding; geometry-central's
        # shifted Poisson solve and barycentric mass differ (module docstring)
        gap = {m: float(np.abs(D[m] - D["scratch.heat"]).max() / np.abs(D["scratch.heat"]).max()) for m in names}
        if not gap["libigl.heat"] <= 1e-8:
            bad += 1
            print(f"MISMATCH: icosphere {s}: libigl.heat and scratch.heat differ by {gap['libigl.heat']:.1e}")
        print(f"\nicosphere {s}: {len(V):,} vertices, {len(F):,} faces, {a.sources} sources, {a.pairs} rounds, "
              f"load average {os.getloadavg()[0]:.2f}; math-library threads: "
              + threads)
        for m in names:
            p, q = statistics.median(pre[m]), statistics.median(per[m])
            rp = [x / y for x, y in zip(pre[m], pre["scratch.heat"])]
            rq = [x / y for x, y in zip(per[m], per["scratch.heat"])]
            print(f"  {m:18s} precompute {p:8.3f} s ({statistics.median(rp):5.2f}x scratch, {min(rp):.2f}-{max(rp):.2f})"
                  f"   per source {q:7.3f} s ({statistics.median(rq):5.2f}x, {min(rq):.2f}-{max(rq):.2f})"
                  f"   distances differ from scratch.heat by {gap[m]:.1e} (relative)")
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
