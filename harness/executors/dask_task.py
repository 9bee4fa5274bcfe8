"""The Dask task of one case (`run_task`) and what it tells the scheduler and reads from its
worker: it logs its start and its end (`STARTED`, `ENDED`) under a topic of its own
(`_topic`), so that the driver can tell a case that ran when its worker died from one that
waited; it checks whether the client gave up on it (`_cancelled`); it names its worker in
its row.
"""
from __future__ import annotations

from ..config import Case
from ..errors import InvalidMeshError
from ..runner import base_row
from .dask_code import CODE_KEY, _code_of, _versions
from .dask_files import materialize
from .dask_subprocess import _warm, run_in_subprocess

STARTED, ENDED = "started", "ended"   # the events of a task's topic (`_topic`): it began its case, it ended it


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
