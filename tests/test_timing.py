"""The timing protocol: cold call kept apart, every sample stored, autorange, thread limits, method
memory; and the statistical compare on two real runs (no false alarm, a 2x slowdown flagged)."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import harness

pytestmark = pytest.mark.serial          # timing verdicts: run alone (make test runs the rest two at a time)

ROOT = Path(__file__).resolve().parents[1]

CFG = {"name": "timing", "hausdorff_samples": 200, "plugins": ["tests.plugins.slowdown"],
       "meshes": ["knight", "woody"], "noise": [{"model": "gaussian_normal", "levels": [0.2]}],
       "time_budget": 0.25,
       "tasks": {"smoothing": {"methods": ["slowdown.sleep", "scratch.explicit", "scratch.implicit",
                                           "scratch.taubin"]},
                 "laplacian": {"methods": ["scratch.cotan", "scratch.uniform"]}}}


def _run(out, factor):
    env = {**os.environ, "SLOWDOWN_FACTOR": str(factor), "PYTHONPATH": str(ROOT)}
    cfg = Path(out).with_suffix(".yaml")
    cfg.write_text(json.dumps(CFG))
    r = subprocess.run([sys.executable, "-m", "harness.cli", "run", str(cfg), "--out", str(out), "--quiet"],
                       cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr


def test_protocol_columns(tmp_path):
    out = tmp_path / "run"
    harness.run(CFG, out=out, quiet=True)
    df = pd.read_csv(out / "smoothing.csv")
    assert (df["status"] == "ok").all(), df[["method", "error"]]
    for r in df.itertuples():
        times = json.loads(r.times)
        assert len(times) == r.repeats >= 1 and min(times) == r.time_min_s and max(times) == r.time_max_s
        assert r.time_q1_s <= r.time_s <= r.time_q3_s and r.time_cold_s > 0
        cpu = json.loads(r.cpu_times)                 # one CPU time per sample, median time_cpu_s
        assert len(cpu) == len(times) and min(cpu) >= 0 and r.time_cpu_s == float(np.median(cpu))
        if sum(times) >= 0.25:                        # a window long enough for /proc/stat's ticks
            assert 0 <= r.others_cpu <= os.cpu_count()
        else:
            assert np.isnan(r.others_cpu) or 0 <= r.others_cpu <= os.cpu_count()
        # autorange: keeps sampling until the budget is spent (or the sample cap)
        assert sum(times) >= 0.25 or len(times) == 1000
    assert df["others_cpu"].notna().any()
    sleep = df[df.method == "slowdown.sleep"]
    assert (sleep["time_s"] > 0.004).all() and (sleep["repeats"] >= 20).all()
    assert (sleep["time_cpu_s"] < 0.5 * sleep["time_s"]).all()      # sleeping uses no CPU
    meta = json.loads((out / "run.json").read_text())
    assert meta["timing"]["threads_per_case"] == max(1, (os.cpu_count() or 1) // meta["workers"])
    fixed = meta["fixed_cost_per_case_s"]             # outside the method: loading, noise, measuring
    assert fixed["cases"] == sum(len(pd.read_csv(p)) for p in out.glob("*.csv") if p.stem in ("smoothing", "laplacian"))
    assert 0 <= fixed["mean"] <= fixed["max"] < 30
    ok = pd.concat([pd.read_csv(out / f"{t}.csv") for t in ("smoothing", "laplacian")])
    spent = sum(sum(json.loads(t)) for t in ok["times"]) + ok["time_cold_s"].sum()
    assert fixed["share_of_method_time"] == pytest.approx(fixed["mean"] * fixed["cases"] / spent,
                                                         abs=5e-5 * fixed["cases"] / spent + 1e-4)   # mean rounded
    assert 0 <= fixed["median_case_share"]
    assert 0 < fixed["measuring_mean"] <= fixed["mean"]          # every ok case measured its result
    mem = pd.read_csv(out / "laplacian.csv")["method_mem_mb"]
    if Path("/proc/self/clear_refs").exists():
        assert mem.notna().all() and (mem >= 0).all()


def test_back_to_back_runs_compare_equal_and_a_2x_slowdown_is_flagged(tmp_path):
    a, b, c = tmp_path / "a", tmp_path / "b", tmp_path / "c"
    _run(a, 1)
    _run(b, 1)
    _run(c, 2)
    same = subprocess.run([sys.executable, "-m", "harness.cli", "compare", str(a), str(b)], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    assert same.returncode == 0, same.stdout
    slow = subprocess.run([sys.executable, "-m", "harness.cli", "compare", str(a), str(c)], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    assert slow.returncode == 1, slow.stdout
    flagged = [ln for ln in slow.stdout.splitlines() if ln.startswith("REGRESSION")]
    assert flagged and all("slowdown.sleep" in ln and "time_s" in ln for ln in flagged), slow.stdout


def test_workers_and_threads_follow_the_cpus_the_process_may_use(tmp_path):
    """An outside review: under `taskset -c 0` a run took os.cpu_count() (2) for its workers and
    threads per case, so a BLAS case ran 2 threads on 1 allowed CPU (eigh of a 700 x 700 matrix
    9.6 s against 0.13 s). Now the affinity set (and a cgroup quota) bounds both."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text("meshes: [knight]\nrepeats: 1\ntime_budget: 0\ntasks: {laplacian: {methods: [scratch.uniform]}}\n")
    r = subprocess.run([sys.executable, "-m", "harness.cli", "run", str(cfg), "--out", str(tmp_path / "o"), "--quiet"],
                       cwd=ROOT, capture_output=True, text=True, timeout=300,
                       preexec_fn=lambda: os.sched_setaffinity(0, {min(os.sched_getaffinity(0))}))
    assert r.returncode == 0, r.stderr
    meta = json.loads((tmp_path / "o" / "run.json").read_text())
    assert meta["workers"] == 1 and meta["timing"]["threads_per_case"] == 1
    assert meta["machine"]["usable_cpus"] == 1 and meta["machine"]["cpu_count"] == os.cpu_count()


