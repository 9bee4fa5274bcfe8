"""Reading a task CSV of a run folder: `load_csv` and the checks that refuse a damaged file.

A torn last line (a row cut short by a kill) is left out with a warning, said once per process;
any other damage (not UTF-8, NUL bytes, a row whose field count differs from the header's, a
number column holding text, a true/false column holding something else, an identity column
missing or holding what no run writes) is a `ShootoutError` naming the file, column and line.
"""
from __future__ import annotations

import csv
import io
import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from . import tasks
from .errors import ShootoutError
from .schema import STATUSES


def load_csv(path) -> pd.DataFrame:
    """Read a task CSV with true/false columns as booleans and ids as strings.

    Only an empty cell is missing (that is how rows are written): a mesh or file named
    ``nan``, ``NA`` or ``null`` keeps its name.
    """
    text = _checked_csv_text(Path(path))
    text_cols = ("case_id", "error", "params", "method", "mesh", "library", "task", "status", "noise_model", "file")
    df = pd.read_csv(io.StringIO(text), dtype={c: str for c in text_cols},      # a file '10.obj' is method "10"
                     keep_default_na=False, na_values=[""], true_values=["true"], false_values=["false"])
    if "error" in df:
        df["error"] = df["error"].fillna("")
    _check_numbers(Path(path), df)
    _check_identity(Path(path), df)
    _check_flags(Path(path), df)
    return df


IDENTITY_COLUMNS = ("case_id", "mesh", "noise_model", "noise_level", "seed", "method", "params", "status")


def _check_flags(path: Path, df: pd.DataFrame) -> None:
    """`ShootoutError` naming the first cell of a task's true/false column that holds something
    else than ``true``, ``false`` or nothing (the column would be read as text, and ``"false"``
    taken for true)."""
    try:
        spec = tasks.get(path.stem)
    except (KeyError, ValueError):
        return
    for c in (m.name for m in spec.metrics if m.kind == "bool"):
        if c not in df:
            continue
        vals = df[c]
        bad = vals.notna() & ~vals.map(lambda v: isinstance(v, (bool, np.bool_)))
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
            raise ShootoutError(f"{path}: damaged CSV: column {c} holds {str(vals.iloc[i])[:40]!r} on line {i + 2}, "
                                "expected true or false")


def _check_identity(path: Path, df: pd.DataFrame) -> None:
    """`ShootoutError` naming the first row whose ``params`` is not a JSON object, whose
    ``method`` is empty or whose ``status`` is not one a run writes: a hand-edited file the
    rankings would otherwise fail on deep in the report."""
    def not_object(v) -> bool:
        try:
            return not isinstance(json.loads(v), dict)
        except (TypeError, ValueError):
            return True
    checks = (("params", lambda v: isinstance(v, str) and not_object(v), "a JSON object ({} when a method has none)"),
              ("method", lambda v: not isinstance(v, str) or not v.strip(), "a method's name"),
              ("status", lambda v: v not in STATUSES, f"one of {', '.join(STATUSES)}"))
    missing = [c for c in IDENTITY_COLUMNS if c not in df]
    if missing and len(df.columns):
        raise ShootoutError(f"{path}: damaged CSV: no column(s) {', '.join(missing)}, which every row of a run has")
    for col, bad, want in checks:
        if col not in df:
            continue
        for i, v in enumerate(df[col].tolist()):
            if bad(v):
                shown = "" if not isinstance(v, str) and pd.isna(v) else str(v)[:40]
                raise ShootoutError(f"{path}: damaged CSV: column {col} holds {shown!r} on line {i + 2}, "
                                    f"expected {want}")


NUMERIC_COMMON = ("n_vertices", "n_faces", "noise_level", "seed", "time_s", "time_min_s", "time_max_s", "time_q1_s",
                  "time_q3_s", "time_cold_s", "repeats", "time_cpu_s", "others_cpu", "threads_busy", "method_mem_mb",
                  "peak_rss_mb")


def _check_numbers(path: Path, df: pd.DataFrame) -> None:
    """`ShootoutError` naming the first cell of a number column (the common timing and size
    columns, a task's float and int metrics) that holds something else: a hand-edited or
    foreign file, which would otherwise fail deep in the report. An infinity is a number (this
    version writes none; older ones did): `compare` orders it and prints ``inf``; the report's
    page shows it blank, as a missing value."""
    try:
        spec = tasks.get(path.stem)
    except (KeyError, ValueError):
        spec = None
    cols = list(NUMERIC_COMMON) + ([m.name for m in spec.metrics if m.kind in ("float", "int")] if spec else [])
    for c in cols:
        if c not in df:
            continue
        vals = df[c]
        num = pd.to_numeric(vals, errors="coerce")
        bad = num.isna() & vals.notna()
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
            raise ShootoutError(f"{path}: damaged CSV: column {c} holds {str(vals.iloc[i])[:40]!r} on line {i + 2}, "
                                "expected a number")


_TORN_SAID: set = set()         # (path, cut text) of torn last lines already said in this process


def _checked_csv_text(path: Path) -> str:
    """The CSV's text without a torn last line; `ShootoutError` naming what is damaged otherwise
    (not UTF-8 text, empty, or lines whose field count differs from the header's)."""
    try:
        text = path.read_bytes().decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ShootoutError(f"{path}: damaged CSV (byte {exc.start} is not UTF-8 text)") from None
    except OSError as exc:
        raise ShootoutError(f"{path}: cannot read ({exc.strerror})") from None
    if "\x00" in text:
        raise ShootoutError(f"{path}: damaged CSV (contains NUL bytes)")
    cut = text[text.rfind("\n") + 1:]
    text = text[:text.rfind("\n") + 1]         # a row cut short by a kill: not data (only "\n" ends a
    if cut and text and (str(path), cut) not in _TORN_SAID:    # line: a form feed in a message does not);
        _TORN_SAID.add((str(path), cut))                          # said once, not silent
        print(f"shootout: warning: {path}: its last line was cut short (a run stopped while writing it): left out "
              f"({cut[:40]!r}{'...' if len(cut) > 40 else ''})", file=sys.stderr)
    if not text:
        raise ShootoutError(f"{path}: empty CSV (no header)")
    try:
        rows = list(csv.reader(io.StringIO(text), strict=True))
    except csv.Error as exc:
        raise ShootoutError(f"{path}: damaged CSV ({exc})") from None
    n = len(rows[0])
    bad = [i + 1 for i, r in enumerate(rows) if len(r) != n]
    if bad:
        raise ShootoutError(f"{path}: damaged CSV: line(s) {', '.join(map(str, bad[:5]))} do not have the "
                            f"header's {n} fields")
    return text
