"""Per-input facts shared by the cases of one input within a session.

Every case runs in its own process, so facts a task memoises in ``CaseInput.cache`` (the clean
mesh's topology, the noisy input's own metrics, an exact geodesic reference) would otherwise be
recomputed by each method's case. A task names such entries in ``Task.input_facts``: values that
depend on the case's input alone (mesh, noise model, level, seed, fraction and the measuring
settings), never on the method or its result. After a case, the runner stores those entries in
a private directory of the session (`session`: an unguessable name, mode 0700, removed at the
session's end or, after a driver that was killed, by the next session's `sweep`; known to this
process and its forked case processes only, never through the environment); later cases of the
same task and input load them before measuring. Each fact is its own file; the store holds at
most `MAX_BYTES` in all, and a fact at most a quarter of the free space: one that does not fit
is recomputed by each case instead of kept. Computing a fact stays in the case process, so a
mesh that crashes a measurement costs that case's row, never the driver. A missing, unreadable
or concurrently written store is a cache miss, not an error.
"""
from __future__ import annotations

import contextlib
import hashlib
import os
import pickle
import secrets
import shutil
import socket
import struct
import tempfile
from pathlib import Path

import numpy as np

try:
    import fcntl
except ImportError:                  # not POSIX: no locks, nothing swept
    fcntl = None

_DIR: str | None = None       # this session's private directory; forked case processes inherit it
_LOCK: int | None = None      # the descriptor holding the session's lock (the driver's copy)
PREFIX = "shootout-session-"
LOCK_NAME = "lock"


@contextlib.contextmanager
def session():
    """A private directory for the cases run inside the block (in this process and its forks):
    their input store and the case processes' stderr files (`private_dir`).

    It is made with mode 0700 under an unguessable name and removed at the block's end. While
    the block runs, this process holds an exclusive ``flock`` on its ``lock`` file; the kernel
    drops it when the process dies, however it dies, so a later session removes the directory
    of one whose driver was killed (`sweep`)."""
    global _DIR, _LOCK
    if _DIR is not None:
        yield                                # nested in this process: the outer directory serves
        return
    sweep()
    _DIR, _LOCK = _make_locked_dir()
    try:
        yield
    finally:
        d, lock, _DIR, _LOCK = _DIR, _LOCK, None, None
        shutil.rmtree(d, ignore_errors=True)
        if lock is not None:
            os.close(lock)


def _make_locked_dir() -> tuple[str, int | None]:
    """``(path, lock descriptor)`` of a new private directory, locked before it gets its name
    (made under a hidden name and renamed, so `sweep` never sees it unlocked). Where the temporary
    directory is not writable the path is still returned (the store then misses) with no lock."""
    root = tempfile.gettempdir()
    name = os.path.join(root, PREFIX + secrets.token_hex(16))
    hidden = os.path.join(root, "." + os.path.basename(name))
    fd = None
    try:
        if fcntl is None:
            raise OSError("no flock here")
        os.mkdir(hidden, 0o700)
        fd = os.open(os.path.join(hidden, LOCK_NAME), os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o600)
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        os.write(fd, _host())
        os.rename(hidden, name)
    except OSError:
        if fd is not None:
            os.close(fd)
        shutil.rmtree(hidden, ignore_errors=True)
        return name, None
    return name, fd


def _host() -> bytes:
    """This machine's identity (host name and boot id), written into a session's lock file: a
    temporary directory shared between machines holds locks this one cannot see."""
    try:
        with open("/proc/sys/kernel/random/boot_id", "rb") as fh:
            boot = fh.read().strip()
    except OSError:
        boot = b""
    return socket.gethostname().encode() + b"\n" + boot + b"\n"


def sweep(root: str | None = None) -> int:
    """Remove the private directories (`session`) under ``root`` (the temporary directory) that
    belong to this user, were made on this machine since its last boot, and whose lock nobody
    holds: their driver died without cleaning up (killed, e.g. by the out-of-memory killer).
    Returns how many were removed. A directory without a lock file, another user's or another
    machine's, or a symbolic link, is left alone, as is any whose lock cannot be tested."""
    root = root or tempfile.gettempdir()
    removed = 0
    if fcntl is None:
        return 0
    try:
        entries = [e for e in os.scandir(root) if e.name.startswith(PREFIX)]
    except OSError:
        return 0
    host = _host()
    for e in entries:
        try:
            if not e.is_dir(follow_symlinks=False) or e.stat(follow_symlinks=False).st_uid != os.getuid():
                continue
            fd = os.open(os.path.join(e.path, LOCK_NAME), os.O_RDWR | os.O_NOFOLLOW)   # writable: NFS locks
        except OSError:
            continue
        try:
            if os.read(fd, 4096) != host:
                raise OSError("made on another machine")
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:                      # held (its session is running), or not ours to judge
            os.close(fd)
            continue
        shutil.rmtree(e.path, ignore_errors=True)
        os.close(fd)
        removed += 1
    return removed


def private_dir() -> str | None:
    """The current session's private directory when it exists (else None: use the temporary
    directory)."""
    return _DIR if _DIR is not None and os.path.isdir(_DIR) else None


def drop_lock() -> None:
    """In a forked case process: close the inherited copy of the session's lock descriptor (the
    lock stays with the driver; a process the method leaves behind then never holds it)."""
    global _LOCK
    if _LOCK is not None:
        with contextlib.suppress(OSError):
            os.close(_LOCK)
        _LOCK = None


