"""What `run` refuses, each problem one message, before it writes anything: its arguments
(`run_args_problems`, which also checks the CLI's flags), its config argument as a kind of
thing, a ``results:`` config's problems, and a run folder it may not write into or resume
(`folder_problems`): another program's files, a damaged or missing run.json, a changed config
(`config_hash`: the key of what the rows depend on), task CSVs of another version's columns,
meshes relabelled since their rows were written, and saved meshes that no longer parse."""
from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

from . import tasks
from .config import Config
from .executors import EXECUTORS
from .results import RunFolder


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
