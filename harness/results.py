"""The run folder: one CSV per task appended row by row, resume, and run.json provenance.

Durability: each row is one ``write`` of a complete line to a file opened in append mode,
followed by flush and fsync, so a SIGKILL at any moment leaves every CSV parseable (at most
the rows in flight are lost; a torn last line, should the OS ever leave one, is dropped on
resume). ``run.json`` is written to a temporary file and renamed over the old one.
"""
from __future__ import annotations

import csv
import io
import json
import os
import tempfile
from pathlib import Path

import pandas as pd

from . import tasks
from .schema import cell, columns, scalar, task_file


def format_row(task: str, row: dict) -> str:
    """One CSV line (with newline) in the task's column order; unknown keys are dropped."""
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow([cell(row.get(c)) for c in columns(task)])
    return buf.getvalue()


class RunFolder:
    """Files of one run: ``<task>.csv``, ``run.json``, ``report.html``, ``meshes/``."""

    def __init__(self, path):
        self.path = Path(path)

    def csv_path(self, task: str) -> Path:
        return self.path / task_file(task)

    @property
    def run_json(self) -> Path:
        return self.path / "run.json"

    def read_run_json(self) -> dict | None:
        try:
            return json.loads(self.run_json.read_text())
        except (FileNotFoundError, json.JSONDecodeError):
            return None

    def write_run_json(self, data: dict) -> None:
        self.path.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=self.path, prefix=".run.json.", suffix=".tmp")
        with os.fdopen(fd, "w") as fh:
            json.dump(data, fh, indent=2, default=str)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, self.run_json)

    def read_rows(self, task: str) -> list[dict]:
        """Complete rows of a task CSV as dicts of strings (a torn last line is dropped)."""
        p = self.csv_path(task)
        if not p.exists():
            return []
        text = p.read_text()
        lines = text.splitlines(keepends=True)
        if lines and not lines[-1].endswith("\n"):
            lines = lines[:-1]
        rows = list(csv.DictReader(io.StringIO("".join(lines))))
        n = len(columns(task))
        return [r for r in rows if None not in r and len(r) == n]

    def reset(self) -> None:
        """Remove the CSVs, run.json, report and saved meshes of a previous run (a fresh run)."""
        for task in tasks.names():
            self.csv_path(task).unlink(missing_ok=True)
        for name in ("run.json", "report.html"):
            (self.path / name).unlink(missing_ok=True)
        mdir = self.path / "meshes"
        if mdir.is_dir():
            for f in mdir.glob("*.obj"):
                f.unlink()

    def status_counts(self) -> dict:
        """Rows per status over all task CSVs."""
        out: dict[str, int] = {}
        for task in tasks.names():
            for r in self.read_rows(task):
                out[r["status"]] = out.get(r["status"], 0) + 1
        return out

    def keep_ok_rows(self) -> set[str]:
        """For --resume: rewrite each CSV with only its ok rows; return their case ids."""
        done = set()
        for task in tasks.names():
            rows = [r for r in self.read_rows(task) if r.get("status") == "ok"]
            seen = set()
            rows = [r for r in rows if not (r["case_id"] in seen or seen.add(r["case_id"]))]
            done |= seen
            if self.csv_path(task).exists():
                fd, tmp = tempfile.mkstemp(dir=self.path, prefix=f".{task}.", suffix=".tmp")
                with os.fdopen(fd, "w", newline="") as fh:
                    w = csv.DictWriter(fh, fieldnames=columns(task), lineterminator="\n")
                    w.writeheader()
                    w.writerows(rows)
                    fh.flush()
                    os.fsync(fh.fileno())
                os.replace(tmp, self.csv_path(task))
        return done

    def append(self, task: str, row: dict) -> None:
        """Append one row as a single write, flushed and fsynced; header first if the file is new."""
        self.path.mkdir(parents=True, exist_ok=True)
        p = self.csv_path(task)
        data = format_row(task, row)
        if not p.exists() or p.stat().st_size == 0:
            head = io.StringIO()
            csv.writer(head, lineterminator="\n").writerow(columns(task))
            data = head.getvalue() + data
        fd = os.open(p, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        try:
            os.write(fd, data.encode())
            os.fsync(fd)
        finally:
            os.close(fd)

    def frames(self) -> dict[str, pd.DataFrame]:
        """One DataFrame per task CSV present."""
        out = {}
        for task in tasks.names():
            if self.csv_path(task).exists():
                out[task] = load_csv(self.csv_path(task))
        return out

    # ------------------------------------------------------------------------- views

    def write_views(self, views: list[dict]) -> None:
        """``views/NN-<case_id>.json`` for each view and ``views/index.json`` listing them in order."""
        vdir = self.path / "views"
        vdir.mkdir(parents=True, exist_ok=True)
        index = []
        for i, v in enumerate(views):
            cid = str(v.get("case_id", ""))
            name = f"{i:02d}-{cid}.json" if cid.isalnum() else f"{i:02d}.json"
            _atomic_json(vdir / name, v)
            index.append({"file": name, "case_id": cid, "why": v.get("why")})
        keep = {e["file"] for e in index} | {"index.json"}
        for old in vdir.glob("*.json"):
            if old.name not in keep:
                old.unlink()
        _atomic_json(vdir / "index.json", {"views": index})

    def read_views(self) -> list[dict]:
        """The stored views in order ([] when there are none); an unreadable one is a view with an error."""
        vdir = self.path / "views"
        try:
            index = json.loads((vdir / "index.json").read_text())["views"]
        except (OSError, ValueError, KeyError, TypeError):
            return []
        out = []
        for e in index if isinstance(index, list) else []:
            try:
                out.append(json.loads((vdir / Path(str(e["file"])).name).read_text()))   # never leave views/
            except (OSError, ValueError, KeyError, TypeError) as exc:
                cid = str(e.get("case_id", "?")) if isinstance(e, dict) else "?"
                out.append({"case_id": cid, "why": "", "error": f"view file unreadable ({type(exc).__name__})"})
        return out


def load_csv(path) -> pd.DataFrame:
    """Read a task CSV with true/false columns as booleans and ids as strings.

    Only an empty cell is missing (that is how rows are written): a mesh or file named
    ``nan``, ``NA`` or ``null`` keeps its name.
    """
    df = pd.read_csv(path, dtype={"case_id": str, "error": str, "params": str},
                     keep_default_na=False, na_values=[""], true_values=["true"], false_values=["false"])
    if "error" in df:
        df["error"] = df["error"].fillna("")
    return df


def _atomic_json(path: Path, data) -> None:
    """Write JSON to a temporary file in the same folder and rename it over ``path``."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    with os.fdopen(fd, "w") as fh:
        json.dump(data, fh, separators=(",", ":"), allow_nan=False, default=scalar)
    os.replace(tmp, path)
