"""YAML config -> validated `Config` -> list of `Case`.

Every problem is collected with its key path (``tasks.smoothing.methods[1].params.step``) and
raised once as a `ConfigError`; nothing is written before validation passes.
"""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from . import datasets, yaml_input
from .cases import Case, _count_cases, case_id, expand_cases, method_id_spec, noise_name
from .config_meshes import _check_meshes, _numbered
from .config_tasks import _check_noise, _check_tasks
from .config_values import (MAX_CASES, MAX_REPEATS, MAX_SAMPLES, NOISE_KEYS, REPORT_KEYS, TASK_KEYS, TOP_KEYS,
                            _is_int, _is_num, _unknown_keys, eps_problem, name_problem, samples_problem)
from .errors import ConfigError

__all__ = ["Case", "Config", "load_config", "expand_cases", "case_id", "method_id_spec", "noise_name",
           "name_problem", "samples_problem", "eps_problem", "TOP_KEYS", "TASK_KEYS", "REPORT_KEYS",
           "NOISE_KEYS", "MAX_REPEATS", "MAX_SAMPLES", "MAX_CASES"]


@dataclass
class Config:
    name: str
    raw: dict
    repeats: int
    save_meshes: bool
    plugins: list
    seed: int
    timeout: float | None
    cases: list = field(default_factory=list)
    report: dict = field(default_factory=dict)
    source: str = "<config>"
    tune: object = None             # harness.tune.TuneSpec, or None


def _is_file(p: Path) -> bool:
    """``p.is_file()``, False for a path the system cannot even look up (too long, say)."""
    try:
        return p.is_file()
    except (OSError, ValueError):
        return False


def load_config(source, base_dir: Path | None = None, label: str = "<config>") -> Config:
    """Parse and validate a config given as a path, YAML text or dict; ``label`` names a dict or
    text in messages (a path names itself)."""
    odd: list[str] = []                  # numbers YAML 1.1 reads otherwise: listed with the other problems
    if isinstance(source, dict):
        raw = _plain(source)
    elif isinstance(source, Path):
        label = str(source)
        if not _is_file(source):
            raise ConfigError(label, [f"config file not found (or not a file): {source}"])
        base_dir = base_dir or source.parent
        try:
            raw = yaml_input.load(source.read_text(), odd)
        except (yaml.YAMLError, UnicodeDecodeError) as exc:
            raise ConfigError(label, [_yaml_problem(exc, label)]) from None
    else:
        p = Path(str(source))
        if "\n" not in str(source) and p.suffix in (".yaml", ".yml", ".json"):
            label = str(p)
            if not _is_file(p):
                raise ConfigError(label, [f"config file not found: {p}"])
            base_dir = base_dir or p.parent
            try:
                text = p.read_text()
            except UnicodeDecodeError as exc:
                raise ConfigError(label, [_yaml_problem(exc, label)]) from None
        else:
            text = str(source)
        try:
            raw = yaml_input.load(text, odd)
        except yaml.YAMLError as exc:
            raise ConfigError(label, [_yaml_problem(exc, label)]) from None
    odd = [f"not valid YAML: {o}" for o in odd]
    if raw is None:
        raise ConfigError(label, odd + ["the config is empty: expected a mapping with name, meshes and tasks"])
    if not isinstance(raw, dict):
        raise ConfigError(label, odd + [f"top level: expected a mapping, got {type(raw).__name__}"])
    return _validate(raw, label, (base_dir or Path.cwd()).resolve(), odd)


def _yaml_problem(exc, label: str) -> str:
    """A YAML error on one line, naming the config where the parser says "<unicode string>"."""
    return f"not valid YAML: {exc}".replace("\n", " ").replace('"<unicode string>"', f'"{label}"')


