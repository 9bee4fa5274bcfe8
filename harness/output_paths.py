"""Checks on the paths a command writes, made before any work (a refusal is exit 2).

`check_out_dir`: ``--out`` is a folder of its own that can be written (not the file system root,
the home folder, or mesh-shootout's source or installation folder). `check_output_file`: an
output file named on the command line is not a folder, an input of the command, a run folder's
own file, or an existing file of another kind than the output's (`OUTPUT_KINDS`).
"""
from __future__ import annotations

import errno
import os
import tempfile
from pathlib import Path

from .errors import ShootoutError
from .run_files import run_file_names


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
