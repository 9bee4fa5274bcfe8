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
