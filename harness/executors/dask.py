"""Run cases on a Dask cluster (``shootout run CONFIG --executor dask --scheduler tcp://HOST:8786``).

Design
------
- One Dask task per case, submitted with ``pure=False``, ``retries=0`` and a unique key, and
  one row per task: whatever Dask does underneath (a task re-run after its worker died,
  ``distributed.scheduler.allowed-failures``), the driver writes exactly one row per case, when
  its future completes. A task that Dask gives up on (``KilledWorker``: the worker process
  itself died, e.g. out of memory) becomes an ``error`` row naming it if its case had started
  (its task logs its start and end, `_log`); one that had only waited on that worker (Dask
  counts a death against every task assigned to the worker) is submitted again, three times at
  most. A scheduler lost, or restarted (on the same address, where the client reconnects but
  the tasks it had out are cancelled, or by any client's ``restart()``), interrupts the run
  (exit 1, resumable). A row whose worker ran other sources than the driver, or has other
  package versions (`other_code`), is an error row.
- Cases are small and self-describing. Bundled and procedural meshes are loaded or
  regenerated on the worker (deterministically, from the package data and the spec). For
  ``{file: ...}`` meshes (and the ``clean:`` file of a pair) the *driver* reads the file's
  bytes and scatters them once per distinct file; the task materialises them in a worker-local
  cache directory (``$TMPDIR/mesh-shootout-dask-<uid>/<sha1>/<original name>``, private to the
  user, its bytes checked against the sha1 before each use) and reads them there
  with the same reader and repair policy as a local run, so no shared filesystem is needed.
  The case id, mesh label and error messages (which name the file's base name) are unchanged.
  Should the worker holding the scattered bytes leave (a restart, ``--lifetime``), the cases
  still waiting for them are cancelled by Dask: they are shipped and submitted again (three
  times at most) instead of becoming error rows.
- Isolation and timeouts hold on the worker: every task runs its case in a child process of
  the worker via `harness.executors.isolation.run_isolated` (a crash is an ``error`` row naming the
  signal, a case past the timeout is killed and recorded as ``timeout``; the worker lives on).
  Dask's nanny starts workers as *daemonic* processes by default, and a daemonic process may
  not start multiprocessing children; on such a worker the task falls back to a fresh
  ``python -m harness.executors.dask`` subprocess per case (same isolation, about a second more
  per case for the interpreter start). Start workers with ``DASK_DISTRIBUTED__WORKER__DAEMON=False``
  to get the faster in-process path.
- Only the driver writes run files (CSV rows, run.json, result meshes); workers return rows and,
  with ``save_meshes``, the mesh arrays.

Workers need the same environment as the driver: this package and the backends installed
(same versions, or the metrics may differ: a worker's rows are refused otherwise), and every
module named under ``plugins:`` importable.
"""
from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import os
import pickle
import signal
import subprocess
import sys
import tempfile
import threading
import time
import uuid
from pathlib import Path

from ..config import Case
from ..errors import InvalidMeshError, RunInterrupted, ShootoutError
from ..provenance import usable_cpus
from ..runner import base_row
from .isolation import cancelled_row
from .procs import end_by, python_child, signal_name

FILE_KEYS = ("file", "clean")
CACHE_MAX_AGE_S = 7 * 24 * 3600      # a worker's cached mesh file unused this long is removed
CACHE_DIR_NAME = "mesh-shootout-dask"
STARTED, ENDED = "started", "ended"   # the events of a task's topic (`_topic`): it began its case, it ended it


# ----------------------------------------------------------------------------- driver side

