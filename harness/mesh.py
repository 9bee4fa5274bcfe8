"""Triangle meshes: reading (OBJ/OFF/PLY/STL), validation with documented repairs, topology.

Repair policy (each repair is recorded in ``Mesh.repairs`` and in the run's rows):
- polygons with more than 3 corners are fan-triangulated;
- STL corners at exactly the same position are welded into one vertex (STL has no indices);
- faces with a repeated vertex index are removed, and so is every face but the first on the same
  three vertices (in either orientation: a two-sided sheet becomes one-sided);
- unreferenced vertices are removed, ``Mesh.vertex_map`` keeps the original index of each kept one.
Errors (``InvalidMeshError``): unreadable or empty file, unsupported extension, an OFF or PLY
whose header promises more or less data than it holds (trailing whitespace, NUL padding and a
DOS end-of-file mark are not data), NaN/inf coordinates, indices out of range, no face left
after the repairs, a surface of zero area (every face degenerate). A UTF-8 byte-order mark at
the start of a text file (OBJ, OFF, ASCII PLY or STL) is skipped; a plain OFF whose tokens are
not one vertex or face per line is read as a token stream when that uses every token exactly.
Kept as they are, and said in every row on the mesh (`Mesh.input_notes`): zero-area faces with
distinct corners, non-manifold edges and inconsistent orientation; reported by `topology`:
non-manifold edges and vertices, several components, boundaries.
"""
from __future__ import annotations

import functools
import hashlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .core.geometry import (COMPILED_EDGES_FROM, edge_face_counts, face_cross, mean_edge_length,  # noqa: F401
                            referenced, repeated_half_edges)
from .errors import InvalidMeshError
from .mesh_formats import _fan, _read_obj, _read_off, _read_ply, _read_stl
from .mesh_formats import write_obj, write_ply  # noqa: F401

__all__ = ["COORD_LIMIT", "SUPPORTED", "Mesh", "file_sha1", "mean_edge_length", "missing_file_problem", "nonmanifold_vertices", "read_mesh",
           "topology", "validate", "write_obj", "write_ply"]

SUPPORTED = (".obj", ".off", ".ply", ".stl")


@dataclass
class Mesh:
    """``V`` (n, 3) float64, ``F`` (m, 3) int64; ``vertex_map[i]`` = index of vertex i in the source."""

    V: np.ndarray
    F: np.ndarray
    name: str = ""
    vertex_map: np.ndarray | None = None
    repairs: list = field(default_factory=list)

    @property
    def n_vertices(self) -> int:
        return int(self.V.shape[0])

    @property
    def n_faces(self) -> int:
        return int(self.F.shape[0])

    def diagonal(self) -> float:
        """Length of the bounding-box diagonal."""
        return float(np.linalg.norm(self.V.max(0) - self.V.min(0)))

    @functools.cached_property
    def noise_frame(self) -> tuple[float, np.ndarray]:
        """``(mean edge length, area-weighted unit vertex normals (n, 3))``: what the noise
        models scale and displace by (`harness.noise`), computed once per mesh (the mesh is not
        modified after loading)."""
        from .core.geometry import vertex_normals
        return mean_edge_length(self.V, self.F), vertex_normals(self.V, self.F)

    @functools.cached_property
    def input_notes(self) -> list[str]:
        """What a row on this mesh should say of it, beside its repairs: `orientation_note` and
        `degenerate_note` (computed once per mesh; the driver computes them before forking)."""
        return [n for n in (self.orientation_note, self.degenerate_note, self.seam_note) if n]

    @functools.cached_property
    def seam_note(self) -> str:
        """'' unless two vertices that faces use sit at exactly the same position (an unwelded
        seam, duplicated vertices): every operator treats them as separate, so the surface is cut
        there (a Laplacian's spectrum, a smoothing, a geodesic see a boundary)."""
        used = np.flatnonzero(np.bincount(self.F.ravel(), minlength=len(self.V))) if len(self.F) else []
        if len(used) < 2:
            return ""
        P = self.V[used]
        order = np.lexsort(P.T[::-1])
        same = (P[order[1:]] == P[order[:-1]]).all(axis=1)
        n = int(np.count_nonzero(same))
        return (f"{n} vertex(es) at exactly the position of another (an unwelded seam or duplicated vertices): "
                "methods treat them as separate, so the surface is cut there" if n else "")

    @functools.cached_property
    def degenerate_note(self) -> str:
        """'' unless some faces have zero area to rounding (doubled area at most ``1e-12`` times
        their longest edge squared: coincident or collinear corners, kept as they are): angles,
        cotangents and normals are not defined there, and each method handles them its own way."""
        n = 0
        for i in range(0, len(self.F), 65536):
            f = self.F[i:i + 65536]
            P = self.V[f]
            e2 = np.max([np.einsum("ij,ij->i", d, d) for d in (P[:, 1] - P[:, 0], P[:, 2] - P[:, 1], P[:, 0] - P[:, 2])],
                        axis=0)
            c = face_cross(self.V, f)
            n += int(np.count_nonzero(np.sqrt(np.einsum("ij,ij->i", c, c)) <= 1e-12 * e2))
        return (f"{n} zero-area face(s) (coincident or collinear corners): angles, cotangents and normals are not "
                "defined there" if n else "")

    @functools.cached_property
    def orientation_note(self) -> str:
        """'' when every edge has at most one face on each side (edge-manifold and consistently
        oriented), else what a row on this mesh should say: normals, and whatever a method derives
        from them (curvature estimates, enclosed volumes), depend on the faces' orientation."""
        from .core.geometry import orientation_problem
        why = orientation_problem(self.F)
        return f"{why}: normals, and curvatures or volumes derived from them, are not defined there" if why else ""


