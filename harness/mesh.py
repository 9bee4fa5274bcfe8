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
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .core.geometry import (COMPILED_EDGES_FROM, edge_face_counts, face_cross, mean_edge_length,  # noqa: F401
                            referenced, repeated_half_edges)
from .errors import InvalidMeshError

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

def _fan(polys: list[list[int]]) -> tuple[np.ndarray, int]:
    tris = []
    n_poly = 0
    for p in polys:
        if len(p) < 3:
            raise InvalidMeshError(f"face with {len(p)} corners")
        if len(p) > 3:
            n_poly += 1
        for k in range(1, len(p) - 1):
            tris.append((p[0], p[k], p[k + 1]))
    return np.asarray(tris, dtype=np.int64).reshape(-1, 3), n_poly


_OBJ_V_ANY = re.compile(r"^[ \t]*v(?=[ \t\r]|$)", re.M)
_OBJ_F_ANY = re.compile(r"^[ \t]*f(?=[ \t\r]|$)", re.M)
_OBJ_V3 = re.compile(r"^[ \t]*v[ \t]+([^ \t\r\n]+[ \t]+[^ \t\r\n]+[ \t]+[^ \t\r\n]+)[ \t\r]*$", re.M)
_OBJ_F3 = re.compile(r"^[ \t]*f[ \t]+([0-9]+[ \t]+[0-9]+[ \t]+[0-9]+)[ \t\r]*$", re.M)


def _read_obj_fast(text: str):
    """`_read_obj` for the plain case, vectorised: ``(V, F)`` when the text is ASCII with ``\n``
    or ``\r\n`` line ends and no other whitespace than spaces and tabs, every vertex line holds
    exactly three numbers and every face line exactly three indices from 1 to the vertex count;
    None otherwise (the general reader decides, and words the errors)."""
    if not text.isascii() or text.count("\r") != text.count("\r\n") or \
            any(c in text for c in "\x0b\x0c\x1c\x1d\x1e\x1f"):
        return None                              # whitespace str.split knows and these patterns do not
    vs, fs = _OBJ_V3.findall(text), _OBJ_F3.findall(text)
    if len(vs) != len(_OBJ_V_ANY.findall(text)) or len(fs) != len(_OBJ_F_ANY.findall(text)):
        return None                              # a line of another shape: a short one, a comment after it
    body = " ".join(vs)
    if "(" in body:                              # numpy reads nan(...), Python's float does not
        return None
    try:
        V = np.fromstring(body, dtype=np.float64, sep=" ") if vs else np.zeros(0)
        F = np.fromstring(" ".join(fs), dtype=np.int64, sep=" ") if fs else np.zeros(0, np.int64)
    except (ValueError, OverflowError):          # a token that is not a number
        return None
    if len(V) != 3 * len(vs) or len(F) != 3 * len(fs) or (len(F) and (F.min() < 1 or F.max() > len(vs))):
        return None
    return V.reshape(-1, 3), F.reshape(-1, 3) - 1


def _read_obj(text: str):
    fast = _read_obj_fast(text)
    if fast is not None:
        return fast
    verts, polys = [], []
    top = (0, 0)                             # the largest (1-based) index and its line
    for ln, line in enumerate(text.splitlines(), 1):
        parts = line.split()                 # any whitespace separates tokens (spaces, tabs, indentation)
        if not parts:
            continue
        if parts[0] == "v":
            if len(parts) < 4:
                raise InvalidMeshError(f"line {ln}: vertex with fewer than 3 coordinates")
            verts.append(parts[1:4])
        elif parts[0] == "f":
            idx = []
            for tok in parts[1:]:
                i = int(tok.split("/", 1)[0])
                if i == 0:
                    raise InvalidMeshError(f"line {ln}: face index 0 (OBJ counts vertices from 1; a negative "
                                           "index counts back from the last vertex read)")
                if i < 0 and -i > len(verts):
                    raise InvalidMeshError(f"line {ln}: face index {i} counts back past the first vertex "
                                           f"({len(verts)} read so far)")
                if i > top[0]:
                    top = (i, ln)
                idx.append(i - 1 if i > 0 else len(verts) + i)
            polys.append(idx)
    if top[0] > len(verts):
        raise InvalidMeshError(f"line {top[1]}: face index {top[0]}, but the file has {len(verts)} vertices "
                               "(OBJ counts from 1)")
    try:
        V = np.asarray(verts, dtype=np.float64).reshape(-1, 3)
    except ValueError as exc:
        raise InvalidMeshError(f"bad vertex coordinate: {exc}") from None
    return V, polys


