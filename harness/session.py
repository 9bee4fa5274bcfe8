"""One run of a config: prepare the folder, run the cases through an executor, write the rows,
run.json, the 3D views and the report. ``harness.run`` and ``shootout run`` call `run`."""
from __future__ import annotations

import dataclasses
import errno
import hashlib
import json
import os
import re
import secrets
import statistics
import sys
import time
from pathlib import Path

from . import tasks
from .config import Config, load_config
from .errors import ConfigError, RunInterrupted, ShootoutError, check_interrupt, problems_error
from .executors import EXECUTORS, make_executor
from .mesh import write_ply
from .provenance import code_hash, git_commit, git_dirty, machine_info, now_iso, package_versions, usable_cpus
from .results import PLAN_FILE, Frames, RunFolder, check_output_file, out_dir_problems, with_not_run


def config_hash(cfg: Config, with_tune: bool = True) -> str:
    """sha1 of what the rows depend on (case ids, repeats, Hausdorff samples and gap, the timing
    budget; with ``tune:``, its training cases and metric), so a resume with a changed config is detected. Settings at their defaults are left
    out of the key, so that folders of versions that did not count them still resume."""
    hs = cfg.cases[0].hausdorff_samples if cfg.cases else None
    eps = cfg.cases[0].hausdorff_eps if cfg.cases else 1e-3
    budget = cfg.cases[0].time_budget if cfg.cases else 0.25
    key = ([sorted(c.case_id for c in cfg.cases), cfg.repeats, hs] + ([eps] if eps != 1e-3 else [])
           + ([["time_budget", budget]] if budget != 0.25 else []))
    if cfg.tune is not None and with_tune:   # the training cases and the metric decide the tuned cases
        key.append(["tune", cfg.tune.metric, sorted(c.case_id for c in cfg.tune.cases)])
    blob = json.dumps(key).encode()
    return hashlib.sha1(blob).hexdigest()[:16]


def plan(cases) -> list[dict]:
    """The run folder's ``plan.csv``: the identifying columns (`results.PLAN_COLUMNS`) of every case
    the run means to run, as its rows would start (`runner.base_row`), so that a report of an
    interrupted run counts the cases it never ran (`results.with_not_run`)."""
    from .results import PLAN_COLUMNS
    from .runner import base_row
    return [{k: r[k] for k in PLAN_COLUMNS} for r in map(base_row, cases)]


def _solver_info() -> dict | None:
    try:
        from .core.solvers import solver_info
        return solver_info()
    except Exception as exc:  # provenance must never fail a run
        return {"error": f"{type(exc).__name__}: {exc}"}


class _Lines:
    """Progress for a non-terminal stderr (CI logs, ``| tee``): one line every ``every`` seconds."""

    def __init__(self, total: int, initial: int, every: float = 5.0):
        self.total, self.n, self.every, self.initial = total, initial, every, initial
        self.t0 = self.last = time.perf_counter()
        self.what = ""
        if initial:
            print(f"shootout: resuming, {initial} of {total} case(s) already done", file=sys.stderr, flush=True)

    def set_postfix_str(self, what, refresh=False):
        self.what = what

    def update(self, k=1):
        self.n += k
        now = time.perf_counter()
        if now - self.last >= self.every or self.n == self.total:
            self.last = now
            done, left = self.n - self.initial, self.total - self.n
            eta = (f", about {_duration((now - self.t0) / done * left)} left at this session's pace"
                   if done > 0 and left > 0 else "")
            print(f"shootout: {self.n}/{self.total} cases, {now - self.t0:.0f} s{eta}"
                  + (f" (last: {self.what})" if self.what else ""), file=sys.stderr, flush=True)

    def close(self):
        pass


def _duration(s: float) -> str:
    """Seconds as a rounded duration: ``45 s``, ``12 min``, ``3.4 h``."""
    return f"{s:.0f} s" if s < 90 else f"{s / 60:.0f} min" if s < 5400 else f"{s / 3600:.1f} h"


def _progress(total: int, initial: int):
    if sys.stderr.isatty():
        from tqdm import tqdm
        return tqdm(total=total, initial=initial, unit="case", dynamic_ncols=True)
    return _Lines(total, initial)


def _load() -> float | None:
    try:
        return round(os.getloadavg()[0], 2)
    except OSError:
        return None


def method_sources(cfg: Config) -> dict:
    """For every method of the run: the module that registered it and the installed distribution
    (name, version) that supplied that module, so a plugin's version is on record."""
    from importlib import metadata
    from .plugins import import_methods
    methods = import_methods()
    dists = None
    out = {}
    for name in sorted({c.method for c in cfg.cases}):
        try:
            mod = methods.get(name).func.__module__
        except KeyError:
            continue
        top = mod.split(".")[0]
        if top == "methods":
            dist = "mesh-shootout"
        else:
            if dists is None:               # every installed distribution's files: read once, when needed
                try:
                    dists = metadata.packages_distributions()
                except Exception:  # noqa: BLE001 - provenance must never fail a run
                    dists = {}
            dist = (dists.get(top) or [None])[0]
        try:
            ver = metadata.version(dist) if dist else None
        except metadata.PackageNotFoundError:
            ver = None
        out[name] = {"module": mod, "distribution": dist, "version": ver}
    return out


def task_specs(cfg: Config) -> dict:
    """The declarations of the tasks this run uses (the report and compare read them)."""
    from .plugins import import_methods
    methods = import_methods()
    used = sorted({c.task for c in cfg.cases})
    specs = {t: tasks.get(t).spec() for t in used}
    from .core.params import id_spec
    for t in used:                  # labels name a parameter only where it is not the default
        defaults, ids = {}, {}
        for name in sorted({c.method for c in cfg.cases if c.task == t}):
            try:
                m = methods.get(name)
            except KeyError:
                continue
            defaults[name] = json.loads(json.dumps(m.with_defaults({}), default=str))
            spec = id_spec(m.params)    # how case ids record renamed or added parameters (compare reads it)
            if spec:
                ids[name] = json.loads(json.dumps(spec, default=str))
        specs[t]["method_defaults"] = defaults
        specs[t]["param_ids"] = ids
    return specs


