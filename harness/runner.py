"""One case -> one row. `run_case` runs in a worker (any process, any machine); it knows nothing
of sessions, executors or run folders.

A row is a flat dict of the common columns (`harness.schema`) plus the task's columns.

Timing protocol (the method call alone; metrics are not timed):

1. the thread pools (OpenBLAS, OpenMP, MKL through threadpoolctl) are limited to
   ``case.threads`` (the session sets ``cores // workers``) so concurrent cases do not
   oversubscribe the cores: by the local executor's driver before it forks the case processes,
   which inherit the limit (setting it in the case would start fresh OpenBLAS workers that spin
   for a while and compete with the first samples); elsewhere (serial, Dask) by the case, which
   undoes it at the end; in the case for libraries loaded since, also after the cold call if it
   loaded shared objects (a library the method imports on its first call; always where the
   loaded objects cannot be counted); pools a method starts later are not seen;
2. cold call: the method runs once on the case's own input, untimed as a sample; its wall time
   is ``time_cold_s`` (imports, JIT compilation or cache loads, library start-up: a cost of its
   own, never mixed into the samples);
3. samples: at least ``repeats`` calls, and more while the summed sample time is below
   ``time_budget_s`` (at most ``MAX_SAMPLES``), like ``timeit``'s autorange; every sample is kept
   (``times``, a JSON list, seconds) and summarised as median ``time_s``, quartiles
   ``time_q1_s``/``time_q3_s``, ``time_min_s``/``time_max_s``; ``repeats`` is the number taken;
   before each sample, the harness's own caches of earlier inputs are dropped (`forget_inputs`),
   the previous sample's result is freed, and freed heap memory is returned to the OS (glibc's
   ``malloc_trim``; other allocators' pools, e.g. MKL's, keep theirs), so every sample pays
   for the heap memory it touches (otherwise only the first sample, trimmed for the memory
   measurement, would, and run slower than the rest);
   each sample's process CPU time (all threads of the process) is kept too (``cpu_times``,
   median ``time_cpu_s``), ``others_cpu`` is the number of cores other processes kept busy
   on average over the sampled calls (the cold call left out; ``/proc/stat``, steal included,
   minus this process; blank off Linux and for windows under 0.2 s), and ``threads_busy`` the number of
   this process's threads that ran for 5% of that window and 2 clock ticks or more (blank
   under 0.05 s; `threads_busy`; a BLAS pool spinning while it waits counts): ``shootout compare`` does not call a wall-time change a
   regression when the load explains it (`harness.compare`);
4. memory: ``method_mem_mb`` is the peak resident memory of the first sampled call minus the
   resident memory just before it, in MiB (Linux: freed heap returned to the OS with glibc's
   ``malloc_trim``, then the kernel's high-water mark reset through ``/proc/self/clear_refs``;
   blank elsewhere). It counts pages the call touched beyond what was resident, so memory the
   allocator kept mapped from the cold call and reused is not counted again (a lower bound of
   the call's allocations). ``peak_rss_mb`` is the process's own peak (interpreter, inputs
   and metrics included).
"""
from __future__ import annotations

import contextlib
import json
import math
import os
import socket
import statistics
import threading
import time
import traceback
import warnings
from pathlib import Path

import numpy as np

from . import input_store, tasks
from .case_inputs import QUALITY, input_mesh_name, prepare_input, saved_meshes
from .config import Case
from .errors import ShootoutError
from .probes import _machine_busy_s, _reset_peak, _status_kib, _thread_ticks, _trim_heap, peak_rss_mb, threads_busy

__all__ = ["MAX_SAMPLES", "QUALITY", "SAMPLE_WALL", "THREAD_ENV", "_thread_ticks", "_trim_heap", "base_row",
           "forget_inputs", "input_mesh_name", "limit_threads", "peak_rss_mb", "prepare_input", "release_thread_pools",
           "run_case", "saved_meshes", "scan_thread_pools", "thread_env", "threads_busy", "timing_columns"]


MAX_SAMPLES = 1000
SAMPLE_WALL = 10.0   # beyond `repeats`, samples stop once their loop has taken this times the time budget


_POOLS: tuple | None = None   # (threadpoolctl controller, loaded objects at its scan), see scan_thread_pools


def _loaded_objects() -> int | None:
    """Number of shared objects loaded in this process (``dl_iterate_phdr``), None if unknown."""
    try:
        import ctypes
        count = [0]

        def seen(_info, _size, _data):
            count[0] += 1
            return 0

        proto = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p)
        ctypes.CDLL(None).dl_iterate_phdr(proto(seen), None)
        return count[0]
    except (OSError, AttributeError, ImportError):
        return None


