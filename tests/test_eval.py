"""`shootout eval` and `harness.evaluate`: results made elsewhere get exactly the numbers a run gives."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import harness
import methods
from harness import tasks
from harness.cli import main as cli
from harness.errors import ConfigError, InvalidMeshError
from harness.mesh import read_mesh

PAIR = Path(harness.__file__).parent / "data" / "meshes" / "denoise" / "Fandisk0.3"


@pytest.fixture(scope="module")
def run_with_meshes(tmp_path_factory):
    out = tmp_path_factory.mktemp("evalrun") / "run"
    cfg = {"name": "evalsrc", "save_meshes": True, "hausdorff_samples": 2000, "time_budget": 0,
           "meshes": ["fandisk-noisy-0.3"],
           "tasks": {"smoothing": {"methods": ["scratch.taubin", "scratch.bilateral"]},
                     "simplification": {"methods": ["scratch.qem"], "params": {"target_ratio": 0.2}}}}
    harness.run(cfg, out=out, quiet=True, workers=1)
    return out


@pytest.mark.parametrize("task", ["smoothing", "simplification"])
def test_eval_gives_exactly_the_numbers_of_a_run(run_with_meshes, tmp_path, task):
    rows = pd.read_csv(run_with_meshes / f"{task}.csv")
    files = [run_with_meshes / "meshes" / f"{cid}.ply" for cid in rows["case_id"]]
    noisy = ["--noisy", str(PAIR / "Noisy.obj")]
    out = tmp_path / "eval"
    labels = sum((["--label", m] for m in rows["method"]), [])
    target = ["--target-ratio", "0.2"] if task == "simplification" else []      # the run's
    assert cli(["eval", *map(str, files), "--clean", str(PAIR / "Original.obj"), *noisy, "--out", str(out),
                "--task", task, "--hausdorff-samples", "2000", *labels, *target]) == 0
    ev = pd.read_csv(out / f"{task}.csv")
    assert list(ev["method"]) == list(rows["method"]) and (ev["status"] == "ok").all()
    metrics = list(tasks.get(task).columns)
    pd.testing.assert_frame_equal(ev.set_index("method")[metrics], rows.set_index("method")[metrics],
                                  check_exact=True)
    meta = json.loads((out / "run.json").read_text())
    assert meta["kind"] == "eval" and (out / "report.html").is_file()


def test_evaluate_from_python_and_errors(tmp_path, capsys):
    from harness import datasets
    src = datasets.load("fandisk-noisy-0.3")
    row = harness.evaluate(src.noisy_V, src.clean.F, src.clean.V, src.clean.F, task="smoothing", V_noisy=src.noisy_V)
    assert row["ev_mean"] == pytest.approx(row["input_ev_mean"], rel=1e-12)      # the noisy input scored as a result
    assert harness.evaluate(src.clean.V, src.clean.F, src.clean.V, src.clean.F)["ev_mean"] == 0.0
    (tmp_path / "small.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    code = cli(["eval", str(tmp_path / "small.obj"), "--clean", str(PAIR / "Original.obj"), "--out",
                str(tmp_path / "o"), "--task", "smoothing"])
    row = pd.read_csv(tmp_path / "o" / "smoothing.csv").iloc[0]             # the file's own error row
    assert code == 0 and row["status"] == "error" and "keeps the clean mesh's" in row["error"], row["error"]
    assert cli(["eval", str(tmp_path / "small.obj"), "--clean", str(tmp_path), "--out", str(tmp_path / "p")]) == 2
    assert not (tmp_path / "p").exists() and "is a folder; give a mesh file" in capsys.readouterr().err
    (tmp_path / "looks.obj").mkdir()
    with pytest.raises(InvalidMeshError, match="is a folder; give a mesh file"):
        read_mesh(tmp_path / "looks.obj")


def test_a_results_config_gives_the_same_numbers(run_with_meshes, tmp_path):
    """``shootout run`` on a config with ``results:`` scores files like ``shootout eval`` (the same
    numbers as the run that made them); a bad entry is exit 2 naming every problem, nothing written."""
    import yaml
    rows = pd.read_csv(run_with_meshes / "smoothing.csv")
    cfg = {"name": "scored", "hausdorff_samples": 2000,
           "results": [{"file": str(run_with_meshes / "meshes" / f"{cid}.ply"), "clean": str(PAIR / "Original.obj"),
                        "noisy": str(PAIR / "Noisy.obj"), "label": m, "task": "smoothing"}
                       for cid, m in zip(rows["case_id"], rows["method"])]}
    path = tmp_path / "scored.yaml"
    path.write_text(yaml.safe_dump(cfg))
    assert cli(["run", str(path), "--out", str(tmp_path / "out")]) == 0
    assert harness.run(str(path), out=tmp_path / "out2").not_written == []
    ev = pd.read_csv(tmp_path / "out" / "smoothing.csv")
    metrics = list(tasks.get("smoothing").columns)
    # the rows are in the order the cases finished in (two workers): compared by label
    pd.testing.assert_frame_equal(ev.set_index("method")[metrics].sort_index(),
                                  rows.set_index("method")[metrics].sort_index(), check_exact=True)
    bad = {"results": [{"file": "nope.ply", "clean": str(PAIR / "Original.obj"), "colour": 1}], "tasks_x": 1}
    path.write_text(yaml.safe_dump(bad))
    assert cli(["run", str(path), "--out", str(tmp_path / "bad")]) == 2
    assert not (tmp_path / "bad").exists()
    path.write_text(yaml.safe_dump(cfg))           # flags a results: config cannot honour were ignored
    for flags in (["--resume"], ["--timeout", "5"], ["--export-benchmark-json", str(tmp_path / "b.json")],
                  ["--workers", "2"]):
        assert cli(["run", str(path), "--out", str(tmp_path / "bad"), *flags]) == 2, flags
    assert not (tmp_path / "bad").exists() and not (tmp_path / "b.json").exists()


def test_a_simplified_mesh_on_the_clean_vertex_buffer_is_scored_as_simplification(tmp_path):
    """Half the faces over the clean mesh's own vertices: the vertex count matches the clean mesh,
    but the faces do not, so it is a simplification (it was scored as a perfect smoothing result:
    Hausdorff 0); asked for as smoothing, it is an error."""
    import igl
    from harness import datasets
    m = datasets.load("knight").clean
    igl.write_triangle_mesh(str(tmp_path / "clean.obj"), m.V, m.F)
    igl.write_triangle_mesh(str(tmp_path / "half.obj"), m.V, m.F[: len(m.F) // 2])
    assert cli(["eval", str(tmp_path / "half.obj"), "--clean", str(tmp_path / "clean.obj"),
                "--out", str(tmp_path / "o")]) == 0
    row = pd.read_csv(tmp_path / "o" / "simplification.csv").iloc[0]
    assert row["out_faces"] == len(m.F) // 2 and row["hausdorff"] > 0.01
    assert not (tmp_path / "o" / "smoothing.csv").exists()
    (tmp_path / "torn.obj").write_text("v 0 0 0\nv 1 0\nf 1 2 3\n")
    assert cli(["eval", str(tmp_path / "half.obj"), str(tmp_path / "torn.obj"), str(tmp_path / "clean.obj"),
                "--clean", str(tmp_path / "clean.obj"), "--out", str(tmp_path / "o2"), "--task", "smoothing"]) == 0
    df = pd.read_csv(tmp_path / "o2" / "smoothing.csv")       # each bad file is its own error row
    assert df["status"].tolist() == ["error", "error", "ok"], df[["method", "status", "error"]]
    assert "a smoothing result keeps the clean mesh's faces" in df["error"][0] and "torn" in df["method"][1]
    assert cli(["eval", str(tmp_path / "half.obj"), str(tmp_path / "torn.obj"), "--clean", str(tmp_path / "clean.obj"),
                "--out", str(tmp_path / "o3")]) == 0       # unreadable: filed beside the file scored with it
    assert not (tmp_path / "o3" / "smoothing.csv").exists()
    assert pd.read_csv(tmp_path / "o3" / "simplification.csv")["status"].tolist() == ["ok", "error"]


def test_eval_keeps_a_users_files_and_replaces_a_run_as_a_whole(tmp_path, monkeypatch):
    """eval writes a run folder like a run: into a folder of someone else's files (a CSV with a
    task's name, another tool's run.json) it is refused with exit 2 and nothing changes; into a
    finished run folder it replaces that run as a whole (no rows of the old run left behind); a
    results config's name cannot leave results/; a negative --hausdorff-samples is exit 2."""
    import igl
    from harness import datasets
    m = datasets.load("knight").clean
    igl.write_triangle_mesh(str(tmp_path / "clean.obj"), m.V, m.F)
    igl.write_triangle_mesh(str(tmp_path / "half.obj"), m.V, m.F[: len(m.F) // 2])
    args = ["eval", str(tmp_path / "half.obj"), "--clean", str(tmp_path / "clean.obj"), "--hausdorff-samples", "500"]
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "simplification.csv").write_text("my,data\n1,2\n")
    (mine / "run.json").write_text('{"tool": "other"}')
    before = {p.name: p.read_bytes() for p in mine.iterdir()}
    assert cli([*args, "--out", str(mine)]) == 2
    assert {p.name: p.read_bytes() for p in mine.iterdir()} == before
    run = tmp_path / "run"
    harness.run({"name": "r", "time_budget": 0, "hausdorff_samples": 200, "meshes": ["knight"],
                 "tasks": {"smoothing": {"methods": ["scratch.taubin"]},
                           "simplification": {"methods": ["scratch.qem"], "params": {"target_ratio": 0.5}}}},
                out=run, quiet=True, workers=1)
    assert cli([*args, "--out", str(run)]) == 0
    assert not (run / "smoothing.csv").exists() and len(pd.read_csv(run / "simplification.csv")) == 1
    assert json.loads((run / "run.json").read_text())["kind"] == "eval"
    assert cli([*args[:-2], "--hausdorff-samples", "-5", "--out", str(tmp_path / "neg")]) == 2
    assert not (tmp_path / "neg").exists()
    cfg = tmp_path / "res.yaml"
    cfg.write_text(json.dumps({"name": "../escape", "results": [{"file": str(tmp_path / "half.obj"),
                                                                  "clean": str(tmp_path / "clean.obj")}]}))
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)                    # the default folder would be work/results/../escape
    assert cli(["run", str(cfg)]) == 2 and not (work / "escape").exists() and not (work / "results").exists()


