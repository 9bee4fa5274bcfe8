"""Isolation and timeouts (issue 7): a method that kills its process or never returns costs one
row, and the run goes on.

The misbehaving methods live in tests/plugins/crashy.py and are loaded the way users load
theirs, through ``plugins: [tests.plugins.crashy]`` (the repository root on the path of the
driver and of every child).
"""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:          # so `tests.plugins.crashy` imports here and in forked children
    sys.path.insert(0, str(ROOT))

import harness  # noqa: E402
from harness.results import load_csv  # noqa: E402

SHOOTOUT = Path(sys.executable).with_name("shootout")
MESHES = ["knight", {"procedural": "sphere", "subdivisions": 2}]


def env_with_root():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    return env


def read_all(out: Path) -> pd.DataFrame:
    return pd.concat([load_csv(p) for p in sorted(out.glob("*.csv")) if p.name not in ("leaderboard.csv", "winners.csv", "plan.csv")], ignore_index=True)


def test_abort_segfault_and_sleep_through_the_cli(tmp_path):
    """`shootout run cfg --timeout 3`: per mesh one SIGABRT error row, one SIGSEGV error row, one
    timeout row; every other row ok; exit 0; run.json records the workers and the counts."""
    cfg = {"name": "crash", "plugins": ["tests.plugins.crashy"], "meshes": MESHES,
           "noise": [{"model": "gaussian_normal", "levels": [0.2]}],
           "tasks": {"laplacian": {"methods": ["crashy.abort", "crashy.sleep", "crashy.segfault",
                                               "scratch.cotan", "libigl.cotan"]},
                     "smoothing": {"methods": [{"name": "scratch.explicit", "params": {"iterations": 5}}]},
                     "simplification": {"methods": ["fast_simplification.qem"],
                                        "params": {"target_ratio": 0.5}}}}
    path = tmp_path / "crash.yaml"
    path.write_text(yaml.safe_dump(cfg))
    out = tmp_path / "out"
    r = subprocess.run([str(SHOOTOUT), "run", str(path), "--out", str(out), "--timeout", "3",
                        "--workers", "2", "--quiet"], capture_output=True, text=True, env=env_with_root(),
                       timeout=300)
    assert r.returncode == 0, r.stderr
    assert "Traceback" not in r.stderr
    df = read_all(out)
    assert len(df) == len(MESHES) * 7 and df["case_id"].is_unique
    for mesh, rows in df.groupby("mesh"):
        by = rows.set_index("method")
        assert by.loc["crashy.abort", "status"] == "error"
        assert "SIGABRT" in by.loc["crashy.abort", "error"]
        assert by.loc["crashy.segfault", "status"] == "error"
        assert "SIGSEGV" in by.loc["crashy.segfault", "error"]
        assert by.loc["crashy.sleep", "status"] == "timeout"
        assert "3 s" in by.loc["crashy.sleep", "error"]
        others = by.drop(index=["crashy.abort", "crashy.segfault", "crashy.sleep"])
        assert (others["status"] == "ok").all(), others[["status", "error"]]
        assert (others["peak_rss_mb"] > 0).all()       # measured in the worker, from the OS
    meta = json.loads((out / "run.json").read_text())
    assert meta["status"] == "finished" and meta["workers"] == 2 and meta["timeout_s"] == 3
    assert meta["status_counts"] == {"ok": 8, "error": 4, "timeout": 2}


