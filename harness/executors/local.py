"""Local executors: ``local`` runs ``workers`` cases at a time, each in its own child process
(isolation and timeout, see `harness.executors.isolation`); ``serial`` runs in-process without
isolation (debugging only).

The local executor is a single-threaded scheduler waiting on the children's pipes: no threads in
the forking process, and no re-import of the user's ``__main__`` (scripts need no
``if __name__ == "__main__"`` guard). A driver that has started GNU OpenMP's threads, which a
fork does not survive, runs the cases in fresh interpreters instead (`harness.executors.fresh`).
"""
from __future__ import annotations

import os
import time
from multiprocessing.connection import wait as mp_wait

from .. import input_store
from ..errors import check_interrupt
from ..runner import preload_tasks, release_thread_pools, run_case
from .gomp import forked_openmp_hangs
from .isolation import _children, _Job, reap_strays, signals_blocked

REAP = False      # the driver is a child subreaper (the ``shootout`` command): kill orphans cases leave


POLL_S = 0.5


class SerialExecutor:
    """In-process, one case at a time, no isolation or timeout (for debugging): a crash ends the
    run; the working directory and numpy's error state are restored after each case."""

    name = "serial"

    def __init__(self, **_):
        pass

    def run(self, cases, want_meshes=False):
        import numpy as np
        with input_store.session():
            for c in cases:
                cwd, err = os.getcwd(), np.geterr()
                try:
                    row, extras = run_case(c, want_meshes=want_meshes)
                finally:                 # what one case changes in the shared process, the next does not see
                    os.chdir(cwd)
                    np.seterr(**err)
                yield c, row, extras

    def close(self):
        pass

    def describe(self) -> dict:
        return {"executor": self.name, "workers": getattr(self, "workers", 1)}


class LocalExecutor:
    """``workers`` cases at a time, each in its own child process (isolation + timeout)."""

    name = "local"

    def __init__(self, workers: int = 1, timeout: float | None = None, **_):
        self.workers = max(1, int(workers))
        self.timeout = timeout

    def run(self, cases, want_meshes=False):
        import warnings
        todo = list(cases)
        gomp = bool(todo) and forked_openmp_hangs()
        if gomp:
            from .fresh import fresh_resolvable, run_fresh
            if fresh_resolvable(todo):
                warnings.warn(GOMP_FRESH, RuntimeWarning, stacklevel=2)
                yield from run_fresh(todo, self.workers, self.timeout, want_meshes)
                return
            warnings.warn(GOMP_SAID, RuntimeWarning, stacklevel=2)
        preload_tasks(todo)                    # compiled code first: the mesh loaders inherit it
        _warm_mesh_cache(todo, self.timeout)
        from ..runner import scan_thread_pools
        scan_thread_pools(next((c.threads for c in todo), None))    # last: after every library loaded
        todo.reverse()
        running: list[_Job] = []
        before = set(_children(os.getpid())) if REAP else set()     # the driver's own children stay

        def reap():                        # after a case ended: the orphans it left, if it crashed first
            if REAP:
                reap_strays(before | {j.proc.pid for j in running})
        store = input_store.session()
        store.__enter__()
        try:
            while todo or running:
                while todo and len(running) < self.workers:
                    with signals_blocked():      # an interrupt is delivered after the job is registered
                        running.append(_Job(todo[-1], want_meshes))
                        todo.pop()
                # a process the method forked may hold the pipe and the sentinel open after the case
                # process died: poll the exit status too, at least every POLL_S
                wait_s = POLL_S
                if self.timeout is not None:
                    now = time.perf_counter()
                    wait_s = min(wait_s, max(0.0, min(j.t0 + self.timeout - now for j in running)))
                ready = set(mp_wait([j.conn for j in running] + [j.sentinel for j in running], timeout=wait_s))
                check_interrupt()
                for job in running:
                    job.keep_tail()
                for job in [j for j in running if j.conn in ready or j.sentinel in ready or j.ended()]:
                    running.remove(job)
                    row, extras = job.collect()
                    reap()
                    yield job.case, row, extras
                if self.timeout is not None:
                    now = time.perf_counter()
                    for job in [j for j in running if now - j.t0 >= self.timeout]:
                        running.remove(job)
                        row, extras = job.kill_timeout(self.timeout)
                        if gomp:
                            row["error"] += "; " + GOMP_SAID
                        reap()
                        yield job.case, row, extras
        finally:
            for job in running:                # interrupted: leave no orphan behind
                job.abort()
            if REAP:
                reap_strays(before)
            store.__exit__(None, None, None)
            release_thread_pools()

    def close(self):
        pass

    def describe(self) -> dict:
        return {"executor": self.name, "workers": getattr(self, "workers", 1)}