def test_a_result_with_the_clean_counts_but_other_faces_is_not_scored_per_vertex(tmp_path):
    """A smoothing result is scored vertex by vertex against the clean mesh, so it must keep the
    clean mesh's vertex order and faces. The clean mesh saved as binary STL (the reader welds and
    re-sorts its corners: the same counts, another order) scored hausdorff 0.28 and volume_ratio
    0.27 as 'smoothing'; it is an error row, with --task smoothing or without."""
    import struct

    from harness.mesh import read_mesh
    clean = read_mesh(PAIR / "Original.obj")
    tri = clean.V[clean.F]
    body = b"".join(struct.pack("<12fH", 0, 0, 0, *t.ravel(), 0) for t in tri)
    stl = tmp_path / "same.stl"
    stl.write_bytes(b"\0" * 80 + struct.pack("<I", len(tri)) + body)
    again = read_mesh(stl)
    assert (again.n_vertices, again.n_faces) == (clean.n_vertices, clean.n_faces)
    assert not np.array_equal(again.F, clean.F)
    # the clean mesh with its faces listed in reverse order, each from its second corner: the same
    # oriented triangles on the same vertices, scored as the clean mesh itself
    same = tmp_path / "same.obj"
    F2 = clean.F[::-1][:, [1, 2, 0]]
    same.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in clean.V.tolist()) + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F2))
    assert cli(["eval", str(same), "--clean", str(PAIR / "Original.obj"), "--out", str(tmp_path / "same")]) == 0
    row = pd.read_csv(tmp_path / "same" / "smoothing.csv").iloc[0]
    assert row["status"] == "ok" and row["ev_mean"] == 0.0, row["error"]
    for extra in (["--task", "smoothing"], []):
        out = tmp_path / f"o{len(extra)}"
        assert cli(["eval", str(stl), "--clean", str(PAIR / "Original.obj"), "--out", str(out), *extra]) == 0
        row = pd.read_csv(out / "smoothing.csv").iloc[0]
        assert row["status"] == "error" and "other faces" in row["error"], row["error"]


