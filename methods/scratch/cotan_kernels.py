"""Compiled kernels of the cotangent Laplacian assembly (`operators.CotanPattern`, `operators.cotan_laplacian`).

Plain Python until `_kernel` compiles one with numba (``cache=True``; the callees `_face_terms`
and `_sort_pairs` first). `_pattern_kernel` builds the CSR pattern of one connectivity and the
slot of every entry, `_numeric_kernel` writes the cotangent weights and mixed Voronoi areas
(`_face_terms`, Meyer et al. 2003) into it; `_sweep_kernel` and `_rows_kernel`, driven by
`_single_pass`, make one assembly without a reusable pattern. Indices are int32 (6m + n < 2^31).
"""
from __future__ import annotations

import numpy as np


# ----------------------------------------------------------------------------------------
# Fast cotangent assembly: a sparsity pattern built once per connectivity, then a single
# numeric pass over the faces that writes straight into the CSR value array.
# ----------------------------------------------------------------------------------------
_OFF = 1 << 31


def _pattern_kernel(F0, n):
    """CSR pattern of the mesh Laplacian (edges + diagonal) and the slot of every entry.

    The faces are first reordered by their smallest vertex (a counting sort, ``Fp``), so that
    the numeric pass, which follows ``Fp``, updates the CSR rows nearly in order. Entry
    ``e = 6 f + k`` (k = 0..2) is the directed edge of face ``Fp[f]`` opposite corner k,
    ``Fp[f, k+1] -> Fp[f, k+2]``; ``e = 6 f + k + 3`` is its reverse. Returns
    ``indptr (n+1), indices (nnz), slot (m, 6) int32, diag (n) int32, Fp (m, 3)`` where
    ``slot[f, k]`` / ``diag[i]`` is the index into the CSR value array of that entry / of
    ``(i, i)`` (int32: the numeric pass is memory-bound, so its index streams are kept small;
    the caller falls back to the numpy assembly beyond 2^31 entries). Empty arrays when a
    face index lies outside [0, n).
    """
    m = F0.shape[0]
    first = np.zeros(n + 1, np.int64)
    for f in range(m):
        lo = min(F0[f, 0], F0[f, 1], F0[f, 2])
        if lo < 0 or max(F0[f, 0], F0[f, 1], F0[f, 2]) >= n:     # empty arrays: out of range
            return (np.empty(0, np.int64), np.empty(0, np.int32), np.empty((0, 6), np.int32),
                    np.empty(0, np.int32), np.empty((0, 3), np.int64))
        first[lo + 1] += 1
    for i in range(n):
        first[i + 1] += first[i]
    F = np.empty((m, 3), np.int64)
    for f in range(m):
        lo = min(F0[f, 0], F0[f, 1], F0[f, 2])
        p = first[lo]
        first[lo] += 1
        F[p, 0], F[p, 1], F[p, 2] = F0[f, 0], F0[f, 1], F0[f, 2]
    start = np.zeros(n + 1, np.int64)
    for f in range(m):
        for c in range(3):
            start[F[f, c] + 1] += 2        # each corner vertex starts two directed entries
    for i in range(n):
        start[i + 1] += start[i] + 1       # and each row holds its diagonal
    fill = start[:-1].copy()
    # one key per entry, sorted within its row: column << 32 | (entry id + 2^31), the entry id
    # being -1 - i for the diagonal of row i
    key = np.empty(start[n], np.int64)
    for i in range(n):
        key[fill[i]] = (i << 32) | (_OFF - 1 - i)
        fill[i] += 1
    for f in range(m):
        for k in range(3):
            a = F[f, (k + 1) % 3]
            b = F[f, (k + 2) % 3]
            e = 6 * f + k
            key[fill[a]] = (b << 32) | (_OFF + e)
            fill[a] += 1
            key[fill[b]] = (a << 32) | (_OFF + e + 3)
            fill[b] += 1
    slot = np.empty((m, 6), np.int32)
    diag = np.empty(n, np.int32)
    indptr = np.empty(n + 1, np.int64)
    indices = np.empty(start[n], np.int32)
    out = 0
    indptr[0] = 0
    low = (1 << 32) - 1
    for i in range(n):
        s, t = start[i], start[i + 1]
        if t - s > 32:
            key[s:t] = key[s:t][np.argsort(key[s:t], kind="mergesort")]
        for p in range(s + 1, t):          # insertion sort of the (short) row
            x = key[p]
            q = p - 1
            while q >= s and key[q] > x:
                key[q + 1] = key[q]
                q -= 1
            key[q + 1] = x
        prev = -1
        for p in range(s, t):
            col = key[p] >> 32
            if col != prev:
                indices[out] = col
                prev = col
                out += 1
            e = (key[p] & low) - _OFF
            if e < 0:
                diag[-1 - e] = out - 1
            else:
                slot[e // 6, e % 6] = out - 1
        indptr[i + 1] = out
    return indptr, indices[:out].copy(), slot, diag, F


def _face_terms(V, i0, i1, i2, want_mass):
    """Half cotangent weights and mixed Voronoi corner areas of face (i0, i1, i2).

    ``w_k = cot(angle at corner k) / 2`` belongs to the edge opposite corner k; ``a_k`` is
    corner k's share of the face area (Meyer et al. 2003: circumcentric part
    ``(|e_j|^2 cot_j + |e_l|^2 cot_l) / 8`` on non-obtuse faces; area/2 at an obtuse corner
    and area/4 at the others), zero unless ``want_mass``. A zero-area face gives zeros
    (the policy of `corner_cotangents` / `voronoi_areas`).
    """
    # edge vectors opposite corner k: e0 = p2 - p1, e1 = p0 - p2, e2 = p1 - p0
    e0x = V[i2, 0] - V[i1, 0]
    e0y = V[i2, 1] - V[i1, 1]
    e0z = V[i2, 2] - V[i1, 2]
    e1x = V[i0, 0] - V[i2, 0]
    e1y = V[i0, 1] - V[i2, 1]
    e1z = V[i0, 2] - V[i2, 2]
    e2x = V[i1, 0] - V[i0, 0]
    e2y = V[i1, 1] - V[i0, 1]
    e2z = V[i1, 2] - V[i0, 2]
    cx = e1y * e2z - e1z * e2y
    cy = e1z * e2x - e1x * e2z
    cz = e1x * e2y - e1y * e2x
    dbl = np.sqrt(cx * cx + cy * cy + cz * cz)
    if dbl > 0.0:
        c0 = -(e1x * e2x + e1y * e2y + e1z * e2z) / dbl
        c1 = -(e2x * e0x + e2y * e0y + e2z * e0z) / dbl
        c2 = -(e0x * e1x + e0y * e1y + e0z * e1z) / dbl
    else:
        c0 = 0.0
        c1 = 0.0
        c2 = 0.0
    a0 = 0.0
    a1 = 0.0
    a2 = 0.0
    if want_mass:
        if c0 < 0.0 or c1 < 0.0 or c2 < 0.0:
            a = dbl / 2.0
            a0 = a / 2.0 if c0 < 0.0 else a / 4.0
            a1 = a / 2.0 if c1 < 0.0 else a / 4.0
            a2 = a / 2.0 if c2 < 0.0 else a / 4.0
        else:
            s0 = e0x * e0x + e0y * e0y + e0z * e0z
            s1 = e1x * e1x + e1y * e1y + e1z * e1z
            s2 = e2x * e2x + e2y * e2y + e2z * e2z
            a0 = (s1 * c1 + s2 * c2) / 8.0
            a1 = (s2 * c2 + s0 * c0) / 8.0
            a2 = (s0 * c0 + s1 * c1) / 8.0
    return 0.5 * c0, 0.5 * c1, 0.5 * c2, a0, a1, a2


def _numeric_kernel(V, F, slot, diag, indptr, nnz, want_mass):
    """Cotangent weights into the CSR values of a `CotanPattern`, and mixed Voronoi areas;
    one pass over the faces (`_face_terms`)."""
    m = F.shape[0]
    n = V.shape[0]
    data = np.zeros(nnz, np.float64)
    area = np.zeros(n if want_mass else 0, np.float64)
    for f in range(m):
        i0, i1, i2 = F[f, 0], F[f, 1], F[f, 2]
        w0, w1, w2, a0, a1, a2 = _face_terms(V, i0, i1, i2, want_mass)
        data[slot[f, 0]] += w0
        data[slot[f, 3]] += w0
        data[slot[f, 1]] += w1
        data[slot[f, 4]] += w1
        data[slot[f, 2]] += w2
        data[slot[f, 5]] += w2
        if want_mass:
            area[i0] += a0
            area[i1] += a1
            area[i2] += a2
    # diagonal = minus the row's off-diagonal sum: one sequential pass over the rows (cheaper
    # than three random read-modify-writes per face)
    for i in range(n):
        d = diag[i]
        acc = 0.0
        for p in range(indptr[i], indptr[i + 1]):
            if p != d:
                acc += data[p]
        data[d] = -acc
    return data, area


def _sort_pairs(bc, bv, k):
    """Sort the first k (column, value) pairs of ``bc``, ``bv`` by column, in place
    (insertion sort for the usual short rows, a merge sort beyond 32 pairs)."""
    if k <= 32:
        for p in range(1, k):
            x = bc[p]
            y = bv[p]
            q = p - 1
            while q >= 0 and bc[q] > x:
                bc[q + 1] = bc[q]
                bv[q + 1] = bv[q]
                q -= 1
            bc[q + 1] = x
            bv[q + 1] = y
    else:
        o = np.argsort(bc[:k], kind="mergesort")
        c = bc[:k][o]
        v = bv[:k][o]
        bc[:k] = c
        bv[:k] = v


def _sweep_kernel(V, F0, n, want_mass, first, pstart, F, pcol, pval, area, uptr, ucol, uval, lcnt):
    """The upper triangle of ``W`` (rows ``uptr``, columns ``ucol``, values ``uval``), the count of
    lower entries per column (``lcnt``) and mixed Voronoi areas (``area``), for one assembly
    without a reusable pattern. Returns the number of upper entries, or -1 (before any write by
    face index) when an index lies outside [0, n).

    The faces are sorted by their smallest vertex (counting sort into ``F``). Then one sweep over
    the rows i = 0, 1, ... builds the upper triangle (columns j > i) row by row: the faces whose
    smallest vertex is i give their two edges at i directly, and their third edge (j, k),
    i < j < k, is appended to row j's pending list (``pcol``, ``pval``), complete by the time row
    j is reached. The row's pairs (column, half weight, `_face_terms`) are sorted and equal
    columns summed; corner areas are added on the way. Edges with equal ends (degenerate faces)
    are skipped: their weight is zero and the diagonal is recomputed anyway.

    Work arrays come from the caller (`_single_pass`): ``first``, ``pstart`` (n + 1), ``lcnt`` (n)
    and ``area`` (n, or 0 when not ``want_mass``) zeroed; ``F`` (m, 3), ``pcol``, ``pval`` (m: a
    face has at most one edge away from its smallest vertex), ``uptr`` (n + 1), ``ucol``, ``uval``
    (3m) uninitialised. Requires 6m + n < 2^31 (int32 counters).
    """
    m = F0.shape[0]
    bad = 0
    for f in range(m):
        a, b, c = F0[f, 0], F0[f, 1], F0[f, 2]
        lo = min(a, b, c)
        bad |= lo | (n - 1 - max(a, b, c))          # negative iff an index is out of [0, n)
        first[min(max(lo, -1), n - 1) + 1] += 1     # clamped: in bounds either way
        if a != lo and b != lo and a != b:          # the edge away from lo (if any): its smaller end
            j = min(a, b)
        elif b != lo and c != lo and b != c:
            j = min(b, c)
        elif c != lo and a != lo and c != a:
            j = min(c, a)
        else:
            continue
        pstart[min(max(j, -1), n - 1) + 1] += 1
    if bad < 0:
        return -1
    longest = 0
    for i in range(n):
        longest = max(longest, 2 * first[i + 1] + pstart[i + 1])
        first[i + 1] += first[i]
        pstart[i + 1] += pstart[i]
    for f in range(m):
        a, b, c = F0[f, 0], F0[f, 1], F0[f, 2]
        lo = min(a, b, c)
        p = first[lo]
        first[lo] = p + 1                           # ends as the end of row lo's faces
        F[p, 0] = a
        F[p, 1] = b
        F[p, 2] = c
    bc = np.empty(longest + 1, np.int64)
    bv = np.empty(longest + 1, np.float64)
    uptr[0] = 0
    out = 0
    f0 = 0
    ps = 0
    for i in range(n):
        k = 0
        for f in range(f0, first[i]):
            i0, i1, i2 = F[f, 0], F[f, 1], F[f, 2]
            w0, w1, w2, a0, a1, a2 = _face_terms(V, i0, i1, i2, want_mass)
            for e in range(3):
                if e == 0:
                    a, b, w = i1, i2, w0
                elif e == 1:
                    a, b, w = i2, i0, w1
                else:
                    a, b, w = i0, i1, w2
                if a == b:
                    continue
                lo, hi = min(a, b), max(a, b)
                if lo == i:
                    bc[k] = hi
                    bv[k] = w
                    k += 1
                else:
                    p = pstart[lo]
                    pstart[lo] = p + 1
                    pcol[p] = hi
                    pval[p] = w
            if want_mass:
                area[i0] += a0
                area[i1] += a1
                area[i2] += a2
        f0 = first[i]
        for p in range(ps, pstart[i]):
            bc[k] = pcol[p]
            bv[k] = pval[p]
            k += 1
        ps = pstart[i]
        _sort_pairs(bc, bv, k)
        o = out - 1
        for p in range(k):
            if o >= out and ucol[o] == bc[p]:
                uval[o] += bv[p]
            else:
                o += 1
                ucol[o] = bc[p]
                uval[o] = bv[p]
                lcnt[bc[p]] += 1
        out = o + 1
        uptr[i + 1] = out
    return out


def _rows_kernel(uptr, ucol, uval, lcnt, indptr, indices, data, lfill):
    """Full CSR rows of ``W`` from its upper triangle (`_sweep_kernel`), into ``indptr`` (n + 1),
    ``indices``, ``data`` (2 * upper + n) and the work array ``lfill`` (n).

    Row i is its lower part (``(i, j)`` for j < i, placed while row j was written, hence in
    column order), the diagonal (minus the row's off-diagonal sum) and its upper part. Every
    mesh edge and every diagonal has an entry (explicit zeros where weights cancel), as in
    `CotanPattern`.
    """
    n = lcnt.size
    indptr[0] = 0
    for i in range(n):
        indptr[i + 1] = indptr[i] + lcnt[i] + 1 + (uptr[i + 1] - uptr[i])
        lfill[i] = indptr[i]
    for i in range(n):
        d = lfill[i]                      # row i's lower part is complete
        acc = 0.0
        for p in range(indptr[i], d):
            acc += data[p]
        o = d + 1
        for p in range(uptr[i], uptr[i + 1]):
            j = ucol[p]
            w = uval[p]
            indices[o] = j
            data[o] = w
            o += 1
            acc += w
            q = lfill[j]
            lfill[j] = q + 1
            indices[q] = i
            data[q] = w
        indices[d] = i
        data[d] = -acc


def _single_pass(V, F, n, want_mass):
    """``(indptr, indices, data, area)`` of one assembly (`_sweep_kernel`, `_rows_kernel`), or
    None when a face index lies outside [0, n).

    The arrays are allocated here, by numpy, rather than inside the compiled code: numpy asks
    the kernel for transparent huge pages on large blocks, which makes first touching them
    several times cheaper than numba's 4 KiB pages (the assembly writes ~100 bytes per face).
    """
    m = F.shape[0]
    first = np.zeros(n + 1, np.int32)
    pstart = np.zeros(n + 1, np.int32)
    lcnt = np.zeros(n, np.int32)
    area = np.zeros(n if want_mass else 0, np.float64)
    uptr = np.empty(n + 1, np.int32)
    ucol = np.empty(3 * m, np.int32)
    uval = np.empty(3 * m, np.float64)
    Fs = np.empty((m, 3), np.int32)
    pcol = np.empty(m, np.int32)
    pval = np.empty(m, np.float64)
    out = _kernel("_sweep_kernel")(V, F, n, want_mass, first, pstart, Fs, pcol, pval, area, uptr, ucol, uval, lcnt)
    if out < 0:
        return None
    del first, pstart, Fs, pcol, pval
    nnz = 2 * out + n
    indptr = np.empty(n + 1, np.int32)
    indices = np.empty(nnz, np.int32)
    data = np.empty(nnz, np.float64)
    _kernel("_rows_kernel")(uptr, ucol, uval, lcnt, indptr, indices, data, np.empty(n, np.int32))
    return indptr, indices, data, area


_KERNELS: dict = {}


def _kernel(name: str):
    """The numba-compiled kernel ``name`` (compiled lazily so that importing this module does
    not import numba; ``cache=True``: compiled once per machine, ~2-4 s, then loaded from
    ``__pycache__`` in ~0.1 s). Without numba, the plain Python function (slow)."""
    if name not in _KERNELS:
        func = globals()[name]
        try:
            from numba import njit
        except ImportError:  # pragma: no cover - numba is a project dependency
            _KERNELS[name] = func
        else:
            g = globals()
            for callee in ("_face_terms", "_sort_pairs"):   # callees are compiled first
                if not hasattr(g[callee], "py_func"):
                    g[callee] = njit(cache=True, nogil=True, inline="always")(g[callee])
            _KERNELS[name] = njit(cache=True, nogil=True)(func)
    return _KERNELS[name]
