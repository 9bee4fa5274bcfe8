"""Benchmark: heat-method geodesics at large sizes, scratch.heat against libigl's and
geometry-central's (potpourri3d) heat methods, precomputation and per-source cost.

Run:  .venv/bin/python benchmarks/bench_geodesics.py [--subdivisions 7,8] [--pairs 3] [--sources 4]

Meshes: icosphere subdivisions 7 (327,680 faces) and 8 (1,310,720 faces). All three are run in
one process, alternating (scratch, libigl, potpourri3d) per round, after a warm-up on a small
mesh; each prints the median over rounds of its precomputation time and per-source time (each
method's own split), the min-max of the per-round ratios to scratch.heat, with the load average.
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
    a = ap.parse_args(argv)
    import methods
    from harness import datasets
    from harness.runner import forget_inputs
    names = ["scratch.heat", "libigl.heat", "potpourri3d.heat"]
    V, F = datasets.icosphere(3)
    for m in names:
        methods.get(m)(V, F, sources=1)
    print(f"load average {os.getloadavg()}")
    for s in map(int, a.subdivisions.split(",")):
        V, F = datasets.icosphere(s)
        pre = {m: [] for m in names}
        per = {m: [] for m in names}
        for _ in range(a.pairs):
            for m in names:
                forget_inputs()
                r = methods.get(m)(V, F, sources=a.sources)
                pre[m].append(r.precompute_s)
                per[m].append(r.per_source_s)
        print(f"\nicosphere {s}: {len(V):,} vertices, {len(F):,} faces, {a.sources} sources, {a.pairs} rounds, "
              f"load average {os.getloadavg()[0]:.2f}")
        p0, q0 = statistics.median(pre["scratch.heat"]), statistics.median(per["scratch.heat"])
        for m in names:
            p, q = statistics.median(pre[m]), statistics.median(per[m])
            rp = [x / y for x, y in zip(pre[m], pre["scratch.heat"])]
            rq = [x / y for x, y in zip(per[m], per["scratch.heat"])]
            print(f"  {m:18s} precompute {p:8.3f} s ({statistics.median(rp):5.2f}x scratch, {min(rp):.2f}-{max(rp):.2f})"
                  f"   per source {q:7.3f} s ({statistics.median(rq):5.2f}x, {min(rq):.2f}-{max(rq):.2f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
