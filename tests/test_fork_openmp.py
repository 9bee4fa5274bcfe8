"""A driver that ran GNU OpenMP before its run (a notebook that called a MeshLab filter and then
PARDISO): a case forked from it would hang in PARDISO's first OpenMP region (libgomp is not
fork-safe). The driver tests a forked child first (`harness.executors.gomp`), and when that
hangs, the local executor runs each case in a fresh interpreter and says so. A method
registered in the driver's ``__main__`` exists in no fresh interpreter: that run forks as
before, warns, and a timeout row would say why."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TWO_CORES = pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="one core: libgomp starts no thread pool to inherit")


def _python(script: str, *args, paths=(), cwd=None, timeout: float = 600):
    """The JSON on the last stdout line of ``script`` run in a fresh interpreter with ``paths``
    on its path and two OpenMP threads, so that libgomp starts a pool (the test workers' own
    OpenMP is one thread: tests/conftest.py)."""
    env = {k: v for k, v in os.environ.items() if k not in ("OMP_NUM_THREADS", "MKL_NUM_THREADS")}
    env.update(PYTHONPATH=os.pathsep.join([str(ROOT), *map(str, paths)]), OMP_NUM_THREADS="2")
    out = subprocess.run([sys.executable, "-c", script, *map(str, args)], cwd=cwd, env=env, capture_output=True,
                         text=True, timeout=timeout)
    assert out.returncode == 0, out.stderr[-3000:]
    return json.loads(out.stdout.strip().splitlines()[-1])

SCRIPT = r"""
import json, sys, warnings
import harness
from harness.executors.gomp import forked_openmp_hangs, gnu_openmp_started
from harness.plugins import import_methods
from harness import datasets
from methods import register, SmoothingResult
fresh = gnu_openmp_started()
m = import_methods()
a = datasets.load("fandisk").clean
m.get("meshlab.taubin")(a.V, a.F)              # libgomp's pool started in this process
m.get("scratch.implicit")(a.V, a.F)            # PARDISO (MKL on that libgomp): 6,475 unknowns

@register("mainlab.same", task="smoothing", library="mainlab")
def same(V, F):
    return SmoothingResult(V=V.copy())

methods = sys.argv[2].split(",")
cfg = {"name": "gomp", "repeats": 1, "time_budget": 0, "timeout": 60, "meshes": ["fandisk"],
       "noise": [{"model": "gaussian_normal", "levels": [0.3]}],
       "tasks": {"smoothing": {"methods": methods}}}
with warnings.catch_warnings(record=True) as said:
    warnings.simplefilter("always")
    df = harness.run(cfg, out=sys.argv[1], quiet=True, workers=int(sys.argv[3]))["smoothing"]
import glob, os
views = [json.load(open(f)) for f in sorted(glob.glob(os.path.join(sys.argv[1], "views", "0*.json")))]
print(json.dumps({"fresh": fresh, "after": gnu_openmp_started(), "hangs": forked_openmp_hangs(),
                  "views": [[v.get("error"), "meshes" in v] for v in views], "status": df["status"].tolist(),
                  "method": df["method"].tolist(), "error": df["error"].fillna("").tolist(),
                  "dist": df["dist_mean"].tolist(),
                  "warned": [str(w.message) for w in said if issubclass(w.category, RuntimeWarning)]}))
