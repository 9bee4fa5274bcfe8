"""Vectorized triangle-mesh primitives.

Conventions: ``V`` (n, 3) float64, ``F`` (m, 3) integer indices. Corner ``k`` of face ``f`` is
``F[f, k]``; the edge *opposite* corner ``k`` joins ``F[f, k+1]`` and ``F[f, k+2]`` (indices
mod 3). Lengths are in the mesh's units, areas in units squared. Normals follow the right-hand
rule (counter-clockwise corners give an outward normal on a consistently oriented closed mesh).

Undirected edges are identified by the int64 key ``min(i, j) * n + max(i, j)``; sorting keys
(rather than ``np.unique(axis=0)`` on index pairs) keeps edge extraction linear-time in practice.
"""
from __future__ import annotations

import numpy as np

# ----------------------------------------------------------------------------- edges

COMPILED_EDGES_FROM = 20_000     # faces; below, numpy's key sort (no numba import)


def _half_edges(F: np.ndarray) -> np.ndarray:
    """(3m, 2) vertex pairs of the half-edges (edge opposite corner 2, 0, 1 of each face)."""
    F = np.asarray(F, dtype=np.int64)
    return np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])


def edge_keys(F: np.ndarray, n: int | None = None) -> tuple[np.ndarray, int]:
    """Undirected int64 key per half-edge, ``min * n + max``, and the ``n`` used."""
    E = _half_edges(F)
    n = int(E.max()) + 1 if n is None else int(n)
    lo, hi = np.minimum(E[:, 0], E[:, 1]), np.maximum(E[:, 0], E[:, 1])
    return lo * n + hi, n


def repeated_half_edges(F: np.ndarray) -> int:
    """How many directed edges ``(i, j)`` occur in more than one face. 0 exactly when every edge
    has at most one face on each side: the mesh is edge-manifold and consistently oriented
    (two faces on one edge must traverse it in opposite directions)."""
    if len(F) == 0:
        return 0
    E = _half_edges(F)
    n = int(E.max()) + 1
    keys = np.sort(E[:, 0] * n + E[:, 1])
    dup = keys[1:] == keys[:-1]                           # a key equal to the one before it
    return int(np.count_nonzero(dup & ~np.r_[False, dup[:-1]]))    # the first repeat of each key


def orientation_problem(F: np.ndarray) -> str | None:
    """What `repeated_half_edges` finds, in words (None when it finds nothing): the shared start
    of the messages of the inputs that need consistently oriented edge-manifold faces."""
    k = repeated_half_edges(F)
    return (f"{k} directed edge(s) in more than one face (faces not consistently oriented, or an edge of more "
            "than two faces)") if k else None


