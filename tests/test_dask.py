"""The Dask executor (issue 7) against a real `distributed.LocalCluster` with worker processes.

- a Dask run gives the same metrics as a local run of the same config (every metric column
  equal; timing and memory columns excluded), including a `{file: ...}` mesh the driver ships;
- crash isolation and timeouts hold on the workers (SIGABRT row, timeout row, worker lives on);
- a worker process that dies is one error row (no Dask retry, no double count) and takes its
  case process with it;
- daemonic workers (Dask's default) fall back to a subprocess per case with the same outcome;
- an unreachable scheduler is exit 2 with a message and nothing written.
"""
import json
import logging
import os
import socket
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pandas as pd
import psutil
import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:          # plugins import in the driver, the workers and their children
    sys.path.insert(0, str(ROOT))

dask = pytest.importorskip("dask")
distributed = pytest.importorskip("distributed")

import harness  # noqa: E402
from harness.config import load_config  # noqa: E402
from harness.executors.dask import _prune, DaskExecutor, materialize, run_in_subprocess, ship_files  # noqa: E402
from harness import tasks  # noqa: E402
from harness.errors import RunInterrupted  # noqa: E402

SHOOTOUT = Path(sys.executable).with_name("shootout")
NOT_COMPARED = {"time_s", "time_min_s", "time_max_s", "time_q1_s", "time_q3_s", "time_cold_s", "times", "repeats",
                "time_cpu_s", "cpu_times", "others_cpu", "threads_busy", "method_mem_mb", "peak_rss_mb"}
# min_eig (smallest eigenvalue of -(W+W^T)/2 over the largest) comes from ARPACK with a random
# start vector: it differs between two *local* runs too, by ~1e-17 (values ~1e-17 on PSD
# operators). Compared with an absolute tolerance of 1e-12 on that relative number.
NOISY = {"min_eig": 1e-12}


@pytest.fixture(scope="module")
def cluster():
    # non-daemonic workers may fork a child per case; allowed-failures 0: a dead worker fails
    # its task at once (KilledWorker) instead of re-running it elsewhere
    with dask.config.set({"distributed.worker.daemon": False, "distributed.scheduler.allowed-failures": 0}):
        cl = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                      dashboard_address=None, silence_logs=logging.ERROR)
        try:
            yield cl
        finally:
            cl.close()


def quad_obj(path: Path):
    """A 4x4-vertex grid of quads (fan-triangulated on reading), slightly bent."""
    n = 4
    lines = [f"v {i / 3:.6f} {j / 3:.6f} {0.1 * np.sin(i + j):.6f}" for i in range(n) for j in range(n)]
    for i in range(n - 1):
        for j in range(n - 1):
            a = i * n + j + 1
            lines.append(f"f {a} {a + n} {a + n + 1} {a + 1}")
    path.write_text("\n".join(lines) + "\n")


def config(tmp_path):
    (tmp_path / "shipped").mkdir()
    quad_obj(tmp_path / "shipped" / "grid.obj")
    return {"name": "dask-vs-local", "plugins": ["tests.plugins.crashy"], "timeout": 30,
            "meshes": ["knight", {"procedural": "sphere", "subdivisions": 2},
                       {"file": str(tmp_path / "shipped" / "grid.obj")}],
            "noise": [{"model": "gaussian_normal", "levels": [0.2]}],
            "tasks": {"laplacian": {"methods": ["libigl.cotan", "crashy.abort"]},
                      "smoothing": {"methods": [{"name": "scratch.explicit", "params": {"iterations": 5}},
                                                "scratch.implicit"]},
                      "simplification": {"methods": ["fast_simplification.qem"], "params": {"target_ratio": 0.5}}}}


def test_dask_run_equals_local_run(cluster, tmp_path):
    cfg = load_config(config(tmp_path))
    local = harness.run(cfg, out=tmp_path / "local", workers=2)
    remote = harness.run(cfg, out=tmp_path / "dask", executor="dask", scheduler=cluster.scheduler_address)
    assert set(local) == set(remote)
    compared = 0
    for task, a in local.items():
        b = remote[task]
        a, b = a.set_index("case_id").sort_index(), b.set_index("case_id").sort_index()
        assert list(a.index) == list(b.index) and a.index.is_unique
        cols = [c for c in a.columns if c not in NOT_COMPARED and c not in NOISY]
        # exact equality (same code, same input bytes, deterministic methods); NaN == NaN
        pd.testing.assert_frame_equal(a[cols], b[cols], check_exact=True)
        for c, atol in NOISY.items():
            if c in a:
                np.testing.assert_allclose(a[c], b[c], rtol=0, atol=atol, equal_nan=True)
        compared += int(a["status"].eq("ok").sum()) * len(tasks.get(task).columns)
        assert b["peak_rss_mb"][b["status"] == "ok"].gt(0).all()
    assert compared > 100
    lap = remote["laplacian"]
    assert (lap[lap.method == "crashy.abort"]["error"].str.contains("SIGABRT")).all()
    others = pd.concat([df[~df.method.str.startswith("crashy.")] for df in remote.values()])
    assert (others["status"] == "ok").all(), others[["mesh", "method", "error"]]
    assert set(others["mesh"]) == {"knight", "sphere(subdivisions=2)", "grid"}
    meta = harness.results.RunFolder(tmp_path / "dask").read_run_json()
    assert meta["executor"] == "dask" and meta["workers"] == 2
    # the solver backends the workers' cases factored with come back with their rows, as a local run's
    used = meta["solver"]["used"]
    assert used and used == harness.results.RunFolder(tmp_path / "local").read_run_json()["solver"]["used"]
    assert all(v["methods"] == ["scratch.implicit"] and v["cases"] == 3 for v in used.values()), used