def run_args_problems(workers, timeout, executor, scheduler) -> list[str]:
    """What is wrong with the run's settings (the CLI's flags, `run`'s arguments), every one."""
    import numbers
    P = []
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, numbers.Integral) or workers < 1):
        P.append(f"--workers: expected an integer >= 1, got {workers!r}")
    if timeout is not None and (isinstance(timeout, bool) or not isinstance(timeout, numbers.Real)
                                or not 0 < timeout < float("inf")):
        P.append(f"--timeout: expected a finite number of seconds > 0, got {timeout!r}")
    if executor not in EXECUTORS:
        P.append(f"--executor: expected one of {', '.join(EXECUTORS)}, got {executor!r}")
    elif executor == "dask" and not scheduler:
        P.append("--executor dask needs --scheduler tcp://HOST:PORT")
    elif executor == "serial":
        if workers is not None and workers != 1:
            P.append(f"--workers {workers}: --executor serial runs one case at a time in this process")
        if timeout is not None:
            P.append("--timeout: --executor serial runs cases in this process, where no time limit can stop one "
                     "(use the local executor)")
    if scheduler and executor != "dask":
        P.append(f"--scheduler: only the dask executor uses a scheduler (this run's executor is {executor})")
    return P


def run(config_or_path, out=None, workers=None, executor="local", scheduler=None, resume=False,
        timeout=None, quiet=True, export_benchmark_json=None):
    """Run a config (a `Config`, a path, YAML text or a dict) end to end; returns
    ``{task: DataFrame}`` of the rows in the run folder (a `Frames`: its ``not_written`` lists
    what the end of the run could not write, e.g. the report). ``out``: a non-empty folder path,
    or None for ``results/<name>``. A ``results:`` config (scoring files made elsewhere) runs no
    case: it takes ``out`` and ``quiet`` only, as ``shootout run`` takes no other flag for it. Bad
    arguments are one `ShootoutError` listing each, before anything is written."""
    P = [re.sub(r"--(workers|timeout|executor|scheduler)\b", r"\1", p)      # arguments here, not flags
         for p in run_args_problems(workers, timeout, executor, scheduler)]
    if out is not None and not isinstance(out, (str, os.PathLike)):
        P.append(f"out: expected a folder path, got {type(out).__name__} {out!r}")
    elif isinstance(out, str) and not out.strip():       # Path("") would be the current folder
        P.append("out: an empty path; give the run folder, or out=None for results/<name>")
    why = _config_problem(config_or_path)
    if why:
        P.append(why)
    if out is not None and isinstance(out, (str, os.PathLike)) and str(out).strip():
        P += out_dir_problems(Path(out), resume)      # before a results: config's problems, which join them
    raw = None if why else _results_config(config_or_path)
    if raw is not None:
        given = [k for k, on in (("resume", resume), ("timeout", timeout is not None), ("executor", executor != "local"),
                                 ("scheduler", bool(scheduler)), ("workers", workers is not None),
                                 ("export_benchmark_json", bool(export_benchmark_json))) if on]
        if given:                        # scoring files runs no case: these would be silently ignored
            P.append(f"{', '.join(given)}: a results: config scores files made elsewhere and runs no case; "
                     "drop these arguments")
        scored = scored_results(raw, config_or_path, P)
    bad_config = None
    if raw is None and not why and not isinstance(config_or_path, Config):
        try:                             # the config's own problems join the arguments', as the CLI's do
            config_or_path = load_config(config_or_path)
        except ConfigError as exc:
            bad_config = exc
    if bad_config is not None:
        if not P:
            raise bad_config
        P += [f"{bad_config.source}: {p}" for p in bad_config.problems]
    if P:
        raise problems_error(list(dict.fromkeys(P)))
    if raw is not None:                  # a results: config scores files made elsewhere (shootout eval)
        from .scoring import eval_entries
        entries, hs = scored
        out_dir = Path(out) if out else Path("results") / str(raw[0].get("name") or "eval")
        return eval_entries(entries, out_dir, hs, raw[0], hausdorff_eps=raw[0].get("hausdorff_eps", 1e-3))
    cfg: Config = config_or_path if isinstance(config_or_path, Config) else load_config(config_or_path)
    out_dir = Path(out) if out else Path("results") / cfg.name
    folder = RunFolder(out_dir)
    cpus = usable_cpus()                 # the cores this run may use
    workers = 1 if executor == "serial" else int(workers) if workers else cpus
    timeout = None if executor == "serial" else timeout if timeout is not None else cfg.timeout
    chash = config_hash(cfg)
    threads = 1 if executor == "dask" else max(1, cpus // workers)
    cases = [dataclasses.replace(c, threads=threads) for c in cfg.cases]
    # refused before the folder or its lock is made (a given out was checked with the config above)
    problems = [] if out else out_dir_problems(out_dir, resume)
    try:
        check_output_file(export_benchmark_json, "export_benchmark_json", run_dirs=(out_dir,), kind="json")
    except ShootoutError as exc:
        problems.append(str(exc))
    if not problems and out_dir.is_dir():
        problems = folder_problems(folder, out_dir, _accepted(cfg, chash), resume, cfg)
    if problems:
        raise problems_error(problems)
    # before anything is written: an unreachable Dask scheduler is exit 2 with the folder untouched
    ex = make_executor(executor, workers, timeout, scheduler)
    try:
        lock = folder.lock()              # one run per folder; held until this function returns
    except BaseException:
        ex.close()
        raise
    from .runner import thread_env
    try:
        # libigl's count, inherited by forked cases should the driver start libigl's threads during
        # the run; the other variables are set in each case only (MKL loaded here would keep them)
        with thread_env(threads, ("IGL_NUM_THREADS",)):
            return _locked_run(cfg, folder, out_dir, cases, workers, timeout, chash, threads, executor, scheduler,
                               resume, quiet, export_benchmark_json, ex)
    except BaseException:
        try:
            ex.close()
        except Exception:  # noqa: BLE001 - already closed
            pass
        raise
    finally:
        lock.close()


def _fixed_cost(row: dict, extras: dict) -> tuple[float, float, float] | None:
    """``(fixed, method, measuring)`` seconds of an ok case: ``method`` its timed samples plus the
    cold call, ``fixed`` the rest of its wall time (imports, loading, noise, measuring), and
    ``measuring`` the part of ``fixed`` spent measuring the result (0 where unknown)."""
    wall = extras.get("case_wall_s")
    if wall is None or row.get("status") != "ok":
        return None
    try:
        method = sum(json.loads(row.get("times") or "[]")) + float(row.get("time_cold_s") or 0.0)
    except (TypeError, ValueError):
        return None
    return max(0.0, wall - method), method, float(extras.get("measure_s") or 0.0)


def _config_problem(source) -> str | None:
    """What is wrong with `run`'s config argument as a kind of thing (a `Config`, a dict, YAML
    text, or the path of a config file), or None; what is wrong inside a config is `load_config`'s."""
    if isinstance(source, (Config, dict)):
        return None
    expected = "expected a Config, a dict, YAML text or the path of a config file (.yaml, .yml, .json)"
    if not isinstance(source, (str, os.PathLike)):
        from .yaml_input import short
        got = "None" if source is None else f"{type(source).__name__} {short(source, 60)}"
        return f"config_or_path: {expected}, got {got}"
    text = os.fspath(source)
    if not isinstance(text, str) or "\n" in text:
        return None
    if not text.strip():
        return f"config_or_path: an empty string; {expected}"
    try:                                   # one-line YAML or JSON text may be no possible file name at all
        is_file, is_dir = Path(text).is_file(), Path(text).is_dir()
    except (OSError, ValueError):
        is_file = is_dir = False
    if is_file:
        return None
    if is_dir:
        return f"config_or_path: {text} is a folder; {expected}"
    if isinstance(source, str) and Path(text).suffix not in (".yaml", ".yml", ".json"):   # those: "not found"
        from . import yaml_input
        try:
            raw = yaml_input.load(text)
        except Exception:  # noqa: BLE001 - load_config reports what is wrong with the text
            return None
        if not isinstance(raw, dict):
            return f"config_or_path: {text!r} names no file and is not YAML text of a mapping; {expected}"[:400]
    return None


def scored_results(raw: tuple, source, problems: list) -> tuple | None:
    """The entries and sample count of the ``results:`` config ``raw`` (`_results_config` of
    ``source``; `harness.scoring.results_config`). Its problems join ``problems`` (each named
    by the config's source) when there are already some, so one message lists them all;
    alone, its `ConfigError` is raised."""
    from .errors import ConfigError
    from .scoring import results_config
    given = str(source) if isinstance(source, (str, Path)) else ""
    label = given if given and "\n" not in given and Path(given).is_file() else "<config>"
    found = [f"not valid YAML: {o}" for o in raw[2]]         # duplicate keys, numbers YAML 1.1 misreads
    try:
        got = results_config(raw[0], raw[1], label)
    except ConfigError as exc:
        label, found = exc.source, found + list(exc.problems)
    else:
        if not found:
            return got
    if not problems:
        raise ConfigError(label, found)
    problems += [f"{label}: {p}" for p in found]
    return None


def _results_config(source):
    """``(raw, base_dir, yaml_problems)`` when ``source`` is a config with a top-level ``results:``
    key, else None; ``yaml_problems``: its duplicate keys and numbers YAML 1.1 reads otherwise
    than they look (`harness.yaml_input.load`), to be listed with its other problems."""
    if isinstance(source, Config):
        return None
    odd: list = []
    try:
        if isinstance(source, dict):
            raw, base = source, Path.cwd()
        else:
            from . import yaml_input
            p = Path(str(source))
            if "\n" not in str(source) and p.suffix in (".yaml", ".yml", ".json") and p.is_file():
                raw, base = yaml_input.load(p.read_text(), odd), p.resolve().parent
            else:
                raw, base = yaml_input.load(str(source), odd), Path.cwd()
    except Exception:  # noqa: BLE001 - load_config reports what is wrong with it
        return None
    return (raw, base, odd) if isinstance(raw, dict) and "results" in raw and "tasks" not in raw else None


def _inside(path, folder) -> bool:
    """Whether ``path`` lies in ``folder`` (both made absolute, links not followed)."""
    return Path(os.path.abspath(path)).is_relative_to(Path(os.path.abspath(folder)))


class DiskFull(ShootoutError):
    """The run folder's disk filled up (exit 1: not a config problem)."""

    exit_code = 1


def _mesh_ok(path: Path) -> bool:
    """A saved mesh that exists and parses (a diverged result's coordinates that are not finite
    included: they are the result)."""
    try:
        import numpy as np

        from .mesh import read_mesh
        with np.errstate(all="ignore"):          # its coordinates may overflow the area check
            read_mesh(path, repair=False, finite=False)
        return True
    except Exception:  # noqa: BLE001
        return False


def _write_status_in_place(folder, status: str) -> None:
    """Overwrite run.json's ``"status": "running"`` and the spaces after it (`RunFolder.write_run_json`
    leaves room) in place, which needs no new disk block, when a full disk refuses a new file. A
    status that does not fit is not written (the file stays valid JSON)."""
    from .results import RUNNING, STATUS_ROOM
    try:
        with open(folder.run_json, "r+b") as fh:
            data = fh.read()
            old = (RUNNING + " " * STATUS_ROOM).encode()
            i = data.find(old)
            new = f'"status": "{status}"'.encode()
            if i >= 0 and len(new) <= len(old):
                fh.seek(i)
                fh.write(new.ljust(len(old)))
                fh.flush()
                os.fsync(fh.fileno())
    except OSError:
        pass


def _accepted(cfg: Config, chash: str) -> tuple:
    """The config hashes a folder to resume may hold: this version's, and for a tuned run the one
    versions before it wrote without the tune section (its training rows are kept by case id, so a
    changed tune section still cannot mix rows)."""
    return (chash,) if cfg.tune is None else (chash, config_hash(cfg, with_tune=False))


def _what_changed(prev: dict, folder, cfg: Config | None) -> str:
    """What differs between the run recorded in ``folder`` (its run.json's config, its plan.csv)
    and ``cfg``, as far as those files tell: ``'; found: ...'``, or '' when they do not."""
    if cfg is None or not isinstance(prev.get("config"), dict):
        return ""
    old, new, out = prev["config"], cfg.raw if isinstance(cfg.raw, dict) else {}, []
    for key, default in (("repeats", 1), ("time_budget", 0.25), ("hausdorff_samples", 20000),
                         ("hausdorff_eps", 1e-3)):
        a, b = old.get(key, default), new.get(key, default)
        if a != b:
            out.append(f"{key} {a!r} -> {b!r}")
    if old.get("tune") != new.get("tune"):
        out.append("tune:")
    try:
        ran = {r["case_id"] for r in (folder.read_plan() or [])}
    except Exception:  # noqa: BLE001 - a damaged plan says nothing here; its own check names it
        ran = set()
    if ran:
        now = {c.case_id for c in cfg.cases}
        if ran - now or now - ran:
            out.append(f"{len(ran - now)} of its cases not in this config, {len(now - ran)} of this config's not in it")
    return f"; found: {', '.join(out)}" if out else ""


def folder_problems(folder, out_dir, chash, resume: bool, cfg: Config | None = None) -> list[str]:
    """Why this run may not write into ``folder``: another program's files there (a fresh run), or
    (``--resume``) a run.json that is damaged, missing beside output files or of another config,
    or a task CSV whose columns are not this version's (resuming would drop its rows)."""
    state = folder.run_json_state()
    if not resume:
        return [str(folder.foreign_error())] if folder.foreign_files() else []
    prev = folder.read_run_json()
    if state == "ok" and prev.get("kind") == "eval":
        return [f"--resume: {out_dir} holds the scores of `shootout eval`, not a run of a config; "
                "use a new --out folder"]
    if state == "corrupt" or (state == "ok" and not prev.get("config_hash")):
        return [f"--resume: {folder.run_json} is damaged, so the rows in {out_dir} cannot be matched "
                "to this config; run without --resume (a fresh run) or use a new --out folder"]
    if state == "missing" and folder.foreign_files():
        return [f"--resume: {out_dir} has {', '.join(folder.foreign_files())} but no run.json; "
                "they cannot be matched to this config"]
    accepted = (chash,) if isinstance(chash, str) else tuple(chash)
    if prev and len(accepted) > 1 and not (isinstance(prev.get("config"), dict) and prev["config"].get("tune")):
        accepted = accepted[:1]             # the tune-less hash stands for an older tuned run only
    if prev and prev.get("config_hash") not in accepted:
        return [f"--resume: the config changed since the run in {out_dir} started "
                "(cases, tune:, repeats, time_budget, hausdorff_samples or hausdorff_eps differ; a case id also changes when a "
                "mesh file's contents or a method's default parameters do" + _what_changed(prev, folder, cfg)
                + "); run without --resume to start over, or use a new --out folder"]
    return [f"--resume: {p}: written by another version of mesh-shootout or of its task kind, so resuming would "
            "drop its rows; run without --resume (a fresh run replaces them) or use a new --out folder"
            for p in folder.column_problems()]


PROVENANCE = ("git_commit", "git_dirty", "code_sha256", "versions")


NO_ROOM = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)


