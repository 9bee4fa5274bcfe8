"""report.html from a real (tiny) run: content, self-containment, rebuild via `shootout report`,
3D views recomputed from run.json, and the failure paths (the page says why, it never crashes)."""
from __future__ import annotations

import base64
import csv
import json
import re
import shutil
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import harness
from harness.cli import main as cli
from harness.mesh import write_obj
from harness.results import load_csv
from harness.report import build_report
from harness.report import html as rh



@pytest.fixture(scope="module")
def run_dir(tiny_run):
    return tiny_run


def page_data(path) -> dict:
    text = path.read_text()
    m = re.search(r"<script type='application/json' id='report-data'>(.*?)</script>", text, re.S)
    assert m, "the report has no inline data block"
    return json.loads(m.group(1).replace("<\\/", "</"))


def copy_run(run_dir, tmp_path):
    dst = tmp_path / "run"
    shutil.copytree(run_dir, dst)
    (dst / "report.html").unlink()
    return dst


def rewrite_csv(path, edit):
    rows = list(csv.DictReader(path.open()))
    fields = list(rows[0])
    edit(rows)
    with path.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


def test_report_is_self_contained_and_small(run_dir):
    path = run_dir / "report.html"
    text = path.read_text()
    assert path.stat().st_size < 5_000_000
    # no external resource of any kind: scripts and styles are inline, nothing is fetched
    assert not re.search(r"<script[^>]*\ssrc=", text)
    assert "<link" not in text and "@import" not in text
    assert not re.search(r"url\(\s*['\"]?(https?:)?//", text)
    assert not re.search(r"""(src|href)=['"]?(https?:)?//""", text)
    for sid in ("overview", "task-laplacian", "task-smoothing", "task-simplification", "views"):
        assert f"id='{sid}'" in text
    assert "Cases by status" in text and "config (" in text


def test_the_header_states_the_timing_protocol_of_run_json(run_dir):
    meta = json.loads((run_dir / "run.json").read_text())
    text = (run_dir / "report.html").read_text()
    row = re.search(r"<th>timing protocol</th><td>(.*?)</td>", text)
    assert row, "the report does not state how it timed"
    t, fc = meta["timing"], meta["fixed_cost_per_case_s"]
    assert f"{t['threads_per_case']} thread(s) per case" in row.group(1)
    assert f"at least {t['min_repeats']} " in row.group(1)
    assert f"load average {meta['load_average'][0]:.2f} at the start" in row.group(1)
    assert f"fixed cost per case {rh._fmt(fc['mean'])} s mean" in row.group(1)
    import pandas as pd                   # the load the timed calls saw, beside the load average
    busy = pd.concat([pd.read_csv(p)["others_cpu"] for p in run_dir.glob("*.csv")
                      if "others_cpu" in pd.read_csv(p, nrows=0).columns]).dropna()
    if len(busy):
        assert f"other processes kept {busy.median():.2g} cores busy in the median case" in row.group(1), row.group(1)
    said = rh._others_text({"a": pd.DataFrame({"others_cpu": [0.1, 1.3, None]}),
                            "b": pd.DataFrame({"others_cpu": ["0.2"]}), "c": pd.DataFrame({"x": [1]})})
    assert said.startswith("other processes kept 0.2 cores busy in the median case (max 1.3)") and "3 case(s)" in said


