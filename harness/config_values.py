"""The config's vocabulary and limits (its top-level, task, report and noise keys; the bounds on
repeats, Hausdorff samples and cases) and the small checks its validators share: unknown keys
with close matches, integer and number tests, and the ``*_problem`` checks of a run's name and
Hausdorff settings (also used by `harness.scoring`), each returning what is wrong, or None."""
from __future__ import annotations

import difflib
import re

from . import yaml_input

TOP_KEYS = {"name", "repeats", "save_meshes", "plugins", "seed", "meshes", "noise", "tasks",
            "timeout", "report", "hausdorff_samples", "hausdorff_eps", "time_budget", "tune"}
TASK_KEYS = {"methods", "params", "noise"}
REPORT_KEYS = {"views"}
MAX_REPEATS = 1000               # minimum timed samples per case
MAX_SAMPLES = 10_000_000         # Hausdorff area samples per side
MAX_CASES = 100_000              # cases in one config (the grid is expanded in memory)
NOISE_KEYS = {"model", "levels", "seeds", "fraction"}


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
