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
import math
import os
import platform
import subprocess
import tempfile
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path

import pandas as pd

from .measure import TASK_COLUMNS
from .runner import COMMON_COLUMNS

TASK_FILES = {t: f"{t}.csv" for t in TASK_COLUMNS}
VERSION_PACKAGES = ["numpy", "scipy", "pandas", "libigl", "pymeshlab", "fast-simplification", "pygel3d",
                    "numba", "robust-laplacian", "pyfqmr", "distributed", "mesh-shootout"]


def columns(task: str) -> list[str]:
    return COMMON_COLUMNS + TASK_COLUMNS[task]


def _cell(v):
    if v is None:
        return ""
    if isinstance(v, float) and math.isnan(v):
        return ""
    if isinstance(v, (bool,)) or type(v).__name__ == "bool_":
        return "true" if v else "false"
    return v


def format_row(task: str, row: dict) -> str:
    """One CSV line (with newline) in the task's column order; unknown keys are dropped."""
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow([_cell(row.get(c)) for c in columns(task)])
    return buf.getvalue()


class RunFolder:
    """Files of one run: ``<task>.csv``, ``run.json``, ``report.html``, ``meshes/``."""

    def __init__(self, path):
        self.path = Path(path)

    def csv_path(self, task: str) -> Path:
        return self.path / TASK_FILES[task]

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
        for task in TASK_FILES:
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
        for task in TASK_FILES:
            for r in self.read_rows(task):
                out[r["status"]] = out.get(r["status"], 0) + 1
        return out

    def keep_ok_rows(self) -> set[str]:
        """For --resume: rewrite each CSV with only its ok rows; return their case ids."""
        done = set()
        for task in TASK_FILES:
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
        for task in TASK_FILES:
            if self.csv_path(task).exists():
                out[task] = load_csv(self.csv_path(task))
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


# ----------------------------------------------------------------------------- provenance

def package_versions() -> dict:
    out = {}
    for name in VERSION_PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = None
    out["python"] = platform.python_version()
    return out


def git_commit() -> str | None:
    try:
        here = Path(__file__).resolve().parent
        r = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True, timeout=5)
        return r.stdout.strip() or None if r.returncode == 0 else None
    except (OSError, subprocess.SubprocessError):
        return None


def machine_info() -> dict:
    import psutil
    freq = psutil.cpu_freq()
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"node": platform.node(), "system": platform.system(), "release": platform.release(),
            "machine": platform.machine(), "cpu": cpu, "cpu_count": os.cpu_count(),
            "cpu_freq_mhz": freq.max if freq else None,
            "memory_gb": round(psutil.virtual_memory().total / 2 ** 30, 1)}


def now_iso() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")
