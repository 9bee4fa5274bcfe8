"""How every output names a variant, a case's parameters, a noise cell and a cell's setting: a
variant is its method plus the parameters that vary between the method's rows or are set away
from its default (`label_keys`, `label_text`, `variant_labels`), values as JSON or bare text
that cannot be read as anything else (`label_value`), so two settings never share a label.
"""
from __future__ import annotations

import json
import math
import re


def label_keys(methods, params, axis=(), defaults=None) -> dict[str, list[str]]:
    """Per method, the parameters its variants' labels name: those (other than axis parameters)
    that vary between its rows, and those set away from the method's default (``defaults``:
    ``{method: {param: default}}`` as run.json's task declaration records it), so a label without
    a parameter means that parameter's default."""
    def key(v):
        return json.dumps(v, sort_keys=True, default=str)
    seen: dict[str, dict[str, set]] = {}
    for m, p in zip(methods, params):
        for k, v in p.items():
            if k not in axis:
                seen.setdefault(m, {}).setdefault(k, set()).add(key(v))
    defaults = defaults if isinstance(defaults, dict) else {}
    out = {}
    for m, ks in seen.items():
        d = defaults.get(m) if isinstance(defaults.get(m), dict) else {}
        out[m] = sorted(k for k, vals in ks.items() if len(vals) > 1 or (k in d and vals != {key(d[k])}))
    return out


def label_value(v) -> str:
    """A parameter value in a label: JSON (``true``, ``null``, ``0.25``) as a config writes it;
    text bare where it cannot be read as anything else (``scipy``), quoted where it could
    (``"null"``, ``"3"``, one with a space, ``=`` or quote), so two settings never share a label."""
    if isinstance(v, str):
        bare = v and re.fullmatch(r"[A-Za-z_][A-Za-z0-9_.:/+-]*", v) and v not in ("true", "false", "null", "NaN", "Infinity")
        return v if bare else json.dumps(v)
    return json.dumps(v, sort_keys=True, default=str)


def label_text(method: str, params: dict, keys) -> str:
    """A variant's label: ``method k=v ...`` for the ``keys`` (`label_keys`), values by
    `label_value`. The report, the leaderboard and the winners all label variants this way."""
    return method + "".join(f" {k}={label_value(params.get(k))}" for k in keys)


def params_text(params: dict) -> str:
    """A case's parameters as ``k=v,k=v`` (sorted keys, values by `label_value`, unset ones
    left out): how `shootout compare` and the benchmark JSON name a case's setting."""
    return ",".join(f"{k}={label_value(params[k])}" for k in sorted(params) if params[k] is not None)


def params_of(s) -> dict:
    """A row's ``params`` JSON as a dict ({} when it is blank or not a JSON object)."""
    try:
        p = json.loads(s) if isinstance(s, str) and s else {}
        return p if isinstance(p, dict) else {}
    except json.JSONDecodeError:
        return {}


def variant_labels(df, axis_params=frozenset(), defaults=None) -> list[str]:
    """Method name plus the parameters `label_keys` names: those that vary between this method's
    rows and those set away from its default (axis params excluded); `label_text` writes them.
    The report, the leaderboard and the winners label rows with this one function."""
    ps = [params_of(s) for s in df["params"]] if "params" in df else [{} for _ in range(len(df))]
    ps = _external_files_left_out(df, ps)
    keys = label_keys(df["method"], ps, set(axis_params), defaults)
    return [label_text(m, p, keys.get(m, ())) for m, p in zip(df["method"], ps)]


def _external_files_left_out(df, ps: list[dict]) -> list[dict]:
    """``ps`` with the ``file`` of each scored result (`shootout eval`: library ``external``,
    params ``{"file": path}``) left out where its label names one file per mesh: the file is
    where a result came from, not a setting, so one label over several meshes is one variant
    (ranked across them). A label with two files on one mesh keeps them in its labels."""
    if "library" not in df or "mesh" not in df:
        return ps
    ext = [lib == "external" for lib in df["library"]]
    files: dict = {}
    for e, m, mesh, p in zip(ext, df["method"], df["mesh"], ps):
        if e:
            files.setdefault(m, {}).setdefault(str(mesh), set()).add(json.dumps(p.get("file")))
    one = {m for m, by_mesh in files.items() if all(len(f) == 1 for f in by_mesh.values())}
    return [{k: v for k, v in p.items() if k != "file"} if e and m in one else p
            for e, m, p in zip(ext, df["method"], ps)]


def noise_label(model, level) -> str:
    """A noise cell's label, as every output prints it: ``no noise``, ``gaussian_normal 0.3``."""
    if model in (None, "none") or (isinstance(model, float) and math.isnan(model)):
        return "no noise"
    if level is None or (isinstance(level, float) and math.isnan(level)):
        return str(model)
    try:
        return f"{model} {float(level):g}"
    except (TypeError, ValueError):
        return f"{model} {level}"


def setting_text(setting) -> str:
    """A cell's setting (the axis parameters as JSON) as ``k=v`` pairs (`params_text`), unset ones
    left out: ``target_ratio=0.1``, not ``{"target_faces": null, "target_ratio": 0.1}``."""
    try:
        d = json.loads(setting) if isinstance(setting, str) and setting else {}
    except json.JSONDecodeError:
        return str(setting)
    return params_text(d) if isinstance(d, dict) else str(setting)