def edge_face_counts(F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unique undirected edges (e, 2) (``E[:, 0] < E[:, 1]``, lexicographic order) and the
    number of faces using each (e,)."""
    if len(F) == 0:
        return np.zeros((0, 2), np.int64), np.zeros(0, np.int64)
    if len(F) >= COMPILED_EDGES_FROM:
        from ._edges_kernel import edges_and_counts
        F = np.ascontiguousarray(F, dtype=np.int64)
        return edges_and_counts(F, int(F.max()) + 1)
    keys, n = edge_keys(F)
    keys = np.sort(keys)
    start = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]])
    counts = np.diff(np.r_[start, keys.size])
    u = keys[start]
    return np.stack([u // n, u % n], axis=1), counts


def warm() -> None:
    """Load (or compile) the compiled edge extraction and face screen once, e.g. in a driver
    before it forks."""
    from ._edges_kernel import edges_and_counts, fan_counts
    from ._faces_kernel import near_degenerate
    edges_and_counts(np.array([[0, 1, 2]], dtype=np.int64), 3)
    fan_counts(np.array([[0, 1, 2]], dtype=np.int64), 3)
    near_degenerate(np.eye(3), np.array([[0, 1, 2]], dtype=np.int64), 1e-5)


def unique_edges(F: np.ndarray) -> np.ndarray:
    """Undirected edges (e, 2) int64 with ``E[:, 0] < E[:, 1]``, sorted lexicographically."""
    return edge_face_counts(F)[0]


def boundary_vertices(F: np.ndarray, n: int) -> np.ndarray:
    """Boolean mask (n,) of vertices on an edge that belongs to exactly one face."""
    E, counts = edge_face_counts(F)
    mask = np.zeros(int(n), dtype=bool)
    mask[E[counts == 1].ravel()] = True
    return mask


def mean_edge_length(V: np.ndarray, F: np.ndarray) -> float:
    """Mean length of the unique undirected edges of ``(V, F)``."""
    E = unique_edges(F)
    return float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).mean())


# ----------------------------------------------------------------------------- faces


def cross_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross products (k, 3) of (k, 3) arrays: the operations of ``np.cross`` (same
    values bit for bit) without its axis shuffling and temporaries."""
    a0, a1, a2 = a[:, 0], a[:, 1], a[:, 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    out = np.empty((len(a), 3), dtype=np.result_type(a, b))
    np.multiply(a1, b2, out=out[:, 0])
    out[:, 0] -= a2 * b1
    np.multiply(a2, b0, out=out[:, 1])
    out[:, 1] -= a0 * b2
    np.multiply(a0, b1, out=out[:, 2])
    out[:, 2] -= a1 * b0
    return out


def face_cross(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """``(v1 - v0) x (v2 - v0)`` per face (m, 3): twice the area times the unit normal."""
    p0 = V[F[:, 0]]
    return cross_rows(V[F[:, 1]] - p0, V[F[:, 2]] - p0)


def double_areas(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Twice the area of each face (m,): ``|(v1 - v0) x (v2 - v0)|``."""
    return np.linalg.norm(face_cross(V, F), axis=1)


def face_normals(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Unit face normals (m, 3) by the right-hand rule; zero rows for zero-area faces."""
    N = face_cross(V, F)
    nrm = np.linalg.norm(N, axis=1, keepdims=True)
    return np.divide(N, nrm, out=np.zeros_like(N), where=nrm > 0)


def vertex_normals(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals (n, 3): the normalised sum of the incident faces'
    cross products; zero for vertices with no area around them."""
    C = face_cross(V, F)
    idx = np.asarray(F).ravel()
    N = np.stack([np.bincount(idx, weights=np.repeat(C[:, j], 3), minlength=len(V)) for j in range(3)], 1)
    nrm = np.linalg.norm(N, axis=1, keepdims=True)
    return np.divide(N, nrm, out=np.zeros_like(N), where=nrm > 0)


def area(V: np.ndarray, F: np.ndarray) -> float:
    """Total surface area ``sum_f |(v1 - v0) x (v2 - v0)| / 2``."""
    return float(double_areas(V, F).sum() / 2)


def volume(V: np.ndarray, F: np.ndarray) -> float:
    """Signed enclosed volume by the divergence theorem, ``sum_f v0 . (v1 x v2) / 6``
    (meaningful for closed, consistently oriented meshes; positive for outward normals)."""
    return float(np.einsum("ij,ij->i", V[F[:, 0]], cross_rows(V[F[:, 1]], V[F[:, 2]])).sum() / 6.0)


def edge_lengths(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Corner-opposite edge lengths (m, 3): ``l[f, c] = |V[F[f, c+1]] - V[F[f, c+2]]|``."""
    p0, p1, p2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    return np.stack([np.linalg.norm(p2 - p1, axis=1), np.linalg.norm(p0 - p2, axis=1),
                     np.linalg.norm(p1 - p0, axis=1)], axis=1)


def cotangents_from_lengths(l: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Corner cotangents (m, 3) and double areas (m,) from corner-opposite edge lengths.

    ``cot_c = (l_{c+1}^2 + l_{c+2}^2 - l_c^2) / (4 A)``; the area by Kahan's stable Heron
    formula. Zero-area faces get cotangent 0 (they contribute no weight).
    """
    s = -np.sort(-l, axis=1)            # descending
    x, y, z = s[:, 0], s[:, 1], s[:, 2]
    p = (x + (y + z)) * (z - (x - y)) * (z + (x - y)) * (x + (y - z))
    ar = 0.25 * np.sqrt(np.maximum(p, 0.0))
    sq = l * l
    num = np.stack([sq[:, 1] + sq[:, 2] - sq[:, 0], sq[:, 2] + sq[:, 0] - sq[:, 1],
                    sq[:, 0] + sq[:, 1] - sq[:, 2]], axis=1)
    ok = ar > 0
    C = np.where(ok[:, None], num / np.where(ok, 4.0 * ar, 1.0)[:, None], 0.0)
    return C, 2.0 * ar


def corner_cotangents(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cotangent of each corner angle (m, 3) and the face double areas (m,).

    ``cot = (a . b) / |a x b|`` for the two edge vectors leaving the corner. Faces of zero area
    get cotangent 0 (PMP's clamped-weight policy, which keeps W finite).
    """
    p0, p1, p2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    e0, e1, e2 = p2 - p1, p0 - p2, p1 - p0          # edge opposite corner k
    dbl = np.linalg.norm(cross_rows(e1, e2), axis=1)
    dots = np.stack([-(e1 * e2).sum(1), -(e2 * e0).sum(1), -(e0 * e1).sum(1)], axis=1)
    safe = np.where(dbl > 0, dbl, 1.0)
    C = np.where((dbl > 0)[:, None], dots / safe[:, None], 0.0)
    return C, dbl


def corner_angles(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Interior angle at each corner (m, 3), in degrees, via atan2(|a x b|, a . b).

    A corner with a zero-length edge has angle 0 (``a . b`` is taken as +0, never -0, so the
    angle does not depend on the signs of the other edge's coordinates)."""
    out = np.empty((len(F), 3))
    for k in range(3):
        a = V[F[:, (k + 1) % 3]] - V[F[:, k]]
        b = V[F[:, (k + 2) % 3]] - V[F[:, k]]
        dot = (a * b).sum(1) + 0.0                    # -0.0 + 0.0 == +0.0
        out[:, k] = np.degrees(np.arctan2(np.linalg.norm(cross_rows(a, b), axis=1), dot))
    return out


def vertex_components(F: np.ndarray, n: int) -> np.ndarray:
    """Connected-component label (n,) of each of the n vertices, vertices joined by the faces'
    edges (a vertex in no face is a component of its own)."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components
    F = np.asarray(F, dtype=np.int64)
    a, b = F.ravel(), F[:, [1, 2, 0]].ravel()
    G = sp.coo_matrix((np.ones(len(a), np.int8), (a, b)), shape=(n, n))
    return connected_components(G, directed=False)[1]


def zero_area_faces(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Indices of faces with zero area by the cross product or by Kahan's Heron formula on the
    edge lengths (a numerically flat face can have a cross-product double area of 1e-20 and a
    Heron area of exactly 0, which is how libigl measures it).

    From `COMPILED_EDGES_FROM` faces, a compiled screen first keeps the faces whose cross product
    is at most 1e-5 of their longest squared edge L^2 (`_faces_kernel.near_degenerate`), and both
    measures are taken on those only; the result is the same. Outside the screen the height over
    the longest edge exceeds 1e-5 L, so the cross product (error ~1e-16 L^2) is far from 0, and
    so is Heron's area: its least stable factor, ``y + z - x`` for the longest edge x, is at least
    2 h^2 / L = 2e-10 L there, against rounding in the lengths of ~1e-15 L.

    Both are measured in float64 (``V`` is converted). A face index outside [-n, n) is an
    IndexError, as in numpy indexing.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    n = V.shape[0]
    shaped = F.ndim == 2 and F.shape[1] == 3 and V.ndim == 2 and V.shape[1] == 3
    if shaped and F.shape[0] >= COMPILED_EDGES_FROM:
        lo, hi = int(F.min()), int(F.max())
        if lo < -n or hi >= n:          # the compiled screen reads V unchecked
            raise IndexError(f"face index {lo if lo < -n else hi} is out of bounds for {n} vertices")
        if lo < 0:
            F = np.where(F < 0, F + n, F)
        from ._faces_kernel import near_degenerate
        cand = near_degenerate(np.ascontiguousarray(V), np.ascontiguousarray(F), 1e-5)
        return cand[_zero_area(V, F[cand])]
    return np.flatnonzero(_zero_area(V, F))


def _zero_area(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    heron = cotangents_from_lengths(edge_lengths(V, F))[1]
    return (double_areas(V, F) == 0) | ~(heron > 0)


# ----------------------------------------------------------------------------- whole meshes


def referenced(F: np.ndarray, n: int) -> np.ndarray:
    """Boolean mask (n,) of the vertices some face uses."""
    used = np.zeros(int(n), dtype=bool)
    used[np.asarray(F).ravel()] = True
    return used


def compact(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Drop unreferenced vertices and reindex the faces: ``(V, F)`` as float64 (k, 3) and int64
    (l, 3); kept vertices stay in their original order."""
    V = np.ascontiguousarray(V, dtype=np.float64).reshape(-1, 3)
    F = np.ascontiguousarray(F, dtype=np.int64).reshape(-1, 3)
    used = referenced(F, V.shape[0])
    remap = np.cumsum(used) - 1
    return V[used], remap[F]


def sample_surface(V: np.ndarray, F: np.ndarray, n: int, seed: int = 0, return_faces: bool = False):
    """``n`` area-uniform random points (n, 3): faces drawn with probability proportional to
    area, points uniform in the face (barycentric (1 - sqrt(r1), sqrt(r1)(1 - r2), sqrt(r1) r2)).
    ``return_faces``: also the face (n,) of each point."""
    rng = np.random.default_rng(seed)
    dbl = double_areas(V, F)
    if n <= 0 or dbl.sum() <= 0:
        return (np.zeros((0, 3)), np.zeros(0, np.int64)) if return_faces else np.zeros((0, 3))
    f = rng.choice(len(F), size=n, p=dbl / dbl.sum())
    r1 = np.sqrt(rng.random(n))
    r2 = rng.random(n)
    a, b, c = 1 - r1, r1 * (1 - r2), r1 * r2
    P = a[:, None] * V[F[f, 0]] + b[:, None] * V[F[f, 1]] + c[:, None] * V[F[f, 2]]
    return (P, f) if return_faces else P


def face_around_vertex(F: np.ndarray, n: int) -> np.ndarray:
    """For each of ``n`` vertices one face (m) that uses it, -1 for a vertex in no face."""
    out = np.full(int(n), -1, np.int64)
    out[np.asarray(F).ravel()] = np.repeat(np.arange(len(F)), 3)
    return out


def _spread3(x: np.ndarray) -> np.ndarray:
    """Insert two zero bits between the low 21 bits of x (for 3-D Morton codes)."""
    x = x.astype(np.uint64) & np.uint64(0x1FFFFF)
    x = (x | (x << np.uint64(32))) & np.uint64(0x1F00000000FFFF)
    x = (x | (x << np.uint64(16))) & np.uint64(0x1F0000FF0000FF)
    x = (x | (x << np.uint64(8))) & np.uint64(0x100F00F00F00F00F)
    x = (x | (x << np.uint64(4))) & np.uint64(0x10C30C30C30C30C3)
    x = (x | (x << np.uint64(2))) & np.uint64(0x1249249249249249)
    return x


def morton_order(P: np.ndarray) -> np.ndarray:
    """Indices (k,) that sort the points P (k, 3) along a Morton (Z-order) curve over their
    bounding cube, 2^20 cells per axis (stable among equal codes): points near in space end up
    mostly near in the order."""
    P = np.asarray(P, dtype=np.float64)
    if len(P) == 0:
        return np.zeros(0, np.int64)
    lo = P.min(axis=0)
    ext = float((P.max(axis=0) - lo).max()) or 1.0
    g = np.minimum(((P - lo) / ext * (1 << 20)).astype(np.int64), (1 << 21) - 1)
    code = _spread3(g[:, 0]) | (_spread3(g[:, 1]) << np.uint64(1)) | (_spread3(g[:, 2]) << np.uint64(2))
    return np.argsort(code, kind="stable")


def bounding_box_diagonal(V: np.ndarray) -> float:
    """Length of the axis-aligned bounding box's diagonal."""
    return float(np.linalg.norm(V.max(0) - V.min(0)))