GOMP_FRESH = ("a process forked from this one hangs in GNU OpenMP (libgomp), which is not fork-safe: this "
              "process has started its thread pool (PyMeshLab, or PARDISO through MKL, called before the run); "
              "each case runs in a fresh Python process instead (an interpreter's start-up more per case; the "
              "same metrics)")

GOMP_SAID = ("a process forked from this one hangs in GNU OpenMP (libgomp), which is not fork-safe: this "
             "process has started its thread pool (PyMeshLab, or PARDISO through MKL, called before the run); "
             "a method or task defined outside the built-ins, the config's plugins and the entry points (in "
             "__main__, say) exists in no fresh process, so the cases are forked anyway, and one that enters "
             "an OpenMP parallel region hangs until its timeout: run the config from a fresh process (shootout "
             "run, or harness.run before such calls)")


def _load_in_child(spec: dict, frame: bool, timeout: float | None):
    """The `harness.datasets.Source` of a ``{file: ...}`` mesh (with its input notes, and its
    noise frame if ``frame``) read in a child process, or None when that fails or takes longer
    than ``timeout``: a file that is slow, huge or hostile to read costs that child, not the
    driver, and its cases read it again under their own timeout."""
    from multiprocessing.connection import wait as mp_wait
    from .isolation import _context
    ctx = _context()
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_loader, args=(send, spec, frame, os.getpid()), daemon=True)
    with signals_blocked():
        proc.start()
    send.close()
    try:
        if mp_wait([recv, proc.sentinel], timeout) and recv.poll(0):
            return recv.recv()
        return None
    except (EOFError, OSError):
        return None
    finally:
        recv.close()
        if proc.is_alive():
            proc.kill()
        proc.join()


def _loader(conn, spec: dict, frame: bool, driver: int) -> None:
    import signal

    from .. import datasets
    from ..results import close_inherited_locks
    from .isolation import _SIGNALS
    from .procs import die_with_parent
    close_inherited_locks()                       # the run folder's lock stays the driver's alone
    input_store.drop_lock()
    if not die_with_parent(driver):               # with the driver (SIGKILL to it too); it died before that
        os._exit(0)
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, _SIGNALS)
    try:
        src = datasets.cached(spec)
        _compute_facts(src, frame)
        conn.send(src)
    except BaseException:  # noqa: BLE001 - the cases read it again and say why
        pass
    os._exit(0)                                   # none of the driver's exit handlers


def _compute_facts(src, frame: bool) -> None:
    """The facts of an input every case of it reads (its notes; its noise frame when ``frame``
    and the noise is not given), computed once where the driver keeps them."""
    src.clean.input_notes
    if frame and src.noisy_V is None:
        src.clean.noise_frame


def _warm_mesh_cache(cases, timeout: float | None = None) -> None:
    """Load each distinct mesh (and its noise frame) once in the driver so forked children
    inherit it instead of reading, repairing and measuring it in every case (best effort:
    failures fail again in the case, as its error row). Mesh files are read in a child process
    (`_load_in_child`, bounded by the run's ``timeout``), the driver keeps what it returns."""
    from .. import datasets

    def key(c):
        return repr(sorted(c.mesh.items()))
    noisy = {key(c) for c in cases if c.adds_noise}
    seen = set()
    for c in cases:
        k = key(c)
        if k in seen or len(seen) >= 8:
            continue
        seen.add(k)
        if "file" in c.mesh:
            src = _load_in_child(c.mesh, k in noisy, timeout)
            if src is not None:
                datasets.prime(c.mesh, src)
            continue
        try:
            _compute_facts(datasets.cached(c.mesh), k in noisy)
        except Exception:  # noqa: BLE001 - the case's own child reports it as an error row
            pass
