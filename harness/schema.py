"""The columns of a task CSV and the one function that turns a value into a CSV/JSON scalar.

A row is a flat dict: the common columns (`COMMON_COLUMNS`, declared with the task contract),
then the task's metric columns in the order its `harness.tasks` declaration gives them.
"""
from __future__ import annotations

import math

import numpy as np

from . import tasks
from .tasks.base import COMMON_COLUMNS  # noqa: F401 - the common columns live with the task contract

STATUSES = ("ok", "error", "timeout", "unavailable")


def columns(task: str) -> list[str]:
    """Every column of ``task``'s CSV, in order."""
    return COMMON_COLUMNS + tasks.get(task).columns


def task_file(task: str) -> str:
    return f"{task}.csv"


def text(v) -> str:
    """``str(v)`` that any UTF-8 file can hold: NUL and lone surrogates (a path decoded with
    ``surrogateescape``, say) as backslash escapes, everything else unchanged."""
    s = str(v)
    if "\x00" in s:
        s = s.replace("\x00", "\\x00")
    try:
        s.encode("utf-8")
    except UnicodeEncodeError:
        s = s.encode("utf-8", "backslashreplace").decode("utf-8")
    return s


def scalar(v):
    """A JSON-ready scalar: None for missing or non-finite numbers, Python bool/int/float for
    numpy and Python numbers, `text` of anything else."""
    if v is None:
        return None
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        f = float(v)
        return f if math.isfinite(f) else None
    return text(v)


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
    """The one number formatter of reports and listings: ``—`` for missing (NaN too), ``inf``,
    ``true``/``false``, integers as they are, ``digits`` significant digits in [1e-3, 1e5), scientific outside."""
    inf = None if isinstance(v, (bool, np.bool_)) else number(v)
    if inf is not None and math.isinf(inf):           # a number or its text; not missing: an older version wrote it
        return "inf" if inf > 0 else "-inf"
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
    if not math.isfinite(x):                          # NaN (an infinity was said above)
        return "—"
    if x == 0:
        return "0"
    if 1e-3 <= abs(x) < 1e5:
        return f"{x:.{digits}g}"
    return f"{x:.{max(digits - 1, 1)}e}"
