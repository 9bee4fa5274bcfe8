"""libigl smoothing adapter: implicit (backward Euler) fairing on libigl's own operators."""
from __future__ import annotations

import numpy as np

from methods import Param, SmoothingResult, register
from methods.libigl import check_finite, reject_zero_area
from harness.core.solvers import backward_euler
from methods.vocabulary import solver_param


def _igl_operator(P, F):
    """``(W, m)`` from ``igl.cotmatrix`` and the diagonal of ``igl.massmatrix(VORONOI)``. The
    input is screened for zero-area faces before the call (``precheck``); a face that a
    reassembly step flattens makes `check_finite` name it.

    A zero mass (isolated vertex, whose ``W`` row is empty too) is set to 1 so the system
    stays positive definite and the vertex stays put, as in ``scratch.implicit``.
    """
    import igl
    W = igl.cotmatrix(P, F).tocsr()
    check_finite(W, P, F, "libigl.implicit")
    n = P.shape[0]
    if W.shape[0] < n:   # libigl sizes W and M by max(F) + 1: pad trailing unreferenced vertices
        W.resize((n, n))
    M = igl.massmatrix(P, F, igl.MASSMATRIX_TYPE_VORONOI)
    m = np.asarray(M.diagonal(), dtype=np.float64)
    m = np.concatenate([m, np.zeros(n - m.size)])
    m = np.where((m > 0) & np.isfinite(m), m, 1.0)
    return W, m


def _mean_edge_length(V, F) -> float:
    import igl
    E = igl.edges(F)
    return float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).mean())


@register("libigl.implicit", task="smoothing", library="libigl", requires=("igl",),
          precheck=reject_zero_area,
          params={"step": Param("step", 1.0, "float", low=0.0,
                                doc="dimensionless step: h = step * (mean edge length)^2"),
                  "iterations": Param("iterations", 1, "int", low=0, high=10000,
                                      doc="number of backward-Euler steps"),
                  "reassemble": Param("reassemble", False, "bool",
                                      doc="rebuild W and M from the current positions each step"),
                  "solver": solver_param()})
def implicit(V, F, *, step=1.0, iterations=1, reassemble=False, solver="auto"):
    """Implicit fairing ``(M - h W) X' = M X`` with ``W = igl.cotmatrix``, ``M = igl.massmatrix``.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    step : float
        ``h = step * lbar^2``, ``lbar`` the mean length of ``igl.edges(F)`` on the input.
    iterations : int
    reassemble : bool
        Rebuild ``W`` and ``M`` from the current positions before every step.
    solver : str
        Sparse SPD solver of ``harness.core.solvers``.

    Returns
    -------
    SmoothingResult

    Notes
    -----
    The same algorithm and parameters as ``scratch.implicit`` with ``weights: cotan_area``
    (Desbrun et al. 1999), only the operators come from libigl (``igl.cotmatrix``; mass
    ``MASSMATRIX_TYPE_VORONOI``, the mixed Voronoi area of Meyer et al. 2003), so the pair
    cross-validates to solver precision. libigl's own tutorial 205 (Laplacian smoothing) solves
    an ``(M - h L)`` system too, but with the barycentric mass rebuilt every step and the area
    renormalised, so it is not this method's twin.
    """
    h = float(step) * _mean_edge_length(V, F) ** 2
    X = backward_euler(V, F, lambda P: _igl_operator(P, F), h, iterations, reassemble, solver)
    return SmoothingResult(V=X)
