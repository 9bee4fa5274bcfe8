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
import fcntl
import glob
import io
import json
import os
import re
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

from . import tasks
from .errors import ShootoutError
from .schema import STATUSES, cell, columns, scalar, task_file
from .tasks.base import rule_ok

MANIFEST = ".written"


def _umask() -> int:
    m = os.umask(0)
    os.umask(m)
    return m


RUNNING = '"status": "running"'
STATUS_ROOM = len('"interrupted"') - len('"running"')       # the longest status written in place


def atomic_write(path: Path, write) -> None:
    """Write ``path`` through ``write(fh)`` on a temporary file in the same folder, fsync, chmod to the
    umask's default and rename into place; the temporary file never survives a failure."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", newline="", encoding="utf-8") as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


_HELD_LOCKS: list = []            # the run folders' lock files this process opened (`RunFolder.lock`)


def close_inherited_locks() -> None:
    """In a forked case process: close the inherited copies of the driver's run-folder locks.
    An ``flock`` belongs to the open file, which a fork shares, so a method holding a copy could
    release the driver's lock (``flock(fd, LOCK_UN)``) and let a second run write into the folder;
    closing a copy leaves the lock with the driver."""
    for fh in _HELD_LOCKS:
        with contextlib.suppress(OSError, ValueError):
            fh.close()
    _HELD_LOCKS.clear()


def write_csv_rows(fh, rows) -> None:
    """CSV lines ending in ``\n``; a row holding a carriage return in a value (a file name may)
    has every field quoted, since the csv module quotes only the line terminator's characters
    and a bare ``\r`` would end the line for a reader."""
    plain = csv.writer(fh, lineterminator="\n")
    quoted = csv.writer(fh, lineterminator="\n", quoting=csv.QUOTE_ALL)
    for r in rows:
        (quoted if any(isinstance(v, str) and "\r" in v for v in r) else plain).writerow(r)


def format_row(task: str, row: dict) -> str:
    """One CSV line (with newline) in the task's column order; unknown keys are dropped."""
    buf = io.StringIO()
    write_csv_rows(buf, [[cell(row.get(c)) for c in columns(task)]])
    return buf.getvalue()


_TEMP = re.compile(r"\.[a-z0-9_]{8}\.tmp")      # what `atomic_write`'s mkstemp appends to ".<name>"
REPORT_FILES = ("report.html", "leaderboard.csv", "leaderboard.md", "leaderboard.tex", "winners.csv",
                "winners.md", "winners.tex")


PLAN_FILE = "plan.csv"            # every case the config plans (`RunFolder.write_plan`)


def output_names() -> list[str]:
    """The files a run writes at the top of its folder and may replace or delete: task CSVs,
    run.json, the report, leaderboard and winners tables."""
    return [task_file(t) for t in tasks.names()] + ["run.json", PLAN_FILE, *REPORT_FILES]


def run_file_names() -> list[str]:
    """The names of the files a run writes at the top of its folder (`output_names` and its lock)."""
    return output_names() + [".shootout.lock"]


def _is_ours(data) -> bool:
    """A run.json this project wrote: an object with the keys every run and eval writes (a run
    also its config hash), not merely any JSON object another tool left under that name."""
    if not isinstance(data, dict) or not {"started", "status", "versions"} <= set(data):
        return False
    return data.get("kind") == "eval" or "config_hash" in data


_NUM = (int, float)
_META_TYPES = {      # run.json's keys and the types its readers rely on
    "name": str, "status": str, "started": str, "finished": str, "command": str, "config_source": str,
    "config_dir": str, "config_hash": str, "git_commit": str, "code_sha256": str, "executor": str, "scheduler": str, "kind": str,
    "config": dict, "machine": dict, "versions": dict, "tasks": dict, "timing": dict, "solver": dict, "tune": dict,
    "fixed_cost_per_case_s": dict, "status_counts": dict, "method_sources": dict, "measurement": dict,
    "workers": int, "n_cases": int, "resumed_ok_cases": int, "wall_s": _NUM, "timeout_s": _NUM,
    "git_dirty": bool, "load_average": list, "sessions": list, "provenance_changed": list,
}
_SESSION_NUMBERS = ("wall_s", "resumed_ok_cases")


