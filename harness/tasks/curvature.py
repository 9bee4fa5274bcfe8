"""Task ``curvature``: discrete curvature estimators against the analytic curvature of procedural
surfaces.

Conventions (every adapter maps its library to them): per-vertex *pointwise* values (densities,
not integrated over a vertex area); ``K`` Gaussian curvature (1/length^2), ``H`` mean curvature
``(k1 + k2) / 2`` (1/length) with the sign of the mesh's orientation: ``H > 0`` on a sphere with
outward normals (``H n = -1/2 Laplace-Beltrami(x)``), ``k1 >= k2`` principal curvatures.

Ground truth (`analytic`) from the exact surface a procedural mesh samples
(`harness.tasks.base.CaseInput.shape`), evaluated at the clean vertex positions: sphere
``K = 1/r^2, H = 1/r``; torus (tube angle v) ``K = cos v / (r (R + r cos v))``,
``H = (R + 2 r cos v) / (2 r (R + r cos v))``; cylinder ``K = 0, H = 1/(2 r)``; ellipsoid
(``h = (x^2/a^4 + y^2/b^4 + z^2/c^4)^-1/2``) ``K = h^4 / (a^2 b^2 c^2)``,
``H = h^3 (a^2 + b^2 + c^2 - |x|^2) / (2 a^2 b^2 c^2)``; saddle ``z = a (x^2 - y^2)`` with upward
normals ``K = -4 a^2 / W^4``, ``H = 4 a^3 (x^2 - y^2) / W^3``, ``W^2 = 1 + 4 a^2 (x^2 + y^2)``;
planes 0; ``k1,2 = H +- sqrt(H^2 - K)``. Meshes from files have no analytic curvature: only
``gauss_bonnet_error`` is measured there.

Errors: for a quantity ``q`` with truth ``q*`` over the interior vertices, weighted by the
barycentric vertex areas ``A``: ``q_rel_l2 = ||q - q*||_A / ||q*||_A`` and ``q_max = max |q - q*| /
max |q*|``; where ``q*`` vanishes identically (K on a cylinder or plane) the denominators are
replaced by the bounding-box diagonal's scale (``1/diag^2`` for K, ``1/diag`` for the others), so
the column stays dimensionless. ``q_boundary_max``: the same max over boundary vertices (open
meshes). ``gauss_bonnet_error``: ``|sum_i K_i A_i - 2 pi chi| / (2 pi max(|chi|, 1))`` on closed
meshes, the method's total curvature: ``A_i`` the areas it divided by where it returns them
(``area``), else the barycentric areas above. By the discrete Gauss-Bonnet theorem an angle
defect meets it to rounding (1e-13) with its own areas. ``gauss_bonnet_error_barycentric``: the
same with the barycentric areas for every method, so the same K scores the same whether or not
its method returns its areas (MeshLab's angle defect returns none: 0.12 on bunny in the first
column, equal to ours in this one); an angle defect over Voronoi areas misses it (2.6 on knight,
whose obtuse triangles make the two areas differ). Both are consistency checks, not accuracy
measures, and rank nothing (``info``): the exact K of the smooth surface misses them too (the
mesh's area is not the surface's: 0.019 on a subdivision-2 unit icosphere).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import MethodFailed
from .base import Metric, Task, float_array

QUANTITIES = ("K", "H", "k1", "k2")


@dataclass
class CurvatureResult:
    """Per-vertex curvatures (n,) float64 in the task's conventions; None for a quantity the method
    does not estimate. ``area``: the vertex areas (n,) the densities were divided by, if any."""

    K: np.ndarray | None = None
    H: np.ndarray | None = None
    k1: np.ndarray | None = None
    k2: np.ndarray | None = None
    area: np.ndarray | None = None


def _check(result: CurvatureResult, V, F):
    n = V.shape[0]
    if all(getattr(result, q) is None for q in QUANTITIES):
        raise MethodFailed("returned no curvature (K, H, k1 and k2 all None)")
    for q in QUANTITIES + ("area",):
        X = getattr(result, q)
        if X is None:
            continue
        X = float_array("", q, X, (n,))
        if not np.isfinite(X).all():
            raise MethodFailed(f"returned {q} with {int((~np.isfinite(X)).sum())} non-finite value(s)")
        setattr(result, q, X)
    return result


# ----------------------------------------------------------------------------- ground truth

def analytic(shape: dict | None, P: np.ndarray) -> dict | None:
    """``{K, H, k1, k2}`` (n,) at points ``P`` of the exact surface ``shape``; None if unknown."""
    if not shape:
        return None
    kind = shape.get("procedural")
    x, y, z = P[:, 0], P[:, 1], P[:, 2]
    if kind in ("sphere", "sphere_random"):
        r = float(shape.get("radius", 1.0))
        K, H = np.full(len(P), 1 / r ** 2), np.full(len(P), 1 / r)
    elif kind == "torus":
        R, r = float(shape["R"]), float(shape["r"])
        rho = np.hypot(x, y)
        cosv = np.clip((rho - R) / r, -1.0, 1.0)
        K = cosv / (r * (R + r * cosv))
        H = (R + 2 * r * cosv) / (2 * r * (R + r * cosv))
    elif kind == "cylinder":
        r = float(shape["radius"])
        K, H = np.zeros(len(P)), np.full(len(P), 1 / (2 * r))
    elif kind == "ellipsoid":
        a, b, c = float(shape["rx"]), float(shape["ry"]), float(shape["rz"])
        h = (x ** 2 / a ** 4 + y ** 2 / b ** 4 + z ** 2 / c ** 4) ** -0.5
        K = h ** 4 / (a * b * c) ** 2
        H = h ** 3 * (a * a + b * b + c * c - (x * x + y * y + z * z)) / (2 * (a * b * c) ** 2)
    elif kind == "saddle":
        a = float(shape["a"])
        W2 = 1 + 4 * a * a * (x * x + y * y)
        K = -4 * a * a / W2 ** 2
        H = 4 * a ** 3 * (x * x - y * y) / W2 ** 1.5
    elif kind in ("plane_delaunay", "plane_nondelaunay", "plane_skinny"):
        K, H = np.zeros(len(P)), np.zeros(len(P))
    else:
        return None
    disc = np.sqrt(np.maximum(H * H - K, 0.0))
    return {"K": K, "H": H, "k1": H + disc, "k2": H - disc}


def _facts(inp) -> dict:
    """Per-input facts: barycentric areas, boundary mask, Euler characteristic, closedness, truth."""
    if "curvature" not in inp.cache:
        from ..core.geometry import boundary_vertices, double_areas
        from ..mesh import topology
        V, F = inp.clean.V, inp.F
        A = np.bincount(F.ravel(), weights=np.repeat(double_areas(inp.V, F) / 6.0, 3), minlength=len(inp.V))
        topo = topology(V, F)
        from ..core.geometry import mean_edge_length
        inp.cache["curvature"] = {"A": A, "boundary": boundary_vertices(F, len(V)), "h": mean_edge_length(V, F),
                                  "chi": topo["euler"], "closed": topo["boundary_edges"] == 0,
                                  "truth": analytic(inp.shape, V)}
    return inp.cache["curvature"]


def measure(inp, result, params) -> dict:
    f = _facts(inp)
    A, bnd, truth = f["A"], f["boundary"], f["truth"]
    row: dict = {"mean_edge_length": float(f["h"])}
    for q in QUANTITIES:
        row[f"provides_{q}"] = getattr(result, q) is not None
    if truth is not None:
        for q in QUANTITIES:
            est = getattr(result, q)
            if est is None:
                continue
            err, ref = est - truth[q], truth[q]
            scale = inp.diag ** (2 if q == "K" else 1)
            inner = ~bnd
            ref_l2 = np.sqrt((A[inner] * ref[inner] ** 2).sum())
            if ref_l2 <= 1e-12 * np.sqrt(A[inner].sum()) / scale:      # q* == 0: dimensionless by the diagonal
                l2_den, max_den = np.sqrt(A[inner].sum()) / scale, 1.0 / scale
            else:
                l2_den, max_den = ref_l2, np.abs(ref[inner]).max()
            if inner.any():
                row[f"{q}_rel_l2"] = float(np.sqrt((A[inner] * err[inner] ** 2).sum()) / l2_den)
                row[f"{q}_max"] = float(np.abs(err[inner]).max() / max_den)
            if bnd.any():
                row[f"{q}_boundary_max"] = float(np.abs(err[bnd]).max() / max_den)
    if result.K is not None and f["closed"]:
        chi = f["chi"]
        gb = lambda areas: float(abs((result.K * areas).sum() - 2 * np.pi * chi) / (2 * np.pi * max(abs(chi), 1)))  # noqa: E731
        row["gauss_bonnet_error"] = gb(A if result.area is None else result.area)
        row["gauss_bonnet_error_barycentric"] = gb(A)
    return row


def view(inp, result) -> list:
    """The result coloured by the quantity of the view metric (H, ``H_rel_l2``) when it provides
    it, else by its first provided one, and, with ground truth, by its error."""
    f = _facts(inp)
    q = next(q for q in ("H",) + QUANTITIES if getattr(result, q) is not None)
    est = getattr(result, q)
    meshes = [("estimate", inp.V, inp.F, est, f"{q} estimated", {"signed": True})]
    if f["truth"] is not None:
        meshes.append(("error", inp.V, inp.F, np.abs(est - f["truth"][q]), f"|{q} - exact {q}|"))
    return meshes


def output_mesh(inp, result):
    q = next(q for q in QUANTITIES if getattr(result, q) is not None)
    return inp.V, inp.F, getattr(result, q), f"quality = estimated {q} per vertex (task curvature conventions)"


def _sphere_signs(method, V, F):
    """On a unit icosphere every provided quantity has the sign and scale of its value on the sphere
    (K 1, H 1, k1 = k2 = 1; median within a factor 2: a flipped sign, a missing 1/2 or an
    integrated instead of a pointwise value fails)."""
    from ..datasets import icosphere
    Vs, Fs = icosphere(4, 1.0)
    r = method(Vs, Fs)
    for q in QUANTITIES:
        x = getattr(r, q)
        if x is not None:
            med = float(np.median(x))
            assert 0.5 < med < 2.0, f"median {q} on the unit sphere is {med:g}, expected ~1"


_E = dict(rel=0.01, abs=1e-9)
_METRICS = []
for _q, _what in (("K", "Gaussian curvature"), ("H", "mean curvature"), ("k1", "larger principal curvature"),
                  ("k2", "smaller principal curvature")):
    _METRICS += [
        Metric(f"{_q}_rel_l2", "lower", f"{_what}: area-weighted relative L2 error, interior vertices", rank=_q in ("K", "H"), **_E),
        Metric(f"{_q}_max", "lower", f"{_what}: max error over max |exact|, interior vertices", **_E),
        Metric(f"{_q}_boundary_max", "lower", f"{_what}: max error over max |exact|, boundary vertices", **_E)]
_METRICS += [Metric("gauss_bonnet_error", "info", "|sum K A - 2 pi chi| / (2 pi max(|chi|, 1)), closed meshes, A the "
                    "areas the method divided by (barycentric where it returns none): its total curvature; a "
                    "consistency check, not accuracy (an angle defect meets it by construction; the exact K does not)",
                    **_E),
             Metric("gauss_bonnet_error_barycentric", "info", "gauss_bonnet_error with the barycentric areas for every "
                    "method: the same K scores the same whether or not its method returns its areas", **_E)]
_METRICS += [Metric(f"provides_{q}", "info", f"the method estimates {q}", kind="bool") for q in QUANTITIES]
_METRICS += [Metric("mean_edge_length", "input", "mean edge length of the clean input (input units): the resolution "
                    "the report's convergence panels fit each error's observed order against", **_E)]

TASK = Task(
    name="curvature", title="Curvature", result_type=CurvatureResult,
    intro="Discrete curvature estimators against the analytic curvature of procedural surfaces "
          "(pointwise values; H > 0 on a sphere with outward normals; errors relative to the exact values).",
    metrics=tuple(_METRICS), measure=measure, check_result=_check, view=view, view_metric="H_rel_l2",
    output_mesh=output_mesh, order=40, checks=(("sphere_signs", _sphere_signs),), input_facts=("curvature",))
