"""Helpers shared by the report's sections: escaping, the one number formatter, variant labels."""
from __future__ import annotations

import html
import json
import re

from ..leaderboard import noise_label, params_of, variant_labels  # noqa: F401  (one labelling for every reader)
from ..schema import fmt  # noqa: F401  (the report's formatter is the project's)

__all__ = ["esc", "fmt", "natural_key", "noise_label", "params_of", "short", "variant_labels"]


def esc(x) -> str:
    return html.escape("" if x is None else str(x))


def short(v) -> str:
    return json.dumps(v) if isinstance(v, (dict, list)) else str(v)


def natural_key(s: str):
    """Sort key that orders "iterations=5" before "iterations=20"."""
    return [(0, float(t), "") if re.fullmatch(r"\d+(\.\d+)?", t) else (1, 0.0, t) for t in re.split(r"(\d+(?:\.\d+)?)", s)]


