"""Benchmark: the certified Hausdorff distance (`harness.metrics.hausdorff`, relative gap 1e-3)
against the plain call a user would write, ``igl.hausdorff(VA, FA, VB, FB)`` (each mesh's
vertices against the other surface: a lower bound), against the sampled estimate it replaced
(all vertices plus 20,000 area-uniform random points per side, exact point-to-surface
distances), on meshes simplified to 10%, and against ``cascading-upper-bounds`` (Sacht &
Jacobson 2024, C++) when installed.

Run:  .venv/bin/python benchmarks/bench_hausdorff.py [--meshes bunny,armadillo] [--upsample 0] [--pairs 3]

For each mesh and simplifier (``scratch.qem``, ``meshlab.qem``) ``igl.hausdorff``, the sampled
estimate, the certified bracket alone (``n_samples=0``) and the whole metric as a case computes
it (the bracket plus the sampled mean surface distance, 20,000 points per side) alternate in one
process, each warmed first; printed: libigl's and the sampled value, the certified bracket
(either lower bound above its upper end is a MISMATCH), the median (min-max) time ratios
certified/libigl, metric/libigl, certified/sampled and metric/sampled, and the load average.
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


def sampled(VA, FA, VB, FB, n=20000, seed=0):
    from harness.core.geometry import sample_surface
    from harness.metrics.surface_distance import point_surface_distance
    PA = np.concatenate([VA, sample_surface(VA, FA, n, seed)])
    PB = np.concatenate([VB, sample_surface(VB, FB, n, seed + 1)])
    return max(point_surface_distance(PA, VB, FB).max(), point_surface_distance(PB, VA, FA).max())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--meshes", default="bunny,armadillo")
    ap.add_argument("--upsample", type=int, default=0, help="midpoint subdivisions of the input (igl.upsample)")
    ap.add_argument("--pairs", type=int, default=3)
    a = ap.parse_args(argv)
    import igl

    import methods
    from harness import datasets
    from harness.metrics.hausdorff import hausdorff, warm
    warm()
    print(f"load average {os.getloadavg()}")
    bad = 0
    for name in a.meshes.split(","):
        m = datasets.load(name).clean
        V, F = m.V, m.F
        if a.upsample:
            V, F = igl.upsample(V, F, a.upsample)
            F = np.asarray(F, dtype=np.int64)
        diag = float(np.linalg.norm(np.ptp(V, axis=0)))
        for meth in ("scratch.qem", "meshlab.qem"):
            r = methods.get(meth)(V, F, target_ratio=0.1)
            ts, tc, tm, ti = [], [], [], []
            igl.hausdorff(r.V, r.F, V, F)              # each path once, untimed: the timed rounds are all warm
            sampled(r.V, r.F, V, F)
            hausdorff(r.V, r.F, V, F, n_samples=0)
            hausdorff(r.V, r.F, V, F)
            for _ in range(a.pairs):
                t = time.perf_counter(); hi = float(igl.hausdorff(r.V, r.F, V, F)); ti.append(time.perf_counter() - t)
                t = time.perf_counter(); hs = sampled(r.V, r.F, V, F); ts.append(time.perf_counter() - t)
                t = time.perf_counter(); h = hausdorff(r.V, r.F, V, F, n_samples=0); tc.append(time.perf_counter() - t)
                t = time.perf_counter(); hausdorff(r.V, r.F, V, F); tm.append(time.perf_counter() - t)
            tol = 1e-12 * diag
            for label, low in (("libigl's", hi), ("a sampled", hs)):   # both are lower bounds of the true one
                if not low <= h["hausdorff_upper"] + tol:
                    bad += 1
                    print(f"MISMATCH: {name} {meth}: {label} distance {low / diag:.4e} above the certified upper bound "
                          f"{h['hausdorff_upper'] / diag:.4e}")

            def spread(x, y):
                r = [p / q for p, q in zip(x, y)]
                return f"{statistics.median(r):.2f} ({min(r):.2f}-{max(r):.2f})"
            line = (f"{name} ({len(F):,} faces) {meth}: igl.hausdorff {hi / diag:.4e}, sampled {hs / diag:.4e}, "
                    f"certified [{h['hausdorff'] / diag:.4e}, {h['hausdorff_upper'] / diag:.4e}] "
                    f"({'certified' if h['hausdorff_certified'] else 'budget ran out'}); time, median (min-max): "
                    f"certified/igl.hausdorff {spread(tc, ti)}, metric/igl.hausdorff {spread(tm, ti)}, "
                    f"certified/sampled {spread(tc, ts)}, metric/sampled {spread(tm, ts)}")
            try:
                import cascading_upper_bounds as cub
                A = (np.ascontiguousarray(r.V), np.ascontiguousarray(r.F, dtype=np.int32))
                B = (np.ascontiguousarray(V), np.ascontiguousarray(F, dtype=np.int32))
                cub.pompeiu_hausdorff(A[0], A[1], B[0], B[1], tol=1e-3 * h["hausdorff"])      # warm, untimed
                t = time.perf_counter()
                ab = cub.pompeiu_hausdorff(A[0], A[1], B[0], B[1], tol=1e-3 * h["hausdorff"])
                ba = cub.pompeiu_hausdorff(B[0], B[1], A[0], A[1], tol=1e-3 * h["hausdorff"])
                t = time.perf_counter() - t
                line += (f"; cascading-upper-bounds [{max(ab[0], ba[0]) / diag:.4e}, {max(ab[1], ba[1]) / diag:.4e}], "
                         f"its time / ours {t / statistics.median(tc):.2f} (one call, both directions certified)")
                if max(ab[0], ba[0]) > h["hausdorff_upper"] + tol or h["hausdorff"] > max(ab[1], ba[1]) + tol:
                    bad += 1
                    print(f"MISMATCH: {name} {meth}: the two certified brackets do not overlap")
            except ImportError:
                pass
            print(line)
    print(f"load average {os.getloadavg()}")
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
