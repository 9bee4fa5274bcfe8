"""No lost data, untrusted configs, safe readers: each test reproduces a failure of the previous
version (user files deleted, double runs, torn meshes, disk full, alias bombs, unbounded grids,
plugins imported by rejected configs, damaged run.json and CSVs, 0600 files, tab-separated OBJ)."""
from __future__ import annotations

import json
import os
import shutil
import stat
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from harness.mesh import read_mesh

ROOT = Path(__file__).resolve().parents[1]
SMALL = {"time_budget": 0, "hausdorff_samples": 100, "meshes": ["knight"],
         "tasks": {"smoothing": {"methods": ["scratch.explicit", "scratch.taubin"]}}}


def cli(args, cwd=ROOT, timeout=120, **env):
    return subprocess.run([sys.executable, "-m", "harness.cli", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=timeout, env={**os.environ, "PYTHONPATH": str(ROOT), **env})


def write_cfg(path, cfg):
    path.write_text(json.dumps(cfg))
    return path


def test_a_fresh_run_never_deletes_a_users_meshes(tmp_path):
    (tmp_path / "meshes").mkdir()
    shutil.copy(ROOT / "harness/data/meshes/woody.obj", tmp_path / "meshes" / "scan.obj")
    (tmp_path / "meshes" / "notes.obj").write_text("v 0 0 0\n")
    cfg = write_cfg(tmp_path / "c.yaml", {**SMALL, "meshes": [{"file": "meshes/scan.obj"}]})
    for _ in range(2):                                   # a second fresh run into the same folder too
        r = cli(["run", cfg, "--out", "."], cwd=tmp_path)
        assert r.returncode == 0, r.stderr
    assert (tmp_path / "meshes" / "scan.obj").stat().st_size > 0 and (tmp_path / "meshes" / "notes.obj").exists()


def test_a_second_run_into_a_busy_folder_is_refused_naming_the_pid(tmp_path):
    slow = {**SMALL, "plugins": ["tests.plugins.slowdown"], "repeats": 1,
            "tasks": {"smoothing": {"methods": ["slowdown.until"]}}}
    cfg = write_cfg(tmp_path / "c.yaml", slow)
    release = tmp_path / "release"                 # the first run's case waits for it
    first = subprocess.Popen([sys.executable, "-m", "harness.cli", "run", str(cfg), "--out", str(tmp_path / "o")],
                             cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT), "SLOWDOWN_RELEASE": str(release)},
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        for _ in range(100):
            if (tmp_path / "o" / "run.json").exists():
                break
            time.sleep(0.1)
        for extra in ([], ["--resume"]):
            r = cli(["run", cfg, "--out", tmp_path / "o", *extra])
            assert r.returncode == 2 and f"pid {first.pid}" in r.stderr, r.stderr
        for cmd in ("views", "report"):            # both rewrote views/ or the report beside the run
            r = cli([cmd, tmp_path / "o"])
            assert r.returncode == 2 and f"pid {first.pid}" in r.stderr and "--out" not in r.stderr, r.stderr
        assert first.poll() is None                 # the refusals all came while it ran
    finally:
        release.touch()
        first.wait(timeout=120)
    df = pd.read_csv(tmp_path / "o" / "smoothing.csv")
    assert len(df) == 1 and df["case_id"].is_unique and first.returncode == 0


def test_a_lock_file_that_cannot_be_opened_is_a_message_and_a_link_is_not_followed(tmp_path):
    """A `.shootout.lock` that was a folder was a traceback (IsADirectoryError); a symbolic link was
    followed and its target truncated to the pid."""
    from harness.errors import ShootoutError
    from harness.results import RunFolder
    target = tmp_path / "notes.txt"
    target.write_text("mine")
    for make in (lambda p: p.mkdir(), lambda p: p.symlink_to(target)):
        d = tmp_path / f"o{len(list(tmp_path.iterdir()))}"
        d.mkdir()
        make(d / ".shootout.lock")
        with pytest.raises(ShootoutError, match="cannot take the run folder's lock"):
            RunFolder(d).lock()
    assert target.read_text() == "mine"


def test_resume_repairs_a_torn_saved_mesh(tmp_path):
    cfg = write_cfg(tmp_path / "c.yaml", {**SMALL, "save_meshes": True})
    out = tmp_path / "o"
    assert cli(["run", cfg, "--out", out]).returncode == 0
    rows = pd.read_csv(out / "smoothing.csv")
    victim = out / "meshes" / f"{rows['case_id'][0]}.ply"
    victim.write_text("")                                # what a SIGKILL mid-write used to leave
    r = cli(["run", cfg, "--out", out, "--resume"])
    assert r.returncode == 0, r.stderr
    assert len(read_mesh(victim, repair=False).F) > 0
    assert len(pd.read_csv(out / "smoothing.csv")) == len(rows) and not list(out.rglob(".*.tmp"))


@pytest.fixture
def tiny_disk(tmp_path):
    d = tmp_path / "disk"
    d.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=400k", "tmpfs", str(d)], capture_output=True)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a small tmpfs here: {r.stderr.decode().strip()}")
    yield d
    subprocess.run(["umount", "-l", str(d)], capture_output=True)


def test_disk_full_is_one_message_an_interrupted_run_and_resumable(tmp_path, tiny_disk):
    cfg = write_cfg(tmp_path / "c.yaml", {**SMALL, "save_meshes": True, "meshes": ["bunny", "knight"]})
    out = tiny_disk / "o"
    r = cli(["run", cfg, "--out", out])
    assert r.returncode == 1 and "disk is full" in r.stderr and "Traceback" not in r.stderr, r.stderr
    meta = json.loads((out / "run.json").read_text())
    assert meta["status"] == "interrupted"
    assert not list(out.rglob(".*.tmp"))
    for m in (out / "meshes").glob("*.ply"):             # whatever was kept is whole
        assert len(read_mesh(m, repair=False).F) > 0
    subprocess.run(["mount", "-o", "remount,size=20m", str(tiny_disk)], check=True)
    r = cli(["run", cfg, "--out", out, "--resume"])
    assert r.returncode == 0, r.stderr
    meta = json.loads((out / "run.json").read_text())
    assert meta["status"] == "finished"
    assert [x["status"] for x in meta["sessions"]] == ["interrupted", "finished"]   # the full-disk session on record
    assert len(pd.read_csv(out / "smoothing.csv")) == 4


BOMB = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n" for p, c in zip("abcdefgh", "bcdefghi"))


