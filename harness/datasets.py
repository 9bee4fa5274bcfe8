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

from .core.geometry import compact
from .errors import InvalidMeshError
from .mesh import Mesh, file_sha1, read_mesh, validate
from .procedural import (GENERATORS, cylinder, ellipsoid, icosphere, plane_delaunay, plane_nondelaunay, plane_skinny,
                         saddle, sphere_random, torus)

__all__ = ["DATA_DIR", "BUNDLED", "PAIRS", "PROCEDURAL", "PROCEDURAL_BOUNDS", "SURFACE_TOL", "Source", "bundled_names",
           "resolve_bundled", "content_keys", "same_surface", "spec_key", "load", "cached", "prime", "describe_all",
           "GENERATORS", "icosphere", "torus", "plane_delaunay", "plane_nondelaunay", "plane_skinny", "cylinder",
           "ellipsoid", "saddle", "sphere_random"]

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