def test_evaluate_refuses_input_it_cannot_score_honestly():
    """harness.evaluate scored a smoothing result with another connectivity (or faces out of
    range) a perfect 0, took NaN noisy coordinates, truncated fractional face indices and let
    hausdorff_samples reach 1e9 (24 GB); each is now a ShootoutError naming the argument."""
    from harness import datasets
    from harness.errors import ShootoutError
    src = datasets.load("fandisk-noisy-0.3")
    V, F = src.clean.V, src.clean.F
    assert harness.evaluate(V, None, V, F)["ev_mean"] == 0.0
    assert harness.evaluate(V, F[::-1][:, [2, 0, 1]], V, F)["ev_mean"] == 0.0     # the same faces, reordered
    bad_noisy = src.noisy_V.copy()
    bad_noisy[3, 1] = np.nan
    for kwargs, needle in (({"F": (F + 1) % len(V)}, "other faces: a smoothing result must keep"),
                           ({"F": F + 1000000}, "F: vertex indices out of range"),
                           ({"F": None, "task": "simplification"}, "F: a simplification result needs its faces"),
                           ({"F": F + 0.5, "task": "simplification"}, "F: expected integer"),
                           ({"F": F, "V_noisy": bad_noisy}, "NaN or inf"),
                           ({"F": F, "hausdorff_samples": 10**9}, "hausdorff_samples"),
                           # scored against the result's own face count; a KeyError for a task name
                           ({"F": F, "task": "simplification", "target_faces": 0}, "target_faces: expected"),
                           ({"F": F, "task": "area"}, "eval scores smoothing and simplification")):
        with pytest.raises(ShootoutError, match=needle):
            harness.evaluate(V, V_clean=V, F_clean=F, **kwargs)


