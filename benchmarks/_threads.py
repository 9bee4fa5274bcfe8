"""Math-library thread limits for the benchmarks' timed rounds."""
from __future__ import annotations


def limit_threads(n: int) -> str:
    """Limit every loaded math-library pool (BLAS, MKL, OpenMP) to ``n`` threads and return them
    as text (``mkl 1, openmp 1, ...``). Setting MKL's threads can load its OpenMP runtime
    (libiomp5) after threadpoolctl listed the pools, so the limit is set again until no pool is
    new (at most three times)."""
    from threadpoolctl import threadpool_info, threadpool_limits
    seen = None
    for _ in range(3):
        threadpool_limits(n)
        now = sorted(p.get("filepath") or "" for p in threadpool_info())
        if now == seen:
            break
        seen = now
    return pools()


def pools() -> str:
    """The loaded pools and their thread counts, as text."""
    from threadpoolctl import threadpool_info
    return ", ".join(sorted({f"{p.get('internal_api')} {p.get('num_threads')}" for p in threadpool_info()}))
