"""PyMeshLab smoothing adapters (VCGLib ``vcg/complex/algorithms/smooth.h``).

Vertex order: only referenced vertices are handed to MeshLab (two-step smoothing refuses a
non-compact mesh), each carrying its caller index in a custom per-vertex attribute
(``_shootout_index``) through the filter; the result is scattered back into the caller's order
and count. Unreferenced vertices (and any a filter removed) keep their input position.

Formulas of VCGLib (checked numerically in tests/test_smoothing_xval.py). ``N(i)`` are the
neighbours of vertex ``i``; on a closed mesh every edge is visited once per incident face, so
uniform sums count each neighbour twice and cotangent sums give ``cot a + cot b``:

``meshlab.laplacian`` (``apply_coord_laplacian_smoothing``, ``VertexCoordLaplacian``)
    interior: ``x' = (x + sum_j w_ij x_j) / (1 + sum_j w_ij)`` with ``w_ij = 2`` (uniform) or
    ``w_ij = cot a_ij + cot b_ij`` (``cotangentweight``, computed in single precision), i.e.
    the vertex itself IS averaged in with weight 1/2 of an edge weight:
    ``x' = x + m_i / (m_i + 1/2) (L x)_i`` with ``m_i = sum_j W_ij`` of the uniform / cotangent
    ``W``. This equals ``scratch.explicit(step=1, self_weight=0.5)`` (uniform: to rounding).
    With cotangent weights it equals that with ``reassemble=True``, as VCG recomputes the
    cotangents from the current positions at every step (without it the two are 2e-3 to
    3e-2 of the diagonal apart after 5 iterations on open, obtuse and noisy meshes); VCG's
    single-precision weights leave 1e-8 to 1e-6 of the diagonal after 5 iterations,
    growing with them, 6e-4 after 50 on a non-Delaunay plane, and 2e-2 on a mesh with a
    numerically flat face. Boundary vertices
    (``boundary: true``) average themselves twice with their boundary neighbours only:
    ``x' = (2 x + sum_{boundary nbrs} x_j) / (n_b + 2)``, uniform weights even in cotangent
    mode (``scratch.explicit`` with ``boundary: curve``). ``iterations`` -> ``stepsmoothnum``.
``meshlab.taubin`` (``apply_coord_taubin_smoothing``, ``VertexCoordTaubin``)
    ``x += lambda (mean_{N(i)} x_j - x)`` then the same with ``mu``, per iteration; boundary
    vertices use ``(x + sum_b x_j)/(1 + n_b)`` as their "mean". This is ``scratch.taubin``
    with uniform weights and ``boundary: curve`` (on a closed mesh any boundary rule).
    ``iterations`` -> ``stepsmoothnum``. VCG holds ``lambda`` and ``mu`` in single precision:
    the result is that of ``float32(lambda)``, ``float32(mu)`` (``-0.53`` becomes
    ``-0.52999997``, a difference of ~1e-10 of the diagonal per iteration).
``meshlab.hc`` (``apply_coord_hc_laplacian_smoothing``, ``VertexCoordLaplacianHC``)
    no parameters; the filter runs one pass, called ``iterations`` times. With ``q`` the
    positions before the pass, ``p_i = mean_{N(i)} q_j`` and ``b_i = p_i - q_i`` (the paper's
    alpha = 0), the pass gives ``p_i - beta b_i + (1 - beta) mean_{N(i)} b_j`` with beta 0.5.
    Vollmer, Mencl and Mueller's HC (1999) *subtracts* the neighbours' mean ``b``
    (`scratch.hc`), so this is MeshLab's variant of HC, not the paper's: on Fandisk0.3, after
    one pass, a vertex is up to 6.7e-3 of the noisy input's bounding-box diagonal away from it
    (tests/test_smoothing_hc.py).
``meshlab.two_steps`` (``apply_coord_two_steps_smoothing``, VCG ``VertexCoordPasoDoble``)
    MeshLab names Belyaev & Ohtake's two-step smoothing; the formulas are those of Sun et al.
    2007 (`scratch.sun`): ``iterations`` times, unit face normals, then ``normal_iterations``
    Jacobi passes ``n_f <- normalize(sum_g w_fg n_g)``, ``w_fg = (c - T)^2`` where
    ``c = clamp(n_f . n_g, 1e-4, 1) >= T``, ``T = max(cos(normal_threshold_deg), 0)`` (no area
    weights; 0 degrees moves nothing, 90 or more are all alike), then ``vertex_iterations`` passes
    ``x_i += 1/|F_i| sum_f n_f (n_f . (c_f - x_i))`` (boundary not fixed). Unlike Sun et al.,
    VCG's normal pass walks each vertex's face list from the face itself, and the lists run
    in decreasing face index, so a face averages only with the vertex-adjacent faces of a
    lower or equal index (about half its ring; some faces only with themselves): the result
    depends on the order of the faces (Fandisk0.3 at the defaults: ``dist_mean`` 4.13e-3 in
    the file's order, 2.33e-3 with the faces shuffled, against the noisy input's 3.33e-3;
    `scratch.sun` gives 1.31e-3 in both orders at its defaults, the authors' code's, and 1.08e-3
    with Zhang et al.'s settings), and it is not the paper's
    method (tests/test_smoothing_sun.py).
``meshlab.surface_preserving`` (``apply_coord_laplacian_smoothing_surface_preserving``)
    uniform Laplacian step cancelled for vertices whose move would rotate an incident face
    normal by more than ``angle_deg`` (Lacewell et al. style "planar" Laplacian).
``meshlab.scale_dependent`` (``apply_coord_laplacian_smoothing_scale_dependent``, Fujiwara 1995)
    ``x += delta * sum_j e_ij/|e_ij| / sum_j |e_ij|``. PyMeshLab's ``delta`` is a
    ``PercentageValue`` (percent of the bounding-box diagonal) by default, or a ``PureValue``
    (absolute). Since ``delta`` multiplies a quantity of unit 1/length, it has unit length^2
    for the displacement to be a length; this adapter passes
    ``PureValue(step * lbar^2)`` (``lbar`` = mean edge length), which makes ``step`` the
    uniform-Laplacian step on a regular mesh (``sum e/|e| / sum |e| = mean(x_j - x)/lbar^2``).
"""
from __future__ import annotations

