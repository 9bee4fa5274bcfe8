"""Per-input facts shared by the cases of one input within a session.

Every case runs in its own process, so facts a task memoises in ``CaseInput.cache`` (the clean
mesh's topology, the noisy input's own metrics, an exact geodesic reference) would otherwise be
recomputed by each method's case. A task names such entries in ``Task.input_facts``: values that
depend on the case's input alone (mesh, noise model, level, seed, fraction and the measuring
settings), never on the method or its result. After a case, the runner stores those entries in
a private directory of the session (`session`, created with mode 0700 and removed at its end);
later cases of the same input load them before measuring. Computing a fact stays in the case
process, so a mesh that crashes a measurement costs that case's row, never the driver. A missing,
unreadable or concurrently written store is a cache miss, not an error.
"""
from __future__ import annotations

import contextlib
import hashlib
import os
import pickle
import shutil
import tempfile
from pathlib import Path

ENV = "SHOOTOUT_INPUT_STORE"


@contextlib.contextmanager
def session():
    """A private store for the cases run inside the block (in this process and its forks)."""
    if os.environ.get(ENV):
        yield                                # nested: the outer session's store serves
        return
    d = tempfile.mkdtemp(prefix="shootout-inputs-")
    os.environ[ENV] = d
    try:
        yield
    finally:
        os.environ.pop(ENV, None)
        shutil.rmtree(d, ignore_errors=True)


def _path(case) -> Path | None:
    d = os.environ.get(ENV)
    if not d:
        return None
    ident = [sorted(case.mesh.items()), case.noise_model, repr(case.noise_level), case.seed,
             repr(case.fraction), case.hausdorff_samples, repr(case.hausdorff_eps)]
    if "file" in case.mesh:
        with contextlib.suppress(OSError):
            st = os.stat(case.mesh["file"])
            ident.append((st.st_size, st.st_mtime_ns))
    return Path(d) / (hashlib.sha1(repr(ident).encode()).hexdigest() + ".pkl")


def _wanted(key, names) -> bool:
    return key in names or (isinstance(key, tuple) and bool(key) and key[0] in names)


def load(case, names) -> dict:
    """The stored facts of the case's input among ``names`` (a key or a tuple key's first item)."""
    p = _path(case) if names else None
    if p is None or not p.exists():
        return {}
    try:
        with open(p, "rb") as fh:
            data = pickle.load(fh)               # written by this session's own cases only
    except Exception:  # noqa: BLE001 - a torn or concurrent write is a miss
        return {}
    return {k: v for k, v in data.items() if _wanted(k, names)} if isinstance(data, dict) else {}


def save(case, cache: dict, names) -> None:
    """Add the case's facts among ``names`` to its input's store (atomic replace; best effort)."""
    p = _path(case) if names else None
    if p is None:
        return
    facts = {k: v for k, v in cache.items() if _wanted(k, names)}
    if not facts:
        return
    old = load(case, names)
    if all(k in old for k in facts):
        return
    old.update(facts)
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(dir=p.parent, suffix=".tmp")
        with os.fdopen(fd, "wb") as fh:
            pickle.dump(old, fh, protocol=pickle.HIGHEST_PROTOCOL)
        os.replace(tmp, p)
    except Exception:  # noqa: BLE001 - a full disk or a vanished store only costs the reuse
        if tmp is not None:
            with contextlib.suppress(Exception):
                os.unlink(tmp)