def _probe_scheduler(address: str) -> None:
    """Ask ``address`` who it is before `distributed.Client` connects: the Client's handshake
    waits for ever on a server that accepts the connection and never answers as Dask (the
    dashboard's HTTP port 8787, any other service). TLS and other schemes are left to the Client."""
    import asyncio
    import socket

    import dask
    from dask.utils import parse_timedelta
    from distributed.comm import connect
    from distributed.comm.addressing import parse_address, parse_host_port
    try:
        scheme, where = parse_address(address)
    except ValueError:
        return                          # the Client names what is wrong with it
    if scheme != "tcp":
        return
    limit = float(parse_timedelta(dask.config.get("distributed.comm.timeouts.connect"), default="s"))
    try:                                # can it be reached at all?
        socket.create_connection(parse_host_port(where), timeout=limit).close()
    except (OSError, ValueError) as exc:
        raise OSError(f"cannot reach {where} ({exc})") from None
    outcome: dict = {}

    async def identity():
        comm = await connect(address, timeout=limit)
        try:
            await asyncio.wait_for(comm.write({"op": "identity"}), limit)
            return await asyncio.wait_for(comm.read(), limit)
        finally:
            comm.abort()

    def probe():                        # a thread of its own: the caller may be inside an event loop (Jupyter)
        try:
            outcome["reply"] = asyncio.run(asyncio.wait_for(identity(), 2 * limit + 1))
        except BaseException as exc:  # noqa: BLE001 - handed to the caller's thread
            outcome["error"] = exc

    t = threading.Thread(target=probe, name="dask-probe", daemon=True)
    t.start()
    t.join(2 * limit + 5)
    exc = outcome.get("error")          # it accepted a connection above: what it did with Dask's
    if t.is_alive() or isinstance(exc, asyncio.TimeoutError):
        raise TimeoutError(f"it accepts connections but gave no Dask answer within {2 * limit + 1:g} s "
                           "(is it another service, e.g. the dashboard's HTTP port?)") from None
    if isinstance(exc, OSError):        # CommClosedError too
        raise OSError(f"it accepts connections but closed Dask's without an answer ({type(exc).__name__}: "
                      f"{exc}); is it another service?") from None
    if exc is not None:                 # bytes that are not Dask's protocol (a banner read as a frame length)
        raise ValueError(f"it answered, but not in Dask's protocol ({type(exc).__name__}: {str(exc)[:100]}); "
                         "is it another service?") from None
    reply = outcome.get("reply")
    if not isinstance(reply, dict) or reply.get("type") != "Scheduler":
        kind = reply.get("type") if isinstance(reply, dict) else type(reply).__name__
        raise ValueError(f"it answered as a {kind}, not a scheduler")


