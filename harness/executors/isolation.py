"""Isolation: one case in one fresh child process, its row back through a pipe.

A segfault or abort in a C++ backend costs one row (status ``error``, the signal named) and a
case past its timeout is killed (status ``timeout``). The child is forked from the driver, which
has the method registry loaded and the meshes of the run cached.

What a method may do, and what it costs:

- crash, abort, hang or exhaust memory: one row (the signal named, or ``timeout``);
- fork: only the case process's own result counts (a forked copy returning from the method
  exits silently), and every process of the case is killed when the case ends, because each
  case runs in its own session and process group (``os.setsid``), killed as a group; a
  descendant that leaves the group (``setsid`` and a double fork) is re-parented to the case
  process (a Linux child subreaper), which kills it at the end of the case; when the case
  process itself dies first, such orphans go to the nearest subreaper above it: the ``shootout``
  command's driver is one while it runs its cases (`become_subreaper`) and kills every child
  of its own that is neither a running case nor one it had before (`reap_strays`);
- signal its process group (``os.killpg(0, ...)``): reaches only its own case;
- signal its parent (``os.kill(os.getppid(), ...)``): the case runs in a child of the process
  the driver forked, a guard (`_guard`) that takes the signals of `_GUARDED` from the driver
  alone, waits for the case and ends as it did; the case dies with it (`_die_with_guard`), so
  it never becomes the driver's child, whatever ends the guard;
- print: the case's stdout goes to /dev/null and its stderr to a temporary file (in the session's
  private directory, `harness.input_store.session`) whose last lines are quoted in the row of a
  case that died; the driver keeps that file under ``STDERR_MAX`` bytes while the case runs
  (`_Job.keep_tail`: past it, only the last ``STDERR_TAIL`` bytes are kept), so a flood of output
  cannot fill the disk;
- SIGINT (Ctrl-C) is ignored by case processes and always reaches the driver: signals are blocked
  while a case is forked and registered, so an interrupt cannot be lost inside the fork.
"""
from __future__ import annotations

import contextlib
import gc
import multiprocessing as mp
import os
import select
import signal
import tempfile
import threading
import time

from .. import input_store
from ..config import Case
from ..results import close_inherited_locks
from ..runner import base_row, run_case
from .guard import _GUARD_WAITS, _die_with_guard, _guard
from .procs import signal_name
from .subreaper import _children, become_subreaper, reap_strays


STDERR_MAX = 16 << 20          # a case's stderr file is cut back to its tail past this size
STDERR_TAIL = 64 << 10


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


_SIGNALS = (signal.SIGINT, signal.SIGTERM)


@contextlib.contextmanager
def signals_blocked():
    """Hold SIGINT/SIGTERM while a case is forked and registered: an interrupt that arrives during
    ``fork`` would otherwise be raised inside an at-fork hook, where Python ignores it."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, _SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _isolate(stderr_path: str | None) -> None:
    """In the child: own session and process group, no SIGINT, output away from the driver's."""
    try:
        os.setsid()
    except OSError:
        pass
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, _SIGNALS)
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, 1)
        os.close(devnull)
        if stderr_path:
            # appending: when the driver cuts the file back to its tail, writes continue after it
            err = os.open(stderr_path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_APPEND, 0o600)
            os.dup2(err, 2)
            os.close(err)
    except OSError:
        pass


def _child(conn, case, want_meshes, own_reader_fd=None, want_view=False, stderr_path=None):
    # The objects inherited from the driver go to the permanent generation first thing (an O(1)
    # splice that touches none of them): the case's garbage collector then never walks them. A
    # full collection in the case (it can come at any allocation, e.g. an import) would
    # otherwise write to every inherited object and copy the driver's heap page by page
    # (about 40 MB, 75 ms here). The driver's own collector is left as it was.
    gc.freeze()
    input_store.drop_lock()
    close_inherited_locks()              # the run folder's lock stays the driver's alone
    _isolate(stderr_path)
    if own_reader_fd is not None:
        os.close(own_reader_fd)
    guard = 0
    if hasattr(os, "fork") and hasattr(signal, "pthread_sigmask"):   # the case runs below a guard, never the driver
        old = signal.pthread_sigmask(signal.SIG_BLOCK, _GUARD_WAITS)  # held from the fork on: the guard waits for them
        parent = os.getpid()
        guard = os.fork()
        if guard:
            conn.close()
            _guard(guard)
        signal.pthread_sigmask(signal.SIG_SETMASK, old)
        _die_with_guard(parent)
    _die_with_driver(conn, None)
    pid = os.getpid()
    become_subreaper()                    # descendants that leave the process group come back here
    try:
        result = run_case(case, want_meshes=want_meshes, want_view=want_view)
        if os.getpid() != pid:            # a copy the method forked: only the case process answers
            os._exit(0)
        # every process the case left behind, in or out of its group, before the result goes: once
        # the driver has it, it closes its end and the die-with-driver watch ends this process
        # (closing our own end ends it too), which left such processes to whoever reaps orphans
        reap_strays()
        conn.send(result)
    finally:
        if os.getpid() != pid:
            os._exit(0)
        reap_strays()
        conn.close()


