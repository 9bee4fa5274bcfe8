"""YAML config -> validated `Config` -> list of `Case`.

Every problem is collected with its key path (``tasks.smoothing.methods[1].params.step``) and
raised once as a `ConfigError`; nothing is written before validation passes.
"""
from __future__ import annotations

import difflib
import hashlib
import itertools
import json
import math
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from . import datasets, yaml_input
from .errors import ConfigError, ShootoutError
from .mesh import SUPPORTED, file_sha1, missing_file_problem
from .noise import MODELS

TOP_KEYS = {"name", "repeats", "save_meshes", "plugins", "seed", "meshes", "noise", "tasks",
            "timeout", "report", "hausdorff_samples", "hausdorff_eps", "time_budget", "tune"}
TASK_KEYS = {"methods", "params", "noise"}
REPORT_KEYS = {"views"}
MAX_REPEATS = 1000               # minimum timed samples per case
MAX_SAMPLES = 10_000_000         # Hausdorff area samples per side
MAX_CASES = 100_000              # cases in one config (the grid is expanded in memory)
NOISE_KEYS = {"model", "levels", "seeds", "fraction"}


@dataclass(frozen=True)
class Case:
    """One (mesh, noise model, level, seed, method, params): small, picklable, self-describing."""

    case_id: str
    task: str
    mesh: dict                      # spec, see harness.datasets
    mesh_key: str
    noise_model: str
    noise_level: float
    seed: int
    fraction: float
    method: str
    params: dict
    repeats: int = 1
    plugins: tuple = ()
    hausdorff_samples: int = 20000
    time_budget: float = 0.25       # seconds of samples to aim for (timeit-like autorange)
    threads: int = 0                # BLAS/OpenMP threads of the case process (0: no limit)
    hausdorff_eps: float = 1e-3     # relative gap the certified Hausdorff distance aims for

    @property
    def noise_name(self) -> str:
        """The noise as rows name it: the model, with its fraction when it moves only part of
        the vertices (``impulsive(fraction=0.3)``), so that entries differing only in their
        fraction are different inputs in every table and cell."""
        return noise_name(self.noise_model, self.fraction)

    @property
    def adds_noise(self) -> bool:
        """Whether the harness adds noise to the clean mesh (it then uses the mesh's noise frame);
        False for a clean input and for a given noisy/clean pair (model ``given``)."""
        return self.noise_model not in ("none", "given") and self.noise_level != 0


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


def noise_name(model: str, fraction: float = 1.0) -> str:
    """``model``, or ``model(fraction=f)`` when ``f`` < 1 (the impulsive model's moved share)."""
    return model if fraction is None or float(fraction) == 1.0 else f"{model}(fraction={float(fraction)!r})"


def _close(word, options):
    m = difflib.get_close_matches(str(word), [str(o) for o in options], n=3, cutoff=0.5)
    return f" (did you mean {', '.join(m)}?)" if m else ""


def _unknown_keys(mapping: dict, allowed, prefix: str, P: list) -> None:
    """One problem per key of ``mapping`` not in ``allowed``, with close matches."""
    for k in mapping:
        if k not in allowed:
            P.append(f"{prefix}{k}: unknown key{_close(k, allowed)}; expected one of {sorted(allowed)}")


def _is_int(x):
    return isinstance(x, int) and not isinstance(x, bool)