def _sane(meta: dict) -> dict:
    """run.json with every value of a wrong type left out (a hand-edited ``machine: "x"`` or
    ``sessions: 5``), so that its readers see a missing value, never a value they would crash on;
    a non-number in ``load_average`` is None in its place, sessions that are not objects are
    dropped, and a session's non-numeric ``wall_s`` is None."""
    out = {}
    for k, v in meta.items():
        want = _META_TYPES.get(k)
        if v is None or want is None:
            out[k] = v
        elif isinstance(v, want) and not (isinstance(v, bool) and want in (int, _NUM)):
            out[k] = v
    if "load_average" in out:         # [start, end]: a bad entry is None in its place
        out["load_average"] = [x if isinstance(x, _NUM) and not isinstance(x, bool) else None
                                for x in out["load_average"]]
    if "sessions" in out:
        out["sessions"] = [{**x, **{k: None for k in _SESSION_NUMBERS
                                    if k in x and (not isinstance(x[k], _NUM) or isinstance(x[k], bool))}}
                           for x in out["sessions"] if isinstance(x, dict)]
    return out


def recorded_specs(meta: dict, frames) -> dict:
    """Task declarations: those recorded in run.json (a hand-edited one whose ``metrics`` is not a
    list of declarations gives way to the installed kind's, and so do ``invalid_when`` rules that
    are not a list of rules with a column and an operator), then known tasks with a CSV in the folder."""
    recorded = meta.get("tasks") if isinstance(meta.get("tasks"), dict) else {}
    specs = {k: v for k, v in recorded.items() if isinstance(v, dict) and isinstance(v.get("metrics"), list)
             and all(isinstance(m, dict) and isinstance(m.get("name"), str) for m in v["metrics"])}
    known = tasks.all_tasks()
    for name, spec in specs.items():     # hand-edited validity rules no version writes: the installed kind's
        rules = spec.get("invalid_when", [])
        if not (isinstance(rules, list) and all(rule_ok(r) for r in rules)):
            specs[name] = {**spec, "invalid_when": known[name].spec()["invalid_when"] if name in known else []}
    for name, task in known.items():
        if name not in specs and name in frames:
            specs[name] = task.spec()
    return specs


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
        """The run's metadata; None when missing, unreadable or not one this project wrote (see
        `run_json_state`)."""
        try:
            data = json.loads(self.run_json.read_text())
        except (OSError, ValueError):
            return None
        return _sane(data) if _is_ours(data) else None

    def run_json_state(self) -> str:
        """``missing``, ``ok`` (a run.json this project wrote) or ``corrupt`` (unreadable, or
        another tool's: nothing in the folder is then taken for ours)."""
        if not self.run_json.exists():
            return "missing"
        return "ok" if self.read_run_json() is not None else "corrupt"

    def write_run_json(self, data: dict) -> None:
        """run.json, indented; a ``"status": "running"`` is followed by `STATUS_ROOM` spaces (JSON
        whitespace), room for a longer status written in place when a full disk refuses a new file."""
        self.path.mkdir(parents=True, exist_ok=True)
        text = json.dumps(data, indent=2, default=str).replace(RUNNING, RUNNING + " " * STATUS_ROOM, 1)
        atomic_write(self.run_json, lambda fh: fh.write(text))

    # ------------------------------------------------------------------------- ownership

    def lock(self, advice: str = "wait for it to finish or choose another --out"):
        """Take the folder's exclusive lock (held until the returned file is closed or the process
        ends); `ShootoutError` naming the holder's pid and ``advice`` when another run holds it, or
        saying why the folder cannot be made."""
        try:
            self.path.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ShootoutError(f"--out {self.path}: cannot make this folder ({exc.strerror or exc})") from None
        try:                             # never through a symlink (it would truncate its target)
            fd = os.open(self.path / ".shootout.lock", os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o644)
            fh = os.fdopen(fd, "r+")
        except OSError as exc:
            why = "it is a symbolic link" if exc.errno == errno.ELOOP else (exc.strerror or str(exc))
            raise ShootoutError(f"{self.path}: cannot take the run folder's lock {self.path / '.shootout.lock'} "
                                f"({why}); every command that writes in a run folder takes it") from None
        try:
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            if exc.errno not in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                fh.close()
                raise
            fh.seek(0)
            holder = fh.read().strip() or "unknown"
            fh.close()
            raise ShootoutError(f"{self.path}: another run is using this folder (pid {holder}); {advice}") from None
        fh.seek(0)
        fh.truncate()
        fh.write(str(os.getpid()))
        fh.flush()
        _HELD_LOCKS[:] = [f for f in _HELD_LOCKS if not f.closed] + [fh]
        return fh

    def foreign_files(self) -> list[str]:
        """Files with the names of a run's outputs (task CSVs, run.json, reports, leaderboard and
        winners tables, ``views/``, ``tune/``) present without a run.json of ours: files this
        project cannot prove it wrote, which a run would overwrite or delete. (``meshes/`` may
        hold the user's meshes: a run only ever removes the files its manifest lists.)"""
        if self.run_json_state() == "ok":
            return []
        found = [n for n in output_names() if (self.path / n).exists()]
        for d in ("views", "tune"):
            p = self.path / d
            if p.exists() and (not p.is_dir() or any(p.iterdir())):
                found.append(d + "/")
        return found

    def foreign_error(self) -> ShootoutError:
        """The refusal of this folder when `foreign_files` lists anything (exit 2)."""
        return ShootoutError(f"--out {self.path}: holds {', '.join(self.foreign_files())} and no run.json written by "
                             "mesh-shootout; these may be your files: choose another --out, or remove them")

    def save_mesh(self, name: str, write) -> Path:
        """Write ``meshes/<name>`` atomically (``write(fh)``), listed in the manifest first."""
        mdir = self.path / "meshes"
        mdir.mkdir(parents=True, exist_ok=True)
        name = Path(name).name
        with open(mdir / MANIFEST, "a") as fh:
            fh.write(name + "\n")
            fh.flush()
            os.fsync(fh.fileno())
        atomic_write(mdir / name, write)
        return mdir / name

    def written_meshes(self) -> set[str]:
        try:
            return {ln.strip() for ln in (self.path / "meshes" / MANIFEST).read_text().splitlines() if ln.strip()}
        except OSError:
            return set()

    def remove_temporaries(self) -> None:
        """Leftover temporary files of ours (`atomic_write`'s ``.<name>.*.tmp``, from a write
        interrupted by a full disk or a kill): those of the run's own file names at the top and
        of the meshes its manifest lists, and any in ``views/`` of a folder whose run.json is ours."""
        where = [(self.path, n) for n in output_names()] + [(self.path / "meshes", Path(n).name)
                                                              for n in self.written_meshes()]
        for d, n in where:
            for f in d.glob(f".{glob.escape(n)}.*.tmp"):
                if _TEMP.fullmatch(f.name[len(n) + 1:]):           # exactly `atomic_write`'s name
                    f.unlink(missing_ok=True)
        vdir = self.path / "views"
        if vdir.is_dir() and self.run_json_state() == "ok":
            for f in vdir.glob(".*.tmp"):
                f.unlink(missing_ok=True)

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
        for name in self._written_views() - keep:
            (vdir / name).unlink(missing_ok=True)
        _atomic_json(vdir / "index.json", {"views": index})

    def _written_views(self) -> set[str]:
        """The view files the stored ``views/index.json`` lists (ours: every other file there is the user's)."""
        try:
            index = json.loads((self.path / "views" / "index.json").read_text())["views"]
        except (OSError, ValueError, KeyError, TypeError):
            return set()
        if not isinstance(index, list):
            return set()
        vdir = self.path / "views"
        names = {Path(str(e["file"])).name for e in index if isinstance(e, dict) and "file" in e}
        return {n for n in names if n not in ("", ".", "..") and ((vdir / n).is_file() or (vdir / n).is_symlink())}

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


