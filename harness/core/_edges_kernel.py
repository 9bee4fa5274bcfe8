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


@njit(cache=True, inline="always")
def _root(parent, p):
    while parent[p] != p:
        parent[p] = parent[parent[p]]
        p = parent[p]
    return p


@njit(cache=True)
def fan_counts(F, n):
    """Number of edge-connected fans of faces around each vertex (n,), for faces ``F`` (m, 3)
    int64: two corners at a vertex v are in one fan when their faces share an edge (v, x),
    i.e. when the corners' other two vertices share an x (0 for unreferenced vertices)."""
    m = F.shape[0]
    start = np.zeros(n + 1, np.int64)
    for f in range(m):
        for c in range(3):
            start[F[f, c] + 1] += 1
    for i in range(n):
        start[i + 1] += start[i]
    fill = start[:-1].copy()
    nxt = np.empty(3 * m, np.int64)           # the corner's two other vertices, grouped by vertex
    prv = np.empty(3 * m, np.int64)
    for f in range(m):
        for c in range(3):
            v = F[f, c]
            nxt[fill[v]] = F[f, (c + 1) % 3]
            prv[fill[v]] = F[f, (c + 2) % 3]
            fill[v] += 1
    parent = np.arange(3 * m)
    fans = np.zeros(n, np.int64)
    for v in range(n):
        s, e = start[v], start[v + 1]
        if e - s <= 48:                       # a few corners: compare every pair
            for p in range(s, e):
                for q in range(p + 1, e):
                    if nxt[p] == nxt[q] or nxt[p] == prv[q] or prv[p] == nxt[q] or prv[p] == prv[q]:
                        a, b = _root(parent, p), _root(parent, q)
                        if a != b:
                            parent[max(a, b)] = min(a, b)
        else:                                 # many: sort the (other vertex, corner) pairs
            k = e - s
            key = np.empty(2 * k, np.int64)
            for p in range(k):
                key[2 * p] = nxt[s + p]
                key[2 * p + 1] = prv[s + p]
            order = np.argsort(key, kind="mergesort")
            for t in range(1, 2 * k):
                if key[order[t]] == key[order[t - 1]]:
                    a, b = _root(parent, s + order[t] // 2), _root(parent, s + order[t - 1] // 2)
                    if a != b:
                        parent[max(a, b)] = min(a, b)
        for p in range(s, e):
            if parent[p] == p:
                fans[v] += 1
    return fans