def _is_num(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def case_id(task, mesh_spec, model, level, seed, fraction, method, params) -> str:
    """Stable 12-hex id: sha1 of the canonical JSON of everything that defines the case."""
    blob = json.dumps([task, mesh_spec, model, level, seed, fraction, method, params],
                      sort_keys=True, default=str)
    return hashlib.sha1(blob.encode()).hexdigest()[:12]


def method_id_spec(method: str) -> dict:
    """How a case id records ``method``'s parameters (`harness.core.params.id_spec`: a parameter
    under its ``id_as`` name, one with ``id_omit_default`` left out at its default)."""
    from .core.params import id_spec
    from .plugins import import_methods
    try:
        return id_spec(import_methods().get(method).params)
    except KeyError:
        return {}


def _resolved(meth, params: dict) -> dict:
    """Declared defaults filled in, floats as floats: equal settings give equal case ids."""
    return meth.with_defaults(params)


def _identity(spec: dict) -> dict:
    """What defines a mesh for the case id: file contents (sha1), not where the file lies."""
    out = {}
    for k, v in spec.items():
        if k.endswith("_sha1"):
            continue                      # a case's record of the bytes it must read (`expand_cases`)
        if k in ("file", "clean"):
            out[k + "_sha1"] = file_sha1(v)
        elif k == "name":
            continue                      # a label only: renaming a mesh keeps its case ids
        else:
            out[k] = v
    return out


def _unique_labels(meshes: list[dict]) -> list[str]:
    """``mesh`` column labels; file meshes with the same stem get their parent folder prepended
    (``d1-Noisy``), then an index, so no two different meshes share a label."""
    from collections import Counter
    base = [datasets.spec_key(s) for s in meshes]
    nbase = Counter(base)
    labels = [f"{Path(s['file']).parent.name}-{b}" if "file" in s and nbase[b] > 1 else b
              for s, b in zip(meshes, base)]
    nlab = Counter(labels)
    first: dict[str, int] = {}
    seen: dict[str, int] = {}
    for i, lab in enumerate(labels):
        if nlab[lab] > 1:
            j = first.setdefault(lab, i)
            if j != i and _identity(meshes[i]) != _identity(meshes[j]):
                seen[lab] = seen.get(lab, 0) + 1
                labels[i] = f"{lab}-{seen[lab]}"
    return labels


def _grid(params: dict) -> list[dict]:
    """Cartesian product over list-valued parameters."""
    keys = list(params)
    vals = [v if isinstance(v, list) else [v] for v in params.values()]
    return [dict(zip(keys, combo)) for combo in itertools.product(*vals)]


def name_problem(name) -> str | None:
    """What is wrong with a run's ``name`` (a folder name under results/), or None."""
    if isinstance(name, str) and re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,99}", name) and ".." not in name:
        return None
    return f"expected letters, digits, '_', '-' or '.' (a folder name under results/), got {yaml_input.short(name)}"


def samples_problem(hs) -> str | None:
    """What is wrong with a ``hausdorff_samples`` value, or None."""
    if _is_int(hs) and 0 <= hs <= MAX_SAMPLES:
        return None
    return f"expected an integer in [0, {MAX_SAMPLES:,}], got {yaml_input.short(hs)}"


def eps_problem(eps) -> str | None:
    """What is wrong with a ``hausdorff_eps`` value, or None."""
    if _is_num(eps) and 1e-9 <= eps <= 1:
        return None
    return f"expected a relative gap in [1e-9, 1], got {yaml_input.short(eps)}"


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


def _noise_of(noises, task: str) -> list:
    """The noise list of ``task``: ``noises`` itself, or its entry when it maps tasks to lists."""
    return noises.get(task, []) if isinstance(noises, dict) else noises


def _count_cases(meshes: list, noises, tasks: dict) -> int:
    def per_mesh(nl):
        return sum(len(n.get("levels") or [0.0]) * (1 if n["model"] == "none" else n.get("seeds", 1)) for n in nl)
    return len(meshes) * sum(per_mesh(_noise_of(noises, task)) * len(grid)
                             for task, entries in tasks.items() for _, grid in entries)