def test_thread_limits_reuse_the_drivers_scan_until_a_library_is_loaded(monkeypatch):
    """`limit_threads` in a case process reuses the driver's thread-pool scan (so a case does not
    pay for it) and limits every pool it found; a shared object loaded after the scan is seen
    (the count of loaded objects changes), so the limits are then set from a new scan."""
    import ctypes
    import threadpoolctl
    from harness import runner
    monkeypatch.setattr(runner, "_POOLS", runner._POOLS)   # the scan is undone after the test
    runner.scan_thread_pools()
    n0 = runner._loaded_objects()
    assert n0 and n0 == runner._POOLS[1]
    lim = runner.limit_threads(1)
    try:
        assert all(p["num_threads"] == 1 for p in threadpoolctl.threadpool_info())
    finally:
        lim.restore_original_limits()
    with open("/proc/self/maps") as fh:
        mapped = fh.read()
    new = next(name for name in ("libform.so.6", "libmenu.so.6", "libgdbm.so.6", "libexpatw.so.1")
               if name not in mapped)
    ctypes.CDLL(new)
    assert runner._loaded_objects() > n0


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="one core: one thread is also OpenMP's default")
def test_pools_a_method_loads_on_its_first_call_are_limited_for_the_samples(tmp_path):
    """A method that loads an OpenMP runtime inside its first call (here PyMeshLab's libgomp,
    imported in the call) gets that pool limited to the case's threads, in the timed samples
    (threadpoolctl, after the cold call) and in the cold call itself (OMP_NUM_THREADS, set in
    the case). A fresh interpreter, so no earlier test has loaded libgomp."""
    pytest.importorskip("pymeshlab")
    log = tmp_path / "seen.jsonl"
    code = (
        "from harness.config import Case\n"
        "from harness.runner import run_case\n"
        "c = Case(case_id='c', task='smoothing', mesh={'bundled': 'knight'}, mesh_key='knight',\n"
        "         noise_model='none', noise_level=0.0, seed=0, fraction=1.0,\n"
        "         method='lazy_openmp.identity', params={}, repeats=3, time_budget=0.0,\n"
        "         plugins=('tests.plugins.lazy_openmp',), threads=1)\n"
        "row, _ = run_case(c)\n"
        "assert row['status'] == 'ok', row.get('error')\n")
    env = {k: v for k, v in os.environ.items() if k != "OMP_NUM_THREADS"}
    env.update(LAZY_OPENMP_LOG=str(log), PYTHONPATH=str(ROOT))
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    calls = [json.loads(line) for line in log.read_text().splitlines()]
    assert len(calls) >= 4 and calls[0]                 # the cold call and three samples
    assert all(c == [1] * len(c) and c for c in calls), calls     # the cold call too (OMP_NUM_THREADS)


