"""One case in a fresh ``python -m harness.executors.dask`` process, for Dask workers that may
not fork multiprocessing children (daemonic workers): `run_in_subprocess` on the worker,
`_subprocess_main` in that process (a guard that forks the case and kills whatever it left),
and `_warm`, what a worker (or that process) loads once before its cases: the registry, the
case's plugins and a bundled or procedural mesh.
"""
from __future__ import annotations

import contextlib
import os
import pickle
import signal
import subprocess
import sys
import tempfile
import threading
import time

from ..config import Case
from ..runner import base_row
from .dask_code import CODE_KEY
from .dask_files import FILE_KEYS
from .isolation import cancelled_row
from .procs import end_by, python_child, signal_name


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


def run_in_subprocess(case: Case, timeout: float | None = None, want_meshes: bool = False, stop=None,
                      want_view: bool = False):
    """Run one case in a fresh ``python -m harness.executors.dask`` process; ``(row, meshes)``
    (`harness.runner.run_case`'s extras: the meshes with ``want_meshes``, the view's with
    ``want_view``).

    For processes that may not fork multiprocessing children (daemonic Dask workers, a driver
    that started GNU OpenMP: `harness.executors.fresh`). The
    case goes in on stdin (pickled) and the result comes back through a temporary file (the
    method may print to stdout). The child holds stdin open and exits when it reaches EOF,
    so it dies with this process. It runs the case behind a guard (`_subprocess_main`) that
    kills every process the case left, even in a session of its own. Crash -> ``error`` row
    naming the signal; past ``timeout`` -> stopped (SIGTERM to the guard, SIGKILL 10 s later),
    ``timeout`` row; ``stop()`` true (polled twice a second) -> stopped. The timeout counts from
    the moment the child can fork its case (its interpreter started, the harness, the registry,
    the case's plugins and a bundled or procedural mesh loaded (`_warm`), the task's compiled
    measuring code loaded and the thread pools limited to the case's threads: what a forking
    worker's case inherits), which it writes on a pipe; its start-up may take `STARTUP_S` beyond ``timeout``.
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
            proc.stdin.write(pickle.dumps((case, want_meshes, want_view), protocol=pickle.HIGHEST_PROTOCOL))
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
    exit code, or killed by the same signal. Where a plugin started GNU OpenMP's pool at import,
    so that a fork would hang (`harness.executors.gomp`), the case runs in this process itself,
    and what it left is killed when it ends (and with the session, by the worker)."""
    case, want_meshes, *rest = pickle.load(sys.stdin.buffer)
    want_view = bool(rest and rest[0])
    from ..provenance import code_hash, package_versions
    from ..runner import run_case
    from .isolation import become_subreaper, reap_strays
    from .. import tasks
    _warm(case)                  # registry, plugins and bundled mesh, as a forking worker's case inherits them
    tasks.get(case.task)
    from ..runner import preload_tasks, scan_thread_pools
    preload_tasks([case])       # the measuring's compiled code, as a local case inherits it
    scan_thread_pools(case.threads)   # pools limited before the fork, as a local case's: none spin in its samples
    from .gomp import forked_openmp_hangs
    in_place = forked_openmp_hangs()  # a plugin started GNU OpenMP's pool at import: a fork would hang
    become_subreaper()
    if ready_fd is not None:                          # the case's timeout starts here
        os.write(ready_fd, repr(time.monotonic()).encode())
        os.close(ready_fd)
    pid = 0 if in_place else os.fork()
    if pid == 0:
        try:
            null = os.open(os.devnull, os.O_RDONLY)   # the case reads no input, as a local case's (its
            os.dup2(null, 0)                           # stdin is the pipe its case came on, open till it ends)
            os.close(null)
            result = run_case(case, want_meshes=want_meshes, want_view=want_view)
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
            if in_place:
                reap_strays()
            os._exit(1)
        if in_place:                  # what the case left dies here (the worker kills the session too)
            reap_strays()
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