class Frames(dict):
    """``{task: DataFrame}`` of a run folder's rows, and ``not_written``: what the end of the run
    could not (re)write (3D views, leaderboard, report), empty when everything was written."""

    def __init__(self, frames: dict, not_written=()):
        super().__init__(frames)
        self.not_written = list(not_written)


def _resolved(p: Path, what: str) -> Path:
    """``p.resolve()``; `ShootoutError` naming ``what`` for a loop of symbolic links (an ELOOP
    from stat; Python < 3.13 raises from resolve itself)."""
    try:
        os.stat(p)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise ShootoutError(f"{what}: a loop of symbolic links") from None
    try:
        return p.resolve()
    except (RuntimeError, OSError) as exc:
        raise ShootoutError(f"{what}: cannot be resolved ({exc})") from None


def _sniff(p: Path, n: int = 4096) -> bytes:
    try:
        with open(p, "rb") as fh:
            return fh.read(n)
    except OSError:
        return b""


OUTPUT_KINDS = {   # what an existing file must look like to be replaced by an output of that kind
    "json": ("a benchmark export (JSON with 'benchmarks')",
             lambda p: (lambda b: b[:4096].lstrip().startswith(b"{") and b'"benchmarks"' in b)(_sniff(p, 1 << 20))),
    "html": ("an HTML page", lambda p: _sniff(p, 512).lstrip()[:15].lower().startswith((b"<!doctype html", b"<html"))),
}


