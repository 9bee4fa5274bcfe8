"""How a run writes the files at the top of its folder, and their names.

`atomic_write`: a temporary file in the same folder, fsynced, chmodded to the umask's default and
renamed over the name, so no reader sees half a file. A task CSV row is one line ending in a
newline (`format_row`, `write_csv_rows`). `output_names` and `run_file_names`: the files a run
writes at the top of its folder. `close_inherited_locks` closes, in a forked case process, its
copies of the run-folder locks the driver holds (`RunFolder.lock` records them).
"""
from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import re
import tempfile
from pathlib import Path

from . import tasks
from .schema import cell, columns, scalar, task_file

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


def _atomic_json(path: Path, data) -> None:
    """Write JSON atomically (see `atomic_write`)."""
    atomic_write(path, lambda fh: json.dump(data, fh, separators=(",", ":"), allow_nan=False, default=scalar))