def _no_room(exc: OSError, out_dir, then: str = "the run is marked interrupted and nothing half-written was "
             "kept; make room (or raise the limit), then continue with --resume") -> str:
    """The message of a write that found no room: where (the file, when the error names one: the
    run folder, or elsewhere such as the cases' temporary files in ``TMPDIR``), why (a full
    disk, a quota, or the file-size limit of ``ulimit -f``), and ``then``, what was kept and what to do."""
    import tempfile
    why = {errno.EFBIG: "a file reached the size limit this process may write (ulimit -f)",
           errno.EDQUOT: "the disk quota is used up"}.get(exc.errno, "the disk is full")
    where = Path(exc.filename) if isinstance(exc.filename, (str, bytes, os.PathLike)) and exc.filename else None
    note = ""
    if where is not None and not _inside(where, out_dir):
        note = (f" (not in the run folder {out_dir}: the cases' temporary files go to {tempfile.gettempdir()}, "
                "set by TMPDIR)")
    return f"{where or out_dir}: {why} ({exc.strerror}){note}; {then}"


def _keep_first_provenance(meta: dict, prev: dict, session_id: str, quiet: bool) -> None:
    """On --resume: run.json's top-level commit and package versions stay the first run's (as
    ``started`` and ``command`` do; each session records its own), and a session whose code or
    packages differ is listed in ``provenance_changed`` and said on stderr: the folder then
    holds rows of both."""
    now = {k: meta[k] for k in PROVENANCE}
    first = {k: prev[k] for k in PROVENANCE if k in prev}     # what the first run recorded (None is a value:
    diff: dict = {}                                           # not installed, not a git checkout); a key an
    for k in ("git_commit", "git_dirty", "code_sha256"):      # older version did not write is no change
        if k in first and first[k] != now[k]:
            diff[k] = [first[k], now[k]]
    fv = first.get("versions") if isinstance(first.get("versions"), dict) else {}
    vers = {p: [fv[p], now["versions"].get(p)] for p in sorted(fv)
            if p in now["versions"] and fv[p] != now["versions"][p]}
    if vers:
        diff["versions"] = vers
    meta.update(first)
    changed = [x for x in prev.get("provenance_changed") or [] if isinstance(x, dict)]
    if diff:
        changed.append({"session": session_id, **diff})
        if not quiet:
            what = ([f"commit {diff['git_commit'][0]} -> {diff['git_commit'][1]}"] if "git_commit" in diff else []) \
                + (["uncommitted changes " + ("now" if now["git_dirty"] else "then")] if "git_dirty" in diff else []) \
                + (["the source files (harness, methods, plugins: code_sha256)"] if "code_sha256" in diff else []) \
                + [f"{p} {a} -> {b}" for p, (a, b) in vers.items()]
            print("shootout: warning: this session's code or packages differ from the run's first ("
                  + "; ".join(what) + "): the folder will hold rows of both (run.json provenance_changed)",
                  file=sys.stderr, flush=True)
    if changed:
        meta["provenance_changed"] = changed
    loads = prev.get("load_average")
    if isinstance(loads, list) and loads and isinstance(loads[0], (int, float)):
        meta["load_average"] = [loads[0]] + meta["load_average"][-1:]    # the run's start, this session's