def check_output_file(path, flag: str, protect=(), run_dirs=(), kind: str | None = None) -> None:
    """An output file named on the command line can be written: not a folder, not one of the
    ``protect``ed inputs (e.g. the config being run), not an existing file or a run's own file
    name inside one of the ``run_dirs`` (the runs compared, the run folder written), not an
    existing file of another kind than the output's (``kind``, a key of `OUTPUT_KINDS`: a mesh
    or a config named by mistake is never overwritten), under a writable folder (missing folders
    are made). Checked before any work, so a typo costs exit 2, not a finished run or an
    overwritten input."""
    if path is None:
        return
    if not str(path).strip():                    # Path("") is the current folder
        raise ShootoutError(f"{flag}: an empty path; give a file name")
    p = Path(path)
    rp = _resolved(p, f"{flag} {path}")
    if p.is_dir():
        raise ShootoutError(f"{flag} {path}: is a folder; give a file name")
    if kind is not None and p.is_file() and p.stat().st_size > 0 and not OUTPUT_KINDS[kind][1](p):
        raise ShootoutError(f"{flag} {path}: exists and is not {OUTPUT_KINDS[kind][0]}, so it is not overwritten; "
                            "name a new file or remove it first")
    for q in protect:
        try:
            if q is not None and Path(q).exists() and p.exists() and rp == Path(q).resolve():
                raise ShootoutError(f"{flag} {path}: is an input of this command; writing it would overwrite it")
        except OSError:
            pass
    for d in run_dirs:
        if d is None:
            continue
        rd = Path(d).resolve()
        if rp == rd:
            raise ShootoutError(f"{flag} {path}: is the run folder itself; give a file name")
        inner = rp.relative_to(rd).parts if rd in rp.parents else ()
        if inner and (inner[0] in ("views", "tune", "meshes")
                      or (len(inner) == 1 and (p.exists() or p.name in run_file_names()))):
            raise ShootoutError(f"{flag} {path}: is inside the run folder {d} (its views/, tune/ or meshes/, or one "
                                "of its files); writing it would overwrite the run's own files")
    d = rp.parent
    while not d.exists():
        d = d.parent
    if not d.is_dir() or not os.access(d, os.W_OK | os.X_OK):
        raise ShootoutError(f"{flag} {path}: {d} is not a writable folder")
    try:                                  # access() says yes to root everywhere (/proc too): try it
        fd, probe = tempfile.mkstemp(dir=d, prefix=".shootout-probe-")
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise ShootoutError(f"{flag} {path}: cannot write in {d} ({exc.strerror or exc})") from None


