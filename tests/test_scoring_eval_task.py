"""The task (and so the case id) of an eval row that failed: a result file that was read keeps the
task read from it; only one whose task is unknown (the file could not be read) goes beside the
other files' task. Its case id is the one it gets once the file is fixed."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import methods
from harness.cli import main as cli
from harness.mesh import write_obj


@pytest.fixture()
def files(tmp_path):
    from harness import datasets
    s = datasets.load({"procedural": "sphere", "subdivisions": 2}).clean
    write_obj(tmp_path / "clean.obj", s.V, s.F)
    write_obj(tmp_path / "good.obj", s.V * 1.01, s.F)                     # a smoothing result
    simp = methods.get("scratch.qem")(s.V, s.F, target_faces=len(s.F) // 2)
    for d, V in (("a", np.where(np.arange(len(simp.V))[:, None] == 0, np.nan, simp.V)), ("b", simp.V)):
        (tmp_path / d).mkdir()
        write_obj(tmp_path / d / "tool.obj", V, simp.F)                 # a: one NaN vertex; b: fixed
    return tmp_path


def _rows(out):
    return pd.concat([pd.read_csv(p, keep_default_na=False) for p in sorted(out.glob("*.csv")) if p.stem
                      in ("smoothing", "simplification")]).set_index("method")


def test_a_read_result_that_fails_keeps_its_task_and_case_id(files):
    """Before: the NaN simplification result was filed as a smoothing error row (beside good.obj),
    under another case id than the fixed file's, so compare called the fix a missing case (exit 1)."""
    ev = ["eval", "--clean", str(files / "clean.obj"), "--hausdorff-samples", "200", str(files / "good.obj")]
    assert cli([*ev, str(files / "a" / "tool.obj"), "--out", str(files / "evA")]) == 0
    assert cli([*ev, str(files / "b" / "tool.obj"), "--out", str(files / "evB")]) == 0
    a, b = _rows(files / "evA"), _rows(files / "evB")
    assert a.loc["tool", "status"] == "error" and a.loc["tool", "task"] == "simplification", a.loc["tool"].to_dict()
    assert b.loc["tool", "status"] == "ok" and b.loc["tool", "task"] == "simplification"
    assert a.loc["tool", "case_id"] == b.loc["tool", "case_id"]
    assert a.loc["good", "case_id"] == b.loc["good", "case_id"]
    assert cli(["compare", str(files / "evA"), str(files / "evB"), "--no-time"]) == 0


def test_an_unreadable_result_goes_beside_the_others_or_to_its_target(files):
    (files / "a" / "broken.obj").write_text("v 0 0 0\n")                # no faces: cannot be read
    ev = ["eval", "--clean", str(files / "clean.obj"), "--hausdorff-samples", "200"]
    assert cli([*ev, str(files / "good.obj"), str(files / "a" / "broken.obj"), "--out", str(files / "u")]) == 0
    rows = _rows(files / "u")
    assert rows.loc["broken", "task"] == "smoothing" and rows.loc["broken", "status"] == "error"
    # with a target, the task is simplification before the file is read: the fixed file's case id
    target = ["--target-faces", "10", "--label", "tool"]
    assert cli([*ev, *target, str(files / "a" / "broken.obj"), "--out", str(files / "t1")]) == 0
    assert cli([*ev, *target, str(files / "b" / "tool.obj"), "--out", str(files / "t2")]) == 0
    t1, t2 = _rows(files / "t1"), _rows(files / "t2")
    assert t1.loc["tool", "task"] == "simplification" and t1.loc["tool", "status"] == "error"
    assert t1.loc["tool", "case_id"] == t2.loc["tool", "case_id"]
