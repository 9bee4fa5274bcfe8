"""Bundled real meshes (package data) and procedural meshes with exact ground truth.

A mesh spec is a dict, the normalised form of a config entry:
``{"bundled": "bunny"}``, ``{"procedural": "sphere", "subdivisions": 4}``,
``{"file": "scan.obj"}`` or ``{"file": "noisy.obj", "clean": "clean.obj"}`` (optional ``name``: the
label in the ``mesh`` column; ``level``: the known noise level of a given pair).
`load(spec)` returns a `Source` (a copy; `cached(spec)` the shared one): the clean `Mesh` and, for
ready noisy/clean pairs, the noisy vertex positions (same count and order; no synthetic noise is
added to a pair).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from .core.geometry import compact, face_cross
from .errors import InvalidMeshError
from .mesh import Mesh, file_sha1, read_mesh, validate

DATA_DIR = Path(__file__).parent / "data" / "meshes"

# short name -> (file, description); every file stem is accepted too
BUNDLED = {
    "bunny": ("bunny.off", "Stanford bunny, decimated, closed"),
    "stanford-bunny": ("stanford-bunny.obj", "Stanford bunny scan, open (5 holes), 1,113 unreferenced vertices removed"),
    "fandisk": ("fandisk.obj", "Fandisk CAD part, closed, sharp features"),
    "armadillo": ("armadillo.obj", "Stanford armadillo, decimated, closed"),
    "camelhead": ("camelhead.off", "camel head, open (1 boundary loop)"),
    "fertility": ("fertility.off", "Fertility statue, closed, genus 4"),
    "max": ("decimated-max.obj", "Max Planck bust, decimated, poor triangles"),
    "knight": ("decimated-knight.off", "knight, decimated to 1k faces"),
    "woody": ("woody.obj", "Woody, open, small"),
    "spot": ("spot.obj", "Spot the cow, closed"),
}
# published noisy/clean pairs (Zhang et al. 2015, Guided mesh normal filtering)
PAIRS = {
    "fandisk-noisy-0.3": ("denoise/Fandisk0.3/Noisy.obj", "denoise/Fandisk0.3/Original.obj", 0.3,
                          "Fandisk with Gaussian noise 0.3 x mean edge length (Zhang et al. 2015)"),
    "sharpsphere-noisy-0.3": ("denoise/SharpSphere0.3/Noisy.obj", "denoise/SharpSphere0.3/Original.obj", 0.3,
                              "SharpSphere with Gaussian noise 0.3 x mean edge length (Zhang et al. 2015)"),
}
PROCEDURAL = {
    "sphere": {"subdivisions": 3, "radius": 1.0},
    "torus": {"R": 1.0, "r": 0.4, "resolution": 48},
    "plane_delaunay": {"n_points": 300, "seed": 0},
    "plane_nondelaunay": {"n_points": 300, "seed": 0, "flip_fraction": 0.3},
    "plane_skinny": {"n_points": 300, "seed": 0, "split_fraction": 0.5, "offset": 0.02},
    "cylinder": {"radius": 1.0, "height": 2.0, "resolution": 32},
    "ellipsoid": {"rx": 1.0, "ry": 0.75, "rz": 0.5, "subdivisions": 4},
    "saddle": {"a": 0.5, "n_points": 2000, "seed": 0},
    "sphere_random": {"n_points": 2000, "seed": 0, "radius": 1.0},
}
PROCEDURAL_BOUNDS = {
    "subdivisions": (0, 9), "radius": (1e-9, 1e9), "R": (1e-9, 1e9), "r": (1e-9, 1e9),
    "resolution": (3, 4096), "n_points": (4, 2_000_000), "seed": (0, 2**32 - 1),
    "flip_fraction": (0.0, 1.0), "height": (1e-9, 1e9), "a": (-1e6, 1e6), "rx": (1e-9, 1e9), "ry": (1e-9, 1e9),
    "rz": (1e-9, 1e9), "split_fraction": (0.0, 1.0), "offset": (1e-6, 1.0 / 3.0),
}


def bundled_names() -> list[str]:
    """Short names of bundled meshes and pairs, plus file stems that differ from them."""
    stems = [Path(f).stem for f, _ in BUNDLED.values() if Path(f).stem not in BUNDLED]
    return sorted(BUNDLED) + sorted(PAIRS) + sorted(stems)


def resolve_bundled(name: str) -> str | None:
    """Canonical short name for a bundled name or file stem, or None."""
    if name in BUNDLED or name in PAIRS:
        return name
    for short, (fname, _) in BUNDLED.items():
        if Path(fname).stem == name or fname == name:
            return short
    return None


def _spec_files(spec: dict) -> list[Path]:
    """The files a mesh spec reads (a bundled mesh's or pair's package files, a file mesh and its
    clean file); none for a procedural mesh."""
    if "procedural" in spec:
        return []
    if "bundled" in spec:
        name = resolve_bundled(spec["bundled"])
        return ([DATA_DIR / PAIRS[name][0], DATA_DIR / PAIRS[name][1]] if name in PAIRS
                else [DATA_DIR / BUNDLED[name][0]] if name in BUNDLED else [])
    return [Path(spec[k]) for k in ("file", "clean") if k in spec]


def content_keys(spec: dict) -> set[str]:
    """What a mesh spec is made of, whatever it is called: the sha1 of each file it reads and,
    prefixed ``faces:``, the faces (and vertex count) each holds, or, for a procedural mesh, its
    kind and parameters. Two specs sharing a key other than ``faces:`` share a surface; sharing a
    ``faces:`` key, they do when `same_surface` says so (`harness.config` refuses training on a
    test mesh by these)."""
    import json
    if "procedural" in spec:
        return {json.dumps({k: v for k, v in spec.items() if k != "name"}, sort_keys=True, default=str)}
    out = set()
    for f in _spec_files(spec):
        try:
            out.add(file_sha1(f))
        except OSError:            # already a problem of its own (file not found)
            continue
        got = _surface_of(f)
        if got is not None:
            out.add(got[0])
    return out


SURFACE_TOL = 1e-5     # vertices this close (fraction of the bounding-box diagonal) are the same surface


def same_surface(a: dict, b: dict) -> bool:
    """Whether two mesh specs hold one surface in some file of each: the same faces over their
    referenced vertices, and those vertices, centred and scaled to a unit bounding-box diagonal,
    within `SURFACE_TOL` times the larger of 1 and the coordinates' size in diagonals (rounding
    to six significant digits loses in proportion to a coordinate, not to the mesh): a re-save,
    another format keeping the vertex order, a moved or scaled copy, one with unused vertices
    (the harness's metrics and noise are scale-free, so a scaled copy is the same test).
    Reordered copies (an STL, whose reader welds and renumbers vertices) and remeshed ones differ."""
    sa = [x for x in (_surface_of(f) for f in _spec_files(a)) if x is not None]
    sb = [x for x in (_surface_of(f) for f in _spec_files(b)) if x is not None]
    return any(ka == kb and float(np.abs(va - vb).max(initial=0.0)) <= SURFACE_TOL * max(1.0, ra, rb)
               for ka, va, ra in sa for kb, vb, rb in sb)


def _surface_of(path) -> tuple[str, np.ndarray, float] | None:
    try:
        st = Path(path).stat()
    except OSError:
        return None
    return _surface(str(Path(path).resolve()), st.st_size, st.st_mtime_ns)


@functools.lru_cache(maxsize=8)       # a config's meshes are compared pairwise in one pass; each holds its vertices
def _surface(path: str, size: int, mtime_ns: int) -> tuple[str, np.ndarray, float] | None:
    """(``faces:`` key, referenced vertices centred and scaled to a unit bounding-box diagonal,
    the largest coordinate's size in diagonals) of a mesh file as read (unused vertices dropped,
    nothing else repaired), or None when it does not read (said elsewhere)."""
    import hashlib
    try:
        m = read_mesh(path, repair=False)
    except Exception:  # noqa: BLE001 - an unreadable file is a problem of its own
        return None
    F = np.asarray(m.F, dtype=np.int64)
    if not len(m.V) or not F.size or F.min() < 0 or F.max() >= len(m.V):
        return None
    V, F = compact(m.V, F)
    lo, hi = V.min(axis=0), V.max(axis=0)
    d = float(np.linalg.norm(hi - lo)) or 1.0
    if not np.isfinite(d):
        return None
    return (f"faces:{len(V)}:" + hashlib.sha1(F.tobytes()).hexdigest(), (V - (lo + hi) / 2) / d,
            float(np.abs(V).max()) / d)


@dataclass
class Source:
    """A clean mesh and, for a ready pair, the given noisy positions."""

    key: str                      # short label for the `mesh` column
    clean: Mesh
    noisy_V: np.ndarray | None = None
    pair_level: float | None = None
    shape: dict | None = None     # procedural meshes: {"procedural": kind, **all parameters}


def spec_key(spec: dict) -> str:
    """Readable label of a spec for the ``mesh`` column (stable across runs)."""
    if "name" in spec:
        return spec["name"]
    if "bundled" in spec:
        return spec["bundled"]
    if "procedural" in spec:
        defaults = PROCEDURAL.get(spec["procedural"], {})
        extra = ",".join(f"{k}={spec[k]}" for k in sorted(spec)
                         if k != "procedural" and spec[k] != defaults.get(k))
        return spec["procedural"] + (f"({extra})" if extra else "")
    return Path(spec["file"]).stem


def load(spec) -> Source:
    """The mesh a spec names, as a `Source` of its own: fresh arrays, so a caller (or a method it
    calls) that writes into them changes nothing else in the process."""
    src = cached(spec)
    m = src.clean
    clean = Mesh(m.V.copy(), m.F.copy(), m.name, None if m.vertex_map is None else m.vertex_map.copy(),
                 list(m.repairs))
    return replace(src, clean=clean, noisy_V=None if src.noisy_V is None else src.noisy_V.copy(),
                   shape=None if src.shape is None else dict(src.shape))


def cached(spec) -> Source:
    """The mesh a spec names, loaded once per process and shared by every case of the process
    (with its memoised facts, e.g. `Mesh.noise_frame`): never to be written into; `load` gives a
    copy."""
    if isinstance(spec, str):
        spec = {"bundled": spec}
    frozen = _freeze(spec)
    return _PRIMED[frozen] if frozen in _PRIMED else _load_cached(frozen)


_PRIMED: dict = {}      # Sources another process loaded for this one (`prime`), by frozen spec


def prime(spec: dict, source: Source) -> None:
    """Let `cached` answer ``spec`` with ``source``, loaded elsewhere (the run's driver reads mesh
    files in a child process of its own: `harness.executors.local`). At most 8 are kept."""
    if len(_PRIMED) >= 8:
        _PRIMED.pop(next(iter(_PRIMED)))
    _PRIMED[_freeze(spec)] = source


def _freeze(spec: dict):
    return tuple(sorted((k, tuple(v) if isinstance(v, list) else v) for k, v in spec.items()))


@functools.lru_cache(maxsize=8)
def _load_cached(frozen) -> Source:
    spec = dict(frozen)
    sha = {k: spec.pop(f"{k}_sha1", None) for k in ("file", "clean")}   # a case's files must still hold these bytes
    key = spec_key(spec)
    if "bundled" in spec:
        name = resolve_bundled(spec["bundled"])
        if name is None:
            raise InvalidMeshError(f"unknown bundled mesh {spec['bundled']!r}")
        if name in PAIRS:
            noisy, clean, level, _ = PAIRS[name]
            return _pair(key, DATA_DIR / noisy, DATA_DIR / clean, level)
        return Source(key, read_mesh(DATA_DIR / BUNDLED[name][0], name=name))
    if "procedural" in spec:
        kind = spec.pop("procedural")
        params = {**PROCEDURAL[kind], **spec}
        V, F = GENERATORS[kind](**params)
        return Source(key, validate(V, F, name=key), shape={"procedural": kind, **params})
    if "clean" in spec:
        return _pair(key, Path(spec["file"]), Path(spec["clean"]), spec.get("level"), sha["file"], sha["clean"])
    return Source(key, read_mesh(spec["file"], sha1=sha["file"]))


def _pair(key: str, noisy_path: Path, clean_path: Path, level, noisy_sha1=None, clean_sha1=None) -> Source:
    noisy = read_mesh(noisy_path, repair=False, sha1=noisy_sha1)
    raw = read_mesh(clean_path, repair=False, sha1=clean_sha1)
    if ".stl" in (noisy_path.suffix.lower(), clean_path.suffix.lower()):
        raise InvalidMeshError(f"{key}: an STL file cannot be half of a noisy/clean pair: STL stores every "
                               "triangle's corners apart and each file is welded by its own coordinates, so "
                               "the two halves' vertices cannot be matched; give both as OBJ, OFF or PLY")
    validated = validate(raw.V, raw.F, name=key)
    said = [*raw.repairs, *(f"noisy file: {r}" for r in noisy.repairs)]    # the readers' own (polygons split)
    clean = replace(validated, repairs=[*said, *validated.repairs])
    if validated.repairs and noisy.n_vertices == clean.n_vertices and np.array_equal(noisy.F, clean.F):
        return Source(key, clean, noisy_V=noisy.V, pair_level=level)       # the clean mesh's repaired layout
    also = (f" (or the clean mesh's {clean.n_vertices} after its repairs: {'; '.join(validated.repairs)})"
            if validated.repairs else "")
    if noisy.n_vertices != raw.n_vertices:
        raise InvalidMeshError(f"{key}: noisy ({noisy.n_vertices}) and clean ({raw.n_vertices}{also}) "
                               "vertex counts differ; a pair needs the same vertices in the same order")
    if noisy.n_faces != raw.n_faces or not np.array_equal(noisy.F, raw.F):
        raise InvalidMeshError(f"{key}: noisy and clean faces differ; a pair needs the same connectivity")
    return Source(key, clean, noisy_V=noisy.V[clean.vertex_map], pair_level=level)


# ----------------------------------------------------------------------------- procedural

def icosphere(subdivisions: int = 3, radius: float = 1.0):
    """Icosahedron subdivided ``subdivisions`` times (4x faces each), projected to the sphere.

    Faces: 20 * 4^s. Every vertex lies exactly (to rounding) on the sphere of ``radius``.
    """
    t = (1 + 5 ** 0.5) / 2
    V = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
                  [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], float)
    F = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
                  [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
                  [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]], np.int64)
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    for _ in range(int(subdivisions)):
        E = np.sort(np.concatenate([F[:, [1, 2]], F[:, [2, 0]], F[:, [0, 1]]]), axis=1)
        uniq, inv = np.unique(E, axis=0, return_inverse=True)
        mid = V[uniq[:, 0]] + V[uniq[:, 1]]
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        m = len(F)
        e = inv.ravel().reshape(3, m) + len(V)          # midpoint opposite corner k
        a, b, c = F[:, 0], F[:, 1], F[:, 2]
        F = np.concatenate([np.stack([a, e[2], e[1]], 1), np.stack([b, e[0], e[2]], 1),
                            np.stack([c, e[1], e[0]], 1), np.stack([e[0], e[1], e[2]], 1)])
        V = np.concatenate([V, mid])
    return V * radius, F


def torus(R: float = 1.0, r: float = 0.4, resolution: int = 48):
    """Torus of major radius R, minor radius r; ``resolution`` x ``resolution // 2`` quads split in two."""
    n, m = int(resolution), max(3, int(resolution) // 2)
    u, v = np.meshgrid(np.arange(n) * 2 * np.pi / n, np.arange(m) * 2 * np.pi / m, indexing="ij")
    V = np.stack([(R + r * np.cos(v)) * np.cos(u), (R + r * np.cos(v)) * np.sin(u), r * np.sin(v)], -1)
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    a = i * m + j
    b = ((i + 1) % n) * m + j
    c = ((i + 1) % n) * m + (j + 1) % m
    d = i * m + (j + 1) % m
    F = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return V.reshape(-1, 3), F.astype(np.int64)


def _plane_points(n_points: int, seed: int):
    rng = np.random.default_rng(int(seed))
    k = max(2, int(round(np.sqrt(n_points) / 2)))
    s = np.linspace(0, 1, k + 1)[:-1]
    border = np.concatenate([np.stack([s, 0 * s], 1), np.stack([1 + 0 * s, s], 1),
                             np.stack([1 - s, 1 + 0 * s], 1), np.stack([0 * s, 1 - s], 1)])
    # interior points keep one border spacing away from the sides, so the angle opposite a
    # boundary edge stays below 2 atan(1/2) = 53 degrees (no negative boundary cotangent)
    inner = rng.uniform(1.0 / k, 1 - 1.0 / k, size=(max(1, n_points - len(border)), 2))
    return np.concatenate([border, inner])


def plane_delaunay(n_points: int = 300, seed: int = 0):
    """Delaunay triangulation of seeded random points in the unit square (z = 0)."""
    from scipy.spatial import Delaunay
    P = _plane_points(n_points, seed)
    F = Delaunay(P).simplices.astype(np.int64)
    V = np.column_stack([P, np.zeros(len(P))])
    return V, _orient_up(V, F)


def _orient_up(V, F):
    n = face_cross(V, F)[:, 2]
    F = F.copy()
    F[n < 0] = F[n < 0][:, [0, 2, 1]]
    return F


def plane_nondelaunay(n_points: int = 300, seed: int = 0, flip_fraction: float = 0.3):
    """`plane_delaunay` with a seeded fraction of interior edges flipped.

    Only edges whose quad is strictly convex are flipped, and no two flipped edges share a
    face, so every flipped edge has opposite angles summing above pi (non-Delaunay) and the
    triangulation stays valid and planar.
    """
    V, F = plane_delaunay(n_points, seed)
    rng = np.random.default_rng(int(seed) + 1)
    m = len(F)
    he = np.concatenate([F[:, [1, 2]], F[:, [2, 0]], F[:, [0, 1]]])   # edge opposite corner k
    fid = np.tile(np.arange(m), 3)
    opp = np.concatenate([F[:, 0], F[:, 1], F[:, 2]])
    key = np.sort(he, axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    k_sorted = key[order]
    same = np.all(k_sorted[1:] == k_sorted[:-1], axis=1)
    h1, h2 = order[:-1][same], order[1:][same]                        # the two halves of interior edges
    sel = rng.permutation(len(h1))[: int(round(flip_fraction * len(h1)))]
    used = np.zeros(m, bool)
    F = F.copy()
    P = V[:, :2]

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    for s in sel:                       # a few hundred edges: generation, not a hot path
        a, b = h1[s], h2[s]
        f1, f2 = fid[a], fid[b]
        if used[f1] or used[f2]:
            continue
        p, q = he[a]
        x, y = opp[a], opp[b]
        # convex quad x-p-y-q: x and y on opposite sides of pq, p and q on opposite sides of xy
        if cross(P[p], P[q], P[x]) * cross(P[p], P[q], P[y]) >= 0:
            continue
        if cross(P[x], P[y], P[p]) * cross(P[x], P[y], P[q]) >= -1e-12:
            continue
        F[f1] = [x, p, y]
        F[f2] = [y, q, x]
        used[f1] = used[f2] = True
    return V, _orient_up(V, F)


def cylinder(radius: float = 1.0, height: float = 2.0, resolution: int = 32):
    """Open cylinder ``x^2 + y^2 = radius^2``, ``0 <= z <= height`` (two boundary circles).

    ``resolution`` vertices per ring; rings spaced so triangles are close to equilateral
    (alternate rings rotated by half a step). Every vertex lies exactly on the cylinder.
    K = 0, H = 1 / (2 radius) (outward normals), geodesics are straight lines once unrolled.
    """
    n = int(resolution)
    step = 2 * np.pi * radius / n
    rings = max(1, int(round(height / (step * np.sqrt(3) / 2))))
    j, i = np.meshgrid(np.arange(rings + 1), np.arange(n), indexing="ij")
    theta = (i + 0.5 * (j % 2)) * 2 * np.pi / n
    V = np.stack([radius * np.cos(theta), radius * np.sin(theta), j * height / rings], -1).reshape(-1, 3)
    j, i = np.meshgrid(np.arange(rings), np.arange(n), indexing="ij")
    a = j * n + i
    b = j * n + (i + 1) % n
    c = (j + 1) * n + i
    d = (j + 1) * n + (i + 1) % n
    even = (j % 2 == 0)
    # even rows: the ring above is shifted +half a step, so split quads along b-c; odd rows along a-d
    T1 = np.where(even[..., None], np.stack([a, b, c], -1), np.stack([a, b, d], -1))
    T2 = np.where(even[..., None], np.stack([b, d, c], -1), np.stack([a, d, c], -1))
    F = np.concatenate([T1.reshape(-1, 3), T2.reshape(-1, 3)]).astype(np.int64)
    return V, F


def ellipsoid(rx: float = 1.0, ry: float = 0.75, rz: float = 0.5, subdivisions: int = 4):
    """Ellipsoid with semi-axes rx, ry, rz: an icosphere scaled per axis (vertices exactly on it).

    ``x^2/rx^2 + y^2/ry^2 + z^2/rz^2 = 1``; the triangulation is the icosphere's, stretched.
    """
    V, F = icosphere(subdivisions, 1.0)
    return V * np.array([rx, ry, rz], dtype=np.float64), F


def saddle(a: float = 0.5, n_points: int = 2000, seed: int = 0):
    """Open saddle height field ``z = a (x^2 - y^2)`` over ``[-1/2, 1/2]^2`` (irregular).

    The Delaunay triangulation of `plane_delaunay`'s seeded points, normals up (+z side).
    """
    V, F = plane_delaunay(n_points, seed)
    x, y = V[:, 0] - 0.5, V[:, 1] - 0.5
    return np.column_stack([x, y, a * (x * x - y * y)]), F


def plane_skinny(n_points: int = 300, seed: int = 0, split_fraction: float = 0.5, offset: float = 0.02):
    """`plane_delaunay` remeshed with slivers: a seeded ``split_fraction`` of its faces split in
    three at a point next to their longest edge (barycentric ``offset`` toward the opposite corner),
    each giving a sliver whose angle at the new vertex approaches 180 degrees.

    The same unit square (z = 0, every point in it), so the plane's analytic references hold; no
    edge of the plane is split, so no vertex hangs on a neighbour's edge.
    """
    V, F = plane_delaunay(n_points, seed)
    rng = np.random.default_rng(int(seed) + 2)
    pick = np.flatnonzero(rng.random(len(F)) < float(split_fraction))
    T = F[pick]
    L = np.stack([np.linalg.norm(V[T[:, (k + 1) % 3]] - V[T[:, (k + 2) % 3]], axis=1) for k in range(3)], 1)
    k = L.argmax(axis=1)                              # the corner opposite the longest edge
    c = T[np.arange(len(T)), k]
    a, b = T[np.arange(len(T)), (k + 1) % 3], T[np.arange(len(T)), (k + 2) % 3]
    w = float(offset)
    P = (1 - w) * 0.5 * (V[a] + V[b]) + w * V[c]
    n = len(V) + np.arange(len(T))
    V = np.vstack([V, P])
    keep = np.ones(len(F), bool)
    keep[pick] = False
    F = np.vstack([F[keep], np.stack([a, b, n], 1), np.stack([b, c, n], 1), np.stack([c, a, n], 1)])
    return V, _orient_up(V, F)


def sphere_random(n_points: int = 2000, seed: int = 0, radius: float = 1.0):
    """Irregular sphere: the convex hull of seeded uniform random points on the sphere.

    ``n_points`` points of the sphere of ``radius`` (every vertex exactly on it), faces outward.
    """
    from scipy.spatial import ConvexHull
    rng = np.random.default_rng(int(seed))
    P = rng.normal(size=(max(4, int(n_points)), 3))
    P /= np.linalg.norm(P, axis=1, keepdims=True)
    F = ConvexHull(P).simplices.astype(np.int64)
    C = P[F].mean(axis=1) - P[np.unique(F)].mean(axis=0)   # from a point inside the hull (the origin may not be)
    flip = np.einsum("ij,ij->i", face_cross(P, F), C) < 0
    F[flip] = F[flip][:, [0, 2, 1]]
    return P * radius, F


GENERATORS = {"sphere": icosphere, "torus": torus, "plane_delaunay": plane_delaunay,
              "plane_nondelaunay": plane_nondelaunay, "plane_skinny": plane_skinny, "cylinder": cylinder, "ellipsoid": ellipsoid,
              "saddle": saddle, "sphere_random": sphere_random}


def describe_all() -> list[dict]:
    """Rows for `shootout datasets`: name, kind, vertex and face counts, description."""
    rows = []
    for name, (fname, desc) in BUNDLED.items():
        m = load({"bundled": name}).clean
        rows.append({"name": name, "kind": "bundled", "file": fname, "vertices": m.n_vertices,
                     "faces": m.n_faces, "description": desc})
    for name, (noisy, _, _, desc) in PAIRS.items():
        m = load({"bundled": name}).clean
        rows.append({"name": name, "kind": "noisy/clean pair", "file": noisy, "vertices": m.n_vertices,
                     "faces": m.n_faces, "description": desc})
    for name, defaults in PROCEDURAL.items():
        m = load({"procedural": name}).clean
        args = ", ".join(f"{k}={v}" + (f" [{PROCEDURAL_BOUNDS[k][0]:g}, {PROCEDURAL_BOUNDS[k][1]:g}]"
                                        if k in PROCEDURAL_BOUNDS else "") for k, v in defaults.items())
        rows.append({"name": name, "kind": "procedural", "file": f"({args})", "vertices": m.n_vertices,
                     "faces": m.n_faces, "description": GENERATORS[name].__doc__.strip().splitlines()[0],
                     "parameters": {k: {"default": v, "bounds": list(PROCEDURAL_BOUNDS.get(k, (None, None)))}
                                    for k, v in defaults.items()}})
    return rows