SOURCE_DIRS = ("harness", "methods", "tests", "configs", "benchmarks", "docs", ".git", ".ci")   # never an --out


def check_out_dir(out_dir: Path) -> None:
    """``--out`` must be a folder we can write, or creatable in one (exit 2 before anything is written)."""
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise ShootoutError(f"--out {out_dir}: exists and is not a folder")
    p = _resolved(out_dir, f"--out {out_dir}")
    try:
        home = Path.home().resolve()
    except (RuntimeError, KeyError, OSError):      # no HOME and no passwd entry (a container's uid)
        home = None
    if p == Path(p.anchor) or p == home:
        raise ShootoutError(f"--out {out_dir}: is {'the file system root' if p == Path(p.anchor) else 'your home folder'}"
                            "; give a folder of its own for the run")
    src = Path(__file__).resolve().parent.parent          # the folder holding the harness and methods packages
    if p == src or any(p.is_relative_to(src / d) for d in SOURCE_DIRS):
        what = "source folder" if (src / "pyproject.toml").is_file() else "installation folder"
        raise ShootoutError(f"--out {out_dir}: is mesh-shootout's {what}{'' if p == src else ' or inside it'} "
                            f"({src}); give a folder of its own for the run"
                            + (f" (e.g. {src / 'results' / 'NAME'})" if what == "source folder" else ""))
    while not p.exists():
        p = p.parent
    if not p.is_dir():
        raise ShootoutError(f"--out {out_dir}: {p} is not a folder")
    if not os.access(p, os.W_OK | os.X_OK):
        raise ShootoutError(f"--out {out_dir}: {p} is not writable")
    try:
        st = os.statvfs(p)
        if st.f_flag & os.ST_RDONLY:
            raise ShootoutError(f"--out {out_dir}: {p} is on a read-only file system")
    except (OSError, AttributeError):
        pass


PLAN_COLUMNS = ("case_id", "task", "mesh", "noise_model", "noise_level", "seed", "method", "library", "params")
NOT_RUN = "not run"               # a planned case with no row (in memory only, never in a CSV)


def _plan_row(r: dict) -> dict | None:
    """A plan.csv row with its columns typed as a task CSV's (seed int, noise level float or
    None), or None when a value is not what the harness writes."""
    try:
        params = json.loads(r["params"])
        level = None if r["noise_level"] == "" else float(r["noise_level"])
        seed = int(r["seed"])
    except (TypeError, ValueError, KeyError):
        return None
    ok = (isinstance(params, dict) and r["task"] in tasks.names() and all(r[k] for k in ("case_id", "mesh", "method"))
          and (level is None or np.isfinite(level)))
    return {**r, "noise_level": level, "seed": seed} if ok else None


