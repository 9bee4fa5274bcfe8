"""Convergence under refinement for the report: a task that declares a ``mean_edge_length``
column (the input's resolution, e.g. curvature) gets, per lower-is-better metric, each variant's
error against the mean edge length ``h`` over the meshes of one family (the same procedural
surface at several resolutions: the mesh label without ``subdivisions``, ``resolution`` or
``n_points``), and the observed order: the least-squares slope of ``log error`` against
``log h`` (error ~ C h^p), from three resolutions or more with an error above the metric's
compare tolerance ``abs`` (an error at or below it is rounding: an exact method's angle defects
on a cylinder, 4e-14 to 3e-12, grow as 1/h^2 and would fit as divergence). Errors are means over
seeds of the valid ok rows (`harness.leaderboard.validity`)."""
from __future__ import annotations

import re

import numpy as np
import pandas as pd

H = "mean_edge_length"
RESOLUTION = ("subdivisions", "resolution", "n_points")
_PARAM = re.compile(r"(?:^|,)\s*(?:" + "|".join(RESOLUTION) + r")=[^,()]*")


def family(mesh: str) -> str:
    """The mesh label without its resolution parameters: ``torus(r=0.3,resolution=16)`` ->
    ``torus(r=0.3)``, ``sphere(subdivisions=2)`` -> ``sphere``."""
    m = re.fullmatch(r"([^()]*)\((.*)\)", str(mesh))
    if not m:
        return str(mesh)
    rest = _PARAM.sub("", m.group(2)).strip(", ")
    return m.group(1) + (f"({rest})" if rest else "")


def observed_order(h, err, floor: float = 0.0) -> float | None:
    """Slope of ``log err`` against ``log h`` (least squares) over the points with ``h > 0`` and
    ``err > floor`` (``floor`` >= 0: the level below which an error is rounding); None for fewer
    than 3 such points, or a single resolution."""
    h, err = np.asarray(h, dtype=np.float64), np.asarray(err, dtype=np.float64)
    ok = (h > 0) & (err > max(float(floor), 0.0)) & np.isfinite(h) & np.isfinite(err)
    if ok.sum() < 3 or np.ptp(np.log(h[ok])) == 0:
        return None
    return float(np.polyfit(np.log(h[ok]), np.log(err[ok]), 1)[0])


def convergence(spec: dict, df: pd.DataFrame, variants, invalid) -> list[dict]:
    """Records ``{metric, family, noise, variant, points: [[h, err], ...], order, floor,
    at_floor}`` (points by ascending ``h``; ``floor`` the metric's ``abs`` tolerance, ``at_floor``
    how many points are at or below it, left out of the order) for every lower-is-better metric
    of ``spec`` with values; ``variants`` and ``invalid`` the rows' variant labels and validity
    reasons (empty: valid)."""
    if H not in df or not len(df):
        return []
    from .common import noise_label
    d = df.assign(_variant=list(variants), _bad=[bool(x) for x in invalid],
                  _family=[family(m) for m in df["mesh"]],
                  _noise=[noise_label(m, lv) for m, lv in zip(df["noise_model"], df["noise_level"])],
                  _h=pd.to_numeric(df[H], errors="coerce"))
    d = d[(d["status"] == "ok") & ~d["_bad"] & d["_h"].notna()]
    out = []
    for m in spec.get("metrics", []):
        name = m.get("name")
        if m.get("better") != "lower" or name not in d:
            continue
        try:
            floor = float(m.get("abs") or 0.0)
        except (TypeError, ValueError):
            floor = 0.0
        floor = floor if np.isfinite(floor) and floor > 0 else 0.0      # a hand-edited run.json: no floor
        v = d.assign(_y=pd.to_numeric(d[name], errors="coerce"))
        v = v[np.isfinite(v["_y"]) & np.isfinite(v["_h"])]     # an inf in a hand-edited CSV: no point
        for (fam, noise, var), g in v.groupby(["_family", "_noise", "_variant"], sort=True):
            pts = g.groupby("mesh").agg(h=("_h", "first"), y=("_y", "mean")).sort_values("h")
            if len(pts) < 2:
                continue
            out.append({"metric": name, "family": fam, "noise": noise, "variant": var,
                        "points": [[float(a), float(b)] for a, b in zip(pts["h"], pts["y"])],
                        "order": observed_order(pts["h"], pts["y"], floor), "floor": floor,
                        "at_floor": int((pts["y"] <= floor).sum())})
    return out
