"""Adapters for the pygel backend (one module per task); the library is imported lazily."""

import os
import tempfile

import numpy as np


def triangles(m) -> np.ndarray:
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
