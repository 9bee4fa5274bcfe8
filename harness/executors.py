"""Executors: run cases and yield ``(case, row, meshes)`` as each finishes.

Isolation: every case runs in a fresh child process forked from the driver (which has the
method registry loaded and the meshes of the run cached), so a segfault or abort in a C++
backend costs one row (status ``error``, the signal named) and a case past its timeout is
killed (status ``timeout``). The local executor is a single-threaded scheduler waiting on the
children's pipes and sentinels: no threads in the forking process, and no re-import of the
user's ``__main__`` (scripts need no ``if __name__ == "__main__"`` guard).
``serial`` runs in-process without isolation (debugging only).
"""
from __future__ import annotations

import multiprocessing as mp
import os
import select
import signal
import threading
import time
from multiprocessing.connection import wait as mp_wait

from .config import Case
from .runner import base_row, run_case


def _context():
    try:
        return mp.get_context("fork")
    except ValueError:                 # no fork on this platform (Windows): spawn still isolates
        return mp.get_context("spawn")


def _die_with_driver(conn, own_reader_fd) -> None:
    """In the child: exit as soon as no process can read our result any more (driver killed).

    A forked child outlives a SIGKILLed driver (it is re-parented), so a sleeping or long case
    would run on as an orphan. Linux reports POLLERR on a pipe's write end once every read end
    is closed. The child first closes its inherited copy of its own read end; the copies of
    older siblings' read ends it inherited are released when it exits, so after the driver
    dies the children go youngest first, each in turn.
    """
    if own_reader_fd is not None:
        os.close(own_reader_fd)
    if not hasattr(select, "poll"):
        return

    def watch():
        p = select.poll()
        p.register(conn.fileno(), 0)  # no events asked: only POLLERR/POLLHUP/POLLNVAL wake us
        while not p.poll():
            pass
        os._exit(70)

    threading.Thread(target=watch, name="die-with-driver", daemon=True).start()


def _child(conn, case, want_meshes, own_reader_fd=None):
    _die_with_driver(conn, own_reader_fd)
    try:
        conn.send(run_case(case, want_meshes=want_meshes))
    finally:
        conn.close()


def _signal_name(code: int) -> str:
    try:
        return signal.Signals(-code).name
    except (ValueError, TypeError):
        return f"signal {-code}"


class _Job:
    """A case running in its own child process."""

    def __init__(self, case: Case, want_meshes: bool):
        ctx = _context()
        self.case = case
        self.conn, send = ctx.Pipe(duplex=False)
        own = self.conn.fileno() if ctx.get_start_method() == "fork" else None   # inherited copy
        self.proc = ctx.Process(target=_child, args=(send, case, want_meshes, own), daemon=True)
        self.t0 = time.perf_counter()
        self.proc.start()
        send.close()

    def collect(self):
        """``(row, meshes)`` once the pipe is readable (a result, or EOF when the child died)."""
        try:
            result = self.conn.recv()
        except (EOFError, OSError):
            result = None
        self.conn.close()
        self.proc.join(10)
        if self.proc.is_alive():
            self.proc.kill()
            self.proc.join()
        if result is not None:
            return result
        row = base_row(self.case)
        code = self.proc.exitcode
        if code is not None and code < 0:
            row["error"] = f"worker process died: {_signal_name(code)} (the method crashed its process)"
        else:
            row["error"] = f"worker process exited with code {code} without a result"
        return row, {}

    def kill_timeout(self, timeout: float):
        self.proc.kill()
        self.proc.join()
        self.conn.close()
        row = base_row(self.case)
        row.update(status="timeout", error=f"killed after {timeout:g} s (timeout)")
        return row, {}


def run_isolated(case: Case, timeout: float | None = None, want_meshes: bool = False):
    """Run one case in a fresh child process; returns ``(row, meshes)``, never raises."""
    job = _Job(case, want_meshes)
    if job.conn.poll(timeout):
        return job.collect()
    return job.kill_timeout(timeout)


class SerialExecutor:
    """In-process, one case at a time, no isolation or timeout (for debugging)."""

    name = "serial"

    def __init__(self, **_):
        pass

    def run(self, cases, want_meshes=False):
        for c in cases:
            row, meshes = run_case(c, want_meshes=want_meshes)
            yield c, row, meshes

    def close(self):
        pass


class LocalExecutor:
    """``workers`` cases at a time, each in its own child process (isolation + timeout)."""

    name = "local"

    def __init__(self, workers: int = 1, timeout: float | None = None, **_):
        self.workers = max(1, int(workers))
        self.timeout = timeout

    def run(self, cases, want_meshes=False):
        todo = list(cases)
        _warm_mesh_cache(todo)
        todo.reverse()
        running: list[_Job] = []
        try:
            while todo or running:
                while todo and len(running) < self.workers:
                    running.append(_Job(todo.pop(), want_meshes))
                wait_s = None
                if self.timeout is not None:
                    now = time.perf_counter()
                    wait_s = max(0.0, min(j.t0 + self.timeout - now for j in running))
                ready = mp_wait([j.conn for j in running], timeout=wait_s)
                for job in [j for j in running if j.conn in ready]:
                    running.remove(job)
                    row, meshes = job.collect()
                    yield job.case, row, meshes
                if self.timeout is not None:
                    now = time.perf_counter()
                    for job in [j for j in running if now - j.t0 >= self.timeout and j.conn not in ready]:
                        running.remove(job)
                        row, meshes = job.kill_timeout(self.timeout)
                        yield job.case, row, meshes
        finally:
            for job in running:                # interrupted: leave no orphan behind
                job.proc.kill()
                job.proc.join()

    def close(self):
        pass


def _warm_mesh_cache(cases) -> None:
    """Load each distinct bundled or procedural mesh once in the driver so forked children
    inherit it. File meshes are never read here: a reader that crashes on a bad file must
    cost that file's rows, not the driver (best effort: failures fail again, as error rows)."""
    from . import datasets
    seen = set()
    for c in cases:
        if "file" in c.mesh:
            continue
        key = repr(sorted(c.mesh.items()))
        if key in seen or len(seen) >= 8:
            continue
        seen.add(key)
        try:
            datasets.load(c.mesh)
        except Exception:  # noqa: BLE001 - the case's own child reports it as an error row
            pass


def make_executor(kind: str, workers: int, timeout: float | None, scheduler: str | None):
    """Executor by name: ``local`` (default), ``serial`` or ``dask``."""
    if kind == "serial":
        return SerialExecutor()
    if kind == "dask":
        from .dask_executor import DaskExecutor
        return DaskExecutor(workers=workers, timeout=timeout, scheduler=scheduler)
    return LocalExecutor(workers=workers, timeout=timeout)