def expand_cases(meshes: list, noises, tasks: dict, seed: int, repeats: int, plugins: tuple, hs: int,
                 budget: float, eps: float = 1e-3) -> list:
    """Every (mesh, noise model, level, seed, task, method, params) case, duplicates removed;
    ``noises`` is one list for every task or a mapping task -> list."""
    from .core.params import id_form
    cases = []
    ids: dict = {}                  # method -> how its case ids record its parameters (`method_id_spec`)
    labels = _unique_labels(meshes)
    for spec, key in zip(meshes, labels):
        ident = _identity(spec)
        spec = {**spec, **{k: v for k, v in ident.items() if k.endswith("_sha1")}}   # the bytes each case must read
        is_pair = "clean" in spec or datasets.resolve_bundled(spec.get("bundled", "")) in datasets.PAIRS
        given = ("given", float("nan"), seed, 1.0)          # one NaN object: tuples compare by identity first

        def noise_list(task):
            return [given] if is_pair else [
                (n["model"], float(lv), seed + s, float(n.get("fraction", 1.0)))
                for n in _noise_of(noises, task) for lv in (n.get("levels") or [0.0])
                for s in range(1 if n["model"] == "none" else n.get("seeds", 1))]
        lists = {task: noise_list(task) for task in tasks}
        for model, level, s, frac in dict.fromkeys(x for nl in lists.values() for x in nl):
            for task, entries in tasks.items():
                if (model, level, s, frac) not in lists[task]:
                    continue
                for mname, grid in entries:
                    if mname not in ids:
                        ids[mname] = method_id_spec(mname)
                    for params in grid:
                        cid = case_id(task, ident, model, level, s, frac, mname, id_form(params, ids[mname]))
                        cases.append(Case(cid, task, spec, key, model, level, s, frac, mname,
                                          params, repeats, plugins, hs, budget, hausdorff_eps=eps))
    seen = set()
    return [c for c in cases if not (c.case_id in seen or seen.add(c.case_id))]


def _numbered(listed, valid: list, base_dir: Path, key: str) -> dict:
    """``{index as listed: spec}`` of a mesh list's valid entries: ``valid`` (`_check_meshes`'s
    result) when every entry was, else each entry checked alone (their problems are listed
    already), so a message names an entry by its place in the config."""
    if not isinstance(listed, list):
        return {}
    if len(valid) == len(listed):
        return dict(enumerate(valid))
    return {i: alone[0] for i, e in enumerate(listed) if (alone := _check_meshes([e], base_dir, [], key))}


