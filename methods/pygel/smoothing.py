"""PyGEL3D smoothing adapters: ``laplacian_smooth``, ``taubin_smooth``, ``anisotropic_smooth``.

Vertex order: ``hmesh.Manifold.from_triangles`` does *not* keep the caller's vertex order
(measured: on bunny.off 3,482 of 3,485 rows move). Every adapter therefore maps the result back
through the faces, which PyGEL keeps in order (:func:`build_manifold`), so distinct vertices
at the same position (UV seams) keep their own results. Input vertices the manifold does not
contain (unreferenced ones) keep their position.

Formulas of GEL (``src/GEL/HMesh/smooth.cpp``), Jacobi-style (new positions from the old
ones). Measured on PyGEL3D 0.8.2 (tests/test_smoothing_xval.py): boundary vertices move too,
by the same uniform rule over all their neighbours (older GEL sources skip them):

``laplacian_smooth(m, w, n)``
    ``x_i <- x_i + w (mean of the 1-ring neighbours - x_i)``: exactly ``scratch.explicit``
    with uniform weights and ``step = w`` on any mesh (the vertex itself is not averaged in).
    ``w`` is passed as a C float (0.5, 0.25 exact).
``taubin_smooth(m, n)``
    ``n`` pairs of uniform steps with the fixed factors ``+0.5`` and ``-0.52``:
    ``scratch.taubin`` with ``lambda 0.5, mu -0.52``.
``anisotropic_smooth(m, sharpness, n)``
    Per iteration: face normals filtered with weights ``area * exp(angle-based Gaussian)``
    controlled by ``sharpness`` (0 = area-weighted average of the incident faces' normals),
    then faces rotated to the new normals and each vertex set to the mean of its rotated
    corners (Baerentzen's GEL notes; cf. Sun et al. 2007 vertex update).
"""
from __future__ import annotations

import numpy as np

from harness.core.geometry import referenced
from methods import Param, SmoothingResult, register


def _row_bits(X: np.ndarray) -> np.ndarray:
    """Rows of ``X`` (k, 3) as their 64-bit patterns (k, 3), -0.0 read as 0.0."""
    X = np.ascontiguousarray(X, dtype=np.float64) + 0.0   # -0.0 -> 0.0: keys compare values
    return X.view(np.uint64).reshape(-1, 3)


def _mix(x: np.ndarray) -> np.ndarray:
    """splitmix64's finalizer: every input bit moves about half of the output bits."""
    x = x ^ (x >> np.uint64(30))
    x = x * np.uint64(0xBF58476D1CE4E5B9)
    x ^= x >> np.uint64(27)
    x *= np.uint64(0x94D049BB133111EB)
    x ^= x >> np.uint64(31)
    return x


def _row_hash(bits: np.ndarray) -> np.ndarray:
    """64-bit hash of each row's three bit patterns, chained through `_mix` (coordinates with
    short mantissas, e.g. integers, differ in their high bits only)."""
    with np.errstate(over="ignore"):
        h = _mix(bits[:, 0] + np.uint64(0x9E3779B97F4A7C15))
        h = _mix(h ^ bits[:, 1])
        return _mix(h ^ bits[:, 2])


