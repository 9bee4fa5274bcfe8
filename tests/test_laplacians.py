"""Cross-validation of the scratch Laplacians against libigl on every bundled mesh.

Tolerances (relative to the largest magnitude of the reference matrix):
- cotangent weights vs ``igl.cotmatrix``: 1e-10;
- barycentric / voronoi mass vs ``igl.massmatrix``: 1e-10;
- intrinsic Delaunay vs ``igl.intrinsic_delaunay_cotmatrix``: 1e-8;
- uniform: exact (integers).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import methods

igl = pytest.importorskip("igl")

MESH_DIR = Path(__file__).resolve().parents[1] / "harness" / "data" / "meshes"
MESH_FILES = sorted(p for p in MESH_DIR.iterdir() if p.suffix in (".obj", ".off", ".ply", ".stl"))
_CACHE: dict = {}


def load(path: Path):
    if path not in _CACHE:
        V, F = igl.read_triangle_mesh(str(path))
        _CACHE[path] = (np.ascontiguousarray(V, dtype=np.float64), np.ascontiguousarray(F, dtype=np.int64))
    return _CACHE[path]


def rel_err(A, B) -> float:
    """max |A - B| / max |B| for sparse or dense arrays."""
    D = abs(sp.csr_matrix(A) - sp.csr_matrix(B))
    return float(D.max()) / float(abs(sp.csr_matrix(B)).max())


def test_bundled_meshes_found():
    assert len(MESH_FILES) >= 10


@pytest.mark.parametrize("path", MESH_FILES, ids=lambda p: p.stem)
def test_cotan_matches_libigl(path):
    V, F = load(path)
    for mass, kind in (("voronoi", igl.MASSMATRIX_TYPE_VORONOI),
                       ("barycentric", igl.MASSMATRIX_TYPE_BARYCENTRIC)):
        r = methods.get("scratch.cotan")(V, F, mass=mass)
        ref = methods.get("libigl.cotan")(V, F, mass=mass)
        L = igl.cotmatrix(V, F)
        assert rel_err(r.W, L) < 1e-10
        assert rel_err(r.M, igl.massmatrix(V, F, kind)) < 1e-10
        assert rel_err(ref.W, L) == 0.0
    assert methods.get("scratch.cotan")(V, F, mass="none").M is None


@pytest.mark.parametrize("path", MESH_FILES, ids=lambda p: p.stem)
def test_uniform_exact(path):
    V, F = load(path)
    W = methods.get("scratch.uniform")(V, F).W
    # reference: igl.adjacency_matrix, diagonal = -degree; integers, so exact equality
    A = sp.csr_matrix(igl.adjacency_matrix(F), dtype=float)
    if A.shape[0] < V.shape[0]:
        A.resize((V.shape[0], V.shape[0]))
    ref = A - sp.diags(np.asarray(A.sum(axis=1)).ravel())
    assert abs(W - ref).max() == 0.0
    r = methods.get("scratch.umbrella")(V, F)
    assert abs(r.W - ref).max() == 0.0
    deg = np.asarray(A.sum(axis=1)).ravel()
    assert np.array_equal(r.M.diagonal(), np.where(deg > 0, deg, 1.0))


@pytest.mark.parametrize("path", MESH_FILES, ids=lambda p: p.stem)
def test_intrinsic_delaunay_matches_libigl(path):
    """W vs igl.intrinsic_delaunay_cotmatrix to 1e-8; voronoi mass vs igl to 1e-10.

    The barycentric mass of an intrinsic Delaunay triangulation depends on how cocircular
    quads are split (fandisk has many), so it is checked against ``igl.massmatrix_intrinsic``
    on our own triangulation (1e-10), and its total against the surface area (1e-12).
    """
    from harness.core.geometry import cotangents_from_lengths
    from methods.scratch.intrinsic_delaunay import intrinsic_delaunay_triangulation
    V, F = load(path)
    r = methods.get("scratch.intrinsic_delaunay")(V, F, mass="voronoi")
    L, l_ref, F_ref = igl.intrinsic_delaunay_cotmatrix(V, F)
    assert rel_err(r.W, L) < 1e-8
    Mv = igl.massmatrix_intrinsic(l_ref, F_ref, igl.MASSMATRIX_TYPE_VORONOI)
    assert rel_err(r.M, Mv) < 1e-10
    l_int, F_int, _ = intrinsic_delaunay_triangulation(V, F)
    rb = methods.get("scratch.intrinsic_delaunay")(V, F, mass="barycentric")
    Mb = igl.massmatrix_intrinsic(l_int, F_int, igl.MASSMATRIX_TYPE_BARYCENTRIC)
    Mb.resize(rb.M.shape)
    assert rel_err(rb.M, Mb) < 1e-10
    area = igl.doublearea(V, F).sum() / 2
    assert abs(rb.M.diagonal().sum() - area) < 1e-12 * area
    # every flippable interior edge of our result is Delaunay: cot a + cot b >= -1e-9
    C, _ = cotangents_from_lengths(l_int)
    from methods.scratch.intrinsic_delaunay import halfedge_twins
    tw = halfedge_twins(F_int)
    h = np.flatnonzero(tw >= 0)
    cot_of = lambda hh: C[hh // 3, hh % 3]
    assert (cot_of(h) + cot_of(tw[h])).min() > -1e-9


def test_mean_value_and_normalized_against_loops():
    """Mean value weights vs a direct per-face loop with arccos/tan (1e-12 relative);
    cotan_normalized = rows of igl.cotmatrix divided by minus its diagonal (1e-12)."""
    V, F = load(MESH_DIR / "decimated-knight.off")
    n = V.shape[0]
    ref = np.zeros((n, n))
    for f in F:
        for k in range(3):
            i, j, l = f[k], f[(k + 1) % 3], f[(k + 2) % 3]
            u, v = V[j] - V[i], V[l] - V[i]
            ang = np.arccos(np.clip(u @ v / np.linalg.norm(u) / np.linalg.norm(v), -1, 1))
            ref[i, j] += np.tan(ang / 2) / np.linalg.norm(u)
            ref[i, l] += np.tan(ang / 2) / np.linalg.norm(v)
    ref -= np.diag(ref.sum(1))
    W = methods.get("scratch.mean_value")(V, F).W
    assert np.abs(W.toarray() - ref).max() < 1e-12 * np.abs(ref).max()
    L = igl.cotmatrix(V, F)
    Wn = methods.get("scratch.cotan_normalized")(V, F).W
    refn = sp.diags(-1.0 / L.diagonal()) @ L
    assert rel_err(Wn, refn) < 1e-12
    assert np.allclose(Wn.diagonal(), -1.0)


def test_robust_tufted_equals_intrinsic_delaunay_on_closed_mesh():
    """On a closed manifold mesh the tufted cover's intrinsic Delaunay Laplacian (no
    mollification) is the intrinsic Delaunay Laplacian: 1e-8 relative on bunny."""
    pytest.importorskip("robust_laplacian")
    V, F = load(MESH_DIR / "bunny.off")
    r = methods.get("robust.tufted")(V, F, mollify_factor=0.0)
    L, _, _ = igl.intrinsic_delaunay_cotmatrix(V, F)
    assert rel_err(r.W, L) < 1e-8


def test_robust_tufted_rows_sum_to_zero_with_unreferenced_vertices():
    pytest.importorskip("robust_laplacian")
    V, F = load(MESH_DIR / "stanford-bunny.obj")
    W = methods.get("robust.tufted")(V, F).W
    assert np.abs(np.asarray(W.sum(axis=1))).max() < 1e-10 * abs(W).max()


def _degenerate_mesh():
    """A planar fan plus: a zero-area face (collinear corners), a face with a repeated vertex,
    a needle (area ~1e-14), a duplicated vertex (zero-length edge), an isolated vertex."""
    V = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [-0.5, 1, 0], [-1, 0, 0], [0, -1, 0],
                  [2, 0, 0],            # 6: collinear with 0, 1
                  [0.5, 1e-14, 0],      # 7: needle apex on edge 0-1
                  [1, 0, 0],            # 8: duplicate of vertex 1
                  [5, 5, 5]], float)    # 9: isolated
    F = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5], [0, 5, 1],
                  [0, 1, 6],            # zero area (collinear)
                  [1, 1, 2],            # repeated vertex
                  [1, 0, 7],            # needle
                  [1, 8, 2]], np.int64)  # zero-length edge 1-8
    return V, F


@pytest.mark.parametrize("name", ["scratch.uniform", "scratch.umbrella", "scratch.cotan",
                                  "scratch.cotan_normalized", "scratch.mean_value",
                                  "scratch.intrinsic_delaunay", "robust.tufted"])
def test_degenerate_triangles_give_finite_weights(name):
    if not methods.get(name).is_available:
        pytest.skip(f"{name} unavailable")
    V, F = _degenerate_mesh()
    r = methods.get(name)(V, F)
    W = sp.csr_matrix(r.W)
    assert np.isfinite(W.data).all()
    assert np.abs(np.asarray(W.sum(axis=1))).max() <= 1e-9 * max(1.0, abs(W).max())
    if r.M is not None:
        assert np.isfinite(r.M.data).all()


def test_compiled_assembly_equals_numpy_path():
    """The one-off compiled assembly (used by scratch.cotan from FAST_MIN_FACES faces) and the
    cached-pattern re-assembly equal the numpy path to 1e-13 relative, with the same sorted
    CSR structure, on a closed mesh, an open one (camelhead), degenerate faces (zero area,
    repeated vertex, needle, isolated vertex) and a vertex of valence 60."""
    from methods.scratch import operators as op
    V, F = load(MESH_DIR / "decimated-knight.off")
    t = np.linspace(0, 2 * np.pi, 61)[:-1]              # a bumpy closed fan of 60 triangles:
    fan_V = np.c_[np.cos(t), np.sin(t), 0.1 * np.sin(5 * t)]    # row 0 has 120 pairs to sort
    fan_V = np.r_[[[0.0, 0.0, 0.3]], fan_V]
    fan_F = np.c_[np.zeros(60, np.int64), 1 + np.arange(60), 1 + (np.arange(60) + 1) % 60]
    meshes = [(V, F), load(MESH_DIR / "camelhead.off"), _degenerate_mesh(), (fan_V, fan_F)]
    for V, F in meshes:
        pattern = op.CotanPattern(F, V.shape[0])
        for mass in ("voronoi", "barycentric"):
            W, M = op.cotan_laplacian(V, F, mass)
            Wp, Mp = pattern.assemble(V, mass)
            assert np.isfinite(W.data).all() and np.isfinite(M.data).all()
            assert rel_err(W, op.cotan_weights(V, F)) < 1e-13
            assert rel_err(M, op.mass_matrix(V, F, mass)) < 1e-13
            assert rel_err(Wp, W) < 1e-13 and rel_err(Mp, M) < 1e-13
            assert np.array_equal(W.indptr, Wp.indptr) and np.array_equal(W.indices, Wp.indices)
            assert W.has_sorted_indices
    V, F = meshes[0]
    pattern = op.CotanPattern(F, V.shape[0])
    V2 = V + 0.01 * np.sin(7 * V[:, [1, 2, 0]])
    W2, M2 = pattern.assemble(V2)
    assert rel_err(W2, igl.cotmatrix(V2, F)) < 1e-10
    assert rel_err(M2, igl.massmatrix(V2, F, igl.MASSMATRIX_TYPE_VORONOI)) < 1e-10
    assert W2.has_sorted_indices


@pytest.mark.parametrize("bad", [-1, 4, 2**40])
def test_compiled_assembly_rejects_out_of_range_faces(bad):
    """A face index outside [0, n) is a ValueError from both compiled paths (they write by
    index; without the check a negative index corrupted memory and n gave a wrong W)."""
    from methods.scratch import operators as op
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, bad]])
    with pytest.raises(ValueError, match=r"face indices must lie in \[0, 4\)"):
        op.cotan_laplacian(V, F)
    with pytest.raises(ValueError, match=r"face indices must lie in \[0, 4\)"):
        op.CotanPattern(F, 4)


def test_cotan_pattern_rejects_positions_of_another_size():
    """A pattern re-assembles only positions for its own vertex count (its numeric pass reads V
    and writes the areas by the pattern's indices)."""
    from methods.scratch import operators as op
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    pattern = op.CotanPattern(F, 4)
    for bad in (V[:3], np.vstack([V, V]), V[:, :2]):
        with pytest.raises(ValueError, match="this pattern is for 4 vertices"):
            op.cotan_laplacian(bad, F, pattern=pattern)
    W, _ = op.cotan_laplacian(V, F, pattern=pattern)
    assert W.shape == (4, 4)


@pytest.mark.parametrize("name", ["libigl.cotan", "libigl.intrinsic_delaunay"])
def test_libigl_adapters_on_degenerate_mesh(name):
    """libigl does not clamp (zero-area faces give inf/NaN, or std::bad_alloc in the intrinsic
    flips), so the adapters refuse such faces by name; W and M are n x n even with a trailing
    isolated vertex (libigl sizes its matrices by max(F) + 1)."""
    V, F = _degenerate_mesh()
    with pytest.raises(ValueError, match=r"zero-area face\(s\) \(first: \[5, 6"):
        methods.get(name)(V, F)
    import importlib                             # the module's function, called directly, screens too
    direct = getattr(importlib.import_module("methods.libigl.laplacian"), name.split(".")[1])
    with pytest.raises(ValueError, match=r"zero-area face\(s\) \(first: \[5, 6"):
        direct(V, F)
    sound = [0, 1, 2, 3, 4]                     # the fan, with isolated vertices 6..9 after it
    r = methods.get(name)(V, F[sound])
    assert r.W.shape == (V.shape[0], V.shape[0]) and r.M.shape == r.W.shape
    assert np.isfinite(r.W.data).all() and abs(r.W[9]).sum() == 0


def test_zero_area_faces_screen_keeps_every_degenerate_face():
    """From COMPILED_EDGES_FROM faces, zero_area_faces screens with a compiled test before the
    exact measures; on a sphere with inserted flat caps (height / longest edge from 1e-3 down to
    0), needles, repeated and coincident vertices, at scales 1e-120 to 1e120 and far from the
    origin, it returns exactly the faces that the unscreened measures give."""
    from harness.core import geometry as g
    from harness.datasets import icosphere
    V0, F0 = icosphere(5)
    assert F0.shape[0] == 20480 >= g.COMPILED_EDGES_FROM
    n = V0.shape[0]
    extra_V, extra_F = [], []
    for k, h in enumerate([1e-3, 1e-5, 3e-6, 1e-7, 1e-8, 1e-9, 1e-12, 1e-16, 1e-20, 0.0]):
        base = n + 3 * k
        extra_V += [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.37, h, 0.0]]    # cap: apex near the long edge
        extra_F += [[base, base + 1, base + 2]]
    base = n + len(extra_V)
    extra_V += [[0.0, 0.0, 0.0], [1e-9, 0.0, 0.0], [0.5, 1.0, 0.0], [0.5, 1.0, 0.0]]  # needle, duplicate
    extra_F += [[base, base + 1, base + 2], [base, base + 2, base + 3], [base, base, base + 2]]
    V = np.vstack([V0, np.array(extra_V)])
    F = np.vstack([F0, np.array(extra_F, np.int64)])
    rng = np.random.default_rng(0)
    scales = [(1.0, 0.0), (1e-120, 0.0), (1e-81, 0.0), (1e-78, 0.0), (1e-60, 0.0), (1e60, 0.0),
              (1e120, 0.0), (1.0, 1e6), (1e-3, 1e3)]
    for scale, offset in scales:
        W = V * scale + offset
        R = np.linalg.qr(rng.standard_normal((3, 3)))[0]
        for P in (W, (W - offset) @ R.T + offset):
            with np.errstate(over="ignore", under="ignore", invalid="ignore"):   # 1e120: squares overflow
                exact = np.flatnonzero(g._zero_area(P, F))
                got = g.zero_area_faces(P, F)
            assert np.array_equal(got, exact), (scale, offset, got, exact)
            assert {20491, 20492} <= set(exact.tolist())    # the duplicate and the repeated vertex
            assert P is not W or 20489 in exact              # the h = 0 cap, unless rotated
    wrapped = F.copy()
    wrapped[-1, 0] -= V.shape[0]                             # -1 style indices read as numpy does
    assert np.array_equal(g.zero_area_faces(V, wrapped), g.zero_area_faces(V, F))
    for bad in (V.shape[0], -V.shape[0] - 1, 2**40):        # the screen reads V unchecked: refuse first
        F_bad = F.copy()
        F_bad[-1, 2] = bad
        with pytest.raises(IndexError, match="out of bounds"):
            g.zero_area_faces(V, F_bad)