def test_a_method_run_only_away_from_its_defaults_is_labelled_so(tmp_path):
    """A label without a parameter means that parameter's default: `scratch.taubin` run only with
    `iterations: 3` used to be labelled plain "scratch.taubin" in the report, the leaderboard and
    the winners, a number a reader would take for the default's. The report's tables, its
    property matrix, the leaderboard and the winners write one label alike."""
    cfg = {"name": "labels", "time_budget": 0, "hausdorff_samples": 200, "meshes": ["knight", "woody"],
           "noise": [{"model": "gaussian_normal", "levels": [0.2]}],
           "tasks": {"smoothing": {"methods": [{"name": "scratch.taubin", "params": {"iterations": 3}},
                                               {"name": "scratch.explicit", "params": {"step": 0.25,
                                                                                       "weights": "cotan"}}]},
                     "laplacian": {"methods": [{"name": "libigl.cotan", "params": {"mass": "barycentric"}},
                                               "scratch.cotan"]}}}
    out = tmp_path / "r"
    harness.run(cfg, out=out, quiet=True)
    want = {"scratch.taubin iterations=3", "scratch.explicit weights=cotan"}      # 0.25 is explicit's default step
    assert set(page_data(out / "report.html")["tasks"]["smoothing"]["variants"]) == want
    board = pd.read_csv(out / "leaderboard.csv")
    assert set(board[board.task == "smoothing"]["method"]) == want
    winners = pd.read_csv(out / "winners.csv")
    assert set(winners[winners.task == "smoothing"]["best"]) <= want
    lap = {"libigl.cotan mass=barycentric", "scratch.cotan"}
    assert set(page_data(out / "report.html")["tasks"]["laplacian"]["variants"]) == lap
    matrix = (out / "report.html").read_text().split("Property matrix", 1)[1].split("</table>", 1)[0]
    assert "libigl.cotan mass=barycentric" in matrix and "scratch.cotan" in matrix
    meta = json.loads((out / "run.json").read_text())
    assert meta["tasks"]["smoothing"]["method_defaults"]["scratch.taubin"]["iterations"] == 10


def test_page_data_matches_the_csvs(run_dir):
    d = page_data(run_dir / "report.html")
    for task in ("laplacian", "smoothing", "simplification"):
        with (run_dir / f"{task}.csv").open() as fh:
            n = sum(1 for _ in csv.DictReader(fh))
        assert len(d["tasks"][task]["rows"]) == n == 12
    assert d["tasks"]["smoothing"]["variants"] == ["scratch.explicit iterations=2", "scratch.explicit iterations=6"]
    # the simplification target is a plot axis, not part of the method's name
    assert d["tasks"]["simplification"]["variants"] == ["fast_simplification.qem"]
    cols = d["tasks"]["smoothing"]["columns"]
    hist = [r[cols.index("_hist")] for r in d["tasks"]["smoothing"]["rows"]]
    assert all(len(h) == 12 for h in hist)                     # 5-degree bins over [0, 60]
    faces = [r[cols.index("n_faces")] for r in d["tasks"]["smoothing"]["rows"]]
    assert [sum(h) for h in hist] == faces                     # one count per face


def test_property_matrix_and_uniform_note(run_dir):
    df = load_csv(run_dir / "laplacian.csv")
    from harness.report.laplacian import property_matrix
    mat = {e["variant"]: e["props"] for e in property_matrix(df)}
    cot, uni = mat["scratch.cotan"], mat["scratch.uniform"]
    # LIN is measured only on the exactly planar input (plane_nondelaunay, noise none): 1 row each
    assert cot["LIN"]["measured"] == 1 and cot["LIN"]["fails"] == 0 and cot["LIN"]["worst"] < 1e-9
    assert uni["LIN"]["measured"] == 1 and uni["LIN"]["fails"] == 1 and uni["LIN"]["worst"] > 1e-6
    assert cot["SYM"]["fails"] == uni["SYM"]["fails"] == 0
    assert uni["POS"]["fails"] == 0 and cot["POS"]["fails"] >= 1          # non-Delaunay plane: negative cotans
    assert "plane_nondelaunay(n_points=120)" in cot["POS"]["fail_meshes"]
    text = (run_dir / "report.html").read_text()
    assert "Delaunay triangulations without obtuse boundary angles" in text and "D = diag(1/N" in text
    lin = df[(df.method == "scratch.uniform") & df.lin_error.notna()].lin_error.iloc[0]
    assert f"lin_error = {rh._fmt(lin)}" in text                          # the numbers come from the row
    worst_loc = int(max(p["LOC"]["worst"] for p in mat.values() if p["LOC"]["worst"] is not None))
    assert f"max {worst_loc}</span>" in text                                # a count, not 2.14e+03
    assert "not that its symmetric part is semi-definite" in text


