"""HC Laplacian smoothing as Vollmer, Mencl and Mueller publish it (one small adapter)."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from methods import Param, SmoothingResult, register
from methods.scratch.operators import adjacency


def neighbour_mean(F: np.ndarray, n: int) -> sp.csr_matrix:
    """``A`` with ``(A X)_i`` the mean of the positions of ``i``'s edge neighbours; the row of a
    vertex without neighbours is zero."""
    A = adjacency(F, n)
    deg = np.asarray(A.sum(axis=1)).ravel()
    return (sp.diags(np.divide(1.0, deg, out=np.zeros(n), where=deg > 0)) @ A).tocsr()


@register("scratch.hc", task="smoothing", library="scratch",
          params={"alpha": Param("alpha", 0.0, "float", low=0.0, high=1.0,
                                 doc="weight of the original positions in b (the paper's alpha)"),
                  "beta": Param("beta", 0.5, "float", low=0.0, high=1.0,
                                doc="weight of a vertex's own b against its neighbours' mean b"),
                  "iterations": Param("iterations", 1, "int", low=0, high=100000,
                                      doc="number of HC passes")})
def hc(V, F, *, alpha=0.0, beta=0.5, iterations=1):
    """HC ("Humphrey's Classes") smoothing, Vollmer, Mencl, Mueller, "Improved Laplacian
    smoothing of noisy surface meshes", Eurographics 1999, as the paper's algorithm states it.

    Per pass, with ``o`` the input positions, ``q`` the positions before the pass and ``N(i)``
    the edge neighbours of vertex ``i`` (uniform weights, boundary vertices included):

    ``p_i = mean_{j in N(i)} q_j``,  ``b_i = p_i - (alpha o_i + (1 - alpha) q_i)``,
    ``p_i <- p_i - (beta b_i + (1 - beta) mean_{j in N(i)} b_j)``.

    The correction pulls each vertex back toward where it and its neighbours were, which limits
    the shrinkage of plain Laplacian smoothing. A vertex without neighbours (unreferenced)
    stays where it is. Lengths keep their unit; ``alpha`` and ``beta`` are dimensionless in
    [0, 1]. This equals ``trimesh.smoothing.filter_humphrey`` given the uniform operator over the
    undirected edges (1e-12 of the diagonal, tests/test_smoothing_hc.py); with trimesh's default
    operator, built from the faces' directed edges, a boundary vertex of an open mesh misses one
    neighbour and the two differ there (5.4e-3 to 5.9e-3 of the diagonal on camelhead, with or
    without noise, alpha 0.1, beta 0.6 or 0.5, 3 passes).
    The defaults are MeshLab's fixed ones (alpha 0, beta 0.5); ``meshlab.hc`` runs the same
    pass with the neighbours' mean ``b`` added instead of subtracted (its docstring).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    alpha, beta : float in [0, 1]
    iterations : int

    Returns
    -------
    SmoothingResult
    """
    n = V.shape[0]
    A = neighbour_mean(F, n)
    lonely = np.asarray(A.sum(axis=1)).ravel() == 0
    o = V
    p = V.copy()
    for _ in range(int(iterations)):
        q = p
        p = A @ q
        p[lonely] = q[lonely]
        b = p - (alpha * o + (1.0 - alpha) * q)
        p = p - (beta * b + (1.0 - beta) * (A @ b))
    return SmoothingResult(V=p)