def test_a_scheduler_that_went_is_told_from_a_task_cancelled_for_itself():
    """An outside review: a scheduler restarted on its address (or by another client's
    ``restart()``) cancels the tasks out with a reason of its own, while the client reconnects,
    so the run counted them as failed cases and ended 'finished'. Those reasons now interrupt
    the run (checked by hand with a real scheduler killed and restarted, and with a second
    client's restart(): exit 1, resumable)."""
    from distributed.client import FutureCancelledError

    from harness.executors.dask import scheduler_went
    assert scheduler_went(FutureCancelledError("k", "scheduler-connection-lost"))
    assert scheduler_went(FutureCancelledError("k", "scheduler-restart", "Scheduler has restarted"))
    assert not scheduler_went(FutureCancelledError("k", "lost dependencies"))
    assert not scheduler_went(FutureCancelledError("k", None)) and not scheduler_went(RuntimeError("scheduler-restart"))


def _told_then_not(cluster, pretend, value):
    """The rows of a one-case run while the workers run ``pretend(value)``, then after ``pretend(None)``."""
    cfg = load_config({"name": "t", "time_budget": 0, "meshes": ["knight"],
                       "tasks": {"smoothing": {"methods": ["scratch.taubin"]}}})
    ex = DaskExecutor(timeout=60, scheduler=cluster.scheduler_address)
    try:
        ex.client.run(pretend, value)
        rows = [row for _, row, _ in ex.run(cfg.cases)]
        ex.client.run(pretend, None)
        return rows, [row for _, row, _ in ex.run(cfg.cases)]
    finally:
        ex.close()


def _pretend_other_code(code):
    import harness.executors.dask as d
    d._CODE.clear()
    if code:
        d._CODE[()] = code


def test_a_worker_running_other_code_costs_its_rows_not_a_mixed_folder(cluster):
    """An outside review: a worker started on another checkout (an older commit, or edited code)
    made rows that the run recorded under the driver's commit and code_sha256 (10 regressions
    against a local run, nothing said). A row from a worker whose sources hash otherwise is an
    error row naming both hashes. (The workers here are told another hash: the same thing to the
    driver as another checkout.)"""
    rows, again = _told_then_not(cluster, _pretend_other_code, "0123456789abcdef")
    assert [r["status"] for r in rows] == ["error"] and "ran other code than the driver" in rows[0]["error"]
    assert "0123456789abcdef" in rows[0]["error"] and "_worker_code" not in rows[0]
    assert [r["status"] for r in again] == ["ok"] and "_worker_code" not in again[0]


def _pretend_other_numpy(version):
    import harness.executors.dask as d
    d._CODE.pop("versions", None)
    if version:
        d._CODE["versions"] = {**d._versions(), "numpy": version}


def test_a_worker_with_other_package_versions_costs_its_rows(cluster):
    """Only the sources were compared: a worker with another numpy (or libigl, ...) made rows the
    run recorded as the driver's environment's. A row from a worker whose package versions differ
    is an error row naming each difference."""
    rows, again = _told_then_not(cluster, _pretend_other_numpy, "1.0.0")
    assert [r["status"] for r in rows] == ["error"] and "other package versions" in rows[0]["error"]
    assert "numpy 1.0.0, the driver's" in rows[0]["error"] and "_worker_code" not in rows[0]
    assert [r["status"] for r in again] == ["ok"]


