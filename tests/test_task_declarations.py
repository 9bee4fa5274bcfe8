"""A task kind's declaration and its measured columns are checked: a metric named like a common
column, a misspelt metric key, an array where a number belongs and a task module that does not
import each made rows wrong or unreadable, or every command crash (an outside review's findings)."""
from __future__ import annotations

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from harness import tasks
from harness.errors import MethodFailed
from harness.tasks import Metric, declaration_problems

ROOT = Path(__file__).resolve().parents[1]
SMOOTHING = tasks.get("smoothing")


def test_the_shipped_task_kinds_are_well_declared():
    assert tasks.BROKEN == {}
    for t in tasks.all_tasks().values():
        assert declaration_problems(t) == [], t.name


def test_bad_declarations_are_named():
    one = replace(SMOOTHING, metrics=Metric("area", "lower"))            # the missing trailing comma
    assert "trailing comma" in declaration_problems(one)[0]
    clash = replace(SMOOTHING, metrics=SMOOTHING.metrics + (Metric("error"), Metric("dist_mean")))
    P = declaration_problems(clash)
    assert any("'error' is a common column" in p for p in P) and any("'dist_mean' is declared twice" in p for p in P)
    assert any("view_metric" in p for p in declaration_problems(replace(SMOOTHING, view_metric="nope")))


@pytest.mark.parametrize("out, said", [
    ({"dist_mean": 0.1, "n_vertices": 7}, "['n_vertices'], which are not its declared metrics"),
    ({"dist_maen": 0.1}, "['dist_maen']"),
    ({"dist_mean": np.array([0.1])}, "'dist_mean' is a ndarray of shape (1,)"),
    ({"dist_mean": [0.1]}, "'dist_mean' is a list"),
])
def test_measured_columns_are_declared_scalars(out, said):
    t = replace(SMOOTHING, measure=lambda inp, res, params: out)
    with pytest.raises(MethodFailed) as ei:
        t.measured(None, None, {})
    assert said in str(ei.value)
    ok = {"dist_mean": np.float64(0.1), "diverged": np.bool_(False), "normal_error_deg": None}
    assert replace(SMOOTHING, measure=lambda inp, res, params: ok).measured(None, None, {}) is ok


def test_a_task_module_that_does_not_import_costs_that_task_kind_only(tmp_path):
    """Before: a task module with an import error made `shootout methods`, `run` of a config of
    the built-in tasks and `report` die with a traceback."""
    extra = tmp_path / "extra"
    extra.mkdir()
    (extra / "broken_kind.py").write_text("import nonexistent_helper_xyz\n")
    code = ("import sys, harness.tasks as t; t.__path__.append(sys.argv[1]); "
            "from harness.cli import main; rc = main(['methods', '--task', 'smoothing']); "
            "print('names', t.names()); "
            "from harness.config import load_config\n"
            "try:\n load_config({'meshes': ['knight'], 'tasks': {'broken_kind': {'methods': ['x']}}})\n"
            "except Exception as e: print('config', e)\n"
            "sys.exit(rc)")
    r = subprocess.run([sys.executable, "-c", code, str(extra)], cwd=ROOT, capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    assert "broken_kind.py is not loaded as a task kind: importing it failed (ModuleNotFoundError" in r.stderr
    assert "scratch.taubin" in r.stdout and "'smoothing'" in r.stdout
    assert "tasks.broken_kind: unknown task" in r.stdout and "is not loaded: importing it failed" in r.stdout


def test_a_task_kinds_name_is_an_identifier_and_taken_once(tmp_path):
    """A task module named 'brokene.py' declaring name='smoothing' replaced or dropped the built-in
    kind by the order of the file names, with no word; name='../escaped' wrote its CSV outside the
    run folder. Now the module named after a kind keeps it, the other is named as not loaded, and
    a name that is not an identifier is refused."""
    assert "not a lower-case identifier" in declaration_problems(replace(SMOOTHING, name="../escaped"))[0]
    extra = tmp_path / "extra"
    extra.mkdir()
    (extra / "brokene.py").write_text("from dataclasses import replace\nfrom harness.tasks.smoothing import TASK as T\n"
                                      "TASK = replace(T, name='smoothing', order=-1)\n")
    (extra / "zz_twin.py").write_text("from dataclasses import replace\nfrom harness.tasks.laplacian import TASK as T\n"
                                      "TASK = replace(T, name='laplacian')\n")
    code = ("import sys, harness.tasks as t; t.__path__.append(sys.argv[1]); "
            "print(sorted((k, v.order) for k, v in t.all_tasks().items()), sorted(t.BROKEN))")
    r = subprocess.run([sys.executable, "-c", code, str(extra)], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "('smoothing', -1)" not in r.stdout and "['brokene', 'zz_twin']" in r.stdout, r.stdout
    assert "brokene.py is not loaded as a task kind: its name 'smoothing' is the task kind of smoothing.py" in r.stderr
    assert "zz_twin.py is not loaded as a task kind: its name 'laplacian' is the task kind of laplacian.py" in r.stderr
