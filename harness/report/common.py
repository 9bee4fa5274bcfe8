"""Helpers shared by the report's sections: escaping, the one number formatter, variant labels."""
from __future__ import annotations

import html
import json
import math
import re

import numpy as np

from ..schema import fmt  # noqa: F401  (the report's formatter is the project's)


def esc(x) -> str:
    return html.escape("" if x is None else str(x))


def params_of(s) -> dict:
    try:
        p = json.loads(s) if isinstance(s, str) and s else {}
        return p if isinstance(p, dict) else {}
    except json.JSONDecodeError:
        return {}


def short(v) -> str:
    return json.dumps(v) if isinstance(v, (dict, list)) else str(v)


def variant_labels(df, axis_params=frozenset(), defaults=None) -> list[str]:
    """Method name plus the parameters `harness.leaderboard.label_keys` names: those that vary
    between this method's rows and those set away from its default (axis params excluded)."""
    from ..leaderboard import label_keys, label_text
    ps = [params_of(s) for s in df["params"]] if "params" in df else [{} for _ in range(len(df))]
    keys = label_keys(df["method"], ps, set(axis_params), defaults)
    return [label_text(m, p, keys.get(m, ())) for m, p in zip(df["method"], ps)]


def natural_key(s: str):
    """Sort key that orders "iterations=5" before "iterations=20"."""
    return [(0, float(t), "") if re.fullmatch(r"\d+(\.\d+)?", t) else (1, 0.0, t) for t in re.split(r"(\d+(?:\.\d+)?)", s)]


def noise_label(model, level) -> str:
    if model in (None, "none") or (isinstance(model, float) and math.isnan(model)):
        return "no noise"
    if level is None or (isinstance(level, float) and math.isnan(level)):
        return str(model)
    return f"{model} {level:g}"