def test_timeout_and_crash_on_workers_through_the_cli(cluster, tmp_path):
    """`shootout run --executor dask --scheduler ADDR --timeout 3`: the sleeping case is killed on
    its worker (timeout row), the segfault is an error row naming SIGSEGV, the rest is ok."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text("plugins: [tests.plugins.crashy]\nmeshes: [knight]\n"
                   "tasks: {laplacian: {methods: [crashy.sleep, crashy.segfault, crashy.missing, scratch.uniform]}}\n")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    r = subprocess.run([str(SHOOTOUT), "run", str(cfg), "--out", str(tmp_path / "out"), "--quiet",
                        "--executor", "dask", "--scheduler", cluster.scheduler_address, "--timeout", "3"],
                       capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    st = pd.read_csv(tmp_path / "out" / "laplacian.csv").set_index("method")
    assert st.loc["crashy.sleep", "status"] == "timeout"
    assert st.loc["crashy.segfault", "status"] == "error" and "SIGSEGV" in st.loc["crashy.segfault", "error"]
    assert st.loc["scratch.uniform", "status"] == "ok"
    missing = st.loc["crashy.missing"]            # which machine lacks the library
    assert missing["status"] == "unavailable" and "no_such_module_xyz" in missing["error"]
    assert "(on the worker at tcp://" in missing["error"] and socket.gethostname() in missing["error"]


def test_shipped_file_needs_no_shared_filesystem(tmp_path):
    """A worker reads a shipped file from its own cache: the driver's path may be gone."""
    cfg = load_config(config(tmp_path))
    case = next(c for c in cfg.cases if c.mesh_key == "grid" and c.method == "libigl.cotan")
    (sent,), blobs = ship_files([case])          # the driver's step (DaskExecutor.run scatters blobs)
    assert sent.case_id == case.case_id and "file_sha1" in sent.mesh
    shutil.rmtree(tmp_path / "shipped")         # the driver's copy is gone
    local = materialize(sent, blobs)
    assert Path(local.mesh["file"]).name == "grid.obj" and Path(local.mesh["file"]).is_file()
    row, _ = run_in_subprocess(local, timeout=60)
    assert row["status"] == "ok", row["error"]
    assert "fan-triangulated 9 polygon" in row["error"]        # the same repair note as a local run


def test_the_worker_cache_is_private_and_checked_by_content(tmp_path):
    """Before: a cached file of the right size was trusted, so bytes planted or changed in the
    shared /tmp cache were measured under the case's id (25 cells differed from a local run)."""
    cfg = load_config(config(tmp_path))
    case = next(c for c in cfg.cases if c.mesh_key == "grid")
    (sent,), blobs = ship_files([case])
    target = Path(materialize(sent, blobs).mesh["file"])
    good = target.read_bytes()
    target.write_bytes(good.replace(b"v 0", b"v 7"))              # same size, other mesh
    assert len(target.read_bytes()) == len(good) and target.read_bytes() != good
    assert Path(materialize(sent, blobs).mesh["file"]).read_bytes() == good
    assert (target.parents[1].stat().st_mode & 0o077) == 0 and str(os.getuid()) in target.parents[1].name
    stale, fresh = target.parents[1] / ("0" * 40), target.parents[1] / ("1" * 40)   # unused for 8 days / 1 day
    for d, days in ((stale, 8), (fresh, 1)):
        d.mkdir(exist_ok=True)
        (d / "x.obj").write_text("v 0 0 0\n")
        os.utime(d, (time.time() - days * 86400,) * 2)
    target.unlink()                                              # a new entry is written: the cache is pruned
    os.utime(target.parent, (time.time() - 30 * 86400,) * 2)      # old, but this case uses it: kept
    assert Path(materialize(sent, blobs).mesh["file"]).read_bytes() == good
    assert not stale.exists() and fresh.exists() and target.is_file()
    os.utime(target.parent, (time.time() - 30 * 86400,) * 2)      # reused as it is (no write): the use
    materialize(sent, blobs)                                     # marks it, so another case's prune keeps it
    _prune(target.parents[1], keep="another")
    assert target.is_file()


def test_daemonic_worker_fallback_isolates_too(tmp_path):
    """`run_in_subprocess` (used on daemonic workers): crash, timeout and ok rows as locally."""
    cfg = load_config({"plugins": ["tests.plugins.crashy"], "meshes": ["knight"],
                       "tasks": {"laplacian": {"methods": ["crashy.segfault", "crashy.sleep", "crashy.kill9",
                                                           "crashy.exit"]}}})
    rows = {c.method: run_in_subprocess(c, timeout=4)[0] for c in cfg.cases}
    assert rows["crashy.segfault"]["status"] == "error" and "SIGSEGV" in rows["crashy.segfault"]["error"]
    assert "died: SIGKILL" in rows["crashy.kill9"]["error"], rows["crashy.kill9"]      # as the OOM killer's
    assert "exited with code 3" in rows["crashy.exit"]["error"], rows["crashy.exit"]
    assert rows["crashy.sleep"]["status"] == "timeout"      # (an ok row: the shipped-file test)
    # its own session: os.killpg(0, SIGTERM) in the case reaches the case, not the worker (it killed
    # a daemonic worker and its nanny)
    cfg = load_config({"plugins": ["tests.plugins.hostile"], "meshes": ["knight"],
                       "tasks": {"smoothing": {"methods": ["hostile.killpg"]}}})
    row = run_in_subprocess(cfg.cases[0], timeout=30)[0]
    assert row["status"] == "error" and "SIGTERM" in row["error"]
    sleeper = next(c for c in load_config({"plugins": ["tests.plugins.crashy"], "meshes": ["knight"],
                                           "tasks": {"laplacian": {"methods": ["crashy.sleep"]}}}).cases)
    t0 = time.monotonic()                          # a cancelled task's case is killed, not left to its timeout
    row = run_in_subprocess(sleeper, timeout=60, stop=lambda: time.monotonic() > t0 + 1)[0]
    assert "cancelled" in row["error"] and time.monotonic() - t0 < 10, row


