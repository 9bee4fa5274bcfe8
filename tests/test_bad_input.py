"""Bad input, all of it defined (issue 7).

Small files written in a temporary folder go through the runner (`harness.run`, the default
isolated executor) with every task. Each input has one defined outcome, per the policy in
harness/mesh.py:

- error (every row of the mesh is ``error`` and the message names the problem): NaN or inf
  coordinates, empty file, unreadable or truncated file, a header promising more or less data
  than the file holds, unsupported extension, indices out of range, a surface of zero area;
- repaired (rows ok, the repair named in the ``error`` column as ``input repaired: ...``):
  quads and polygons (fan-triangulated), duplicate faces, faces with a repeated vertex,
  unreferenced vertices;
- kept as is (rows ok): zero-area faces with distinct corners, non-manifold edges and
  vertices, several components, a single triangle.

On the kept and repaired meshes, every method must give either an ``ok`` row whose metrics
are sane (what `check_ok_row` checks, column by column) or an ``error`` row with a message
that is not a process death: a C++ backend crashing on a valid mesh is a bug in its adapter
(it must check the precondition and raise), and this test names the exact case.
"""
import struct
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import harness  # noqa: E402
import methods  # noqa: E402
from harness.config import load_config  # noqa: E402
from harness.errors import ConfigError  # noqa: E402
from harness.mesh import read_mesh, topology  # noqa: E402

TASKS = ("laplacian", "smoothing", "simplification")
C_BACKENDS = ("libigl.", "meshlab.", "pygel.", "fast_simplification.", "pyfqmr.", "robust.")
SCRATCH_REFERENCE = ("scratch.cotan", "scratch.explicit")
# Adapter bugs this matrix found are fixed in the adapters, not listed here: e.g. PyGEL3D 0.8.2's
# laplacian_smooth dies of SIGFPE on meshes with fewer than 8 vertices, so pygel.laplacian now
# refuses them (test_pygel_laplacian_refuses_tiny_meshes).

# ----------------------------------------------------------------------------- the files

OCTA_V = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
OCTA_F = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]


def _obj(V, F, extra=""):
    return ("".join(f"v {x} {y} {z}\n" for x, y, z in V)
            + "".join("f " + " ".join(str(i + 1) for i in f) + "\n" for f in F) + extra)


def _off(V, F):
    return (f"OFF\n{len(V)} {len(F)} 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in V)
            + "".join(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in F))