def _check_meshes(meshes, base_dir: Path, P: list, key: str = "meshes") -> list[dict]:
    """The mesh list at ``key`` (``meshes``, ``tune.train``): specs of the good entries, a problem
    in ``P`` for each bad one, named by its key path."""
    out, where = [], []
    if not isinstance(meshes, list) or not meshes:
        P.append(f"{key}: expected a non-empty list of meshes")
        return out
    marks = []                                   # (specs, problems) so far as each entry starts
    for i, m in enumerate(meshes):
        at = f"{key}[{i}]"
        marks.append((len(out), len(P)))
        if isinstance(m, str):
            if datasets.resolve_bundled(m):
                out.append({"bundled": datasets.resolve_bundled(m)})
                where.append(at)
            elif m in datasets.PROCEDURAL:
                out.append({"procedural": m, **datasets.PROCEDURAL[m]})
                where.append(at)
            else:
                opts = datasets.bundled_names() + list(datasets.PROCEDURAL)
                P.append(f"{at}: unknown mesh {yaml_input.short(m)}{_close(m, opts)}; see `shootout datasets`")
        elif isinstance(m, dict) and "procedural" in m:
            kind = m["procedural"]
            if not isinstance(kind, str) or kind not in datasets.PROCEDURAL:
                P.append(f"{at}.procedural: unknown procedural mesh {yaml_input.short(kind)}{_close(kind, datasets.PROCEDURAL)}; "
                         f"expected one of {sorted(datasets.PROCEDURAL)}")
                continue
            spec = {"procedural": kind}
            for k, v in m.items():
                if k == "procedural":
                    continue
                if k not in datasets.PROCEDURAL[kind]:
                    P.append(f"{at}.{k}: unknown parameter of {kind}{_close(k, datasets.PROCEDURAL[kind])}; "
                             f"expected {sorted(datasets.PROCEDURAL[kind])}")
                    continue
                lo, hi = datasets.PROCEDURAL_BOUNDS[k]
                want_int = _is_int(datasets.PROCEDURAL[kind][k])
                if not (_is_int(v) if want_int else _is_num(v)) or not lo <= v <= hi:
                    P.append(f"{at}.{k}: expected {'an integer' if want_int else 'a number'} in [{lo}, {hi}], got {yaml_input.short(v)}")
                    continue
                spec[k] = v if want_int else float(v)      # `radius: 1` is the default 1.0: one case id
            out.append({**{"procedural": kind}, **datasets.PROCEDURAL[kind], **spec})
            where.append(at)
        elif isinstance(m, dict) and "file" in m:
            extra = set(m) - {"file", "clean", "name", "level"}
            if extra:
                P.append(f"{at}: unknown key(s) {sorted(extra)}; a file mesh takes 'file' and optional "
                         "'clean', 'name', 'level'")
            spec = {}
            if "name" in m:
                nm = m["name"]
                if not isinstance(nm, str) or not re.fullmatch(r"[A-Za-z0-9_.\-]{1,80}", nm):
                    P.append(f"{at}.name: expected 1-80 letters, digits, '_', '-' or '.', got {yaml_input.short(nm)}")
                else:
                    spec["name"] = nm
            if "level" in m:
                lv = m["level"]
                if "clean" not in m:
                    P.append(f"{at}.level: the noise level of a given pair needs 'clean' (the noise-free mesh)")
                elif not _is_num(lv) or not 0 <= lv <= 1e6:
                    P.append(f"{at}.level: expected a number >= 0 (sigma / mean edge length), got {yaml_input.short(lv)}")
                else:
                    spec["level"] = float(lv)
            for k in ("file", "clean"):
                if k not in m:
                    continue
                f = m[k]
                if not isinstance(f, str):
                    P.append(f"{at}.{k}: expected a path string, got {yaml_input.short(f)}")
                    continue
                path = Path(f) if Path(f).is_absolute() else base_dir / f
                if not path.is_file() and Path(f).is_file():
                    path = Path(f).resolve()
                if path.is_dir():
                    P.append(f"{at}.{k}: {f} {missing_file_problem(path)}")
                    continue
                if not path.is_file():
                    if path.exists() or path.is_symlink():     # a pipe, a device, a dangling or looping link
                        why = missing_file_problem(path) if path.exists() else "is a symbolic link to nothing readable"
                        P.append(f"{at}.{k}: {f} {why}")
                    else:
                        P.append(f"{at}.{k}: file not found: {f} (relative paths are resolved against {base_dir})")
                    continue
                if path.suffix.lower() not in SUPPORTED:
                    P.append(f"{at}.{k}: unsupported extension {yaml_input.short(path.suffix)} of {f}; expected one of {list(SUPPORTED)}")
                    continue
                try:
                    with open(path, "rb") as fh:
                        fh.read(1)
                except OSError as exc:
                    P.append(f"{at}.{k}: cannot read {f}: {exc.strerror or exc}")
                    continue
                spec[k] = str(path.resolve())
            if "file" in spec and "clean" in spec:
                try:
                    datasets.cached(spec)
                except ShootoutError as exc:
                    P.append(f"{at}: {exc}")
                    continue
            if "file" in spec and ("clean" in spec or "clean" not in m):
                out.append(spec)
                where.append(at)
        else:
            P.append(f"{at}: expected a bundled name, {{procedural: ...}} or {{file: ...}}, got {yaml_input.short(m)}")
    marks.append((len(out), len(P)))
    ok = [j for (k0, p0), (k1, p1) in zip(marks, marks[1:]) if p1 == p0 for j in range(k0, k1)]
    # (an entry with a problem of its own may stand for another mesh than it reads as: not compared)
    P += _same_mesh_problems([out[j] for j in ok], [where[j] for j in ok])
    return out


def _same_mesh_key(spec: dict) -> dict:
    """What makes two mesh entries one mesh: `_identity`, where a bundled mesh (not a pair) is the
    file it reads, so that the same bytes given as a ``file:`` are the same mesh too."""
    if set(spec) <= {"bundled", "name"}:
        files = datasets._spec_files(spec)
        if len(files) == 1:
            try:
                return {"file_sha1": file_sha1(files[0])}
            except OSError:
                pass
    return _identity(spec)


