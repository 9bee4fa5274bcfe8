"""numba's on-disk cache of a kernel module that compiles functions of other modules into its own.

numba keys a cached function by its own file only: a function that calls a jitted function of
another module compiles that one into itself, so an edited dependency (a ``git pull`` changes
only the files that changed) would otherwise keep running the old machine code.
`drop_stale_cache` keeps a hash of the dependencies beside the cache and removes the module's
cache files when it changed.
"""
from __future__ import annotations

import hashlib
import os
from pathlib import Path


def drop_stale_cache(here: Path | str, deps: tuple[str, ...]) -> bool:
    """Remove the numba cache files of the module ``here`` when one of ``deps`` (file names beside
    it) changed since they were written. The dependencies' hash is kept beside the cache
    (``__pycache__/<module>.deps``). Returns True when files were removed; any file-system error
    leaves things as they are (numba then falls back on its own rules)."""
    here = Path(here).resolve()
    cache, stem = here.parent / "__pycache__", here.stem
    stamp = cache / f"{stem}.deps"
    try:
        digest = hashlib.sha256()
        for name in deps:
            digest.update(name.encode() + b"\0" + hashlib.sha256(here.with_name(name).read_bytes()).digest())
        digest = digest.hexdigest()
        if stamp.is_file() and stamp.read_text() == digest:
            return False
        stale = [f for f in cache.glob(f"{stem}.*") if f.suffix in (".nbi", ".nbc")] if cache.is_dir() else []
        for f in stale:
            f.unlink(missing_ok=True)
        cache.mkdir(exist_ok=True)
        tmp = stamp.with_name(f"{stamp.name}.{os.getpid()}.tmp")   # whole or absent to a concurrent first import
        tmp.write_text(digest)
        os.replace(tmp, stamp)
        return bool(stale)
    except OSError:
        return False
