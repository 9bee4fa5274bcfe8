"""Terms of a mesh's connectivity alone for `laplacian_properties`: the sorted directed keys
``i*n + j`` of its edges, membership of keys in them, and the vertices on a boundary or
non-manifold edge.
"""
from __future__ import annotations

import numpy as np

from ..core.geometry import edge_face_counts


def _edge_keys(F: np.ndarray, n: int) -> np.ndarray:
    """Sorted unique directed keys ``i*n + j`` of both orientations of every mesh edge (a
    degenerate face's self-loop ``i*n + i`` once)."""
    E = edge_face_counts(F)[0] if len(F) else np.zeros((0, 2), np.int64)
    i, j = E[:, 0], E[:, 1]
    loop = i == j
    keys = np.concatenate([i * np.int64(n) + j, j[~loop] * np.int64(n) + i[~loop]])
    keys.sort()
    return keys


def _isin_sorted(keys: np.ndarray, sorted_keys: np.ndarray) -> np.ndarray:
    if sorted_keys.size == 0:
        return np.zeros(keys.shape, bool)
    pos = np.searchsorted(sorted_keys, keys)
    pos = np.minimum(pos, sorted_keys.size - 1)
    return sorted_keys[pos] == keys


def _boundary_vertices(F: np.ndarray, n: int) -> np.ndarray:
    """Vertices on an edge with one incident face, or with more than two (non-manifold)."""
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    keys = E[:, 0] * np.int64(n) + E[:, 1]
    keys.sort()
    start = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]])
    counts = np.diff(np.r_[start, keys.size])
    bad = keys[start[counts != 2]]
    out = np.zeros(n, bool)
    out[bad // n] = True
    out[bad % n] = True
    return out
