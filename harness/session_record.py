"""What run.json records of a session beside its rows: the module and distribution of every
method, the declarations of the tasks used (with each method's defaults and how its case ids
name parameters), the solver backends, the load average, each ok case's fixed cost beside its
method time, and, on ``--resume``, the first run's provenance kept at the top level with the
sessions whose code or packages differ listed in ``provenance_changed``."""
from __future__ import annotations

import json
import os
import sys

from . import tasks
from .config import Config


def _solver_info() -> dict | None:
    try:
        from .core.solvers import solver_info
        return solver_info()
    except Exception as exc:  # provenance must never fail a run
        return {"error": f"{type(exc).__name__}: {exc}"}


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


def _count_solvers(used: dict, case, solvers) -> None:
    """Add a case's sparse solver backends (`harness.runner.run_case`'s ``extras["solver"]``,
    ``{backend: largest system}``) to ``used``: ``{backend: {"cases", "unknowns_max",
    "methods"}}`` for run.json's ``solver.used``."""
    if not isinstance(solvers, dict):
        return
    for name, n in solvers.items():
        _add_solver(used, name, 1, int(n), [case.method])


def _add_solver(used: dict, name, cases: int, unknowns: int, methods: list) -> None:
    """Count ``cases`` case runs of backend ``name`` in ``used`` (`_count_solvers`' form)."""
    u = used.setdefault(str(name), {"cases": 0, "unknowns_max": 0, "methods": []})
    u["cases"] += cases
    u["unknowns_max"] = max(u["unknowns_max"], unknowns)
    u["methods"] = sorted(set(u["methods"]) | {str(m) for m in methods})


def _merged_solvers(this: dict, earlier_sessions: list) -> dict:
    """run.json's ``solver.used`` over the run's sessions: this session's (`_count_solvers`)
    added to each earlier session's own record (``sessions[i].solver_used``; entries of a wrong
    type, a hand edit, are left out). ``cases`` counts case runs: a case a resume ran again counts
    again; a session whose driver was killed recorded none."""
    out: dict = {}
    records = [x.get("solver_used") for x in earlier_sessions if isinstance(x, dict)] + [this]
    for rec in records:
        for name, v in (rec.items() if isinstance(rec, dict) else ()):
            if not (isinstance(v, dict) and isinstance(v.get("cases"), int) and isinstance(v.get("unknowns_max"), int)
                    and isinstance(v.get("methods"), list)):
                continue
            _add_solver(out, name, v["cases"], v["unknowns_max"], v["methods"])
    return {k: out[k] for k in sorted(out)}


PROVENANCE = ("git_commit", "git_dirty", "code_sha256", "versions")


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
