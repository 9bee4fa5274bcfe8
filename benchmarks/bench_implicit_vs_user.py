"""Benchmark: one implicit smoothing step of ``scratch.implicit`` against the plain pipeline a
user would write with libigl and PARDISO:

    W = igl.cotmatrix(V, F); M = igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI)
    X = pypardiso.spsolve((M - h W).tocsr(), M @ V)

with a fresh factorization every call (pypardiso keeps the factor of a matrix it has seen: it is
freed before each call, as a user's first call would find it), ``h = lbar^2`` (step 1, the mean
edge length). ``scratch.implicit`` runs as registered (argument validation, operator assembly,
automatic solver choice, symbolic-analysis cache cleared before each call: a first step).

Run:  .venv/bin/python benchmarks/bench_implicit_vs_user.py [--subdivisions 6,7,8] [--pairs 3]

Both alternate (A B A B ...) in one process after a warm-up call of each at each size (the
first call at a size pays one-off costs of its own, e.g. PARDISO's first use); per size it
prints the median, min and max of the per-pair ratio ours/user with the load average, and
checks that the two results agree (relative 1e-8; MISMATCH and exit 1 otherwise).
``pypardiso.spsolve`` factors the matrix as general (LU, PARDISO's mtype 11); a third line
gives the ratio against the same user pipeline told the matrix is symmetric positive definite
(one ``pypardiso.PyPardisoSolver(mtype=2)``, its factor freed before each call, on the upper
triangle: Cholesky, as ours),
which says how much of the difference is the factorization chosen.
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
    ap.add_argument("--subdivisions", default="6,7,8")
    ap.add_argument("--pairs", type=int, default=3)
    a = ap.parse_args(argv)
    import igl
    import pypardiso
    import scipy.sparse as sp

    import methods
    from harness import datasets
    from harness.core.geometry import mean_edge_length
    from harness.core.solvers import clear_cache

    ours = methods.get("scratch.implicit")

    def user(V, F):
        pypardiso.ps.free_memory(everything=True)
        h = mean_edge_length(V, F) ** 2
        W = sp.csr_matrix(igl.cotmatrix(V, F))
        M = sp.csr_matrix(igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI))
        return pypardiso.spsolve((M - h * W).tocsr(), np.asarray(M @ V))

    spd = pypardiso.PyPardisoSolver(mtype=2)

    def user_spd(V, F):
        spd.free_memory(everything=True)               # a fresh factorization, as for spsolve
        h = mean_edge_length(V, F) ** 2
        W = sp.csr_matrix(igl.cotmatrix(V, F))
        M = sp.csr_matrix(igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI))
        return spd.solve(sp.triu(M - h * W, format="csr"), np.asarray(M @ V))

    def scratch(V, F):
        clear_cache()
        return ours(V, F).V

    bad = 0
    for s in map(int, a.subdivisions.split(",")):
        V, F = datasets.icosphere(s)
        V = V + np.random.default_rng(0).normal(scale=1e-3, size=V.shape)     # not a perfect sphere
        scratch(V, F), user(V, F), user_spd(V, F)                            # warm-up at this size
        ta, tb, tc = [], [], []
        for _ in range(a.pairs):
            t = time.perf_counter(); xa = scratch(V, F); ta.append(time.perf_counter() - t)
            t = time.perf_counter(); xb = user(V, F); tb.append(time.perf_counter() - t)
            t = time.perf_counter(); xc = user_spd(V, F); tc.append(time.perf_counter() - t)
            err = max(np.abs(xa - x).max() / np.abs(x).max() for x in (xb, xc))
            if not err <= 1e-8:
                bad += 1
                print(f"MISMATCH: icosphere {s}: the results differ by {err:.1e} (relative)")
        r, q = [x / y for x, y in zip(ta, tb)], [x / y for x, y in zip(ta, tc)]
        print(f"icosphere {s} ({len(F):,} faces): scratch.implicit {statistics.median(ta):.3f} s, user pipeline "
              f"{statistics.median(tb):.3f} s; ratio min {min(r):.2f} median {statistics.median(r):.2f} max {max(r):.2f}; "
              f"results differ by {err:.1e}; load average {os.getloadavg()[0]:.2f}")
        print(f"  against the user pipeline with PARDISO told the matrix is SPD (mtype 2, Cholesky): "
              f"{statistics.median(tc):.3f} s; ratio min {min(q):.2f} median {statistics.median(q):.2f} max {max(q):.2f}")
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
