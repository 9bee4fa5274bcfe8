"""PyGEL3D's Garland-Heckbert simplification (``hmesh.quadric_simplify``).

The library is imported lazily so a missing install makes the method `unavailable`.
"""
from __future__ import annotations

import warnings

import numpy as np

from methods import Param, SimplificationResult, register
from methods.pygel import triangles as _triangles


# passes of quadric_simplify: a mesh with a long boundary reaches the target in a few
MAX_PASSES = 10


@register(
    "pygel.qem",
    task="simplification",
    library="pygel3d",
    params={
        "singular_thresh": Param("singular_thresh", 1e-4, "float", low=0.0, high=1.0,
                                 doc="threshold on the quadric's eigenvalues below which a "
                                     "direction counts as singular (small: keep subtle "
                                     "sharp features)"),
    },
    requires=("pygel3d",),
)
def qem(V, F, *, target_faces, singular_thresh=1e-4):
    """Garland-Heckbert quadric simplification of PyGEL3D (GEL, Baerentzen).

    ``quadric_simplify`` takes ``keep_fraction`` of VERTICES. The face target is translated
    with Euler's formula for interior collapses (each removes one vertex and two faces):
    ``keep_vertices = n - (m - target_faces) / 2``. If the result still has more than
    ``1.01 target_faces + 2`` faces (meshes with long boundaries, where a collapse removes
    one face), further passes run with the fraction recomputed from the current counts, up
    to ``MAX_PASSES`` or until a pass removes nothing (then a RuntimeWarning says so).
    ``error_thresh`` is set to 1e30: GEL stops collapsing once the quadric error reaches it,
    and its value 1 stalled woody at 82 faces for a target of 25; on bunny, camelhead and
    stanford-bunny the output is bit-identical either way. ``cleanup()`` is called before
    reading ``positions()`` (before it, the array still holds the deleted vertices).

    Parameters
    ----------
    V : (n, 3) float64 array
    F : (m, 3) int64 array
    target_faces : int
    singular_thresh : float
        Passed through.

    Returns
    -------
    SimplificationResult
        As the library returns it; the task drops unreferenced vertices (untimed).
    """
    from pygel3d import hmesh

    m = hmesh.Manifold.from_triangles(V, F)
    for _ in range(MAX_PASSES):
        nv, nf = len(m.vertices()), len(m.faces())
        if nf <= 1.01 * target_faces + 2:
            break
        keep_v = nv - (nf - target_faces) / 2.0
        frac = float(np.clip(keep_v / nv, 1e-9, 1.0))
        hmesh.quadric_simplify(m, frac, singular_thresh=float(singular_thresh), error_thresh=1e30)
        m.cleanup()
        if len(m.faces()) >= nf:          # no progress: GEL refuses further collapses
            break
    m.cleanup()
    if len(m.faces()) > 1.01 * target_faces + 2:
        warnings.warn(f"pygel.qem stopped at {len(m.faces())} faces, target {target_faces}",
                      RuntimeWarning, stacklevel=2)
    Vo = np.array(m.positions(), dtype=np.float64, copy=True)
    Fo = _triangles(m)
    return SimplificationResult(V=Vo, F=Fo)