def _off_stream(toks: list, nv: int, nf: int):
    """A plain OFF body read as one token stream (3 coordinates a vertex, then ``k i_1 .. i_k``
    a face), or None unless it uses every token exactly (each face's as integers)."""
    if len(toks) < 3 * nv:
        return None
    pos, polys = 3 * nv, []
    try:
        for _ in range(nf):
            if pos >= len(toks):
                return None
            k = int(toks[pos])
            if k < 3 or pos + 1 + k > len(toks):     # a face has 3 corners at least
                return None
            polys.append([int(x) for x in toks[pos + 1:pos + 1 + k]])
            pos += 1 + k
        if pos != len(toks):
            return None
        return np.asarray(toks[:3 * nv], dtype=np.float64).reshape(-1, 3), polys
    except ValueError:                       # a coordinate where a count or an index belongs
        return None


def _read_off(text: str):
    text = text.rstrip("\x00\x1a\r\n\t ")                 # NUL padding or a DOS end-of-file mark is not data
    tokens_lines = [ln.split("#", 1)[0].split() for ln in text.splitlines()]
    tokens_lines = [t for t in tokens_lines if t]
    if not tokens_lines or not tokens_lines[0][0].endswith("OFF"):
        raise InvalidMeshError("missing OFF header")
    head = tokens_lines[0][1:] or tokens_lines[1]
    start = 1 if tokens_lines[0][1:] else 2
    nv, nf = int(head[0]), int(head[1])
    if nv < 0 or nf < 0:
        raise InvalidMeshError(f"OFF header gives {nv} vertices and {nf} faces: a count cannot be negative")
    plain = tokens_lines[0][0] == "OFF"
    if len(tokens_lines) != start + nv + nf and plain:
        stream = _off_free(head, tokens_lines[start:], nv, nf)
        if stream is not None:
            return stream
    try:
        return _off_lines(tokens_lines[start:], nv, nf, tokens_lines[0][0])
    except (InvalidMeshError, ValueError):
        if plain and len(tokens_lines) == start + nv + nf:   # a free layout whose line count happens to fit
            stream = _off_free(head, tokens_lines[start:], nv, nf)
            if stream is not None:
                return stream
        raise


def _off_free(head: list, lines: list, nv: int, nf: int):
    """A plain OFF laid out freely, read as a token stream (`_off_stream`) from the counts line's
    ``head`` tokens and the data ``lines``, or None. A third token after the counts is an edge
    count only where it is an integer; where it is not, or more data follows it on that line, the
    reading without an edge count is tried too. An integer third token alone is the OFF
    convention's edge count, never a coordinate: a file that does not read whole with it is not
    read (a value missing further on would otherwise shift every coordinate by one). Both
    readings whole: `InvalidMeshError` (ambiguous)."""
    body = [x for t in lines for x in t]
    edges = len(head) > 2 and head[2].lstrip("+-").isdigit()
    with_count = _off_stream(head[3:] + body, nv, nf) if edges or len(head) < 3 else None
    without = _off_stream(head[2:] + body, nv, nf) if len(head) > 2 and (not edges or len(head) > 3) else None
    if with_count is not None and without is not None:
        raise InvalidMeshError("ambiguous OFF: data follows the counts on their line, and it reads whole both "
                               "with and without an edge count; put the data on lines of their own")
    return with_count if with_count is not None else without