# ----------------------------------------------------------------------------- reading

def missing_file_problem(path) -> str | None:
    """Why ``path`` is not a mesh file to read ("is a folder; ...", "no such file"), or None."""
    path = Path(path)
    if path.is_dir():
        return "is a folder; give a mesh file"
    if path.is_file():
        return None
    return "is not a regular file (a pipe, socket or device); give a mesh file" if path.exists() else "no such file"


def file_sha1(path) -> str:
    """The sha1 hex digest of a file's bytes, read once per process for a given resolved path,
    size and modification time (a config's case ids and duplicate check, and `eval`'s case ids,
    all ask for it); `OSError` when the file cannot be read."""
    st = Path(path).stat()
    return _sha1_of(str(Path(path).resolve()), st.st_size, st.st_mtime_ns)


@functools.lru_cache(maxsize=256)
def _sha1_of(path: str, size: int, mtime_ns: int) -> str:
    return hashlib.sha1(Path(path).read_bytes()).hexdigest()


def read_mesh(path, name: str | None = None, repair: bool = True, sha1: str | None = None,
              finite: bool = True) -> Mesh:
    """Read a triangle mesh file and validate it (see the module docstring for the policy).

    ``sha1``: the hex digest the file's bytes must have (a file that changed since its run
    started is an error, not another mesh under the same name). ``finite``: `validate`'s."""
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in SUPPORTED:
        raise InvalidMeshError(f"{path.name}: unsupported extension {ext!r}; expected one of {SUPPORTED}")
    why = missing_file_problem(path)
    if why:
        raise InvalidMeshError(f"{path}: {why}")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InvalidMeshError(f"{path}: cannot read it ({exc.strerror or exc})") from None
    if not data:
        raise InvalidMeshError(f"{path.name}: empty file")
    now = hashlib.sha1(data).hexdigest() if sha1 is not None else None
    if now != sha1:
        raise InvalidMeshError(f"{path}: the file changed since the run started (its sha1 is now "
                               f"{now[:12]}, was {sha1[:12]}); start the run again")
    if ext != ".stl" and data.startswith(b"\xef\xbb\xbf"):          # a UTF-8 byte-order mark
        data = data[3:]
    notes = []
    try:
        if ext in (".obj", ".off", ".ply"):
            if ext == ".ply":
                V, polys = _read_ply(data)
                if V is None:
                    raise InvalidMeshError("PLY file has no vertex element")
            else:
                text = data.decode("utf-8", errors="replace")
                V, polys = _read_obj(text) if ext == ".obj" else _read_off(text)
            if isinstance(polys, np.ndarray):
                F, n_poly = polys, 0
            else:
                F, n_poly = _fan(polys) if len(polys) else (np.zeros((0, 3), np.int64), 0)
            if n_poly:
                notes.append(f"fan-triangulated {n_poly} polygon(s) with more than 3 corners")
        else:
            V, F = _read_stl(data)
            if len(V):       # STL stores each triangle's corners separately: weld exact copies
                V, inv = np.unique(V, axis=0, return_inverse=True)
                F = inv.ravel()[F]
                notes.append("welded exactly coincident STL corners into shared vertices")
    except InvalidMeshError as exc:
        raise InvalidMeshError(f"{path.name}: {exc}") from None
    except (ValueError, IndexError, KeyError, TypeError, UnicodeDecodeError, RuntimeError, OverflowError,
            MemoryError) as exc:
        raise InvalidMeshError(f"{path.name}: unreadable ({type(exc).__name__}: {str(exc)[:200]})") from None
    mesh = validate(V, F, name=name or path.stem, repair=repair, finite=finite)
    mesh.repairs[:0] = notes
    return mesh



