"""Tests of the scratch smoothing methods (issue 4): definitions, stability, denoising.

Cross-validation against libigl / PyMeshLab / PyGEL3D lives in tests/test_smoothing_xval.py.
"""
from pathlib import Path

import igl
import numpy as np
import pytest

import methods
from methods.scratch.operators import adjacency

MESHES = Path(__file__).resolve().parents[1] / "harness" / "data" / "meshes"


def load(name):
    V, F = igl.read_triangle_mesh(str(MESHES / name))
    return np.asarray(V, np.float64), np.asarray(F, np.int64)


@pytest.fixture(scope="module")
def knight():
    return load("decimated-knight.off")


def test_explicit_uniform_step1_is_neighbour_mean(knight):
    """step 1 with uniform weights moves every vertex to its neighbours' mean (exact, 1e-12)."""
    V, F = knight
    A = adjacency(F, V.shape[0])
    deg = np.asarray(A.sum(axis=1)).ravel()
    expected = (A @ V) / deg[:, None]
    out = methods.get("scratch.explicit")(V, F, weights="uniform", step=1.0, iterations=1).V
    assert np.abs(out - expected).max() <= 1e-12 * np.abs(V).max()


def test_explicit_iterations_compose(knight):
    """Two calls of 3 iterations equal one call of 6 (same operator: row-normalized uniform)."""
    V, F = knight
    m = methods.get("scratch.explicit")
    a = m(m(V, F, iterations=3).V, F, iterations=3).V
    b = m(V, F, iterations=6).V
    assert np.allclose(a, b, rtol=0, atol=1e-12)