def _same_mesh_problems(specs: list[dict], where: list[str]) -> list[str]:
    """One mesh listed twice (same spec, or files with the same bytes: its cases would run once,
    whatever its names), and a ``name:`` that another, different mesh also goes by (the ``mesh``
    column and the noise seed come from it; it would be changed silently to tell them apart)."""
    P, again = [], {}
    memo: dict[str, str] = {}                  # a long list repeats a few specs: each is keyed once

    def key(s: dict) -> str:
        raw = json.dumps(s, sort_keys=True, default=str)
        if raw not in memo:
            memo[raw] = json.dumps(_same_mesh_key(s), sort_keys=True, default=str)
        return memo[raw]
    ids = [key(s) for s in specs]
    for i, ident in enumerate(ids):
        again.setdefault(ident, []).append(i)
    for ident, at in again.items():
        if len(at) > 1:
            more = f" and {len(at) - 4} more" if len(at) > 4 else ""
            P.append(f"{', '.join(where[i] for i in at[1:4])}{more}: the same mesh as {where[at[0]]} (the same "
                     f"{'spec' if len({json.dumps(_identity(specs[i]), sort_keys=True, default=str) for i in at[:4]}) == 1 else 'file bytes'}"
                     "): list it once")
    base, final = [datasets.spec_key(s) for s in specs], _unique_labels(specs)
    for i, s in enumerate(specs):
        if "name" not in s or final[i] == s["name"]:
            continue                              # a name the run keeps as it is
        other = next((j for j in range(len(specs)) if j != i and ids[j] != ids[i] and s["name"] in (base[j], final[j])),
                     None)
        whose = f"the label of {where[other]}, another mesh" if other is not None else "another mesh's label"
        P.append(f"{where[i]}.name: {s['name']!r} is also {whose} (the run would call this one {final[i]!r}): give "
                 "each mesh a label of its own (it names the mesh column and seeds the noise)")
    return P


def _check_noise(noise, P: list, where: str = "noise") -> list[dict]:
    out = []
    if not isinstance(noise, list) or not noise:
        P.append(f"{where}: expected a non-empty list of {{model: ..., levels: [...]}}")
        return out
    for i, n in enumerate(noise):
        at = f"{where}[{i}]"
        if not isinstance(n, dict):
            P.append(f"{at}: expected a mapping like {{model: gaussian_normal, levels: [0.1]}}, got {yaml_input.short(n)}")
            continue
        _unknown_keys(n, NOISE_KEYS, f"{at}.", P)
        model = n.get("model")
        if model not in MODELS:
            P.append(f"{at}.model: expected one of {list(MODELS)}, got {yaml_input.short(model)}{_close(model, MODELS)}")
            continue
        entry = {"model": model}
        levels = n.get("levels")
        if model == "none":
            if levels not in (None, [], [0], [0.0]):
                P.append(f"{at}.levels: model none takes no levels, got {yaml_input.short(levels)}")
            entry["levels"] = [0.0]
        else:
            if not isinstance(levels, list) or not levels:
                P.append(f"{at}.levels: expected a non-empty list of numbers >= 0, got {yaml_input.short(levels)}")
            else:
                for j, lv in enumerate(levels):
                    if not _is_num(lv) or not 0 <= lv <= 100:
                        P.append(f"{at}.levels[{j}]: expected a number in [0, 100] (x mean edge length), got {yaml_input.short(lv)}")
                entry["levels"] = levels
        seeds = n.get("seeds", 1)
        if not _is_int(seeds) or not 1 <= seeds <= 1000:
            P.append(f"{at}.seeds: expected an integer in [1, 1000], got {yaml_input.short(seeds)}")
        elif model == "none" and seeds != 1:
            P.append(f"{at}.seeds: model none adds no noise, so every seed is the same input: drop seeds")
        entry["seeds"] = seeds if _is_int(seeds) else 1
        frac = n.get("fraction", 1.0)
        if "fraction" in n and model != "impulsive":
            P.append(f"{at}.fraction: only the impulsive model takes a fraction")
        if not _is_num(frac) or not 0 < frac <= 1:
            P.append(f"{at}.fraction: expected a number in (0, 1], got {yaml_input.short(frac)}")
        entry["fraction"] = frac
        out.append(entry)
    return out