class DaskExecutor:
    """Run cases on a Dask cluster; yields ``(case, row, meshes)`` as each case completes.

    Parameters
    ----------
    workers : int, optional
        Only used without ``scheduler``: the size of the local cluster started for the run.
    timeout : float, optional
        Seconds per case (enforced on the worker); ``None`` for no limit.
    scheduler : str, optional
        Address of a running scheduler (``tcp://HOST:8786``), or a `distributed.Client` /
        cluster object. ``None`` starts a `distributed.LocalCluster` (processes, one thread
        each, non-daemonic workers) and closes it in `close`.
    """

    name = "dask"

    def __init__(self, workers: int | None = None, timeout: float | None = None, scheduler=None, **_):
        try:
            from distributed import Client, LocalCluster
        except ImportError as exc:
            raise ShootoutError(f"--executor dask needs the 'distributed' package ({exc})") from None
        self.timeout = timeout
        self._cluster = None
        self._own_client = True
        self._futures: dict = {}
        self._no_daemon = False
        if scheduler is None:
            # the nanny reads this setting each time it starts a worker process, a restart too (a
            # daemonic worker may not fork: its cases would take the slower subprocess path), so it
            # holds until `close` (of the last executor with a cluster of its own)
            _hold_no_daemon(+1)
            self._no_daemon = True
            try:
                self._cluster = LocalCluster(n_workers=max(1, int(workers or usable_cpus())),
                                             threads_per_worker=1, processes=True,
                                             dashboard_address=None)
                self.client = Client(self._cluster)
            except BaseException:
                _hold_no_daemon(-1)
                self._no_daemon = False
                raise
        elif isinstance(scheduler, Client):
            self.client, self._own_client = scheduler, False
        elif hasattr(scheduler, "scheduler_address"):          # a cluster object (LocalCluster, ...)
            self.client = Client(scheduler)
        else:
            try:
                # connect timeout: dask config distributed.comm.timeouts.connect (30 s by default;
                # env DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT=5s)
                _probe_scheduler(str(scheduler))
                self.client = Client(scheduler)
            except (OSError, TimeoutError, ValueError, TypeError) as exc:
                raise ShootoutError(f"--scheduler: cannot connect to a Dask scheduler at {scheduler!r} "
                                    f"({type(exc).__name__}: {exc}); start one with `dask scheduler` "
                                    "and workers with `dask worker ADDRESS`") from None
        self.scheduler = self.client.scheduler.address

    def n_workers(self) -> int:
        """Worker threads currently in the cluster (the number of cases that run at once)."""
        return sum(w.get("nthreads", 1) for w in self.client.scheduler_info()["workers"].values())

    def _scheduler_alive(self) -> bool:
        try:
            self.client.sync(self.client.scheduler.identity, callback_timeout=5)
            return True
        except Exception:  # noqa: BLE001 - any failure to reach it
            return False

    def _wait_for_workers(self) -> None:
        """Say so while the cluster has no worker; give up after ``$MESH_SHOOTOUT_DASK_WAIT`` s (120)."""
        import sys
        import time
        limit = float(os.environ.get("MESH_SHOOTOUT_DASK_WAIT", "120"))
        t0 = time.perf_counter()
        last = t0 - 10.0
        while self.n_workers() == 0:
            now = time.perf_counter()
            if now - t0 >= limit:
                raise RunInterrupted(f"the Dask scheduler {self.scheduler} has had no worker for {limit:.0f} s; "
                                     "start workers with `dask worker ADDRESS` and run again with --resume")
            if now - last >= 5:
                print(f"shootout: the Dask scheduler has no workers; waiting ({now - t0:.0f} s of {limit:.0f})",
                      file=sys.stderr, flush=True)
                last = now
            time.sleep(0.5)

    def run(self, cases, want_meshes: bool = False):
        from distributed import as_completed
        cases = list(cases)
        if not cases:
            return
        self._wait_for_workers()
        shipped, data = ship_files(cases)
        blobs = {h: self.client.scatter(b, hash=False) for h, b in data.items()}   # once per file
        sent_of: dict = {}
        tries: dict = {}       # per case: cancellations before it ran (its file's holder left)
        died: dict = {}        # per case: cancellations while it ran (its worker died under it)
        waited: dict = {}      # per case: KilledWorker before it started (deaths counted against it while queued)

        def submit(case, sent):
            for h in _hashes(sent):          # scattered bytes lost with their worker: ship them again
                for attempt in range(3):
                    if h not in blobs or blobs[h].status == "finished":
                        break
                    self._wait_for_workers()     # a restarting worker (nanny) takes a while to come back
                    try:
                        blobs[h] = self.client.scatter(data[h], hash=False)
                    except (OSError, TimeoutError) as exc:     # no worker left to take them
                        if attempt == 2:
                            raise RunInterrupted(f"cannot ship {Path(sent.mesh.get('file', '?')).name} to the Dask "
                                                 f"cluster again ({type(exc).__name__}: {exc}); start workers and "
                                                 "continue with --resume") from None
                        time.sleep(1)
            need = {h: blobs[h] for h in _hashes(sent) if h in blobs}
            return self.client.submit(run_task, sent, need, self.timeout, want_meshes,
                                      key=f"shootout-{case.case_id}-{uuid.uuid4().hex[:12]}",
                                      pure=False, retries=0)
        futures = {}
        for case, sent in zip(cases, shipped):
            sent_of[case.case_id] = sent
            futures[submit(case, sent)] = case
        self._futures = futures
        ac = as_completed(list(futures))
        for fut in self._completed(ac):
            case = futures.pop(fut)
            try:
                row, extras = fut.result()
            except Exception as exc:  # KilledWorker, CancelledError: one error row; a lost scheduler: stop
                name = type(exc).__name__
                if name != "KilledWorker" and (scheduler_went(exc) or not self._scheduler_alive()):
                    # gone, gone and back (a restart on the same address: the client reconnects, but
                    # the tasks it had out are cancelled), or restarted by a client: the run stops, resumable
                    raise RunInterrupted(f"lost the Dask scheduler {self.scheduler} ({name}); the rows "
                                         "finished so far are saved: continue with --resume") from None
                sent, cid = sent_of[case.case_id], case.case_id
                what = None
                if name == "KilledWorker" and self._ran_when_lost(fut.key, unknown=True) is False:
                    # Dask counts a worker's death against every task assigned to it, also those
                    # queued behind the case that killed it: one that never started is run again
                    waited[cid] = waited.get(cid, 0) + 1
                    if waited[cid] <= 3:
                        fut.release()
                        again = submit(case, sent)
                        futures[again] = case
                        ac.add(again)
                        continue
                    what = (f"Dask gave up on this case {waited[cid]} times (KilledWorker) while it waited on "
                            "workers that died before it started (another case may kill them); --resume runs it again")
                if "Cancelled" in name and _hashes(sent):
                    # the worker holding the file's bytes left (a restart, --lifetime, or a case that
                    # killed it): every task waiting for them is cancelled, whether it ran or not
                    if self._ran_when_lost(fut.key):
                        died[cid] = died.get(cid, 0) + 1
                        if died[cid] >= 2:
                            what = (f"the Dask worker running this case died each of the {died[cid]} times it ran "
                                    "it (this case, or another one running beside it on that worker, may kill it: "
                                    "memory, a signal to its parent process)")
                    else:
                        tries[cid] = tries.get(cid, 0) + 1
                        if tries[cid] > 3 + sum(died.values()):
                            what = (f"cancelled by Dask {tries[cid]} times before its result reached the driver: "
                                    "each time the worker holding its mesh file's bytes (or its result) left (died or "
                                    "restarted); --resume runs it again")
                    if what is None:
                        fut.release()
                        again = submit(case, sent)
                        futures[again] = case
                        ac.add(again)
                        continue
                row, extras = base_row(case), {}
                what = what or (("the Dask worker running this case died (this case, or another one running "
                                  "beside it on that worker, may have killed it)" if name == "KilledWorker"
                                  else "the Dask task failed") + f" ({name}: {exc})")
                row["error"] = what[:2000]
            fut.release()
            why = other_code(row, case)
            if why and row.get("status") == "ok":
                row, extras = base_row(case), {}
                row["error"] = why
            elif why:                              # its own failure first (e.g. a plugin it cannot import)
                row["error"] = f"{row.get('error') or ''}; {why}".lstrip("; ")[:2000]
            yield case, row, extras
        self._futures = {}

    def _ran_when_lost(self, key, unknown=False):
        """Whether the cancelled task ``key`` was running its case when its worker went: `run_task`
        logs its start and its end to the scheduler, under a topic of its own (`_topic`, so no
        other task's events push them out of the scheduler's bounded log), and a task that ended
        there but whose result was lost with the worker before the driver fetched it ran
        innocently (the log is read again a second later before a started task is blamed).
        ``unknown`` is the answer when the log cannot be read."""
        for wait in (0.0, 1.0):              # an end on a surviving worker may reach the log a moment later
            time.sleep(wait)
            try:
                events = {msg for _, msg in self.client.get_events(_topic(key))}
            except Exception:  # noqa: BLE001 - no record: ``unknown`` (a cancellation counts as one before it ran)
                return unknown
            if ENDED in events or STARTED not in events:
                return False
        return True

    def _completed(self, ac):
        """The futures of ``ac`` as they complete (it may grow meanwhile); while none completes
        and the cluster has no worker, say so every few seconds and give up after
        ``$MESH_SHOOTOUT_DASK_WAIT`` s (workers that all left mid-run would otherwise leave the
        driver silent for ever)."""
        import time
        limit = float(os.environ.get("MESH_SHOOTOUT_DASK_WAIT", "120"))
        empty_since = last_check = last_say = None
        while not ac.is_empty():
            batch = ac.next_batch(block=False)
            if batch:
                empty_since = None
                yield from batch
                continue
            now = time.perf_counter()
            if last_check is None or now - last_check >= 2:
                last_check = now
                if self.n_workers() > 0:
                    empty_since = None
                elif empty_since is None:
                    empty_since = last_say = now
            if empty_since is not None:
                if now - empty_since >= limit:
                    raise RunInterrupted(f"the Dask cluster has had no worker for {limit:.0f} s with cases left; "
                                         "start workers and continue with --resume")
                if now - last_say >= 5:
                    print(f"shootout: the Dask cluster has no workers; waiting ({now - empty_since:.0f} s of "
                          f"{limit:.0f})", file=sys.stderr, flush=True)
                    last_say = now
            time.sleep(0.1)

    def describe(self) -> dict:
        return {"executor": self.name, "workers": self.n_workers(), "scheduler": self.scheduler}

    def close(self):
        """Cancel the futures still out and close what this executor opened. Closing a client
        whose scheduler is gone cancels its reconnection loop, which distributed logs as an
        error with its traceback; the run has said so in one line, so those logs are muted."""
        import logging
        quiet = [logging.getLogger(n) for n in ("distributed.client", "distributed.utils", "distributed.core",
                                                "distributed.batched")]
        levels = [lg.level for lg in quiet]
        for lg in quiet:
            lg.setLevel(logging.CRITICAL)
        try:
            if self._futures:
                self.client.cancel(list(self._futures))
                self._futures = {}
            if self._own_client:
                self.client.close()
            if self._cluster is not None:
                self._cluster.close()
        finally:
            if self._no_daemon:
                _hold_no_daemon(-1)
                self._no_daemon = False
            for lg, lv in zip(quiet, levels):
                lg.setLevel(lv)


