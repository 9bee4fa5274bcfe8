"""Shared fixtures: one small run of all three tasks, reused by the report tests.

The pytest workers run methods in-process too (PARDISO, MeshLab filters) before they run
configs. With GNU OpenMP on several threads, that starts libgomp's pool, which a forked case
cannot use, and the local executor then runs every case in a fresh interpreter
(`harness.executors.gomp`), several times slower for these small runs. The workers' own OpenMP
is one thread (``OMP_NUM_THREADS`` and ``MKL_NUM_THREADS``, read when libgomp and MKL load;
OpenBLAS keeps its own count):
their case processes still get their threads from the runner, and `tests/test_fork_openmp.py`
tests the fresh path in interpreters of its own. A test that runs a case in-process with
several threads (the serial executor) could still start a pool; none does now, and the suite's
runs then warn (the warning is ignored in pyproject; `-W default:"a process forked"` shows it).
"""
import os

os.environ["OMP_NUM_THREADS"] = "1"       # whatever the CI's environment says: MKL reads its own first
os.environ["MKL_NUM_THREADS"] = "1"
os.environ.setdefault("OPENBLAS_NUM_THREADS", str(len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                                                  else os.cpu_count() or 1))

import pytest  # noqa: E402

import harness  # noqa: E402

# every task, two meshes (one planar so LIN is measured), two noise levels plus none
TINY = {
    "name": "tiny-report",
    "repeats": 1,
    "time_budget": 0,         # one timed sample a case: these tests read rows and pages, not timings
    "seed": 0,
    "hausdorff_samples": 2000,
    "meshes": ["knight", {"procedural": "plane_nondelaunay", "n_points": 120}],
    "noise": [{"model": "gaussian_normal", "levels": [0.2, 0.5]}, {"model": "none"}],
    "tasks": {
        "laplacian": {"methods": ["scratch.uniform", "scratch.cotan"]},
        "smoothing": {"methods": [{"name": "scratch.explicit", "params": {"iterations": [2, 6]}}]},
        "simplification": {"methods": ["fast_simplification.qem"], "params": {"target_ratio": [0.5, 0.2]}},
    },
}


@pytest.fixture(scope="session")
def tiny_run(tmp_path_factory):
    """Run folder of `TINY` (read-only: tests that change files work on a copy)."""
    out = tmp_path_factory.mktemp("tiny_run")
    harness.run(TINY, out=out, quiet=True, workers=1)
    return out
