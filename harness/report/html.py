"""A plain, self-contained report.html: one table per task (no external resources)."""
from __future__ import annotations

import html
import json
from pathlib import Path

from ..results import RunFolder


def build_report(run_dir) -> Path:
    """Write ``run_dir/report.html`` from the CSVs and run.json; return its path."""
    folder = RunFolder(run_dir)
    meta = folder.read_run_json() or {}
    frames = folder.frames()
    parts = [f"<h1>mesh-shootout: {html.escape(str(meta.get('name', Path(run_dir).name)))}</h1>",
             f"<p>started {html.escape(str(meta.get('started')))}, finished {html.escape(str(meta.get('finished')))}</p>",
             f"<pre>{html.escape(json.dumps(meta.get('versions', {}), indent=1))}</pre>"]
    for task, df in frames.items():
        parts.append(f"<h2 id='{task}'>{task}</h2>")
        parts.append(df.to_html(index=False, na_rep="", escape=True, classes="rows"))
    page = ("<!doctype html><html><head><meta charset='utf-8'><title>mesh-shootout report</title>"
            "<style>body{font-family:sans-serif;margin:1em}table{border-collapse:collapse;font-size:12px}"
            "td,th{border:1px solid #ccc;padding:2px 4px}</style></head><body>"
            + "\n".join(parts) + "</body></html>")
    out = Path(run_dir) / "report.html"
    out.write_text(page)
    return out
