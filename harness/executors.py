"""Executors: run cases and yield ``(case, row, meshes)`` as each finishes.

Isolation: every case runs in a fresh child process (forked from a forkserver that has
numpy, scipy and the harness preloaded), so a segfault or abort in a C++ backend costs one
row (status ``error``, the signal named) and a case past its timeout is killed (status
``timeout``). ``serial`` runs in-process without isolation (debugging only).
"""
from __future__ import annotations

import multiprocessing as mp
import signal
import time
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

from .config import Case
from .runner import base_row, run_case

_CTX = None


def _context():
    global _CTX
    if _CTX is None:
        try:
            _CTX = mp.get_context("forkserver")
            _CTX.set_forkserver_preload(["numpy", "scipy.sparse", "harness.runner", "harness.measure"])
        except ValueError:            # no forkserver on this platform
            _CTX = mp.get_context("spawn")
    return _CTX


def _child(conn, case, want_meshes):
    try:
        conn.send(run_case(case, want_meshes=want_meshes))
    finally:
        conn.close()


def _signal_name(code: int) -> str:
    try:
        return signal.Signals(-code).name
    except (ValueError, TypeError):
        return f"signal {-code}"


def run_isolated(case: Case, timeout: float | None = None, want_meshes: bool = False):
    """Run one case in a fresh child process; returns ``(row, meshes)``, never raises."""
    ctx = _context()
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(send, case, want_meshes), daemon=True)
    t0 = time.perf_counter()
    proc.start()
    send.close()
    result = None
    try:
        if recv.poll(timeout):
            try:
                result = recv.recv()
            except EOFError:
                result = None
    finally:
        recv.close()
    if result is None and proc.is_alive() and timeout is not None and time.perf_counter() - t0 >= timeout:
        proc.kill()
        proc.join()
        row = base_row(case)
        row.update(status="timeout", error=f"killed after {timeout:g} s (timeout)")
        return row, {}
    proc.join(5)
    if proc.is_alive():
        proc.kill()
        proc.join()
    if result is not None:
        return result
    row = base_row(case)
    code = proc.exitcode
    if code is not None and code < 0:
        row["error"] = f"worker process died: {_signal_name(code)} (the method crashed its process)"
    else:
        row["error"] = f"worker process exited with code {code} without a result"
    return row, {}


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
        cases = list(cases)
        with ThreadPoolExecutor(max_workers=self.workers) as pool:
            pending = {}
            it = iter(cases)
            for c in it:
                pending[pool.submit(run_isolated, c, self.timeout, want_meshes)] = c
                if len(pending) >= self.workers:
                    break
            while pending:
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in done:
                    c = pending.pop(fut)
                    row, meshes = fut.result()
                    yield c, row, meshes
                    nxt = next(it, None)
                    if nxt is not None:
                        pending[pool.submit(run_isolated, nxt, self.timeout, want_meshes)] = nxt

    def close(self):
        pass


def make_executor(kind: str, workers: int, timeout: float | None, scheduler: str | None):
    """Executor by name: ``local`` (default), ``serial`` or ``dask``."""
    if kind == "serial":
        return SerialExecutor()
    if kind == "dask":
        from .dask_executor import DaskExecutor
        return DaskExecutor(workers=workers, timeout=timeout, scheduler=scheduler)
    return LocalExecutor(workers=workers, timeout=timeout)