# ----------------------------------------------------------------------------- validation

COORD_LIMIT = 1e60        # |coordinate| at most this, extent at least its inverse: length^4 stays a finite double


def validate(V, F, name: str = "", repair: bool = True, finite: bool = True) -> Mesh:
    """Check arrays and apply the documented repairs; raises InvalidMeshError. ``finite=False``
    keeps NaN, inf and out-of-range coordinates (a method's output read back from a file, which
    its task scores as it scores the method's arrays: e.g. a smoothing result is ``diverged``)."""
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F)
    label = f"{name}: " if name else ""
    if V.ndim != 2 or V.shape[1] != 3 or V.shape[0] == 0:
        raise InvalidMeshError(f"{label}no vertices (or not 3D): shape {V.shape}")
    if F.ndim != 2 or F.shape[0] == 0:
        raise InvalidMeshError(f"{label}no faces")
    if F.shape[1] != 3:
        raise InvalidMeshError(f"{label}faces must be triangles, got {F.shape[1]} corners")
    F = F.astype(np.int64)
    if F.min() < 0 or F.max() >= len(V):
        raise InvalidMeshError(f"{label}face indices out of range [0, {len(V)}): "
                               f"min {int(F.min())}, max {int(F.max())}")
    notes = []
    vmap = np.arange(len(V))
    if repair:
        rep = (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])
        if rep.any():
            notes.append(f"removed {int(rep.sum())} face(s) with a repeated vertex")
            F = F[~rep]
        if len(F):
            key = np.sort(F, axis=1)
            _, first = np.unique(key, axis=0, return_index=True)
            if len(first) < len(F):
                notes.append(f"removed {len(F) - len(first)} duplicate face(s)")
                F = F[np.sort(first)]
        if len(F) == 0:
            raise InvalidMeshError(f"{label}no valid face left after removing degenerate faces")
        used = referenced(F, len(V))
        if not used.all():
            notes.append(f"removed {int((~used).sum())} unreferenced vertex/vertices")
            vmap = np.flatnonzero(used)
            remap = np.full(len(V), -1, np.int64)
            remap[vmap] = np.arange(len(vmap))
            V, F = V[vmap], remap[F]
    if finite:                             # over the vertices the faces use: a dropped one changes nothing
        idx = vmap if repair else np.flatnonzero(referenced(F, len(V)))
        Vu = V if repair else V[idx]
        if not np.isfinite(Vu).all():
            bad = ~np.isfinite(Vu).all(axis=1)
            raise InvalidMeshError(f"{label}{int(bad.sum())} vertices with NaN or inf coordinates "
                                   f"(first: {idx[np.flatnonzero(bad)[:5]].tolist()})")
        big, span = float(np.abs(Vu).max()), float((Vu.max(axis=0) - Vu.min(axis=0)).max())
        if big > COORD_LIMIT or 0 < span < 1 / COORD_LIMIT:
            raise InvalidMeshError(f"{label}coordinates up to {big:.3g} over a span of {span:.3g}: beyond "
                                   f"{COORD_LIMIT:g} (or a span below {1 / COORD_LIMIT:g}) the fourth powers of "
                                   "lengths that areas and angles use overflow (or underflow) double precision; "
                                   "rescale the mesh")
    if not any(face_cross(V, f).any() for f in (F[:64], *(F[i:i + 65536] for i in range(0, len(F), 65536)))):
        raise InvalidMeshError(f"{label}every face has zero area (the surface is degenerate: its vertices "
                               "lie on a line or coincide)")
    return Mesh(V=np.ascontiguousarray(V), F=np.ascontiguousarray(F), name=name,
                vertex_map=vmap, repairs=notes)