def test_views_computed_by_the_session_and_stored_in_the_run_folder(run_dir):
    d = page_data(run_dir / "report.html")
    views = d["views"]
    index = json.loads((run_dir / "views" / "index.json").read_text())["views"]
    assert [e["case_id"] for e in index] == [v["case_id"] for v in views]
    assert [v["why"].split()[0] for v in views] == ["best", "worst", "best", "worst"]
    for v in views:
        assert "error" not in v, v.get("error")
        assert "mismatch" not in v
        assert [m["label"] for m in v["meshes"]][0] == "clean" and len(v["meshes"]) == 3
        for m in v["meshes"]:
            V = np.frombuffer(base64.b64decode(m["V"]), "<u2")
            F = np.frombuffer(base64.b64decode(m["F"]), "<u4")
            assert V.size == 3 * m["nv"] and F.size == 3 * m["nf"] and F.max() < m["nv"]
            if "e" in m:
                assert np.frombuffer(base64.b64decode(m["e"]), np.uint8).size == m["nv"]


def test_decimation_for_display_only():
    from harness import datasets
    from harness.views import _decimate
    mesh = datasets.load("bunny").clean
    err = np.linalg.norm(mesh.V, axis=1)
    V, F, e, note = _decimate(mesh.V, mesh.F, err, 2000)
    assert len(F) <= 2000 * 1.01 and len(e) == len(V) and "decimated" in note
    assert _decimate(mesh.V, mesh.F, err, 10**6)[3] is None


def test_shootout_report_rebuilds(run_dir, tmp_path):
    dst = copy_run(run_dir, tmp_path)
    assert cli(["report", str(dst)]) == 0
    assert page_data(dst / "report.html")["tasks"].keys() == {"laplacian", "smoothing", "simplification"}
    empty = tmp_path / "empty"
    empty.mkdir()
    assert cli(["report", str(empty)]) == 2


def test_views_chosen_in_the_config_and_their_errors(run_dir, tmp_path):
    dst = copy_run(run_dir, tmp_path)
    lap = next(csv.DictReader((dst / "laplacian.csv").open()))["case_id"]
    smo = next(csv.DictReader((dst / "smoothing.csv").open()))
    meta = json.loads((dst / "run.json").read_text())
    meta["config"]["report"] = {"views": [smo["case_id"], lap, "000000000000"]}
    (dst / "run.json").write_text(json.dumps(meta))
    assert cli(["views", str(dst)]) == 0                              # explicit: runs the methods again
    views = page_data(dst / "report.html")["views"]
    assert [v["case_id"] for v in views] == [smo["case_id"], lap, "000000000000"]
    assert "error" not in views[0] and views[0]["why"].startswith("chosen in the config")
    assert "no mesh to show" in views[1]["error"]
    assert "not in this run" in views[2]["error"]      # rebuilt from run.json: an id no longer a case (a run
    from harness.config import load_config            # refuses it up front)
    with pytest.raises(harness.errors.ConfigError, match="report.views"):
        load_config(meta["config"])


def test_views_of_a_changed_file_are_kept_and_a_users_files_in_views_stay(tmp_path, capsys):
    """`shootout views` after a mesh file changed replaced the run's views with stubs saying the
    case 'is not among the run's cases'; and it deleted every *.json in views/, the user's too."""
    from harness import datasets
    s = datasets.load({"procedural": "sphere", "subdivisions": 2}).clean
    mesh = tmp_path / "kn.obj"
    write_obj(mesh, s.V, s.F)
    out = tmp_path / "o"
    harness.run({"name": "v", "time_budget": 0, "hausdorff_samples": 200, "meshes": [{"file": str(mesh)}],
                 "noise": [{"model": "gaussian_normal", "levels": [0.3]}],
                 "tasks": {"smoothing": {"methods": ["scratch.taubin"]}}}, out=out)
    before = page_data(out / "report.html")["views"]
    assert before and not any(v.get("error") for v in before)
    mine = ("camera.json", "notes.json", "2024-notes.json", "10.json")     # names like the views' own too
    for name in mine:
        (out / "views" / name).write_text("{}")
    with mesh.open("a") as fh:
        fh.write("# re-saved\n")
    assert cli(["views", str(out)]) == 0
    assert "kept as the run made them" in capsys.readouterr().out
    after = page_data(out / "report.html")["views"]
    assert [v["case_id"] for v in after] == [v["case_id"] for v in before]
    assert all(not v.get("error") and "sha1" in v["kept"] and v.get("meshes") for v in after), after
    assert all((out / "views" / name).exists() for name in mine)
    index = json.loads((out / "views" / "index.json").read_text())        # a damaged index names no folder
    index["views"] += [{"file": ".."}, {"file": ""}, {"file": "."}]
    (out / "views" / "index.json").write_text(json.dumps(index))
    harness.run({"name": "v", "time_budget": 0, "hausdorff_samples": 200, "meshes": [{"file": str(mesh)}],
                 "tasks": {"smoothing": {"methods": ["scratch.taubin"]}}}, out=out)       # a fresh run: theirs stay
    assert all((out / "views" / name).exists() for name in mine)