def relabelled_meshes(folder, cases) -> list[str]:
    """For --resume: meshes whose label changed since their rows were written (a file's ``name:``
    or file name). A case id leaves the label out, but the noise is seeded by it, so the
    recorded noisy inputs differ from the ones this config would make."""
    label = {c.case_id: c.mesh_key for c in cases}
    seen: dict = {}
    for sub in (folder, RunFolder(folder.path / "tune")):
        for task in tasks.names():
            for r in sub.read_rows(task):
                now = label.get(r.get("case_id"))
                if now is not None and r.get("mesh") not in (None, "", now):
                    seen.setdefault((r["mesh"], now), r.get("noise_model"))
    return [f"--resume: the mesh labelled {old!r} in the run's rows is labelled {new!r} by this config (its "
            "name: or file name changed); the noise is seeded by the label, so the rows would mix two different "
            "noisy inputs of one mesh: label it as before, or run without --resume"
            for (old, new) in sorted(seen)]


def _earlier_tuned_ids(record) -> set:
    """The tuned test cases an earlier session's choice (run.json ``tune``) made; none of a
    record that does not hold them as written."""
    methods = record.get("methods") if isinstance(record, dict) else None
    if not isinstance(methods, dict):
        return set()
    return {str(c) for ch in methods.values() if isinstance(ch, dict) and isinstance(ch.get("test_case_ids"), list)
            for c in ch["test_case_ids"]}