def _files() -> dict[str, str | bytes]:
    """file name -> content."""
    out = {}
    V = [list(v) for v in OCTA_V]
    Vn = [list(v) for v in OCTA_V]
    Vn[2][1] = float("nan")
    out["nan.obj"] = _obj(Vn, OCTA_F)
    Vi = [list(v) for v in OCTA_V]
    Vi[3][0] = float("inf")
    out["inf.off"] = _off(Vi, OCTA_F)
    out["empty.obj"] = ""
    t = _off(V, OCTA_F)
    out["truncated.off"] = t[: len(t) // 2]
    out["badtoken.obj"] = _obj(V, OCTA_F, "f 1 x 3\n")
    out["garbage_ply.ply"] = bytes(range(256)) * 4
    out["garbage_stl.stl"] = b"solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0"
    # binary PLY and STL of the octahedron, whole and cut short
    hdr = ("ply\nformat binary_little_endian 1.0\nelement vertex 6\nproperty float x\nproperty float y\n"
           "property float z\nelement face 8\nproperty list uchar int vertex_indices\nend_header\n").encode()
    vb = np.asarray(V, "<f4").tobytes()
    fb = b"".join(struct.pack("<B3i", 3, *f) for f in OCTA_F)
    out["octa_binary.ply"] = hdr + vb + fb
    out["truncated_binary.ply"] = hdr + vb + fb[:30]
    out["lying_header.ply"] = hdr.replace(b"element face 8", b"element face 800000000") + vb + fb
    Va = np.asarray(V, float)
    body = b"".join(struct.pack("<12fH", 0, 0, 0, *Va[f[0]], *Va[f[1]], *Va[f[2]], 0) for f in OCTA_F)
    stl = b"\0" * 80 + struct.pack("<I", len(OCTA_F)) + body
    out["octa_binary.stl"] = stl
    out["truncated_binary.stl"] = stl[: 84 + 50 * 3 + 20]
    out["out_of_range.obj"] = _obj(V, OCTA_F + [(0, 1, 98)])
    # finite, but length^4 overflows or underflows: zero-area faces, NaN noise, crashes in libraries
    out["huge_coords.obj"] = _obj([[x * 1e100 for x in v] for v in V], OCTA_F)
    out["tiny_coords.obj"] = _obj([[x * 1e-100 for x in v] for v in V], OCTA_F)
    # unit cube of quads
    CV = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    out["quads.obj"] = _obj(CV, [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)])
    # pentagonal prism, pentagon caps and quad sides (OFF polygons)
    a = np.arange(5) * 2 * np.pi / 5
    PV = [(np.cos(t), np.sin(t), 0.0) for t in a] + [(np.cos(t), np.sin(t), 1.0) for t in a]
    PF = [(4, 3, 2, 1, 0), (5, 6, 7, 8, 9)] + [(i, (i + 1) % 5, 5 + (i + 1) % 5, 5 + i) for i in range(5)]
    out["polygons.off"] = _off(PV, PF)
    # edge a-b split by its midpoint m, closed by the needle (a, m, b): area exactly 0
    out["zero_area.obj"] = _obj([(0, 0, 0), (2, 0, 0), (1, 0, 0), (1, 1, 0.3), (1, -1, 0.3)],
                                [(0, 1, 3), (0, 4, 2), (2, 4, 1), (0, 2, 1)])
    out["duplicate_faces.obj"] = _obj(V, OCTA_F + [OCTA_F[0], OCTA_F[3][::-1]])
    out["repeated_vertex.obj"] = _obj(V, OCTA_F + [(0, 0, 1)])
    # three triangles on edge 0-1
    out["nonmanifold_edge.obj"] = _obj([(0, 0, 0), (1, 0, 0), (0.5, 1, 0), (0.5, -1, 0), (0.5, 0, 1)],
                                       [(0, 1, 2), (1, 0, 3), (0, 1, 4)])
    # two octahedra sharing one vertex (x = 1)
    V2 = [list(v) for v in OCTA_V] + [[x + 2, y, z] for x, y, z in OCTA_V]
    F2 = OCTA_F + [(p + 6, q + 6, r + 6) for p, q, r in OCTA_F]
    F2 = [tuple(0 if i == 7 else (i if i < 7 else i - 1) for i in f) for f in F2]
    del V2[7]
    out["nonmanifold_vertex.obj"] = _obj(V2, F2)
    out["unreferenced.obj"] = _obj(V + [(5, 5, 5), (6, 6, 6)], OCTA_F)
    V3 = V + [[x + 5, y, z] for x, y, z in OCTA_V]
    out["components.obj"] = _obj(V3, OCTA_F + [(p + 6, q + 6, r + 6) for p, q, r in OCTA_F])
    out["single_triangle.obj"] = _obj([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0, 1, 2)])
    out["bom.obj"] = b"\xef\xbb\xbf" + _obj(V, OCTA_F).encode()        # a UTF-8 byte-order mark first
    # MeshLab's per-corner texture coordinates: a second list on each face, after or before the indices
    thdr = hdr.replace(b"vertex_indices\n", b"vertex_indices\nproperty list uchar float texcoord\n")
    tc = struct.pack("<B6f", 6, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6)
    out["texcoord_binary.ply"] = thdr + vb + b"".join(struct.pack("<B3i", 3, *f) + tc for f in OCTA_F)
    out["texcoord_first_ascii.ply"] = (
        "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 8\nproperty list uchar float texcoord\nproperty list uchar int vertex_indices\nend_header\n"
        + "".join(f"{x} {y} {z}\n" for x, y, z in V)
        + "".join("6 0.1 0.2 0.3 0.4 0.5 0.6 3 " + " ".join(map(str, f)) + "\n" for f in OCTA_F))
    # an ASCII PLY whose header declares 1e9 more elements than the file holds (read in a Python loop)
    out["huge_count.ply"] = (
        "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 8\nproperty list uchar int vertex_indices\nelement junk 1000000000\nproperty float a\n"
        "end_header\n" + "".join(f"{x} {y} {z}\n" for x, y, z in V)
        + "".join("3 " + " ".join(map(str, f)) + "\n" for f in OCTA_F))
    # an element without properties declared 1e12 times (the reader looped over it), and faces past
    # the declared count in ASCII and binary PLY (dropped without a word)
    out["empty_element.ply"] = (
        "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 8\nproperty list uchar int vertex_indices\nelement junk 1000000000000\nend_header\n"
        + "".join(f"{x} {y} {z}\n" for x, y, z in V) + "".join("3 " + " ".join(map(str, f)) + "\n" for f in OCTA_F))
    out["extra_faces_ascii.ply"] = (
        "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 7\nproperty list uchar int vertex_indices\nend_header\n"
        + "".join(f"{x} {y} {z}\n" for x, y, z in V) + "".join("3 " + " ".join(map(str, f)) + "\n" for f in OCTA_F))
    out["extra_faces_binary.ply"] = hdr.replace(b"element face 8", b"element face 7") + vb + fb
    out["padded_binary.ply"] = hdr + vb + fb + b"\n\x00\x00"            # trailing newline and NUL padding: fine
    out["dos_eof.off"] = _off(V, OCTA_F) + "\x1a"                       # a DOS end-of-file mark: fine
    out["bom_ascii.stl"] = b"\xef\xbb\xbf" + (
        "solid octa\n" + "".join("facet normal 0 0 0\nouter loop\n" + "".join(f"vertex {x} {y} {z}\n" for x, y, z in
                                  (V[i] for i in f)) + "endloop\nendfacet\n" for f in OCTA_F) + "endsolid octa\n").encode()
    out["extra_faces.off"] = _off(V, OCTA_F).replace("6 8 0", "6 7 0", 1)   # one face past the promised count
    out["free_layout.off"] = ("OFF\n6 8 0\n" + " ".join(f"{x} {y} {z}" for x, y, z in V) + "\n"   # all vertices on a line
                              + "  ".join("3 " + " ".join(map(str, f)) for f in OCTA_F[:5]) + "\n"
                              + "\n".join("3 " + " ".join(map(str, f)) for f in OCTA_F[5:]) + "\n")
    out["collinear.obj"] = _obj([(0, 0, 0), (1, 0, 0), (2, 0, 0), (3, 0, 0)], [(0, 1, 2), (1, 2, 3)])
    return out