def test_report_reads_files_only_even_when_the_config_no_longer_loads(run_dir, tmp_path, capsys):
    dst = copy_run(run_dir, tmp_path)
    before = page_data(build_report(dst))["views"]
    meta = json.loads((dst / "run.json").read_text())
    meta["config"]["tasks"]["smoothing"]["methods"] = ["nobody.nothing"]
    (dst / "run.json").write_text(json.dumps(meta))

    def fail_two(rows):
        for r in rows[:2]:
            r.update(status="error", error="ValueError: boom at smoothing.py:12")
    rewrite_csv(dst / "smoothing.csv", fail_two)
    path = build_report(dst)
    d = page_data(path)
    assert [v["case_id"] for v in d["views"]] == [v["case_id"] for v in before]     # the stored views
    text = path.read_text()
    assert re.search(r"<td class='st-error'>error</td><td>2</td><td class='msg'>ValueError: boom at smoothing.py:12",
                     text)
    assert cli(["views", str(dst)]) == 2                              # recomputing needs the config
    assert "nobody.nothing" in capsys.readouterr().err


PLUGIN = '''
import os

from methods import register, SmoothingResult


@register("reporttest.crashy", task="smoothing", library="reporttest", params={"iterations": 1})
def crashy(V, F, *, iterations=1):
    """Identity smoothing that aborts its process once the marker file exists (tests the report)."""
    if os.path.exists(os.environ.get("REPORTTEST_CRASH_MARKER", "/nonexistent")):
        import faulthandler
        faulthandler.disable()          # no traceback dump from pytest's handler in the child
        os.abort()
    return SmoothingResult(V=V.copy())
'''


def test_a_method_that_crashes_when_recomputed_costs_only_its_view(tmp_path, monkeypatch, capsys):
    (tmp_path / "reporttest_plugin.py").write_text(PLUGIN)
    monkeypatch.syspath_prepend(str(tmp_path))
    marker = tmp_path / "crash-now"
    monkeypatch.setenv("REPORTTEST_CRASH_MARKER", str(marker))
    cfg = {"name": "crashy", "repeats": 1, "hausdorff_samples": 500, "plugins": ["reporttest_plugin"],
           "meshes": ["knight"], "noise": [{"model": "gaussian_normal", "levels": [0.2]}],
           "tasks": {"smoothing": {"methods": ["reporttest.crashy"]}}}
    out = tmp_path / "run"
    harness.run(cfg, out=out, quiet=True, workers=1)
    views = page_data(out / "report.html")["views"]
    assert len(views) == 1 and "error" not in views[0]              # computed fine when the run finished
    marker.write_text("")
    views = page_data(build_report(out))["views"]                    # the report runs nothing
    assert len(views) == 1 and "error" not in views[0]
    capsys.readouterr()
    assert cli(["views", str(out)]) == 0                             # recomputing: the method aborts
    said = capsys.readouterr().out
    assert "1 view(s) written" in said and "1 of them failed" in said and "SIGABRT" in said, said
    views = page_data(out / "report.html")["views"]
    assert "SIGABRT" in views[0]["error"] and "computing the view failed" in views[0]["error"]


