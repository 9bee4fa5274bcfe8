"""The columns of a task CSV and the one function that turns a value into a CSV/JSON scalar.

A row is a flat dict: the common columns below, then the task's metric columns in the order
its `harness.tasks` declaration gives them.
"""
from __future__ import annotations

import math

import numpy as np

from . import tasks

COMMON_COLUMNS = ["case_id", "task", "mesh", "n_vertices", "n_faces", "noise_model", "noise_level", "seed",
                  "method", "library", "params", "status", "error", "time_s", "time_min_s", "time_max_s",
                  "time_q1_s", "time_q3_s", "time_cold_s", "repeats", "times", "time_cpu_s", "cpu_times", "others_cpu",
                  "method_mem_mb", "peak_rss_mb"]
STATUSES = ("ok", "error", "timeout", "unavailable")


def columns(task: str) -> list[str]:
    """Every column of ``task``'s CSV, in order."""
    return COMMON_COLUMNS + tasks.get(task).columns


def task_file(task: str) -> str:
    return f"{task}.csv"


def scalar(v):
    """A JSON-ready scalar: None for missing or non-finite numbers, Python bool/int/float for
    numpy and Python numbers, ``str(v)`` for anything else."""
    if v is None:
        return None
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        f = float(v)
        return f if math.isfinite(f) else None
    return str(v)


def cell(v) -> str | int | float:
    """A CSV cell: empty for missing, ``true``/``false`` for flags, numbers as they are."""
    v = scalar(v)
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    return v


def number(v) -> float | None:
    """``v`` as a float (booleans as 0/1), or None when it is not a number."""
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def fmt(v, digits: int = 3) -> str:
    """The one number formatter of reports and listings: ``—`` for missing, ``true``/``false``,
    integers as they are, ``digits`` significant digits in [1e-3, 1e5), scientific outside."""
    v = scalar(v) if not isinstance(v, str) else v
    if v is None or v == "":
        return "—"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    x = number(v)
    if x is None:
        return str(v)
    if not math.isfinite(x):
        return "—"
    if x == 0:
        return "0"
    if 1e-3 <= abs(x) < 1e5:
        return f"{x:.{digits}g}"
    return f"{x:.{max(digits - 1, 1)}e}"
