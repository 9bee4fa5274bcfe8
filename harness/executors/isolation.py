"""Isolation: one case in one fresh child process, its row back through a pipe.

A segfault or abort in a C++ backend costs one row (status ``error``, the signal named) and a
case past its timeout is killed (status ``timeout``). The child is forked from the driver, which
has the method registry loaded and the meshes of the run cached.
"""
from __future__ import annotations

import multiprocessing as mp
import os
import select
import signal
import threading
import time

from ..config import Case
from ..runner import base_row, run_case


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


def _child(conn, case, want_meshes, own_reader_fd=None, want_view=False):
    _die_with_driver(conn, own_reader_fd)
    try:
        conn.send(run_case(case, want_meshes=want_meshes, want_view=want_view))
    finally:
        conn.close()


def signal_name(code: int) -> str:
    """'SIGSEGV' for a process exit code -11 (a process killed by that signal)."""
    try:
        return signal.Signals(-code).name
    except (ValueError, TypeError):
        return f"signal {-code}"


class _Job:
    """A case running in its own child process."""

    def __init__(self, case: Case, want_meshes: bool, want_view: bool = False):
        ctx = _context()
        self.case = case
        self.conn, send = ctx.Pipe(duplex=False)
        own = self.conn.fileno() if ctx.get_start_method() == "fork" else None   # inherited copy
        self.proc = ctx.Process(target=_child, args=(send, case, want_meshes, own, want_view), daemon=True)
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
            row["error"] = f"worker process died: {signal_name(code)} (the method crashed its process)"
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


def run_isolated(case: Case, timeout: float | None = None, want_meshes: bool = False, want_view: bool = False):
    """Run one case in a fresh child process; returns ``(row, extras)``, never raises."""
    job = _Job(case, want_meshes, want_view)
    if job.conn.poll(timeout):
        return job.collect()
    return job.kill_timeout(timeout)
