"""A run folder's disk that fills up: `DiskFull` (exit 1, not a config problem), the errnos
that mean no room (`NO_ROOM`: a full disk, a quota, the ``ulimit -f`` file-size limit), the
message saying where, why and what to do, and the last resort of overwriting run.json's status
in place, which needs no new disk block."""
from __future__ import annotations

import errno
import os
from pathlib import Path

from .errors import ShootoutError


def _inside(path, folder) -> bool:
    """Whether ``path`` lies in ``folder`` (both made absolute, links not followed)."""
    return Path(os.path.abspath(path)).is_relative_to(Path(os.path.abspath(folder)))


class DiskFull(ShootoutError):
    """The run folder's disk filled up (exit 1: not a config problem)."""

    exit_code = 1


def _write_status_in_place(folder, status: str) -> None:
    """Overwrite run.json's ``"status": "running"`` and the spaces after it (`RunFolder.write_run_json`
    leaves room) in place, which needs no new disk block, when a full disk refuses a new file. A
    status that does not fit is not written (the file stays valid JSON)."""
    from .results import RUNNING, STATUS_ROOM
    try:
        with open(folder.run_json, "r+b") as fh:
            data = fh.read()
            old = (RUNNING + " " * STATUS_ROOM).encode()
            i = data.find(old)
            new = f'"status": "{status}"'.encode()
            if i >= 0 and len(new) <= len(old):
                fh.seek(i)
                fh.write(new.ljust(len(old)))
                fh.flush()
                os.fsync(fh.fileno())
    except OSError:
        pass


NO_ROOM = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)


def _no_room(exc: OSError, out_dir, then: str = "the run is marked interrupted and nothing half-written was "
             "kept; make room (or raise the limit), then continue with --resume") -> str:
    """The message of a write that found no room: where (the file, when the error names one: the
    run folder, or elsewhere such as the cases' temporary files in ``TMPDIR``), why (a full
    disk, a quota, or the file-size limit of ``ulimit -f``), and ``then``, what was kept and what to do."""
    import tempfile
    why = {errno.EFBIG: "a file reached the size limit this process may write (ulimit -f)",
           errno.EDQUOT: "the disk quota is used up"}.get(exc.errno, "the disk is full")
    where = Path(exc.filename) if isinstance(exc.filename, (str, bytes, os.PathLike)) and exc.filename else None
    note = ""
    if where is not None and not _inside(where, out_dir):
        note = (f" (not in the run folder {out_dir}: the cases' temporary files go to {tempfile.gettempdir()}, "
                "set by TMPDIR)")
    return f"{where or out_dir}: {why} ({exc.strerror}){note}; {then}"
