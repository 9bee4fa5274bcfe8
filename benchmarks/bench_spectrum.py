"""Benchmark: the k smallest Laplace-Beltrami eigenpairs on the bundled armadillo (86,482 faces),
our ARPACK shift-invert route (the one `scratch.spectral` and `scratch.spectrum` use: the shifted
matrix factored by `harness.core.solvers`) against plain ``scipy.sparse.linalg.eigsh`` in
shift-invert mode with scipy's own SuperLU, same operator (cotan W, Voronoi M), same shift.

Run:  .venv/bin/python benchmarks/bench_spectrum.py [--k 200] [--pairs 3]

The two routes alternate (A B A B ...) in one process after a warm-up on a small mesh; the
median, min and max of the per-pair ratio A/B are printed with the load average, and the
eigenvalues of the two routes are compared.
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
    ap.add_argument("--k", type=int, default=200)
    ap.add_argument("--pairs", type=int, default=3)
    a = ap.parse_args(argv)
    from scipy.sparse.linalg import eigsh

    from harness import datasets
    from methods.scratch.spectrum import inversion_shift, operator_and_mass, smallest_eigenpairs

    def ours(W, M, k):
        return smallest_eigenpairs(W, M, k, "shift_invert")[0]

    def plain(W, M, k):
        lam = eigsh((-W).tocsc(), k=k, M=M.tocsc(), sigma=inversion_shift(W, M), which="LM",
                    v0=np.random.default_rng(0).standard_normal(W.shape[0]))[0]
        return np.sort(lam)

    Vs, Fs = datasets.icosphere(3)
    W, M = operator_and_mass(Vs, Fs, "cotan", "voronoi")
    ours(W, M, 10), plain(W, M, 10)
    m = datasets.load("armadillo").clean
    W, M = operator_and_mass(m.V, m.F, "cotan", "voronoi")
    ta, tb = [], []
    for _ in range(a.pairs):
        t = time.perf_counter(); la = ours(W, M, a.k); ta.append(time.perf_counter() - t)
        t = time.perf_counter(); lb = plain(W, M, a.k); tb.append(time.perf_counter() - t)
    r = [x / y for x, y in zip(ta, tb)]
    print(f"armadillo {len(m.F):,} faces, k = {a.k}, {a.pairs} pairs, load average {os.getloadavg()}")
    print(f"  ours (ARPACK + our factorization): median {statistics.median(ta):.2f} s")
    print(f"  plain eigsh + SuperLU:             median {statistics.median(tb):.2f} s")
    print(f"  ratio ours/plain: min {min(r):.2f}  median {statistics.median(r):.2f}  max {max(r):.2f}")
    print(f"  max relative eigenvalue difference {np.abs(la - lb).max() / lb.max():.1e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