import numpy as np

from harness.core.geometry import referenced
from methods import Param, SmoothingResult, register

_INDEX = "_shootout_index"


def _meshset(V: np.ndarray, F: np.ndarray):
    """A MeshSet holding the referenced vertices only (some filters refuse meshes that are
    not compact), each tagged with its caller index."""
    import pymeshlab
    n = V.shape[0]
    if referenced(F, n).all():           # the usual case: no compaction, indices as they are
        Vm, Fc, index = V, F.astype(np.int32), np.arange(n, dtype=np.float64)
    else:
        keep, Fc = np.unique(F, return_inverse=True)
        Vm, Fc, index = V[keep], Fc.reshape(F.shape).astype(np.int32), keep.astype(np.float64)
    m = pymeshlab.Mesh(vertex_matrix=Vm, face_matrix=Fc)
    m.add_vertex_custom_scalar_attribute(index, _INDEX)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(m)
    return ms


def _result(V: np.ndarray, ms) -> np.ndarray:
    """Current mesh's positions scattered back into the caller's order and count."""
    m = ms.current_mesh()
    P = np.asarray(m.vertex_matrix(), dtype=np.float64)
    idx = np.asarray(m.vertex_custom_scalar_attribute_array(_INDEX))
    ii = np.rint(idx).astype(np.int64)
    n = V.shape[0]
    if len(ii) == len(P) == n and np.array_equal(idx, np.arange(n, dtype=np.float64)):
        return np.array(P, dtype=np.float64, order="C")      # every vertex, in the caller's order
    if (len(ii) != len(P) or np.any(np.abs(idx - ii) > 0) or ii.min(initial=0) < 0
            or ii.max(initial=-1) >= n or np.bincount(ii, minlength=n).max(initial=0) > 1):
        raise RuntimeError("pymeshlab lost the vertex index attribute; cannot map vertices back")
    out = V.copy()
    out[ii] = P
    return out


_ITER = Param("iterations", 10, "int", low=0, high=100000,
               doc="stepsmoothnum (MeshLab's own default is 3; 10 here, as the Taubin filters')")


@register("meshlab.laplacian", task="smoothing", library="pymeshlab", requires=("pymeshlab",),
          params={"iterations": _ITER,
                  "cotangentweight": Param("cotangentweight", True,
                                           doc="cotangent edge weights (else uniform)"),
                  "boundary": Param("boundary", True,
                                    doc="smooth boundary vertices along the boundary (our boundary: curve when "
                                        "true; false is VCG's own, none of ours)")})
def laplacian(V, F, *, iterations=10, cotangentweight=True, boundary=True):
    """MeshLab classic Laplacian smoothing (``apply_coord_laplacian_smoothing``).

    ``x' = (x + sum_j w_ij x_j) / (1 + sum_j w_ij)`` (module docstring); the vertex itself is
    averaged in, so there is no step parameter.
    """
    ms = _meshset(V, F)
    if iterations > 0:
        ms.apply_coord_laplacian_smoothing(stepsmoothnum=int(iterations),
                                           cotangentweight=bool(cotangentweight),
                                           boundary=bool(boundary), selected=False)
    return SmoothingResult(V=_result(V, ms))


@register("meshlab.taubin", task="smoothing", library="pymeshlab", requires=("pymeshlab",),
          params={"lambda": Param("lambda", 0.5, "float", low=0.0, doc="lambda_ (shrink)"),
                  "mu": Param("mu", -0.53, "float", high=0.0, doc="mu (inflate)"),
                  "iterations": _ITER})
