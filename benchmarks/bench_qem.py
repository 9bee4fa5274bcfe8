"""Benchmark: scratch.qem against fast-simplification and MeshLab (and optionally PyGEL3D,
libigl QSlim) on large meshes, to 10% of the faces.

Run:  .venv/bin/python benchmarks/bench_qem.py [--sizes large,200k] [--repeats 3]
                                               [--with pygel,qslim] [--ratio 0.1]

Meshes (built here, deterministic):
- ``large``: the bundled armadillo (86,482 faces) with two rounds of Loop subdivision
  (``igl.loop``; vertices move, so the surface is smooth, not piecewise flat): 1,383,712 faces.
- ``200k``: the bundled fandisk (12,946 faces), two rounds of Loop subdivision: 207,136 faces.

Everything runs in one process. Before timing, every method runs once on a small mesh (numba
compilation / cache load, library initialisation). The fast methods are then timed in
interleaved rounds (scratch, fast-simplification, scratch, ...) so that load changes on a
shared machine hit both alike; the median wall time and the median CPU time (process_time,
less sensitive to other processes) are reported. The slow libraries run once per size.

Accuracy: symmetric Hausdorff distance between input and output, relative to the input's
bounding-box diagonal, computed here with ``igl.point_mesh_squared_distance`` from all
vertices plus ``--samples`` area-uniform random points of each surface, in both directions.

Targets (issue 5): scratch.qem time <= 3x fast-simplification's, and Hausdorff <= 1.1x
MeshLab's.
"""
from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

MESHES = {"large": ("armadillo.obj", 2), "200k": ("fandisk.obj", 2)}
DATA = Path(__file__).resolve().parents[1] / "harness" / "data" / "meshes"


def build(size: str) -> tuple[np.ndarray, np.ndarray]:
    import igl

    fname, rounds = MESHES[size]
    V, F = igl.read_triangle_mesh(str(DATA / fname))
    V, F = igl.loop(V, F, rounds)
    return np.ascontiguousarray(V, dtype=np.float64), np.ascontiguousarray(F, dtype=np.int64)


def area_samples(V: np.ndarray, F: np.ndarray, n: int, rng) -> np.ndarray:
    """n points uniformly distributed by area on the mesh (vectorised)."""
    dbl = np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    f = rng.choice(len(F), size=n, p=dbl / dbl.sum())
    r1 = np.sqrt(rng.random(n))
    r2 = rng.random(n)
    a, b, c = 1 - r1, r1 * (1 - r2), r1 * r2
    return a[:, None] * V[F[f, 0]] + b[:, None] * V[F[f, 1]] + c[:, None] * V[F[f, 2]]


def hausdorff(VA, FA, VB, FB, samples: int, seed: int = 0) -> float:
    """max(h(A, B), h(B, A)), h(X, Y) = max over X's vertices and samples of dist to Y."""
    import igl

    rng = np.random.default_rng(seed)
    PA = np.concatenate([VA, area_samples(VA, FA, samples, rng)])
    PB = np.concatenate([VB, area_samples(VB, FB, samples, rng)])
    dab, _, _ = igl.point_mesh_squared_distance(PA, VB, FB)
    dba, _, _ = igl.point_mesh_squared_distance(PB, VA, FA)
    return float(np.sqrt(max(np.max(dab), np.max(dba))))


def timed(fn, V, F, target):
    c0, t0 = time.process_time(), time.perf_counter()
    res = fn(V, F, target_faces=target)
    return res, time.perf_counter() - t0, time.process_time() - c0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="large,200k")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--ratio", type=float, default=0.1)
    ap.add_argument("--samples", type=int, default=200_000)
    ap.add_argument("--with", dest="extra", default="",
                    help="comma list of slow extra peers: pygel, qslim")
    args = ap.parse_args(argv)

    import methods

    fast = {"scratch.qem": methods.get("scratch.qem"),
            "fast_simplification.qem": methods.get("fast_simplification.qem")}
    slow = {"meshlab.qem": methods.get("meshlab.qem")}
    extra = {"pygel": "pygel.qem", "qslim": "libigl.qslim"}
    for e in filter(None, args.extra.split(",")):
        slow[extra[e]] = methods.get(extra[e])

    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cpus, "
          f"load average {os.getloadavg()[0]:.1f} (shared machine: timings are under load)")
    import igl
    Vw, Fw = igl.read_triangle_mesh(str(DATA / "bunny.off"))
    c0 = time.perf_counter()
    fast["scratch.qem"](Vw, Fw, target_ratio=0.5)
    print(f"warm-up (numba compile or cache load + first call): {time.perf_counter() - c0:.2f} s")
    for m in list(fast.values()) + list(slow.values()):
        m(Vw, Fw, target_ratio=0.5)

    summary = []
    for size in filter(None, args.sizes.split(",")):
        V, F = build(size)
        target = int(round(args.ratio * len(F)))
        diag = float(np.linalg.norm(V.max(0) - V.min(0)))
        print(f"\n== {size}: {MESHES[size][0]} Loop x{MESHES[size][1]}: {len(V):,} vertices, "
              f"{len(F):,} faces -> {target:,} faces ==")
        rows = {}
        walls = {k: [] for k in fast}
        cpus = {k: [] for k in fast}
        res_of = {}
        for _ in range(args.repeats):
            for name, m in fast.items():
                res, w, c = timed(m, V, F, target)
                walls[name].append(w)
                cpus[name].append(c)
                res_of[name] = res
        for name in fast:
            rows[name] = (statistics.median(walls[name]), statistics.median(cpus[name]),
                          res_of[name])
        for name, m in slow.items():
            res, w, c = timed(m, V, F, target)
            rows[name] = (w, c, res)
        print(f"{'method':26s} {'wall s':>8s} {'cpu s':>8s} {'faces':>9s} {'hausdorff/diag':>15s}")
        haus = {}
        for name, (w, c, res) in rows.items():
            haus[name] = hausdorff(V, F, res.V, res.F, args.samples) / diag
            print(f"{name:26s} {w:8.2f} {c:8.2f} {len(res.F):9,d} {haus[name]:15.3e}")
        s, fs, ml = rows["scratch.qem"], rows["fast_simplification.qem"], rows["meshlab.qem"]
        t_ratio_w, t_ratio_c = s[0] / fs[0], s[1] / fs[1]
        h_ratio = haus["scratch.qem"] / haus["meshlab.qem"]
        print(f"ratios: scratch/fast-simplification time {t_ratio_w:.2f}x wall, "
              f"{t_ratio_c:.2f}x cpu (target <= 3); scratch/meshlab time {s[0] / ml[0]:.2f}x; "
              f"Hausdorff scratch/meshlab {h_ratio:.2f} (target <= 1.1), "
              f"scratch/fast-simplification {haus['scratch.qem'] / haus['fast_simplification.qem']:.2f}")
        summary.append((size, t_ratio_w, t_ratio_c, h_ratio))
    print("\nsummary (size, time ratio wall, time ratio cpu, Hausdorff ratio vs MeshLab):")
    for row in summary:
        print(f"  {row[0]:6s} {row[1]:.2f} {row[2]:.2f} {row[3]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
