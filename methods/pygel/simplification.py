"""PyGEL3D's Garland-Heckbert simplification (``hmesh.quadric_simplify``).

The library is imported lazily so a missing install makes the method `unavailable`.
"""
from __future__ import annotations

import os
import tempfile

import numpy as np

from methods import Param, SimplificationResult, register
from methods.scratch.qem import compact


def _triangles(m) -> np.ndarray:
    """Faces (k, 3) of a cleaned-up PyGEL manifold, read vectorised from its OFF export.

    PyGEL has no bulk face accessor (``circulate_face`` is one call per face), so the mesh is
    written with ``hmesh.off_save`` (C++) and only the face block is parsed back; positions
    come from ``positions()`` at full precision.
    """
    from pygel3d import hmesh

    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "m.off")
        hmesh.off_save(path, m)
        with open(path) as fh:
            tok = fh.read().split()
    if tok[0] != "OFF":
        raise RuntimeError("pygel3d off_save wrote an unexpected header")
    nv, nf = int(tok[1]), int(tok[2])
    start = 4 + 3 * nv
    rows = np.asarray(tok[start:start + 4 * nf], dtype=np.int64).reshape(nf, 4)
    if np.any(rows[:, 0] != 3):
        raise RuntimeError("pygel3d produced non-triangular faces")
    return rows[:, 1:]


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
    one face), one more ``quadric_simplify`` pass is run with the fraction recomputed from the
    current counts. ``cleanup()`` is called before reading ``positions()`` (before it, the
    array still holds the deleted vertices).

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
        Compacted.
    """
    from pygel3d import hmesh

    m = hmesh.Manifold.from_triangles(V, F)
    for _ in range(2):
        nv, nf = len(m.vertices()), len(m.faces())
        if nf <= 1.01 * target_faces + 2:
            break
        keep_v = nv - (nf - target_faces) / 2.0
        frac = float(np.clip(keep_v / nv, 1e-9, 1.0))
        hmesh.quadric_simplify(m, frac, singular_thresh=float(singular_thresh), error_thresh=1)
        m.cleanup()
    m.cleanup()
    Vo = np.array(m.positions(), dtype=np.float64, copy=True)
    Fo = _triangles(m)
    Vo, Fo = compact(Vo, Fo)
    return SimplificationResult(V=Vo, F=Fo)