_NO_DAEMON = {"holders": 0, "setting": None}
_NO_DAEMON_LOCK = threading.Lock()


def _hold_no_daemon(step: int) -> None:
    """Count the executors whose own LocalCluster needs non-daemonic workers (``step`` +1 or -1):
    the first sets ``distributed.worker.daemon: False``, the last one's close restores it."""
    import dask
    with _NO_DAEMON_LOCK:
        _NO_DAEMON["holders"] += step
        if step > 0 and _NO_DAEMON["holders"] == 1:
            _NO_DAEMON["setting"] = dask.config.set({"distributed.worker.daemon": False})
        elif step < 0 and _NO_DAEMON["holders"] == 0 and _NO_DAEMON["setting"] is not None:
            _NO_DAEMON["setting"].__exit__(None, None, None)
            _NO_DAEMON["setting"] = None


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


def _daemonic() -> bool:
    import multiprocessing as mp
    return bool(mp.current_process().daemon)


def run_task(case: Case, blobs: dict, timeout: float | None, want_meshes: bool):
    """The Dask task: one case, isolated in a child process of the worker; never raises."""
    try:
        case = materialize(case, blobs)
    except InvalidMeshError as exc:         # its file changed since the run started
        row = base_row(case)
        row["error"] = f"InvalidMeshError: {exc}"
        return row, {}
    except Exception as exc:  # a cache directory we cannot write is this case's error, not the run's
        row = base_row(case)
        row["error"] = f"cannot materialise the shipped mesh file on the worker ({type(exc).__name__}: {exc})"
        return row, {}
    _log(STARTED)
    if _daemonic():
        row, meshes = run_in_subprocess(case, timeout, want_meshes, stop=_cancelled)
        code, versions = row.pop(CODE_KEY, (None, None))     # that subprocess's: the code that ran
    else:
        _warm(case)
        code, versions = _code_of(case.plugins), _versions()   # the worker's loaded code, which its forked cases run
        from .isolation import reap_orphans_here, run_isolated
        reap_orphans_here()                       # what a crashed case left comes back to the worker, and dies
        row, meshes = run_isolated(case, timeout, want_meshes, stop=_cancelled)
    if row.get("status") == "unavailable":      # which machine lacks the library
        row["error"] = f"{row.get('error') or ''} (on the worker at {_worker_name()})".lstrip()
    if code is not None:
        row[CODE_KEY] = (code, _worker_name(), versions)
    _log(ENDED)
    return row, meshes