_PARENT_LIMIT: tuple | None = None   # (n, limiter, thread id) set before forking, see scan_thread_pools


def scan_thread_pools(threads: int | None = None) -> None:
    """Find this process's BLAS/OpenMP thread pools once (threadpoolctl), in the driver before
    forking: case processes inherit the scan and `limit_threads` reuses it unless a shared
    object was loaded since. With ``threads``, the pools are also limited to it
    here: the limit is library state a forked case process inherits, so the case need not set
    it again, and setting it again would start fresh OpenBLAS workers that spin for a while and
    compete with the first timed samples."""
    global _POOLS, _PARENT_LIMIT
    try:
        from threadpoolctl import ThreadpoolController
    except ImportError:
        return
    release_thread_pools()                 # a limit set earlier is undone first, never stacked
    ctl = ThreadpoolController()
    if threads:                            # OpenMP's limit holds for the calling thread: it must fork
        _PARENT_LIMIT = (int(threads), ctl.limit(limits=int(threads)), threading.get_ident())
    _POOLS = (ctl, _loaded_objects())


def release_thread_pools() -> None:
    """Undo `scan_thread_pools`'s limit in this process (the local executor, when its run ends)."""
    global _PARENT_LIMIT
    if _PARENT_LIMIT is not None:
        try:
            _PARENT_LIMIT[1].restore_original_limits()
        finally:
            _PARENT_LIMIT = None


def preload_tasks(cases) -> None:
    """Run each task's ``preload`` (compiled measuring code) once in the driver, so forked case
    processes inherit it instead of loading it again (best effort: harness code, never a method's).
    An interrupt meanwhile is deferred to the end (`harness.errors.interrupts_deferred`; a second
    one ends the process at once)."""
    from .core import geometry
    from .errors import interrupts_deferred
    with interrupts_deferred():          # a KeyboardInterrupt inside llvmlite crashed the driver
        try:
            geometry.warm()
        except Exception:  # noqa: BLE001 - the numpy path below the threshold still works
            pass
        for name in sorted({c.task for c in cases}):
            try:
                fn = tasks.get(name).preload
                if fn is not None:
                    fn()
            except Exception:  # noqa: BLE001 - a failure here shows again, as the cases' rows
                pass


# Read once, when the library loads or first goes parallel: libigl's own std::threads (which
# threadpoolctl does not see), and MKL, OpenMP and OpenBLAS loaded by a method after the case's
# pools were limited (pypardiso's MKL is loaded at its first solve, inside the cold call).
THREAD_ENV = ("IGL_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS")


@contextlib.contextmanager
def thread_env(n: int | None, keys=THREAD_ENV):
    """``keys`` (of `THREAD_ENV`) set to ``n`` inside (None or 0: left alone), the caller's values
    restored after. Only a library that loads (or first goes parallel) inside keeps the count."""
    if not n:
        yield
        return
    before = {k: os.environ.get(k) for k in keys}
    os.environ.update({k: str(n) for k in keys})
    try:
        yield
    finally:
        for k, v in before.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def limit_threads(n: int | None):
    """Limit BLAS/OpenMP thread pools of this process to ``n`` (None or 0: leave them); returns the
    threadpoolctl limiter, whose ``restore_original_limits()`` undoes it (None: nothing was set).
    Pools the parent process limited to ``n`` before forking this one from the same thread
    (`scan_thread_pools`) are left alone; only libraries loaded since are limited."""
    if not n:
        return None
    n = int(n)
    scanned = _POOLS is not None and _POOLS[1] is not None
    inherited = (scanned and _PARENT_LIMIT is not None and _PARENT_LIMIT[0] == n
                 and _PARENT_LIMIT[2] == threading.get_ident())
    if scanned and _POOLS[1] == _loaded_objects():
        return None if inherited else _POOLS[0].limit(limits=n)
    try:
        from threadpoolctl import ThreadpoolController
    except ImportError:
        return None
    ctl = ThreadpoolController()
    if inherited:
        known = {lib.filepath for lib in _POOLS[0].lib_controllers}
        new = [lib.filepath for lib in ctl.lib_controllers if lib.filepath not in known]
        return ctl.select(filepath=new).limit(limits=n) if new else None
    return ctl.limit(limits=n)


def _library(name: str):
    from .plugins import import_methods
    methods = import_methods()
    try:
        return methods.get(name).library
    except KeyError:
        return None