def test_a_case_on_a_daemonic_worker_reads_no_input_as_a_local_case(tmp_path):
    """A review: a case there inherited the pipe its case came on as stdin, open till it ended,
    so a method reading its input hung the run (no --timeout) where a local case reads nothing."""
    cfg = load_config({"plugins": ["tests.plugins.hostile"], "meshes": ["knight"], "repeats": 1, "time_budget": 0,
                       "tasks": {"smoothing": {"methods": ["hostile.reads_stdin"]}}})
    t0 = time.monotonic()
    row = run_in_subprocess(cfg.cases[0], timeout=30)[0]
    assert row["status"] == "ok" and time.monotonic() - t0 < 25, row


def test_a_daemonic_workers_timeout_counts_the_case_not_the_interpreter_start(monkeypatch):
    """The fresh interpreter's start-up and imports (about 0.7 s here, and 1.5 s more for the
    plugin below, which a forking worker imports before it forks) counted against --timeout, which
    a forking worker's case never pays: a case of about 0.85 s timed out at 1.5 s."""
    cfg = load_config({"plugins": ["tests.plugins.crashy", "tests.plugins.slow_import"], "meshes": ["knight"],
                       "repeats": 1, "time_budget": 0,
                       "tasks": {"laplacian": {"methods": [{"name": "crashy.slow", "params": {"seconds": 0.4}}]}}})
    monkeypatch.setenv("SHOOTOUT_TEST_IMPORT_S", "1.5")        # for the case's fresh interpreter only
    t0 = time.monotonic()
    row = run_in_subprocess(cfg.cases[0], timeout=1.5)[0]
    assert row["status"] == "ok", row["error"]
    assert time.monotonic() - t0 > 2.3                 # the start-up did happen, and was not counted


def test_a_plugin_that_ends_a_forking_workers_process_on_import_costs_its_rows(cluster):
    """The worker's warm-up imported the plugin in the worker process itself: os._exit(0) there
    ended the worker (a clean exit, so the nanny gave up and the cluster kept no workers)."""
    cfg = load_config({"name": "t", "time_budget": 0, "meshes": ["knight"], "plugins": ["tests.plugins.dask_exiter"],
                       "tasks": {"smoothing": {"methods": ["dask_exiter.identity", "scratch.taubin"]}}})
    ex = DaskExecutor(timeout=60, scheduler=cluster.scheduler_address)
    try:
        ex.client.run(lambda: os.environ.update(SHOOTOUT_TEST_EXIT_ON_IMPORT="1"))   # the worker's own environ
        before = sorted(ex.client.run(os.getpid).values())
        rows = {row["method"]: row for _, row, _ in ex.run(cfg.cases)}
        after = sorted(ex.client.run(os.getpid).values())
    finally:
        ex.client.run(lambda: os.environ.pop("SHOOTOUT_TEST_EXIT_ON_IMPORT", None))
        ex.close()
    for row in rows.values():
        assert row["status"] == "error", row
        assert ("plugin 'tests.plugins.dask_exiter' cannot be imported in the case's process on "
                in row["error"] and "(importing it ended the process (exit status 0))" in row["error"]), row
    assert after == before                         # the same two workers, alive


def _run_killing_a_busy_worker(ex, cases, before_kill):
    """The rows of ``ex.run(cases)`` while another thread SIGKILLs the first worker process that
    has a task, after ``before_kill(pid)``."""
    def kill():
        t0 = time.time()
        while time.time() - t0 < 60:
            busy = [w for w, keys in ex.client.processing().items() if keys]
            if busy:
                pid = ex.client.run(os.getpid, workers=busy)[busy[0]]
                before_kill(pid)
                os.kill(pid, signal.SIGKILL)
                return
            time.sleep(0.05)
    killer = threading.Thread(target=kill)
    killer.start()
    try:
        return [row for _, row, _ in ex.run(cases)]
    finally:
        killer.join()