CODE_KEY = "_worker_code"   # a row's (code_sha256, worker, package versions) from `run_task`, checked and dropped by the driver
_CODE: dict = {}


def _versions() -> dict:
    """`harness.provenance.package_versions` of this process, once (what its cases import)."""
    if "versions" not in _CODE:
        from ..provenance import package_versions
        _CODE["versions"] = package_versions()
    return _CODE["versions"]


def _code_of(plugins) -> str:
    """`harness.provenance.code_hash` of this process's sources and ``plugins``, once per process
    and plugin list: for the driver and a forking worker, after their modules are loaded (their
    cases run that code, whatever the files become); a case in a subprocess hashes its own."""
    key = tuple(plugins)
    if key not in _CODE:
        from ..provenance import code_hash
        _CODE[key] = code_hash(key)
    return _CODE[key]


def other_code(row: dict, case: Case) -> str | None:
    """Why ``row`` is not kept: the worker that made it ran other sources (`code_hash`) than this
    driver, e.g. an older checkout on its PYTHONPATH; None when they agree or the row says nothing."""
    theirs = row.pop(CODE_KEY, None)
    if not isinstance(theirs, (tuple, list)) or len(theirs) not in (2, 3):
        return None
    ours = _code_of(case.plugins)
    if theirs[0] != ours:
        return (f"the Dask worker ({theirs[1]}) ran other code than the driver (code_sha256 {theirs[0]}, the "
                f"driver's {ours}: its harness, methods or plugins differ); its row is not kept: give every "
                "worker the driver's code")
    mine, versions = _versions(), theirs[2] if len(theirs) == 3 else None
    other = sorted(k for k in mine if isinstance(versions, dict) and _differ(k, versions.get(k), mine[k]))
    if other:
        return (f"the Dask worker ({theirs[1]}) has other package versions than the driver ("
                + ", ".join(f"{k} {versions[k]}, the driver's {mine[k]}" for k in other)
                + "): the metrics may differ; its row is not kept: give every worker the driver's environment")
    return None


