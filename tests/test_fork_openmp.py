"""A driver that ran GNU OpenMP before forking its cases (a notebook that called a MeshLab filter
and then PARDISO): the forked case hangs in PARDISO's first OpenMP region (libgomp is not
fork-safe) until its timeout. The run warns, and the timeout row says why."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

SCRIPT = r"""
import json, sys, warnings
import harness
from harness.executors.local import gnu_openmp_started
from harness.plugins import import_methods
from harness import datasets
fresh = gnu_openmp_started()
m = import_methods()
a = datasets.load("fandisk").clean
m.get("meshlab.taubin")(a.V, a.F)              # libgomp's pool started in this process
m.get("scratch.implicit")(a.V, a.F)            # PARDISO (MKL on that libgomp): 6,475 unknowns
cfg = {"name": "gomp", "repeats": 1, "time_budget": 0, "timeout": 8, "meshes": ["fandisk"],
       "noise": [{"model": "gaussian_normal", "levels": [0.3]}],
       "tasks": {"smoothing": {"methods": ["scratch.implicit"]}}}
with warnings.catch_warnings(record=True) as said:
    warnings.simplefilter("always")
    df = harness.run(cfg, out=sys.argv[1], quiet=True, workers=1)["smoothing"]
print(json.dumps({"fresh": fresh, "after": gnu_openmp_started(), "status": df["status"].tolist(),
                  "error": df["error"].fillna("").tolist(),
                  "warned": [str(w.message) for w in said if issubclass(w.category, RuntimeWarning)]}))
"""


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="one core: libgomp starts no thread pool to inherit")
def test_a_driver_that_started_gnu_openmp_warns_and_its_timeout_rows_say_why(tmp_path):
    # two OpenMP threads, so libgomp starts a pool (a test before this one in the same pytest
    # worker may have left OMP_NUM_THREADS=1 in the environment: then it starts none)
    env = {k: v for k, v in os.environ.items() if k not in ("OMP_NUM_THREADS", "MKL_NUM_THREADS")}
    env.update(PYTHONPATH=str(ROOT), OMP_NUM_THREADS="2")
    out = subprocess.run([sys.executable, "-c", SCRIPT, str(tmp_path / "run")], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-3000:]
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["fresh"] is False and got["after"] is True
    assert any("GNU OpenMP" in w for w in got["warned"]), got["warned"]
    if got["status"] == ["timeout"]:                  # the hang (here every time): said in the row
        assert "GNU OpenMP (libgomp)" in got["error"][0], got["error"]
    else:
        assert got["status"] == ["ok"], got
