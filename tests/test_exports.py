"""Saved result meshes: PLY with a per-vertex quality that MeshLab reads as the distance to the
clean surface."""
import numpy as np
import pytest

from harness import run
from harness.datasets import load


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    out = tmp_path_factory.mktemp("ply")
    run({"name": "ply", "meshes": ["knight"], "noise": [{"model": "gaussian_normal", "levels": [0.3]}],
         "tasks": {"smoothing": {"methods": ["scratch.taubin"]},
                   "simplification": {"methods": ["scratch.qem"], "params": {"target_ratio": [0.3]}}},
         "repeats": 1, "save_meshes": True}, out=out, quiet=True)
    return out


def test_ply_quality_is_the_distance_to_the_clean_surface_in_pymeshlab(saved):
    """PyMeshLab loads every saved PLY with the vertex positions we wrote and a per-vertex
    quality equal to VCG's own distance from each vertex to the clean surface
    (``compute_scalar_by_distance_from_another_mesh_per_vertex``). PyMeshLab keeps vertex
    quality in single precision, so both sides carry float32 rounding: relative 1e-6 plus 1e-9 of the diagonal
    (measured ~6e-8). The file itself holds the double-precision distance: equal to our metric
    to 1e-15 relative."""
    from harness.mesh import read_mesh
    from harness.metrics.surface_distance import point_surface_distance
    import pymeshlab
    clean = load("knight").clean
    diag = clean.diagonal()
    files = sorted((saved / "meshes").glob("*.ply"))
    assert len(files) == 3                                   # two results + one noisy input
    for f in files:
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(clean.V, clean.F), "clean")
        ms.load_new_mesh(str(f))
        m = ms.current_mesh()
        ours = m.vertex_scalar_array().copy()
        assert ours.shape == (m.vertex_number(),) and ours.max() > 1e-4 * diag
        ms.compute_scalar_by_distance_from_another_mesh_per_vertex(measuremesh=1, refmesh=0, signeddist=False)
        theirs = ms.current_mesh().vertex_scalar_array()
        assert np.allclose(ours, theirs, rtol=1e-6, atol=1e-9 * diag), f.name
        lines = f.read_text().splitlines()
        n = m.vertex_number()
        start = lines.index("end_header") + 1
        q = np.array([float(ln.split()[3]) for ln in lines[start:start + n]])
        mesh = read_mesh(f, repair=False)
        assert np.allclose(q, point_surface_distance(mesh.V, clean.V, clean.F), rtol=1e-15, atol=0)
        assert np.allclose(q, ours, rtol=1e-6, atol=1e-9 * diag)
    text = files[0].read_text()
    assert "comment quality = unsigned distance of each vertex to the clean surface" in text


def test_file_meshes_take_a_name_and_a_known_level(tmp_path):
    """A given pair with ``name`` and ``level``: the rows carry that label and noise level; the
    name is a label only (same case ids as without it); bad values are listed with their key."""
    import pandas as pd
    from harness.config import load_config
    from harness.errors import ConfigError
    src = __import__("harness.datasets", fromlist=["DATA_DIR"]).DATA_DIR / "denoise" / "Fandisk0.3"
    base = {"name": "named", "repeats": 1, "tasks": {"smoothing": {"methods": ["scratch.taubin"]}}}
    pair = {"file": str(src / "Noisy.obj"), "clean": str(src / "Original.obj")}
    cfg = {**base, "meshes": [{**pair, "name": "fandisk-zhang", "level": 0.3}]}
    run(cfg, out=tmp_path / "r", quiet=True)
    rows = pd.read_csv(tmp_path / "r" / "smoothing.csv")
    assert rows["mesh"].tolist() == ["fandisk-zhang"] and rows["noise_level"].tolist() == [0.3]
    ids = lambda c: [x.case_id for x in load_config(c).cases]                      # noqa: E731
    assert ids({**base, "meshes": [{**pair, "name": "other", "level": 0.3}]}) == ids(cfg)
    with pytest.raises(ConfigError) as e:
        load_config({**base, "meshes": [{"file": pair["file"], "level": 0.3},
                                        {**pair, "name": "a b", "level": -1}]})
    msg = str(e.value)
    assert "meshes[0].level: the noise level of a given pair needs 'clean'" in msg
    assert "meshes[1].name:" in msg and "meshes[1].level:" in msg


def test_impulsive_entries_differing_only_in_fraction_are_different_inputs(tmp_path):
    """Two impulsive entries at one level and seed, fractions 0.1 and 0.9, are different inputs:
    their rows name the fraction, each gets its own winners row and its own saved input mesh
    (rows alike would be averaged as seeds of one cell, and the inputs would share one file)."""
    import pandas as pd
    from harness.datasets import load
    from harness.mesh import read_mesh
    from harness.noise import apply_noise
    out = tmp_path / "frac"
    run({"name": "frac", "meshes": ["knight"], "save_meshes": True, "repeats": 1,
         "noise": [{"model": "impulsive", "levels": [0.5], "fraction": 0.1},
                   {"model": "impulsive", "levels": [0.5], "fraction": 0.9},
                   {"model": "impulsive", "levels": [0.5]}],
         "tasks": {"smoothing": {"methods": ["scratch.taubin"]}}}, out=out, quiet=True)
    rows = pd.read_csv(out / "smoothing.csv")
    assert sorted(rows.noise_model) == ["impulsive", "impulsive(fraction=0.1)", "impulsive(fraction=0.9)"]
    assert len(set(rows.input_ev_mean)) == 3
    win = pd.read_csv(out / "winners.csv")
    assert sorted(win[win.metric == "ev_mean"].noise_model) == sorted(rows.noise_model)
    clean = load("knight").clean
    for frac, name in ((0.1, "knight-impulsive-fraction0.1-0.5-0-input.ply"),
                       (0.9, "knight-impulsive-fraction0.9-0.5-0-input.ply"),
                       (1.0, "knight-impulsive-0.5-0-input.ply")):
        V = read_mesh(out / "meshes" / name, repair=False).V
        want = apply_noise(clean.V, clean.F, "impulsive", 0.5, 0, mesh_key="knight", fraction=frac,
                           frame=clean.noise_frame)
        np.testing.assert_allclose(V, want, rtol=0, atol=1e-12 * clean.diagonal())


def test_two_levels_that_agree_to_six_digits_save_two_inputs():
    """A review: ``{level:g}`` named the inputs at 0.1234567 and 0.1234568 alike, so the second
    was never written and the saved file was the other level's input."""
    from harness.config import load_config
    from harness.runner import input_mesh_name
    cfg = load_config({"name": "lv", "meshes": ["knight"], "noise": [
        {"model": "gaussian_normal", "levels": [0.1234567, 0.1234568, 0.5]}, {"model": "none"}],
        "tasks": {"smoothing": {"methods": ["scratch.taubin"]}}})
    names = sorted({input_mesh_name(c) for c in cfg.cases})
    assert names == ["knight-gaussian_normal-0.1234567-0-input.ply", "knight-gaussian_normal-0.1234568-0-input.ply",
                     "knight-gaussian_normal-0.5-0-input.ply", "knight-none-0-0-input.ply"], names