def with_not_run(frames: dict, plan: list | None) -> dict:
    """``frames`` plus one row of status `NOT_RUN` for every case of ``plan`` (`RunFolder.read_plan`)
    that no CSV holds, e.g. the cases an interrupted run never reached: a seed or a whole cell
    such a run never ran is then missing in the leaderboard and the winners, and the report
    counts the cases. A published pair's level is measured when its case runs, so a planned row
    without one takes the level the pair's other rows give. ``frames`` as they are without a plan."""
    if not plan:
        return frames
    seen = {cid for df in frames.values() if "case_id" in df for cid in df["case_id"].astype(str)}
    pair_level = {}
    for df in frames.values():
        if {"mesh", "noise_model", "noise_level"} <= set(df.columns):
            given = df[(df["noise_model"] == "given") & df["noise_level"].notna()]
            pair_level.update(zip(given["mesh"], given["noise_level"]))
    extra: dict[str, list] = {}
    for r in plan:
        if r["case_id"] in seen:
            continue
        level = r["noise_level"] if r["noise_level"] is not None or r["noise_model"] != "given" \
            else pair_level.get(r["mesh"])
        extra.setdefault(r["task"], []).append({**r, "noise_level": level, "status": NOT_RUN,
                                                "error": "not run: its task's CSV has no row for this case (the run stopped "
                                                         "before it, or the row was removed)"})
    out = dict(frames)
    for task, rows in extra.items():
        add = pd.DataFrame(rows)
        base = out.get(task)
        if base is None:
            base = pd.DataFrame(columns=columns(task))
        if "seed" in base and len(base):
            add = add.astype({"seed": base["seed"].dtype}, errors="ignore")
        out[task] = pd.concat([base, add.reindex(columns=base.columns)], ignore_index=True)
    return out


def load_csv(path) -> pd.DataFrame:
    """Read a task CSV with true/false columns as booleans and ids as strings.

    Only an empty cell is missing (that is how rows are written): a mesh or file named
    ``nan``, ``NA`` or ``null`` keeps its name.
    """
    text = _checked_csv_text(Path(path))
    text_cols = ("case_id", "error", "params", "method", "mesh", "library", "task", "status", "noise_model", "file")
    df = pd.read_csv(io.StringIO(text), dtype={c: str for c in text_cols},      # a file '10.obj' is method "10"
                     keep_default_na=False, na_values=[""], true_values=["true"], false_values=["false"])
    if "error" in df:
        df["error"] = df["error"].fillna("")
    _check_numbers(Path(path), df)
    _check_identity(Path(path), df)
    _check_flags(Path(path), df)
    return df


IDENTITY_COLUMNS = ("case_id", "mesh", "noise_model", "noise_level", "seed", "method", "params", "status")


def _check_flags(path: Path, df: pd.DataFrame) -> None:
    """`ShootoutError` naming the first cell of a task's true/false column that holds something
    else than ``true``, ``false`` or nothing (the column would be read as text, and ``"false"``
    taken for true)."""
    try:
        spec = tasks.get(path.stem)
    except (KeyError, ValueError):
        return
    for c in (m.name for m in spec.metrics if m.kind == "bool"):
        if c not in df:
            continue
        vals = df[c]
        bad = vals.notna() & ~vals.map(lambda v: isinstance(v, (bool, np.bool_)))
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
            raise ShootoutError(f"{path}: damaged CSV: column {c} holds {str(vals.iloc[i])[:40]!r} on line {i + 2}, "
                                "expected true or false")


def _check_identity(path: Path, df: pd.DataFrame) -> None:
    """`ShootoutError` naming the first row whose ``params`` is not a JSON object, whose
    ``method`` is empty or whose ``status`` is not one a run writes: a hand-edited file the
    rankings would otherwise fail on deep in the report."""
    def not_object(v) -> bool:
        try:
            return not isinstance(json.loads(v), dict)
        except (TypeError, ValueError):
            return True
    checks = (("params", lambda v: isinstance(v, str) and not_object(v), "a JSON object ({} when a method has none)"),
              ("method", lambda v: not isinstance(v, str) or not v.strip(), "a method's name"),
              ("status", lambda v: v not in STATUSES, f"one of {', '.join(STATUSES)}"))
    missing = [c for c in IDENTITY_COLUMNS if c not in df]
    if missing and len(df.columns):
        raise ShootoutError(f"{path}: damaged CSV: no column(s) {', '.join(missing)}, which every row of a run has")
    for col, bad, want in checks:
        if col not in df:
            continue
        for i, v in enumerate(df[col].tolist()):
            if bad(v):
                shown = "" if not isinstance(v, str) and pd.isna(v) else str(v)[:40]
                raise ShootoutError(f"{path}: damaged CSV: column {col} holds {shown!r} on line {i + 2}, "
                                    f"expected {want}")