def test_worker_death_is_one_error_row(cluster):
    """Kill the worker process running a case: one error row naming it, no retry, no second row;
    the case's own process goes with the worker; the cluster recovers (nanny restart)."""
    cfg = load_config({"plugins": ["tests.plugins.crashy"], "meshes": ["knight"],
                       "tasks": {"laplacian": {"methods": ["crashy.sleep"]}}})
    ex = DaskExecutor(timeout=120, scheduler=cluster.scheduler_address)
    victims = {}

    def wait_for_its_case(pid):
        proc = psutil.Process(pid)
        t1 = time.time()
        while not proc.children(recursive=True) and time.time() - t1 < 30:
            time.sleep(0.05)
        victims["kids"] = [k.pid for k in proc.children(recursive=True)]

    try:
        rows = _run_killing_a_busy_worker(ex, cfg.cases, before_kill=wait_for_its_case)
    finally:
        ex.close()
    assert len(rows) == 1
    assert rows[0]["status"] == "error" and "worker" in rows[0]["error"] and "died" in rows[0]["error"]
    assert victims["kids"]
    t0 = time.time()
    while time.time() - t0 < 10 and any(psutil.pid_exists(p) and psutil.Process(p).status() != "zombie"
                                        for p in victims["kids"]):
        time.sleep(0.1)
    alive = [p for p in victims["kids"] if psutil.pid_exists(p) and psutil.Process(p).status() != "zombie"]
    for p in alive:
        os.kill(p, signal.SIGKILL)
    assert not alive, "the case process outlived its worker"


def test_an_interrupted_driver_leaves_no_case_running_on_the_workers(cluster):
    """Ctrl-C (or any exit) closes the executor, which cancels its futures; Dask lets a running
    task's thread go on, so its case process ran to the end (or its timeout) on the worker. The
    task now polls for the cancellation and kills its case."""
    cfg = load_config({"plugins": ["tests.plugins.crashy"], "meshes": ["knight"],
                       "tasks": {"laplacian": {"methods": ["crashy.sleep"]}}})
    ex = DaskExecutor(timeout=120, scheduler=cluster.scheduler_address)
    def drive():
        try:
            for _ in ex.run(cfg.cases):
                pass
        except RunInterrupted:                   # the executor closed under it: how the driver stops
            pass
    threading.Thread(target=drive, daemon=True).start()
    workers = [psutil.Process(p) for p in ex.client.run(os.getpid).values()]
    kids: list = []
    t0 = time.time()
    while not kids and time.time() - t0 < 60:
        kids = [k for w in workers for k in w.children(recursive=True)]
        time.sleep(0.05)
    assert kids, "the case never started"
    ex.close()
    gone, alive = psutil.wait_procs(kids, timeout=10)
    for k in alive:
        k.kill()
    assert not alive, "the case ran on after its driver gave up on it"


@pytest.fixture
def one_worker():
    """One worker, with Dask's default retries of a task whose worker died (the module's
    `cluster` sets 0)."""
    with dask.config.set({"distributed.worker.daemon": False, "distributed.scheduler.allowed-failures": 3}):
        cl = distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0",
                                      silence_logs=logging.CRITICAL)
    try:
        yield cl
    finally:
        cl.close()


def test_a_restarted_worker_costs_no_shipped_file_case_but_its_own(one_worker, tmp_path):
    """Before: when the worker holding a `{file:}` mesh's scattered bytes was restarted, every
    case still waiting for them became an error row ('cancelled ... already forgotten'), an
    innocent method ranked last; now they are shipped and submitted again."""
    (tmp_path / "shipped").mkdir()
    quad_obj(tmp_path / "shipped" / "grid.obj")
    cfg = load_config({"plugins": ["tests.plugins.slowdown"], "time_budget": 0,
                       "meshes": [{"file": str(tmp_path / "shipped" / "grid.obj")}],
                       "noise": [{"model": "gaussian_normal", "levels": [0.1], "seeds": 4}],
                       "tasks": {"smoothing": {"methods": [{"name": "slowdown.sleep", "params": {"ms": 1500.0}}]}}})
    ex = DaskExecutor(timeout=120, scheduler=one_worker.scheduler_address)
    try:
        rows = _run_killing_a_busy_worker(ex, cfg.cases, before_kill=lambda pid: time.sleep(0.5))
    finally:
        ex.close()
    assert len(rows) == 4 and len({r["case_id"] for r in rows}) == 4
    assert [r["error"] for r in rows if r["status"] != "ok"] == []


def test_a_case_that_kills_its_worker_costs_its_own_row_only(one_worker, tmp_path):
    """Two cases that kill their worker each time they run, beside shipped-file cases waiting on
    one worker: each kill lost the file's bytes and cancelled every waiting case, and after three
    such kills all of them were error rows saying 'FutureCancelledError ... already forgotten'.
    Now a case cancelled while it ran is retried once and then named as killing its worker; the
    waiting cases run."""
    (tmp_path / "shipped").mkdir()
    quad_obj(tmp_path / "shipped" / "grid.obj")
    cfg = load_config({"plugins": ["tests.plugins.worker_killer", "tests.plugins.slowdown"], "time_budget": 0,
                       "meshes": [{"file": str(tmp_path / "shipped" / "grid.obj")}],
                       "noise": [{"model": "gaussian_normal", "levels": [0.1], "seeds": 2}],
                       "tasks": {"smoothing": {"methods": ["worker_killer.parent", "slowdown.sleep"]}}})
    ex = DaskExecutor(timeout=120, scheduler=one_worker.scheduler_address)
    try:
        rows = [row for _, row, _ in ex.run(cfg.cases)]
    finally:
        ex.close()
    by = {}
    for r in rows:
        by.setdefault(r["method"], []).append(r)
    assert len(rows) == 4 and len({r["case_id"] for r in rows}) == 4
    assert [r["status"] for r in by["slowdown.sleep"]] == ["ok", "ok"], [r["error"] for r in by["slowdown.sleep"]]
    for r in by["worker_killer.parent"]:
        assert r["status"] == "error" and "worker running this case died each of the 2 times" in r["error"], r


