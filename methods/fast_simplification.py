"""fast-simplification (pyvista/fast-simplification, a wrapper of Sven Forstmann's
Fast-Quadric-Mesh-Simplification, FQMS) as a simplification method.

The library is imported lazily so a missing install makes the method `unavailable`.
"""
from __future__ import annotations

import numpy as np

from methods import Param, SimplificationResult, register


@register(
    "fast_simplification.qem",
    task="simplification",
    library="fast-simplification",
    params={
        "aggressiveness": Param("aggressiveness", 7.0, "float", low=0.0, high=20.0, id_as="agg",
                                doc="aggressiveness of FQMS's error threshold schedule "
                                    "(0 = most accurate/slowest, 10 = fast/coarse; library default 7)"),
        "preserve_boundary": Param("preserve_boundary", False, id_as="preserve_border",
                                   doc="forbid collapses of edges touching an open boundary"),
    },
    requires=("fast_simplification",),
)
def qem(V, F, *, target_faces, aggressiveness=7.0, preserve_boundary=False):
    """Quadric-error decimation with fast-simplification (FQMS).

    FQMS (Forstmann) uses Garland-Heckbert quadrics ``Q = sum_f n n^T`` (unweighted face
    planes) but, instead of a global priority queue, sweeps all edges repeatedly and collapses
    every edge whose error is below a threshold ``1e-9 * (iteration + 3) ** aggressiveness``
    (per iteration), which is fast but not error-ordered.

    Parameters
    ----------
    V : (n, 3) float64 array
    F : (m, 3) int64 array
    target_faces : int
        Passed as ``target_count``.
    aggressiveness : float
        The threshold schedule's exponent (see above; the library's ``agg``).
    preserve_boundary : bool
        Forbid collapses touching border vertices (the library's ``preserve_border``).

    Returns
    -------
    SimplificationResult
        As the library returns it; the task drops vertices no face references (untimed).
    """
    import fast_simplification

    Vo, Fo = fast_simplification.simplify(V, F.astype(np.int32), target_count=int(target_faces),
                                          agg=float(aggressiveness), preserve_border=bool(preserve_boundary))
    return SimplificationResult(V=Vo, F=Fo)