def test_a_forked_case_inherits_the_drivers_limit_and_starts_no_spinning_pool():
    """The driver limits its pools to the case threads before forking; the case keeps that limit
    without setting it again. Setting it again in the case started fresh OpenBLAS workers that
    spun for ~0.1 s: a sleeping method's first samples showed as much CPU as wall time."""
    import threadpoolctl
    from harness import runner
    before = [p["num_threads"] for p in threadpoolctl.threadpool_info()]
    try:
        runner.scan_thread_pools(1)
        runner.scan_thread_pools(2)                    # a second run in the same process: not stacked
        assert runner._PARENT_LIMIT[0] == 2
        r, w = os.pipe()
        pid = os.fork()
        if pid == 0:                                   # the case process
            ok = runner.limit_threads(2) is None         # nothing to set: inherited
            ok &= all(p["num_threads"] == 2 for p in threadpoolctl.threadpool_info()
                      if p["internal_api"] == "openblas")
            c0, t0 = time.process_time(), time.perf_counter()
            time.sleep(0.05)
            busy = (time.process_time() - c0) / (time.perf_counter() - t0)
            os.write(w, f"{int(ok)} {busy:.3f}".encode())
            os._exit(0)
        os.close(w)
        ok, busy = os.read(r, 100).decode().split()
        os.waitpid(pid, 0)
        assert ok == "1" and float(busy) < 0.2, busy
    finally:
        runner.release_thread_pools()
    assert runner._PARENT_LIMIT is None and [p["num_threads"] for p in threadpoolctl.threadpool_info()] == before


@pytest.mark.parametrize("executor", ["serial", "local"])
def test_a_run_leaves_the_callers_thread_pools_as_they_were(tmp_path, executor):
    """The cases' thread limit is undone when the run ends: an in-process (serial) run left the
    caller's BLAS pools at the case's thread count."""
    import contextlib

    import threadpoolctl
    # serial: one case at a time with every core, under a caller limited to 1 thread; local: two
    # workers of one thread each, under an unlimited caller
    with threadpoolctl.threadpool_limits(1) if executor == "serial" else contextlib.nullcontext():
        before = {p["filepath"]: p["num_threads"] for p in threadpoolctl.threadpool_info()}
        harness.run({"name": "t", "meshes": ["knight"], "noise": [{"model": "none"}], "time_budget": 0,
                     "tasks": {"laplacian": {"methods": ["scratch.uniform"]}}}, out=tmp_path / "r",
                    workers=1 if executor == "serial" else max(2, os.cpu_count() or 1), executor=executor)
        after = {p["filepath"]: p["num_threads"] for p in threadpoolctl.threadpool_info()}
    assert before and {k: after[k] for k in before} == before