def test_a_case_queued_behind_a_worker_killer_is_not_blamed_for_its_death(tmp_path):
    """An outside review: with a bundled mesh (no shipped file), a case that only waited behind
    one that kills its worker got Dask's KilledWorker too (Dask counts a death against every task
    assigned to the worker) and became an error row: 1 run in 2 here before (a daemonic worker,
    cases in subprocesses), so two runs of the same code compared as a regression. A KilledWorker
    task that never started runs again; the killer is still named."""
    with dask.config.set({"distributed.worker.daemon": True, "distributed.scheduler.allowed-failures": 3}):
        cl = distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0",
                                      silence_logs=logging.CRITICAL)
    cfg = load_config({"plugins": ["tests.plugins.worker_killer", "tests.plugins.slowdown"], "time_budget": 0,
                       "meshes": ["knight"], "noise": [{"model": "gaussian_normal", "levels": [0.1]}],
                       "tasks": {"smoothing": {"methods": ["worker_killer.parent", "slowdown.sleep", "scratch.taubin"]}}})
    try:
        ex = DaskExecutor(timeout=120, scheduler=cl.scheduler_address)
        try:
            rows = {row["method"]: row for _, row, _ in ex.run(cfg.cases)}
        finally:
            ex.close()
    finally:
        cl.close()
    assert rows["slowdown.sleep"]["status"] == rows["scratch.taubin"]["status"] == "ok", rows
    killer = rows["worker_killer.parent"]
    assert killer["status"] == "error" and "worker running this case died" in killer["error"], killer


def test_a_result_that_never_reaches_the_driver_costs_its_row_not_the_run(tmp_path, monkeypatch):
    """A fresh-clone suite under heavy load hung in ``fut.result()`` after the killer test's cases
    were done: a finished case whose result must come from a worker waits without end where that
    worker died and its task is not computed again. The fetch now waits at most
    ``$MESH_SHOOTOUT_DASK_WAIT`` s; the case is sent again up to three times, then it is an error
    row. (A wait of 0 s times out every fetch: each result is on a worker of its own process.)"""
    monkeypatch.setenv("MESH_SHOOTOUT_DASK_WAIT", "0")
    with dask.config.set({"distributed.worker.daemon": False}):
        cl = distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0",
                                      silence_logs=logging.CRITICAL)
    cfg = load_config({"time_budget": 0, "meshes": ["knight"], "noise": [{"model": "none"}],
                       "tasks": {"smoothing": {"methods": ["scratch.taubin"]}}})
    try:
        ex = DaskExecutor(timeout=60, scheduler=cl.scheduler_address)
        try:
            rows = [row for _, row, _ in ex.run(cfg.cases)]
        finally:
            ex.close()
    finally:
        cl.close()
    assert len(rows) == 1 and rows[0]["status"] == "error", rows
    assert "its result did not reach the driver within 0 s, 4 times" in rows[0]["error"], rows[0]["error"]


def _log_as(*events):
    from harness.executors.dask import _log
    for e in events:
        _log(e)


def test_a_cases_start_is_not_pushed_out_of_the_schedulers_log_by_later_cases():
    """The scheduler keeps the last ``distributed.admin.low-level-log-length`` events of a topic
    (1000 by default): with every task's start in one topic, a long case whose start was
    followed by that many others' counted as one that had not started when its worker died, and
    the worker killer was retried without end. Each task now logs under its own topic."""
    from harness.executors.dask import ENDED, STARTED
    with dask.config.set({"distributed.worker.daemon": False, "distributed.admin.low-level-log-length": 2}):
        cl = distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0",
                                      silence_logs=logging.CRITICAL)
    ex = DaskExecutor(timeout=60, scheduler=cl.scheduler_address)
    try:
        first = ex.client.submit(_log_as, STARTED, key="long-case", pure=False)
        first.result()
        later = [ex.client.submit(_log_as, STARTED, key=f"later-{i}", pure=False) for i in range(5)]
        ex.client.gather(later)
        ex.client.submit(_log_as, STARTED, ENDED, key="ended-case", pure=False).result()
        assert ex._ran_when_lost("long-case")            # started, never ended: it ran when its worker went
        assert not ex._ran_when_lost("never-ran")        # no start logged: it waited
        assert not ex._ran_when_lost("ended-case")       # ended: its result was lost, not its run
    finally:
        ex.close()
        cl.close()


