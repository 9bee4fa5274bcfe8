"""The run folder: one CSV per task appended row by row, resume, and run.json provenance.

Durability: each row is one ``write`` of a complete line to a file opened in append mode,
followed by flush and fsync, so a SIGKILL at any moment leaves every CSV parseable (at most
the rows in flight are lost; a torn last line is dropped when the file is read). Every other
file (``run.json``, saved meshes, views) is written to a temporary file, fsynced and renamed
over its name, so no reader ever sees half a file. Files get the user's umask, like any file
the user creates.

Ownership: a fresh run deletes only what a previous run in this folder wrote: its task CSVs
(when its ``run.json`` says it is a run folder), its report and views, and the saved meshes
listed in ``meshes/.written`` (one name per line, appended before each mesh is renamed into
place). A user's own file is never deleted. One run at a time: `lock` takes an exclusive
``flock`` on ``.shootout.lock`` (holding the owner's pid) for the whole run.
"""
from __future__ import annotations

import contextlib
import csv
import errno
import io
import os
import re
from pathlib import Path

import pandas as pd

from . import tasks
from .errors import ShootoutError
from .folder_files import _META_TYPES, FolderFiles, _sane, recorded_specs
from .output_paths import OUTPUT_KINDS, SOURCE_DIRS, check_out_dir, check_output_file
from .run_csv import IDENTITY_COLUMNS, NUMERIC_COMMON, _checked_csv_text, load_csv
from .run_files import (MANIFEST, PLAN_FILE, REPORT_FILES, RUNNING, STATUS_ROOM, atomic_write, close_inherited_locks,
                        format_row, output_names, run_file_names, write_csv_rows)
from .run_plan import NOT_RUN, PLAN_COLUMNS, _plan_row, with_not_run
from .schema import cell, columns, task_file

__all__ = [      # this module's names and those of the modules above that callers and tests import from here
    "RunFolder", "Frames", "out_dir_problems", "FolderFiles", "recorded_specs", "_META_TYPES", "_sane",
    "OUTPUT_KINDS", "SOURCE_DIRS", "check_out_dir", "check_output_file",
    "IDENTITY_COLUMNS", "NUMERIC_COMMON", "load_csv", "_checked_csv_text",
    "MANIFEST", "PLAN_FILE", "REPORT_FILES", "RUNNING", "STATUS_ROOM", "atomic_write", "close_inherited_locks",
    "format_row", "output_names", "run_file_names", "write_csv_rows",
    "NOT_RUN", "PLAN_COLUMNS", "with_not_run", "columns",
]