def test_signed_view_values_keep_their_sign():
    """A signed quantity (a saddle's curvature, an eigenvector) is coloured on a scale symmetric
    about 0 with 0 in the middle, not clipped at 0; an unsigned error keeps the 0-based scale."""
    import base64

    from harness.views import pack
    V = np.eye(3)
    F = np.array([[0, 1, 2]])
    p = pack([("a", V, F, np.array([-2.0, 0.0, 2.0]), "K estimated", {"signed": True}),
              ("b", V, F, np.array([0.0, 1.0, 2.0]), "|err|"),
              ("c", V, F, np.array([-0.1, 1.0, 2.0]), "distance, 12 level lines", {"isolines": 12})])
    a, b, c = p["meshes"]
    assert a["signed"] and not b["signed"] and a["eminv"] == -2.0
    assert list(base64.b64decode(a["e"])) == [0, 128, 255]      # -2 -> 0, 0 -> the middle, +2 -> 255
    assert list(base64.b64decode(b["e"]))[0] == 0 and b["escale"] > 0
    # a slightly negative heat distance keeps its 0-based scale and its level lines: signed is opt-in
    assert not c["signed"] and list(base64.b64decode(c["e"])) == [0, 128, 255] and c["isolines"] == 12


def test_rebuilding_an_older_runs_report_says_its_rules_differ(run_dir, tmp_path, capsys):
    """`shootout report` reads files only, so a folder made before a task's axis parameters or
    validity rules changed keeps the recorded ones: it says so, per task; a current run says nothing."""
    from harness.cli import main as cli
    run = copy_run(run_dir, tmp_path)
    assert cli(["report", str(run)]) == 0
    assert "note:" not in capsys.readouterr().err
    meta = json.loads((run / "run.json").read_text())
    meta["tasks"]["smoothing"]["invalid_when"] = []           # as recorded by an older version
    (run / "run.json").write_text(json.dumps(meta))
    assert cli(["report", str(run)]) == 0
    err = capsys.readouterr().err
    assert "note: smoothing: this run ranks by the invalid_when recorded when it ran" in err
    assert "simplification" not in err and "laplacian" not in err


def test_run_json_says_whether_the_code_that_ran_is_its_commit(run_dir, tmp_path):
    """run.json records git_dirty next to git_commit (the benchmark export's commit_info.dirty was
    always null), and a tracked file changed in a checkout turns it True."""
    import subprocess
    from harness.benchmark_json import build
    meta = json.loads((run_dir / "run.json").read_text())
    assert "git_dirty" in meta and build(run_dir)["commit_info"]["dirty"] == meta["git_dirty"]
    root = Path(harness.__file__).resolve().parents[1]
    if subprocess.run(["git", "rev-parse", "HEAD"], cwd=root, capture_output=True).returncode != 0:
        pytest.skip("not a git checkout")
    clone = tmp_path / "clone"                  # a throwaway clone: this checkout is never touched
    subprocess.run(["git", "clone", "-q", "--depth", "1", f"file://{root}", str(clone)], check=True)
    probe = ("import sys; sys.path.insert(0, sys.argv[1]); from harness.provenance import git_dirty; "
             "print(git_dirty())")
    clean = subprocess.run([sys.executable, "-c", probe, str(clone)], capture_output=True, text=True)
    (clone / "README.md").write_text((clone / "README.md").read_text() + "\nedited\n")
    dirty = subprocess.run([sys.executable, "-c", probe, str(clone)], capture_output=True, text=True)
    assert (clean.stdout.strip(), dirty.stdout.strip()) == ("False", "True"), (clean, dirty)