def test_results_named_like_numbers_are_method_names(tmp_path):
    """`shootout eval ... 10.obj 20.obj`: the method column read back as integers, so the report
    crashed (and then the CSV check called the folder it had just written damaged)."""
    from harness import datasets
    from harness.cli import main
    from harness.mesh import write_obj
    s = datasets.load({"procedural": "sphere", "subdivisions": 2}).clean
    write_obj(tmp_path / "clean.obj", s.V, s.F)
    for name, k in (("10", 1.01), ("20", 0.99)):
        write_obj(tmp_path / f"{name}.obj", s.V * k, s.F)
    assert main(["eval", "--clean", str(tmp_path / "clean.obj"), "--out", str(tmp_path / "o"), "--hausdorff-samples",
                 "200", str(tmp_path / "10.obj"), str(tmp_path / "20.obj")]) == 0
    assert main(["report", str(tmp_path / "o")]) == 0
    from harness.results import load_csv
    assert list(load_csv(tmp_path / "o" / "smoothing.csv")["method"]) == ["10", "20"]


def test_a_result_file_with_nan_coordinates_is_scored_as_the_same_arrays_are(tmp_path):
    """Before: `eval` called a smoothing result file holding NaN (a diverged method's output) an
    unreadable file, an error row, while `harness.evaluate` scored the same arrays as
    ``diverged``; a row the leaderboard ranks as invalid, not a failure to read. Now both say
    diverged; a simplification result with NaN is an error row in both, as in a run."""
    from harness.mesh import write_obj
    clean = read_mesh(PAIR / "Original.obj")
    V = clean.V.copy()
    V[7] = np.nan
    write_obj(tmp_path / "nan.obj", V, clean.F)
    assert "nan" in (tmp_path / "nan.obj").read_text()
    row = harness.evaluate(V, clean.F, clean.V, clean.F, task="smoothing")
    assert row["diverged"] is True
    assert cli(["eval", str(tmp_path / "nan.obj"), "--clean", str(PAIR / "Original.obj"), "--out",
                str(tmp_path / "o"), "--task", "smoothing"]) == 0
    ev = pd.read_csv(tmp_path / "o" / "smoothing.csv").iloc[0]
    assert ev["status"] == "ok" and bool(ev["diverged"]), ev["error"]
    assert cli(["eval", str(tmp_path / "nan.obj"), "--clean", str(PAIR / "Original.obj"), "--out",
                str(tmp_path / "s"), "--task", "simplification"]) == 0
    ev = pd.read_csv(tmp_path / "s" / "simplification.csv").iloc[0]
    assert ev["status"] == "error" and "non-finite" in ev["error"], ev["error"]
    with pytest.raises(InvalidMeshError, match="NaN"):      # as an input, still refused
        read_mesh(tmp_path / "nan.obj")


def test_a_simplification_scored_without_its_target_is_not_judged_on_it(run_with_meshes, tmp_path):
    """An outside review: eval took a simplification result's own face count as its target, so the
    unsimplified input was a valid result (over_target false, Hausdorff 0) and ranked best.
    Without a target, target_faces and over_target are blank and the row says why; with
    --target-faces (or --target-ratio) the unsimplified input is over its target."""
    clean = str(PAIR / "Original.obj")
    out = tmp_path / "o"
    assert cli(["eval", clean, "--clean", clean, "--task", "simplification", "--out", str(out),
                "--hausdorff-samples", "200"]) == 0
    row = pd.read_csv(out / "simplification.csv").iloc[0]
    assert pd.isna(row["target_faces"]) and pd.isna(row["over_target"]) and "over_target is not judged" in row["error"]
    assert cli(["eval", clean, "--clean", clean, "--task", "simplification", "--out", str(tmp_path / "t"),
                "--hausdorff-samples", "200", "--target-faces", "100"]) == 0
    row = pd.read_csv(tmp_path / "t" / "simplification.csv").iloc[0]
    assert row["target_faces"] == 100 and row["over_target"] and pd.isna(row["error"]), row
    assert cli(["eval", clean, "--clean", clean, "--target-faces", "0", "--target-ratio", "x", "--out",
                str(tmp_path / "bad")]) == 2 and not (tmp_path / "bad").exists()


