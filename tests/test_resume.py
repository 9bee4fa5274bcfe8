"""Durability and resume (issue 7): a run killed with SIGKILL mid-way leaves parseable CSVs,
``--resume`` finishes it with no duplicate and no lost ok row, a changed config is refused
(exit 2, nothing touched), and no case process outlives a killed driver."""
import contextlib
import csv
import io
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import harness  # noqa: E402
from harness import input_store  # noqa: E402
from harness.config import load_config  # noqa: E402
from harness.results import RunFolder, columns, load_csv  # noqa: E402

SHOOTOUT = Path(sys.executable).with_name("shootout")
TASK_FILES = ("laplacian.csv", "smoothing.csv", "simplification.csv")


def env_with_root():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    return env


def slow_config(seconds=(0.4, 0.41, 0.42, 0.43, 0.44, 0.45)):
    return {"name": "killme", "plugins": ["tests.plugins.crashy"],
            "meshes": ["knight", {"procedural": "sphere", "subdivisions": 2}],
            "tasks": {"laplacian": {"methods": [{"name": "crashy.slow", "params": {"seconds": list(seconds)}},
                                                "crashy.raises"]},
                      "smoothing": {"methods": [{"name": "scratch.explicit", "params": {"iterations": [3, 4]}}]}}}


def data_rows(path: Path) -> int:
    try:
        return max(0, path.read_text().count("\n") - 1)
    except FileNotFoundError:
        return 0


def strict_rows(path: Path, task: str) -> list[dict]:
    """Every line of the CSV parsed with the csv module: header == contract columns, every row
    complete (a torn line would fail here)."""
    text = path.read_text()
    assert text.endswith("\n"), f"{path.name}: last line not terminated"
    rows = list(csv.reader(io.StringIO(text)))
    assert rows[0] == columns(task)
    assert all(len(r) == len(rows[0]) for r in rows[1:]), f"{path.name}: ragged row"
    return [dict(zip(rows[0], r)) for r in rows[1:]]