# stem -> what every row must say (error rows) -----------------------------------------------
LOAD_ERRORS = {
    "nan": "NaN or inf coordinates",
    "inf": "NaN or inf coordinates",
    "empty": "empty file",
    "truncated": "truncated OFF",
    "badtoken": "unreadable",
    "garbage_ply": "missing PLY header",
    "garbage_stl": "truncated ASCII STL",
    "truncated_binary": "unreadable",            # .ply and .stl: both stems map here
    "lying_header": "truncated PLY: the header's elements need at least",
    "out_of_range": "face index 99, but the file has 6 vertices (OBJ counts from 1)",
    "huge_coords": "overflow (or underflow) double precision; rescale the mesh",
    "tiny_coords": "span of 2e-100: beyond",
    "huge_count": "truncated PLY: the header's elements need at least",
    "extra_faces": "OFF header promises 7 faces, but 1 more data line(s) follow them",
    "collinear": "every face has zero area",
    "extra_faces_ascii": "PLY holds 4 value(s) past the elements its header declares",
    "extra_faces_binary": "PLY holds 13 byte(s) past the elements its header declares",
}
# stem -> (repair note in every row, vertices, faces after reading) -------------------------
REPAIRED = {
    "quads": ("fan-triangulated 6 polygon(s)", 8, 12),
    "polygons": ("fan-triangulated 7 polygon(s)", 10, 16),
    "duplicate_faces": ("removed 2 duplicate face(s)", 6, 8),
    "repeated_vertex": ("removed 1 face(s) with a repeated vertex", 6, 8),
    "unreferenced": ("removed 2 unreferenced vertex/vertices", 6, 8),
    "octa_binary": ("", 6, 8),                  # .ply: nothing to repair; .stl: corners welded
    "bom": ("", 6, 8),
    "texcoord_binary": ("", 6, 8),
    "texcoord_first_ascii": ("", 6, 8),
    "free_layout": ("", 6, 8),
    "empty_element": ("", 6, 8),
    "padded_binary": ("", 6, 8),
    "dos_eof": ("", 6, 8),
    "bom_ascii": ("welded exactly coincident STL corners", 6, 8),
}
# stem -> topology facts that must survive reading unchanged --------------------------------
KEPT = {
    "zero_area": {"n_faces": 4, "boundary_edges": 4},
    "nonmanifold_edge": {"nonmanifold_edges": 1},
    "nonmanifold_vertex": {"nonmanifold_vertices": 1, "components": 1},
    "components": {"components": 2},
    "single_triangle": {"n_faces": 1, "boundary_edges": 3},
}


@pytest.fixture(scope="module")
def bad_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("bad_input")
    for name, content in _files().items():
        (d / name).write_bytes(content if isinstance(content, bytes) else content.encode())
    return d


def _stem(path: Path) -> str:
    return path.stem


def representative(task: str) -> list[str]:
    """Every available method of a compiled backend, plus the scratch reference of the task."""
    names = [m for m in methods.available(task) if m.startswith(C_BACKENDS) or m in SCRATCH_REFERENCE]
    assert names, task
    return names


def config(meshes, method_lists, noise=None):
    tasks = {t: {"methods": ms} for t, ms in method_lists.items()}
    if "simplification" in tasks:
        tasks["simplification"]["params"] = {"target_ratio": 0.5}
    return {"name": "bad", "meshes": meshes, "timeout": 120, "hausdorff_samples": 2000, "repeats": 1,
            "time_budget": 0, "noise": noise or [{"model": "none"}], "tasks": tasks}   # rows, not timings


# ----------------------------------------------------------------------------- row checks

def _finite(row, col):
    v = row[col]
    return v is not None and not pd.isna(v) and np.isfinite(float(v))


def _blank(row, col):
    return col not in row or pd.isna(row[col])


