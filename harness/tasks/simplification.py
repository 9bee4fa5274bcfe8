"""Task ``simplification``: a mesh with fewer faces approximating the input surface, measured
against the input (the noisy positions when noise is applied). Lengths are fractions of the
clean mesh's bounding-box diagonal."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.geometry import compact, zero_area_faces
from ..core.params import Param
from ..errors import MethodFailed
from ..metrics.hausdorff import hausdorff
from ..metrics.surface_distance import cached_surface, point_surface_distance
from ..metrics.triangle_quality import triangle_quality, warm as _warm_metrics
from .base import Invalid, Metric, Task, float_array, target_tolerance


@dataclass
class SimplificationResult:
    """Simplified mesh: ``V`` (k, 3) float64, ``F`` (l, 3) integer indices into ``V``. Every
    built-in adapter returns it compact from its timed call (every vertex used), as the libraries
    do in theirs; one that keeps unused vertices (e.g. the input's, as meshoptimizer does) is
    compacted by the task's untimed validation (`harness.core.geometry.compact`) so the output is
    measured and saved compact, but its time then leaves that out: compact in the adapter."""

    V: np.ndarray
    F: np.ndarray


PARAMS = {
    "target_ratio": Param("target_ratio", 0.5, "float", low=1e-6, high=1.0,
                          doc="fraction of input faces to keep (ignored when target_faces is set)"),
    "target_faces": Param("target_faces", None, "int", low=1, optional=True,
                          doc="number of faces to keep; overrides target_ratio"),
}


def target_face_count(n_faces: int, target_ratio: float | None, target_faces: int | None) -> int:
    """Faces asked for: ``target_faces`` if given, else ``round(target_ratio * n_faces)``, in
    ``[1, n_faces]`` (a target above the input's face count asks for the input)."""
    if target_faces is not None:
        return max(1, min(int(target_faces), int(n_faces)))
    return max(1, min(int(round(float(target_ratio) * n_faces)), int(n_faces)))



def prepare(params: dict, V, F) -> dict:
    """The adapter receives one integer ``target_faces`` in place of the two shared parameters."""
    p = dict(params)
    p["target_faces"] = target_face_count(F.shape[0], p.pop("target_ratio"), p.pop("target_faces"))
    return p


def _check(result: SimplificationResult, V, F):
    Vo = float_array("", "V", result.V, (-1, 3))
    Fo = result.F
    if not isinstance(Fo, np.ndarray) or Fo.dtype.kind not in "iu" or Fo.ndim != 2 or Fo.shape[1:] != (3,):
        what = f"{type(Fo).__name__} of dtype {getattr(Fo, 'dtype', '?')} and shape {getattr(Fo, 'shape', '?')}"
        raise MethodFailed(f"returned F as {what}, expected an integer array (l, 3)")
    if Fo.size == 0:
        raise MethodFailed(f"returned an empty mesh ({len(Vo)} vertices, 0 faces)")
    if not np.isfinite(Vo).all():
        raise MethodFailed("returned non-finite vertex coordinates")
    if Fo.min() < 0 or Fo.max() >= len(Vo):
        raise MethodFailed(f"returned face indices out of range [0, {len(Vo)}): min {Fo.min()}, max {Fo.max()}")
    result.V, result.F = compact(Vo, Fo)
    return result


def _topology_in(inp) -> dict:
    if "topology" not in inp.cache:
        from ..mesh import topology
        inp.cache["topology"] = topology(inp.V, inp.F)
    return inp.cache["topology"]


def measure(inp, result, params) -> dict:
    """Output size, certified symmetric Hausdorff distance and mean surface distance to the input
    surface (`harness.metrics.hausdorff`), manifoldness, topology change."""
    from ..mesh import topology
    V_out, F_out, diag = result.V, result.F, inp.diag
    given = params.get("target_ratio") is not None or params.get("target_faces") is not None
    target = target_face_count(inp.F.shape[0], params.get("target_ratio"), params.get("target_faces")) if given else None
    topo_in = _topology_in(inp)
    row = {"target_faces": None if target is None else int(target), "out_faces": int(len(F_out))}
    S_in = cached_surface(inp.cache, "input_surface", inp.V, inp.F)
    hd = hausdorff(V_out, F_out, inp.V, inp.F, eps=inp.settings.get("hausdorff_eps", 1e-3),
                   n_samples=inp.settings.get("hausdorff_samples", 20000), surface_b=S_in, vertex_distances=True)
    topo = topology(V_out, F_out)
    row.update({"hausdorff": hd["hausdorff"] / diag, "hausdorff_gap": hd["hausdorff_gap"],
                "hausdorff_upper": hd["hausdorff_upper"] / diag,
                "surface_dist_mean": hd.get("surface_dist_mean", np.nan) / diag,
                "surface_dist_mean_se": hd.get("surface_dist_mean_se", np.nan) / diag,
                "dist_mean": float(hd["vertex_distances_ab"][np.unique(F_out)].mean()) / diag,
                "over_target": None if target is None else bool(len(F_out) > target + target_tolerance(target)),
                "manifold": topo["manifold"],
                "manifold_lost": bool(topo_in["manifold"] and not topo["manifold"]),
                "orientation_lost": bool(topo_in["oriented"] and not topo["oriented"]),
                # chi = 2c - 2g - b gives the genus of orientable manifold meshes only: blank otherwise
                "genus_change": (topo["genus"] - topo_in["genus"] if all(t["manifold"] and t["oriented"]
                                                                         for t in (topo, topo_in)) else np.nan),
                "boundary_loops_change": topo["boundary_loops"] - topo_in["boundary_loops"],
                "components_change": topo["components"] - topo_in["components"]})
    row["topology_changed"] = bool(topo["euler"] != topo_in["euler"] or row["boundary_loops_change"] != 0
                                   or row["components_change"] != 0)
    q = triangle_quality(V_out, F_out)
    row.update({k: q[k] for k in ("min_angle", "radius_ratio_mean", "obtuse_fraction", "min_angle_hist")})
    row["zero_area_faces"] = int(len(zero_area_faces(V_out, F_out)))
    return row


def output_mesh(inp, result):
    return result.V, result.F


def view(inp, result) -> list:
    """Meshes of the 3D view: the input coloured by its distance to the result and the result by
    its distance to the input (the two directions of the Hausdorff distance)."""
    e_in = point_surface_distance(inp.V, result.V, result.F) / inp.diag
    S_in = cached_surface(inp.cache, "input_surface", inp.V, inp.F)
    e_out = point_surface_distance(result.V, inp.V, inp.F, S_in) / inp.diag
    return [("clean", inp.clean.V, inp.F, None, "reference mesh"),
            ("input", inp.V, inp.F, e_in, "distance of each input vertex to the simplified surface"),
            ("result", result.V, result.F, e_out, "distance of each result vertex to the input surface")]


def _face_target_reached(method, V, F):
    """Within 1% + 2 faces of the target, for a ratio and for an absolute count; no unreferenced vertex."""
    for kw, target in (({"target_ratio": 0.5}, round(0.5 * len(F))), ({"target_ratio": 0.1}, round(0.1 * len(F))),
                       ({"target_faces": 300}, 300)):
        res = method(V, F, **kw)
        assert abs(len(res.F) - target) <= target_tolerance(target), f"{kw}: {len(res.F)} faces for a target of {target}"
        assert len(np.unique(res.F)) == len(res.V), "output has unreferenced vertices"


_LEN = dict(unit="diag", rel=0.01, abs=1e-6)
TASK = Task(
    name="simplification", title="Simplification", result_type=SimplificationResult,
    intro="Simplified meshes against their (noisy) input. Hausdorff and mean distances are fractions of the "
          "bounding-box diagonal; lower is better.",
    metrics=(
        Metric("target_faces", "info", "faces asked for (blank for a result scored by eval without a target)", kind="int"),
        Metric("out_faces", "target", "faces returned", kind="int", target="target_faces"),
        Metric("over_target", "false", "kept more faces than target_faces + 1% + 2 (its errors are not comparable: "
               "an invalid result; blank without a target)", kind="bool"),
        Metric("hausdorff", "lower", "symmetric Hausdorff distance to the input surface, certified by branch and "
               "bound: the largest distance found, the true value at most hausdorff_upper", rank=True, upper="hausdorff_upper", **_LEN),
        Metric("hausdorff_gap", "info", "relative gap (upper - lower) / lower of the Hausdorff bracket, 0 when upper - "
               "lower <= 1e-12 of the diagonal plus 4 r (r = 256 eps max|coordinate|, the rounding allowance both ends "
               "carry); certified: <= hausdorff_eps (default 1e-3), or the whole bracket within lower + hausdorff_eps "
               "lower + 1e-12 of the diagonal + 4 r (a distance near rounding level may then show a larger gap); larger "
               "when the time or point budget ran out", rel=1.0, abs=1e-3),
        Metric("hausdorff_upper", "info", "certified upper bound of the Hausdorff distance", **_LEN),
        Metric("surface_dist_mean", "lower", "symmetric mean surface distance: average of the two one-sided "
               "area-weighted means, from hausdorff_samples random points per side", rank=True,
               se="surface_dist_mean_se", **_LEN),
        Metric("surface_dist_mean_se", "info", "standard error of surface_dist_mean (sampling)", unit="diag"),
        Metric("dist_mean", "info", "mean distance of the result's vertices to the input surface (exact; as "
               "smoothing's dist_mean): not a quality ranking, since a method that keeps input positions scores 0 "
               "whatever its faces do; surface_dist_mean measures the surfaces", unit="diag"),
        Metric("manifold", "true", "output is edge- and vertex-manifold", kind="bool"),
        Metric("manifold_lost", "false", "the input was manifold and the output is not (an invalid result)",
               kind="bool"),
        Metric("orientation_lost", "false", "the input's faces were consistently oriented and the output's are "
               "not: a face flipped (or an edge of more than two faces); an invalid result", kind="bool"),
        Metric("topology_changed", "false", "Euler characteristic (for manifold meshes: the genus), number of "
               "boundary loops or of connected components changed",
               kind="bool"),
        Metric("genus_change", "info", "output genus minus input genus (blank unless both are manifold and "
               "consistently oriented: chi = 2c - 2g - b holds for orientable manifold meshes only)"),
        Metric("boundary_loops_change", "info", "output boundary loops minus input's", kind="int"),
        Metric("components_change", "info", "output connected components (faces joined through a shared vertex "
               "or edge) minus input's", kind="int"),
        Metric("min_angle", "higher", "smallest triangle angle", unit="deg", rel=0.01, abs=0.01),
        Metric("radius_ratio_mean", "higher", "mean of 2 r_in / r_circ over faces (1 = equilateral)",
               rel=0.01, abs=1e-3),
        Metric("obtuse_fraction", "lower", "fraction of faces with an angle above 90 degrees", rel=0.01, abs=2e-3),
        Metric("min_angle_hist", "info", "histogram of the smallest angle per face (12 bins of 5 degrees)",
               kind="json"),
        Metric("zero_area_faces", "count", "output faces of zero area (collapsed: no normal, and no cotangent "
               "weight for a Laplacian built on them), by the cross product or Heron's formula", kind="int"),
    ),
    params=PARAMS, prepare=prepare, measure=measure, check_result=_check, output_mesh=output_mesh, view=view,
    view_metric="hausdorff", axis_params=frozenset({"target_ratio", "target_faces"}),
    checks=(("face_target_reached", _face_target_reached),), order=30,
    preload=_warm_metrics, input_facts=("topology", "input_surface"),
    invalid_when=(Invalid("over_target", "==", "kept more faces than the target", value=True),
                  Invalid("manifold_lost", "==", "non-manifold output from a manifold input", value=True),
                  Invalid("orientation_lost", "==", "flipped faces in the output of a consistently oriented input",
                          value=True),
                  Invalid("topology_changed", "==", "topology changed", value=True)))