def test_libigls_own_threads_get_the_cases_limit(tmp_path, monkeypatch):
    """libigl starts std::threads that threadpoolctl does not see: with 2 workers on 2 cores
    libigl.cotan's wall time was 1.5-2x its CPU time on bunny, beside a single-threaded peer at 1x
    (the order of the two flipped with --workers). Its own knob is IGL_NUM_THREADS, read once per
    process: every case process sees threads_per_case, and the caller's value comes back."""
    monkeypatch.syspath_prepend(str(Path(__file__).resolve().parents[1]))
    monkeypatch.setenv("HOSTILE_MARK_DIR", str(tmp_path))
    monkeypatch.setenv("IGL_NUM_THREADS", "7")
    cfg = {"name": "t", "meshes": ["knight"], "time_budget": 0, "plugins": ["tests.plugins.hostile"],
           "noise": [{"model": "gaussian_normal", "levels": [0.1], "seeds": 2}],
           "tasks": {"smoothing": {"methods": ["hostile.report_igl_threads"]}}}
    harness.run(cfg, out=tmp_path / "r", workers=2, quiet=True)
    seen = {p.read_text() for p in tmp_path.glob("igl-threads-*.txt")}
    assert seen == {str(max(1, (os.cpu_count() or 1) // 2))}, seen
    assert os.environ["IGL_NUM_THREADS"] == "7"
    assert "IGL_NUM_THREADS" in json.loads((tmp_path / "r" / "run.json").read_text())["timing"]["protocol"]


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="one core: one thread is also MKL's default")
def test_a_library_loaded_in_the_cold_call_gets_the_cases_thread_limit(tmp_path):
    """MKL loaded by a method's first pypardiso solve (after the case's pools were limited) ran
    its cold call with every core, beside another case's timed samples; MKL_NUM_THREADS (with
    OMP_ and OPENBLAS_) set in each case limits it from its first call; the 3D views, which run
    cases again after the run, too."""
    pytest.importorskip("pypardiso")
    cfg = tmp_path / "c.yaml"
    cfg.write_text(json.dumps({"name": "t", "meshes": ["knight"], "time_budget": 0, "repeats": 1,
                               "plugins": ["tests.plugins.hostile"],
                               "noise": [{"model": "gaussian_normal", "levels": [0.1], "seeds": 2}],
                               "tasks": {"smoothing": {"methods": ["hostile.lazy_mkl"]}}}))
    env = {**os.environ, "PYTHONPATH": str(ROOT), "HOSTILE_MARK_DIR": str(tmp_path)}
    for k in ("MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        env.pop(k, None)
    r = subprocess.run([sys.executable, "-m", "harness.cli", "run", str(cfg), "--out", str(tmp_path / "r"),
                        "--workers", "2", "--quiet"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    calls = [ln for p in sorted(tmp_path.glob("mkl-threads-*.txt")) for ln in p.read_text().split()]
    assert len(calls) >= 4 and set(calls) == {str(max(1, os.cpu_count() // 2))}, calls   # cold calls and samples
    for p in tmp_path.glob("mkl-threads-*.txt"):
        p.unlink()
    r = subprocess.run([sys.executable, "-m", "harness.cli", "views", str(tmp_path / "r")], cwd=ROOT, env=env,
                       capture_output=True, text=True, timeout=300)       # views recomputed later: the run's threads
    assert r.returncode == 0, r.stderr
    calls = [ln for p in sorted(tmp_path.glob("mkl-threads-*.txt")) for ln in p.read_text().split()]
    assert calls and set(calls) == {str(max(1, os.cpu_count() // 2))}, calls


def test_no_sample_reuses_the_factorization_pypardiso_spsolve_keeps():
    """An outside review: a plugin doing one implicit step with `pypardiso.spsolve`, as the
    package's README shows, timed 0.095 s per sample against 0.207 s for the same call without
    the factorization pypardiso keeps from the cold call (it skips the factorization when it
    sees the same matrix again). Each timed call now starts without it."""
    import scipy.sparse as sp
    pypardiso = pytest.importorskip("pypardiso")
    from harness.runner import forget_inputs
    A = sp.random(200, 200, density=0.02, random_state=0, format="csr") + sp.identity(200, format="csr") * 5
    A = (A + A.T).tocsr()
    x1 = pypardiso.spsolve(A, np.ones(200))
    assert pypardiso.ps.factorized_A.shape == (200, 200)      # kept: the next call on A would skip phase 12
    forget_inputs()
    assert pypardiso.ps.factorized_A.shape == (0, 0)
    assert np.allclose(pypardiso.spsolve(A, np.ones(200)), x1)


def test_timed_calls_do_not_reuse_a_previous_calls_symbolic_analysis(monkeypatch):
    """The solvers' pattern-keyed symbolic analyses are dropped before the cold call and every
    sample: a sample of an implicit step pays for its ordering like a first call on the mesh
    (it used to inherit the cold call's, about half of libigl.implicit's time at 86k faces)."""
    from harness import runner
    from harness.config import load_config
    from harness.core import solvers
    seen = []
    real = solvers.factorize

    def spy(A, *a, **k):
        seen.append(len(solvers._SYMBOLIC))
        return real(A, *a, **k)
    monkeypatch.setattr(solvers, "factorize", spy)
    cfg = load_config({"name": "t", "repeats": 3, "time_budget": 0, "meshes": ["knight"],
                       "noise": [{"model": "gaussian_normal", "levels": [0.2]}],
                       "tasks": {"smoothing": {"methods": [
                           {"name": "scratch.implicit", "params": {"iterations": 2, "solver": "scipy"}},
                           {"name": "libigl.implicit", "params": {"iterations": 2, "solver": "scipy"}}]}}})
    for case in cfg.cases:
        seen.clear()
        row, _ = runner.run_case(case)
        assert row["status"] == "ok", row["error"]
        assert row["repeats"] == 3 and len(seen) >= 4, seen
        assert seen.count(0) == 4, seen        # one fresh start per call: the cold call and 3 samples


def test_every_sample_starts_from_a_trimmed_heap(monkeypatch):
    """Freed heap memory goes back to the OS before every sample, not only before the first
    (trimmed for the memory measurement): otherwise sample 1 alone paid for touching fresh
    memory, 1.0-1.24x the others at 86k faces, and a method with one or two samples carried it."""
    from harness import runner
    from harness.config import load_config
    calls = []
    real = runner._trim_heap
    monkeypatch.setattr(runner, "_trim_heap", lambda: (calls.append(1), real())[1])
    cfg = load_config({"name": "t", "repeats": 4, "time_budget": 0, "meshes": ["knight"],
                       "noise": [{"model": "gaussian_normal", "levels": [0.2]}],
                       "tasks": {"laplacian": {"methods": ["scratch.cotan"]}}})
    row, _ = runner.run_case(cfg.cases[0])
    assert row["status"] == "ok" and row["repeats"] == 4
    assert len(calls) == 4


def test_the_harness_checks_are_not_timed_as_the_method(monkeypatch):
    """A sample times the adapter alone: the mesh checks before it and the result's validation
    after it (here made to take 30 ms each) are outside every timed call, the cold one included;
    the validation still runs on every call's result."""
    import methods.base
    from harness import runner, tasks
    from harness.config import load_config
    task = tasks.get("laplacian")
    slow_checks, validated = [], []
    real_check, real_validate = methods.base.check_arrays, task.validate_result

    def check(V, F):
        time.sleep(0.03)
        slow_checks.append(1)
        return real_check(V, F)

    def validate(name, result, V, F):
        time.sleep(0.03)
        validated.append(1)
        return real_validate(name, result, V, F)
    monkeypatch.setattr(methods.base, "check_arrays", check)
    monkeypatch.setattr(type(task), "validate_result", lambda self, *a: validate(*a))
    cfg = load_config({"name": "t", "repeats": 3, "time_budget": 0, "meshes": ["knight"],
                       "noise": [{"model": "gaussian_normal", "levels": [0.2]}],
                       "tasks": {"laplacian": {"methods": ["scratch.uniform"]}}})
    row, _ = runner.run_case(cfg.cases[0])
    assert row["status"] == "ok" and row["repeats"] == 3
    assert len(slow_checks) == 4 and len(validated) == 4               # the cold call and 3 samples
    assert max(json.loads(row["times"]) + [row["time_cold_s"]]) < 0.03, row["times"]


def test_a_methods_precheck_runs_before_every_call_untimed(monkeypatch):
    """An adapter's ``precheck`` (libigl's zero-area screen) runs with the harness's checks
    before the cold call and every sample, outside the timed call (here made to take 30 ms)."""
    import dataclasses

    import methods
    from harness import runner
    from harness.config import load_config
    from methods import registry
    real = methods.get("libigl.cotan")
    seen = []

    def slow(V, F, name):
        time.sleep(0.03)
        seen.append(name)
        return real.precheck(V, F, name)
    monkeypatch.setitem(registry._REGISTRY, "libigl.cotan", dataclasses.replace(real, precheck=slow))
    cfg = load_config({"name": "t", "repeats": 3, "time_budget": 0, "meshes": ["knight"],
                       "tasks": {"laplacian": {"methods": ["libigl.cotan"]}}})
    row, _ = runner.run_case(cfg.cases[0])
    assert row["status"] == "ok" and seen == ["libigl.cotan"] * 4
    assert max(json.loads(row["times"]) + [row["time_cold_s"]]) < 0.03, row["times"]


def test_a_case_process_inherits_the_drivers_objects_frozen(monkeypatch):
    """A case process moves the objects it inherits to the permanent generation before anything
    else (its garbage collector never walks them, so it never copies the driver's heap pages:
    an import in a case cost 75 ms more in the runs where a collection fell into it); the
    driver's own collector is untouched (nothing frozen there)."""
    import gc
    from harness.config import load_config
    from harness.executors import isolation
    keep = [[] for _ in range(2000)]                          # noqa: F841 - tracked objects of the driver
    assert gc.get_freeze_count() == 0
    monkeypatch.setattr(isolation, "run_case", lambda case, **kw: ({"frozen": gc.get_freeze_count()}, {}))
    case = load_config({"name": "t", "meshes": ["knight"], "tasks": {"laplacian": {"methods": ["scratch.uniform"]}}}).cases[0]
    row, _ = isolation.run_isolated(case)
    assert row["frozen"] >= 2000, row
    assert gc.get_freeze_count() == 0


@pytest.mark.parametrize("cgroup, files, want", [
    ("0::/\n", {"cpu.max": "100000 100000\n"}, 1.0),                                   # v2, private namespace
    ("0::/system.slice/docker-abc.scope\n", {"cpu.max": "150000 100000\n"}, 1.5),       # v2, host namespace
    ("4:cpu,cpuacct:/docker/abc\n", {"cpu,cpuacct/cpu.cfs_quota_us": "100000\n",        # v1 docker
                                     "cpu,cpuacct/cpu.cfs_period_us": "100000\n"}, 1.0),
    ("0::/lim.slice/run-x.scope\n", {"lim.slice/cpu.max": "200000 100000\n",            # quota on a parent slice
                                      "lim.slice/run-x.scope/cpu.max": "max 100000\n"}, 2.0),
    ("0::/a\n", {"a/cpu.max": "max 100000\n"}, None),                                   # unlimited
    ("0::/\n", {"cpu.max": "100000 0\n"}, None),                                        # odd contents: no limit
    ("0::/\n", {"cpu.max": "-100000 100000\n"}, None),                                  # known, never a crash
    ("4:cpu:/d\n", {"cpu/d/cpu.cfs_quota_us": "100000\n", "cpu/d/cpu.cfs_period_us": "-5\n"}, None),
    (b"0::/caf\xe9\n", {"cpu.max": "50000 100000\n"}, 0.5),                              # a non-UTF-8 name
])
def test_the_cgroup_cpu_quota_is_found_in_common_container_layouts(tmp_path, cgroup, files, want):
    """An outside review: only a v2 cgroup with a private namespace was read; a v1 Docker layout,
    a v2 host namespace and a quota on a parent slice fell back to the host's CPUs."""
    from harness.provenance import _cgroup_quota
    root = tmp_path / "cgroup"
    for rel, text in files.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)
    (tmp_path / "self").write_bytes(cgroup if isinstance(cgroup, bytes) else cgroup.encode())
    assert _cgroup_quota(root, tmp_path / "self") == want


def test_threads_busy_counts_the_threads_that_ran_in_the_window():
    """``threads_busy`` (`harness.runner.threads_busy`) tells a single-threaded case from one whose
    second thread ran, even when the samples used one core (a pool spinning for a core): the
    compare rules for an oversubscribed machine use it instead of the run's thread cap."""
    import threading

    from harness.runner import _thread_ticks, threads_busy

    def spin(s):
        end = time.perf_counter() + s
        while time.perf_counter() < end:
            pass
    def only(ticks, *ids):         # the test's own threads: another thread of the process (a library's
        return {t: v for t, v in ticks.items() if t in ids}       # pool, the test runner's) may run too
    me = threading.get_native_id()
    t0, w0 = _thread_ticks(), time.perf_counter()
    spin(0.4)
    assert threads_busy(only(t0, me), only(_thread_ticks(), me), time.perf_counter() - w0) == 1
    t0, w0 = _thread_ticks(), time.perf_counter()
    th = threading.Thread(target=spin, args=(0.6,))
    th.start()
    spin(0.4)
    busy = threads_busy(t0, only(_thread_ticks(), me, th.native_id), time.perf_counter() - w0)  # an ended thread
    th.join()                                                                                # is not listed
    assert busy == 2
    assert threads_busy(t0, _thread_ticks(), 0.04) is None                  # too short for 10 ms ticks


def test_the_load_window_is_the_samples_and_their_loop_is_bounded_in_wall_time(tmp_path):
    """A timing review: others_cpu and threads_busy were measured from before the cold call, so a
    long first call (a numba compile: 9.8 s) diluted the load during the samples and lent them
    its own (compare called unchanged code a 2x regression, and excused a real one). The window
    is now the samples' alone: with a 1.5 s cold call and 0.02 s of samples it is too short for
    others_cpu (blank under 0.2 s). And the samples beyond `repeats` stop once their loop took 10x
    the time budget: a call of microseconds with milliseconds of untimed work around it ran
    1000 samples."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text("name: w\nplugins: [tests.plugins.slowdown]\nmeshes: [armadillo]\nnoise: [{model: none}]\n"
                   "tasks:\n  smoothing:\n    methods: [{name: slowdown.cold, params: {cold_ms: 1500.0, ms: 20.0}},\n"
                   "              slowdown.identity]\ntime_budget: 0.02\n")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    r = subprocess.run([sys.executable, "-m", "harness.cli", "run", str(cfg), "--out", str(tmp_path / "o"),
                        "--quiet", "--workers", "1"], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    df = pd.read_csv(tmp_path / "o" / "smoothing.csv").set_index("method")
    cold = df.loc["slowdown.cold"]
    assert cold["time_cold_s"] >= 1.5 and cold["repeats"] >= 1 and pd.isna(cold["others_cpu"]), cold
    ident = df.loc["slowdown.identity"]
    assert ident["time_s"] < 1e-3 and 1 <= ident["repeats"] < 1000, ident


def test_a_result_the_harness_would_have_to_compute_or_assemble_is_refused():
    """A timing review: the tasks converted what a method returned in their untimed checks, so an
    object whose ``__array__`` runs the computation (geodesics: igl.exact_geodesic) timed 7e-6 s
    against 0.1 s, and a Laplacian returned as COO triplets had its assembly (17 ms at 86k faces)
    done untimed. A result must be a numpy array, a matrix CSR, CSC or DIA; nothing else is touched."""
    import scipy.sparse as sp

    from harness.errors import MethodFailed
    from harness.tasks import get
    from harness.tasks.geodesics import GeodesicResult
    from harness.tasks.laplacian import LaplacianResult
    from harness.tasks.spectrum import SpectrumResult
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    F = np.array([[0, 1, 2]])
    touched = []

    class Lazy:
        def __array__(self, dtype=None, copy=None):
            touched.append(1)
            return np.zeros((1, 3))
    with pytest.raises(MethodFailed, match="returned D as Lazy, expected a float64 numpy array"):
        get("geodesics").validate_result("m", GeodesicResult(D=Lazy()), V, F)
    with pytest.raises(MethodFailed, match="returned vectors as Lazy"):
        get("spectrum").validate_result("m", SpectrumResult(values=np.zeros(1), vectors=Lazy()), V, F)
    assert touched == []
    W = sp.coo_matrix(np.array([[-2.0, 1, 1], [1, -2, 1], [1, 1, -2]]))
    for bad in (W, W.toarray(), W.tolil()):
        with pytest.raises(MethodFailed, match="expected a scipy sparse CSR or CSC matrix"):
            get("laplacian").validate_result("m", LaplacianResult(W=bad), V, F)
        with pytest.raises(MethodFailed, match="expected a scipy sparse CSR or CSC matrix"):
            get("spectrum").validate_result("m", SpectrumResult(values=np.zeros(1), W=bad), V, F)
    for good in (W.tocsr(), W.tocsc(), W.todia()):
        out = get("laplacian").validate_result("m", LaplacianResult(W=good, M=sp.diags([1.0, 1, 1]).tocsr()), V, F)
        assert out.W.format == "csr"