def test_unreachable_scheduler_is_exit_2(tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("meshes: [knight]\ntasks: {laplacian: {methods: [scratch.uniform]}}\n")
    env = dict(os.environ, DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT="1s")
    r = subprocess.run([str(SHOOTOUT), "run", str(cfg), "--out", str(tmp_path / "out"), "--executor", "dask",
                        "--scheduler", "tcp://127.0.0.1:9"], capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 2
    assert "cannot connect to a Dask scheduler" in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "out").exists()


def test_a_server_that_is_not_dask_is_exit_2_within_the_connect_timeout(tmp_path):
    """The dashboard's HTTP port (or any service that accepts and never answers as Dask) used to
    block inside distributed.Client for ever."""
    import socket
    cfg = tmp_path / "c.yaml"
    cfg.write_text("meshes: [knight]\ntasks: {laplacian: {methods: [scratch.uniform]}}\n")
    env = dict(os.environ, DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT="2s")
    with socket.socket() as srv:          # accepts (the kernel's backlog) and never answers
        srv.bind(("127.0.0.1", 0))
        srv.listen(4)
        port = srv.getsockname()[1]
        r = subprocess.run([str(SHOOTOUT), "run", str(cfg), "--out", str(tmp_path / "out"), "--executor", "dask",
                            "--scheduler", f"tcp://127.0.0.1:{port}"], capture_output=True, text=True, env=env,
                           timeout=60)
    assert r.returncode == 2, r.stderr
    assert "gave no Dask answer within 5 s" in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "out").exists()


def _scheduler(tmp_path):
    port_file = tmp_path / "sched.json"
    proc = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                             "--port", "0", "--scheduler-file", str(port_file), "--no-dashboard"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for _ in range(200):
        if port_file.exists() and port_file.stat().st_size:
            break
        time.sleep(0.1)
    return proc, json.loads(port_file.read_text())["address"]


def test_a_scheduler_without_workers_is_said_and_given_up_on(tmp_path):
    proc, addr = _scheduler(tmp_path)
    try:
        cfg = tmp_path / "c.yaml"
        cfg.write_text("meshes: [knight]\ntime_budget: 0\ntasks: {laplacian: {methods: [scratch.uniform]}}\n")
        env = dict(os.environ, MESH_SHOOTOUT_DASK_WAIT="3")
        r = subprocess.run([str(SHOOTOUT), "run", str(cfg), "--out", str(tmp_path / "out"), "--executor", "dask",
                            "--scheduler", addr], capture_output=True, text=True, env=env, timeout=120)
        assert r.returncode == 1, r.stderr
        assert "has no workers; waiting" in r.stderr and "no worker for 3 s" in r.stderr
        assert json.loads((tmp_path / "out" / "run.json").read_text())["status"] == "interrupted"
    finally:
        proc.kill()


def test_a_lost_scheduler_interrupts_the_run_instead_of_failing_its_cases(tmp_path):
    proc, addr = _scheduler(tmp_path)
    worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", addr, "--nthreads", "1",
                               "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                              env=dict(os.environ, PYTHONPATH=str(ROOT), DASK_DISTRIBUTED__WORKER__DAEMON="False"))
    try:
        cfg = tmp_path / "c.yaml"
        cfg.write_text(json.dumps({"meshes": ["knight"], "time_budget": 0, "plugins": ["tests.plugins.slowdown"],
                                   "noise": [{"model": "gaussian_normal", "levels": [0.1], "seeds": 6}],
                                   "tasks": {"smoothing": {"methods": [{"name": "slowdown.sleep",
                                                                        "params": {"ms": 1500.0}}]}}}))
        run = subprocess.Popen([str(SHOOTOUT), "run", str(cfg), "--out", str(tmp_path / "out"), "--executor", "dask",
                                "--scheduler", addr], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env=dict(os.environ, PYTHONPATH=str(ROOT)))
        for _ in range(300):
            if (tmp_path / "out" / "smoothing.csv").exists():
                break
            time.sleep(0.1)
        proc.kill()                                   # the scheduler dies mid-run
        _, err = run.communicate(timeout=120)
        assert run.returncode == 1 and "lost the Dask scheduler" in err and "--resume" in err, err
        assert "Traceback" not in err and len(err.splitlines()) < 15, err   # one message, no library traceback
        meta = json.loads((tmp_path / "out" / "run.json").read_text())
        assert meta["status"] == "interrupted"
        rows = pd.read_csv(tmp_path / "out" / "smoothing.csv")
        assert (rows["status"] == "ok").all() and len(rows) < 6      # no false error rows
    finally:
        proc.kill()
        worker.kill()


def test_a_file_changed_after_the_run_started_is_an_error_row_on_a_worker(tmp_path):
    """The cases carry the sha1 of their files' bytes when the config was read; a file edited
    since is not shipped as if it were the same mesh: the worker's row says it changed."""
    from harness.executors.dask import run_task
    cfg = load_config(config(tmp_path))
    case = next(c for c in cfg.cases if c.mesh_key == "grid" and c.method == "libigl.cotan")
    grid = tmp_path / "shipped" / "grid.obj"
    grid.write_text(grid.read_text().replace("v 0.000000 0.000000", "v 0.000000 0.050000", 1))
    (sent,), blobs = ship_files([case])
    assert blobs == {}
    row, _ = run_task(sent, blobs, timeout=60, want_meshes=False)
    assert row["status"] == "error" and "changed since the run started" in row["error"], row["error"]


