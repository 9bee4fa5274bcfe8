"""Benchmark: one implicit smoothing step (factor + solve, 3 right-hand sides), every solver.

The system is backward Euler with the Laplace-Beltrami operator, ``(M - h W) X' = M X``,
``h = step * lbar^2`` (``weights: cotan_area``, ``step`` 1 by default), on an icosphere with
``--subdivisions`` 8 (655,362 vertices, 1,310,720 faces) unless told otherwise.

For each installed backend of ``harness.core.solvers`` it times, in one process:

* ``cold``: symbolic analysis + numeric factorization + solve (empty symbolic cache), the
  cost of a first step;
* ``warm``: numeric factorization + solve of a second matrix with the same pattern (different
  values: ``h`` scaled by 1.01) with the cached symbolic analysis, the cost of every later
  step with ``reassemble: true`` within one call (a run clears the cache before every timed call).

Baselines (not backends of the harness): ``splu_mmd_sym`` (plain ``splu`` with
``permc_spec="MMD_AT_PLUS_A"``, symmetric mode: the floor the pure-scipy path must beat),
optionally ``splu_colamd`` (scipy's default ordering, ``--with-colamd``: slow) and
``cg_jacobi`` (``--with-cg``: Jacobi-preconditioned CG to 1e-10 relative residual).

Prints a table and the ratio of the automatically chosen solver to the fastest; writes JSON
with ``--json PATH``. Timings are wall-clock on a shared machine: repeat on a quiet one
before quoting them.

Usage::

    python benchmarks/bench_implicit.py [--subdivisions 8] [--step 1.0] [--with-colamd]
        [--with-cg] [--solvers pypardiso,scipy] [--json out.json]
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from harness.datasets import icosphere  # noqa: E402
from harness.core import solvers  # noqa: E402
from methods.scratch.smoothing import mean_edge_length, smoothing_operator  # noqa: E402


def _timed(fn):
    t = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t


def bench_backend(name, A, A2, B, ref):
    solvers.clear_cache()
    fac, t_fac = _timed(lambda: solvers.factorize(A, name))
    X, t_sol = _timed(lambda: fac.solve(B))
    err = float(np.abs(X - ref).max() / np.abs(ref).max())
    fac = None                     # free the factor before the next one
    fac2, t_fac2 = _timed(lambda: solvers.factorize(A2, name))
    _, t_sol2 = _timed(lambda: fac2.solve(B))
    fac2 = None
    solvers.clear_cache()
    return {"solver": name, "cold_factor_s": t_fac, "cold_solve_s": t_sol,
            "cold_total_s": t_fac + t_sol, "warm_factor_s": t_fac2, "warm_solve_s": t_sol2,
            "warm_total_s": t_fac2 + t_sol2, "rel_error": err}


def bench_splu(A, B, ref, permc_spec, symmetric):
    opts = {"SymmetricMode": True} if symmetric else {}
    kw = {"diag_pivot_thresh": 0.0} if symmetric else {}
    lu, t_fac = _timed(lambda: sla.splu(A.tocsc(), permc_spec=permc_spec, options=opts, **kw))
    X, t_sol = _timed(lambda: lu.solve(B))
    return {"cold_factor_s": t_fac, "cold_solve_s": t_sol, "cold_total_s": t_fac + t_sol,
            "rel_error": float(np.abs(X - ref).max() / np.abs(ref).max())}


def _in_child(fn, timeout, *args):
    """Run ``fn(*args)`` in a forked child; None if it exceeds ``timeout`` seconds (killed)."""
    import multiprocessing as mp
    ctx = mp.get_context("fork")
    q = ctx.Queue()
    p = ctx.Process(target=lambda: q.put(fn(*args)), daemon=True)
    p.start()
    p.join(timeout)
    if p.is_alive():
        p.kill()
        p.join()
        return None
    return q.get() if not q.empty() else None


def bench_cg(A, B, ref):
    d = A.diagonal()
    P = sla.LinearOperator(A.shape, matvec=lambda x: x / d)

    def run():
        out, its = [], []
        for k in range(B.shape[1]):
            n = [0]
            x, info = sla.cg(A, B[:, k], rtol=1e-10, M=P, callback=lambda _: n.__setitem__(0, n[0] + 1))
            out.append(x)
            its.append(n[0])
        return np.column_stack(out), its
    (X, its), t = _timed(run)
    return {"cold_factor_s": 0.0, "cold_solve_s": t, "cold_total_s": t, "iterations": its,
            "rel_error": float(np.abs(X - ref).max() / np.abs(ref).max())}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--subdivisions", type=int, default=8)
    ap.add_argument("--step", type=float, default=1.0)
    ap.add_argument("--solvers", default="", help="comma-separated subset (default: all installed)")
    ap.add_argument("--with-colamd", action="store_true")
    ap.add_argument("--with-cg", action="store_true")
    ap.add_argument("--json", default="")
    ap.add_argument("--baseline-timeout", type=float, default=600.0,
                    help="seconds before a baseline (run in a child process) is abandoned")
    args = ap.parse_args(argv)

    V, F = icosphere(args.subdivisions)
    rng = np.random.default_rng(0)
    V = V + 0.2 * 1e-3 * rng.standard_normal(V.shape) * (4.0 / 2 ** args.subdivisions)
    W, m = smoothing_operator(V, F, "cotan_area")
    h = args.step * mean_edge_length(V, F) ** 2
    A = (sp.diags(m) - h * W).tocsr()
    A2 = (sp.diags(m) - 1.01 * h * W).tocsr()
    B = m[:, None] * V
    print(f"icosphere subdiv {args.subdivisions}: {len(V):,} vertices, {len(F):,} faces, "
          f"nnz {A.nnz:,}; step {args.step} (h = {h:.3g})", flush=True)

    installed = solvers.installed_solvers()
    chosen = args.solvers.split(",") if args.solvers else installed
    auto = solvers.auto_solver(A.shape[0])
    print(f"installed: {installed}; auto: {auto}", flush=True)

    # reference solution from the auto solver (every backend is compared to it)
    ref = solvers.factorize(A, auto, reuse_symbolic=False).solve(B)

    rows = []
    for name in chosen:
        r = bench_backend(name, A, A2, B, ref)
        rows.append(r)
        print(f"  {name:10s} cold {r['cold_total_s']:7.2f} s (factor {r['cold_factor_s']:.2f}) "
              f"warm {r['warm_total_s']:7.2f} s  err {r['rel_error']:.1e}", flush=True)
    baselines = []
    todo = [("splu_mmd_sym", "MMD_AT_PLUS_A", True)]
    if args.with_colamd:
        todo.append(("splu_colamd", "COLAMD", False))
    for label, spec, sym in todo:
        r = _in_child(bench_splu, args.baseline_timeout, A, B, ref, spec, sym)
        if r is None:
            r = {"cold_total_s": None, "timed_out_after_s": args.baseline_timeout}
            print(f"  {label} > {args.baseline_timeout:.0f} s (abandoned)", flush=True)
        else:
            print(f"  {label} cold {r['cold_total_s']:7.2f} s  err {r['rel_error']:.1e}", flush=True)
        baselines.append({"solver": label, **r})
    if args.with_cg:
        r = bench_cg(A, B, ref)
        baselines.append({"solver": "cg_jacobi", **r})
        print(f"  cg_jacobi   {r['cold_total_s']:7.2f} s  its {r['iterations']} err {r['rel_error']:.1e}",
              flush=True)

    summary = {}
    # cholmod (scikit-sparse) needs SuiteSparse headers from the OS: not "PyPI alone"
    pypi_only = [r for r in rows if r["solver"] != "cholmod"]
    auto_pypi = solvers.auto_solver(A.shape[0]) if auto != "cholmod" else next(
        (s for s in solvers.AUTO_LARGE if s != "cholmod" and s in installed), "scipy")
    for phase in ("cold_total_s", "warm_total_s"):
        for label, pool, who in (("all", rows, auto), ("pypi_only", pypi_only, auto_pypi)):
            fastest = min(pool, key=lambda r: r[phase])
            a = next((r for r in pool if r["solver"] == who), None)
            if a is None:
                continue
            summary[f"{phase}/{label}"] = {
                "fastest": fastest["solver"], "fastest_s": fastest[phase], "auto": who,
                "auto_s": a[phase], "ratio_auto_to_fastest": a[phase] / fastest[phase]}
            print(f"{phase} [{label}]: auto {who} {a[phase]:.2f} s, fastest "
                  f"{fastest['solver']} {fastest[phase]:.2f} s, ratio "
                  f"{a[phase] / fastest[phase]:.2f}")
    sc = next((r for r in rows if r["solver"] == "scipy"), None)
    if sc is not None:
        base = baselines[0]["cold_total_s"]
        base_s = f"{base:.2f} s" if base is not None else f"> {args.baseline_timeout:.0f} s"
        print(f"scipy backend cold {sc['cold_total_s']:.2f} s / warm {sc['warm_total_s']:.2f} s vs "
              f"plain splu_mmd_sym {base_s}")
    out = {"mesh": f"icosphere{args.subdivisions}", "n_vertices": int(len(V)),
           "n_faces": int(len(F)), "step": args.step, "nnz": int(A.nnz),
           "machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                       "loadavg": os.getloadavg()},
           "solver_info": solvers.solver_info(), "backends": rows, "baselines": baselines,
           "summary": summary}
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=2)
    wrong = [r["solver"] for r in rows + baselines if r.get("rel_error") is not None and not r["rel_error"] <= 1e-8]
    for name in wrong:
        print(f"MISMATCH: {name} differs from the automatic solver's solution by more than 1e-8 (relative)")
    out["mismatch"] = wrong
    print(f"load average {os.getloadavg()[0]:.2f}")
    return out


if __name__ == "__main__":
    raise SystemExit(1 if main()["mismatch"] else 0)
