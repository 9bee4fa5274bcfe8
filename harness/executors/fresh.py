"""Cases in fresh interpreters, for a driver that may not fork: one whose process has started
GNU OpenMP's thread pool (a MeshLab filter, or PARDISO through MKL on libgomp, called before
the run). libgomp is not fork-safe: a process forked from such a driver waits forever at its
first OpenMP parallel region. Each case then runs as a Dask worker's does when it may not fork
(`harness.executors.dask_subprocess.run_in_subprocess`): a new ``python`` process that imports
the harness, the registry and the case's plugins, and forks the case behind a guard of its own,
with the run's timeout from the moment it could fork. A case costs an interpreter's start-up
more (not counted in its times or fixed cost) and reads its input's facts again (the session's
input store is the forking driver's alone); its rows are the same. A case whose interpreter
read other sources than the driver loaded (files edited during the run) is an error row.

Only for cases whose method and task a fresh interpreter finds by name: built-in, an entry
point, or in the case's ``plugins``; a method registered in the driver's ``__main__`` (a
notebook) exists nowhere else, and its run forks as before (`fresh_resolvable`).
"""
from __future__ import annotations

import threading
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

from ..errors import check_interrupt

POLL_S = 0.5


def fresh_resolvable(cases) -> bool:
    """Whether a fresh interpreter finds every case's method and task by name (see the module)."""
    from importlib.metadata import entry_points

    from methods import registry

    from .. import tasks
    eps = {ep.module for ep in entry_points(group=registry.ENTRY_POINT_GROUP)}
    for c in cases:
        try:
            mods = (registry.get(c.method).func.__module__, type(tasks.get(c.task)).__module__)
        except Exception:  # noqa: BLE001 - an unknown name is the case's error row either way
            continue
        for mod in mods:
            if not (mod.startswith(("methods.", "harness.tasks.")) or mod in c.plugins or mod in eps):
                return False
    return True


def run_fresh(cases, workers: int, timeout: float | None, want_meshes: bool):
    """Yield ``(case, row, extras)`` for ``cases``, ``workers`` at a time, each in a fresh
    interpreter (the module's). An interrupt (or closing the generator) stops the running ones:
    their processes and what they left are killed, and they yield nothing."""
    from ..runner import base_row
    from .dask_code import CODE_KEY, _code_of
    from .dask_subprocess import run_in_subprocess
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
                row, extras = fut.result()
                theirs = row.pop(CODE_KEY, None)
                if isinstance(theirs, (tuple, list)) and theirs and theirs[0] != _code_of(case.plugins):
                    why = (f"its fresh interpreter read other sources (code_sha256 {theirs[0]}) than this run "
                           f"loaded ({_code_of(case.plugins)}): the harness, methods or plugins changed on disk "
                           "during the run; its row is not kept")
                    row, extras = base_row(case), {}
                    row["error"] = why
                yield case, row, extras
    finally:
        stop.set()                       # the running cases' processes are killed within POLL_S
        pool.shutdown(wait=True, cancel_futures=True)