def start(cfg_path, out, *extra, tmpdir=None):
    env = env_with_root() if tmpdir is None else {**env_with_root(), "TMPDIR": str(tmpdir)}
    return subprocess.Popen([str(SHOOTOUT), "run", str(cfg_path), "--out", str(out), "--quiet", *extra],
                            env=env, start_new_session=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def wait_for_rows(out: Path, n: int, proc, limit=120):
    t0 = time.time()
    while sum(data_rows(out / f) for f in TASK_FILES) < n:
        assert proc.poll() is None, f"run ended before {n} rows: {proc.communicate()}"
        assert time.time() - t0 < limit, "no rows appeared"
        time.sleep(0.05)


def test_sigkill_mid_run_then_resume(tmp_path):
    cfg_path = tmp_path / "killme.yaml"
    cfg_path.write_text(yaml.safe_dump(slow_config()))
    out = tmp_path / "out"
    n_cases = len(load_config(cfg_path).cases)           # 2 meshes x (6 slow + 1 raises + 2 smoothing) = 18
    proc = start(cfg_path, out, "--workers", "2")
    wait_for_rows(out, 5, proc)
    os.killpg(proc.pid, signal.SIGKILL)                 # the whole process group, mid-run
    proc.wait(30)
    assert proc.returncode == -signal.SIGKILL

    before = {}
    for f in TASK_FILES:
        if (out / f).exists():
            task = f[:-4]
            load_csv(out / f)                            # pandas parses it
            for r in strict_rows(out / f, task):
                before[r["case_id"]] = r
    assert 5 <= len(before) < n_cases, "the kill should land mid-run"
    ok_before = {k: r for k, r in before.items() if r["status"] == "ok"}
    assert ok_before

    r = subprocess.run([str(SHOOTOUT), "run", str(cfg_path), "--out", str(out), "--quiet", "--resume",
                        "--workers", "2"], env=env_with_root(), capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    after = {}
    for f in ("laplacian.csv", "smoothing.csv"):         # the tasks of this config
        rows = strict_rows(out / f, f[:-4])
        ids = [x["case_id"] for x in rows]
        assert len(ids) == len(set(ids)), f"duplicate rows in {f}"
        after.update({x["case_id"]: x for x in rows})
    assert set(after) == {c.case_id for c in load_config(cfg_path).cases}
    for cid, row in ok_before.items():                   # ok rows kept exactly as written
        assert after[cid] == row
    statuses = {x["method"]: set() for x in after.values()}
    for x in after.values():
        statuses[x["method"]].add(x["status"])
    assert statuses == {"crashy.slow": {"ok"}, "crashy.raises": {"error"}, "scratch.explicit": {"ok"}}
    meta = RunFolder(out).read_run_json()
    assert meta["status"] == "finished" and meta["resumed_ok_cases"] == len(ok_before)
    killed, resumed = meta["sessions"]                   # the killed session is on record, as killed
    assert killed["status"] == "killed" and killed["wall_s"] is None and resumed["status"] == "finished"
    assert meta["wall_s"] == resumed["wall_s"]
    assert killed["executor"] == resumed["executor"] == "local" and resumed["workers"] == meta["workers"]


def test_resume_with_a_changed_config_is_refused(tmp_path):
    cfg = slow_config(seconds=(0.0,))
    cfg_path = tmp_path / "c.yaml"
    cfg_path.write_text(yaml.safe_dump(cfg))
    out = tmp_path / "out"
    harness.run(load_config(cfg_path), out=out, workers=2)
    snapshot = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file() and p.name != ".shootout.lock"}

    cfg["tasks"]["laplacian"]["methods"].append("scratch.uniform")     # one more method: new cases
    cfg_path.write_text(yaml.safe_dump(cfg))
    r = subprocess.run([str(SHOOTOUT), "run", str(cfg_path), "--out", str(out), "--resume"],
                       env=env_with_root(), capture_output=True, text=True, timeout=120)
    assert r.returncode == 2
    assert "config changed" in r.stderr and "--resume" in r.stderr and "Traceback" not in r.stderr
    assert "0 of its cases not in this config" in r.stderr, r.stderr        # what changed (a review: not said)
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file() and p.name != ".shootout.lock"} == snapshot
    cfg["tasks"]["laplacian"]["methods"].pop()
    with pytest.raises(harness.errors.ShootoutError, match=r"found: repeats 1 -> 2\)"):
        harness.run({**cfg, "repeats": 2}, out=out, resume=True)


def test_resume_with_a_changed_time_budget_is_refused(tmp_path):
    """The timing budget decides how many samples a row holds: a resume with another budget would
    mix rows of 2 samples with rows of 100 under one recorded setting."""
    from harness.session import config_hash
    cfg = slow_config(seconds=(0.0,))
    base = config_hash(load_config({**cfg, "time_budget": 0.25}))
    assert config_hash(load_config(cfg)) == base                          # the default: the key of older folders
    assert config_hash(load_config({**cfg, "time_budget": 0})) != base
    assert config_hash(load_config({**cfg, "time_budget": 0.3})) != config_hash(load_config({**cfg, "time_budget": 0}))


def test_resume_of_a_csv_with_other_columns_is_refused_and_keeps_it(tmp_path):
    """Before: a CSV written by a version with one column fewer (e.g. before `others_cpu`) had
    every row silently dropped and rerun ('0 finished case(s) kept'); a renamed metric crashed
    --resume with a traceback. A folder of the user's with no run.json kept our lock file."""
    cfg = load_config(slow_config(seconds=(0.0,)))
    out = tmp_path / "out"
    harness.run(cfg, out=out, workers=2)
    p = out / "laplacian.csv"
    rows = list(csv.DictReader(p.open()))
    head = [c for c in rows[0] if c != "others_cpu"]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=head, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    p.write_text(buf.getvalue())
    before = p.read_bytes()
    with pytest.raises(harness.errors.ShootoutError, match=r"laplacian.csv has other columns than this version's "
                       r"\(without \['others_cpu'\]\).*would drop its rows"):
        harness.run(cfg, out=out, workers=2, resume=True)
    assert p.read_bytes() == before
    p.write_text(",".join(columns("laplacian"))[:40])      # a header torn by a full disk: nothing to keep
    assert RunFolder(out).column_problems() == []
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "laplacian.csv").write_text("a,b\n1,2\n")
    with pytest.raises(harness.errors.ShootoutError, match="but no run.json"):
        harness.run(cfg, out=mine, workers=2, resume=True)
    assert sorted(x.name for x in mine.iterdir()) == ["laplacian.csv"]


