"""libigl reference Laplacians (task ``laplacian``); ``igl`` is imported lazily.

libigl's sign convention is the project's: off-diagonal weights positive where POS holds,
rows sum to zero, ``W`` negative semi-definite on Delaunay meshes.
Note: libigl does not clamp degenerate faces: a zero-area face gives inf/NaN cotangents (and
``intrinsic_delaunay_cotmatrix`` may throw std::bad_alloc). These adapters therefore refuse
zero-area faces with a ValueError naming them (`methods.libigl.reject_zero_area`), and name
the faces behind any non-finite entry libigl still returns (`methods.libigl.check_finite`).
"""
from __future__ import annotations

import numpy as np

from methods import LaplacianResult, Param, register
from methods.libigl import check_finite, reject_zero_area

_MASS = Param("mass", "voronoi", choices=("barycentric", "voronoi", "none"),
              doc="igl.massmatrix type: barycentric -> MASSMATRIX_TYPE_BARYCENTRIC, voronoi -> "
                  "MASSMATRIX_TYPE_VORONOI (mixed Voronoi, Meyer et al. 2003), none -> M=None")


def _igl_mass(igl, V, F, mass):
    if mass == "none":
        return None
    kind = {"barycentric": igl.MASSMATRIX_TYPE_BARYCENTRIC,
            "voronoi": igl.MASSMATRIX_TYPE_VORONOI}[mass]
    M = igl.massmatrix(V, F, kind)               # as libigl returns it: the task converts, untimed
    n = V.shape[0]
    if M.shape[0] < n:  # libigl sizes M by max(F) + 1: pad trailing unreferenced vertices
        M.resize((n, n))
    return M


@register("libigl.cotan", task="laplacian", library="libigl", params={"mass": _MASS},
          requires=("igl",), precheck=reject_zero_area)
def cotan(V, F, *, mass="voronoi"):
    """libigl cotangent Laplacian ``igl.cotmatrix(V, F)`` and ``igl.massmatrix(V, F, type)``.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    mass : {"voronoi", "barycentric", "none"}
        Mass matrix type (see the module's ``_MASS`` declaration).

    Returns
    -------
    LaplacianResult
        ``W_ij = (cot a_ij + cot b_ij) / 2`` (Pinkall & Polthier 1993), ``M`` diagonal areas.
    """
    import igl
    W = igl.cotmatrix(V, F)
    check_finite(W, V, F, "libigl.cotan")
    return LaplacianResult(W=W, M=_igl_mass(igl, V, F, mass))


@register("libigl.intrinsic_delaunay", task="laplacian", library="libigl",
          params={"mass": _MASS}, requires=("igl",), precheck=reject_zero_area)   # NaN, or std::bad_alloc
def intrinsic_delaunay(V, F, *, mass="voronoi"):
    """libigl's cotangent Laplacian of the intrinsic Delaunay triangulation.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    mass : {"voronoi", "barycentric", "none"}
        Mass of the intrinsic triangulation, ``igl.massmatrix_intrinsic`` on its edge lengths
        (areas are preserved by intrinsic flips, so barycentric totals equal the input's).

    Returns
    -------
    LaplacianResult
        ``W = igl.intrinsic_delaunay_cotmatrix(V, F)[0]`` (Fisher et al. 2006; Bobenko &
        Springborn 2007): cotangent weights of the intrinsic Delaunay triangulation, all
        non-negative (POS), but between vertices that need not share a mesh edge (no LOC).
    """
    import igl
    W, l_int, F_int = igl.intrinsic_delaunay_cotmatrix(V, F)
    n = V.shape[0]
    if W.shape[0] < n:  # libigl sizes W by max(F) + 1: pad trailing unreferenced vertices
        W.resize((n, n))
    M = None
    if mass != "none":
        kind = {"barycentric": igl.MASSMATRIX_TYPE_BARYCENTRIC,
                "voronoi": igl.MASSMATRIX_TYPE_VORONOI}[mass]
        M = igl.massmatrix_intrinsic(np.ascontiguousarray(l_int), np.ascontiguousarray(F_int), kind)
        if M.shape[0] < n:  # trailing unreferenced vertices
            M.resize((n, n))
    return LaplacianResult(W=W, M=M)