# ----------------------------------------------------------------------------- topology

def nonmanifold_vertices(F: np.ndarray, n: int) -> np.ndarray:
    """Indices of vertices whose incident faces form more than one edge-connected fan."""
    if len(F) == 0:
        return np.zeros(0, np.int64)
    if len(F) >= COMPILED_EDGES_FROM:
        from .core._edges_kernel import fan_counts
        return np.flatnonzero(fan_counts(np.ascontiguousarray(F, dtype=np.int64), int(n)) > 1)
    m = len(F)
    corner_v = F.ravel()                           # corner c = 3 f + k sits at vertex F[f, k]
    c = np.arange(3 * m)
    nxt = F[:, [1, 2, 0]].ravel()
    prv = F[:, [2, 0, 1]].ravel()
    # each corner touches the two edges (v, nxt) and (v, prv); corners sharing (v, x) are one fan
    keys = np.concatenate([corner_v * n + nxt, corner_v * n + prv])
    corners = np.concatenate([c, c])
    order = np.argsort(keys)                       # equal keys end up adjacent
    g, cs = keys[order], corners[order]
    same = g[1:] == g[:-1]
    a, b = cs[:-1][same], cs[1:][same]
    G = sp.coo_matrix((np.ones(len(a)), (a, b)), shape=(3 * m, 3 * m))
    _, comp = connected_components(G, directed=False)
    pairs = np.sort(corner_v * (3 * m) + comp)
    pairs = pairs[np.r_[True, pairs[1:] != pairs[:-1]]]
    fans = np.bincount(pairs // (3 * m), minlength=n)
    return np.flatnonzero(fans > 1)


def topology(V: np.ndarray, F: np.ndarray) -> dict:
    """Topological facts of a triangle mesh.

    Returns a dict with ``n_edges``, ``boundary_edges``, ``boundary_loops`` (components of the
    boundary-edge graph), ``components`` (connected pieces of the surface as a point set: faces
    joined through a shared vertex or edge, over referenced vertices; two fans meeting at one
    vertex are one piece), ``euler`` (chi = V - E + F over referenced vertices), ``genus``
    (from chi = 2c - 2g - b, total over components: the genus of an orientable manifold mesh,
    fractional or meaningless otherwise), ``nonmanifold_edges`` (edges with more than two faces),
    ``nonmanifold_vertices``, ``manifold`` (edge- and vertex-manifold), ``oriented`` (no directed
    edge in more than one face: on a manifold mesh, consistently oriented faces, which make it
    orientable). A face with a repeated corner (``[a, a, b]``: a triangle collapsed onto an edge
    or a point, which ``zero_area_faces`` counts) has no edges of its own and is left out: it
    made a closed mesh look non-manifold, misoriented and one boundary loop richer.
    """
    n = len(V)
    F = np.asarray(F)
    if len(F):
        F = F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 2] != F[:, 0])]
    edges, counts = edge_face_counts(F)
    used = np.flatnonzero(referenced(F, n)) if len(F) else np.zeros(0, np.int64)
    bnd = edges[counts == 1]
    if len(bnd):
        Gb = sp.coo_matrix((np.ones(len(bnd)), (bnd[:, 0], bnd[:, 1])), shape=(n, n))
        nb, lab = connected_components(Gb, directed=False)
        loops = int(np.count_nonzero(np.bincount(lab[bnd.ravel()], minlength=nb)))
    else:
        loops = 0
    Ge = sp.coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    _, lab = connected_components(Ge, directed=False)
    comps = int(np.count_nonzero(np.bincount(lab[used], minlength=int(lab.max()) + 1))) if len(used) else 0
    chi = len(used) - len(edges) + len(F)
    nm_edges = int((counts > 2).sum())
    nm_verts = len(nonmanifold_vertices(F, n))
    return {
        "n_edges": int(len(edges)),
        "boundary_edges": int(len(bnd)),
        "boundary_loops": int(loops),
        "components": int(comps),
        "euler": int(chi),
        "genus": (2 * comps - loops - chi) / 2,
        "nonmanifold_edges": nm_edges,
        "nonmanifold_vertices": nm_verts,
        "manifold": nm_edges == 0 and nm_verts == 0,
        "oriented": bool(len(F) == 0 or repeated_half_edges(F) == 0),
    }
