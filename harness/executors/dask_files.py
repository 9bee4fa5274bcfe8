"""Mesh files sent to Dask workers, so that no shared filesystem is needed.

The driver reads each distinct ``{file: ...}`` (and ``clean:``) file once and tags the case's
spec with the sha1 of its bytes (`ship_files`); the worker writes the bytes it received to a
cache directory private to its user, ``$TMPDIR/mesh-shootout-dask-<uid>/<sha1>/<original name>``,
checks them against the sha1 before each use and points the spec there (`materialize`). A
cached file unused for `CACHE_MAX_AGE_S` is removed (`_prune`).
"""
from __future__ import annotations

import dataclasses
import hashlib
import os
import tempfile
import time
from pathlib import Path

from ..config import Case
from ..errors import InvalidMeshError, ShootoutError

FILE_KEYS = ("file", "clean")
CACHE_MAX_AGE_S = 7 * 24 * 3600      # a worker's cached mesh file unused this long is removed
CACHE_DIR_NAME = "mesh-shootout-dask"


# ----------------------------------------------------------------------------- driver side

def ship_files(cases):
    """Cases as sent (file specs tagged with the sha1 of their bytes) and ``{sha1: bytes}``.

    Each distinct file is read once by the driver; a file the driver cannot read is left
    untagged and the worker reports it (an ``error`` row naming the file); a file whose bytes
    differ from the case's tag (it changed since the run started) is not sent, and the worker
    makes that case an error row saying so.
    """
    data: dict[str, bytes] = {}
    read: dict[str, bytes] = {}
    hashes: dict[str, str | None] = {}
    out = []
    for c in cases:
        if not any(k in c.mesh for k in FILE_KEYS):
            out.append(c)
            continue
        spec = dict(c.mesh)
        for k in FILE_KEYS:
            p = spec.get(k)
            if not isinstance(p, str):
                continue
            if p not in hashes:
                try:
                    raw = Path(p).read_bytes()
                except OSError:
                    hashes[p] = None
                else:
                    hashes[p] = hashlib.sha1(raw).hexdigest()
                    read[hashes[p]] = raw
            expected = spec.get(f"{k}_sha1")
            if hashes[p] is None:
                spec.pop(f"{k}_sha1", None)          # unreadable here: the worker reads the path and says why
            elif expected is None or expected == hashes[p]:
                spec[f"{k}_sha1"] = hashes[p]
                data.setdefault(hashes[p], read[hashes[p]])
            # else: the file changed since the run started; the tag stays, no bytes go, the worker says so
        out.append(dataclasses.replace(c, mesh=spec))
    return out, data


def _hashes(case: Case) -> list[str]:
    return [case.mesh[f"{k}_sha1"] for k in FILE_KEYS if f"{k}_sha1" in case.mesh]


# ----------------------------------------------------------------------------- worker side

def materialize(case: Case, blobs: dict) -> Case:
    """The case with its shipped file bytes written to the worker's cache and the spec pointing there.

    ``blobs`` maps sha1 -> bytes. The file keeps its base name (so the mesh name, the reader
    chosen by extension and error messages are those of a local run).
    """
    if not any(f"{k}_sha1" in case.mesh for k in FILE_KEYS):
        return case
    spec = dict(case.mesh)
    root = Path(tempfile.gettempdir()) / f"{CACHE_DIR_NAME}-{os.getuid()}"     # this user's, not shared
    root.mkdir(mode=0o700, exist_ok=True)
    if root.is_symlink() or root.stat().st_uid != os.getuid() or root.stat().st_mode & 0o077:
        raise ShootoutError(f"{root}: not a private folder of this user (mode {oct(root.stat().st_mode & 0o777)}); "
                            "remove it")
    for k in FILE_KEYS:
        h = spec.pop(f"{k}_sha1", None)
        if h is None:
            continue
        data = blobs.get(h)
        if data is None:
            raise InvalidMeshError(f"{spec[k]}: the file changed since the run started (its bytes no longer "
                                   f"have sha1 {h[:12]}); start the run again")
        if hashlib.sha1(data).hexdigest() != h:
            raise ShootoutError(f"shipped bytes of {spec[k]} do not match their sha1")
        target = root / h / Path(spec[k]).name
        if target.parent.is_dir():
            os.utime(target.parent)       # in use: not pruned
        if not target.is_file() or hashlib.sha1(target.read_bytes()).hexdigest() != h:   # never trust the cache
            target.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=".part.")
            with os.fdopen(fd, "wb") as fh:
                fh.write(data)
            os.replace(tmp, target)       # atomic: concurrent tasks on one machine never see a half file
            _prune(root, keep=h)
        spec[k] = str(target)
    return dataclasses.replace(case, mesh=spec)


def _prune(root: Path, keep: str) -> None:
    """Remove cached files no case has used for `CACHE_MAX_AGE_S` (each use touches its folder)."""
    import shutil
    cutoff = time.time() - CACHE_MAX_AGE_S
    for d in root.iterdir():
        try:
            if d.name != keep and d.is_dir() and not d.is_symlink() and d.stat().st_mtime < cutoff:
                shutil.rmtree(d, ignore_errors=True)
        except OSError:
            pass
