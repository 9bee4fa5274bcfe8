"""Validation of a config's noise lists and ``tasks`` section: noise models, levels, seeds and
fractions; each task's methods and their parameters (canonical names, bounds, list-valued
parameters expanded as a Cartesian grid, settings a method refuses), with declared defaults
filled in. Each function appends its problems, named by key path, to the caller's list."""
from __future__ import annotations

import itertools
import json
import math

from . import yaml_input
from .config_values import MAX_CASES, NOISE_KEYS, TASK_KEYS, _close, _is_int, _is_num, _unknown_keys
from .noise import MODELS


def _resolved(meth, params: dict) -> dict:
    """Declared defaults filled in, floats as floats: equal settings give equal case ids."""
    return meth.with_defaults(params)


def _grid(params: dict) -> list[dict]:
    """Cartesian product over list-valued parameters."""
    keys = list(params)
    vals = [v if isinstance(v, list) else [v] for v in params.values()]
    return [dict(zip(keys, combo)) for combo in itertools.product(*vals)]


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
