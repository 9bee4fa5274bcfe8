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