def _differ(package: str, theirs, ours) -> bool:
    """Whether a worker's version of ``package`` differs from the driver's in a way the metrics
    could show: both installed and not equal (Python: another major or minor version). A package
    missing on one side is not compared: a method that needs it is `unavailable` there."""
    if theirs is None or ours is None:
        return False
    if package == "python":
        return str(theirs).split(".")[:2] != str(ours).split(".")[:2]
    return theirs != ours


SCHEDULER_REASONS = ("scheduler-connection-lost", "scheduler-restart")


def scheduler_went(exc: BaseException) -> bool:
    """Whether ``exc`` cancelled a task because its scheduler went (the client lost it, or it
    restarted: on the same address after a crash, or by any client's ``restart()``), not the
    task: distributed's ``FutureCancelledError.reason``."""
    return str(getattr(exc, "reason", "") or "") in SCHEDULER_REASONS


def _topic(key) -> str:
    """The scheduler event topic of the task ``key``: one per task, holding its `STARTED` and
    `ENDED` events (a few hundred bytes on the scheduler per task, kept until it restarts)."""
    return f"mesh-shootout-case:{key}"


def _worker():
    """The Dask worker running this thread's task, or None outside one (a test calling `run_task`)."""
    try:
        from distributed import get_worker
        return get_worker()
    except Exception:  # noqa: BLE001 - ValueError outside a worker; no distributed at all
        return None


def _log(event: str) -> None:
    """Tell the scheduler this task's case begins (`STARTED`) or ended (`ENDED`): a task
    cancelled between the two ran when its worker died, rather than waited for a worker that
    left or finished before it left."""
    w = _worker()
    if w is not None:
        try:
            w.log_event(_topic(w.get_current_task()), event)
        except Exception:  # noqa: BLE001 - a worker closing: the event is lost, the case counts as waiting
            pass


def _cancelled() -> bool:
    """Whether the client gave up on the task this worker thread runs (it cancelled the future:
    the driver was interrupted, or closed): Dask lets the thread run on, so its case is killed."""
    w = _worker()
    if w is None:
        return False
    try:
        ts = w.state.tasks.get(w.get_current_task())
    except Exception:  # noqa: BLE001 - no current task
        return False
    return ts is None or ts.state == "cancelled"


def _worker_name() -> str:
    import socket
    w = _worker()
    return (f"{w.address}, " if w is not None else "") + f"host {socket.gethostname()}"