def _locked_run(cfg, folder, out_dir, cases, workers, timeout, chash, threads, executor, scheduler, resume, quiet,
                export_benchmark_json, ex):
    done: set[str] = set()
    refused = folder_problems(folder, out_dir, _accepted(cfg, chash), resume, cfg)   # before the lock too; again under it
    if refused:
        raise problems_error(refused)
    try:
        planned = plan(cfg.cases)                # before anything is removed: a case no row can hold fails here
        if resume:
            relabelled = relabelled_meshes(folder, list(cfg.cases) + (list(cfg.tune.cases) if cfg.tune else []))
            if relabelled:
                raise problems_error(relabelled)
            try:
                known = None if cfg.tune is not None else {c.case_id for c in cfg.cases}   # tuned cases come later
                done = folder.keep_ok_rows(known=known)
                if cfg.save_meshes:              # an ok row whose saved mesh is missing or torn runs again
                    meshed = {c.case_id for c in cfg.cases if tasks.get(c.task).output_mesh is not None}
                    done = {cid for cid in done if cid not in meshed or _mesh_ok(out_dir / "meshes" / f"{cid}.ply")}
                    folder.drop_rows(lambda r: r["case_id"] not in done)
            except OSError as exc:
                if exc.errno in NO_ROOM:
                    folder.remove_temporaries()
                    raise DiskFull(_no_room(exc, out_dir, "--resume rewrites the CSVs with their ok rows first and "
                                            "could not finish (each CSV is whole: written to a temporary file and "
                                            "renamed); make room (or raise the limit) and resume again")) from None
                raise
            folder.remove_temporaries()
            cases = [c for c in cases if c.case_id not in done]
        else:
            folder.reset()
    except BaseException:
        ex.close()
        raise
    started = session_started = now_iso()
    session_id = secrets.token_hex(8)         # names this session's record in run.json (times are to the second)
    command = " ".join(sys.argv)
    prev_meta = folder.read_run_json() if resume else None
    prev_sessions: list = []
    if prev_meta and prev_meta.get("started"):
        started = prev_meta["started"]
        command = prev_meta.get("command") or command
        prev_sessions = list(prev_meta.get("sessions") or [])
        last_id, last = prev_meta.get("session_id"), prev_meta.get("session_started")
        if last_id:
            unrecorded = not any(x.get("id") == last_id for x in prev_sessions)
        elif last:                         # run.json before session ids: start times (to the second)
            unrecorded = not any(x.get("started") == last for x in prev_sessions)
        else:
            unrecorded = not prev_sessions or prev_meta.get("status") == "running"
        if unrecorded:
            # the last session never wrote its own record: its driver was killed (we hold the
            # folder's lock, so none runs) or its last write failed (a full disk); when it ran
            # and how long are what run.json kept
            prev_sessions.append({"id": last_id, "started": prev_meta.get("session_started") or prev_meta.get("started"),
                                  "finished": prev_meta.get("finished"), "wall_s": prev_meta.get("wall_s")
                                  if prev_meta.get("status") != "running" else None,
                                  "command": prev_meta.get("session_command") or prev_meta.get("command"),
                                  "status": "killed" if prev_meta.get("status") == "running"
                                  else prev_meta.get("status"), "executor": prev_meta.get("executor"),
                                  "scheduler": prev_meta.get("scheduler"), "workers": prev_meta.get("workers")})
    src = Path(cfg.source) if cfg.source and cfg.source != "<config>" else None
    meta = {"name": cfg.name, "config_source": cfg.source,
            "config_dir": str(src.resolve().parent) if src is not None and src.is_file() else str(Path.cwd()),
            "config": cfg.raw, "config_hash": chash,
            "started": started, "session_started": session_started, "session_id": session_id,
            "session_command": " ".join(sys.argv),
            "finished": None, "status": "running", "executor": executor,
            "scheduler": scheduler, "workers": workers, "timeout_s": timeout,
            "n_cases": len(cfg.cases), "resumed_ok_cases": len(done),
            "versions": package_versions(), "git_commit": git_commit(), "git_dirty": git_dirty(),
            "code_sha256": code_hash(cfg.plugins), "machine": machine_info(),
            "solver": _solver_info(), "command": command, "tasks": task_specs(cfg),
            "method_sources": method_sources(cfg),
            "measurement": {"hausdorff_samples": cfg.cases[0].hausdorff_samples if cfg.cases else None,
                            "hausdorff_eps": cfg.cases[0].hausdorff_eps if cfg.cases else None,
                            "sample_seed": 0},
            "timing": {"threads_per_case": threads, "min_repeats": cfg.repeats,
                       "time_budget_s": cfg.cases[0].time_budget if cfg.cases else None,
                       "protocol": "one untimed cold call on the case's own input (time_cold_s), then samples "
                                   "until both repeats and time_budget_s are reached; median and quartiles; each sample's "
                                   "process CPU time kept too (cpu_times); "
                                   "BLAS/OpenMP pools and libigl's own threads limited to "
                                   "threads_per_case (pools by the local driver before "
                                   "it forks, inherited; else in the case; in the case for libraries loaded since); "
                                   "IGL_NUM_THREADS, MKL_NUM_THREADS, OMP_NUM_THREADS and OPENBLAS_NUM_THREADS "
                                   "set to it in every case, for libraries a method loads during its cold call"}}
    meta["load_average"] = [_load()]
    load0 = meta["load_average"][0]             # this session's start (the run's stays first in run.json)
    own = {k: meta[k] for k in PROVENANCE}        # this session's code and packages, in its own record
    if prev_meta:
        _keep_first_provenance(meta, prev_meta, session_id, quiet)
    meta["sessions"] = prev_sessions          # kept if this session's driver is killed
    if resume:
        meta["resumed_at"] = now_iso()
        if cfg.tune is not None and isinstance((prev_meta or {}).get("tune"), dict):
            meta["tune"] = prev_meta["tune"]      # the earlier choice stands until this session's tuning chooses
            meta["n_cases"] = len(cfg.cases) + len(_earlier_tuned_ids(meta["tune"]))   # its cases too, until then
    if executor == "dask":       # the cluster's worker threads, not --workers
        meta.update(ex.describe())
    try:
        if not (resume and cfg.tune is not None):   # a tuned resume keeps its plan until tuning has chosen
            folder.write_plan(planned)
        folder.write_run_json(meta)
    except BaseException as exc:          # a full disk, or an interrupt between the two files
        ex.close()
        folder.remove_temporaries()
        if not resume:                    # a fresh run whose run.json was not written leaves no plan either
            (out_dir / PLAN_FILE).unlink(missing_ok=True)
        if isinstance(exc, OSError) and exc.errno in NO_ROOM:
            raise DiskFull(_no_room(exc, out_dir, "nothing half-written was kept; make room (or raise the limit), "
                                    "then run again" + (" with --resume" if resume else ""))) from None
        raise
    bar = None
    if not quiet:
        n_todo = len(cases) + _training_left(cfg, out_dir, resume)
        own_ids = {c.case_id for c in cfg.cases}
        if resume:
            print(f"shootout: resuming {out_dir}: {len(done)} finished case(s) kept, {n_todo} to run"
                  + (" (and the tuned cases the choice makes)" if cfg.tune is not None else ""),
                  file=sys.stderr, flush=True)
        budget = cfg.cases[0].time_budget if cfg.cases else 0.25
        floor = n_todo * budget / max(int(meta["workers"] or 1), 1)     # every case samples its budget at least
        print(f"shootout: {meta['n_cases']} case(s), {n_todo} to run on {meta['workers']} worker(s)"
              + (f" (a large run: {n_todo:,} cases, at least {_duration(floor)} of timing alone, "
                 f"time_budget {budget:g} s each; --timeout bounds each one)" if n_todo > 1000 else ""),
              file=sys.stderr, flush=True)
        bar = _progress(len(cfg.cases), len(done & own_ids))
    counts: dict[str, int] = {}
    overhead: list[tuple[float, float, float]] = []
    t0 = time.perf_counter()
    extra_cases: list = []
    try:
        if cfg.tune is not None:
            extra_cases = _tune(cfg, ex, out_dir, meta, threads, resume, quiet,
                                previous=(prev_meta or {}).get("tune") if resume else None)
            if resume:                   # rows of tuned settings this choice no longer makes are not this run's
                ours = {c.case_id for c in list(cfg.cases) + extra_cases}
                folder.drop_rows(lambda r: r["case_id"] not in ours)
                done &= ours
            todo = [c for c in extra_cases if c.case_id not in done]
            cases = cases + todo
            meta["n_cases"] = len(cfg.cases) + len(extra_cases)
            folder.write_run_json(meta)
            folder.write_plan(plan(list(cfg.cases) + list(extra_cases)))
            if bar is not None:
                bar.total = meta["n_cases"]
                kept_tuned = len(extra_cases) - len(todo)
                if kept_tuned:            # tuned test cases a resume kept: done, as the config's own kept ones
                    bar.update(kept_tuned)
        for case, row, extras in ex.run(cases, want_meshes=cfg.save_meshes):
            for fname, (V, F, q, what) in (extras.get("meshes") or {}).items():   # meshes first, then the row
                if not (out_dir / "meshes" / fname).exists() or fname.startswith(case.case_id):
                    folder.save_mesh(fname, lambda fh, V=V, F=F, q=q, w=what: write_ply(fh, V, F, q, w))
            folder.append(case.task, row)
            counts[row["status"]] = counts.get(row["status"], 0) + 1
            fixed = _fixed_cost(row, extras)
            if fixed is not None:
                overhead.append(fixed)
            if bar is not None:
                bar.set_postfix_str(f"{case.method} on {case.mesh_key}", refresh=False)
                bar.update(1)
            check_interrupt()
        check_interrupt()
        meta["status"] = "finished"
    except KeyboardInterrupt:
        meta["status"] = "interrupted"
        raise
    except OSError as exc:
        meta["status"] = "interrupted"
        folder.remove_temporaries()
        if exc.errno in NO_ROOM:
            raise DiskFull(_no_room(exc, out_dir)) from None
        if exc.filename is None or not _inside(str(exc.filename), out_dir):   # not a run file (a socket, a fork)
            raise
        raise RunInterrupted(f"{exc.filename}: {exc.strerror or exc}: the run could not write its "
                             "files (was the run folder changed while it ran?); the rows written so far are kept: "
                             "mend it and run again with --resume") from None
    except BaseException:
        meta["status"] = "interrupted"        # never 'finished' when something escaped the executor
        raise
    finally:
        if bar is not None:
            bar.close()
        ex.close()
        meta["load_average"] = meta["load_average"][:1] + [_load()]
        wall = round(time.perf_counter() - t0, 3)
        session = {"id": session_id, "started": session_started, "finished": now_iso(), "wall_s": wall,
                   "command": " ".join(sys.argv), "status": meta["status"], "resumed_ok_cases": len(done),
                   "executor": meta.get("executor"), "scheduler": meta.get("scheduler"), "workers": meta.get("workers"),
                   "threads_per_case": threads, "timeout_s": timeout, "status_counts": counts,
                   "load_average": [load0, meta["load_average"][-1]], **own}
        if overhead:
            fixed = [f for f, _, _ in overhead]
            spent = sum(m for _, m, _ in overhead)
            shares = [f / m for f, m, _ in overhead if m > 0]
            meta["fixed_cost_per_case_s"] = {
                "mean": round(sum(fixed) / len(fixed), 4), "max": round(max(fixed), 4), "cases": len(fixed),
                "measuring_mean": round(sum(g for _, _, g in overhead) / len(overhead), 4),
                "share_of_method_time": round(sum(fixed) / spent, 4) if spent > 0 else None,
                "median_case_share": round(statistics.median(shares), 4) if shares else None,
                "definition": "wall time of the case call in its process minus its timed samples and cold call "
                              "(imports, mesh loading, noise, measuring; not the fork itself); ok cases of this session; "
                              "share_of_method_time: the cases' summed fixed cost over their summed method time "
                              "(samples + cold call); median_case_share: the median of that ratio per case; "
                              "measuring_mean: the part of the mean spent measuring the results (the task's metrics)"}
            session["fixed_cost_per_case_s"] = meta["fixed_cost_per_case_s"]
        elif prev_meta and isinstance(prev_meta.get("fixed_cost_per_case_s"), dict):
            meta["fixed_cost_per_case_s"] = prev_meta["fixed_cost_per_case_s"]   # the last session that ran cases
        try:
            on_disk = folder.status_counts()
        except (OSError, ShootoutError):       # a CSV that cannot be read now: this session's counts
            on_disk = counts
        meta.update(finished=session["finished"], status_counts=on_disk,
                    status_counts_this_session=counts, sessions=prev_sessions + [session],
                    wall_s=round(wall + sum(x.get("wall_s") or 0 for x in prev_sessions), 3))
        try:
            folder.write_run_json(meta)
        except OSError:                       # disk full: the status below is the best we can record
            folder.remove_temporaries()
            _write_status_in_place(folder, meta["status"])
    try:
        not_written = finish(out_dir, cfg, timeout=timeout, export_benchmark_json=export_benchmark_json,
                             extra_cases=extra_cases, threads=threads)
    except KeyboardInterrupt:               # the rows are whole; the views, report or export are not
        meta["status"] = meta["sessions"][-1]["status"] = "interrupted"
        try:
            folder.write_run_json(meta)
        except OSError:
            pass
        raise
    return Frames(folder.frames(), not_written)


