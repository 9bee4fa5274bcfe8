"""Task ``spectrum``: eigensolvers against dense LAPACK, the sphere's analytic spectrum and its
convergence, residuals and M-orthogonality, the plain libigl + scipy pipeline, and the task
through the pipeline."""
import numpy as np
import pandas as pd
import pytest

import methods
from harness import datasets, run
from harness.tasks.spectrum import analytic


def sphere(s):
    src = datasets.load({"procedural": "sphere", "subdivisions": s})
    return src.clean.V, src.clean.F, src.shape


@pytest.mark.parametrize("kw", [{}, {"mass": "fem"}, {"operator": "intrinsic_delaunay"}, {"operator": "tufted"},
                                {"operator": "uniform", "mass": "barycentric"}])
def test_shift_invert_equals_dense(kw):
    """ARPACK shift-invert with our factorization = LAPACK dense eigh on the same (W, M), to 1e-9
    relative (k = 30, subdivision-3 icosphere, 642 vertices)."""
    V, F, _ = sphere(3)
    a = methods.get("scratch.spectrum")(V, F, k=30, **kw).values
    b = methods.get("scratch.spectrum")(V, F, k=30, solver="dense", **kw).values
    assert np.abs(a - b).max() <= 1e-9 * b.max()


def test_sphere_spectrum_converges_quadratically():
    """Cotan + Voronoi mass on icospheres against l(l+1) with multiplicity 2l+1 (k = 36, l <= 5):
    max relative error 3.2e-2 at subdivision 3 and 8.1e-3 at 4 (measured), a ratio ~4 per halving
    of the edge length (second order)."""
    errs = []
    for s in (3, 4):
        V, F, shape = sphere(s)
        lam = methods.get("scratch.spectrum")(V, F, k=36).values
        ref = analytic(shape, 36)
        errs.append((np.abs(lam[1:] - ref[1:]) / ref[1:]).max())
        assert abs(lam[0]) < 1e-8
    assert errs[1] < 0.012 and 3.3 < errs[0] / errs[1] < 4.7, errs


def test_plain_libigl_scipy_pipeline_agrees():
    """igl.cotmatrix + massmatrix + scipy eigsh (scipy's own LU) gives our eigenvalues to 1e-9."""
    V, F, _ = sphere(4)
    a = methods.get("scratch.spectrum")(V, F, k=20).values
    b = methods.get("libigl.eigsh")(V, F, k=20).values
    assert np.abs(a - b).max() <= 1e-9 * b.max()


def test_the_task_runs_through_the_pipeline(tmp_path):
    """Analytic errors on the sphere, blank on a file mesh; residuals and M-orthogonality small."""
    run({"name": "spec", "repeats": 1, "meshes": [{"procedural": "sphere", "subdivisions": 3}, "knight"],
         "noise": [{"model": "none"}],
         "tasks": {"spectrum": {"methods": [{"name": "scratch.spectrum", "params": {"mass": ["voronoi", "fem"]}},
                                            "libigl.eigsh"], "params": {"k": 16}}}}, out=tmp_path, quiet=True)
    df = pd.read_csv(tmp_path / "spectrum.csv")
    assert len(df) == 6 and (df["status"] == "ok").all(), df[["method", "error"]]
    sph = df[df["mesh"].str.startswith("sphere")]
    assert (sph["eig_rel_error_max"] < 0.05).all()
    assert df[df["mesh"] == "knight"]["eig_rel_error_max"].isna().all()
    assert (df["residual_max"] < 1e-8).all() and (df["orthogonality_error"] < 1e-8).all()
    assert "Laplacian spectrum" in (tmp_path / "report.html").read_text()