def _warm(case: Case) -> None:
    """Load the registry, the case's plugins and (bundled/procedural) mesh with its noise frame in
    the worker once, so the forked children inherit them instead of re-importing per case (the
    thread limits are set in each case: a worker may fork from several threads). Best
    effort: any failure happens again in the isolated child and becomes that case's row; a
    plugin is tried in a child of its own first (`harness.plugins.import_plugins`), so one that
    ends its process on import is the case's error row, not a dead worker. Files are left to the
    child (a C++ reader could crash on a malformed one)."""
    try:
        from ..plugins import import_plugins
        import_plugins(case.plugins)
        if not any(k in case.mesh for k in FILE_KEYS):
            from .. import datasets
            src = datasets.cached(case.mesh)
            src.clean.input_notes
            if src.noisy_V is None and case.adds_noise:
                src.clean.noise_frame
    except (Exception, SystemExit):  # noqa: BLE001 - reported by the child, as a row
        pass


def run_in_subprocess(case: Case, timeout: float | None = None, want_meshes: bool = False, stop=None):
    """Run one case in a fresh ``python -m harness.executors.dask`` process; ``(row, meshes)``.

    For processes that may not fork multiprocessing children (daemonic Dask workers). The
    case goes in on stdin (pickled) and the result comes back through a temporary file (the
    method may print to stdout). The child holds stdin open and exits when it reaches EOF,
    so it dies with this process. It runs the case behind a guard (`_subprocess_main`) that
    kills every process the case left, even in a session of its own. Crash -> ``error`` row
    naming the signal; past ``timeout`` -> stopped (SIGTERM to the guard, SIGKILL 10 s later),
    ``timeout`` row; ``stop()`` true (polled twice a second) -> stopped. The timeout counts from
    the moment the child can fork its case (its interpreter started, the harness, the registry,
    the case's plugins and a bundled or procedural mesh loaded (`_warm`): what a forking worker's
    case inherits), which it writes on a pipe; its start-up may take `STARTUP_S` beyond ``timeout``.
    """
    fd, out_path = tempfile.mkstemp(prefix="shootout-case-", suffix=".pkl")
    os.close(fd)
    try:
        ready_r, ready_w = os.pipe()     # the child's clock reading once it can fork the case
        argv, env = python_child("harness.executors.dask", out_path, str(ready_w))   # the worker's sys.path (plugins)
        try:
            proc = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, pass_fds=(ready_w,),
                                    stderr=subprocess.PIPE, env=env, start_new_session=True)   # killpg(0) hits it alone
        except BaseException:
            os.close(ready_r)
            raise
        finally:
            os.close(ready_w)
        err_chunks: list[bytes] = []

        def keep_tail():                 # a flood of output keeps only its last 64 KiB in memory
            kept = b""
            for chunk in iter(lambda: proc.stderr.read1(1 << 16), b""):
                kept = (kept + chunk)[-(1 << 16):]
            err_chunks.append(kept)
        reader = threading.Thread(target=keep_tail, daemon=True)
        reader.start()
        try:
            proc.stdin.write(pickle.dumps((case, want_meshes), protocol=pickle.HIGHEST_PROTOCOL))
            proc.stdin.flush()
        except BrokenPipeError:
            pass
        started = None
        try:
            deadline = None if timeout is None else time.monotonic() + timeout + STARTUP_S
            while True:
                if started is None:
                    started = _ready_at(ready_r)
                    if started is not None and timeout is not None:
                        deadline = started + timeout     # the case's own time, as a forked case's
                left = None if deadline is None else deadline - time.monotonic()
                timed_out = left is not None and left <= 0
                if timed_out or (stop is not None and stop()):
                    proc.terminate()     # the guard kills the case and what it left, then ends
                    try:
                        proc.wait(10)
                    except subprocess.TimeoutExpired:
                        proc.kill()
                        proc.wait()
                    if not timed_out:
                        return cancelled_row(case), {}
                    row = base_row(case)
                    row.update(status="timeout", error=f"killed after {timeout:g} s (timeout)" if started is not None
                               else f"killed: its Python process had not started the case after {timeout + STARTUP_S:g} s")
                    return row, {}
                try:
                    proc.wait(0.5 if left is None else min(0.5, left))
                    break
                except subprocess.TimeoutExpired:
                    continue
        finally:
            os.close(ready_r)
            try:
                os.killpg(proc.pid, 9)   # what the case left running in its session dies with it
            except OSError:
                pass
            try:
                proc.stdin.close()
            except BrokenPipeError:
                pass
            reader.join(5)
        code = proc.returncode
        if code == 0 and os.path.getsize(out_path) > 0:
            with open(out_path, "rb") as fh:
                return pickle.load(fh)
        row = base_row(case)
        tail = b"".join(err_chunks).decode(errors="replace").strip().splitlines()[-1:]
        if code < 0:
            row["error"] = (f"worker process died: {signal_name(code)} (the method crashed its process)"
                            + (f"; last stderr: {tail[0]}" if tail else ""))[:2000]
        else:
            row["error"] = (f"worker process exited with code {code} without a result"
                            + (f": {tail[0]}" if tail else ""))[:2000]
        return row, {}
    finally:
        os.unlink(out_path)
        try:                             # a case killed while it wrote its result leaves this behind
            os.unlink(out_path + ".part")
        except FileNotFoundError:
            pass