def _off_lines(lines: list, nv: int, nf: int, kind: str = "OFF"):
    """An OFF body of one vertex a line (its first three tokens) and one face a line (``k i_1 .. i_k``,
    colours after them ignored). ``kind``: the header's keyword (a COFF, NOFF, ... has extra
    values a vertex, so only a plain OFF is also read as a free token stream)."""
    if len(lines) < nv + nf:
        if kind != "OFF":
            raise InvalidMeshError(f"{kind}: header promises {nv} vertices and {nf} faces, file has {len(lines)} "
                                   "data lines: truncated, or not one vertex and one face a line (only a plain OFF "
                                   "may spread its values freely)")
        raise InvalidMeshError(f"truncated OFF: header promises {nv} vertices and {nf} faces, "
                               f"file has {len(lines)} data lines")
    V = np.asarray([t[:3] for t in lines[:nv]], dtype=np.float64).reshape(-1, 3)
    extra = len(lines) - (nv + nf)
    if extra:
        raise InvalidMeshError(f"OFF header promises {nf} faces, but {extra} more data line(s) follow them")
    polys = []
    for t in lines[nv:nv + nf]:
        k = int(t[0])
        if k < 3:                                    # refused later too: here a free layout may still read
            raise InvalidMeshError(f"face with {k} corners")
        if len(t) < k + 1:
            raise InvalidMeshError(f"truncated OFF face line: {' '.join(t)}")
        polys.append([int(x) for x in t[1:k + 1]])
    return V, polys


_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
              "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
              "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}