def test_every_other_failure_mode_is_one_defined_row(tmp_path):
    """In-process API, timeout from the config: os._exit, an exception, a missing library, NaN
    smoothing output and out-of-range faces each give one row with a defined status."""
    cfg = {"name": "fail", "plugins": ["tests.plugins.crashy"], "timeout": 3, "meshes": ["knight"],
           "tasks": {"laplacian": {"methods": ["crashy.exit", "crashy.raises", "crashy.missing",
                                               "crashy.sleep", "scratch.uniform"]},
                     "smoothing": {"methods": ["crashy.nan_smooth"]},
                     "simplification": {"methods": ["crashy.bad_faces"], "params": {"target_ratio": 0.5}}}}
    frames = harness.run(cfg, out=tmp_path / "out", workers=2)
    lap = frames["laplacian"].set_index("method")
    assert lap.loc["crashy.exit", "status"] == "error"
    assert "exited with code 3" in lap.loc["crashy.exit", "error"]
    assert lap.loc["crashy.raises", "status"] == "error"
    assert "RuntimeError: crashy.raises failed on purpose" in lap.loc["crashy.raises", "error"]
    assert lap.loc["crashy.missing", "status"] == "unavailable"
    assert "no_such_module_xyz" in lap.loc["crashy.missing", "error"]
    assert lap.loc["crashy.sleep", "status"] == "timeout"
    assert lap.loc["scratch.uniform", "status"] == "ok"
    sm = frames["smoothing"].iloc[0]
    # NaN coordinates are never a good result: ok with diverged=true and no accuracy numbers
    assert sm["status"] == "ok" and bool(sm["diverged"]) is True
    for col in ("ev_mean", "dist_mean", "hausdorff", "normal_error_deg", "min_angle"):
        assert np.isnan(sm[col]), col
    simp = frames["simplification"].iloc[0]
    assert simp["status"] == "error" and "out of range" in simp["error"]
    # the diverged result is no case to look at: no 3D view of it (its NaN coordinates)
    import json
    index = json.loads((tmp_path / "out" / "views" / "index.json").read_text())["views"]
    assert sm["case_id"] not in {v["case_id"] for v in index}


def test_serial_executor_is_not_used_for_isolation_by_default(tmp_path):
    """The default executor isolates: a segfault in the first case does not end the run."""
    cfg = {"name": "seg", "plugins": ["tests.plugins.crashy"], "meshes": ["knight"],
           "tasks": {"laplacian": {"methods": ["crashy.segfault", "scratch.uniform"]}}}
    frames = harness.run(cfg, out=tmp_path / "out", workers=1)
    st = frames["laplacian"].set_index("method")["status"].to_dict()
    assert st == {"crashy.segfault": "error", "scratch.uniform": "ok"}


def test_a_plugin_missing_in_the_case_process_is_named_with_the_fix():
    """A Dask worker without the config's plugin module on its path: every case's row names the
    plugin and the worker's PYTHONPATH, not a bare ModuleNotFoundError at <frozen importlib>."""
    import dataclasses

    from harness import runner
    from harness.config import load_config
    c = load_config({"meshes": ["knight"], "tasks": {"smoothing": {"methods": ["scratch.taubin"]}}})
    row, _ = runner.run_case(dataclasses.replace(c.cases[0], plugins=("no_such_plugin_mod",)))
    assert row["status"] == "error"
    assert "plugin 'no_such_plugin_mod' cannot be imported" in row["error"] and "PYTHONPATH" in row["error"]


def test_the_driver_reads_mesh_files_in_a_child_under_the_runs_timeout(tmp_path):
    """Each case read, repaired and measured a {file: ...} mesh again (0.44 s of fixed cost per case
    at 86k faces); the driver now reads it once, in a child process bounded by the run's timeout, so
    a file slow or hostile to read costs that child (and the cases' own timeouts), never the
    driver. What the child returns is what a case would read."""
    import shutil

    from harness import datasets
    from harness.config import load_config
    from harness.executors.local import _load_in_child
    from harness.mesh import read_mesh
    shutil.copy(datasets.DATA_DIR / "fandisk.obj", tmp_path / "f.obj")
    (tmp_path / "bad.obj").write_text("v 0 0 0\nf 1 2 3\n")
    cfg = load_config({"meshes": [{"file": str(tmp_path / "f.obj")}], "time_budget": 0,
                       "noise": [{"model": "gaussian_normal", "levels": [0.1]}],
                       "tasks": {"smoothing": {"methods": ["scratch.explicit"]}}})
    spec = cfg.cases[0].mesh
    src = _load_in_child(spec, True, 60)
    mine = read_mesh(tmp_path / "f.obj")
    assert np.array_equal(src.clean.V, mine.V) and np.array_equal(src.clean.F, mine.F)
    assert "noise_frame" in vars(src.clean) and "input_notes" in vars(src.clean)   # computed there, once
    assert _load_in_child(spec, True, 1e-4) is None                                 # past its time: left to the cases
    assert _load_in_child({**spec, "file": str(tmp_path / "bad.obj"), "file_sha1": None}, False, 60) is None
    frames = harness.run(cfg, out=tmp_path / "o", quiet=True, workers=1)
    assert frames["smoothing"]["status"].tolist() == ["ok"]