def check_ok_row(task: str, row, closed: bool) -> list[str]:
    """Problems with an ok row: a number promised but missing or non-finite, or out of range."""
    P = []

    def need(cols, lo=-np.inf, hi=np.inf):
        for c in cols:
            if not _finite(row, c):
                P.append(f"{c}={row[c]!r} (a finite number is promised)")
            elif not lo <= float(row[c]) <= hi:
                P.append(f"{c}={row[c]!r} outside [{lo}, {hi}]")

    def flag(cols):
        for c in cols:
            if row[c] not in (True, False):
                P.append(f"{c}={row[c]!r} (true/false promised)")

    def optional(cols, lo=-np.inf, hi=np.inf):      # blank allowed where the metric documents it
        for c in cols:
            if not _blank(row, c):
                need([c], lo, hi)

    need(["time_s", "peak_rss_mb"], 0)
    need(["n_vertices", "n_faces"], 1)
    if task == "laplacian":
        need(["sym_error"], 0)
        need(["neg_weights"], 0, 1)
        need(["loc_violations"], 0)
        need(["nnz"], 1)
        flag(["SYM", "LOC", "POS"])
        optional(["min_eig"], -1 - 1e-9, 1 + 1e-9)   # relative to the largest |eigenvalue|; blank = undetermined
        optional(["lin_error"], 0)                   # blank for non-planar meshes
        for c in ("psd", "LIN", "operator_symmetric"):
            if not _blank(row, c):
                flag([c])
    elif task == "smoothing":
        flag(["diverged"])
        need(["input_ev_mean", "input_dist_mean", "input_dist_mean_sym"], 0)
        need(["input_normal_error_deg"], 0, 180)
        accuracy = ["ev_mean", "ev_rms", "dist_mean", "dist_mean_back", "dist_mean_sym", "ev_sun", "hausdorff", "area_ratio"]
        angles = ["normal_error_deg", "normal_error_rms_deg", "min_angle", "max_angle"]
        if row["diverged"] is True:                  # a blown-up result carries no accuracy numbers
            P += [f"{c}={row[c]!r} on a diverged row" for c in accuracy + angles if not _blank(row, c)]
        else:
            if _finite(row, "area_ratio") and row["area_ratio"] == 0:
                # the result collapsed to zero area: ev_sun (area-weighted) is undefined, blank
                accuracy = [c for c in accuracy if c != "ev_sun"]
            need(accuracy, 0)
            need(angles, 0, 180)
            need(["obtuse_fraction"], 0, 1)
            need(["radius_ratio_mean"], 0, 1 + 1e-9)
            (need if closed else optional)(["volume_ratio"])
    else:
        need(["target_faces"], 1)
        need(["out_faces", "zero_area_faces"], 0)
        flag(["manifold", "topology_changed"])
        if _finite(row, "out_faces") and row["out_faces"] > 0:
            need(["hausdorff", "surface_dist_mean"], 0)
            need(["boundary_loops_change"])
            optional(["genus_change"])        # blank unless input and output are manifold
            if not _blank(row, "genus_change") and float(row["genus_change"]) % 1:
                P.append(f"genus_change={row['genus_change']!r} (an integer or blank is promised)")
            need(["min_angle"], 0, 60 + 1e-9)
            need(["obtuse_fraction"], 0, 1)
            need(["radius_ratio_mean"], 0, 1 + 1e-9)
    return P


def crashes(task, df) -> list[str]:
    """Rows whose process died (no method may crash on these inputs)."""
    return [f"{r.mesh} {r.method} ({task}): {r.error}"
            for r in df[df["error"].str.contains("worker process", na=False)].itertuples()]


def run_and_check(tmp_path, paths, method_lists, noise=None):
    """Run the config; return (rows by task, problems as 'file method: what')."""
    cfg = load_config(config([{"file": str(p)} for p in paths], method_lists, noise))
    source = {c.mesh_key: Path(c.mesh["file"]) for c in cfg.cases}    # mesh label -> file
    frames = harness.run(cfg, out=tmp_path / "out", workers=2)
    for df in frames.values():
        df["file"] = df["mesh"].map(lambda m: source[m].name)
    n_expected = {t: len(paths) * len(ms) for t, ms in method_lists.items()}
    problems = []
    for task, df in frames.items():
        assert len(df) == n_expected[task] and df["case_id"].is_unique
        for _, row in df.iterrows():
            where = f"{row['mesh']} {row['method']} ({task})"
            if row["status"] == "ok":
                m = read_mesh(source[row["mesh"]])
                closed = topology(m.V, m.F)["boundary_edges"] == 0
                problems += [f"{where}: ok row with {p}" for p in check_ok_row(task, row, closed)]
            elif row["status"] == "error":
                if not row["error"].strip():
                    problems.append(f"{where}: error row without a message")
            else:
                problems.append(f"{where}: status {row['status']}: {row['error']}")
    return frames, problems


# ----------------------------------------------------------------------------- tests

def test_the_reader_applies_the_documented_policy(bad_dir):
    """Reading alone: each file gets its documented outcome (no runner involved)."""
    from harness.errors import InvalidMeshError
    for p in sorted(bad_dir.iterdir()):
        stem = _stem(p)
        if stem in LOAD_ERRORS:
            with pytest.raises(InvalidMeshError, match=LOAD_ERRORS[stem].replace("(", r"\(").replace(")", r"\)")):
                read_mesh(p)
            continue
        m = read_mesh(p)
        if stem in REPAIRED:
            note, nv, nf = REPAIRED[stem]
            if p.suffix == ".stl":
                note = "welded exactly coincident STL corners"
            if note:
                assert any(note in r for r in m.repairs), (stem, m.repairs)
            else:
                assert m.repairs == [], (p.name, m.repairs)
            assert (m.n_vertices, m.n_faces) == (nv, nf)
        else:
            assert m.repairs == [], (stem, m.repairs)
            facts = {**topology(m.V, m.F), "n_faces": m.n_faces}
            for k, v in KEPT[stem].items():
                assert facts[k] == v, (stem, k, facts[k])
        assert ("1 zero-area face(s)" in m.degenerate_note) == (stem == "zero_area"), (stem, m.degenerate_note)