def _read_ply(data: bytes):
    """PLY (ascii, binary_little_endian, binary_big_endian): vertex x, y, z and face index lists."""
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise InvalidMeshError("missing PLY header")
    nl = data.find(b"\n", end)
    header = data[:end].decode("ascii", "replace").splitlines()
    body = data[nl + 1:] if nl >= 0 else b""
    fmt, elements = None, []
    for line in header:
        t = line.split()
        if not t or t[0] in ("ply", "comment", "obj_info"):
            continue
        if t[0] == "format":
            fmt = t[1]
        elif t[0] == "element":
            elements.append((t[1], int(t[2]), []))
        elif t[0] == "property" and elements:
            elements[-1][2].append(t[1:])
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise InvalidMeshError(f"unsupported PLY format {fmt!r}")
    for name, count, props in elements:
        if count < 0:
            raise InvalidMeshError(f"PLY element {name} with a negative count {count}")
        for p in props:
            if any(t not in _PLY_TYPES for t in (p[1:3] if p[0] == "list" else p[:1])) or len(p) < (4 if p[0] == "list" else 2):
                raise InvalidMeshError(f"PLY property {' '.join(p)!r}: unknown type or missing name")
    if any(name == "face" and count and not any(p[0] == "list" for p in props) for name, count, props in elements):
        raise InvalidMeshError("PLY face element without an index list")
    elements = [e for e in elements if e[2]]          # an element without properties holds no data
    V, polys = None, []

    def face_list(props):        # the index list of a face: vertex_indices (or vertex_index), else the first list
        lists = [p[-1] for p in props if p[0] == "list"]
        named = [n for n in lists if n in ("vertex_indices", "vertex_index")]
        return (named or lists or [None])[0]

    if fmt == "ascii":
        tokens = body.split()
        least = sum(count * len(props) for _, count, props in elements)     # a list takes its count at least
        if least > len(tokens):
            raise InvalidMeshError(f"truncated PLY: the header's elements need at least {least} values, "
                                   f"the file holds {len(tokens)}")
        pos = 0
        for name, count, props in elements:
            if name == "vertex":
                k = len(props)
                if any(p[0] == "list" for p in props):
                    raise InvalidMeshError("list property in PLY vertex element")
                vals = np.asarray(tokens[pos:pos + k * count], dtype=np.float64)
                if vals.size != k * count:
                    raise InvalidMeshError("truncated PLY vertex data")
                names = [p[-1] for p in props]
                vals = vals.reshape(count, k)
                V = vals[:, [names.index("x"), names.index("y"), names.index("z")]]
                pos += k * count
            else:
                lst = face_list(props)
                for _ in range(count):
                    row = None
                    for p in props:
                        if p[0] == "list":
                            m = int(tokens[pos])
                            if p[-1] == lst:
                                row = [int(x) for x in tokens[pos + 1:pos + 1 + m]]
                            pos += 1 + m
                        else:
                            pos += 1
                    if name == "face":
                        polys.append(row)
                if pos > len(tokens):
                    raise InvalidMeshError(f"truncated PLY {name} data")
        if pos < len(tokens):
            raise InvalidMeshError(f"PLY holds {len(tokens) - pos} value(s) past the elements its header declares")
        return V, polys
    order = "<" if fmt == "binary_little_endian" else ">"
    least = sum(count * sum(np.dtype(_PLY_TYPES[p[1] if p[0] == "list" else p[0]]).itemsize for p in props)
                for _, count, props in elements)
    if least > len(body):
        raise InvalidMeshError(f"truncated PLY: the header's elements need at least {least} bytes, "
                               f"the file holds {len(body)}")
    off = 0
    for name, count, props in elements:
        if all(p[0] != "list" for p in props):
            dt = np.dtype([(p[-1], order + _PLY_TYPES[p[0]]) for p in props])
            arr = np.frombuffer(body, dtype=dt, count=count, offset=off)
            off += dt.itemsize * count
            if name == "vertex":
                V = np.stack([arr["x"], arr["y"], arr["z"]], 1).astype(np.float64)
            continue
        if name == "vertex":                          # as the ASCII path says
            raise InvalidMeshError("list property in PLY vertex element")
        # elements with lists (faces): fast path when every list has 3 entries
        fields = []
        for p in props:
            if p[0] == "list":
                fields.append((p[-1] + "_n", order + _PLY_TYPES[p[1]]))
                fields.append((p[-1], order + _PLY_TYPES[p[2]], (3,)))
            else:
                fields.append((p[-1], order + _PLY_TYPES[p[0]]))
        dt = np.dtype(fields)
        lst = face_list(props)
        arr = np.frombuffer(body, dtype=dt, count=count, offset=off) if len(body) - off >= dt.itemsize * count else None
        if arr is not None and all(np.all(arr[p[-1] + "_n"] == 3) for p in props if p[0] == "list"):
            off += dt.itemsize * count
            if name == "face":
                polys = arr[lst].astype(np.int64)
            continue
        for _ in range(count):                       # general polygons: a loop over faces
            row = None
            for p in props:
                if p[0] == "list":
                    ct, it = np.dtype(order + _PLY_TYPES[p[1]]), np.dtype(order + _PLY_TYPES[p[2]])
                    m = int(np.frombuffer(body, ct, 1, off)[0])
                    off += ct.itemsize
                    if p[-1] == lst:
                        row = np.frombuffer(body, it, m, off).astype(np.int64).tolist()
                    off += it.itemsize * m
                else:
                    off += np.dtype(_PLY_TYPES[p[0]]).itemsize
            if name == "face":
                polys.append(row)
        if off > len(body):                          # the fields stepped over were cut off too
            raise InvalidMeshError(f"truncated PLY: its {name} element needs {off} bytes of the body's {len(body)}")
    rest = body[off:].rstrip(b"\r\n\t \x00\x1a")       # a trailing newline or padding is not data
    if rest:
        raise InvalidMeshError(f"PLY holds {len(body) - off} byte(s) past the elements its header declares")
    return V, polys


