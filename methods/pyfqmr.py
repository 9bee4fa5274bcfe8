"""pyfqmr (Cython wrapper of Forstmann's Fast-Quadric-Mesh-Simplification) as a peer.

The library is imported lazily so a missing install makes the method `unavailable`.
"""
from __future__ import annotations

import numpy as np

from methods import Param, SimplificationResult, register


@register(
    "pyfqmr.qem",
    task="simplification",
    library="pyfqmr",
    params={
        "aggressiveness": Param("aggressiveness", 7.0, "float", low=0.0, high=20.0,
                                doc="growth exponent of the error threshold "
                                    "alpha * (iteration + K) ** aggressiveness"),
        "preserve_boundary": Param("preserve_boundary", False,
                                 doc="forbid collapses touching open-boundary vertices "
                                     "(pyfqmr's own default is true; false here to match "
                                     "the other methods)"),
        "max_iterations": Param("max_iterations", 100, "int", low=1, high=100000,
                                doc="maximum number of threshold sweeps"),
    },
    requires=("pyfqmr",),
)
def qem(V, F, *, target_faces, aggressiveness=7.0, preserve_boundary=False, max_iterations=100):
    """FQMS quadric decimation through pyfqmr.

    Same algorithm as fast-simplification (threshold sweeps over unweighted face-plane
    quadrics, not error-ordered), a different wrapper of another copy of the source: the outputs
    are identical on closed meshes and with ``preserve_boundary`` on, but on open meshes with
    it off (the default) they may differ (by 5e-3 to 1.5e-2 of the bounding-box diagonal on
    camelhead and a jittered grid; identical on woody at 0.2 and 0.1).

    Parameters
    ----------
    V : (n, 3) float64 array
    F : (m, 3) int64 array
    target_faces : int
        ``target_count``.
    aggressiveness, preserve_boundary, max_iterations
        Passed through.

    Returns
    -------
    SimplificationResult
        As the library returns it; the task drops unreferenced vertices (untimed).
    """
    import pyfqmr

    s = pyfqmr.Simplify()
    s.setMesh(V, F.astype(np.int32))
    s.simplify_mesh(target_count=int(target_faces), aggressiveness=float(aggressiveness),
                    preserve_border=bool(preserve_boundary), max_iterations=int(max_iterations),
                    verbose=False)
    Vo, Fo, _ = s.getMesh()
    return SimplificationResult(V=Vo, F=Fo)