def test_the_cases_an_interrupted_run_never_ran_are_counted_as_not_run(run_dir, tmp_path, capsys):
    """An outside review: the report of an interrupted run said nothing of the cases it never
    reached. run.json's plan gives each a ``not run`` row: in the status table, the rows and
    the data the winner tables use (never in a CSV)."""
    dst = copy_run(run_dir, tmp_path)
    before = len(list(csv.DictReader((dst / "smoothing.csv").open())))
    rewrite_csv(dst / "smoothing.csv", lambda rows: rows.__setitem__(slice(None), rows[:-3]))
    assert cli(["report", str(dst)]) == 0
    data = page_data(dst / "report.html")["tasks"]["smoothing"]
    status = [r[data["columns"].index("status")] for r in data["rows"]]
    assert len(status) == before and status.count("not run") == 3
    html = (dst / "report.html").read_text()
    assert "<th>not run</th>" in html
    assert len(list(csv.DictReader((dst / "smoothing.csv").open()))) == before - 3
    with (dst / "plan.csv").open("a") as fh:           # a hand-edited plan: a message, not a traceback
        fh.write("abc,smoothing,knight,none,,x,scratch.taubin,scratch,{}\n")
    assert cli(["report", str(dst)]) == 2
    err = capsys.readouterr().err
    assert "damaged plan: line" in err and "Traceback" not in err, err


def test_shootout_report_rebuilds_the_rankings_too(tiny_run, tmp_path):
    """An outside review: `shootout report` rebuilt report.html only, so the leaderboard and winners
    of an interrupted run, or ones whose write failed at the end, could not be had without a
    resume. It rewrites them from the files, equal to the run's own."""
    d = tmp_path / "copy"
    shutil.copytree(tiny_run, d)
    names = ["leaderboard.csv", "leaderboard.md", "leaderboard.tex", "winners.csv", "winners.md", "winners.tex"]
    before = {n: (d / n).read_text() for n in names}
    for n in names:
        (d / n).unlink()
    assert cli(["report", str(d)]) == 0
    assert {n: (d / n).read_text() for n in names} == before


def test_the_report_shows_the_run_tasks_in_their_declared_order(tmp_path):
    """An outside review: the report always added sections for laplacian, smoothing and
    simplification ("This run has no laplacian cases" on a smoothing run) and put every other kind
    after them, whatever its declared order."""
    harness.run({"name": "o", "time_budget": 0, "meshes": ["knight"],
                 "tasks": {"spectrum": {"methods": ["scratch.spectrum"], "params": {"k": 6}},
                           "smoothing": {"methods": ["scratch.explicit"]}}}, out=tmp_path / "o", quiet=True, workers=1)
    page = (tmp_path / "o" / "report.html").read_text()
    assert "task-laplacian" not in page and "task-simplification" not in page
    assert page.index("id='task-smoothing'") < page.index("id='task-spectrum'")
    meta = json.loads((tmp_path / "o" / "run.json").read_text())
    meta["tasks"]["spectrum"]["order"] = 1                       # a kind declared first comes first
    (tmp_path / "o" / "run.json").write_text(json.dumps(meta))
    build_report(tmp_path / "o")
    page = (tmp_path / "o" / "report.html").read_text()
    assert page.index("id='task-spectrum'") < page.index("id='task-smoothing'")


def test_the_status_table_counts_zero_as_0_not_a_blank():
    """A review: a status no case had showed an empty cell, which reads as "not counted"."""
    import pandas as pd

    from harness.report.html import _status_html
    html = _status_html({"smoothing": pd.DataFrame({"status": ["ok", "ok", "error"]})})
    assert "<td class='st-ok'>2</td><td class='st-error'>1</td><td class='st-timeout'>0</td>" in html, html


def test_a_view_of_a_diverged_result_fails_alone_and_values_that_are_not_finite_are_left_out():
    """A review: a view whose result had NaN coordinates packed NaN/inf summaries, which the
    view file (JSON) cannot hold, so writing it threw away every view of the run."""
    import json

    import numpy as np

    from harness.views import pack
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    F = np.array([[0, 1, 2]])
    with pytest.raises(ValueError, match="result: coordinates that are not finite"):
        pack([("clean", V, F, None, "d"), ("result", V * np.nan, F, None, "d")])
    got = pack([("result", V, F, np.array([0.5, np.nan, np.inf]), "d")])
    json.dumps(got, allow_nan=False)
    mesh = got["meshes"][0]
    assert mesh["emean"] == mesh["emaxv"] == mesh["eminv"] == 0.5, mesh
    nothing = pack([("result", V, F, np.array([np.nan] * 3), "d")])
    json.dumps(nothing, allow_nan=False)
    assert "e" not in nothing["meshes"][0]
