"""The README's "From Python" snippet runs as written."""
from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_from_python_snippet_runs(tmp_path, monkeypatch, capsys):
    text = (ROOT / "README.md").read_text()
    section = text.split("## From Python", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {"__name__": "readme"})
    out = capsys.readouterr().out
    assert "scratch.taubin" in out and (tmp_path / "results" / "api-demo" / "report.html").is_file()
    ev, inp = map(float, out.strip().splitlines()[-1].split())
    assert 0 < ev < inp                                  # taubin reduced the error of the noisy input


SCRIPT = r'''
import re, sys, types
from pathlib import Path
text = Path(sys.argv[1]).read_text()
section = text.split("## Adding a task kind", 1)[1]
code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
mod = types.ModuleType("harness.tasks.area")
sys.modules["harness.tasks.area"] = mod
exec(compile(code, "README.md", "exec"), mod.__dict__)
import harness.tasks as T
T.all_tasks()
T._TASKS["area"] = mod.TASK          # what discovery does for a module file in harness/tasks/
from harness.core.geometry import area
from methods import register

@register("mylab.area", task="area", library="mylab")
def estimate(V, F):
    return mod.AreaResult(value=1.01 * float(area(V, F)))

import harness
frames = harness.run({"name": "area", "repeats": 1, "meshes": ["knight"], "noise": [{"model": "none"}],
                      "tasks": {"area": {"methods": ["mylab.area"]}}}, out=sys.argv[2], quiet=True, workers=1)
print(frames["area"]["status"].tolist(), frames["area"]["area_rel_error"].tolist())
'''


def test_adding_a_task_kind_example_runs(tmp_path):
    """The README's example task module, declared as written, runs through the whole pipeline
    (config validation, a forked case, the CSV, the report) with no other code naming it."""
    import subprocess
    import sys
    script = tmp_path / "area_demo.py"
    script.write_text(SCRIPT)
    r = subprocess.run([sys.executable, str(script), str(ROOT / "README.md"), str(tmp_path / "out")],
                       capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert r.returncode == 0, r.stderr[-2000:]
    status, err = r.stdout.strip().splitlines()[-1].split("] [")
    assert "'ok'" in status and abs(float(err.strip("[]")) - 0.01) < 1e-12
    assert "Surface area" in (tmp_path / "out" / "report.html").read_text()