"""


def _run(tmp_path, methods, workers=1):
    got = _python(SCRIPT, tmp_path / "run", ",".join(methods), workers, cwd=tmp_path)
    assert got["fresh"] is False and got["after"] is True and got["hangs"] is True
    return got


@TWO_CORES
def test_a_driver_that_started_gnu_openmp_runs_its_cases_in_fresh_interpreters(tmp_path):
    got = _run(tmp_path, ["scratch.implicit", "meshlab.taubin"])
    # forked with two threads a case (one worker on two cores), scratch.implicit was a timeout row
    assert got["status"] == ["ok", "ok"], got
    assert any("fresh Python process" in w for w in got["warned"]), got["warned"]
    assert not any("__main__" in w for w in got["warned"]), got["warned"]
    assert all(d > 0 for d in got["dist"]), got
    # the 3D views run their cases again after the run: fresh too (forked, each waited for its timeout)
    assert got["views"] and all(v == [None, True] for v in got["views"]), got["views"]


@TWO_CORES
def test_a_method_registered_in_main_forks_as_before_and_the_warning_says_why(tmp_path):
    got = _run(tmp_path, ["mainlab.same"])
    assert got["status"] == ["ok"], got
    assert any("GNU OpenMP" in w and "__main__" in w for w in got["warned"]), got["warned"]


PROBE = r"""
import json, sys
from harness.executors.gomp import forked_openmp_hangs, gnu_openmp_started
import pymeshlab                                # loads libgomp and starts a thread of its own
said = [gnu_openmp_started(), forked_openmp_hangs()]
from harness.plugins import import_methods
from harness import datasets
a = datasets.load("fandisk").clean
import_methods().get("scratch.implicit")(a.V, a.F)   # PARDISO: libgomp's pool of two threads
said += [gnu_openmp_started(), forked_openmp_hangs(timeout=float(sys.argv[1]))]
print(json.dumps(said))
"""


@TWO_CORES
def test_the_probe_tells_a_loaded_libgomp_from_a_started_pool():
    said = _python(PROBE, "1.0", timeout=300)
    # PyMeshLab imported (libgomp loaded, and a thread of its own, which may not show yet): a
    # forked child runs OpenMP fine; after PARDISO's two threads it hangs
    assert said[1:] == [False, True, True], said


EDITED = r"""
import json, sys, warnings
from pathlib import Path
import harness
from harness import datasets
from harness.executors.gomp import forked_openmp_hangs
from harness.plugins import import_methods
a = datasets.load("fandisk").clean
m = import_methods()
m.get("meshlab.taubin")(a.V, a.F)              # PyMeshLab's libgomp, which MKL then uses
m.get("scratch.implicit")(a.V, a.F)
out, where, plugin, method, runs = sys.argv[1:6]          # a plugin module in folder `where`
cfg = {"name": "edited", "repeats": 1, "time_budget": 0, "timeout": 60, "meshes": ["fandisk"],
       "plugins": [plugin], "tasks": {"smoothing": {"methods": [method]}}}
said = [forked_openmp_hangs()]
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    for i in range(int(runs)):
        df = harness.run(cfg, out=f"{out}{i}", quiet=True, workers=1)["smoothing"]
        said.append([df["status"].tolist(), df["error"].fillna("").tolist()])
        with open(Path(where) / f"{plugin}.py", "a") as fh:    # edited between the runs
            fh.write("# edited\n")
print(json.dumps(said))
"""


@TWO_CORES
def test_a_plugin_edited_between_two_fresh_runs_keeps_the_second_runs_rows(tmp_path):
    """A review: the driver's code hash was kept from the first run, so every row of a second
    run after an edit was refused as "changed during the run"."""
    (tmp_path / "tmpplug.py").write_text(
        "from methods import register, SmoothingResult\n"
        "@register('tmplab.same', task='smoothing', library='tmplab')\n"
        "def same(V, F):\n    return SmoothingResult(V=V.copy())\n")
    said = _python(EDITED, tmp_path / "run", tmp_path, "tmpplug", "tmplab.same", 2, paths=[tmp_path], cwd=tmp_path)
    assert said == [True, [["ok"], [""]], [["ok"], [""]]], said


OMP_PLUGIN = """
import ctypes
import pymeshlab  # noqa: F401 - its libgomp
path = next(ln.split(maxsplit=5)[5].strip() for ln in open("/proc/self/maps") if "libgomp" in ln)
def region():
    ctypes.CDLL(path).GOMP_parallel(ctypes.cast(ctypes.CDLL(None).free, ctypes.c_void_p), None, 2, 0)
region()                                        # at import: libgomp's pool of two threads
from methods import register, SmoothingResult
@register("omplab.same", task="smoothing", library="omplab")
def same(V, F):
    region()                                    # and in the method: a fork of the importer hangs here
    return SmoothingResult(V=V.copy())
"""


@TWO_CORES
def test_a_plugin_that_runs_openmp_at_import_is_tried_in_a_fresh_interpreter(tmp_path):
    """The config's plugins are first imported in a trial process, a fork of the driver: in a
    driver whose fork hangs in GNU OpenMP, a plugin entering an OpenMP region at import hung the
    trial, and the run with it. The case's fresh interpreter imports it too (its pool started
    there): the case then runs in that interpreter, not in a fork of it, where its region hung."""
    (tmp_path / "ompplug.py").write_text(OMP_PLUGIN)
    said = _python(EDITED, tmp_path / "run", tmp_path, "ompplug", "omplab.same", 1, paths=[tmp_path], cwd=tmp_path,
                   timeout=180)
    assert said == [True, [["ok"], [""]]]