def test_a_clean_mesh_that_needs_repairs_scores_as_in_a_run(tmp_path):
    """An outside review: `evaluate` skipped the run's repairs of the clean mesh (two unreferenced
    vertices made the Hausdorff distance 3.5x smaller), and eval refused a smoothing result in
    the clean file's own layout when the repairs changed it (duplicate faces, an unreferenced
    vertex first). Both now score exactly as the repaired mesh does; a saved noisy input in the
    repaired layout is accepted as --noisy."""
    from harness import datasets
    from harness.mesh import write_obj
    src = datasets.load("fandisk-noisy-0.3")
    V, F, Vn = src.clean.V, src.clean.F, src.noisy_V
    smooth = methods.get("scratch.taubin")(Vn, F).V
    far = np.array([[9.0, 9.0, 9.0], [-9.0, 0.0, 0.0]])
    Vr, Vnr, Sr = (np.vstack([far, X]) for X in (V, Vn, smooth))    # two unreferenced vertices first
    Fr = np.vstack([F + 2, F[:3] + 2])                              # and three duplicate faces
    want = harness.evaluate(smooth, F, V, F, V_noisy=Vn)
    assert harness.evaluate(Sr, Fr, Vr, Fr, V_noisy=Vnr) == want
    assert harness.evaluate(Sr, None, Vr, Fr, V_noisy=Vn) == want     # the noisy input in the repaired layout
    simp = methods.get("scratch.qem")(V, F, target_faces=len(F) // 4)
    assert (harness.evaluate(simp.V, simp.F, Vr, Fr, task="simplification", target_faces=len(F) // 4)
            == harness.evaluate(simp.V, simp.F, V, F, task="simplification", target_faces=len(F) // 4))
    write_obj(tmp_path / "clean.obj", Vr, Fr)
    write_obj(tmp_path / "noisy.obj", Vn, F)                          # as a run saves its input: repaired
    write_obj(tmp_path / "mine.obj", Sr, Fr)
    assert cli(["eval", str(tmp_path / "mine.obj"), "--clean", str(tmp_path / "clean.obj"), "--noisy",
                str(tmp_path / "noisy.obj"), "--out", str(tmp_path / "o")]) == 0
    row = pd.read_csv(tmp_path / "o" / "smoothing.csv").iloc[0]
    assert row["status"] == "ok" and "input repaired" in row["error"], row["error"]
    assert row["ev_mean"] == pytest.approx(want["ev_mean"], rel=1e-9) and row["mesh"] == "clean"
    assert row["input_dist_mean"] == pytest.approx(want["input_dist_mean"], rel=1e-9)


def test_a_clean_mesh_that_cannot_be_read_costs_its_results_rows(tmp_path):
    """A results: config whose second clean mesh has a NaN stopped the whole eval with a message
    naming neither the entry nor the file; it is now that entry's error row, naming the file."""
    (tmp_path / "nan.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n")
    (tmp_path / "ok.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    cfg = tmp_path / "r.yaml"
    cfg.write_text(json.dumps({"name": "r", "results": [{"file": "ok.obj", "clean": "ok.obj", "label": "good"},
                                                          {"file": "ok.obj", "clean": "nan.obj", "label": "bad"}]}))
    assert cli(["run", str(cfg), "--out", str(tmp_path / "o")]) == 0
    df = pd.read_csv(tmp_path / "o" / "smoothing.csv", keep_default_na=False).set_index("method")
    assert df.loc["good", "status"] == "ok" and df.loc["bad", "status"] == "error"
    assert "nan.obj" in df.loc["bad", "error"] and "NaN" in df.loc["bad", "error"], df.loc["bad", "error"]
    cfg.write_text(json.dumps({"name": "r", "results": [{"file": "ok.obj", "clean": "ok.obj", "target_faces": 0,
                                                          "task": "smoothing"}]}))
    with pytest.raises(ConfigError) as exc:
        harness.run(cfg, out=tmp_path / "p")
    assert str(cfg) in str(exc.value) and "results[0].target_faces" in str(exc.value), str(exc.value)


def test_two_evals_of_the_same_file_match_whether_the_task_was_given_or_detected(tmp_path):
    """An outside review: the case id hashed the task as given (None when detected), so an eval
    with --task smoothing and one without shared no case and compare exited 1 (a false
    regression)."""
    clean = str(PAIR / "Original.obj")
    a, b = tmp_path / "a", tmp_path / "b"
    assert cli(["eval", str(PAIR / "Noisy.obj"), "--clean", clean, "--out", str(a), "--label", "mine"]) == 0
    assert cli(["eval", str(PAIR / "Noisy.obj"), "--clean", clean, "--out", str(b), "--label", "mine",
                "--task", "smoothing"]) == 0
    ids = [pd.read_csv(d / "smoothing.csv")["case_id"].tolist() for d in (a, b)]
    assert ids[0] == ids[1], ids
    assert cli(["compare", str(a), str(b), "--no-time"]) == 0
    (tmp_path / "broken.obj").write_text("v 0 0 0\n")             # the row of a file that cannot be read
    assert cli(["eval", str(tmp_path / "broken.obj"), "--clean", clean, "--out", str(tmp_path / "c"), "--label",
                "mine", "--task", "smoothing"]) == 0                 # matches the scored row of the same label
    assert pd.read_csv(tmp_path / "c" / "smoothing.csv")["case_id"].tolist() == ids[0]


def test_a_target_given_without_a_task_scores_a_simplification(tmp_path):
    """A review: with --target-faces and no --task, a result with the clean mesh's counts was
    scored as a perfect smoothing result and the target dropped silently."""
    clean = str(PAIR / "Original.obj")
    assert cli(["eval", clean, "--clean", clean, "--target-faces", "100", "--out", str(tmp_path / "o"),
                "--hausdorff-samples", "200"]) == 0
    row = pd.read_csv(tmp_path / "o" / "simplification.csv").iloc[0]
    assert row["target_faces"] == 100 and row["over_target"], row


def test_eval_takes_the_runs_hausdorff_eps(tmp_path):
    """eval used 1e-3 whatever the run it was matched against had set, so a run's simplified mesh
    re-scored by eval could bracket its Hausdorff distance otherwise. It takes --hausdorff-eps."""
    from harness import datasets
    src = datasets.load("fandisk")
    V, F = src.clean.V, src.clean.F
    simp = methods.get("scratch.qem")(V, F, target_faces=len(F) // 10)
    loose = harness.evaluate(simp.V, simp.F, V, F, task="simplification", target_faces=len(F) // 10,
                             hausdorff_samples=0, hausdorff_eps=0.5)
    tight = harness.evaluate(simp.V, simp.F, V, F, task="simplification", target_faces=len(F) // 10,
                             hausdorff_samples=0, hausdorff_eps=1e-6)
    assert tight["hausdorff_gap"] <= 1e-6 < loose["hausdorff_gap"] <= 0.5
    assert tight["hausdorff"] <= tight["hausdorff_upper"] <= loose["hausdorff_upper"]
    assert cli(["eval", str(PAIR / "Noisy.obj"), "--clean", str(PAIR / "Original.obj"), "--hausdorff-eps", "2",
                "--out", str(tmp_path / "o")]) == 2 and not (tmp_path / "o").exists()


def test_results_sharing_a_file_name_are_labelled_by_their_folders_in_any_order(tmp_path):
    """An outside review: ``toolA/out.obj`` and ``toolB/out.obj`` were both labelled ``out`` and
    the second got the next free id, so two evals of the same files in another order swapped
    ids and compare saw 10 regressions. Their labels are now ``toolA/out`` and ``toolB/out``."""
    import shutil

    from harness.scoring import default_labels
    clean = str(PAIR / "Original.obj")
    for tool in ("toolA", "toolB"):
        (tmp_path / tool).mkdir()
    shutil.copy(PAIR / "Noisy.obj", tmp_path / "toolA" / "out.obj")
    m = read_mesh(PAIR / "Noisy.obj")
    from harness.mesh import write_obj
    write_obj(tmp_path / "toolB" / "out.obj", m.V * 0.999 + 0.001 * m.V.mean(axis=0), m.F)
    a, b = [str(tmp_path / t / "out.obj") for t in ("toolA", "toolB")]
    assert cli(["eval", a, b, "--clean", clean, "--out", str(tmp_path / "ab")]) == 0
    assert cli(["eval", b, a, "--clean", clean, "--out", str(tmp_path / "ba")]) == 0
    dfs = [pd.read_csv(tmp_path / d / "smoothing.csv").set_index("method") for d in ("ab", "ba")]
    assert sorted(dfs[0].index) == ["toolA/out", "toolB/out"]
    assert (dfs[0].loc[["toolA/out", "toolB/out"], "case_id"] == dfs[1].loc[["toolA/out", "toolB/out"], "case_id"]).all()
    assert cli(["compare", str(tmp_path / "ab"), str(tmp_path / "ba"), "--no-time"]) == 0
    assert default_labels(["x/a/r.obj", "y/a/r.obj", "z/q.ply"]) == ["x/a/r", "y/a/r", "q"]
    assert default_labels(["x/r.obj", "x/r.obj"]) == ["r", "r"]            # one file twice: one label
    assert default_labels(["t/out.obj", "t/out.ply"]) == ["out.obj", "out.ply"]   # only the extension differs


def test_a_results_config_lists_a_duplicate_key_with_its_other_problems(tmp_path, capsys):
    """A diff review: a duplicate key in a results: config made it read as a tasks config, whose
    problems (no meshes, no tasks, an unknown key results) were listed beside the duplicate;
    an octal number did the same. Now the duplicate and the results config's own problems are
    listed, and nothing else; exit 2, nothing written."""
    cfg = tmp_path / "res.yaml"
    cfg.write_text("name: a\nname: b\nhausdorff_samples: 010\nresults:\n"
                   f"  - {{file: {PAIR / 'Noisy.obj'}, clean: {PAIR / 'Original.obj'}, task: smoothing, bogus: 1}}\n")
    assert cli(["run", str(cfg), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "duplicate key 'name' at line 2" in err and "'010' at line 3 is octal" in err, err
    assert "results[0].bogus: unknown key" in err and "3 problem(s)" in err, err
    assert "meshes" not in err and "tasks" not in err, err
    assert not (tmp_path / "out").exists()
    with pytest.raises(ConfigError, match="duplicate key 'name'"):
        harness.run(cfg.read_text(), out=tmp_path / "out2")


def test_a_results_config_from_python_lists_its_out_problem_too(tmp_path):
    """A diff review: harness.run on a results: config with a problem of its own raised that
    problem alone, without the out folder's (the CLI listed both)."""
    cfg = tmp_path / "res.yaml"
    cfg.write_text("name: a\nname: b\nresults:\n"
                   f"  - {{file: {PAIR / 'Noisy.obj'}, clean: {PAIR / 'Original.obj'}, task: smoothing}}\n")
    with pytest.raises(harness.errors.ShootoutError) as err:
        harness.run(cfg.read_text(), out=str(cfg))
    assert "duplicate key 'name'" in str(err.value) and "not a folder" in str(err.value), str(err.value)


def test_two_clean_meshes_with_one_file_name_are_two_meshes(tmp_path, capsys):
    """Both published pairs name their clean mesh ``Original.obj``: an eval of results on both
    put all rows under one mesh ``Original``, which the report groups as one mesh. Their mesh
    names are now their files' shortest distinct trailing folders, as result labels are."""
    from harness.scoring import eval_entries
    root = PAIR.parent
    entries = [{"file": str(root / p / "Noisy.obj"), "clean": str(root / p / "Original.obj"), "label": "as-is"}
               for p in ("Fandisk0.3", "SharpSphere0.3")]
    df = eval_entries(entries, tmp_path / "o", hausdorff_samples=2000)["smoothing"].set_index("case_id")
    assert sorted(df["mesh"]) == ["Fandisk0.3/Original", "SharpSphere0.3/Original"]
    assert (df["status"] == "ok").all() and df["n_vertices"].nunique() == 2
    one = eval_entries(entries[:1], tmp_path / "one", hausdorff_samples=2000)["smoothing"]
    assert list(one["mesh"]) == ["Original"]                 # alone, its file's name as before
    # a review: compare took the two names of one case (one id) for two cases
    assert one["case_id"].iloc[0] in df.index
    assert cli(["compare", str(tmp_path / "one"), str(tmp_path / "o"), "--no-time"]) == 0
    out = capsys.readouterr().out
    assert "describe different cases" not in out and "1 cases in both" in out and "0 regression(s)" in out, out


def test_one_label_over_several_meshes_is_ranked_across_them(tmp_path):
    """Each scored file's path is its row's ``params``, so a label given on two meshes was two
    variants, one per file, and the leaderboard of an eval of both published pairs was empty
    ("no cell compares two or more methods"). A label with one file per mesh is now one
    variant; a label with two files on one mesh still names its files."""
    from harness import leaderboard as L
    from harness.leaderboard_labels import variant_labels
    from harness.scoring import eval_entries
    root = PAIR.parent
    entries = [{"file": str(root / p / f), "clean": str(root / p / "Original.obj"),
                "noisy": str(root / p / "Noisy.obj"), "label": lab}
               for p in ("Fandisk0.3", "SharpSphere0.3") for f, lab in (("Noisy.obj", "as-is"), ("Original.obj", "exact"))]
    frames = eval_entries(entries, tmp_path / "o", hausdorff_samples=2000)
    df = frames["smoothing"]
    assert sorted(variant_labels(df)) == ["as-is", "as-is", "exact", "exact"]
    meta = json.loads((tmp_path / "o" / "run.json").read_text())
    lb = L.leaderboard(dict(frames), meta["tasks"])
    dm = lb[lb["metric"] == "dist_mean"].set_index("method")
    assert list(dm.index) == ["exact", "as-is"] and (dm["cells"] == 2).all(), dm
    # two files of one label on one mesh: two variants, told apart by their files
    twice = entries[:2] + [{**entries[0], "file": str(root / "Fandisk0.3" / "Original.obj")}]
    df2 = eval_entries(twice, tmp_path / "t", hausdorff_samples=2000)["smoothing"]
    labels = variant_labels(df2)
    assert labels[1] == "exact" and labels[0] != labels[2] and labels[0].startswith("as-is file="), labels


def test_scored_files_without_a_seed_keep_their_standard_errors(tmp_path):
    """An outside audit: a scored file's row has no noise seed, which pandas kept blank through
    ``astype(str)``, so its cell counted 0 seeds and every standard error became infinite: two
    decimations 80 standard errors apart on surface_dist_mean tied at mean rank 1.5, and the
    winners printed ``± inf`` on "0 noise seed(s)". Also: a given noisy input is one fixed draw,
    not a seed to run more of."""
    from harness import leaderboard as L
    from harness.mesh_formats import write_obj
    from harness.scoring import eval_entries
    clean = PAIR / "Original.obj"
    V, F = harness.mesh.read_mesh(clean).V, harness.mesh.read_mesh(clean).F
    files = []
    for r in (0.5, 0.2):
        out = methods.get("fast_simplification.qem")(V, F, target_ratio=r)
        files.append(tmp_path / f"fs{int(r * 100)}.obj")
        write_obj(files[-1], out.V, out.F)
    entries = [{"file": str(f), "clean": str(clean), "task": "simplification"} for f in files]
    frames = dict(eval_entries(entries, tmp_path / "o", hausdorff_samples=4000))
    specs = json.loads((tmp_path / "o" / "run.json").read_text())["tasks"]
    df = frames["simplification"].set_index("method")
    gap = df.loc["fs20", "surface_dist_mean"] - df.loc["fs50", "surface_dist_mean"]
    assert gap > 10 * np.hypot(df.loc["fs20", "surface_dist_mean_se"], df.loc["fs50", "surface_dist_mean_se"])
    lb = L.leaderboard(frames, specs)
    sd = lb[lb["metric"] == "surface_dist_mean"].set_index("method")["mean_rank"]
    assert sd.to_dict() == {"fs50": 1.0, "fs20": 2.0}, sd
    w = L.winners(frames, specs)
    row = w[w["metric"] == "surface_dist_mean"].iloc[0]
    assert np.isfinite(row["value_se"]) and row["seeds"] == 1, row
    noisy = [{"file": str(PAIR / "Noisy.obj"), "clean": str(clean), "noisy": str(PAIR / "Noisy.obj"), "label": "as-is"},
             {"file": str(clean), "clean": str(clean), "noisy": str(PAIR / "Noisy.obj"), "label": "exact"}]
    fr = dict(eval_entries(noisy, tmp_path / "n", hausdorff_samples=2000))
    md = L.winners_markdown(L.winners(fr, json.loads((tmp_path / "n" / "run.json").read_text())["tasks"]),
                            json.loads((tmp_path / "n" / "run.json").read_text())["tasks"])
    assert "one fixed draw" in md and "run more seeds" not in md and "0 noise seed" not in md, md