def match_rows(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """For each row of ``A`` the index of a bit-identical row of ``B`` (the first where ``B``
    repeats a row), or -1.

    Rows are looked up by a 64-bit hash of their bits (integer sorts) and every hit is verified
    bit for bit; a row whose hash meets an unequal row of ``B`` (a collision) is looked up again
    by exact comparison among the rows of that hash."""
    a, b = _row_bits(A), _row_bits(B)
    ha, hb = _row_hash(a), _row_hash(b)
    out = np.full(len(a), -1, np.int64)
    if not len(hb):
        return out
    order = np.argsort(hb)
    hs = hb[order]
    start = np.r_[True, hs[1:] != hs[:-1]]
    first = np.minimum.reduceat(order, np.flatnonzero(start))    # smallest index of each hash
    qa = np.argsort(ha)                   # queries in order: each search starts from the last
    pos = np.empty(len(a), np.int64)
    pos[qa] = np.minimum(np.searchsorted(hs, ha[qa]), len(hs) - 1)
    cand = first[np.cumsum(start)[pos] - 1]
    same_hash = hs[pos] == ha
    exact = same_hash & (b[cand] == a).all(axis=1)
    out[exact] = cand[exact]
    doubt = np.flatnonzero(same_hash & ~exact)
    if doubt.size:                        # rare: exact lookup among the rows of equal hash
        for i in doubt:
            lo, hi = np.searchsorted(hs, ha[i], "left"), np.searchsorted(hs, ha[i], "right")
            rows = order[lo:hi]
            eq = rows[(b[rows] == a[i]).all(axis=1)]
            if eq.size:
                out[i] = eq.min()
    return out


def build_manifold(V: np.ndarray, F: np.ndarray):
    """``(manifold, index)``: ``index[i]`` is the manifold vertex holding input vertex ``i``
    (-1 when absent).

    ``from_triangles`` keeps the faces in order (each up to a rotation of its corners), so the
    map is read through the faces: corner k of face f is the manifold vertex at the rotation
    whose positions equal the input's. This is exact even where distinct input vertices share
    a position (UV seams). Only if the faces cannot be aligned (PyGEL dropped or reoriented
    some) does it fall back to matching exact coordinates.

    First, the cheap case: when matching exact coordinates pairs input vertices one to one with
    all of the manifold's vertices, every referenced input vertex among them, that pairing is
    the map (no two of those vertices share a position, so it is the one the faces give); the
    faces are read back (an OFF round trip, the slow part) only otherwise.
    """
    from pygel3d import hmesh

    from methods.pygel import triangles
    m = hmesh.Manifold.from_triangles(V, F)
    P0 = np.array(m.positions(), dtype=np.float64, copy=True)
    index = match_rows(V, P0)
    hit = index[index >= 0]
    used = referenced(F, len(V))
    if (hit.size == len(P0) and (index[used] >= 0).all()
            and np.bincount(hit, minlength=len(P0)).max(initial=0) <= 1):
        return m, index
    try:
        G = triangles(m)
    except RuntimeError:
        G = None
    if G is not None and G.shape == F.shape and G.size and G.max() < len(P0):
        cols = [(np.arange(3) + r) % 3 for r in range(3)]
        err = np.stack([np.abs(P0[G[:, c]] - V[F]).max(axis=(1, 2)) for c in cols], axis=1)
        r = err.argmin(axis=1)
        if np.all(err[np.arange(len(F)), r] == 0):
            Gr = G[np.arange(len(F))[:, None], (np.arange(3)[None, :] + r[:, None]) % 3]
            index = np.full(len(V), -1, dtype=np.int64)
            index[F.ravel()] = Gr.ravel()
            return m, index
    return m, match_rows(V, P0)


def to_caller_order(V: np.ndarray, m, index: np.ndarray) -> np.ndarray:
    """New positions of ``m`` in the caller's vertex order (absent vertices keep ``V``)."""
    P = np.array(m.positions(), dtype=np.float64, copy=True)
    out = V.copy()
    ok = index >= 0
    out[ok] = P[index[ok]]
    return out


# PyGEL3D 0.8.2's laplacian_smooth divides by zero (SIGFPE, the process dies) on meshes with
# fewer than 8 vertices (octahedron, 7-vertex fan): found by tests/test_bad_input.py.
MIN_VERTICES_LAPLACIAN = 8


@register("pygel.laplacian", task="smoothing", library="pygel3d", requires=("pygel3d",),
          params={"step": Param("step", 0.25, "float", low=0.0, high=10.0,
                                doc="GEL's weight w: x += w (neighbour mean - x)"),
                  "iterations": Param("iterations", 10, "int", low=0, high=100000)})
def laplacian(V, F, *, step=0.25, iterations=10):
    """PyGEL3D ``hmesh.laplacian_smooth(m, w=step, no_iters=iterations)``.

    Uniform umbrella step on every vertex (module docstring). The shared
    ``step`` is GEL's weight ``w`` (row-normalized operator: the same meaning as
    ``scratch.explicit``'s uniform step).
    """
    from pygel3d import hmesh
    n_used = int(referenced(F, len(V)).sum())
    if n_used < MIN_VERTICES_LAPLACIAN:
        raise ValueError(f"pygel.laplacian: PyGEL3D's laplacian_smooth dies with SIGFPE on meshes with "
                         f"fewer than {MIN_VERTICES_LAPLACIAN} vertices (this one has {n_used}); refused")
    m, index = build_manifold(V, F)
    if iterations > 0:
        hmesh.laplacian_smooth(m, float(step), int(iterations))
    return SmoothingResult(V=to_caller_order(V, m, index))


@register("pygel.taubin", task="smoothing", library="pygel3d", requires=("pygel3d",),
          params={"iterations": Param("iterations", 10, "int", low=0, high=100000,
                                      doc="number of (0.5, -0.52) step pairs")})
def taubin(V, F, *, iterations=10):
    """PyGEL3D ``hmesh.taubin_smooth(m, no_iters=iterations)``: fixed lambda 0.5, mu -0.52.

    Uniform weights; GEL exposes no lambda/mu.
    """
    from pygel3d import hmesh
    m, index = build_manifold(V, F)
    if iterations > 0:
        hmesh.taubin_smooth(m, int(iterations))
    return SmoothingResult(V=to_caller_order(V, m, index))


@register("pygel.anisotropic", task="smoothing", library="pygel3d", requires=("pygel3d",),
          params={"sharpness": Param("sharpness", 0.5, "float", low=0.0, high=100.0,
                                     doc="0: area-weighted normal average; larger: more "
                                         "feature-preserving (anisotropic)"),
                  "iterations": Param("iterations", 1, "int", low=0, high=1000)})
def anisotropic(V, F, *, sharpness=0.5, iterations=1):
    """PyGEL3D ``hmesh.anisotropic_smooth(m, sharpness, no_iters=iterations)``.

    Bilateral filtering of face normals followed by a rotation of the faces to the filtered
    normals; vertices move to the average of their rotated corners (module docstring).
    """
    from pygel3d import hmesh
    m, index = build_manifold(V, F)
    if iterations > 0:
        hmesh.anisotropic_smooth(m, float(sharpness), int(iterations))
    return SmoothingResult(V=to_caller_order(V, m, index))