def test_a_daemonic_workers_case_leaves_no_process_behind(tmp_path, monkeypatch):
    """A method's grandchild in a session of its own (setsid and a double fork) outlived its case
    on a daemonic worker (each case a fresh subprocess, no subreaper above it): five of them
    outlived a review's run. The subprocess's guard kills it whether the case returns, crashes
    or runs past its timeout."""
    monkeypatch.setenv("HOSTILE_MARK_DIR", str(tmp_path))
    cfg = load_config({"plugins": ["tests.plugins.hostile"], "meshes": ["knight"], "time_budget": 0,
                       "tasks": {"smoothing": {"methods": [{"name": "hostile.escape",
                                                            "params": {"crash": [False, True]}},
                                                           {"name": "hostile.escape", "params": {"hang": True}}]}}})
    rows = [run_in_subprocess(c, timeout=3 if c.params.get("hang") else 60)[0] for c in cfg.cases]
    assert sorted(r["status"] for r in rows) == ["error", "ok", "timeout"], rows
    assert any("SIGSEGV" in (r.get("error") or "") for r in rows), rows
    pids = [int(p.read_text()) for p in tmp_path.glob("escaped-*.pid")]
    assert len(pids) >= 3, pids              # a warm-up call and a timed one for the ok case
    time.sleep(0.3)

    def alive(pid):
        try:
            return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
        except psutil.NoSuchProcess:
            return False
    assert not [p for p in pids if alive(p)], pids


def test_the_executors_own_cluster_restarts_workers_that_fork():
    """Without --scheduler the executor starts a LocalCluster of non-daemonic workers (they fork
    their cases); a worker the nanny restarted was daemonic, so every later case of it took the
    slower subprocess path. The setting holds until the executor closes, and is then restored."""
    from harness.executors.dask import _daemonic
    before = dask.config.get("distributed.worker.daemon", default=True)
    ex = DaskExecutor(workers=1, timeout=60)
    try:
        pid = next(iter(ex.client.run(os.getpid).values()))
        os.kill(pid, signal.SIGKILL)
        t0 = time.time()
        while time.time() - t0 < 60:
            try:
                now = ex.client.run(os.getpid)
            except Exception:  # noqa: BLE001 - no worker yet
                now = {}
            if now and pid not in now.values():
                break
            time.sleep(0.2)
        assert now and pid not in now.values(), "the worker did not come back"
        assert list(ex.client.run(_daemonic).values()) == [False]
        other = DaskExecutor(workers=1, timeout=60)     # a second executor's close keeps the first one's
        other.close()
        assert dask.config.get("distributed.worker.daemon", default=True) is False
    finally:
        ex.close()
    assert dask.config.get("distributed.worker.daemon", default=True) == before


def test_a_forking_workers_crashed_case_leaves_no_process_behind(tmp_path, monkeypatch):
    """The case process is a subreaper that kills what its method left when the case ends; when it
    crashed first, a grandchild in a session of its own went to init and outlived the run on a
    forking worker. The worker is now a subreaper for its cases and kills such orphans; its own
    children (here a sleep started on it) stay."""
    monkeypatch.setenv("HOSTILE_MARK_DIR", str(tmp_path))          # the workers inherit it
    cfg = load_config({"plugins": ["tests.plugins.hostile"], "meshes": ["knight"], "time_budget": 0,
                       "tasks": {"smoothing": {"methods": [{"name": "hostile.escape",
                                                            "params": {"crash": [True, False]}}]}}})
    ex = DaskExecutor(workers=1, timeout=60)
    try:
        keep = next(iter(ex.client.run(_start_sleep).values()))
        rows = [row for _, row, _ in ex.run(cfg.cases)]
        alive_keep = next(iter(ex.client.run(_alive_pid, keep).values()))
    finally:
        ex.close()
    assert sorted(r["status"] for r in rows) == ["error", "ok"], rows
    pids = [int(p.read_text()) for p in tmp_path.glob("escaped-*.pid")]
    assert len(pids) >= 2, pids
    time.sleep(0.3)
    assert not [p for p in pids if psutil.pid_exists(p) and psutil.Process(p).status() != psutil.STATUS_ZOMBIE], pids
    assert alive_keep


def _start_sleep():
    import subprocess as sp
    import harness.executors.dask as d
    d._KEEP = sp.Popen(["sleep", "60"])
    return d._KEEP.pid


def _alive_pid(pid):
    import psutil as ps
    return ps.pid_exists(pid) and ps.Process(pid).status() != ps.STATUS_ZOMBIE
