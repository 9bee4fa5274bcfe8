"""Timings of a run folder in pytest-benchmark's JSON layout, so its tooling can read them.

``pytest-benchmark compare FILE.json`` (and anything else that reads ``--benchmark-json``
output) understands the result: ``machine_info``, ``commit_info``, ``benchmarks`` (one entry per
case with status ok: ``group`` = task/mesh/noise, ``name`` = method[params], ``params``,
``extra_info`` with the case's metrics, ``stats``), ``datetime`` and ``version``.

Every statistic is computed from the case's stored samples (the ``times`` column, seconds), as
pytest-benchmark computes its own: mean, sample standard deviation, median, quartiles (its
methods, `_quartiles`), IQR, Tukey fences ``ld15iqr``/``hd15iqr`` (the most extreme samples within
1.5 IQR of the quartiles), outlier counts (``mean +- stddev`` and Tukey) and ``total``. Rows of
runs made before samples were stored (no ``times``) fall back to min/median/max, and
``extra_info.stats_note`` says so.
"""
from __future__ import annotations

import json
import math
import platform
from pathlib import Path

import numpy as np

from .leaderboard import params_text
from .results import RunFolder
from .schema import number, scalar

FORMAT_VERSION = "5.1.0"      # the pytest-benchmark JSON layout written here


def _f(v):
    x = number(v)
    return x if x is not None and math.isfinite(x) else None


def _samples(row: dict) -> list[float] | None:
    try:
        t = json.loads(row.get("times") or "null")
    except (TypeError, ValueError):
        return None
    if isinstance(t, list) and t and all(isinstance(x, (int, float)) and math.isfinite(x) for x in t):
        return [float(x) for x in t]
    return None


def stats_from_row(row: dict) -> dict | None:
    """pytest-benchmark ``stats`` from a row's samples (see the module docstring)."""
    med, lo, hi = _f(row.get("time_s")), _f(row.get("time_min_s")), _f(row.get("time_max_s"))
    if med is None:
        return None
    t = _samples(row)
    if t is None:                                       # an older run: min/median/max only
        lo = med if lo is None else lo
        hi = med if hi is None else hi
        t = [lo, med, hi] if lo != hi else [med]
    arr = np.asarray(t)
    n = len(t)
    mean = float(arr.mean())
    stddev = float(arr.std(ddof=1)) if n > 1 else 0.0
    q1, q3 = _quartiles(sorted(float(x) for x in t))
    iqr = q3 - q1
    lo_f, hi_f = q1 - 1.5 * iqr, q3 + 1.5 * iqr
    inside = arr[(arr >= lo_f) & (arr <= hi_f)]
    sd_out = int(((arr < mean - stddev) | (arr > mean + stddev)).sum()) if n > 1 else 0
    iqr_out = int(n - inside.size)
    return {"min": float(arr.min()), "max": float(arr.max()), "mean": mean, "stddev": stddev, "rounds": n,
            "median": float(np.median(arr)), "iqr": iqr, "q1": q1, "q3": q3, "iqr_outliers": iqr_out,
            "stddev_outliers": sd_out, "outliers": f"{sd_out};{iqr_out}",
            "ld15iqr": float(inside.min()) if inside.size else float(arr.min()),
            "hd15iqr": float(inside.max()) if inside.size else float(arr.max()),
            "ops": (1.0 / mean) if mean > 0 else 0.0, "total": float(arr.sum()), "iterations": 1}