def test_unusable_files_are_error_rows_naming_the_problem(bad_dir, tmp_path):
    paths = sorted(p for p in bad_dir.iterdir() if _stem(p) in LOAD_ERRORS)
    assert {_stem(p) for p in paths} == set(LOAD_ERRORS)
    one_each = {t: representative(t)[:1] for t in TASKS}
    frames, problems = run_and_check(tmp_path, paths, one_each)
    assert not problems, "\n".join(problems)
    for task, df in frames.items():
        assert set(df["status"]) == {"error"}, task
        for _, row in df.iterrows():
            assert row["error"].startswith("InvalidMeshError"), row["error"]
            assert LOAD_ERRORS[Path(row["file"]).stem] in row["error"], (row["file"], row["error"])


def test_unsupported_extension_is_a_config_error(tmp_path):
    """Caught at validation (exit 2, nothing written), before any case runs."""
    from harness.cli import main
    (tmp_path / "points.xyz").write_text("0 0 0\n1 0 0\n0 1 0\n")
    cfg = tmp_path / "c.yaml"
    cfg.write_text("meshes: [{file: points.xyz}]\ntasks: {laplacian: {methods: [scratch.uniform]}}\n")
    with pytest.raises(ConfigError, match=r"unsupported extension '\.xyz'"):
        harness.run(str(cfg), out=tmp_path / "out")
    assert main(["run", str(cfg), "--out", str(tmp_path / "out")]) == 2
    assert not (tmp_path / "out").exists()


# files read as exactly the plain octahedron (same V, same F, checked below) hand every backend
# the same arrays: all methods on one of them (unreferenced: the vertex-map path), one method
# per task on the others
FULL_OCTAHEDRON = "unreferenced"


def _is_plain_octahedron(path: Path) -> bool:
    m = read_mesh(path)
    return np.array_equal(m.V, np.asarray(OCTA_V, float)) and np.array_equal(m.F, np.asarray(OCTA_F))


def test_repaired_and_kept_meshes_through_compiled_backends(bad_dir, tmp_path):
    """Every task, every available compiled-backend method (+ the scratch reference) on each
    repaired or kept mesh: ok rows with sane metrics, or error rows that name a reason (no
    process death, no timeout). Repairs are named in every row of the mesh."""
    usable = [p for p in sorted(bad_dir.iterdir()) if _stem(p) in REPAIRED or _stem(p) in KEPT]
    light = [p for p in usable if _stem(p) != FULL_OCTAHEDRON and _is_plain_octahedron(p)]
    full = [p for p in usable if p not in light]
    assert len(light) >= 8 and any(_stem(p) == FULL_OCTAHEDRON for p in full)
    frames, problems = run_and_check(tmp_path / "full", full, {t: representative(t) for t in TASKS})
    frames_l, problems_l = run_and_check(tmp_path / "light", light, {t: representative(t)[:1] for t in TASKS})
    problems += problems_l
    for task in TASKS:
        df = pd.concat([frames[task], frames_l[task]], ignore_index=True)
        problems += crashes(task, df)
        for stem, (note, nv, nf) in REPAIRED.items():
            rows = df[df["file"].map(lambda f: Path(f).stem) == stem]
            assert len(rows), (stem, task)
            ok = rows[rows.status == "ok"]
            assert (ok["n_vertices"] == nv).all() and (ok["n_faces"] == nf).all(), stem
            if note:
                assert ok["error"].str.contains(note, regex=False).all(), (stem, task)
        ok = df[(df["file"].map(lambda f: Path(f).stem) == "zero_area") & (df.status == "ok")]
        assert ok["error"].str.contains("input: 1 zero-area face(s)", regex=False).all(), task  # said nowhere before
    assert not problems, "\n".join(problems)


def test_noise_on_degenerate_meshes(bad_dir, tmp_path):
    """Normal-direction noise on meshes whose normals are ill-defined (zero-area face,
    non-manifold edge and vertex, a lone triangle) still gives defined rows."""
    paths = [bad_dir / n for n in ("zero_area.obj", "nonmanifold_edge.obj", "nonmanifold_vertex.obj",
                                   "single_triangle.obj")]
    lists = {"laplacian": ["scratch.cotan", "libigl.cotan"],
             "smoothing": [m for m in representative("smoothing") if not m.startswith("scratch.")][:2]
             + ["scratch.explicit"],
             "simplification": ["fast_simplification.qem"]}
    _, problems = run_and_check(tmp_path, paths, lists,
                                noise=[{"model": "gaussian_normal", "levels": [0.3]}])
    assert not problems, "\n".join(problems)


@pytest.mark.slow
def test_every_available_method_on_every_usable_bad_mesh(bad_dir, tmp_path):
    """The full matrix: all registered, available methods (not only the compiled ones)."""
    paths = sorted(p for p in bad_dir.iterdir() if _stem(p) in REPAIRED or _stem(p) in KEPT)
    lists = {t: [m for m in methods.available(t) if "." in m and not m.startswith("crashy.")] for t in TASKS}
    frames, problems = run_and_check(tmp_path, paths, lists)
    for task, df in frames.items():
        problems += crashes(task, df)
    assert not problems, "\n".join(problems)