NUMERIC_COMMON = ("n_vertices", "n_faces", "noise_level", "seed", "time_s", "time_min_s", "time_max_s", "time_q1_s",
                  "time_q3_s", "time_cold_s", "repeats", "time_cpu_s", "others_cpu", "threads_busy", "method_mem_mb",
                  "peak_rss_mb")


def _check_numbers(path: Path, df: pd.DataFrame) -> None:
    """`ShootoutError` naming the first cell of a number column (the common timing and size
    columns, a task's float and int metrics) that holds something else: a hand-edited or
    foreign file, which would otherwise fail deep in the report. An infinity is a number (this
    version writes none; older ones did): `compare` orders it and prints ``inf``; the report's
    page shows it blank, as a missing value."""
    try:
        spec = tasks.get(path.stem)
    except (KeyError, ValueError):
        spec = None
    cols = list(NUMERIC_COMMON) + ([m.name for m in spec.metrics if m.kind in ("float", "int")] if spec else [])
    for c in cols:
        if c not in df:
            continue
        vals = df[c]
        num = pd.to_numeric(vals, errors="coerce")
        bad = num.isna() & vals.notna()
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
            raise ShootoutError(f"{path}: damaged CSV: column {c} holds {str(vals.iloc[i])[:40]!r} on line {i + 2}, "
                                "expected a number")


_TORN_SAID: set = set()         # (path, cut text) of torn last lines already said in this process


def _checked_csv_text(path: Path) -> str:
    """The CSV's text without a torn last line; `ShootoutError` naming what is damaged otherwise
    (not UTF-8 text, empty, or lines whose field count differs from the header's)."""
    try:
        text = path.read_bytes().decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ShootoutError(f"{path}: damaged CSV (byte {exc.start} is not UTF-8 text)") from None
    except OSError as exc:
        raise ShootoutError(f"{path}: cannot read ({exc.strerror})") from None
    if "\x00" in text:
        raise ShootoutError(f"{path}: damaged CSV (contains NUL bytes)")
    cut = text[text.rfind("\n") + 1:]
    text = text[:text.rfind("\n") + 1]         # a row cut short by a kill: not data (only "\n" ends a
    if cut and text and (str(path), cut) not in _TORN_SAID:    # line: a form feed in a message does not);
        _TORN_SAID.add((str(path), cut))                          # said once, not silent
        print(f"shootout: warning: {path}: its last line was cut short (a run stopped while writing it): left out "
              f"({cut[:40]!r}{'...' if len(cut) > 40 else ''})", file=sys.stderr)
    if not text:
        raise ShootoutError(f"{path}: empty CSV (no header)")
    try:
        rows = list(csv.reader(io.StringIO(text), strict=True))
    except csv.Error as exc:
        raise ShootoutError(f"{path}: damaged CSV ({exc})") from None
    n = len(rows[0])
    bad = [i + 1 for i, r in enumerate(rows) if len(r) != n]
    if bad:
        raise ShootoutError(f"{path}: damaged CSV: line(s) {', '.join(map(str, bad[:5]))} do not have the "
                            f"header's {n} fields")
    return text


def _atomic_json(path: Path, data) -> None:
    """Write JSON atomically (see `atomic_write`)."""
    atomic_write(path, lambda fh: json.dump(data, fh, separators=(",", ":"), allow_nan=False, default=scalar))


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
