"""Benchmark: how much of the fixed cost per case the printed metrics themselves require (by
default at 86k faces, `configs/fixed_cost_sampled.yaml`), beside what a run spends.

Run:  .venv/bin/python benchmarks/bench_fixed_floor.py [--config C] [--repeats 5]

1. Runs the config as a user would (``shootout run C --workers 1`` into a temporary folder) and
   reads ``run.json``'s ``fixed_cost_per_case_s``: the ok cases' summed fixed cost, the part of
   it spent measuring, and their summed method time (fixed cost / ``share_of_method_time``).
2. In this process, for the same ok cases (each method called once on its case's input), times,
   median of ``--repeats``:
   - **required**: the work the metrics' definitions ask of any implementation, with the
     harness's own distance queries (`harness.metrics._queries`, on the run's threads per case): for a simplified mesh,
     drawing its samples, a hierarchy over it and the ``2 x hausdorff_samples`` sampled
     distances ``surface_dist_mean`` averages; for a smoothed mesh, the distance of every
     vertex, which ``dist_mean`` integrates, and of every clean vertex to the result, which
     ``dist_mean_back`` integrates (its hierarchy refitted); for a Laplacian, one pass over the matrix for the
     PSD column (`harness.metrics._psd_kernel.face_split_bound`, where diagonal dominance does
     not settle it);
   - **this bracket's vertex queries**: the distance of every vertex of both meshes, which the
     certified Hausdorff bracket of `harness.metrics.hausdorff` starts from (another bracket
     could bound clusters of triangles with fewer queries, so this is not required);
   - each input's facts (one per task and input: its measuring with an empty fact cache minus
     with it filled, the input's preparation excluded), which the first case of the input pays.
3. Prints shares of the run's method time: the run's fixed cost outside measuring plus the
   required work; plus the facts; plus this bracket's vertex queries; beside the run's own share.
   What a share goal leaves above the first figure is all the certified Hausdorff bracket, the
   other metrics, the facts and the per-sample validation may cost together.
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


def _queries(P, S, order=None):
    from harness.core.geometry import morton_order
    from harness.metrics._queries import query_blocks
    P = np.ascontiguousarray(P[morton_order(P) if order is None else order])
    return query_blocks(P, np.full(len(P), -1, np.int64), *S.bvh())


def _simplification_work(inp, res, n_samples: int):
    """``(required, bracket)``: callables doing the sampled distances, and the vertex queries."""
    from harness.core.geometry import sample_surface
    from harness.metrics.surface_distance import Surface, cached_surface
    S_in = cached_surface(inp.cache, "input_surface", inp.V, inp.F)
    S_in.bvh()
    S_in.samples(n_samples, 1)
    S_out = Surface(res.V, res.F)
    S_out.bvh()

    def required():
        SA = Surface(res.V, res.F)
        _queries(sample_surface(res.V, res.F, n_samples, 0), S_in)
        P, order = S_in.samples(n_samples, 1)         # drawn once per input, as in a run
        _queries(P, SA, order)

    def bracket():
        _queries(res.V, S_in)
        _queries(inp.V, S_out)
    return required, bracket


def _smoothing_work(inp, res):
    from harness.core.geometry import face_around_vertex, morton_order
    from harness.metrics._queries import query_blocks
    from harness.metrics.surface_distance import cached_surface
    S = cached_surface(inp.cache, "clean_surface", inp.clean.V, inp.F)
    hints = face_around_vertex(np.asarray(inp.F, dtype=np.int64), len(res.V))

    def required():
        order = morton_order(res.V)
        query_blocks(res.V[order], S.leaf_faces(hints[order]), *S.bvh())
        S.displaced(res.V).corresponding_distances(S.V, S.walk())
    return required, None


def _laplacian_work(inp, res):
    import scipy.sparse as sp

    from harness.metrics._psd_kernel import face_split_bound
    W = sp.csr_matrix(res.W)
    S = (-(W + W.T) * 0.5).tocsr()
    S.eliminate_zeros()
    S.sort_indices()
    d = S.diagonal()
    off = np.asarray(abs(S).sum(axis=1)).ravel() - np.abs(d)
    if np.all(d >= 0) and np.all(d >= off):          # diagonal dominance settles the PSD column
        return (lambda: np.all(d >= off)), None
    k = np.frexp(float(d.max()))[1]
    V, F = np.ascontiguousarray(inp.V, dtype=np.float64), np.ascontiguousarray(inp.F, dtype=np.int64)
    indptr, indices = S.indptr.astype(np.int64), S.indices.astype(np.int64)

    def required():
        face_split_bound(indptr, indices, np.ldexp(S.data, -k), V, F)
    return required, None


WORK = {"simplification": lambda inp, res, case: _simplification_work(inp, res, case.hausdorff_samples),
        "smoothing": lambda inp, res, case: _smoothing_work(inp, res),
        "laplacian": lambda inp, res, case: _laplacian_work(inp, res)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default=str(ROOT / "configs" / "fixed_cost_sampled.yaml"))
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    from harness import tasks
    from harness.results import load_csv
    from harness.schema import task_file
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        subprocess.run([sys.executable, "-m", "harness.cli", "run", args.config, "--workers", "1", "--out", str(out),
                        "--quiet"], cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
        meta = json.loads((out / "run.json").read_text())
        fc = meta["fixed_cost_per_case_s"]
        threads = meta["timing"].get("threads_per_case") or 0
        ok = set()
        for t in tasks.names():
            if (out / task_file(t)).is_file():
                df = load_csv(out / task_file(t))
                ok |= set(df.loc[df["status"] == "ok", "case_id"])
    n = fc["cases"]
    fixed, measuring = fc["mean"] * n, fc["measuring_mean"] * n
    method = fixed / fc["share_of_method_time"]
    outside = fixed - measuring
    print(f"run ({args.config}, --workers 1): {n} ok cases, method time {method:.3f} s, fixed cost {fixed:.3f} s "
          f"(measuring {measuring:.3f} s, the rest {outside:.3f} s), share {fc['share_of_method_time']:.3f}")

    if threads:                                          # the run's cases measured on these threads
        os.environ["OMP_NUM_THREADS"] = str(threads)
    from harness import runner
    from harness.config import load_config
    from harness.plugins import import_methods
    cfg = load_config(args.config)
    methods = import_methods()
    required_s = bracket_s = facts_s = 0.0
    seen = set()
    for case in cfg.cases:
        if case.case_id not in ok:
            print(f"  {case.task:15s} {case.method:25s} not ok in the run: left out")
            continue
        task = tasks.get(case.task)
        if task.preload is not None:
            task.preload()
        inp, _ = runner.prepare_input(case)
        res = methods.get(case.method)(inp.V.copy(), inp.F.copy(), **case.params)
        key = (case.task, runner.input_mesh_name(case))
        if key not in seen:                              # the first case of this input for this task
            seen.add(key)
            fresh_inputs = []

            def fresh(case=case, res=res, task=task):
                task.measure(fresh_inputs.pop(), res, case.params)
            task.measure(inp, res, case.params)
            filled = _median_time(lambda: task.measure(inp, res, case.params), args.repeats)
            fresh_inputs[:] = [runner.prepare_input(case)[0] for _ in range(args.repeats + 1)]
            f = max(0.0, _median_time(fresh, args.repeats) - filled)
            facts_s += f
            print(f"  {case.task:15s} facts of {key[1]}: {f * 1e3:7.1f} ms")
        if case.task not in WORK:
            print(f"  {case.task}: no required work defined here; counted as 0")
            continue
        required, bracket = WORK[case.task](inp, res, case)
        r = _median_time(required, args.repeats)
        b = _median_time(bracket, args.repeats) if bracket is not None else 0.0
        required_s, bracket_s = required_s + r, bracket_s + b
        whole = _median_time(lambda: task.measure(inp, res, case.params), args.repeats)
        print(f"  {case.task:15s} {case.method:25s} required {r * 1e3:7.1f} ms, bracket's vertex queries "
              f"{b * 1e3:6.1f} ms, measuring now {whole * 1e3:7.1f} ms")
    base = outside + required_s
    print(f"share of the method time: outside measuring + required {base / method:.3f}; + the inputs' facts "
          f"{(base + facts_s) / method:.3f}; + this bracket's vertex queries {(base + facts_s + bracket_s) / method:.3f} "
          f"(the run: {fc['share_of_method_time']:.3f})")
    print(f"load average {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