def _tail(path: str | None, n: int = 3) -> str:
    try:
        with open(path, "rb") as fh:
            fh.seek(max(0, os.path.getsize(path) - 4000))
            lines = [ln.strip() for ln in fh.read().decode(errors="replace").splitlines() if ln.strip()]
        return " | ".join(lines[-n:])[:600]
    except (OSError, TypeError):
        return ""


class _Job:
    """A case running in its own child process."""

    def __init__(self, case: Case, want_meshes: bool, want_view: bool = False):
        """Start the case process. Call with `signals_blocked` held until the job is registered."""
        ctx = _context()
        self.case = case
        self.conn, send = ctx.Pipe(duplex=False)
        try:
            fd, self.stderr_path = tempfile.mkstemp(prefix="shootout-case-", suffix=".err",
                                                    dir=input_store.private_dir())   # swept with it
        except OSError:                       # the private directory went away: the plain one
            fd, self.stderr_path = tempfile.mkstemp(prefix="shootout-case-", suffix=".err")
        os.close(fd)
        own = self.conn.fileno() if ctx.get_start_method() == "fork" else None   # inherited copy
        self.proc = ctx.Process(target=_child, args=(send, case, want_meshes, own, want_view, self.stderr_path),
                                daemon=True)
        self.t0 = time.perf_counter()
        self.proc.start()
        send.close()

    @property
    def sentinel(self):
        return self.proc.sentinel

    def ended(self) -> bool:
        """The case process has exited (its exit status is known)."""
        return self.proc.exitcode is not None

    def keep_tail(self, limit: int = STDERR_MAX, tail: int = STDERR_TAIL) -> None:
        """Cut the case's stderr file back to its last ``tail`` bytes once it exceeds ``limit``
        (the case appends, so it writes on after the kept tail); lines written in between are
        lost, which only a flood of output can notice."""
        try:
            if os.path.getsize(self.stderr_path) <= limit:
                return
            fd = os.open(self.stderr_path, os.O_RDWR)
            try:
                size = os.fstat(fd).st_size
                os.lseek(fd, max(0, size - tail), os.SEEK_SET)
                kept = os.read(fd, tail)
                os.ftruncate(fd, 0)
                os.lseek(fd, 0, os.SEEK_SET)
                os.write(fd, f"[{size - len(kept)} bytes of earlier output dropped]\n".encode() + kept)
            finally:
                os.close(fd)
        except OSError:
            pass

    def _kill_group(self) -> None:
        """Kill every process left in the case's process group (its own session)."""
        pid = self.proc.pid
        if pid:
            try:
                os.killpg(pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError, OSError):
                pass

    def _cleanup(self) -> None:
        self._kill_group()
        try:
            os.unlink(self.stderr_path)
        except OSError:
            pass

    def collect(self):
        """``(row, extras)`` once the pipe is readable or the process has ended (a result, or an
        error row naming how the process died)."""
        result = None
        try:
            # the process may have ended with its message still in flight: give the pipe a moment
            if self.conn.poll(0) or self.conn.poll(2.0):
                result = self.conn.recv()
        except (EOFError, OSError):
            result = None                     # died without sending
        except Exception as exc:  # noqa: BLE001 - an unpicklable or corrupted message is this case's error
            result = ("garbled", exc)
        self.conn.close()
        with contextlib.suppress(OSError):            # a guard its method stopped (SIGSTOP to its parent) goes on
            if self.proc.pid:
                os.kill(self.proc.pid, signal.SIGCONT)
        self.proc.join(10)
        if self.proc.is_alive():
            self.proc.kill()
            self.proc.join()
        tail = _tail(self.stderr_path)
        self._cleanup()
        if isinstance(result, tuple) and len(result) == 2 and isinstance(result[0], dict):
            return result
        row = base_row(self.case)
        code = self.proc.exitcode
        if isinstance(result, tuple) and result and result[0] == "garbled":
            row["error"] = f"the case process sent a malformed result ({type(result[1]).__name__}: {result[1]})"
        elif code is not None and code < 0:
            row["error"] = f"worker process died: {signal_name(code)} (the method crashed its process)"
        else:
            row["error"] = f"worker process exited with code {code} without a result"
        if tail:
            row["error"] += f"; last stderr: {tail}"
        return row, {}

    def _stop(self) -> None:
        """Stop the case: SIGTERM to its guard, which kills the case and reaps whatever the case
        left, even outside its group (no subreaper above may be there to do it: `harness.run`);
        SIGKILL if it has not ended within 2 s."""
        with contextlib.suppress(OSError):
            self.proc.terminate()
        self.proc.join(2)
        if self.proc.is_alive():
            self.proc.kill()
        self.proc.join()

    def kill_timeout(self, timeout: float):
        self._stop()
        self.conn.close()
        self._cleanup()
        row = base_row(self.case)
        row.update(status="timeout", error=f"killed after {timeout:g} s (timeout)")
        return row, {}

    def abort(self) -> None:
        """Kill the case (driver interrupted)."""
        self._stop()
        self._cleanup()


