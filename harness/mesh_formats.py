"""Mesh file formats: parsers of OBJ, OFF, PLY and STL contents, and the OBJ and PLY writers.

Each parser takes a file's text (OBJ, OFF) or bytes (PLY, STL) and returns ``(V, polys)``:
``V`` (n, 3) float64 and the faces as lists of vertex indices (fan-triangulated by `_fan`) or
already an (m, 3) int64 array. ``_read_stl`` returns one vertex per corner (the caller welds
them). They raise ``InvalidMeshError`` with the reason (the caller prefixes the file's name);
validation and the documented repairs are `harness.mesh`'s (`read_mesh`, `validate`).
"""
from __future__ import annotations

import re

import numpy as np

from .errors import InvalidMeshError


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
