"""The compiled unique-edge extraction equals the numpy key sort on real and hostile meshes."""
import numpy as np
import pytest

from harness import datasets
from harness.core import geometry as g
from harness.core._edges_kernel import edges_and_counts


def _numpy(F):
    keys, n = g.edge_keys(F)
    keys = np.sort(keys)
    start = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]])
    return np.stack([keys[start] // n, keys[start] % n], 1), np.diff(np.r_[start, keys.size])


def _soup(seed):
    """Random faces over few vertices: non-manifold edges, repeated faces, degenerate faces
    (a vertex twice) and a high-valence vertex (rows longer than the insertion-sort limit)."""
    rng = np.random.default_rng(seed)
    F = rng.integers(0, 40, size=(3000, 3))
    F[:200, 0] = 7                                  # vertex 7 in 200+ faces
    F[200:210, 1] = F[200:210, 0]                   # degenerate faces
    return np.vstack([F, F[:50]])                   # repeated faces


@pytest.mark.parametrize("F", [datasets.load("armadillo").clean.F, datasets.load("bunny").clean.F,
                               _soup(0), _soup(1)], ids=["armadillo", "bunny", "soup0", "soup1"])
def test_compiled_edges_equal_the_key_sort(F):
    F = np.ascontiguousarray(F, dtype=np.int64)
    E, c = edges_and_counts(F, int(F.max()) + 1)
    E0, c0 = _numpy(F)
    assert np.array_equal(E, E0) and np.array_equal(c, c0)


def _glued_cones(k):
    """Two closed cones of k faces each sharing their apex 0: 2k corners at vertex 0 in two
    fans (above the pairwise-comparison limit of the compiled fan count when k > 24)."""
    F = []
    for base in (1, 1 + k + 1):
        tip = base + k
        for i in range(k):
            a, b = base + i, base + (i + 1) % k
            F += [[0, a, b], [tip, b, a]]
    return np.array(F, dtype=np.int64)


@pytest.mark.parametrize("F, expect", [(datasets.load("armadillo").clean.F, []), (_soup(0), ...), (_soup(1), ...),
                                       (np.random.default_rng(2).integers(0, 2000, size=(1500, 3)), None),
                                       (_glued_cones(5), [0]), (_glued_cones(40), [0])],
                         ids=["armadillo", "soup0", "soup1", "sparse", "cones5", "cones40"])
def test_compiled_fan_count_equals_the_corner_graph(F, expect):
    """Non-manifold vertices (more than one edge-connected fan): the compiled per-vertex union
    find gives the same vertices as the corner graph's connected components (numpy path)."""
    from harness import mesh
    from harness.core._edges_kernel import fan_counts
    F = np.ascontiguousarray(F, dtype=np.int64)
    n = int(F.max()) + 1
    saved, mesh.COMPILED_EDGES_FROM = mesh.COMPILED_EDGES_FROM, 10**12      # force the numpy path
    try:
        ref = mesh.nonmanifold_vertices(F, n)
    finally:
        mesh.COMPILED_EDGES_FROM = saved
    assert np.array_equal(np.flatnonzero(fan_counts(F, n) > 1), ref)
    if expect is None:
        assert ref.size > 100                   # scattered faces: many vertices in several fans
    elif expect is not ...:
        assert ref.tolist() == expect


def test_row_cross_products_equal_numpy_bit_for_bit():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(5000, 3)) * 10.0 ** rng.integers(-8, 8, size=(5000, 1))
    b = rng.normal(size=(5000, 3))
    a[:5] = [[np.inf, 0, 1], [np.nan, 1, 2], [0, 0, 0], [1e308, 1e308, 1], [-0.0, 0.0, 0.0]]
    with np.errstate(all="ignore"):
        assert np.array_equal(g.cross_rows(a, b), np.cross(a, b), equal_nan=True)
