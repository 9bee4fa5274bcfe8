"""Cases in fresh interpreters, for a driver that may not fork: one whose process has started
GNU OpenMP's thread pool (a MeshLab filter, or PARDISO through MKL on libgomp, called before
the run). libgomp is not fork-safe: a process forked from such a driver waits forever at its
first OpenMP parallel region. Each case then runs as a Dask worker's does when it may not fork
(`harness.executors.dask_subprocess.run_in_subprocess`): a new ``python`` process that imports
the harness, the registry and the case's plugins, and forks the case behind a guard of its own,
with the run's timeout from the moment it could fork. A case costs an interpreter's start-up
more (not counted in its times or fixed cost) and reads its input's facts again (the session's
input store is the forking driver's alone); its metrics are the same. A case whose interpreter
read other sources than there were when the run started (files edited during the run) is an
error row; so is a case whose interpreter could not be started. A plugin that starts GNU
OpenMP's pool at import would hang a case forked in that interpreter too: there the case runs
in the interpreter itself (`harness.executors.dask_subprocess._subprocess_main`).

Only for cases whose method and task a fresh interpreter finds by name: built-in, or defined
in (a submodule of) a module under the case's ``plugins`` or an entry point. A method defined
elsewhere (the driver's ``__main__``, a notebook, a module imported outside ``plugins:``)
exists in no fresh interpreter, and its run forks as before (`fresh_resolvable`).
"""
from __future__ import annotations

import threading
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

from ..errors import check_interrupt

POLL_S = 0.5


def _found_by_name(mod: str, case, eps: set) -> bool:
    """Whether a fresh interpreter imports module ``mod``: built-in, or (in) a module named under
    the case's ``plugins`` or an entry point."""
    roots = ("methods", "harness", *case.plugins, *eps)
    return any(mod == r or mod.startswith(r + ".") for r in roots)


def fresh_resolvable(cases) -> bool:
    """Whether a fresh interpreter finds every case's method and task by name (see the module):
    the modules defining the method's function and the task's ``measure``."""
    from importlib.metadata import entry_points

    from methods import registry

    from .. import tasks
    eps = {ep.module for ep in entry_points(group=registry.ENTRY_POINT_GROUP)}
    for c in cases:
        try:
            mods = (registry.get(c.method).func.__module__, tasks.get(c.task).measure.__module__)
        except Exception:  # noqa: BLE001 - an unknown name is the case's error row either way
            continue
        if not all(_found_by_name(str(m), c, eps) for m in mods):
            return False
    return True


def run_fresh(cases, workers: int, timeout: float | None, want_meshes: bool):
    """Yield ``(case, row, extras)`` for ``cases``, ``workers`` at a time, each in a fresh
    interpreter (the module's). An interrupt (or closing the generator) stops the running ones:
    their processes and what they left are killed, and they yield nothing."""
    from ..provenance import code_hash
    from ..runner import base_row
    from .dask_code import CODE_KEY
    from .dask_subprocess import run_in_subprocess
    ours = {p: code_hash(p) for p in {tuple(c.plugins) for c in cases}}    # the sources as the run starts
    stop = threading.Event()
    todo = list(cases)
    todo.reverse()
    pool = ThreadPoolExecutor(max(1, int(workers)), thread_name_prefix="shootout-fresh")
    running: dict = {}
    try:
        while todo or running:
            while todo and len(running) < workers:
                case = todo.pop()
                running[pool.submit(run_in_subprocess, case, timeout, want_meshes, stop.is_set)] = case
            done, _ = wait(list(running), timeout=POLL_S, return_when=FIRST_COMPLETED)
            check_interrupt()
            for fut in done:
                case = running.pop(fut)
                try:
                    row, extras = fut.result()
                except Exception as exc:  # noqa: BLE001 - no process, or no result read: this case's row
                    row, extras = base_row(case), {}
                    row["error"] = f"could not run the case in a fresh interpreter: {type(exc).__name__}: {exc}"[:2000]
                theirs = row.pop(CODE_KEY, None)
                mine = ours[tuple(case.plugins)]
                if isinstance(theirs, (tuple, list)) and theirs and theirs[0] != mine:
                    row, extras = base_row(case), {}
                    row["error"] = (f"its fresh interpreter read other sources (code_sha256 {theirs[0]}) than there "
                                    f"were when the run started ({mine}): the harness, methods or plugins changed "
                                    "on disk during the run; its row is not kept")
                yield case, row, extras
    finally:
        stop.set()                       # the running cases' processes are killed within POLL_S
        pool.shutdown(wait=True, cancel_futures=True)


def isolated_runner():
    """``run(case, timeout, want_view=False) -> (row, extras)`` for cases run one at a time after
    the run (the 3D views): `harness.executors.isolation.run_isolated` (a fork), or
    `run_in_subprocess` when a fork would hang in GNU OpenMP and the case can run fresh (its row
    is not checked against the run's sources: a view compares its metric with the row instead;
    the fresh interpreter's start-up may take `STARTUP_S` beyond ``timeout``)."""
    def run(case, timeout, want_view=False):
        from .gomp import forked_openmp_hangs
        if forked_openmp_hangs() and fresh_resolvable([case]):
            from .dask_code import CODE_KEY
            from .dask_subprocess import run_in_subprocess
            row, extras = run_in_subprocess(case, timeout, want_view=want_view)
            row.pop(CODE_KEY, None)
            return row, extras
        from .isolation import run_isolated
        return run_isolated(case, timeout=timeout, want_view=want_view)
    return run