def test_resume_drops_a_torn_last_line_and_reruns_that_case(tmp_path):
    """Should the OS ever leave half a line, --resume drops it and runs that case again."""
    cfg = load_config(slow_config(seconds=(0.0,)))
    out = tmp_path / "out"
    harness.run(cfg, out=out, workers=2)
    p = out / "laplacian.csv"
    lines = p.read_text().splitlines(keepends=True)
    torn_id = lines[-1].split(",")[0]
    p.write_text("".join(lines[:-1]) + lines[-1][: len(lines[-1]) // 2])     # half a row, no newline
    frames = harness.run(cfg, out=out, workers=2, resume=True)
    df = frames["laplacian"]
    assert df["case_id"].is_unique and torn_id in set(df["case_id"])
    assert len(df) == sum(c.task == "laplacian" for c in cfg.cases)


def test_resume_drops_a_row_whose_id_is_not_one_of_the_configs_cases(tmp_path):
    """A row edited to another case id (not a case of the config) was kept by --resume beside the
    rerun of its case: one more row than cases, two rows for one setting."""
    cfg = load_config(slow_config(seconds=(0.0,)))
    out = tmp_path / "out"
    harness.run(cfg, out=out, workers=2)
    p = out / "laplacian.csv"
    lines = p.read_text().splitlines(keepends=True)
    lines[1] = "deadbeef0000" + lines[1][lines[1].index(","):]
    p.write_text("".join(lines))
    df = harness.run(cfg, out=out, workers=2, resume=True)["laplacian"]
    assert "deadbeef0000" not in set(df["case_id"]) and df["case_id"].is_unique
    assert len(df) == sum(c.task == "laplacian" for c in cfg.cases)


def _alive(pids):
    out = []
    for pid in pids:
        try:
            if psutil.Process(pid).status() != psutil.STATUS_ZOMBIE:
                out.append(pid)
        except psutil.NoSuchProcess:
            pass
    return out


def test_case_processes_die_with_a_killed_driver(tmp_path):
    """SIGKILL to the driver pid alone (as the OOM killer does): the case children running two
    never-ending cases must not live on as orphans."""
    cfg = {"name": "orphans", "plugins": ["tests.plugins.crashy"], "meshes": ["knight"],
           "tasks": {"laplacian": {"methods": ["crashy.sleep",
                                               {"name": "crashy.slow", "params": {"seconds": [1000.0]}}]}}}
    cfg_path = tmp_path / "o.yaml"
    cfg_path.write_text(yaml.safe_dump(cfg))
    tmp = tmp_path / "tmp"                        # the driver's own temporary directory
    tmp.mkdir()
    proc = start(cfg_path, tmp_path / "out", "--workers", "2", tmpdir=tmp)
    driver = psutil.Process(proc.pid)
    t0 = time.time()
    kids = []
    while len(kids) < 2:
        assert proc.poll() is None and time.time() - t0 < 60, "children did not start"
        kids = []                                  # the case processes: forks of the driver (not its git call)
        for k in driver.children(recursive=True):
            with contextlib.suppress(psutil.Error):
                if k.exe() == driver.exe():
                    kids.append(k.pid)
        time.sleep(0.1)
    time.sleep(0.5)
    try:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(30)
        t0 = time.time()
        while _alive(kids) and time.time() - t0 < 10:
            time.sleep(0.1)
        assert not _alive(kids), "case processes outlived the killed driver"
        # its private directory (input store, the cases' stderr files) stays behind until a
        # later session sweeps it, since nobody holds its lock any more
        (left,) = tmp.glob(input_store.PREFIX + "*")
        assert len(list(left.glob("shootout-case-*.err"))) == 2
        assert input_store.sweep(str(tmp)) == 1 and not any(tmp.iterdir())
    finally:
        for pid in _alive(kids):                   # never leave them behind, even when failing
            os.kill(pid, signal.SIGKILL)


def test_resume_keeps_the_first_session_and_says_what_it_skipped(tmp_path):
    """A resumed run keeps the original start and command in run.json, lists every session
    (start, end, wall time, command, status), sums the wall time, and says how many finished
    cases it kept."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text(yaml.safe_dump({"name": "two", "repeats": 1, "meshes": ["knight"],
                                   "tasks": {"laplacian": {"methods": ["scratch.cotan", "scratch.uniform"]}}}))
    out = tmp_path / "r"
    run = lambda *extra: subprocess.run([str(SHOOTOUT), "run", str(cfg), "--out", str(out), *extra],  # noqa: E731
                                        capture_output=True, text=True, env=env_with_root(), timeout=300)
    assert run().returncode == 0
    first = RunFolder(out).read_run_json()
    r = run("--resume", "--workers", "1")
    assert r.returncode == 0, r.stderr
    assert f"resuming {out}: 2 finished case(s) kept, 0 to run" in r.stderr
    meta = RunFolder(out).read_run_json()
    assert meta["started"] == first["started"] and meta["command"] == first["command"]
    assert "--resume" not in meta["command"]
    s = meta["sessions"]
    assert len(s) == 2 and s[0]["started"] == first["started"] and "--resume" in s[1]["command"]
    assert s[1]["resumed_ok_cases"] == 2 and s[1]["status"] == "finished"
    assert abs(meta["wall_s"] - (s[0]["wall_s"] + s[1]["wall_s"])) < 1e-6
    # a resume that ran nothing kept the first run's fixed cost, commit and versions (it wrote
    # null and its own), and the run's load at the start; each session has its own
    assert meta["fixed_cost_per_case_s"] == first["fixed_cost_per_case_s"] is not None
    assert meta["load_average"][0] == first["load_average"][0] and "provenance_changed" not in meta
    assert all(x["versions"] == first["versions"] and x["git_commit"] == first["git_commit"] for x in s)


def test_a_resume_with_other_code_or_packages_keeps_the_first_and_says_so(tmp_path):
    """--resume replaced run.json's commit and package versions with its own: rows made by the
    first run's code were credited to the resume's, and nothing recorded the first."""
    import json
    cfg = slow_config(seconds=(0.0, 0.01))
    out = tmp_path / "out"
    harness.run(cfg, out=out, workers=1)
    meta = json.loads((out / "run.json").read_text())
    meta["versions"]["numpy"] = "1.0.0-OLD"
    meta["git_commit"] = "0ldc0mmit"
    del meta["git_dirty"]                          # what older versions did not record is no change
    meta["versions"].pop("scipy")
    meta["versions"]["numba"] = None               # recorded as not installed then: a change
    (out / "run.json").write_text(json.dumps(meta))
    p = out / "laplacian.csv"
    p.write_text("".join(p.read_text().splitlines(keepends=True)[:-1]))
    harness.run(cfg, out=out, workers=1, resume=True, quiet=False)
    after = json.loads((out / "run.json").read_text())
    assert after["versions"]["numpy"] == "1.0.0-OLD" and after["git_commit"] == "0ldc0mmit"
    (ch,) = after["provenance_changed"]
    assert ch["session"] == after["sessions"][-1]["id"] and ch["git_commit"][0] == "0ldc0mmit"
    assert ch["versions"]["numpy"][0] == "1.0.0-OLD" and after["sessions"][-1]["versions"]["numpy"] != "1.0.0-OLD"
    assert "git_dirty" not in ch and set(ch["versions"]) == {"numpy", "numba"} and ch["versions"]["numba"][0] is None
    html = (out / "report.html").read_text()
    assert "provenance" in html and "1.0.0-OLD" in html


def test_a_killed_session_started_in_the_same_second_is_still_recorded(tmp_path):
    """Sessions are matched by an id, not by their start time (to the second): a session killed
    within the second of the one before it was left out of the record. Its state is made here
    from a finished run.json as a killed driver leaves it (status running, its own id and start
    time, no record of its own)."""
    import json
    cfg = slow_config(seconds=(0.0,))
    out = tmp_path / "out"
    harness.run(cfg, out=out, workers=1)
    meta = json.loads((out / "run.json").read_text())
    (first,) = meta["sessions"]
    assert first["id"] and first["id"] == meta["session_id"]
    meta.update(status="running", session_id="feedfacefeedface", session_started=first["started"])
    (out / "run.json").write_text(json.dumps(meta))
    harness.run(cfg, out=out, workers=1, resume=True)
    sessions = json.loads((out / "run.json").read_text())["sessions"]
    assert [(s["id"], s["status"]) for s in sessions[:2]] == [(first["id"], "finished"), ("feedfacefeedface", "killed")]
    assert len(sessions) == 3 and sessions[2]["status"] == "finished"


TUNE = {"name": "tuned", "time_budget": 0, "hausdorff_samples": 200,
        "meshes": [{"procedural": "sphere", "subdivisions": 2}], "noise": [{"model": "gaussian_normal", "levels": [0.3]}],
        "tasks": {"smoothing": {"methods": ["scratch.taubin"]}},
        "tune": {"metric": "dist_mean", "train": [{"procedural": "torus", "resolution": 12}],
                 "budget": 2, "params": {"scratch.taubin": {"iterations": [3, 12]}}}}


def test_resume_of_a_tuned_run_refuses_another_tune_section_and_drops_rows_not_its_own(tmp_path):
    """--resume kept the training rows of another tune.train and averaged them into the choice,
    and kept a tuned row of another choice beside the new one (more rows than cases)."""
    from harness.session import config_hash
    base = config_hash(load_config(TUNE))
    assert config_hash(load_config({**TUNE, "tune": {**TUNE["tune"], "train": ["knight"]}})) != base
    assert config_hash(load_config({**TUNE, "tune": {**TUNE["tune"], "metric": "hausdorff"}})) != base
    assert config_hash(load_config({**TUNE, "tune": {**TUNE["tune"], "params": {"scratch.taubin": {"iterations": [3, 11]}}}})) != base
    notune = {k: v for k, v in TUNE.items() if k != "tune"}
    assert config_hash(load_config(notune)) == config_hash(load_config({**notune, "name": "x"}))
    out = tmp_path / "out"
    first = harness.run(TUNE, out=out, workers=1)["smoothing"]
    p = out / "smoothing.csv"
    lines = p.read_text().splitlines(keepends=True)
    p.write_text("".join(lines + ["deadbeef0000" + lines[-1][lines[-1].index(","):]]))   # another choice's row
    again = harness.run(TUNE, out=out, workers=1, resume=True)["smoothing"]
    assert "deadbeef0000" not in set(again["case_id"]) and sorted(again["case_id"]) == sorted(first["case_id"])
    import json                                    # a folder of a version whose hash left tune: out resumes
    meta = json.loads((out / "run.json").read_text())
    (out / "run.json").write_text(json.dumps({**meta, "config_hash": config_hash(load_config(TUNE), with_tune=False)}))
    assert len(harness.run(TUNE, out=out, workers=1, resume=True)["smoothing"]) == len(first)
    fresh = harness.run(TUNE, out=tmp_path / "fresh", workers=1, resume=True)["smoothing"]   # nothing to resume yet
    assert len(fresh) == len(first)
    untuned = tmp_path / "untuned"                 # an untuned run's folder does not resume with a tune: section
    harness.run({k: v for k, v in TUNE.items() if k != "tune"}, out=untuned, workers=1)
    with pytest.raises(harness.errors.ShootoutError, match="config changed"):
        harness.run(TUNE, out=untuned, workers=1, resume=True)
    other = {**TUNE, "tune": {**TUNE["tune"], "metric": "hausdorff"}}   # but not with another tune: section
    with pytest.raises(harness.errors.ShootoutError, match="config changed"):
        harness.run(other, out=out, workers=1, resume=True)


def test_resume_refuses_a_mesh_whose_label_changed(tmp_path):
    """A file mesh's name: is not part of its case ids, but its noise is seeded by it: a resume
    under another name mixed rows of two different noisy inputs, as two meshes."""
    from harness.errors import ShootoutError
    mesh = tmp_path / "kn.obj"
    from harness import datasets
    m = datasets.cached({"procedural": "sphere", **datasets.PROCEDURAL["sphere"], "subdivisions": 2}).clean
    mesh.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in m.V) + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in m.F))
    cfg = {"name": "n", "time_budget": 0, "hausdorff_samples": 200, "meshes": [{"file": str(mesh), "name": "alpha"}],
           "noise": [{"model": "gaussian_normal", "levels": [0.3]}],
           "tasks": {"smoothing": {"methods": ["scratch.taubin", "scratch.explicit"]}}}
    out = tmp_path / "out"
    harness.run(cfg, out=out, workers=1)
    p = out / "smoothing.csv"
    p.write_text("".join(p.read_text().splitlines(keepends=True)[:-1]))          # a killed run's last row missing
    before = p.read_bytes()
    with pytest.raises(ShootoutError, match="labelled 'alpha' in the run's rows is labelled 'beta'"):
        harness.run({**cfg, "meshes": [{"file": str(mesh), "name": "beta"}]}, out=out, workers=1, resume=True)
    assert p.read_bytes() == before
    df = harness.run(cfg, out=out, workers=1, resume=True)["smoothing"]           # under its old name it resumes
    assert len(df) == 2 and set(df["mesh"]) == {"alpha"}


def test_resume_of_a_csv_saved_with_a_byte_order_mark_keeps_its_rows(tmp_path):
    """A task CSV saved by a spreadsheet starts with a BOM: --resume called it another version's
    file and advised a fresh run, which would have deleted its rows."""
    cfg = load_config(slow_config(seconds=(0.0, 0.01)))
    out = tmp_path / "out"
    harness.run(cfg, out=out, workers=1)
    p = out / "laplacian.csv"
    lines = p.read_text().splitlines(keepends=True)
    p.write_bytes(b"\xef\xbb\xbf" + "".join(lines[:-1]).encode())      # and a killed run's last row missing
    kept = {r["case_id"] for r in csv.DictReader(io.StringIO("".join(lines[1:-1])), fieldnames=lines[0].strip().split(","))}
    df = harness.run(cfg, out=out, workers=1, resume=True)["laplacian"]
    assert kept < set(df["case_id"]) and len(df) == sum(c.task == "laplacian" for c in cfg.cases)
    assert not p.read_bytes().startswith(b"\xef\xbb\xbf")


def test_a_resume_with_other_plugin_code_under_the_same_commit_says_so(tmp_path):
    """An outside review: two sessions with different plugin code (or different uncommitted
    edits: ``git_dirty`` is True for both) recorded the same provenance, so the folder mixed rows
    of both without a word. run.json's ``code_sha256`` hashes the harness's, the methods' and the
    plugins' source files."""
    import json
    root = Path(__file__).resolve().parents[1]
    plug = tmp_path / "provplug.py"
    plug.write_text("from methods import SmoothingResult, register\n\n\n"
                    "@register('provplug.scale', task='smoothing', library='provplug')\n"
                    "def scale(V, F):\n    return SmoothingResult(V=V * 1.0)\n")
    cfg = tmp_path / "c.yaml"
    cfg.write_text(json.dumps({"name": "prov", "repeats": 1, "time_budget": 0, "plugins": ["provplug"],
                               "meshes": ["knight", "woody"], "noise": [{"model": "gaussian_normal", "levels": [0.3]}],
                               "tasks": {"smoothing": {"methods": ["provplug.scale"]}}}))
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONPATH": f"{root}:{tmp_path}"}
    run = [sys.executable, "-m", "harness.cli", "run", str(cfg), "--out", str(out), "--workers", "1"]
    assert subprocess.run(run + ["--quiet"], cwd=root, env=env, capture_output=True, timeout=300).returncode == 0
    first = json.loads((out / "run.json").read_text())["code_sha256"]
    assert first and len(first) == 16
    p = out / "smoothing.csv"
    p.write_text("".join(p.read_text().splitlines(keepends=True)[:-1]))
    plug.write_text(plug.read_text().replace("V * 1.0", "V * 1.001"))
    r = subprocess.run(run + ["--resume"], cwd=root, env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and "code_sha256" in r.stderr, r.stderr[-800:]
    after = json.loads((out / "run.json").read_text())
    (ch,) = after["provenance_changed"]
    assert ch["code_sha256"][0] == first and ch["code_sha256"][1] not in (None, first)
    assert after["code_sha256"] == first                    # the run's first, as its commit
    assert "source files (code_sha256)" in (out / "report.html").read_text()


def test_code_sha256_covers_a_namespace_package_plugin(tmp_path, monkeypatch):
    """A review of the hash: a plugin given as a namespace package (no __init__.py) hashed as a
    constant, so editing its module changed nothing."""
    from harness.provenance import code_hash
    (tmp_path / "nsplug").mkdir()
    mod = tmp_path / "nsplug" / "meth.py"
    mod.write_text("X = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    a = code_hash(["nsplug"])
    mod.write_text("X = 2\n")
    assert code_hash(["nsplug"]) != a and code_hash(["nsplug"]) == code_hash(["nsplug"])


def test_resuming_a_finished_run_whose_result_diverged_runs_nothing(tmp_path):
    """A review: with save_meshes, a diverged result's saved mesh (coordinates that are not
    finite) counted as unreadable, so every --resume of a finished run ran those cases again."""
    import json

    import pandas as pd

    import harness
    cfg = {"name": "dv", "repeats": 1, "time_budget": 0, "save_meshes": True, "hausdorff_samples": 100,
           "meshes": ["knight"], "noise": [{"model": "gaussian_normal", "levels": [0.3]}],
           "tasks": {"smoothing": {"methods": [{"name": "scratch.explicit", "params": {"step": 5.0,
                                                                                     "iterations": 400}},
                                               "scratch.taubin"]}}}
    out = tmp_path / "o"
    first = harness.run(cfg, out=out, quiet=True, workers=1)["smoothing"]
    assert first["diverged"].astype(str).str.lower().tolist().count("true") == 1, first[["method", "diverged"]]
    again = harness.run(cfg, out=out, quiet=True, workers=1, resume=True)["smoothing"]
    pd.testing.assert_series_equal(first["time_s"], again["time_s"])
    assert json.loads((out / "run.json").read_text())["status_counts_this_session"] == {}


def test_an_interrupt_between_the_plan_and_run_json_leaves_a_folder_a_run_takes(tmp_path, monkeypatch):
    """A review: a Ctrl-C while run.json was written left plan.csv alone, which both a fresh run
    ('these may be your files') and --resume ('plan.csv but no run.json') then refused."""
    import harness
    from harness.results import RunFolder
    cfg = {"name": "pi", "repeats": 1, "time_budget": 0, "hausdorff_samples": 100, "meshes": ["knight"],
           "tasks": {"smoothing": {"methods": ["scratch.taubin"]}}}

    def interrupted(self, data):
        raise KeyboardInterrupt
    with monkeypatch.context() as m:
        m.setattr(RunFolder, "write_run_json", interrupted)
        with pytest.raises(KeyboardInterrupt):
            harness.run(cfg, out=tmp_path / "o", quiet=True, workers=1)
    assert not (tmp_path / "o" / "plan.csv").exists()
    assert list(harness.run(cfg, out=tmp_path / "o", quiet=True, workers=1)["smoothing"]["status"]) == ["ok"]