def taubin(V, F, **params):
    """MeshLab Taubin smoothing (``apply_coord_taubin_smoothing``): uniform lambda|mu pairs.

    ``lambda`` -> ``lambda_``, ``mu`` -> ``mu``, ``iterations`` -> ``stepsmoothnum`` (pairs).
    """
    ms = _meshset(V, F)
    it = int(params.get("iterations", 10))
    if it > 0:
        ms.apply_coord_taubin_smoothing(lambda_=float(params.get("lambda", 0.5)),
                                        mu=float(params.get("mu", -0.53)),
                                        stepsmoothnum=it, selected=False)
    return SmoothingResult(V=_result(V, ms))


@register("meshlab.hc", task="smoothing", library="pymeshlab", requires=("pymeshlab",),
          params={"iterations": Param("iterations", 1, "int", low=0, high=10000,
                                      doc="number of HC passes (the filter runs one)")})
def hc(V, F, *, iterations=1):
    """MeshLab's HC Laplacian smoothing: VCGLib's variant of Vollmer, Mencl, Mueller 1999.

    One pass, with ``q`` the positions before it and ``N(i)`` the edge neighbours:
    ``p_i = mean_{N(i)} q_j``, ``b_i = p_i - q_i`` and ``p_i - beta b_i + (1 - beta)
    mean_{N(i)} b_j``, beta = 0.5. The paper subtracts the last term (`scratch.hc`); a table
    that names the paper's HC should use `scratch.hc`. The filter has no parameters and runs a
    single pass; it is applied ``iterations`` times.
    """
    ms = _meshset(V, F)
    for _ in range(int(iterations)):
        ms.apply_coord_hc_laplacian_smoothing()
    return SmoothingResult(V=_result(V, ms))


@register("meshlab.two_steps", task="smoothing", library="pymeshlab", requires=("pymeshlab",),
          params={"iterations": Param("iterations", 3, "int", low=0, high=10000,
                                      doc="stepsmoothnum"),
                  "normal_threshold_deg": Param("normal_threshold_deg", 60.0, "float",
                                                low=0.0, high=180.0, doc="normalthr"),
                  "normal_iterations": Param("normal_iterations", 20, "int", low=0,
                                             high=10000, doc="stepnormalnum"),
                  "vertex_iterations": Param("vertex_iterations", 20, "int", low=0, high=10000, id_as="fit_iterations",
                                          doc="stepfitnum")})
def two_steps(V, F, *, iterations=3, normal_threshold_deg=60.0, normal_iterations=20,
              vertex_iterations=20):
    """MeshLab's two-step smoothing: Sun et al. 2007's normal filtering and vertex fitting, with
    VCG's one-sided face neighbourhood (module docstring), so its result depends on the order
    of the faces; `scratch.sun` is the published method.

    Parameters map to the filter's ``stepsmoothnum``, ``normalthr`` (degrees; the threshold is
    ``max(cos(normalthr), 0)`` on the normals' dot product), ``stepnormalnum``, ``stepfitnum``;
    defaults are MeshLab's.
    """
    ms = _meshset(V, F)
    if iterations > 0:
        ms.apply_coord_two_steps_smoothing(stepsmoothnum=int(iterations),
                                           normalthr=float(normal_threshold_deg),
                                           stepnormalnum=int(normal_iterations),
                                           stepfitnum=int(vertex_iterations), selected=False)
    return SmoothingResult(V=_result(V, ms))


@register("meshlab.surface_preserving", task="smoothing", library="pymeshlab",
          requires=("pymeshlab",),
          params={"iterations": Param("iterations", 1, "int", low=0, high=10000),
                  "angle_deg": Param("angle_deg", 0.5, "float", low=0.0, high=180.0,
                                     doc="angledeg: max normal rotation a move may cause")})
def surface_preserving(V, F, *, iterations=1, angle_deg=0.5):
    """MeshLab surface-preserving Laplacian (``..._surface_preserving``, angle in degrees)."""
    ms = _meshset(V, F)
    if iterations > 0:
        ms.apply_coord_laplacian_smoothing_surface_preserving(
            selection=False, angledeg=float(angle_deg), iterations=int(iterations))
    return SmoothingResult(V=_result(V, ms))


@register("meshlab.scale_dependent", task="smoothing", library="pymeshlab",
          requires=("pymeshlab",),
          params={"step": Param("step", 0.25, "float", low=0.0,
                                doc="dimensionless; passed as PureValue(step * lbar^2)"),
                  "iterations": _ITER})
def scale_dependent(V, F, *, step=0.25, iterations=10):
    """MeshLab scale-dependent Laplacian (Fujiwara 1995; Desbrun et al. 1999 Sec. 5).

    ``delta`` is given as ``pymeshlab.PureValue(step * lbar^2)`` (absolute units; the
    filter's default would be ``PercentageValue(1)`` = 1% of the bounding-box diagonal),
    see the module docstring for why ``lbar^2``.
    """
    import pymeshlab

    from harness.core.geometry import mean_edge_length
    ms = _meshset(V, F)
    if iterations > 0:
        delta = float(step) * mean_edge_length(V, F) ** 2
        ms.apply_coord_laplacian_smoothing_scale_dependent(
            stepsmoothnum=int(iterations), delta=pymeshlab.PureValue(delta), selected=False)
    return SmoothingResult(V=_result(V, ms))