STARTUP_S = 60.0     # a case subprocess's start-up (interpreter, imports) allowed beyond ``timeout``


def _ready_at(fd: int) -> float | None:
    """The `time.monotonic` reading (a system-wide clock) a case subprocess wrote on ``fd`` once it
    could fork its case, or None while it has not (never blocks)."""
    import select
    if not select.select([fd], [], [], 0)[0]:
        return None
    data = os.read(fd, 64)
    try:
        return float(data)
    except ValueError:               # it ended before writing: the wait loop sees it end
        return time.monotonic()


def _subprocess_main(out_path: str, ready_fd: int | None = None) -> int:
    """The case process of `run_in_subprocess`, behind a guard: this process becomes a child
    subreaper and forks the case; when the case ends (returns, crashes or is stopped by SIGTERM
    from the worker), the guard kills every process it left, in its process group or out of it
    (``setsid`` and a double fork re-parents them here), then ends as the case did: the same
    exit code, or killed by the same signal."""
    case, want_meshes = pickle.load(sys.stdin.buffer)
    from ..provenance import code_hash, package_versions
    from ..runner import run_case
    from .isolation import become_subreaper, reap_strays
    from .. import tasks
    _warm(case)                  # registry, plugins and bundled mesh, as a forking worker's case inherits them
    tasks.get(case.task)
    become_subreaper()
    if ready_fd is not None:                          # the case's timeout starts here
        os.write(ready_fd, repr(time.monotonic()).encode())
        os.close(ready_fd)
    pid = os.fork()
    if pid == 0:
        try:
            null = os.open(os.devnull, os.O_RDONLY)   # the case reads no input, as a local case's (its
            os.dup2(null, 0)                           # stdin is the pipe its case came on, open till it ends)
            os.close(null)
            result = run_case(case, want_meshes=want_meshes)
            result[0][CODE_KEY] = (code_hash(case.plugins), package_versions())   # what this process loaded and ran
            tmp = out_path + ".part"
            with open(tmp, "wb") as fh:
                pickle.dump(result, fh, protocol=pickle.HIGHEST_PROTOCOL)
            os.replace(tmp, out_path)
            sys.stdout.flush()
            sys.stderr.flush()
        except BaseException:  # noqa: BLE001 - the worker reads no result: an error row with this tail
            import traceback
            traceback.print_exc()
            os._exit(1)
        os._exit(0)                   # no interpreter teardown racing the guard's threads

    def end(sig: int):
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)
        reap_strays()                 # the case and whatever it left (reaps the case too)
        end_by(sig)                   # as the worker will read it

    def die_with_parent():            # stdin EOF: the worker that started us is gone
        while os.read(0, 65536):      # raw fd: no buffered-stream lock held at shutdown
            pass
        end(signal.SIGKILL)

    signal.signal(signal.SIGTERM, lambda *_: end(signal.SIGTERM))
    threading.Thread(target=die_with_parent, daemon=True).start()
    status = os.waitpid(pid, 0)[1]
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    reap_strays()
    if os.WIFSIGNALED(status):        # the worker names the signal that ended the case
        end_by(os.WTERMSIG(status))
    os._exit(os.waitstatus_to_exitcode(status))


if __name__ == "__main__":
    sys.exit(_subprocess_main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else None))