def test_pygel_laplacian_refuses_tiny_meshes(bad_dir):
    """The octahedron used to kill the worker (SIGFPE); now a ValueError row naming the reason."""
    from harness.executors.isolation import run_isolated
    cfg = load_config(config([{"file": str(bad_dir / "unreferenced.obj")}], {"smoothing": ["pygel.laplacian"]}))
    row, _ = run_isolated(cfg.cases[0], timeout=60)
    assert row["status"] == "error" and "SIGFPE on meshes with fewer than 8 vertices" in row["error"], row["error"]


def test_a_file_that_cannot_be_read_is_a_config_problem_and_a_mesh_error(tmp_path):
    """A mesh file whose read fails (here a link to /proc/self/mem, which answers EIO at offset 0:
    the suite runs as root, where chmod 000 does not stop a read) is one config problem naming its
    key path, and `read_mesh` says InvalidMeshError, not an OSError traceback."""
    from harness.errors import InvalidMeshError
    link = tmp_path / "mem.obj"
    link.symlink_to("/proc/self/mem")
    with pytest.raises(ConfigError, match=r"meshes\[0\]\.file: cannot read"):
        load_config(config([{"file": str(link)}], {"laplacian": ["scratch.cotan"]}))
    with pytest.raises(InvalidMeshError, match="cannot read it"):
        read_mesh(link)


def test_a_file_changed_after_the_run_started_is_an_error_row(tmp_path):
    """Case ids hash a file's bytes when the config is read; a case whose file was edited since
    (here: before the cases ran) is an error row saying so, not a row of another mesh under the
    same label and case id."""
    p = tmp_path / "m.obj"
    p.write_text(_obj(OCTA_V, OCTA_F))
    cfg = load_config(config([{"file": str(p)}], {"laplacian": ["scratch.cotan", "libigl.cotan"]}))
    p.write_text(_obj([(2 * x, y, z) for x, y, z in OCTA_V], OCTA_F))
    frames = harness.run(cfg, out=tmp_path / "out", workers=1)
    df = frames["laplacian"]
    assert len(df) == 2 and (df["status"] == "error").all(), df[["method", "status", "error"]]
    assert df["error"].str.contains("the file changed since the run started").all(), df["error"].tolist()


def test_the_vectorised_obj_reader_equals_the_general_one(bad_dir, tmp_path):
    """A plain OBJ (three numbers a vertex, three indices a face) is read by numpy in one pass;
    it must give exactly the general reader's arrays, and leave every other file (slashes,
    polygons, negative or out-of-range indices, other line breaks, short lines) to it."""
    import harness.mesh_formats as M
    rng = np.random.default_rng(3)
    V = rng.standard_normal((500, 3)) * 10.0 ** rng.integers(-8, 8, (500, 1))
    F = rng.integers(0, 500, (900, 3))
    lines = [f"v {float(x)!r} {float(y)!r}\t{z:.17g}" for x, y, z in V] + ["# c", "vn 0 0 1", "g x"] + \
            [f"  f {a + 1} {b + 1} {c + 1}  " for a, b, c in F]
    texts = {"plain": "\n".join(lines), "crlf": "\r\n".join(lines) + "\r\n"}
    texts["four"] = texts["plain"].replace("v ", "v 1 ", 1)               # a vertex with four numbers
    texts["short"] = texts["plain"].replace("  f ", "f 1 2\n  f ", 1)     # a face with two
    texts["cr"] = texts["plain"].replace("\n", "\r", 3)
    texts["negative"] = texts["plain"] + "\nf -1 -2 -3"
    texts["word"] = texts["plain"].replace("v ", "v x", 1)
    # a review: a short line and a long one balanced out (the fast path re-split them across lines),
    # whitespace str.split knows and the patterns did not (a line dropped, the indices shifted)
    texts["short_long_v"] = "v 0 0 0\nv 1 0\nv 0.5 0 1 0\nv 0 0 1\nf 1 2 3\n"
    texts["short_long_f"] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2\nf 4 1 4 3\n"
    texts["nbsp"] = "v 0 0 0\n\u00a0v 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 2 3 4\n"
    texts["em"] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf\u20031 2 3\nf 1 2 3\n"
    texts["unit_sep"] = "v 0 0 0\nv 1 0 0\x1f\nv 0 1 0\nf 1 2 3\n"
    texts["nan_paren"] = "v nan(1) 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
    texts["comment"] = "v 1 0 0 # c\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
    for p in sorted(bad_dir.glob("*.obj")):
        texts[p.name] = p.read_bytes().decode("utf-8", errors="replace")
    for name, text in texts.items():
        fast = M._read_obj_fast(text)
        try:
            V0, polys = _general(M, text)
        except Exception:  # noqa: BLE001 - the general reader refuses it: the fast one must not take it
            assert fast is None, name
            continue
        if fast is not None:
            F0, n_poly = M._fan(polys)
            assert n_poly == 0 and np.array_equal(fast[0], V0, equal_nan=True) and np.array_equal(fast[1], F0), name
    assert M._read_obj_fast(texts["plain"]) is not None and M._read_obj_fast(texts["crlf"]) is not None
    for name in ("four", "short", "cr", "negative", "word", "short_long_v", "short_long_f", "nbsp", "em", "unit_sep",
                 "nan_paren", "comment"):
        assert M._read_obj_fast(texts[name]) is None, name


