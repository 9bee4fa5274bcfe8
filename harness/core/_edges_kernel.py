"""Compiled unique-edge extraction (`harness.core.geometry.edge_face_counts` on large meshes):
a counting sort of the half-edges by their smaller vertex, then a sort of each (short) row."""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def edges_and_counts(F, n):
    """Unique undirected edges (e, 2) in lexicographic order and the number of half-edges on
    each (e,), for faces ``F`` (m, 3) int64 with indices in ``[0, n)``."""
    m = F.shape[0]
    start = np.zeros(n + 1, np.int64)
    for f in range(m):
        for c in range(3):
            a, b = F[f, c], F[f, (c + 1) % 3]
            start[min(a, b) + 1] += 1
    for i in range(n):
        start[i + 1] += start[i]
    fill = start[:-1].copy()
    nb = np.empty(3 * m, np.int64)
    for f in range(m):
        for c in range(3):
            a, b = F[f, c], F[f, (c + 1) % 3]
            lo = min(a, b)
            nb[fill[lo]] = max(a, b)
            fill[lo] += 1
    E = np.empty((3 * m, 2), np.int64)
    counts = np.empty(3 * m, np.int64)
    k = 0
    for i in range(n):
        s, e = start[i], start[i + 1]
        if e - s > 32:
            nb[s:e] = np.sort(nb[s:e])
        else:
            for p in range(s + 1, e):          # insertion sort: rows hold about 3 entries
                x = nb[p]
                q = p - 1
                while q >= s and nb[q] > x:
                    nb[q + 1] = nb[q]
                    q -= 1
                nb[q + 1] = x
        j = s
        while j < e:
            v = nb[j]
            c = 1
            j += 1
            while j < e and nb[j] == v:
                c += 1
                j += 1
            E[k, 0] = i
            E[k, 1] = v
            counts[k] = c
            k += 1
    return E[:k], counts[:k]
