"""Benchmark: how low the fixed cost per case can go with the metrics a run certifies (by default
at 86k faces, `configs/fixed_cost_sampled.yaml`).

Run:  .venv/bin/python benchmarks/bench_fixed_floor.py [--config C] [--repeats 5]

1. Runs the config as a user would (``shootout run C --workers 1`` into a temporary folder) and
   reads ``run.json``'s ``fixed_cost_per_case_s``: the cases' summed fixed cost, the part of it
   spent measuring, and their summed method time (fixed cost / ``share_of_method_time``).
2. In this process, for the same cases (each method called once on its case's input), times the
   work no implementation of these metrics can skip, median of ``--repeats``:
   - simplification: the output's hierarchy, the ``2 x hausdorff_samples`` sampled distances
     (``surface_dist_mean`` is their mean) and one distance query from every vertex of both
     meshes (each corner's distance enters every bound of the Hausdorff bracket);
   - smoothing: one distance query from every output vertex to the clean surface, started at a
     face around the vertex (``dist_mean`` integrates those distances);
   - laplacian: one pass of the PSD certificate over the faces
     (`harness.metrics._psd_kernel.face_split_bound`);
   and each task's per-input facts (its measuring with an empty fact cache minus with it filled),
   which the first case of each input pays.
3. Prints the floor: (the run's fixed cost outside measuring + those floors) / the run's method
   time, without and with the facts, beside the run's own share. A floor above a goal means the
   goal cannot be met by making the measuring faster, only by measuring less.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _median_time(fn, repeats: int) -> float:
    fn()
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return statistics.median(out)


def _simplification_floor(inp, res, n_samples: int):
    from harness.core.geometry import morton_order, sample_surface
    from harness.metrics._bvh_kernel import query_many
    from harness.metrics.surface_distance import Surface, cached_surface
    S_in = cached_surface(inp.cache, "input_surface", inp.V, inp.F)
    S_in.bvh()

    def queries(P, S):
        P = np.ascontiguousarray(P[morton_order(P)])
        return query_many(P, np.full(len(P), -1, np.int64), *S.bvh())

    def work():
        SA = Surface(res.V, res.F)
        queries(sample_surface(res.V, res.F, n_samples, 0), S_in)
        queries(S_in.samples(n_samples, 1)[0], SA)
        queries(res.V, S_in)
        queries(inp.V, SA)
    return work


def _smoothing_floor(inp, res):
    from harness.core.geometry import face_around_vertex, morton_order
    from harness.metrics._bvh_kernel import query_many
    from harness.metrics.surface_distance import cached_surface
    S = cached_surface(inp.cache, "clean_surface", inp.clean.V, inp.F)
    hints = face_around_vertex(np.asarray(inp.F, dtype=np.int64), len(res.V))

    def work():
        order = morton_order(res.V)
        query_many(np.ascontiguousarray(res.V[order]), S.leaf_faces(hints[order]), *S.bvh())
    return work


def _laplacian_floor(inp, res):
    import scipy.sparse as sp

    from harness.metrics._psd_kernel import face_split_bound
    W = sp.csr_matrix(res.W)
    S = (-(W + W.T) * 0.5).tocsr()
    S.sort_indices()
    k = np.frexp(float(S.diagonal().max()))[1]
    V, F = np.ascontiguousarray(inp.V, dtype=np.float64), np.ascontiguousarray(inp.F, dtype=np.int64)

    def work():
        face_split_bound(S.indptr.astype(np.int64), S.indices.astype(np.int64), np.ldexp(S.data, -k), V, F)
    return work


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default=str(ROOT / "configs" / "fixed_cost_sampled.yaml"))
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        subprocess.run([sys.executable, "-m", "harness.cli", "run", args.config, "--workers", "1", "--out", str(out),
                        "--quiet"], cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
        fc = json.loads((out / "run.json").read_text())["fixed_cost_per_case_s"]
    n = fc["cases"]
    fixed, measuring = fc["mean"] * n, fc["measuring_mean"] * n
    method = fixed / fc["share_of_method_time"]
    outside = fixed - measuring
    print(f"run ({args.config}, --workers 1): {n} cases, method time {method:.3f} s, fixed cost {fixed:.3f} s "
          f"(measuring {measuring:.3f} s, the rest {outside:.3f} s), share {fc['share_of_method_time']:.3f}")

    from harness import runner, tasks
    from harness.config import load_config
    from harness.plugins import import_methods
    cfg = load_config(args.config)
    methods = import_methods()
    floors, facts = 0.0, 0.0
    seen_tasks = set()
    for case in cfg.cases:
        task = tasks.get(case.task)
        if task.preload is not None:
            task.preload()
        inp, _ = runner.prepare_input(case)
        res = methods.get(case.method)(inp.V.copy(), inp.F.copy(), **case.params)
        if case.task not in seen_tasks:                  # the first case of the input for this task
            seen_tasks.add(case.task)

            def fresh(case=case, res=res, task=task):
                task.measure(runner.prepare_input(case)[0], res, case.params)
            task.measure(inp, res, case.params)
            filled = _median_time(lambda: task.measure(inp, res, case.params), args.repeats)
            f = max(0.0, _median_time(fresh, args.repeats) - filled)
            facts += f
            print(f"  {case.task:15s} facts of the input {f * 1e3:7.1f} ms")
        if case.task == "simplification":
            work = _simplification_floor(inp, res, case.hausdorff_samples)
        elif case.task == "smoothing":
            work = _smoothing_floor(inp, res)
        elif case.task == "laplacian":
            work = _laplacian_floor(inp, res)
        else:
            print(f"  {case.task}: no floor defined here; counted as 0")
            continue
        t = _median_time(work, args.repeats)
        floors += t
        whole = _median_time(lambda: task.measure(inp, res, case.params), args.repeats)
        print(f"  {case.task:15s} {case.method:25s} floor {t * 1e3:7.1f} ms, measuring now {whole * 1e3:7.1f} ms")
    print(f"floor share of the method time: {(outside + floors) / method:.3f} without the inputs' facts, "
          f"{(outside + floors + facts) / method:.3f} with them (the run: {fc['share_of_method_time']:.3f})")
    print(f"load average {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