def _general(M, text):
    fast, M._read_obj_fast = M._read_obj_fast, lambda t: None
    try:
        return M._read_obj(text)
    finally:
        M._read_obj_fast = fast


def test_size_and_finiteness_are_judged_on_the_vertices_the_faces_use():
    """A 1e-90 surface with one unused vertex at (1, 1, 1) was measured with that vertex (span 1:
    accepted, its noise rounded to nothing while the row said 0.1); a sound mesh whose only
    extreme vertex (1e70, or NaN) is unused was refused for it. The unused vertex is the repair."""
    from harness.errors import InvalidMeshError
    from harness.mesh import validate
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    far = np.array([[1.0, 1.0, 1.0]])
    with pytest.raises(InvalidMeshError, match="span of 1e-90"):
        validate(np.vstack([V * 1e-90, far]), F)
    for extra in (far * 1e70, far * np.nan):
        m = validate(np.vstack([V, extra]), F)
        assert m.repairs == ["removed 1 unreferenced vertex/vertices"] and len(m.V) == 4
    with pytest.raises(InvalidMeshError, match=r"1 vertices with NaN or inf coordinates \(first: \[4\]\)"):
        validate(np.vstack([far, V[:3], [[np.nan, 0, 0]]]), np.array([[1, 3, 2], [1, 2, 4], [1, 4, 3], [2, 3, 4]]))


def test_a_pair_keeps_its_readers_notes_and_an_stl_pair_is_refused_saying_why(tmp_path):
    """The clean half's reader repairs (polygons split) were dropped when the pair was validated,
    so a pair's rows said nothing of them; two STL halves (welded each by its own coordinates)
    were refused as 'faces differ'."""
    from harness import datasets
    from harness.errors import InvalidMeshError
    cube = ("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
            "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n")
    (tmp_path / "c.obj").write_text(cube)
    (tmp_path / "n.obj").write_text(cube.replace("v 1 1 1", "v 1.05 1 1"))
    src = datasets.cached({"file": str(tmp_path / "n.obj"), "clean": str(tmp_path / "c.obj")})
    assert src.clean.repairs == ["fan-triangulated 6 polygon(s) with more than 3 corners",
                                 "noisy file: fan-triangulated 6 polygon(s) with more than 3 corners"]
    assert src.noisy_V[6, 0] == 1.05
    tri = "solid s\n" + "".join(f"facet normal 0 0 1\nouter loop\nvertex {a}\nvertex {b}\nvertex {c}\nendloop\nendfacet\n"
                                for a, b, c in [("0 0 0", "1 0 0", "0 1 0"), ("0 0 0", "0 1 0", "0 0 1"),
                                                ("0 0 0", "0 0 1", "1 0 0"), ("1 0 0", "0 0 1", "0 1 0")]) + "endsolid s\n"
    (tmp_path / "c.stl").write_text(tri)
    (tmp_path / "n.stl").write_text(tri.replace("1 0 0", "1.01 0 0"))
    with pytest.raises(InvalidMeshError, match="an STL file cannot be half of a noisy/clean pair"):
        datasets.cached({"file": str(tmp_path / "n.stl"), "clean": str(tmp_path / "c.stl")})


def test_a_binary_ply_cut_inside_a_field_the_reader_skips_is_refused(tmp_path):
    """The general face loop stepped past a texture-coordinate list without checking the file's
    length: a PLY cut there was read whole, though a header promising more than the file holds is
    an error."""
    from harness.errors import InvalidMeshError
    V = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    F = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
            "property float z\nelement face 4\nproperty list uchar int vertex_indices\n"
            "property list uchar float texcoord\nend_header\n").encode()
    body = b"".join(struct.pack("<3f", *v) for v in V)
    body += b"".join(struct.pack("<B3i", 3, *f) + struct.pack("<B6f", 6, *range(6)) for f in F)
    (tmp_path / "whole.ply").write_bytes(head + body)
    assert read_mesh(tmp_path / "whole.ply").F.tolist() == [list(f) for f in F]
    (tmp_path / "cut.ply").write_bytes(head + body[:-12])
    with pytest.raises(InvalidMeshError, match="truncated PLY"):
        read_mesh(tmp_path / "cut.ply")


@pytest.mark.parametrize("counts", ["4 4 0", "4 4"])
def test_an_off_token_stream_may_start_on_its_counts_line(tmp_path, counts):
    """A plain OFF laid out freely is a token stream; its data may begin on the counts line, after
    the edge count or without it (it was 'truncated OFF: file has 0 data lines')."""
    body = "0 0 0 1 0 0 0 1 0 0 0 1 3 0 2 1 3 0 1 3 3 0 3 2 3 1 2 3"
    for text in (f"OFF {counts} {body}\n", f"OFF\n{counts} {body}\n"):
        (tmp_path / "s.off").write_text(text)
        m = read_mesh(tmp_path / "s.off")
        assert m.V.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], text
        assert m.F.tolist() == [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], text