def _quartiles(d: list) -> tuple[float, float]:
    """``(q1, q3)`` of sorted ``d`` as pytest-benchmark computes them (Wikipedia's quartile
    methods: for an odd count, method 3, a weighted mean of the two data around n/4 and 3n/4;
    for an even count, method 2 ... 1, the medians of the lower and upper halves)."""
    n = len(d)
    if n == 1:
        return d[0], d[0]
    if n % 2:
        m, r = n // 4, n % 4
        if r == 1:
            return 0.25 * d[m - 1] + 0.75 * d[m], 0.75 * d[3 * m] + 0.25 * d[3 * m + 1]
        return 0.75 * d[m] + 0.25 * d[m + 1], 0.25 * d[3 * m + 1] + 0.75 * d[3 * m + 2]
    return float(np.median(d[: n // 2])), float(np.median(d[n // 2:]))


def _machine_info(meta: dict) -> dict:
    m = meta.get("machine") or {}
    v = meta.get("versions") or {}
    return {"node": m.get("node", platform.node()), "processor": m.get("cpu", ""), "machine": m.get("machine", ""),
            "python_compiler": platform.python_compiler(), "python_implementation": platform.python_implementation(),
            "python_implementation_version": v.get("python", platform.python_version()),
            "python_version": v.get("python", platform.python_version()), "python_build": list(platform.python_build()),
            "release": m.get("release", ""), "system": m.get("system", ""),
            "cpu": {"brand_raw": m.get("cpu", ""), "count": m.get("cpu_count"), "hz_advertised_friendly":
                    f"{m['cpu_freq_mhz']} MHz" if m.get("cpu_freq_mhz") else None, "arch": m.get("machine", "")},
            "memory_gb": m.get("memory_gb"), "versions": v}


def commit_info(meta: dict) -> dict:
    return {"id": meta.get("git_commit") or "unversioned", "time": None, "author_time": None, "dirty": meta.get("git_dirty"),
            "project": "mesh-shootout", "branch": None}


def _noise(rec: dict) -> str:
    lvl = rec.get("noise_level")
    return (str(rec.get("noise_model")) if lvl is None or (isinstance(lvl, float) and math.isnan(lvl))
            else f"{rec.get('noise_model')}-{lvl:g}")


def build(run_dir) -> dict:
    """The pytest-benchmark document of a run folder."""
    folder = RunFolder(run_dir)
    meta = folder.read_run_json() or {}
    benchmarks = []
    for task, df in folder.frames().items():
        records = df.to_dict("records")
        seeds: dict = {}
        for rec in records:
            seeds.setdefault((rec.get("mesh"), _noise(rec)), set()).add(rec.get("seed"))
        for rec in records:
            if rec.get("status") != "ok":
                continue
            stats = stats_from_row(rec)
            if stats is None:
                continue
            try:
                params = json.loads(rec.get("params") or "{}")
            except json.JSONDecodeError:
                params = {}
            noise = _noise(rec)
            pstr = params_text(params if isinstance(params, dict) else {})
            name = f"{rec['method']}[{pstr}]" if pstr else str(rec["method"])
            if len(seeds[(rec.get("mesh"), noise)]) > 1:                 # several seeds: each its own name
                name += f"[seed={rec.get('seed')}]"
            group = f"{task}/{rec.get('mesh')}/{noise}"
            extra = {k: scalar(v) for k, v in rec.items()
                     if k not in ("params", "time_s", "time_min_s", "time_max_s", "time_q1_s", "time_q3_s", "times",
                                  "min_angle_hist", "error")}
            if _samples(rec) is None:
                extra["stats_note"] = ("this run stored no samples (older version): statistics are computed from "
                                       "min, median and max only")
            benchmarks.append({
                "group": group, "name": name, "fullname": f"{group}::{name}[seed={rec.get('seed')}]",
                "params": {k: scalar(v) for k, v in params.items()}, "param": pstr or None,
                "extra_info": extra,
                "options": {"disable_gc": False, "timer": "perf_counter", "min_rounds": int(rec.get("repeats") or 1),
                            "max_time": None, "min_time": None, "warmup": True},
                "stats": stats,
            })
    return {"machine_info": _machine_info(meta), "commit_info": commit_info(meta), "benchmarks": benchmarks,
            "datetime": meta.get("finished") or meta.get("started"), "version": FORMAT_VERSION}


def export_benchmark_json(run_dir, file) -> Path:
    """Write ``build(run_dir)`` to ``file``; return its path."""
    doc = build(run_dir)
    path = Path(file)
    if path.parent and not path.parent.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(doc, indent=2, default=str, allow_nan=False))
    return path