class RunFolder(FolderFiles):
    """Files of one run: ``<task>.csv``, ``run.json``, ``report.html``, ``meshes/``."""

    def read_rows(self, task: str) -> list[dict]:
        """Complete rows of a task CSV as dicts of strings (a torn last line is dropped)."""
        p = self.csv_path(task)
        if not p.exists():
            return []
        text = p.read_bytes().decode("utf-8-sig")           # no newline translation; a BOM is no column name
        records = []
        try:                    # records, not lines: a quoted field may hold a newline, \r or \u2028
            for rec in csv.reader(io.StringIO(text, newline="")):
                records.append(rec)
        except csv.Error as exc:
            if "unexpected end of data" not in str(exc):
                raise           # damaged within, not torn at its end: said, as before
            # the file ends inside a quoted field: a torn last row, not kept
        else:
            if records and not text.endswith("\n"):        # every row is written ending in a newline
                records.pop()
        n = len(columns(task))
        if not records or len(records[0]) != n:
            return []
        head = records[0]
        return [dict(zip(head, rec)) for rec in records[1:] if len(rec) == n]

    def recorded_tasks(self) -> list[str]:
        """The task kinds run.json (of ours) says this folder's run had, installed here or not."""
        meta = self.read_run_json() or {}
        rec = meta.get("tasks") if isinstance(meta.get("tasks"), dict) else {}
        return [t for t in rec if isinstance(t, str) and re.fullmatch(r"[A-Za-z0-9_]+", t)]

    def missing_task_kinds(self) -> list[str]:
        """Task kinds of this folder's run (run.json) with a CSV here whose module is not
        installed: every reader would leave their rows out."""
        known = set(tasks.names())
        return [t for t in self.recorded_tasks() if t not in known and self.csv_path(t).exists()]

    def readable_problem(self) -> str | None:
        """Why the readers (report, `harness.load_run`) would misstate this folder: task kinds of
        its run that are not installed here (their rows would be left out)."""
        missing = self.missing_task_kinds()
        if missing:
            return (f"{self.path}: its run has task kind(s) {missing} whose module is not installed here "
                    f"(harness/tasks/{missing[0]}.py): their rows would be left out; install them first")
        return None

    def column_problems(self) -> list[str]:
        """Each task CSV whose header is not this version's columns (`harness.schema.columns`)."""
        out = []
        for task in tasks.names():
            p = self.csv_path(task)
            if not p.is_file() or p.stat().st_size == 0:
                continue
            with p.open(newline="", encoding="utf-8-sig", errors="replace") as fh:   # a BOM (saved by a spreadsheet)
                line = fh.readline()
            if not line.endswith("\n"):          # a header torn by a full disk: no row to keep
                continue
            head = next(csv.reader([line]), [])
            want = columns(task)
            if head != want:
                missing, extra = [c for c in want if c not in head], [c for c in head if c not in want]
                how = [f"without {missing}" if missing else "", f"with {extra}" if extra else "",
                       "" if missing or extra else "in another order"]
                out.append(f"{p.name} has other columns than this version's ({', '.join(h for h in how if h)})")
        return out

    def reset(self) -> None:
        """Remove what a previous run in this folder wrote (a fresh run); never a user's file."""
        ours = self.run_json_state() == "ok"
        if ours:
            kinds = list(dict.fromkeys(tasks.names() + self.recorded_tasks()))   # also kinds not installed now
            for task in kinds:
                self.csv_path(task).unlink(missing_ok=True)
            for name in (*REPORT_FILES, PLAN_FILE):
                (self.path / name).unlink(missing_ok=True)
            vdir = self.path / "views"
            if vdir.is_dir():
                for name in self._written_views() | {"index.json"}:
                    (vdir / name).unlink(missing_ok=True)
            for task in kinds:                           # a tuned run's training rows
                (self.path / "tune" / task_file(task)).unlink(missing_ok=True)
        self.remove_temporaries()                # first: the manifest names the meshes' temporaries
        mdir = self.path / "meshes"
        for name in self.written_meshes():
            (mdir / Path(name).name).unlink(missing_ok=True)
        (mdir / MANIFEST).unlink(missing_ok=True)
        if ours:
            self.run_json.unlink(missing_ok=True)

    def status_counts(self) -> dict:
        """Rows per status over all task CSVs."""
        out: dict[str, int] = {}
        for task in tasks.names():
            for r in self.read_rows(task):
                out[r["status"]] = out.get(r["status"], 0) + 1
        return out

    def keep_ok_rows(self, known: set | None = None) -> set[str]:
        """For --resume: rewrite each CSV with only its ok rows (of the ``known`` case ids, when
        given: a row of another id is not one of this config's cases); return their case ids."""
        done = set()
        for task in tasks.names():
            rows = [r for r in self.read_rows(task) if r.get("status") == "ok"
                    and (known is None or r.get("case_id") in known)]
            seen = set()
            rows = [r for r in rows if not (r["case_id"] in seen or seen.add(r["case_id"]))]
            done |= seen
            if self.csv_path(task).exists():
                def write(fh, rows=rows, task=task):
                    cols = columns(task)
                    write_csv_rows(fh, [cols] + [[r.get(c, "") for c in cols] for r in rows])
                atomic_write(self.csv_path(task), write)
        return done

    def drop_rows(self, drop) -> None:
        """Rewrite each task CSV without the rows for which ``drop(row)`` is true."""
        for task in tasks.names():
            if not self.csv_path(task).exists():
                continue
            rows = self.read_rows(task)
            keep = [r for r in rows if not drop(r)]
            if len(keep) == len(rows):
                continue

            def write(fh, keep=keep, task=task):
                cols = columns(task)
                write_csv_rows(fh, [cols] + [[r.get(c, "") for c in cols] for r in keep])
            atomic_write(self.csv_path(task), write)

    def append(self, task: str, row: dict) -> None:
        """Append one row as a single write, flushed and fsynced; header first if the file is new."""
        self.path.mkdir(parents=True, exist_ok=True)
        p = self.csv_path(task)
        data = format_row(task, row)
        if not p.exists() or p.stat().st_size == 0:
            head = io.StringIO()
            csv.writer(head, lineterminator="\n").writerow(columns(task))
            data = head.getvalue() + data
        fd = os.open(p, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
        try:
            start = os.fstat(fd).st_size
            buf = memoryview(data.encode())
            try:
                while buf:                  # a short write (a full disk, a file size limit) leaves no part row
                    n = os.write(fd, buf)
                    if n <= 0:
                        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(p))
                    buf = buf[n:]
                os.fsync(fd)
            except BaseException:
                with contextlib.suppress(OSError):
                    os.ftruncate(fd, start)
                raise
        finally:
            os.close(fd)

    def frames(self) -> dict[str, pd.DataFrame]:
        """One DataFrame per task CSV present; `ShootoutError` for a CSV that lacks a metric column
        its run declares (run.json ``tasks``), or a case id in two rows (a run writes one row per
        case): an edited or merged file every reader would misstate."""
        out = {}
        meta = self.read_run_json() or {}
        declared = meta.get("tasks") if isinstance(meta.get("tasks"), dict) else {}
        seen: dict[str, str] = {}
        for task in tasks.names():
            path = self.csv_path(task)
            if not path.exists():
                continue
            df = load_csv(path)
            spec = declared.get(task) if isinstance(declared.get(task), dict) else {}
            names = [m.get("name") for m in spec.get("metrics") or [] if isinstance(m, dict)] \
                if isinstance(spec.get("metrics"), list) else []
            lost = [n for n in names if isinstance(n, str) and n not in df and len(df.columns)]
            if lost:
                raise ShootoutError(f"{path}: damaged CSV: no column(s) {', '.join(lost[:5])}"
                                    + (f" and {len(lost) - 5} more" if len(lost) > 5 else "")
                                    + ", which its run (run.json) declares")
            if "case_id" in df:
                for cid in df["case_id"].astype(str):
                    if cid in seen:
                        raise ShootoutError(f"{path}: case id {cid} appears in more than one row (also in "
                                            f"{seen[cid]}): a run folder holds one row per case (an edited or "
                                            "merged file?); which one to show is not decidable")
                    seen[cid] = path.name
            out[task] = df
        return out

    def write_plan(self, rows: list[dict]) -> None:
        """``plan.csv``: the identifying columns (`PLAN_COLUMNS`) of every case the run plans."""
        atomic_write(self.path / PLAN_FILE, lambda fh: write_csv_rows(
            fh, [PLAN_COLUMNS] + [[cell(r.get(c)) for c in PLAN_COLUMNS] for r in rows]))

    def read_plan(self) -> list[dict] | None:
        """The rows of ``plan.csv`` (typed by `_plan_row`), None when the folder has none (a run
        folder of an older version, or of `eval`); `ShootoutError` naming the first damaged line."""
        path = self.path / PLAN_FILE
        if not path.exists():
            return None
        try:
            text = path.read_bytes().decode("utf-8")    # no newline translation: a quoted \r stays one
        except (OSError, UnicodeDecodeError) as exc:
            raise ShootoutError(f"{path}: unreadable ({exc})") from None
        rows = list(csv.reader(io.StringIO(text)))
        if not rows or tuple(rows[0]) != PLAN_COLUMNS:
            raise ShootoutError(f"{path}: damaged plan: its header is not {','.join(PLAN_COLUMNS)}")
        out = []
        for i, r in enumerate(rows[1:], 2):
            row = _plan_row(dict(zip(PLAN_COLUMNS, r))) if len(r) == len(PLAN_COLUMNS) else None
            if row is None:
                raise ShootoutError(f"{path}: damaged plan: line {i} is not a case as this tool writes it "
                                    f"({','.join(r)[:80]!r}); remove the file to build the report without it")
            out.append(row)
        return out


class Frames(dict):
    """``{task: DataFrame}`` of a run folder's rows, and ``not_written``: what the end of the run
    could not (re)write (3D views, leaderboard, report), empty when everything was written."""

    def __init__(self, frames: dict, not_written=()):
        super().__init__(frames)
        self.not_written = list(not_written)


def out_dir_problems(out_dir, resume: bool = False) -> list[str]:
    """What forbids writing a run into ``out_dir`` (`check_out_dir`; another program's files
    in a folder that is not a run folder, unless resuming)."""
    try:
        check_out_dir(Path(out_dir))
        folder = RunFolder(Path(out_dir))
        if not resume and folder.foreign_files():
            return [str(folder.foreign_error())]
    except ShootoutError as exc:
        return [str(exc)]
    return []