@pytest.mark.parametrize("where", ["report", "meshes"])
def test_a_yaml_alias_bomb_is_refused_quickly_with_a_short_message(tmp_path, where):
    text = BOMB.replace("\n", "\n  ").strip()
    body = (f"meshes: [knight]\ntasks: {{smoothing: {{methods: [scratch.explicit]}}}}\nreport:\n  {text}\n"
            if where == "report" else f"tasks: {{smoothing: {{methods: [scratch.explicit]}}}}\nmeshes:\n  {text}\n")
    cfg = tmp_path / "bomb.yaml"
    cfg.write_text(body)
    t0 = time.time()
    r = cli(["run", cfg, "--out", tmp_path / "o"], timeout=60)
    assert r.returncode == 2 and time.time() - t0 < 30
    assert len(r.stderr) < 2000 and "refused" in r.stderr, r.stderr[:500]
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("patch, needle", [
    ({"repeats": 10**9}, "repeats"), ({"hausdorff_samples": 10**12}, "hausdorff_samples"),
    ({"tasks": {"smoothing": {"methods": [{"name": "scratch.explicit",
                                           "params": {"iterations": list(range(1000)),
                                                      "step": [0.1 * i for i in range(1, 1001)]}}]}}},
     "expand to 1,000,000 settings"),
    ({"report": {"colour": "red"}}, "report.colour"),
])
def test_documented_bounds(tmp_path, patch, needle):
    cfg = write_cfg(tmp_path / "c.yaml", {**SMALL, **patch})
    r = cli(["run", cfg, "--out", tmp_path / "o"])
    assert r.returncode == 2 and needle in r.stderr, r.stderr
    assert not (tmp_path / "o").exists()


def test_a_long_mesh_list_validates_in_seconds(tmp_path):
    from harness.config import load_config
    from harness.errors import ConfigError
    # as a YAML file (an outside check: 52 s, then "alias bomb?" for a list with no alias): the
    # values are counted on libyaml's events before the pure-Python loader builds 1.25M nodes
    big = tmp_path / "big.yaml"
    big.write_text("name: big\nmeshes:\n" + "".join(f"  - {{file: m{i}.obj}}\n" for i in range(1_250_000)) +
                   "tasks: {laplacian: {methods: [scratch.uniform]}}\n")
    t0 = time.time()
    with pytest.raises(ConfigError, match="more than 200,000 values \\(a config holds at most that many\\)"):
        load_config(str(big))
    assert time.time() - t0 < 10
    t0 = time.time()
    with pytest.raises(ConfigError, match="expands to 1,250,000 cases"):
        load_config({"meshes": ["knight"] * 1_250_000, "tasks": {"laplacian": {"methods": ["scratch.uniform"]}}})
    assert time.time() - t0 < 20
    with pytest.raises(ConfigError) as err:        # listed with the config's other problems
        load_config({"meshes": ["knight"] * 200_000, "repeats": -1,
                     "tasks": {"laplacian": {"methods": ["scratch.uniform"]}}})
    assert len(err.value.problems) == 3 and "expands to 200,000 cases" in str(err.value) and "repeats" in str(err.value)
    assert "meshes[1], meshes[2], meshes[3] and 199996 more: the same mesh as meshes[0]" in str(err.value)


def test_a_rejected_config_imports_no_plugin(tmp_path):
    (tmp_path / "spy_plugin.py").write_text(f"open({str(tmp_path / 'imported')!r}, 'w').write('yes')\n")
    cfg = write_cfg(tmp_path / "c.yaml", {**SMALL, "plugins": ["spy_plugin"], "meshes": ["no_such_mesh"]})
    r = cli(["run", cfg, "--out", tmp_path / "o"], cwd=tmp_path)
    assert r.returncode == 2 and "no_such_mesh" in r.stderr
    assert not (tmp_path / "imported").exists()


def test_resume_refuses_a_damaged_run_json(tmp_path):
    cfg = write_cfg(tmp_path / "c.yaml", SMALL)
    out = tmp_path / "o"
    assert cli(["run", cfg, "--out", out]).returncode == 0
    (out / "run.json").write_text('{"name": "x", "conf')
    before = (out / "smoothing.csv").read_bytes()
    r = cli(["run", cfg, "--out", out, "--resume"])
    assert r.returncode == 2 and "damaged" in r.stderr and "Traceback" not in r.stderr
    assert (out / "smoothing.csv").read_bytes() == before