def _training_left(cfg: Config, out_dir: Path, resume: bool) -> int:
    """How many training cases of ``tune:`` will run: all, or on ``--resume`` those without an
    ok row in ``tune/`` (what `_tune` keeps); 0 without ``tune:``."""
    if cfg.tune is None:
        return 0
    ids = {c.case_id for c in cfg.tune.cases}
    kept: set = set()
    if resume:
        tf = RunFolder(out_dir / "tune")
        for t in {c.task for c in cfg.tune.cases}:
            try:
                kept |= {r["case_id"] for r in tf.read_rows(t) if r.get("status") == "ok"} & ids
            except Exception:  # noqa: BLE001 - a damaged training CSV: the tuning step says so
                pass
    return len(ids - kept)


def _tune(cfg: Config, ex, out_dir: Path, meta: dict, threads: int, resume: bool, quiet: bool,
          previous: dict | None = None) -> list:
    """Run the training cases of ``tune:`` into ``tune/``, choose each method's setting, and return
    the tuned test cases (see `harness.tune`). On ``--resume``, ``previous`` (run.json's ``tune``)
    is the earlier session's choice: a choice that changed (training cases that failed, e.g. timed
    out, ran again) is said on stderr and kept in ``changed_on_resume``."""
    from .tune import choose, tuned_cases
    tfolder = RunFolder(out_dir / "tune")
    done = tfolder.keep_ok_rows(known={c.case_id for c in cfg.tune.cases}) if resume else set()
    if not resume:
        tfolder.reset()
    todo = [dataclasses.replace(c, threads=threads) for c in cfg.tune.cases if c.case_id not in done]
    if not quiet:
        print(f"shootout: tuning: {len(todo)} of {len(cfg.tune.cases)} training case(s) to run on "
              f"{len(cfg.tune.train)} mesh(es)", file=sys.stderr, flush=True)
    for case, row, _ in ex.run(todo):
        tfolder.append(case.task, row)
    choice = choose(cfg.tune, tfolder.frames())
    for m, ch in choice.items():
        if ch["train_score"] is None:     # no candidate scored: nothing was chosen from
            print(f"shootout: warning: tuning: {m}: no training setting has a valid score (its training cases "
                  f"failed, timed out or are invalid: see {out_dir / 'tune'}); it runs as configured",
                  file=sys.stderr, flush=True)
    from .config import expand_cases
    tuned = [dataclasses.replace(c, threads=threads) for c in tuned_cases(cfg, cfg.tune, choice, expand_cases)]
    for m, ch in choice.items():
        ch["test_case_ids"] = sorted(c.case_id for c in tuned if c.method == m)
    from .datasets import spec_key
    meta["tune"] = {"metric": cfg.tune.metric, "train_meshes": [spec_key(t) for t in cfg.tune.train],
                    "budget": cfg.tune.budget, "seed": cfg.tune.seed, "methods": choice}
    prev = previous if isinstance(previous, dict) else {}
    earlier = prev.get("changed_on_resume")
    changed = [c for c in earlier if isinstance(c, dict)] if isinstance(earlier, list) else []
    chosen_before = prev.get("methods") if isinstance(prev.get("methods"), dict) else {}
    for m, ch in choice.items():
        entry = chosen_before.get(m)
        before = entry.get("chosen") if isinstance(entry, dict) and isinstance(entry.get("chosen"), dict) else None
        if before is not None and before != ch["chosen"]:
            changed.append({"method": m, "before": before, "after": ch["chosen"], "session": meta.get("session_id")})
            print(f"shootout: tuning: {m}: the choice changed on resume, {before or 'as configured'} -> "
                  f"{ch['chosen'] or 'as configured'} (training cases that had failed ran again); the earlier "
                  "choice's test rows are dropped", file=sys.stderr, flush=True)
    if changed:
        meta["tune"]["changed_on_resume"] = changed
    return tuned