def _read_stl(data: bytes):
    """STL, binary (80-byte header, uint32 count, 50 bytes a triangle) or ASCII.

    Binary is recognised by its size (84 + 50 n); an ASCII file must close with ``endsolid``
    and hold three ``vertex`` lines per ``facet``, so a truncated file is an error, not a
    smaller mesh. Returns one vertex per corner; the caller welds them.
    """
    n = int(np.frombuffer(data, "<u4", 1, 80)[0]) if len(data) >= 84 else -1
    if n >= 0 and len(data) == 84 + 50 * n:
        rec = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
        tri = np.frombuffer(data, rec, n, 84)["v"].astype(np.float64)
        return tri.reshape(-1, 3), np.arange(3 * n, dtype=np.int64).reshape(-1, 3)
    text = (data[3:] if data.startswith(b"\xef\xbb\xbf") else data).decode("ascii", "replace")   # a BOM: ASCII only
    past = (f"binary STL of {n} triangle(s) with {len(data) - 84 - 50 * n} byte(s) past them"
            if n >= 0 and len(data) > 84 + 50 * n else "")
    if not text.lstrip().startswith("solid"):
        raise InvalidMeshError(past or "unreadable STL: not ASCII, and its size does not match a binary STL's "
                                       "triangle count (truncated?)")
    if "endsolid" not in text:
        if past and not re.search(r"^\s*facet\b", text, re.M):
            raise InvalidMeshError(past + " (its header begins with 'solid', as an ASCII STL's)")
        raise InvalidMeshError("truncated ASCII STL (no 'endsolid')")
    lines = [ln.split() for ln in text.splitlines()]
    verts = [t[1:4] for t in lines if t and t[0] == "vertex"]
    facets = sum(1 for t in lines if t and t[0] == "facet")
    if len(verts) != 3 * facets:
        raise InvalidMeshError(f"ASCII STL has {facets} facets but {len(verts)} vertex lines")
    V = np.asarray(verts, dtype=np.float64).reshape(-1, 3)
    return V, np.arange(len(V), dtype=np.int64).reshape(-1, 3)


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


def write_obj(path_or_file, V: np.ndarray, F: np.ndarray) -> None:
    """Write a triangle mesh as OBJ (1-based indices, 17 significant digits) to a path or an open
    text file."""
    if hasattr(path_or_file, "write"):
        path_or_file.write("".join(f"v {x:.17g} {y:.17g} {z:.17g}\n" for x, y, z in V))
        path_or_file.write("".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F))
        return
    with open(path_or_file, "w") as fh:
        write_obj(fh, V, F)


def write_ply(path_or_file, V: np.ndarray, F: np.ndarray, quality: np.ndarray | None = None,
              comment: str = "") -> None:
    """Write an ASCII PLY (17 significant digits) to a path or an open text file.

    ``quality`` (n,) becomes the per-vertex ``quality`` property (double), which MeshLab,
    PyMeshLab (``vertex_scalar_array``) and polyscope read as the vertex scalar; ``comment``
    (one line) says what it holds.
    """
    if not hasattr(path_or_file, "write"):
        with open(path_or_file, "w") as fh:
            write_ply(fh, V, F, quality, comment)
        return
    fh = path_or_file
    head = ["ply", "format ascii 1.0"]
    if comment:
        head.append("comment " + " ".join(str(comment).split()))
    head += [f"element vertex {len(V)}", "property double x", "property double y", "property double z"]
    if quality is not None:
        head.append("property double quality")
    head += [f"element face {len(F)}", "property list uchar int vertex_indices", "end_header"]
    fh.write("\n".join(head) + "\n")
    if quality is None:
        fh.write("".join(f"{x:.17g} {y:.17g} {z:.17g}\n" for x, y, z in V))
    else:
        fh.write("".join(f"{x:.17g} {y:.17g} {z:.17g} {q:.17g}\n"
                         for (x, y, z), q in zip(V.tolist(), np.asarray(quality, np.float64).tolist())))
    fh.write("".join(f"3 {a} {b} {c}\n" for a, b, c in np.asarray(F).tolist()))


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


