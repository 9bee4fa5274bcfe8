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

import os
import sys
import threading
import time
import uuid
from pathlib import Path

from ..errors import RunInterrupted, ShootoutError
from ..provenance import usable_cpus
from ..runner import base_row
from .dask_code import CODE_KEY, _CODE, _code_of, _differ, _versions, other_code
from .dask_files import CACHE_DIR_NAME, CACHE_MAX_AGE_S, FILE_KEYS, _hashes, _prune, materialize, ship_files
from .dask_scheduler import SCHEDULER_REASONS, _probe_scheduler, scheduler_went
from .dask_subprocess import STARTUP_S, _ready_at, _subprocess_main, _warm, run_in_subprocess
from .dask_task import ENDED, STARTED, _cancelled, _daemonic, _log, _topic, _worker, _worker_name, run_task

__all__ = ["DaskExecutor",
           "CODE_KEY", "_CODE", "_code_of", "_differ", "_versions", "other_code",
           "CACHE_DIR_NAME", "CACHE_MAX_AGE_S", "FILE_KEYS", "_hashes", "_prune", "materialize", "ship_files",
           "SCHEDULER_REASONS", "_probe_scheduler", "scheduler_went",
           "STARTUP_S", "_ready_at", "_subprocess_main", "_warm", "run_in_subprocess",
           "ENDED", "STARTED", "_cancelled", "_daemonic", "_log", "_topic", "_worker", "_worker_name", "run_task"]


# ----------------------------------------------------------------------------- driver side

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

        def resend(fut, case):
            """Release ``fut`` and submit its case again, awaited with the others."""
            fut.release()
            again = submit(case, sent_of[case.case_id])
            futures[again] = case
            ac.add(again)
        fetch_s = float(os.environ.get("MESH_SHOOTOUT_DASK_WAIT", "120"))
        for fut in self._completed(ac):
            case = futures.pop(fut)
            try:
                # done: its result comes from the worker holding it; where that worker died, Dask
                # computes it again, and a wait that does not end must cost this case, not the run
                row, extras = fut.result(timeout=fetch_s)
            except Exception as exc:  # KilledWorker, CancelledError: one error row; a lost scheduler: stop
                name = type(exc).__name__
                if name != "KilledWorker" and (scheduler_went(exc) or not self._scheduler_alive()):
                    # gone, gone and back (a restart on the same address: the client reconnects, but
                    # the tasks it had out are cancelled), or restarted by a client: the run stops, resumable
                    raise RunInterrupted(f"lost the Dask scheduler {self.scheduler} ({name}); the rows "
                                         "finished so far are saved: continue with --resume") from None
                sent, cid = sent_of[case.case_id], case.case_id
                what = None
                if isinstance(exc, TimeoutError):
                    tries[cid] = tries.get(cid, 0) + 1
                    fut.cancel()
                    if tries[cid] <= 3:
                        resend(fut, case)
                        continue
                    what = (f"its result did not reach the driver within {fetch_s:.0f} s, {tries[cid]} times "
                            "(the worker holding it died and the cluster did not compute it again; "
                            "$MESH_SHOOTOUT_DASK_WAIT sets the wait); --resume runs it again")
                if name == "KilledWorker" and self._ran_when_lost(fut.key, unknown=True) is False:
                    # Dask counts a worker's death against every task assigned to it, also those
                    # queued behind the case that killed it: one that never started is run again
                    waited[cid] = waited.get(cid, 0) + 1
                    if waited[cid] <= 3:
                        resend(fut, case)
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
                        resend(fut, case)
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


if __name__ == "__main__":
    sys.exit(_subprocess_main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else None))