def test_a_mass_matrix_must_be_diagonal():
    """The task takes a lumped mass: an M with a nonzero entry off the diagonal is refused (also
    when stored as duplicates that do not cancel); stored zeros off the diagonal, or duplicates
    that cancel there, are a diagonal M."""
    from harness.errors import MethodFailed
    from harness.tasks import get
    from harness.tasks.laplacian import LaplacianResult
    task = get("laplacian")
    V = np.zeros((3, 3))
    F = np.array([[0, 1, 2]])
    W = sp.csr_matrix(np.array([[-2.0, 1, 1], [1, -2, 1], [1, 1, -2]]))

    def check(M):
        return task.validate_result("m", LaplacianResult(W=W, M=M), V, F)
    check(sp.diags([1.0, 2, 3]).tocsr())
    check(sp.csr_matrix((np.array([1.0, 0.0, 2, 3]), np.array([0, 1, 1, 2]), np.array([0, 2, 3, 4])), shape=(3, 3)))
    check(sp.csr_matrix((np.array([1.0, 0.5, -0.5, 2, 3]), np.array([0, 1, 1, 1, 2]), np.array([0, 3, 4, 5])),
                        shape=(3, 3)))                      # 0.5 - 0.5 off the diagonal: 0
    for M in (sp.csr_matrix(np.array([[1.0, 0.1, 0], [0.1, 2, 0], [0, 0, 3]])),
              sp.csr_matrix((np.array([1.0, 0.5, 0.5, 2, 3]), np.array([0, 1, 1, 1, 2]), np.array([0, 3, 4, 5])),
                            shape=(3, 3))):
        with pytest.raises(MethodFailed, match="non-diagonal M"):
            check(M)