def finish(out_dir, cfg: Config, timeout=None, export_benchmark_json=None, extra_cases=(), threads=None) -> list[str]:
    """After the last row: the 3D views (views/, with the run's ``threads`` per case), the report
    and the optional benchmark export.
    The rows are safe on disk; a failure here is a warning and an entry of the returned list of
    what was not written, never a lost run."""
    from .report import build_report
    from .views import compute_views
    problems: list[str] = []
    folder = RunFolder(out_dir)

    def warn(what: str, exc: Exception, extra: str = "") -> None:
        problems.append(what)
        print(f"shootout: warning: {what} ({type(exc).__name__}: {exc}){extra}", file=sys.stderr)
    try:
        views = compute_views({c.case_id: c for c in list(cfg.cases) + list(extra_cases)}, folder.frames(), cfg.report,
                              timeout=timeout, threads=threads)
        folder.write_views(views)
    except Exception as exc:  # noqa: BLE001
        warn("3D views could not be computed", exc)
    try:
        from .leaderboard import write as write_leaderboard
        write_leaderboard(out_dir, with_not_run(folder.frames(), folder.read_plan()),
                          {t: s for t, s in task_specs(cfg).items()})
    except Exception as exc:  # noqa: BLE001
        warn("the leaderboard could not be written", exc)
    try:
        build_report(out_dir)
    except Exception as exc:  # noqa: BLE001
        warn("report.html could not be built", exc,
             f"; rows are in {out_dir}; retry with `shootout report {out_dir}`")
    if export_benchmark_json:
        from .benchmark_json import export_benchmark_json as _export
        _export(out_dir, export_benchmark_json)
    return problems