def test_an_off_stream_that_reads_whole_with_and_without_an_edge_count_is_refused(tmp_path):
    """A review fuzzed 20,000 small OFF streams: the first layout that used every token won, so a
    file without an edge count whose first coordinate could pass for one was read with the
    wrong geometry (2,878 misread). Both readings whole: the file is refused, never guessed."""
    from harness.errors import InvalidMeshError
    (tmp_path / "a.off").write_text("OFF\n4 3 1 0 1 4\n0 3 1 0 4 3 3 2 4 3 0 4 3 3 1 4 0 4 0 1 2 0\n")
    with pytest.raises(InvalidMeshError, match="ambiguous OFF"):
        read_mesh(tmp_path / "a.off", repair=False)
    # a face of fewer than 3 corners is no reading (this file was ambiguous through a 2-corner face)
    (tmp_path / "a2.off").write_text("OFF\n4 3 0 1 1 1\n0 2 0 0 0 0 3 0 3 2 0 1 3 0 2 3 3 2 1 0\n")
    assert read_mesh(tmp_path / "a2.off", repair=False).F.tolist() == [[2, 0, 1], [0, 2, 3], [2, 1, 0]]
    # a fourth review: a value missing from a vertex line of a file with an edge count was read with
    # the edge count as the first coordinate, every coordinate shifted by one; a file short of a
    # vertex failed with "face with 1 corners"
    (tmp_path / "m.off").write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1\n3 0 1 2\n")
    with pytest.raises(InvalidMeshError):
        read_mesh(tmp_path / "m.off")
    (tmp_path / "t.off").write_text("OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 3\n")
    with pytest.raises(InvalidMeshError, match="truncated OFF"):
        read_mesh(tmp_path / "t.off")
    # a second review: the shifted reading raised on a coordinate (1.5) where a count belongs, and
    # half of 16,472 valid free-layout files (counts with an edge count on their own line) were refused
    (tmp_path / "b.off").write_text("OFF\n4 3 6\n0 0 0 1 0 0\n0 1 0 0 0 1.5\n3 0 2 1\n3 0 1 3 3 0 3 2\n")
    m = read_mesh(tmp_path / "b.off")
    assert m.V.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.5]] and m.F.tolist() == [[0, 2, 1], [0, 1, 3], [0, 3, 2]]
    # a third review: one coordinate after the counts (no edge count) was skipped as the edge count
    # even where it cannot be one (0.5): the file was then refused or, worse, read shifted
    # and a free layout whose line count happens to equal nv + nf was read line by line: faces of 0 corners
    (tmp_path / "d.off").write_text("OFF 3 2\n2 0 1 3\n1 2 0 2\n2 3 1\n0 2 3 2\n0 1\n")
    m = read_mesh(tmp_path / "d.off", repair=False)
    assert m.V.tolist() == [[2, 0, 1], [3, 1, 2], [0, 2, 2]] and m.F.tolist() == [[1, 0, 2], [2, 0, 1]]
    (tmp_path / "c.off").write_text("OFF\n4 3 0.5\n0 0 1 0 0\n0 1 0 0 0 1\n3 0 2 1 3 0 1 3 3 0 3 2\n")
    m = read_mesh(tmp_path / "c.off")
    assert m.V.tolist() == [[0.5, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]] and m.F.tolist() == [[0, 2, 1], [0, 1, 3], [0, 3, 2]]


def test_a_binary_stl_with_bytes_past_its_triangles_says_so(tmp_path):
    """Its header began with 'solid', so the padded file was called a truncated ASCII STL."""
    from harness.errors import InvalidMeshError
    tri = struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0)
    data = b"solid made by a tool".ljust(80, b" ") + struct.pack("<I", 1) + tri
    (tmp_path / "ok.stl").write_bytes(data)
    assert read_mesh(tmp_path / "ok.stl", repair=False).F.shape == (1, 3)
    (tmp_path / "pad.stl").write_bytes(data + b"\0" * 4)
    with pytest.raises(InvalidMeshError, match=r"binary STL of 1 triangle\(s\) with 4 byte\(s\) past them"):
        read_mesh(tmp_path / "pad.stl")


def test_a_coff_off_one_vertex_a_line_is_not_called_truncated(tmp_path):
    """A COFF (or NOFF) has extra values a vertex, so only its one-vertex-a-line layout is read; one
    laid out freely was refused as 'truncated' with all its values there. It still is refused, but
    saying both things it may be; a COFF one vertex a line reads, colours ignored."""
    from harness.errors import InvalidMeshError
    rows = ["0 0 0 255 0 0 255", "1 0 0 0 255 0 255", "0 1 0 0 0 255 255", "0 0 1 9 9 9 255"]
    faces = ["3 0 2 1", "3 0 1 3", "3 0 3 2", "3 1 2 3"]
    (tmp_path / "lines.off").write_text("COFF\n4 4 0\n" + "\n".join(rows + faces) + "\n")
    assert read_mesh(tmp_path / "lines.off").V.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    (tmp_path / "free.off").write_text("COFF\n4 4 0\n" + " ".join(rows) + "\n" + " ".join(faces) + "\n")
    with pytest.raises(InvalidMeshError, match="COFF: header promises 4 vertices and 4 faces, file has 2 data lines: "
                                               "truncated, or not one vertex and one face a line"):
        read_mesh(tmp_path / "free.off")