def test_the_mesh_loader_dies_with_a_killed_driver_and_holds_no_lock(tmp_path):
    """A review: the driver's mesh-loading child inherited the run folder's lock and blocked
    signals, and outlived a driver killed by SIGKILL (3.4 GB, 20 s on a hostile file), so a
    --resume right after was refused. It dies with the driver and holds no lock of its own."""
    import signal
    import time

    import psutil
    n = 600_000                                    # one huge polygon: a second or more to read
    with open(tmp_path / "big.obj", "w") as fh:
        fh.write("".join(f"v {i % 997} {i % 991} {i % 983}\n" for i in range(n)))
        fh.write("f " + " ".join(map(str, range(1, n + 1))) + "\n")
    cfg = tmp_path / "c.yaml"
    cfg.write_text(json.dumps({"name": "big", "time_budget": 0, "meshes": [{"file": str(tmp_path / "big.obj")}],
                               "tasks": {"laplacian": {"methods": ["scratch.uniform"]}}}))
    out = tmp_path / "o"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    p = subprocess.Popen([sys.executable, "-m", "harness.cli", "run", str(cfg), "--out", str(out), "--quiet"],
                         cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        driver, kids, t0 = psutil.Process(p.pid), [], time.time()
        def same_program(k):                      # a child that ended meanwhile (a zombie) is none
            try:
                return k.exe() == driver.exe()
            except psutil.Error:
                return False
        while not kids and time.time() - t0 < 60 and p.poll() is None:
            kids = [k for k in driver.children() if same_program(k)]
            time.sleep(0.05)
        assert kids, "no loader started"
        os.kill(p.pid, signal.SIGKILL)
        p.wait(10)
        gone, alive = psutil.wait_procs(kids, timeout=5)
        assert not alive, "the loader outlived the driver"
    finally:
        if p.poll() is None:
            p.kill()
    r = subprocess.run([sys.executable, "-m", "harness.cli", "run", str(cfg), "--out", str(out), "--resume",
                        "--timeout", "1", "--quiet"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
    assert "another run is using this folder" not in r.stderr, r.stderr


def test_an_interrupt_while_compiled_code_loads_waits_and_a_second_one_stops_at_once():
    """An interrupt inside llvmlite's callbacks crashed the driver (SIGSEGV); while kernels load
    it only sets the flag and is raised at the end of the block, and a second one ends the
    process at once (a cold compile can take tens of seconds)."""
    code = ("import os, signal, time\n"
            "from harness.errors import interrupts_deferred, on_interrupt\n"
            "signal.signal(signal.SIGINT, on_interrupt); signal.signal(signal.SIGTERM, on_interrupt)\n"
            "try:\n"
            "    with interrupts_deferred():\n"
            "        os.kill(os.getpid(), signal.SIGINT); time.sleep(0.2); print('went on', flush=True)\n"
            "except KeyboardInterrupt:\n"
            "    print('raised after', flush=True)\n"
            "with interrupts_deferred():\n"
            "    os.kill(os.getpid(), signal.SIGINT); time.sleep(5); print('not reached', flush=True)\n")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)},
                       capture_output=True, text=True, timeout=60)
    assert r.stdout.split() == ["went", "on", "raised", "after"], r.stdout + r.stderr
    assert r.returncode == 130 and "interrupted again" in r.stderr, (r.returncode, r.stderr)


def test_progress_lines_say_how_long_is_left(capsys):
    """Progress on long work: the lines a non-terminal stderr gets (CI logs, | tee) give an
    estimate of the time left at this session's pace (the cases a resume kept do not count)."""
    from harness.session import _duration, _Lines
    p = _Lines(10, 2, every=0.0)
    p.set_postfix_str("scratch.taubin on knight")
    p.update()
    p.update()
    err = capsys.readouterr().err
    assert "resuming, 2 of 10 case(s) already done" in err
    assert "shootout: 4/10 cases" in err and "left at this session's pace (last: scratch.taubin on knight)" in err
    for _ in range(6):
        p.update()
    assert "left" not in capsys.readouterr().err.splitlines()[-1]          # the last line: nothing left
    assert (_duration(45), _duration(720), _duration(4 * 3600)) == ("45 s", "12 min", "4.0 h")