def test_out_on_a_file_or_a_read_only_place_and_a_huge_face_index(tmp_path, tiny_disk):
    cfg = write_cfg(tmp_path / "c.yaml", SMALL)
    (tmp_path / "afile").write_text("x")
    r = cli(["run", cfg, "--out", tmp_path / "afile"])
    assert r.returncode == 2 and "not a folder" in r.stderr and "Traceback" not in r.stderr
    for root, what in (("/", "the file system root"), (Path.home(), "your home folder"),
                       (ROOT, "mesh-shootout's source folder"), (ROOT / "harness" / "x", "mesh-shootout's source folder"),
                       (ROOT / "tests" / "plugins", "mesh-shootout's source folder")):
        r = cli(["run", cfg, "--out", root])           # the source folder: an outside review's run wrote among the sources
        assert r.returncode == 2 and f"is {what}" in r.stderr and not (Path(root) / "run.json").exists(), r.stderr
    assert not (ROOT / "harness" / "x").exists()
    nohome = subprocess.run(                       # no HOME and no passwd entry: no home folder to refuse
        [sys.executable, "-c", "import pathlib; pathlib.Path.home = lambda: (_ for _ in ()).throw("
         "RuntimeError('Could not determine home directory.')); from harness.results import check_out_dir; "
         f"check_out_dir(pathlib.Path({str(tmp_path / 'h')!r})); print('ok')"],
        cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert nohome.stdout.strip() == "ok", nohome.stderr
    subprocess.run(["mount", "-o", "remount,ro", str(tiny_disk)], check=True)
    r = cli(["run", cfg, "--out", tiny_disk / "o"])
    assert r.returncode == 2 and ("read-only" in r.stderr or "not writable" in r.stderr) and "Traceback" not in r.stderr
    clean = tmp_path / "clean.obj"
    clean.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    noisy = tmp_path / "noisy.obj"
    noisy.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999\n")
    cfg = write_cfg(tmp_path / "p.yaml", {**SMALL, "meshes": [{"file": str(noisy), "clean": str(clean)}]})
    r = cli(["run", cfg, "--out", tmp_path / "o2"])
    assert r.returncode == 2 and "noisy.obj" in r.stderr and "Traceback" not in r.stderr


@pytest.mark.parametrize("damage", ["ragged", "quote", "binary", "empty", "torn", "text_in_a_number", "params",
                                    "flag", "no_identity"])
def test_damaged_csvs_are_a_message_not_a_traceback_or_a_false_regression(tmp_path, damage):
    cfg = write_cfg(tmp_path / "c.yaml", SMALL)
    a, b = tmp_path / "a", tmp_path / "b"
    assert cli(["run", cfg, "--out", a]).returncode == 0
    shutil.copytree(a, b)
    p = b / "smoothing.csv"
    text = p.read_text()
    if damage == "ragged":
        p.write_text(text + "x,y,z\n")
    elif damage == "quote":
        p.write_text(text + '"unclosed,1,2\n')
    elif damage == "binary":
        p.write_bytes(p.read_bytes() + b"\x00\xff\xfe junk\n")
    elif damage == "empty":
        p.write_text("")
    elif damage == "params":                          # hand-edited cells the rankings read
        import csv
        import io

        from harness.errors import ShootoutError
        from harness.results import load_csv

        def edited(col, value):
            rows = list(csv.reader(io.StringIO(text)))
            rows[1][rows[0].index(col)] = value
            buf = io.StringIO()
            csv.writer(buf, lineterminator="\n").writerows(rows)
            p.write_text(buf.getvalue())
        for col, value in (("params", "abc"), ("params", "-1"), ("method", ""), ("status", ""), ("status", "done")):
            edited(col, value)
            with pytest.raises(ShootoutError, match=f"column {col} holds {value!r} on line 2"):
                load_csv(p)
        edited("params", "[1,2")
    elif damage == "text_in_a_number":               # a hand-edited cell of a metric column
        import csv
        import io
        rows = list(csv.reader(io.StringIO(text)))
        rows[1][rows[0].index("ev_rms")] = "notanumber"
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerows(rows)
        p.write_text(buf.getvalue())
    elif damage == "flag":                           # a review: "1" made the column text, "false" then read as true
        import csv
        import io
        rows = list(csv.reader(io.StringIO(text)))
        rows[1][rows[0].index("diverged")] = "1"
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerows(rows)
        p.write_text(buf.getvalue())
    elif damage == "no_identity":                    # a review: a traceback in the report and compare
        df = pd.read_csv(p, dtype=str, keep_default_na=False)
        df.drop(columns=["case_id", "status"]).to_csv(p, index=False)
    else:                                             # a torn last line: half of a real row
        last = text.splitlines()[-1]
        p.write_text(text + last[: len(last) // 2])
    r = cli(["compare", a, b])
    assert "Traceback" not in r.stderr
    if damage == "torn":
        assert r.returncode == 0, r.stdout + r.stderr        # dropped, never compared as data,
        assert "its last line was cut short" in r.stderr and "smoothing.csv" in r.stderr, r.stderr   # and said
    else:
        assert r.returncode == 2 and "smoothing.csv" in r.stderr, r.stderr
    r = cli(["report", b])
    assert "Traceback" not in r.stderr and r.returncode in (0, 2)
    if damage == "text_in_a_number":
        assert r.returncode == 2 and "column ev_rms holds 'notanumber' on line 2" in r.stderr, r.stderr
    if damage == "params":                            # a traceback of json, leaderboard or the page's data
        assert r.returncode == 2 and "column params holds '[1,2' on line 2" in r.stderr, r.stderr
    if damage == "flag":
        assert r.returncode == 2 and "column diverged holds '1' on line 2, expected true or false" in r.stderr, r.stderr
    if damage == "no_identity":
        assert r.returncode == 2 and "no column(s) case_id, status" in r.stderr, r.stderr


def test_files_follow_the_umask(tmp_path):
    cfg = write_cfg(tmp_path / "c.yaml", SMALL)
    out = tmp_path / "o"
    old = os.umask(0o022)
    try:
        assert cli(["run", cfg, "--out", out]).returncode == 0
        assert cli(["run", cfg, "--out", out, "--resume"]).returncode == 0
    finally:
        os.umask(old)
    for name in ("run.json", "smoothing.csv", "report.html"):
        assert stat.S_IMODE((out / name).stat().st_mode) == 0o644, name


def test_obj_faces_separated_by_tabs_or_indented(tmp_path):
    p = tmp_path / "t.obj"
    p.write_text("v 0 0 0\n\tv 1 0 0\nv\t0 1 0\n  v 1 1 0\n  f 1 2 3\nf\t2\t4\t3\n")
    assert read_mesh(p).F.shape == (2, 3)


def test_a_fresh_run_refuses_a_folder_of_someone_elses_outputs(tmp_path):
    """A folder without a run.json of ours that holds files with a run's output names (a report,
    a leaderboard, views, or another tool's run.json next to task CSVs) is refused with exit 2,
    before the folder or its lock is touched; the files stay byte for byte."""
    cfg = write_cfg(tmp_path / "c.yaml", SMALL)
    a, b, c = tmp_path / "a", tmp_path / "b", tmp_path / "c"
    for d in (a, b, c):
        d.mkdir()
    (a / "report.html").write_text("<html>mine</html>")
    (a / "winners.csv").write_text("mine\n")
    (a / ".draft.tmp").write_text("precious")
    (a / "views").mkdir()
    (a / "views" / "mine.json").write_text("{}")
    (b / "run.json").write_text('{"tool": "other"}')
    (b / "spectrum.csv").write_text("id,val\n1,2\n")
    (c / "run.json").write_text("[1, 2, 3]")
    for d in (a, b, c):
        before = {p.relative_to(d): p.read_bytes() for p in d.rglob("*") if p.is_file()}
        r = cli(["run", cfg, "--out", d])
        assert r.returncode == 2 and "written by mesh-shootout" in r.stderr, r.stderr
        assert {p.relative_to(d): p.read_bytes() for p in d.rglob("*") if p.is_file()} == before


def test_resume_with_saved_meshes_keeps_cases_of_tasks_without_an_output_mesh(tmp_path):
    """save_meshes: a Laplacian case has no output mesh, so resuming a finished run keeps it
    (it was re-run because its missing mesh file counted as torn)."""
    cfg = write_cfg(tmp_path / "c.yaml", {**SMALL, "save_meshes": True,
                                          "tasks": {"laplacian": {"methods": ["scratch.cotan"]},
                                                    "smoothing": {"methods": ["scratch.taubin"]}}})
    assert cli(["run", cfg, "--out", tmp_path / "o"]).returncode == 0
    before = (tmp_path / "o" / "laplacian.csv").read_bytes()
    r = cli(["run", cfg, "--out", tmp_path / "o", "--resume"])
    assert r.returncode == 0 and "0 to run" in r.stderr, r.stderr
    assert (tmp_path / "o" / "laplacian.csv").read_bytes() == before


def test_grids_too_large_duplicate_keys_and_exiting_plugins_are_config_errors(tmp_path):
    """Each is exit 2 with the problem named and nothing written, quickly and in little memory:
    a 27M-setting parameter grid (it was built in memory before the case limit was checked), a
    tune grid over the case limit, duplicate keys (the last silently won: a whole task lost; listed
    with the config's other problems, which they hid), a
    plugin that calls sys.exit at import (exit 0 with nothing run), or os._exit(0) (the driver
    itself ended with exit 0), or crashes it (SIGSEGV: no message). A 10^12-setting tune product
    is sampled, never built."""
    big = {**SMALL, "tasks": {"smoothing": {"methods": [{"name": "scratch.explicit", "params": {
        "iterations": list(range(1, 301)), "step": [0.1 + i * 1e-3 for i in range(300)],
        "self_weight": [i * 1e-3 for i in range(300)]}}]}}}
    text = ("name: dup\nmeshes: [knight]\ntasks:\n  laplacian: {methods: [scratch.cotan]}\n"
            "tasks:\n  smoothing: {methods: [scratch.taubin]}\nrepeats: 1\nrepeats: 2\nhausdorff_samples: -1\n"
            "seed: !!python/object/apply:os.system [echo hi]\n")
    (tmp_path / "exitplug.py").write_text("import sys\nsys.exit(0)\n")
    (tmp_path / "osexitplug.py").write_text("import os\nos._exit(0)\n")
    (tmp_path / "segvplug.py").write_text("import os, signal\nos.kill(os.getpid(), signal.SIGSEGV)\n")
    cases = {"big": (json.dumps(big), "27,000,000 settings"),
             "dup": (text, "duplicate key 'tasks' at line 5 (first at line 3): each key may appear once "
                           "in a mapping\n  - not valid YAML: duplicate key 'repeats' at line 8 (first at line 7)"
                           ": each key may appear once in a mapping\n  - not valid YAML: the tag "
                           "'!!python/object/apply:os.system' at line 10 is refused: configs take plain values only"),
             "plug": (json.dumps({**SMALL, "plugins": ["exitplug"]}), "called sys.exit(0) on import"),
             "osexit": (json.dumps({**SMALL, "plugins": ["osexitplug"]}),
                        "plugins[0]: cannot import 'osexitplug' (importing it ended the process (exit status 0))"),
             "segv": (json.dumps({**SMALL, "plugins": ["segvplug"]}),
                      "plugins[0]: cannot import 'segvplug' (importing it killed the process (SIGSEGV))")}
    for name, (body, needle) in cases.items():
        (tmp_path / f"{name}.yaml").write_text(body)
        r = cli(["run", tmp_path / f"{name}.yaml", "--out", tmp_path / name], cwd=tmp_path,
                PYTHONPATH=f"{ROOT}:{tmp_path}")
        assert r.returncode == 2 and needle in r.stderr, (name, r.stderr)
        assert name != "dup" or "hausdorff_samples: expected" in r.stderr, r.stderr     # and the config's others
        assert not (tmp_path / name).exists()
    from harness.config import load_config
    from harness.errors import ConfigError
    tune = {**SMALL, "tasks": {"smoothing": {"methods": ["scratch.explicit"]}},
            "tune": {"metric": "ev_rms", "train": ["woody"], "budget": 1000,
                     "params": {"scratch.explicit": {"step": [0.01 * i for i in range(1, 101)],
                                                     "iterations": list(range(1, 101))}}},
            "noise": [{"model": "gaussian_normal", "levels": [0.1, 0.2, 0.3]}] * 40}
    with pytest.raises(ConfigError, match="training grid expands to"):
        load_config(tune)
    with pytest.raises(ConfigError) as err:                     # with the config's other problems
        load_config({**tune, "hausdorff_samples": -1})
    assert "training grid expands to" in str(err.value) and "hausdorff_samples" in str(err.value)
    huge = {**tune, "noise": [{"model": "gaussian_normal", "levels": [0.3]}],
            "tune": {**tune["tune"], "budget": 5, "params": {"scratch.explicit": {
                "step": [0.001 * i for i in range(1, 1001)], "iterations": list(range(1, 1001)),
                "self_weight": [0.001 * i for i in range(1000)], "boundary": ["free", "fixed", "curve"]}}}}
    cfg = load_config(huge)
    assert 2 <= len(cfg.tune.cases) <= 5


def test_views_rebuild_from_another_directory_and_out_that_cannot_be_made(tmp_path):
    """`shootout views` finds a config's relative mesh files from any working directory (they
    resolve where the run's config was), and an --out that cannot be made is exit 2 with a
    message, not a traceback."""
    proj = tmp_path / "proj"
    (proj / "meshes").mkdir(parents=True)
    shutil.copy(ROOT / "harness/data/meshes/woody.obj", proj / "meshes" / "scan.obj")
    cfg = write_cfg(proj / "c.yaml", {**SMALL, "meshes": [{"file": "meshes/scan.obj"}]})
    assert cli(["run", "c.yaml", "--out", tmp_path / "o"], cwd=proj).returncode == 0
    (tmp_path / "elsewhere").mkdir()
    r = cli(["views", tmp_path / "o"], cwd=tmp_path / "elsewhere")
    assert r.returncode == 0, r.stderr
    r = cli(["run", cfg, "--out", "/proc/no-such-folder/o"])
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert "cannot make this folder" in r.stderr or "not writable" in r.stderr, r.stderr


def test_the_python_api_checks_what_the_cli_checks(tmp_path):
    """harness.run refuses what the CLI refuses, before writing anything (a timeout of -1 made
    every case a 'timeout' row; an unknown executor ran locally); load_run of a missing folder
    is an error, not an empty table; a config file that is not UTF-8 is a config error."""
    import harness
    from harness.errors import ConfigError, ShootoutError
    for kw in ({"timeout": -1}, {"timeout": 0}, {"timeout": float("nan")}, {"executor": "bogus"},
               {"workers": -2}, {"workers": 1.5}, {"executor": "dask"}):
        with pytest.raises(ShootoutError):
            harness.run(SMALL, out=tmp_path / "o", **kw)
        assert not (tmp_path / "o").exists()
    with pytest.raises(ShootoutError, match="no such run folder"):
        harness.load_run(tmp_path / "typo")
    bad = tmp_path / "latin1.yaml"
    bad.write_bytes("name: caf\xe9\n".encode("latin-1"))
    with pytest.raises(ConfigError, match="not valid YAML"):
        harness.run(str(bad), out=tmp_path / "o")


def test_a_rerun_removes_only_its_own_temporaries(tmp_path):
    """Leftover temporaries are removed only in `atomic_write`'s exact form (``.<name>.<8
    characters>.tmp``): a user's ``.report.html.orig.tmp`` beside a run survives a rerun."""
    cfg = write_cfg(tmp_path / "c.yaml", SMALL)
    out = tmp_path / "o"
    assert cli(["run", cfg, "--out", out]).returncode == 0
    (out / ".report.html.orig.tmp").write_text("mine")
    (out / ".run.json.abcd1234.tmp").write_text("a leftover of ours")
    assert cli(["run", cfg, "--out", out]).returncode == 0
    assert (out / ".report.html.orig.tmp").read_text() == "mine" and not (out / ".run.json.abcd1234.tmp").exists()


@pytest.mark.parametrize("status", ["interrupted", "finished"])
def test_the_in_place_status_of_a_full_disk_keeps_run_json_valid(tmp_path, status):
    """When a full disk refuses a new run.json, the status is written over the running one in
    place; 'interrupted' and 'finished' are longer than 'running', and the cut-off write left
    '"status": "interrup' (invalid JSON: neither --resume nor a fresh run would take the folder)."""
    from harness.results import RunFolder
    from harness.session import _write_status_in_place
    folder = RunFolder(tmp_path)
    folder.write_run_json({"name": "x", "status": "running", "config_hash": "abc", "n_cases": 3})
    _write_status_in_place(folder, status)
    meta = json.loads(folder.run_json.read_text())
    assert meta == {"name": "x", "status": status, "config_hash": "abc", "n_cases": 3}


def test_a_report_that_cannot_be_written_is_exit_1_not_a_path_to_a_stale_one(tmp_path, monkeypatch, capsys):
    """The rows are whole, but when report.html cannot be rebuilt (here: the disk refuses it) the
    run said 'report: <path>' of the previous, stale report and exited 0."""
    import errno

    import harness.report
    from harness.cli import main
    cfg = write_cfg(tmp_path / "c.yaml", SMALL)

    def full(run_dir):
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(harness.report, "build_report", full)
    assert main(["run", str(cfg), "--out", str(tmp_path / "o"), "--quiet"]) == 1
    out = capsys.readouterr()
    assert "not written: report.html could not be built" in out.out and "report: " not in out.out, out
    assert "No space left on device" in out.err
    assert len(pd.read_csv(tmp_path / "o" / "smoothing.csv")) > 0
    import harness                       # the Python API says the same, per call
    frames = harness.run(str(cfg), out=str(tmp_path / "o"), resume=True, quiet=True)
    assert frames.not_written == ["report.html could not be built"] and len(frames["smoothing"]) > 0
    monkeypatch.undo()
    assert harness.run(str(cfg), out=str(tmp_path / "o"), resume=True, quiet=True).not_written == []


def test_a_full_disk_while_resume_rewrites_the_csvs_is_the_disk_full_message(tmp_path, monkeypatch, capsys):
    """--resume first rewrites each CSV with its ok rows (and drops rows whose saved mesh is torn);
    a full disk there was an OSError traceback."""
    import errno

    import harness.results
    from harness.cli import main
    cfg = write_cfg(tmp_path / "c.yaml", {**SMALL, "save_meshes": True})
    out = tmp_path / "o"
    assert main(["run", str(cfg), "--out", str(out), "--quiet"]) == 0
    before = (out / "smoothing.csv").read_bytes()
    real = harness.results.atomic_write

    def full(path, write):
        if str(path).endswith(".csv"):
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(path, write)
    monkeypatch.setattr(harness.results, "atomic_write", full)
    capsys.readouterr()
    assert main(["run", str(cfg), "--out", str(out), "--resume", "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "disk is full" in err and "Traceback" not in err, err
    assert (out / "smoothing.csv").read_bytes() == before


def test_compare_refuses_a_folder_with_a_case_id_in_two_rows(tmp_path):
    """Which of two rows of one id to compare is not decidable: exit 2 naming the id (the last
    row silently won, so a duplicated line with a 10x value decided the verdict)."""
    from harness.cli import main
    cfg = write_cfg(tmp_path / "c.yaml", SMALL)
    out = tmp_path / "o"
    assert main(["run", str(cfg), "--out", str(out), "--quiet"]) == 0
    p = out / "smoothing.csv"
    lines = p.read_text().splitlines(keepends=True)
    p.write_text("".join(lines) + lines[1])
    assert main(["compare", str(out), str(out), "--no-time"]) == 2


def test_a_hand_edited_run_json_of_wrong_types_is_read_without_a_traceback(tmp_path):
    """`machine: "x"`, `tasks: []`, `load_average: 5`, `sessions: 5`, a session's `wall_s: "12.5"`
    and the like made report, compare and --resume crash (54 of 696 single-value edits of a
    run.json did, in report or compare); a value of the wrong type now reads as missing."""
    import copy
    import io

    import harness
    from harness.compare import compare_runs
    from harness.report import build_report
    base = tmp_path / "base"
    cfg = {**SMALL, "tasks": {"smoothing": {"methods": ["scratch.explicit"]}}}
    harness.run(cfg, out=base, workers=1)
    meta0 = json.loads((base / "run.json").read_text())
    from harness.results import _META_TYPES, _sane
    for k, want in _META_TYPES.items():           # every typed key: a value of another type is left out
        for bad in (5, "x", ["x"], {"a": 1}, True):
            if not isinstance(bad, want) or (isinstance(bad, bool) and want is not bool):
                assert k not in _sane({k: bad}), (k, bad)
    assert _sane({"load_average": [None, 0.5, "x"]})["load_average"] == [None, 0.5, None]   # positions kept
    from harness.report.html import _timing_text
    assert "unknown at the start, 0.50 at the end" in _timing_text({"load_average": [None, 0.5]})
    resumed = {"timing": {"threads_per_case": 1}, "sessions": [     # a review: the header said 1 for every row
        {"threads_per_case": 2, "status_counts": {"ok": 7}}, {"threads_per_case": 1, "status_counts": {"ok": 21}},
        {"threads_per_case": 4, "status_counts": {}}]}
    assert "1 thread(s) per case (BLAS/OpenMP pools and libigl's) in the last session, 2 in earlier ones" \
        in _timing_text(resumed)
    edits = [(("machine",), "x"), (("tasks",), []), (("versions",), "x"), (("workers",), "x"),
             (("load_average",), 5), (("timing",), ["x"]), (("solver", "versions"), 5), (("solver", "used"), "x"), (("solver", "used", "pypardiso"), 5),
             (("solver", "used", "pypardiso"), {"methods": 5, "cases": "x"}),
             (("solver", "used", "pypardiso"), {"methods": "ab", "unknowns_max": None}),
             (("sessions", 0), 5), (("sessions", 0, "wall_s"), "12.5"), (("load_average", 0), "x"),
             (("tasks", "smoothing", "metrics"), 5), (("tasks", "smoothing"), "x")]   # a review: `shootout report`
    d = tmp_path / "d"
    shutil.copytree(base, d)
    for path, bad in edits:
        m = copy.deepcopy(meta0)
        tgt = m
        for p in path[:-1]:
            tgt = tgt[p]
        tgt[path[-1]] = bad
        (d / "run.json").write_text(json.dumps(m))
        try:
            build_report(d)
            compare_runs(base, d, out=io.StringIO())
        except harness.errors.ShootoutError:
            pass
        from harness.cli import main as cli_main
        assert cli_main(["report", str(d)]) in (0, 2), path          # its rankings too (a TypeError, exit 1)
    m = copy.deepcopy(meta0)
    m["sessions"] = [{**m["sessions"][0], "wall_s": "12.5"}, 5]
    (d / "run.json").write_text(json.dumps(m))
    p = d / "smoothing.csv"
    p.write_text("".join(p.read_text().splitlines(keepends=True)[:-1]))
    harness.run(cfg, out=d, workers=1, resume=True)
    after = json.loads((d / "run.json").read_text())
    assert after["status"] == "finished" and len(after["sessions"]) == 2 and after["sessions"][0]["wall_s"] is None


def test_a_file_size_limit_or_full_temporary_files_is_one_message_naming_where(tmp_path):
    """An outside review: ``ulimit -f`` mid-run (EFBIG) was a traceback, and a full TMPDIR (the
    cases' stderr files) was blamed on the run folder's disk."""
    import errno as _errno
    import resource

    from harness.session import _no_room
    cfg = write_cfg(tmp_path / "c.yaml", {**SMALL, "save_meshes": True, "meshes": ["bunny", "knight"]})
    out = tmp_path / "o"
    r = subprocess.run([sys.executable, "-m", "harness.cli", "run", str(cfg), "--out", str(out)], cwd=ROOT,
                       capture_output=True, text=True, timeout=120, env={**os.environ, "PYTHONPATH": str(ROOT)},
                       preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_FSIZE, (60 * 1024, 60 * 1024)))
    assert r.returncode == 1 and "size limit" in r.stderr and "Traceback" not in r.stderr, r.stderr[-800:]
    assert json.loads((out / "run.json").read_text())["status"] == "interrupted"
    assert cli(["run", cfg, "--out", out, "--resume"]).returncode == 0
    first = tmp_path / "first"                        # no room for the first run.json (a review: a traceback)
    r = subprocess.run([sys.executable, "-m", "harness.cli", "run", str(cfg), "--out", str(first)], cwd=ROOT,
                       capture_output=True, text=True, timeout=120, env={**os.environ, "PYTHONPATH": str(ROOT)},
                       preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_FSIZE, (2048, 2048)))
    assert r.returncode == 1 and "size limit" in r.stderr and "then run again" in r.stderr, r.stderr[-800:]
    assert "Traceback" not in r.stderr and not [p.name for p in first.iterdir() if p.name != ".shootout.lock"]
    elsewhere = OSError(_errno.ENOSPC, "No space left on device", "/elsewhere/tmp/shootout-case-x.err")
    msg = _no_room(elsewhere, out)
    assert msg.startswith("/elsewhere/tmp/shootout-case-x.err: the disk is full") and "TMPDIR" in msg
    inside = _no_room(OSError(_errno.ENOSPC, "No space left on device", str(out / "smoothing.csv")), out)
    assert "TMPDIR" not in inside and "disk is full" in inside


def test_a_short_write_leaves_no_part_row_and_a_torn_quoted_row_is_not_kept(tmp_path):
    """An outside review: on a nearly full disk a row holding a multi-line note was written in
    part (``os.write``'s count was not checked) and its torn end, cut after a newline inside the
    quoted note, passed the line-based torn-line check; --resume kept it as an ok case with no
    metrics, never run again. A short write now truncates the file back and raises; the reader
    parses records, so a row cut inside a quoted field, or short of columns, is dropped."""
    from harness.results import RunFolder
    folder = RunFolder(tmp_path / "o")
    row = {"case_id": "abc123", "task": "smoothing", "mesh": "m", "noise_model": "none", "noise_level": 0.0,
           "seed": 0, "method": "scratch.taubin", "library": "scratch", "params": "{}", "status": "ok",
           "error": "the method warned: first line\nsecond line\u2028third\rfourth"}
    folder.append("smoothing", row)
    p = folder.csv_path("smoothing")
    whole = p.read_bytes()
    assert [r["error"] for r in folder.read_rows("smoothing")] == [row["error"]]
    cut = whole.index(b"second line")                           # just after the newline inside the note
    for end in (cut, cut + 3, len(whole) - 1):
        p.write_bytes(whole + whole[whole.index(b"\n") + 1:][: end - whole.index(b"\n") - 1])
        assert [r["case_id"] for r in folder.read_rows("smoothing")] == ["abc123"], end
    short = whole.decode().splitlines(keepends=True)
    p.write_text(short[0] + "def456,smoothing,m\n" + "".join(short[1:]))     # a row short of columns
    assert [r["case_id"] for r in folder.read_rows("smoothing")] == ["abc123"]
    import csv
    p.write_text(short[0] + '"' + "x" * 200_000 + '"\n' + "".join(short[1:]))  # damaged within: said, not dropped
    with pytest.raises(csv.Error, match="field larger"):
        folder.read_rows("smoothing")
    p.write_bytes(whole)
    big = {**row, "case_id": "def456", "error": "x" * 20000}
    code = ("import resource, sys\n"
            "from harness.results import RunFolder\n"
            f"resource.setrlimit(resource.RLIMIT_FSIZE, ({len(whole) + 4096}, {len(whole) + 4096}))\n"
            "try:\n"
            f"    RunFolder(sys.argv[1]).append('smoothing', {big!r})\n"
            "except OSError as e:\n"
            "    print('raised', e.errno)\n")
    r = subprocess.run([sys.executable, "-c", code, str(folder.path)], cwd=ROOT, capture_output=True, text=True,
                       timeout=60, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert r.stdout.startswith("raised"), (r.stdout, r.stderr[-500:])
    assert p.read_bytes() == whole                              # nothing of the new row is left


def test_a_csv_that_cannot_be_written_interrupts_the_run_with_a_message(tmp_path, monkeypatch):
    """An outside review: a folder put in place of smoothing.csv mid-run was two chained
    tracebacks (the write, then the status count of the unreadable CSV) and run.json stayed
    'running'. It is a message naming the file (exit 1), run.json 'interrupted', and the run
    resumes once mended; `shootout report` where report.html cannot be replaced is a message too."""
    import harness
    from harness.errors import RunInterrupted
    from harness.results import RunFolder
    out = tmp_path / "o"
    real = RunFolder.append
    seen = []

    def append(self, task, row):
        seen.append(row["case_id"])
        if len(seen) == 2:                      # the second row: the CSV is a folder now
            p = self.csv_path(task)
            p.rename(p.with_name("moved.csv"))
            p.mkdir()
        return real(self, task, row)
    monkeypatch.setattr(RunFolder, "append", append)
    with pytest.raises(RunInterrupted, match="smoothing.csv: Is a directory: the run could not write its files"):
        harness.run({**SMALL, "name": "x"}, out=out, quiet=True, workers=1)
    assert json.loads((out / "run.json").read_text())["status"] == "interrupted"
    monkeypatch.setattr(RunFolder, "append", real)
    (out / "smoothing.csv").rmdir()
    (out / "moved.csv").rename(out / "smoothing.csv")
    harness.run({**SMALL, "name": "x"}, out=out, quiet=True, workers=1, resume=True)
    assert json.loads((out / "run.json").read_text())["status"] == "finished"
    assert len(pd.read_csv(out / "smoothing.csv")) == 2
    def reset(self, task, row):             # not a file of the run (a review): no misleading message
        raise ConnectionResetError("peer gone")
    monkeypatch.setattr(RunFolder, "append", reset)
    with pytest.raises(ConnectionResetError):
        harness.run({**SMALL, "name": "x"}, out=tmp_path / "o2", quiet=True, workers=1)
    assert json.loads((tmp_path / "o2" / "run.json").read_text())["status"] == "interrupted"
    monkeypatch.setattr(RunFolder, "append", real)
    (out / "report.html").unlink()
    (out / "report.html").mkdir()
    (out / "report.html" / "keep").write_text("x")
    r = cli(["report", out])
    assert r.returncode == 1 and "Traceback" not in r.stderr and "report.html" in r.stderr, r.stderr[-600:]


def test_a_carriage_return_in_a_label_survives_every_csv_the_run_writes(tmp_path):
    """A review of plan.csv: a bare \\r in a mesh label (a file name may hold one) was written
    unquoted, so readers split the row there: plan.csv, and the task CSVs before it, were then
    'damaged'. Rows holding one are quoted whole, and readers keep the \\r."""
    from harness.results import RunFolder, load_csv
    folder = RunFolder(tmp_path / "o")
    row = {"case_id": "abc123", "task": "smoothing", "mesh": "cr\rmesh, \"q\"", "noise_model": "none",
           "noise_level": 0.0, "seed": 0, "method": "scratch.taubin", "library": "scratch", "params": "{}",
           "status": "ok", "error": ""}
    folder.append("smoothing", row)
    folder.append("smoothing", {**row, "case_id": "def456", "mesh": "plain"})
    assert load_csv(folder.csv_path("smoothing"))["mesh"].tolist() == [row["mesh"], "plain"]
    assert folder.keep_ok_rows() == {"abc123", "def456"}                     # rewritten, still whole
    assert load_csv(folder.csv_path("smoothing"))["mesh"].tolist() == [row["mesh"], "plain"]
    folder.write_plan([row])
    assert [r["mesh"] for r in folder.read_plan()] == [row["mesh"]]


def test_an_empty_out_is_refused_not_taken_for_the_default(tmp_path, capsys, monkeypatch):
    """An outside review: ``--out ""`` ran into results/<name> (run) or the current folder (eval)."""
    from harness.cli import main
    monkeypatch.chdir(tmp_path)
    cfg = write_cfg(tmp_path / "c.yaml", SMALL)
    bunny = str(ROOT / "harness" / "data" / "meshes" / "bunny.obj")
    assert main(["run", str(cfg), "--out", "", "--workers", "0"]) == 2
    err = capsys.readouterr().err
    assert "--out: an empty path" in err and "--workers" in err              # with the other problems
    assert main(["eval", bunny, "--clean", bunny, "--out", " "]) == 2
    assert "--out: an empty path" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.yaml"]


@pytest.mark.parametrize("threaded", [False, True])
def test_plugin_import_is_tried_in_a_child_that_takes_what_it_started(tmp_path, monkeypatch, threaded):
    """`harness.plugins.import_problems`: modules are tried in order, each failure named (one that
    ends the trial process does not hide the ones after it), a clean module is not reported, and
    what an import started (here a `sleep` it spawned) is killed with the trial's process group.
    With another thread running (a notebook's, a Dask worker's) the trial is a fresh interpreter,
    not a fork (a fork copies an import lock that thread may hold: the trial hung). A module fixed
    since is tried again (a failure is not remembered for the life of the process)."""
    import subprocess
    import threading

    from harness import plugins, trial
    mark = tmp_path / "pid"
    (tmp_path / "probe_spawn.py").write_text(
        "import subprocess\np = subprocess.Popen(['sleep', '300'])\n"
        f"open({str(mark)!r}, 'w').write(str(p.pid))\n")
    (tmp_path / "probe_exit.py").write_text("import os\nos._exit(3)\n")
    (tmp_path / "probe_raise.py").write_text("raise ValueError('nope')\n")
    (tmp_path / "probe_ok.py").write_text(f"import sys\nopen({str(tmp_path / 'argv')!r}, 'w').write(sys.argv[0])\n")
    (tmp_path / "probe_86.py").write_text("import os\nos._exit(86)\n")            # the code of a lost record pipe
    (tmp_path / "probe_closer.py").write_text("import os\nos.closerange(3, 65536)\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(trial, "ENDED", {})
    stop = threading.Event()
    other = threading.Thread(target=stop.wait, daemon=True)
    if threaded:
        other.start()
    fresh = threading.active_count() > 1          # (earlier tests of the session may have left threads)
    try:
        found = plugins.import_problems(["probe_spawn", "probe_exit", "probe_raise", "probe_ok"])
        assert found == {"probe_exit": "importing it ended the process (exit status 3)",
                         "probe_raise": "ValueError: nope"}, found
        assert trial.ENDED == {"probe_exit": "importing it ended the process (exit status 3)"}
        pid = int(mark.read_text())
        gone = subprocess.run(["ps", "-o", "stat=", "-p", str(pid)], capture_output=True, text=True).stdout.strip()
        assert gone in ("", "Z"), gone                       # killed (a zombie until init reaps it)
        assert "probe_spawn" not in sys.modules and "probe_ok" not in sys.modules   # tried, not imported here
        assert (tmp_path / "argv").read_text().endswith("trial.py") == fresh   # a fresh interpreter, or a fork
        assert fresh or not threaded
        (tmp_path / "probe_exit.py").write_text("X = 2\n")                         # fixed
        assert plugins.import_problems(["probe_exit"]) == {} and trial.ENDED == {}
        # a second review: os._exit(86) passed as a lost pipe, and a module after one that closed it went untried;
        # the two cannot be told apart from the exit status, so the message names both
        lost = "importing it closed the files the process had open, or ended the process with exit status 86"
        assert plugins.import_problems(["probe_86", "probe_closer", "probe_exit", "probe_raise"]) == {
            "probe_86": lost, "probe_closer": lost, "probe_raise": "ValueError: nope"}
    finally:
        stop.set()


def test_a_torn_last_row_holding_a_form_feed_is_dropped_whole(tmp_path):
    """Only the part after a form feed (or \\x0b, \\x1c, \\x85, \\u2028: str.splitlines breaks lines
    there) was dropped as torn, so the rest made the folder a 'damaged CSV' for report and compare."""
    from harness.results import _checked_csv_text
    good = 'case_id,status,error\nabc,ok,"line one\x0cline two"\n'
    for sep in ("\x0c", "\x0b", "\x1c", "\x85", "\u2028"):
        p = tmp_path / "t.csv"
        p.write_text(good + f'def,error,"warning: line one{sep}line two, and mor', encoding="utf-8")
        assert _checked_csv_text(p) == good, repr(sep)


def test_a_plugin_trial_in_a_process_that_ignores_sigchld(tmp_path, monkeypatch):
    """A review: with SIGCHLD ignored the system reaps the trial itself, and waiting for it raised
    ChildProcessError out of load_config. The failing module is still named."""
    import signal

    from harness import plugins, trial
    (tmp_path / "probe_sigchld_exit.py").write_text("import os\nos._exit(3)\n")
    (tmp_path / "probe_sigchld_raise.py").write_text("raise ValueError('nope')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(trial, "ENDED", {})
    old = signal.signal(signal.SIGCHLD, signal.SIG_IGN)
    try:
        found = plugins.import_problems(["probe_sigchld_exit", "probe_sigchld_raise"])
    finally:
        signal.signal(signal.SIGCHLD, old)
    assert found["probe_sigchld_exit"].startswith("importing it ended the process (exit status"), found
    assert found["probe_sigchld_raise"] == "ValueError: nope"


def test_a_plugin_that_sends_itself_sigterm_is_named_in_a_forked_trial(tmp_path):
    """A review: the forked trial kept the caller's SIGTERM handler (the interrupt flag), so the
    signal became a KeyboardInterrupt, no failure; the real import then ended the run (130) and
    every other plugin problem of the config went unsaid. (In a process of its own: this one may
    run other threads, which make the trial a fresh interpreter.)"""
    (tmp_path / "probe_termed.py").write_text("import os, signal\nos.kill(os.getpid(), signal.SIGTERM)\n")
    code = ("import signal, sys, threading\nsys.path.insert(0, sys.argv[1])\n"
            "signal.signal(signal.SIGTERM, lambda *_: (_ for _ in ()).throw(KeyboardInterrupt()))\n"
            "from harness import plugins\nassert threading.active_count() == 1\n"
            "print(plugins.import_problems(['probe_termed']))\n")
    r = subprocess.run([sys.executable, "-c", code, str(tmp_path)], capture_output=True, text=True, cwd=ROOT,
                       timeout=120, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert r.stdout.strip() == "{'probe_termed': 'importing it killed the process (SIGTERM)'}", r.stdout + r.stderr


def test_a_plugin_that_changes_the_working_folder_at_import_moves_no_path_of_the_run(tmp_path):
    """A review: a plugin calling os.chdir at import moved the run folder of a relative --out
    (made after the plugins were imported) to wherever the plugin went."""
    work, away = tmp_path / "work", tmp_path / "away"
    work.mkdir()
    away.mkdir()
    (tmp_path / "cdplug.py").write_text(f"import os\nos.chdir({str(away)!r})\n")
    cfg = write_cfg(work / "c.json", {**SMALL, "name": "cd", "plugins": ["cdplug"],
                                      "tasks": {"smoothing": {"methods": ["scratch.taubin"]}}})
    r = cli(["run", cfg, "--out", "myrun", "--workers", "1", "--quiet"], cwd=work,
            PYTHONPATH=f"{ROOT}{os.pathsep}{tmp_path}")
    assert r.returncode == 0, r.stderr
    assert (work / "myrun" / "smoothing.csv").is_file() and list(away.iterdir()) == []


def test_a_config_path_that_is_not_utf8_still_gets_its_report(tmp_path):
    """A review: run.json keeps the command line, whose undecodable byte (a lone surrogate) the
    page embeds, so report.html could not be written and `shootout report` ended in a traceback."""
    cfg = write_cfg(tmp_path / "tiny\udcff.json", {**SMALL, "name": "u8", "tasks": {
        "smoothing": {"methods": ["scratch.taubin"]}}})
    r = cli(["run", cfg, "--out", tmp_path / "o", "--workers", "1", "--quiet"])
    assert r.returncode == 0 and "could not be built" not in r.stderr, r.stderr
    page = (tmp_path / "o" / "report.html").read_text(encoding="utf-8")
    assert "tiny\\udcff.json" in page
    r = cli(["report", tmp_path / "o"])
    assert r.returncode == 0, r.stderr
