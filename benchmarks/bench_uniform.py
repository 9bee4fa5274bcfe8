"""Benchmark: the uniform (graph) Laplacian ``W = A - diag(deg)``: ``scratch.uniform`` (the whole
registered method call, identity mass included) against the pipeline a user would write with
libigl, ``A = igl.adjacency_matrix(F); W = (A - diags(A.sum(1))).tocsr()``, on the bundled
armadillo (86k faces) and a subdivision-8 icosphere (1.31M faces).

Run:  .venv/bin/python benchmarks/bench_uniform.py [--pairs 7] [--subdivisions 8]

The two alternate in one process (warm); the per-pair ratio ours/libigl is printed as median
(min-max) with the load average, and the two matrices are checked equal.
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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pairs", type=int, default=7)
    ap.add_argument("--subdivisions", type=int, default=8, help="of the icosphere (8: 1.31M faces)")
    a = ap.parse_args(argv)
    import igl
    import scipy.sparse as sp

    import methods
    from harness import datasets

    def user(F, n):
        A = igl.adjacency_matrix(F)
        return (A - sp.diags(np.asarray(A.sum(axis=1)).ravel().astype(np.float64))).tocsr()

    ours = methods.get("scratch.uniform")
    print(f"load average {os.getloadavg()}")
    for label, (V, F) in (("armadillo", (datasets.load("armadillo").clean.V, datasets.load("armadillo").clean.F)),
                          (f"icosphere {a.subdivisions}", datasets.icosphere(a.subdivisions))):
        n = len(V)
        diff = abs(ours(V, F).W - user(F, n)).max()
        if diff != 0:                   # a ratio of two different matrices compares nothing
            print(f"MISMATCH: {label}: scratch.uniform and the igl adjacency pipeline differ by {diff:.1e}")
            return 1
        r = []
        for _ in range(a.pairs):
            t = time.perf_counter(); ours(V, F); ta = time.perf_counter() - t
            t = time.perf_counter(); user(F, n); tb = time.perf_counter() - t
            r.append(ta / tb)
        print(f"{label} ({len(F):,} faces): scratch.uniform / igl adjacency pipeline median {statistics.median(r):.2f} "
              f"(min {min(r):.2f}, max {max(r):.2f})")
    print(f"load average {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