def _recorded_tuned_cases(cfg: Config, meta: dict) -> list:
    """The tuned test cases of a run (its config's ``tune:`` and the settings run.json records as
    chosen): the tuning is not run again. [] when there are none or the record is unusable."""
    from .config import expand_cases
    from .tune import tuned_cases
    methods = ((meta.get("tune") or {}).get("methods") if isinstance(meta.get("tune"), dict) else None) or {}
    if cfg.tune is None or not isinstance(methods, dict):
        return []
    choice = {m: {"chosen": ch["chosen"]} for m, ch in methods.items()
              if m in cfg.tune.configured and isinstance(ch, dict) and isinstance(ch.get("chosen"), dict)}
    try:
        return tuned_cases(cfg, cfg.tune, choice, expand_cases)
    except Exception:  # noqa: BLE001 - a damaged record: those views say their case is not among the run's
        return []


def recompute_views(run_dir) -> list[dict]:
    """Rebuild the cases from run.json's config and compute the 3D views again (this runs the
    chosen methods, including any plugin named in run.json). Returns the views written (a
    failed one carries its ``error`` text)."""
    from .views import compute_views
    folder = RunFolder(run_dir)
    meta = folder.read_run_json()
    if meta is None and folder.run_json_state() == "corrupt":
        raise ShootoutError(f"{folder.run_json}: damaged or not written by mesh-shootout (unreadable JSON, or keys "
                            "such as 'versions' missing): the cases cannot be rebuilt from it")
    if not meta or not isinstance(meta.get("config"), dict):
        raise ShootoutError(f"{run_dir}: no run.json with a config to rebuild the cases from")
    src, where = meta.get("config_source"), meta.get("config_dir")
    if where and Path(where).is_dir():               # relative mesh files resolve where the run did
        base = Path(where)
    else:
        base = Path(src).parent if src and Path(src).parent.is_dir() else Path.cwd()
    raw = dict(meta["config"])
    report = raw.pop("report", None)     # a listed id no longer a case (its file changed): its view says so
    cfg = load_config({**raw, "report": {k: v for k, v in report.items() if k != "views"}} if isinstance(report, dict)
                      else raw, base_dir=base.resolve(), label=f"{folder.run_json} (its config)")
    threads = (meta.get("timing") or {}).get("threads_per_case") if isinstance(meta.get("timing"), dict) else None
    threads = threads if isinstance(threads, int) and not isinstance(threads, bool) and 0 < threads <= 4096 else None
    cases = list(cfg.cases) + _recorded_tuned_cases(cfg, meta)
    views = compute_views({c.case_id: c for c in cases}, folder.frames(),
                          report if isinstance(report, dict) else cfg.report, threads=threads)
    stored = {v.get("case_id"): v for v in folder.read_views() if isinstance(v, dict) and not v.get("error")}
    views = [{**stored[v["case_id"]], "why": v.get("why"), "kept": v["error"]}     # the run's own view stays
             if v.get("not_rebuilt") and v.get("case_id") in stored else v for v in views]
    folder.write_views(views)
    return views
