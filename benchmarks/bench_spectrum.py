"""Benchmark: the k smallest Laplace-Beltrami eigenpairs on the bundled armadillo (86,482 faces),
cotan W with the Voronoi mass, and spectral smoothing built on them. Routes:

- ``bands``: our band-by-band shift-invert (`methods.scratch.bands`, what ``auto`` picks for
  k > 100): 50-pair ARPACK runs at successive shifts, QDLDL factorizations, inertia-certified;
- ``arpack``: one ARPACK shift-invert run for all k (+ max(8, k/20)) pairs with our SPD
  factorization as ``OPinv`` (the route before bands);
- ``plain``: ``scipy.sparse.linalg.eigsh`` in shift-invert mode with scipy's own SuperLU, same
  operator and shift (what a user would write);
- ``spectral``: the whole ``scratch.spectral`` smoothing call (operator, eigenpairs, projection),
  and ``spectral_old`` the same call with one ARPACK run.

Run:  .venv/bin/python benchmarks/bench_spectrum.py [--k 200] [--pairs 3]

The routes alternate in one process after a warm-up of each on armadillo at the timed ``k``
(the first call at a size was up to 1.6x slower), with ``--threads`` math
threads each; per round the ratios are formed and their median, min and max printed with the
load average and the thread counts; the eigenvalues of the routes must agree (relative 1e-8:
MISMATCH and exit 1 otherwise).
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
    ap.add_argument("--threads", type=int, default=1,
                    help="math-library threads for every route (default 1, as a case of a run with one "
                         "worker per core has; with the libraries' defaults the times vary several-fold "
                         "on a shared machine)")
    a = ap.parse_args(argv)
    from _threads import limit_threads, pools
    limit_threads(a.threads)
    import scipy.sparse as sp
    from scipy.sparse.linalg import eigsh

    from harness import datasets
    from methods.scratch.smoothing import smoothing_operator
    from methods.scratch.spectrum import inversion_shift, operator_and_mass, smallest_eigenpairs

    def plain(W, M, k):
        lam = eigsh((-W).tocsc(), k=k, M=M.tocsc(), sigma=inversion_shift(W, M), which="LM",
                    v0=np.random.default_rng(0).standard_normal(W.shape[0]))[0]
        return np.sort(lam)

    def spectral(V, F, k, solver):
        W, m = smoothing_operator(V, F, "cotan_area")
        _, Phi = smallest_eigenpairs(W.tocsr(), sp.diags(m).tocsr(), k, solver)
        return Phi @ (Phi.T @ (m[:, None] * V))

    routes = {
        "bands": lambda W, M, V, F, k: smallest_eigenpairs(W, M, k, "bands")[0],
        "arpack": lambda W, M, V, F, k: smallest_eigenpairs(W, M, k, "shift_invert")[0],
        "plain": lambda W, M, V, F, k: plain(W, M, k),
        "spectral": lambda W, M, V, F, k: spectral(V, F, k, "auto"),
        "spectral_old": lambda W, M, V, F, k: spectral(V, F, k, "shift_invert"),
    }
    m = datasets.load("armadillo").clean
    W, M = operator_and_mass(m.V, m.F, "cotan", "voronoi")
    for f in routes.values():                    # warm-up: each route once at the timed size and k
        f(W, M, m.V, m.F, a.k)
    before = limit_threads(a.threads)            # again: the warm-up and the loading loaded more libraries
    T = {r: [] for r in routes}
    C = {r: [] for r in routes}
    out = {}
    load0 = os.getloadavg()
    for _ in range(a.pairs):
        for name, f in routes.items():
            c, t = time.process_time(), time.perf_counter()
            out[name] = f(W, M, m.V, m.F, a.k)
            T[name].append(time.perf_counter() - t)
            C[name].append(time.process_time() - c)
    after = pools()
    print(f"armadillo {len(m.F):,} faces, k = {a.k}, {a.pairs} rounds, load average {load0} -> {os.getloadavg()}; "
          f"math-library threads: {before}" + ("" if after == before else
                                                f" (after the rounds, a pool loaded by them unlimited: {after})"))
    for name in routes:
        print(f"  {name:13s} median {statistics.median(T[name]):6.2f} s, cpu/wall "
              f"{statistics.median(c / w for c, w in zip(C[name], T[name])):.2f}")

    def ratio(x, y, label):
        r = [p / q for p, q in zip(T[x], T[y])]
        print(f"  {label:44s} min {min(r):.2f}  median {statistics.median(r):.2f}  max {max(r):.2f}")

    ratio("bands", "plain", "bands / plain eigsh + SuperLU")
    ratio("arpack", "plain", "one ARPACK run (ours) / plain")
    ratio("bands", "arpack", "bands / one ARPACK run")
    fastest = min(("bands", "arpack", "plain"), key=lambda r: statistics.median(T[r]))
    ratio("spectral", fastest, f"scratch.spectral / fastest route ({fastest})")
    ratio("spectral", "spectral_old", "scratch.spectral / its one-ARPACK-run version")
    bad = 0
    for x, y in (("bands", "plain"), ("arpack", "plain")):
        d = np.abs(out[x] - out[y]).max() / out[y].max()
        print(f"  max relative eigenvalue difference {x} vs {y}: {d:.1e}")
        if not d <= 1e-8:
            bad += 1
            print(f"MISMATCH: the eigenvalues of {x} and {y} differ by {d:.1e} (relative to the largest)")
    print(f"  smoothed coordinates, bands vs one run: max difference "
          f"{np.abs(out['spectral'] - out['spectral_old']).max() / np.ptp(m.V, axis=0).max():.1e} of the box")
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