def _check_tasks(tasks, P: list, skip_unknown: bool = False, noise: dict | None = None) -> dict:
    """``{task: [(method, [params, ...]), ...]}``; a task's own ``noise`` list (which replaces the
    top-level one for that task) goes into ``noise`` when given."""
    from .plugins import import_methods
    methods = import_methods()
    from .tasks import names
    TASKS = names()
    out = {}
    if not isinstance(tasks, dict) or not tasks:
        P.append(f"tasks: expected a mapping with one or more of {list(TASKS)}")
        return out
    for task, body in tasks.items():
        at = f"tasks.{task}"
        if task not in TASKS:
            from .tasks import BROKEN
            why = f" (harness/tasks/{task}.py is not loaded: {BROKEN[task]})" if task in BROKEN else ""
            P.append(f"{at}: unknown task{_close(task, TASKS)}; expected one of {list(TASKS)}{why}")
            continue
        if not isinstance(body, dict):
            P.append(f"{at}: expected a mapping with 'methods' (and optional 'params'), got {yaml_input.short(body)}")
            continue
        _unknown_keys(body, TASK_KEYS, f"{at}.", P)
        if "noise" in body:
            own_noise = _check_noise(body["noise"], P, f"{at}.noise")
            if noise is not None:
                noise[task] = own_noise
        shared = body.get("params")
        shared = {} if shared is None else shared
        if not isinstance(shared, dict):
            P.append(f"{at}.params: expected a mapping of parameter -> value or list, got {yaml_input.short(shared)}")
            shared = {}
        mlist = body.get("methods")
        if not isinstance(mlist, list) or not mlist:
            P.append(f"{at}.methods: expected a non-empty list of method names or {{name:, params:}}")
            continue
        entries = []
        for i, m in enumerate(mlist):
            mat = f"{at}.methods[{i}]"
            if isinstance(m, str):
                mname, own = m, {}
            elif isinstance(m, dict) and isinstance(m.get("name"), str):
                mname, own = m["name"], m.get("params")
                own = {} if own is None else own
                extra = set(m) - {"name", "params"}
                if extra:
                    P.append(f"{mat}: unknown key(s) {sorted(extra)}; expected 'name' and 'params'")
                if not isinstance(own, dict):
                    P.append(f"{mat}.params: expected a mapping, got {yaml_input.short(own)}")
                    own = {}
            else:
                P.append(f"{mat}: expected a method name or {{name: ..., params: ...}}, got {yaml_input.short(m)}")
                continue
            try:
                meth = methods.get(mname, task=task if task in TASKS else None)
            except KeyError as exc:
                prefix = str(mname).split(".", 1)[0]
                known = any(m.name.split(".", 1)[0] == prefix for m in methods.all_methods())
                if not skip_unknown or known:   # a failed plugin explains the methods of a prefix no module registered
                    P.append(f"{mat}: {exc.args[0]}; see `shootout methods`")
                continue
            if meth.task != task:
                P.append(f"{mat}: {mname} is a {meth.task} method, not {task}")
                continue
            own, both = meth.canonical(own)              # a library's own spelling under the shared name
            shared_m, both_s = meth.canonical(shared)
            params = {**shared_m, **own}
            n_before = len(P)
            P.extend(f"{mat}.params: {b}" for b in both)
            P.extend(f"{at}.params: {b}" for b in both_s if f"{at}.params: {b}" not in P)
            for k, v in params.items():
                src = f"{mat}.params.{k}" if k in own else f"{at}.params.{k}"
                values = v if isinstance(v, list) else [v]
                if isinstance(v, list) and not v:
                    P.append(f"{src}: empty list of values")
                said = set()                             # an unknown name is one problem, not one per value
                for val in values:
                    for prob in meth.param_problems({k: val}):
                        if prob not in said:
                            said.add(prob)
                            P.append(f"{src}: {prob}")
            size = math.prod(len(v) if isinstance(v, list) else 1 for v in params.values())
            if size > MAX_CASES:             # refused before the product is built in memory
                P.append(f"{mat}: its parameter lists expand to {size:,} settings, more than {MAX_CASES:,} cases")
                continue
            grid = list(_grid(params))
            bad = [(g, meth.setting_problem(g)) for g in grid] if len(P) == n_before else []
            bad = [(g, why) for g, why in bad if why]
            if bad:
                P.append(f"{mat}: {len(bad)} of its {len(grid)} setting(s) cannot run, e.g. "
                         f"{json.dumps(bad[0][0], sort_keys=True, default=str)}: {bad[0][1]}")
                continue
            entries.append((mname, [_resolved(meth, g) for g in grid]))
        out[task] = entries
    return out