def cancelled_row(case: Case) -> dict:
    """The row of a case killed because its caller gave up on it (nobody records it)."""
    row = base_row(case)
    row["error"] = "cancelled: the run that asked for this case stopped waiting for it"
    return row


_RUNNING: set = set()              # pids of the case processes `run_isolated` has running, any thread


def _kill_running_at_exit() -> None:
    """At interpreter exit, before multiprocessing's own hook (registered earlier, so run later)
    sends SIGTERM to its daemonic children and joins them: kill the running cases' guards and
    groups outright, so a case whose method keeps signalling its parent (which can merge with
    that SIGTERM) does not hold the exit until it ends."""
    for pid in list(_RUNNING):
        with contextlib.suppress(OSError):
            os.killpg(pid, signal.SIGKILL)
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)


import atexit  # noqa: E402
import multiprocessing.util  # noqa: E402,F401 - registers its exit hook now, so that this one, later, runs first
atexit.register(_kill_running_at_exit)
_RUNNING_LOCK = threading.Lock()    # held while one starts (until registered) and while orphans are reaped
_REAP = {"on": False}


def reap_orphans_here() -> None:
    """Make this process a child subreaper for the cases `run_isolated` runs in it (a Dask worker
    forking cases from several threads): the processes a case leaves behind after its case
    process died first (a crash, a timeout) come here and are killed when a case ends. Only
    children in another session than this process's are touched (a case runs in a session of its
    own, and so do processes that left it): the process's own children stay."""
    with _RUNNING_LOCK:
        if not _REAP["on"]:
            _REAP["on"] = become_subreaper()


def _reap_orphans() -> None:
    if not _REAP["on"]:
        return
    with _RUNNING_LOCK:
        me, keep = os.getsid(0), set(_RUNNING)
        for c in _children(os.getpid()):
            with contextlib.suppress(OSError):
                if os.getsid(c) == me:
                    keep.add(c)
        reap_strays(keep)


def run_isolated(case: Case, timeout: float | None = None, want_meshes: bool = False, want_view: bool = False,
                 stop=None):
    """Run one case in a fresh child process; returns ``(row, extras)``, never raises.
    ``stop``: a callable polled twice a second; when it returns true the case is killed (its
    caller gave up on it) and the row says so."""
    from multiprocessing.connection import wait as mp_wait
    with _RUNNING_LOCK, signals_blocked():
        job = _Job(case, want_meshes, want_view)
        _RUNNING.add(job.proc.pid)
    try:
        deadline = None if timeout is None else time.perf_counter() + timeout
        while True:
            left = None if deadline is None else deadline - time.perf_counter()
            if left is not None and left <= 0:
                return job.kill_timeout(timeout)
            if stop is not None and stop():
                job.abort()
                return cancelled_row(case), {}
            if mp_wait([job.conn, job.sentinel], 0.5 if left is None else min(0.5, left)) or job.ended():
                return job.collect()
            job.keep_tail()
    except BaseException:
        job.abort()
        raise
    finally:
        with _RUNNING_LOCK:
            _RUNNING.discard(job.proc.pid)
        _reap_orphans()