def _plain(x):
    """A config given from Python with numpy scalars as the Python numbers they hold
    (``np.int64(5)`` is 5, ``np.float64(0.3)`` 0.3: equal settings, equal case ids, JSON a run can
    record; ``np.float32(0.3)`` is the float 0.30000001192092896 it holds)."""
    import numpy as np
    if isinstance(x, dict):
        return {_plain(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return type(x)(_plain(v) for v in x)
    return x.item() if isinstance(x, np.generic) else x


def _validate(raw: dict, label: str, base_dir: Path, found=()) -> Config:
    from .plugins import import_methods
    methods = import_methods()
    P: list[str] = list(found)

    if "results" in raw and "tasks" in raw:    # a results: config scores files and runs no task: not both
        P.append("results: a config either runs tasks (tasks:) or scores files made elsewhere (results:), "
                 "not both; split it into two configs")
    _unknown_keys({k: v for k, v in raw.items() if k != "results" or "tasks" not in raw}, TOP_KEYS, "", P)

    name = raw.get("name", Path(label).stem if label != "<config>" and Path(label).is_file() else "run")
    if name_problem(name):
        given = "name" in raw
        P.append(f"name: {name_problem(name)}" + ("" if given else
                 f" (no name: in the config, so it came from the file name {Path(label).name!r}; set one)"))
    repeats = raw.get("repeats", 1)
    if not _is_int(repeats) or not 1 <= repeats <= MAX_REPEATS:
        P.append(f"repeats: expected an integer in [1, {MAX_REPEATS}], got {yaml_input.short(repeats)}")
    save = raw.get("save_meshes", False)
    if not isinstance(save, bool):
        P.append(f"save_meshes: expected true or false, got {yaml_input.short(save)}")
    seed = raw.get("seed", 0)
    if not _is_int(seed) or not 0 <= seed < 2 ** 32 - 1000:
        P.append(f"seed: expected an integer in [0, 2**32 - 1000), got {yaml_input.short(seed)}")
    timeout = raw.get("timeout")
    if timeout is not None and (not _is_num(timeout) or not math.isfinite(timeout) or timeout <= 0):
        P.append(f"timeout: expected a number of seconds > 0, got {yaml_input.short(timeout)}")
    budget = raw.get("time_budget", 0.25)
    if not _is_num(budget) or not 0 <= budget <= 3600:
        P.append(f"time_budget: expected seconds in [0, 3600], got {yaml_input.short(budget)}")
        budget = 0.25
    hs = raw.get("hausdorff_samples", 20000)
    if samples_problem(hs):
        P.append(f"hausdorff_samples: {samples_problem(hs)}")
    eps = raw.get("hausdorff_eps", 1e-3)
    if eps_problem(eps):
        P.append(f"hausdorff_eps: {eps_problem(eps)}")
        eps = 1e-3
    report = raw.get("report", {})
    if not isinstance(report, dict):
        P.append(f"report: expected a mapping, got {type(report).__name__}")
        report = {}
    _unknown_keys(report, REPORT_KEYS, "report.", P)
    views = report.get("views")
    if views is not None and (not isinstance(views, list) or not all(isinstance(v, str) for v in views)
                              or len(views) > 50):
        P.append(f"report.views: expected a list of at most 50 case ids, got {yaml_input.short(views)}")

    plugins = raw.get("plugins")
    plugins = [] if plugins is None else plugins
    if not isinstance(plugins, list) or not all(isinstance(x, str) for x in plugins):
        P.append(f"plugins: expected a list of module names, got {yaml_input.short(plugins)}")
        plugins = []
    meshes = _check_meshes(raw.get("meshes"), base_dir, P)
    noises = _check_noise(raw.get("noise", [{"model": "none"}]), P)
    early_problems = bool(P)                     # a config already rejected imports no plugin
    plugin_failed = early_problems and bool(plugins)
    for d in (str(base_dir), str(Path.cwd())):   # a plugin package beside the config, or here
        if d not in sys.path:
            sys.path.append(d)
    from .plugins import import_plugins
    failed = import_plugins(plugins if not early_problems else [])   # any failure of a user's module: a problem
    for i, mod in enumerate(plugins if not early_problems else []):
        if mod in failed:
            plugin_failed = True
            P.append(f"plugins[{i}]: cannot import {yaml_input.short(mod)} ({failed[mod]})")
    methods.load_plugins([])

    task_noise: dict = {}
    tasks = _check_tasks(raw.get("tasks"), P, skip_unknown=plugin_failed, noise=task_noise)
    noises = {t: task_noise.get(t, noises) for t in tasks}   # each task's noise list
    tune = None
    if raw.get("tune") is not None:
        from .tune import check_tune
        seen: list = []                           # the training meshes, checked even when tune: has other problems

        def check_train(m):
            seen.append(_check_meshes(m, base_dir, P, "tune.train"))
            return seen[-1]
        tune = check_tune(raw["tune"], base_dir, P, tasks, check_train)
        given = raw["tune"].get("train") if isinstance(raw["tune"], dict) else None
        train = (dict(enumerate(tune.train)) if tune is not None
                 else _numbered(given, seen[0] if seen else [], base_dir, "tune.train"))
        if train:                                 # searched on the meshes it is judged on: not a fair test
            tested = _numbered(raw.get("meshes"), meshes, base_dir, "meshes")
            judged: dict = {}
            for j, m in tested.items():
                for key in datasets.content_keys(m):
                    judged.setdefault(key, []).append(j)
            for i, m in train.items():
                hit = sorted({j for k in datasets.content_keys(m) for j in judged.get(k, ())
                              if not k.startswith("faces:") or datasets.same_surface(m, tested[j])})
                if hit:
                    what = m.get("bundled") or m.get("procedural") or Path(m.get("file", "?")).name
                    P.append(f"tune.train[{i}]: {what} is also a test mesh (meshes[{hit[0]}]: the same file, the "
                             "same faces and vertices saved otherwise, the same pair's noisy or clean file, or the "
                             "same procedural mesh); tuning on the "
                             "meshes a method is judged on favours the tuned setting: train on other meshes")

    try:                       # counted whenever the meshes and tasks allow, to join the other problems
        n = _count_cases(meshes, noises, tasks)
    except Exception:  # noqa: BLE001 - a part already listed as a problem
        n = None
    if n is not None and n > MAX_CASES:
        P.append(f"the grid expands to {n:,} cases, more than {MAX_CASES:,}: split the config or "
                 "narrow its parameter lists")
    if tune is not None:
        try:
            nt = _count_cases(tune.train, noises, tune.n_training_settings())
        except Exception:  # noqa: BLE001 - a part already listed as a problem
            nt = None
        if nt is not None and nt > MAX_CASES:
            P.append(f"tune: the training grid expands to {nt:,} cases, more than {MAX_CASES:,}: "
                     "lower tune.budget, or use fewer tune.train meshes or parameter values")
    if P:
        raise ConfigError(label, P)

    common = (seed, repeats, tuple(plugins), hs, float(budget), float(eps))
    unique = expand_cases(meshes, noises, tasks, *common)
    wanted = report.get("views") if isinstance(report, dict) else None
    if wanted and tune is None:                      # a tuned case's id is known only after the tuning
        ids = {c.case_id for c in unique}
        unknown = [v for v in wanted if v not in ids]
        if unknown:
            raise ConfigError(label, [f"report.views: {yaml_input.short(unknown)} are not case ids of this config "
                                      "(each view names a case_id of its CSVs)"])
    if tune is not None:
        tune.common = common
        tune.noises = noises
        tune.cases = expand_cases(tune.train, noises, tune.grid_tasks(), *common)
    return Config(name=name, raw=raw, repeats=repeats, save_meshes=save, plugins=plugins,
                  seed=seed, timeout=float(timeout) if timeout else None, cases=unique,
                  report=report, source=label, tune=tune)