def forget_inputs() -> None:
    """Drop what is kept between calls about the inputs seen (`harness.core.solvers.forget_inputs`:
    the solvers' analyses and the sparse libraries' own cached factorizations), so that every
    timed call pays for its input like a first call; within one call, repeated factorizations
    still share them. Compiled code stays loaded: that is warming the code path, not the data. A
    method's own caches across calls are its author's to avoid."""
    from .core import solvers
    solvers.forget_inputs()


def base_row(case: Case) -> dict:
    """The common columns known before running (status error until proven otherwise)."""
    return {"case_id": case.case_id, "task": case.task, "mesh": case.mesh_key, "n_vertices": None,
            "n_faces": None, "noise_model": case.noise_name,
            "noise_level": None if math.isnan(case.noise_level) else case.noise_level,
            "seed": case.seed, "method": case.method, "library": _library(case.method),
            "params": json.dumps(case.params, sort_keys=True), "status": "error", "error": "",
            "time_s": None, "time_min_s": None, "time_max_s": None, "repeats": case.repeats,
            "peak_rss_mb": None}


def timing_columns(times: list[float], cold: float | None, cpu: list[float] | None = None) -> dict:
    """The time columns of a row from its samples (wall and, optionally, process CPU seconds,
    kept to 9 significant digits)."""
    times = [float(f"{t:.9g}") for t in times]
    q1, q3 = (float(x) for x in np.percentile(times, [25, 75]))
    out = {"time_s": statistics.median(times), "time_min_s": min(times), "time_max_s": max(times),
           "time_q1_s": q1, "time_q3_s": q3, "time_cold_s": cold, "repeats": len(times),
           "times": json.dumps(times)}
    if cpu:
        cpu = [float(f"{t:.9g}") for t in cpu]
        out.update(time_cpu_s=statistics.median(cpu), cpu_times=json.dumps(cpu))
    return out


def _has_value(v) -> bool:
    """Whether a measured value is there: not None and not NaN."""
    return v is not None and not (isinstance(v, float) and v != v)


