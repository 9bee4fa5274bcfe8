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