def _path(case, create: bool = False) -> Path | None:
    if _DIR is None:
        return None
    if create:
        try:
            os.mkdir(_DIR, 0o700)
        except FileExistsError:                # made by another case of this session: check it
            st = os.lstat(_DIR)
            if not os.path.isdir(_DIR) or os.path.islink(_DIR) or st.st_uid != os.getuid() or st.st_mode & 0o077:
                return None
        except OSError:
            return None
    ident = [case.task, sorted(case.mesh.items()), case.mesh_key, case.noise_model, repr(case.noise_level),
             case.seed, repr(case.fraction), tuple(case.plugins), case.hausdorff_samples, repr(case.hausdorff_eps)]
    if "file" in case.mesh:
        with contextlib.suppress(OSError):
            st = os.stat(case.mesh["file"])
            ident.append((st.st_size, st.st_mtime_ns))
    return Path(_DIR) / (hashlib.sha1(repr(ident).encode()).hexdigest() + ".pkl")


MAX_BYTES = 2 * 1024**3       # the store's total size; one fact also at most a quarter of the free space


def _room(directory: Path, size: int) -> bool:
    """Whether a fact of ``size`` bytes may be kept: the store stays within `MAX_BYTES` and the
    fact within a quarter of the free space."""
    try:
        used = sum(e.stat().st_size for e in os.scandir(directory) if e.is_file(follow_symlinks=False))
        free = shutil.disk_usage(directory).free
    except OSError:
        return False
    return used + size <= MAX_BYTES and size <= free // 4


def _wanted(key, names) -> bool:
    return key in names or (isinstance(key, tuple) and bool(key) and key[0] in names)


def _fact_path(p: Path, key, suffix: str = ".pkl") -> Path:
    """One file per fact: ``<input>-<key hash>.pkl`` (``.skip`` marks a fact too large to keep)."""
    return p.with_name(p.stem + "-" + hashlib.sha1(repr(key).encode()).hexdigest()[:20] + suffix)


_MAGIC = b"SHOOTIS1"
_ALIGN = 64                   # each array's bytes start on a multiple of this in the file


def _aligned(pos: int) -> int:
    return -(-pos // _ALIGN) * _ALIGN


def _encode(obj) -> tuple[list, int]:
    """The pieces of a fact's file and its size: `_MAGIC`, the pickle's length and its
    out-of-band buffer sizes, the pickle (protocol 5), then the contiguous arrays' bytes
    written directly from their memory (no serialised copy), each aligned to `_ALIGN`."""
    raws = []

    def out_of_band(buf):
        try:
            raws.append(buf.raw())
        except BufferError:                  # not contiguous: in the pickle stream
            return True
        return False

    head = pickle.dumps(obj, protocol=5, buffer_callback=out_of_band)
    pieces = [_MAGIC + struct.pack(f"<QQ{len(raws)}Q", len(head), len(raws), *(r.nbytes for r in raws)), head]
    pos = sum(len(x) for x in pieces)
    for r in raws:
        pad = _aligned(pos) - pos
        pieces += [b"\0" * pad, r]
        pos += pad + r.nbytes
    return pieces, pos


def _decode(path: str):
    """The object of an `_encode`d file; its arrays are views of one buffer read from it."""
    with open(path, "rb") as fh:
        size = os.fstat(fh.fileno()).st_size
        data = np.empty(size, np.uint8)          # writeable, aligned, not zero-filled
        if fh.readinto(data) != size or data[:8].tobytes() != _MAGIC:
            raise ValueError("not a fact file")
    hl, n = struct.unpack_from("<QQ", data, 8)
    pos = 24 + 8 * n
    if pos + hl > size:
        raise ValueError("a torn fact file")
    sizes = struct.unpack_from(f"<{n}Q", data, 24)
    mv = memoryview(data)
    head, pos = mv[pos:pos + hl], pos + hl
    buffers = []
    for s in sizes:
        pos = _aligned(pos)
        if pos + s > size:
            raise ValueError("a torn fact file")
        buffers.append(mv[pos:pos + s])
        pos += s
    if pos != size:
        raise ValueError("a torn fact file")
    return pickle.loads(head, buffers=buffers)


def load(case, names) -> dict:
    """The stored facts of the case's input among ``names`` (a key or a tuple key's first item)."""
    p = _path(case) if names else None
    if p is None:
        return {}
    out = {}
    try:
        entries = [e.path for e in os.scandir(p.parent) if e.name.startswith(p.stem + "-") and e.name.endswith(".pkl")]
    except OSError:
        return {}
    for path in entries:
        try:
            key, value = _decode(path)           # written by this session's own cases only
        except Exception:  # noqa: BLE001 - a torn or concurrent write is a miss
            continue
        if _wanted(key, names):
            out[key] = value
    return out


def save(case, cache: dict, names) -> None:
    """Keep the case's facts among ``names`` that its input's store lacks, one file each (atomic
    replace; best effort). A fact that does not fit (`_room`) is marked, so that later cases of
    the input neither keep nor serialise it again."""
    p = _path(case, create=True) if names else None
    if p is None:
        return
    for key, value in cache.items():
        if not _wanted(key, names):
            continue
        path, skip = _fact_path(p, key), _fact_path(p, key, ".skip")
        if path.exists() or skip.exists():
            continue
        tmp = None
        try:
            pieces, size = _encode((key, value))
            if not _room(p.parent, size):
                skip.touch()
                continue
            fd, tmp = tempfile.mkstemp(dir=p.parent, suffix=".tmp")
            with os.fdopen(fd, "wb") as fh:
                for piece in pieces:
                    fh.write(piece)
            os.replace(tmp, path)
        except Exception:  # noqa: BLE001 - a full disk or a vanished store only costs the reuse
            if tmp is not None:
                with contextlib.suppress(Exception):
                    os.unlink(tmp)
