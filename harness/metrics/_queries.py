"""Exact distances of many points to a surface, in fixed blocks run on the case's threads.

`query_blocks` answers what `harness.metrics._bvh_kernel.query_many` answers (each point's
distance to the hierarchy's triangles and its closest face) block by block: the points are cut
into blocks of `BLOCK` in their given order, and each block is one ``query_many`` call (its first
point without a hint starts at the root, each next one from its predecessor's closest face). The
blocks do not depend on the thread count, so the distances and faces are the same whatever the
threads; only the time changes. The case's threads are ``OMP_NUM_THREADS``, which the runner sets
to the case's thread count (cores over workers) for the whole case, measuring included; unset or
invalid: one.
"""
from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

BLOCK = 4096


def case_threads() -> int:
    """Threads the case may use: ``OMP_NUM_THREADS`` (at least 1, at most the CPUs this process
    may run on, `harness.provenance.usable_cpus`: its affinity set and cgroup quota)."""
    from ..provenance import usable_cpus
    try:
        n = int(os.environ.get("OMP_NUM_THREADS", "1"))
    except ValueError:
        n = 1
    return max(1, min(n, usable_cpus()))


def query_blocks(P: np.ndarray, hints: np.ndarray, V, F, B, threads: int | None = None):
    """``(d, f)``: distances (k,) and closest faces (k,) of the points ``P`` (k, 3) to the
    hierarchy ``(V, F, B)`` (`harness.metrics.surface_distance.Surface.bvh`); ``hints`` (k,):
    a face to start each query from, -1 for none. ``threads``: default `case_threads`."""
    from ._bvh_kernel import query_many
    P = np.ascontiguousarray(P, dtype=np.float64)
    hints = np.ascontiguousarray(hints, dtype=np.int64)
    k = len(P)
    d, f = np.empty(k), np.empty(k, np.int64)
    starts = range(0, k, BLOCK)

    def one(s: int) -> None:
        e = min(s + BLOCK, k)
        d[s:e], f[s:e] = query_many(P[s:e], hints[s:e], V, F, B)
    n = min(case_threads() if threads is None else max(1, int(threads)), len(starts))
    if n <= 1:
        for s in starts:
            one(s)
    else:
        with ThreadPoolExecutor(n) as pool:
            for _ in pool.map(one, starts):
                pass
    return d, f