def run_case(case: Case, want_meshes: bool = False, want_view: bool = False) -> tuple[dict, dict]:
    """Run one case and measure it; never raises (failures become an error row).

    Returns ``(row, extras)``. ``extras["meshes"]`` maps file names to ``(V, F, quality, comment)``
    for the driver to write (`saved_meshes`, when ``want_meshes`` and the task has an output mesh);
    ``extras["view"]`` holds the task's view meshes (``want_view``); ``extras["case_wall_s"]`` the
    wall time of this call (loading, noise, cold call, samples, measuring) and, for an ok case,
    ``extras["measure_s"]`` that of the task's measuring of the result and ``extras["solver"]``
    the backends the method's calls factored with through `harness.core.solvers` (``{backend:
    largest system}``, empty for a method that did not use it).
    """
    row = base_row(case)
    extras: dict = {}
    limiters: list = []
    env = contextlib.ExitStack()          # the thread variables, restored for an in-process (serial) caller
    t_case = time.perf_counter()
    try:
        from .plugins import import_methods
        from .trial import ENDED
        methods = import_methods()
        for mod in case.plugins:           # the config checked them in the driver; a worker may lack them
            if mod in ENDED:               # its import ended the trial process of this one's parent (a Dask worker)
                raise ShootoutError(f"plugin {mod!r} cannot be imported in the case's process on "
                                    f"{socket.gethostname()} ({ENDED[mod]})")
            try:
                methods.load_plugins([mod])
            except ModuleNotFoundError as exc:
                raise ShootoutError(f"plugin {mod!r} cannot be imported in the case's process on "
                                    f"{socket.gethostname()} ({exc}): on a Dask worker, its module must be "
                                    "on the worker's PYTHONPATH too") from None
        methods.load_plugins([])
        method = methods.get(case.method)
        task = tasks.get(case.task)
        row["library"] = method.library
        full = method.resolve_params(case.params)
        row["params"] = json.dumps(full, sort_keys=True, default=str)
        inp, pair_level = prepare_input(case)
        inp.cache.update(input_store.load(case, task.input_facts))
        if pair_level is not None:
            row["noise_level"] = pair_level
        row["n_vertices"], row["n_faces"] = inp.clean.n_vertices, inp.clean.n_faces
        why = method.unavailable_reason()
        if why:
            row.update(status="unavailable", error=why)
            return row, extras
        limiters.append(limit_threads(case.threads))
        env.enter_context(thread_env(case.threads))    # libraries that load or start their threads from here on
        loaded = _loaded_objects()
        from .core import solvers
        solvers.forget_used()
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            run, finish = method.bind(inp.V.copy(), inp.F.copy(), **case.params)   # checks: untimed
            forget_inputs()
            t0 = time.perf_counter()
            cold_result = run()                                     # cold call: same code path, own input
            cold = time.perf_counter() - t0
            finish(cold_result)
            del cold_result
        if case.threads and (loaded is None or _loaded_objects() != loaded):
            limiters.append(limit_threads(case.threads))    # pools the cold call loaded
        times, cpu, result, spent = [], [], None, 0.0
        # others_cpu's and threads_busy's window: the samples alone (a long cold call, e.g. a numba
        # compile, would dilute the load during them and lend them its own)
        busy0, own0, wall0 = _machine_busy_s(), time.process_time(), time.perf_counter()
        ticks0 = _thread_ticks()
        while len(times) < case.repeats or (spent < case.time_budget and len(times) < MAX_SAMPLES
                                            and time.perf_counter() - wall0 < SAMPLE_WALL * case.time_budget):
            result = None                               # the previous result is freed here, untimed
            run, finish = method.bind(inp.V.copy(), inp.F.copy(), **case.params)  # a method that writes
            forget_inputs()                                                       # into its input spoils nothing
            _trim_heap()                                # every sample starts from the same heap state
            first = not times
            if first:
                rss0, reset = _status_kib("VmRSS"), _reset_peak()
            c0, t0 = time.process_time(), time.perf_counter()
            result = run()
            times.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
            spent += times[-1]
            if first:
                hwm = _status_kib("VmHWM")
                if reset and rss0 is not None and hwm is not None:
                    row["method_mem_mb"] = round(max(hwm - rss0, 0) / 1024.0, 2)
            result = finish(result)                     # validated, untimed
        busy1, own1, wall1 = _machine_busy_s(), time.process_time(), time.perf_counter()
        row.update(timing_columns(times, cold, cpu))
        if busy0 is not None and busy1 is not None and wall1 - wall0 >= 0.2:   # /proc/stat counts 10 ms ticks
            others = max(0.0, (busy1 - busy0) - (own1 - own0)) / (wall1 - wall0)
            row["others_cpu"] = round(min(others, float(os.cpu_count() or 1)), 3)
        row["threads_busy"] = threads_busy(ticks0, _thread_ticks(), wall1 - wall0)
        extras["solver"] = solvers.used()               # the method's own calls (measuring may factor too)
        t_measure = time.perf_counter()
        row.update(task.measured(inp, result, full))
        extras["measure_s"] = time.perf_counter() - t_measure
        input_store.save(case, inp.cache, task.input_facts)
        if want_meshes and task.output_mesh is not None:
            extras["meshes"] = saved_meshes(case, task, inp, result)
        if want_view and task.view is not None:
            extras["view"] = task.view(inp, result)
        row["status"] = "ok"
        notes = ["input repaired: " + "; ".join(inp.clean.repairs)] if inp.clean.repairs else []
        notes += ["input: " + n for n in inp.clean.input_notes]
        scored = [m.name for m in task.metrics if m.better not in ("info", "input")]
        if scored and not any(_has_value(row.get(c)) for c in scored):
            notes.append(f"no scored metric of the {task.name} task applies to this input: every column that "
                         "ranks methods is blank (e.g. no analytic truth for a file mesh)")
        heard = list(dict.fromkeys(f"{w.category.__name__}: {w.message}" for w in said
                                   if issubclass(w.category, (RuntimeWarning, UserWarning))))
        notes += [f"the method warned: {m}" for m in heard[:3]]
        row["error"] = "; ".join(notes)[:2000]
    except ShootoutError as exc:
        row.update(status="error", error=f"{type(exc).__name__}: {exc}")
    except (Exception, SystemExit) as exc:  # a method's own failure is data: one error row
        tb = traceback.extract_tb(exc.__traceback__)
        where = f" at {Path(tb[-1].filename).name}:{tb[-1].lineno}" if tb else ""
        row.update(status="error", error=f"{type(exc).__name__}: {exc}{where}"[:2000])
    finally:
        row["peak_rss_mb"] = round(peak_rss_mb(), 1)
        extras["case_wall_s"] = time.perf_counter() - t_case
        env.close()
        for lim in reversed(limiters):      # in-process (serial) runs leave the caller's pools as they were
            if lim is not None:
                try:
                    lim.restore_original_limits()
                except Exception:  # noqa: BLE001 - best effort, after the row is complete
                    pass
    return row, extras
