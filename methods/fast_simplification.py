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
        "agg": Param("agg", 7.0, "float", low=0.0, high=20.0,
                     doc="aggressiveness of FQMS's error threshold schedule "
                         "(0 = most accurate/slowest, 10 = fast/coarse; library default 7)"),
        "preserve_border": Param("preserve_border", False,
                                 doc="forbid collapses of edges touching an open boundary"),
    },
    requires=("fast_simplification",),
)
def qem(V, F, *, target_faces, agg=7.0, preserve_border=False):
    """Quadric-error decimation with fast-simplification (FQMS).

    FQMS (Forstmann) uses Garland-Heckbert quadrics ``Q = sum_f n n^T`` (unweighted face
    planes) but, instead of a global priority queue, sweeps all edges repeatedly and collapses
    every edge whose error is below a threshold ``1e-9 * (iteration + 3) ** agg``
    (per iteration), which is fast but not error-ordered.

    Parameters
    ----------
    V : (n, 3) float64 array
    F : (m, 3) int64 array
    target_faces : int
        Passed as ``target_count``.
    agg : float
        Aggressiveness (see above).
    preserve_border : bool
        Forbid collapses touching border vertices.

    Returns
    -------
    SimplificationResult
        As the library returns it; the task drops vertices no face references (untimed).
    """
    import fast_simplification

    Vo, Fo = fast_simplification.simplify(V, F.astype(np.int32), target_count=int(target_faces),
                                          agg=float(agg), preserve_border=bool(preserve_border))
    return SimplificationResult(V=Vo, F=Fo)
