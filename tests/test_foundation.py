"""Foundation: metrics on closed-form cases, datasets, noise determinism, config errors, CLI end to end."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from harness import datasets
from harness.cli import main
from harness.config import load_config
from harness.errors import ConfigError, InvalidMeshError
from harness.tasks.smoothing import diverged
from harness.schema import columns
from harness.mesh import read_mesh, topology
from harness.metrics.hausdorff import hausdorff
from harness.metrics.normal_error import normal_error
from harness.metrics.surface_distance import point_surface_distance
from harness.metrics.triangle_quality import triangle_quality
from harness.core.geometry import area, volume
from harness.noise import apply_noise

MESH_DIR = Path(datasets.__file__).parent / "data" / "meshes"
KNIGHT, BUNNY = MESH_DIR / "decimated-knight.off", MESH_DIR / "bunny.off"



# ----------------------------------------------------------------------------- metrics

def test_equilateral_triangle_quality():
    V = np.array([[0, 0, 0], [1, 0, 0], [0.5, np.sqrt(3) / 2, 0]])
    q = triangle_quality(V, np.array([[0, 1, 2]]))
    assert q["min_angle"] == pytest.approx(60, abs=1e-9)
    assert q["max_angle"] == pytest.approx(60, abs=1e-9)
    assert q["radius_ratio_mean"] == pytest.approx(1.0, abs=1e-12)
    assert q["obtuse_fraction"] == 0


def test_right_triangle_quality():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]])
    q = triangle_quality(V, np.array([[0, 1, 2]]))
    assert q["max_angle"] == pytest.approx(90, abs=1e-9) and q["min_angle"] == pytest.approx(45, abs=1e-9)
    # 2 r / R for the isosceles right triangle: r = (2 - sqrt 2)/2, R = sqrt(2)/2
    assert q["radius_ratio_mean"] == pytest.approx(2 * (2 - np.sqrt(2)) / 2 / (np.sqrt(2) / 2), rel=1e-12)


def test_sphere_vertices_on_exact_sphere_and_distance():
    V, F = datasets.icosphere(4, radius=2.0)
    assert np.abs(np.linalg.norm(V, axis=1) - 2.0).max() < 1e-12
    # points at radius 3 are at distance >= 1 from the inscribed polyhedron, and close to 1
    P = 1.5 * V[:50]
    d = point_surface_distance(P, V, F)
    assert np.allclose(d, 1.0, atol=1e-12)      # the sphere's vertices are on the mesh


def test_volume_and_area_of_sphere_converge():
    V, F = datasets.icosphere(5)
    assert volume(V, F) == pytest.approx(4 / 3 * np.pi, rel=2e-3)
    assert area(V, F) == pytest.approx(4 * np.pi, rel=2e-3)


def test_hausdorff_of_translated_copy_equals_translation():
    V, F = datasets.icosphere(3)
    t = np.array([0.0, 0.0, 0.05])
    h = hausdorff(V, F, V + t, F, n_samples=5000)
    # every point moves by |t|; the closest point on the translated surface is at most |t| away,
    # and the extreme points along t realise it
    assert h["hausdorff"] == pytest.approx(0.05, rel=0.02)
    assert h["hausdorff"] <= 0.05 + 1e-12


def test_hausdorff_planes():
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.0]])
    F = np.array([[0, 1, 2], [0, 2, 3]])
    h = hausdorff(V, F, V + [0, 0, 0.3], F, n_samples=1000)
    assert h["hausdorff"] == pytest.approx(0.3, abs=1e-12)
    assert h["surface_dist_mean"] == pytest.approx(0.3, abs=1e-12) and h["surface_dist_mean_se"] < 1e-12


def test_normal_error_zero_and_flipped():
    V, F = datasets.icosphere(2)
    assert normal_error(V, V, F)["normal_error_deg"] == pytest.approx(0, abs=1e-6)
    c, s_ = np.cos(np.radians(30)), np.sin(np.radians(30))
    R = np.array([[1, 0, 0], [0, c, -s_], [0, s_, c]])
    tri = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]])
    assert normal_error(tri @ R.T, tri, np.array([[0, 1, 2]]))["normal_error_deg"] == pytest.approx(30)


def test_diverged():
    V = np.random.default_rng(0).random((10, 3))
    assert not diverged(V * 1.1, V)
    assert diverged(V * 1e4, V)
    W = V.copy()
    W[3, 1] = np.nan
    assert diverged(W, V)


# ----------------------------------------------------------------------------- datasets, mesh

def test_bundled_meshes_load_with_documented_counts():
    counts = {"bunny": (3485, 6966), "fandisk": (6475, 12946), "camelhead": (11381, 22704),
              "fertility": (4494, 9000), "max": (5272, 10540), "knight": (502, 1000),
              "woody": (694, 1267), "spot": (2930, 5856), "stanford-bunny": (34834, 69451)}
    for name, (nv, nf) in counts.items():
        m = datasets.load(name).clean
        assert (m.n_vertices, m.n_faces) == (nv, nf), name
    sb = datasets.load("stanford-bunny").clean
    assert len(sb.vertex_map) == 34834 and sb.vertex_map.max() == 35946
    assert datasets.resolve_bundled("decimated-knight") == "knight"


def test_topology_facts():
    assert topology(*_vf("fertility"))["genus"] == 4
    t = topology(*_vf("camelhead"))
    assert t["boundary_loops"] == 1 and t["manifold"]
    t = topology(*_vf("stanford-bunny"))
    assert t["boundary_loops"] == 5


def _vf(name):
    m = datasets.load(name).clean
    return m.V, m.F


def test_planes_delaunay_and_not():
    from scipy.spatial import Delaunay  # noqa: F401  (generator dependency)
    V, F = datasets.plane_delaunay(200, 1)
    V2, F2 = datasets.plane_nondelaunay(200, 1, 0.3)
    assert np.all(V[:, 2] == 0) and len(F) == len(F2)
    from methods.scratch.operators import cotan_weights
    W = cotan_weights(V, F)
    W2 = cotan_weights(V2, F2)
    off = W - __import__("scipy.sparse", fromlist=["diags"]).diags(W.diagonal())
    off2 = W2 - __import__("scipy.sparse", fromlist=["diags"]).diags(W2.diagonal())
    assert off.min() >= -1e-12                      # Delaunay: non-negative cotan weights
    assert off2.min() < -1e-3                       # flipped edges: negative weights


def test_pair_loads_noisy_and_clean():
    src = datasets.load("fandisk-noisy-0.3")
    assert src.noisy_V.shape == src.clean.V.shape and src.pair_level == 0.3
    assert np.abs(src.noisy_V - src.clean.V).max() > 0


def test_polygon_file_is_fan_triangulated(tmp_path):
    p = tmp_path / "quad.obj"
    p.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    m = read_mesh(p)
    assert m.n_faces == 2 and "fan-triangulated" in m.repairs[0]


@pytest.mark.parametrize("text,ext,needle", [
    ("", ".obj", "empty"), ("v 0 0 0\nv nan 0 0\nv 1 1 1\nf 1 2 3\n", ".obj", "NaN"),
    ("v 0 0 0\nf 1 2 3\n", ".obj", "line 2: face index 3, but the file has 1 vertices"),
    ("OFF\n3 1 0\n0 0 0\n", ".off", "truncated"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", ".obj", "line 4: face index 0 .OBJ counts vertices from 1"),
    ("v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n", ".obj", "line 3: face index -3 counts back past the first vertex"),
    ("OFF\n-4 4 0\n0 0 0\n", ".off", "a count cannot be negative"),
    ("solid", ".xyz", "unsupported")])
def test_bad_files_raise_clear_errors(tmp_path, text, ext, needle):
    """Outside reviews: an OBJ's index 0 or 9 was reported 0-based after wrapping (``max 4``,
    ``max 8``), and an OFF count of -4 as ``invalid literal for int()``."""
    p = tmp_path / f"bad{ext}"
    p.write_text(text)
    with pytest.raises(InvalidMeshError, match=needle):
        read_mesh(p)


def test_a_pipe_given_as_a_mesh_is_not_called_missing(tmp_path):
    import os

    from harness.mesh import missing_file_problem
    os.mkfifo(tmp_path / "scan.obj")
    assert missing_file_problem(tmp_path / "scan.obj").startswith("is not a regular file")
    assert missing_file_problem(tmp_path / "nothing.obj") == "no such file"
    # in a config too (a review: a pipe and a looping link were "file not found")
    from harness.config import load_config
    from harness.errors import ConfigError
    (tmp_path / "loop.obj").symlink_to(tmp_path / "loop.obj")
    with pytest.raises(ConfigError) as e:
        load_config({"meshes": [{"file": str(tmp_path / n)} for n in ("scan.obj", "loop.obj", "none.obj")],
                     "tasks": {"smoothing": {"methods": ["scratch.explicit"]}}})
    msg = str(e.value)
    assert "scan.obj is not a regular file" in msg and "loop.obj is a symbolic link to nothing readable" in msg
    assert "file not found: " + str(tmp_path / "none.obj") in msg and msg.count("file not found") == 1


# ----------------------------------------------------------------------------- noise

def test_noise_levels_and_models():
    m = datasets.load("bunny").clean
    from harness.mesh import mean_edge_length
    e = mean_edge_length(m.V, m.F)
    Vn = apply_noise(m.V, m.F, "gaussian_normal", 0.3, 0, "bunny")
    d = np.linalg.norm(Vn - m.V, axis=1)
    assert np.sqrt((d ** 2).mean()) == pytest.approx(0.3 * e, rel=0.05)
    Vi = apply_noise(m.V, m.F, "impulsive", 0.5, 0, "bunny", fraction=0.2)
    moved = (np.linalg.norm(Vi - m.V, axis=1) > 0).mean()
    assert moved == pytest.approx(0.2, abs=0.01)
    assert np.array_equal(apply_noise(m.V, m.F, "none", 0, 0, "bunny"), m.V)
    assert not np.array_equal(apply_noise(m.V, m.F, "gaussian_random", 0.3, 1, "bunny"),
                              apply_noise(m.V, m.F, "gaussian_random", 0.3, 2, "bunny"))


def test_noise_bit_identical_across_processes():
    code = ("import hashlib; from harness import datasets; from harness.noise import apply_noise;"
            "m = datasets.load('bunny').clean;"
            "print(hashlib.sha256(apply_noise(m.V, m.F, 'gaussian_normal', 0.3, 7, 'bunny').tobytes()).hexdigest())")
    outs = {subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
            for _ in range(2)}
    m = datasets.load("bunny").clean
    import hashlib
    here = hashlib.sha256(apply_noise(m.V, m.F, "gaussian_normal", 0.3, 7, "bunny").tobytes()).hexdigest()
    assert outs == {here + "\n"}


def test_driver_computes_the_noise_frame_only_for_meshes_that_get_noise():
    """The driver warms a mesh's noise frame (mean edge length, normals) only when one of its
    cases adds noise: a clean-only mesh costs no frame and no extra (n, 3) array."""
    from harness.config import Case
    from harness.executors.local import _warm_mesh_cache

    def case(spec, level):
        return Case(case_id="c", task="laplacian", mesh=spec, mesh_key="k", noise_model="gaussian_normal",
                    noise_level=level, seed=0, fraction=1.0, method="scratch.cotan", params={})
    clean_only, noisy = {"procedural": "sphere", "subdivisions": 2}, {"procedural": "sphere", "subdivisions": 3}
    datasets._load_cached.cache_clear()          # no frame left over from an earlier test
    _warm_mesh_cache([case(clean_only, 0.0), case(noisy, 0.0), case(noisy, 0.2)])
    assert "noise_frame" not in vars(datasets.cached(clean_only).clean)
    assert "noise_frame" in vars(datasets.cached(noisy).clean)


@pytest.mark.parametrize("model", ["gaussian_normal", "gaussian_random", "impulsive"])
def test_noise_from_the_cached_frame_is_bit_identical(model):
    """The runner passes the mesh's cached (mean edge length, vertex normals) computed in the
    driver: the noisy coordinates are the same bits as when apply_noise computes them."""
    from harness.config import Case
    from harness.runner import prepare_input
    m = datasets.load("armadillo").clean
    plain = apply_noise(m.V, m.F, model, 0.3, 5, "armadillo", fraction=0.2)
    assert np.array_equal(apply_noise(m.V, m.F, model, 0.3, 5, "armadillo", fraction=0.2, frame=m.noise_frame), plain)
    case = Case(case_id="c", task="smoothing", mesh={"bundled": "armadillo"}, mesh_key="armadillo",
                noise_model=model, noise_level=0.3, seed=5, fraction=0.2, method="scratch.taubin", params={})
    assert np.array_equal(prepare_input(case)[0].V, plain)


# ----------------------------------------------------------------------------- config

GOOD = {"name": "t", "meshes": ["knight"], "noise": [{"model": "none"}],
        "tasks": {"laplacian": {"methods": ["scratch.cotan"]}}}


def _problems(cfg):
    with pytest.raises(ConfigError) as ei:
        load_config(cfg)
    return ei.value.problems


def test_config_grid_expansion():
    cfg = load_config({"name": "g", "meshes": ["knight", {"procedural": "sphere", "subdivisions": 2}],
                       "noise": [{"model": "gaussian_normal", "levels": [0.1, 0.2], "seeds": 2}],
                       "tasks": {"smoothing": {"methods": [{"name": "scratch.explicit",
                                                            "params": {"iterations": [1, 2, 3]}}]}}})
    assert len(cfg.cases) == 2 * 2 * 2 * 3
    assert len({c.case_id for c in cfg.cases}) == len(cfg.cases)
    again = load_config(cfg.raw)
    assert [c.case_id for c in again.cases] == [c.case_id for c in cfg.cases]


@pytest.mark.parametrize("patch,needle", [
    ({"repeats": 0}, "repeats: expected an integer in [1, 1000]"),
    ({"repeat": 3}, "repeat: unknown key (did you mean repeats"),
    ({"meshes": ["bunyy"]}, "meshes[0]: unknown mesh 'bunyy' (did you mean bunny"),
    ({"meshes": [{"procedural": "sphere", "subdivisions": "x"}]}, "meshes[0].subdivisions: expected an integer"),
    ({"meshes": [{"file": "nope.obj"}]}, "meshes[0].file: file not found"),
    ({"noise": [{"model": "gauss", "levels": [0.1]}]}, "noise[0].model: expected one of"),
    ({"noise": [{"model": "gaussian_normal", "levels": [-1]}]}, "noise[0].levels[0]"),
    ({"tasks": {"laplacian": {"methods": ["scratch.cotann"]}}}, "tasks.laplacian.methods[0]: unknown method 'scratch.cotann'"),
    ({"tasks": {"laplacian": {"methods": [{"name": "scratch.cotan", "params": {"mass": "area"}}]}}},
     "tasks.laplacian.methods[0].params.mass: parameter 'mass': must be one of"),
    ({"tasks": {"smoothing": {"methods": ["scratch.cotan"]}}}, "is a laplacian method, not smoothing"),
    ({"tasks": {"smoothin": {"methods": ["scratch.explicit"]}}}, "tasks.smoothin: unknown task"),
    ({"plugins": ["no_such_module_xyz"]}, "plugins[0]: cannot import"),
    # an outside review: one mesh listed twice ran once, silently; a name two meshes share (or that is
    # another mesh's label) was changed silently, and with it the noise, which the label seeds
    ({"meshes": ["knight", "knight"]}, "meshes[1]: the same mesh as meshes[0] (the same spec): list it once"),
    ({"meshes": [{"procedural": "sphere", "subdivisions": 2}, {"procedural": "sphere", "subdivisions": 2}]},
     "meshes[1]: the same mesh as meshes[0]"),
    ({"meshes": [{"file": str(KNIGHT), "name": "ball"}, {"file": str(BUNNY), "name": "ball"}]},
     "meshes[0].name: 'ball' is also the label of meshes[1], another mesh"),
    ({"meshes": [{"file": str(KNIGHT), "name": "sphere"}, "sphere"]},
     "meshes[0].name: 'sphere' is also the label of meshes[1], another mesh"),
    # a review: a bundled mesh given again as its file (or a copy of it) ran twice
    ({"meshes": ["knight", {"file": str(KNIGHT)}]}, "meshes[1]: the same mesh as meshes[0] (the same file bytes)"),
    # an outside audit: a bundled pair given again as its two files ran twice, doubling its cells
    ({"meshes": ["fandisk-noisy-0.3", {"file": str(MESH_DIR / "denoise" / "Fandisk0.3" / "Noisy.obj"),
                                       "clean": str(MESH_DIR / "denoise" / "Fandisk0.3" / "Original.obj")}]},
     "meshes[1]: the same mesh as meshes[0] (the same file bytes)"),
])
def test_config_errors_name_key_path(patch, needle):
    probs = _problems({**GOOD, **patch})
    assert any(needle in p for p in probs), probs


def test_a_name_is_checked_against_the_labels_the_run_would_give(tmp_path):
    """A review: two x.obj in other folders are labelled a-x and b-x, so `name: a-x` on a third mesh
    was renamed a-x-1 silently; and an entry whose own value was refused (subdivisions: 99 falls back
    to the default) was also called the same mesh as another: a problem that is not one."""
    for d, src in (("a", KNIGHT), ("b", BUNNY)):
        (tmp_path / d).mkdir()
        (tmp_path / d / "x.off").write_bytes(src.read_bytes())
    probs = _problems({**GOOD, "meshes": [{"file": str(tmp_path / "a" / "x.off")}, {"file": str(tmp_path / "b" / "x.off")},
                                          {"file": str(MESH_DIR / "fertility.off"), "name": "a-x"}]})
    assert len(probs) == 1 and "meshes[2].name: 'a-x' is also the label of meshes[0]" in probs[0], probs
    probs = _problems({**GOOD, "meshes": ["sphere", {"procedural": "sphere", "subdivisions": 99}]})
    assert len(probs) == 1 and "subdivisions" in probs[0], probs


def test_three_mistakes_reported_together_and_nothing_written(tmp_path, capsys):
    cfg = tmp_path / "bad.yaml"
    cfg.write_text("name: bad\nrepeats: -1\nmeshes: [bunyy]\nnoise: [{model: none}]\n"
                   "tasks: {laplacian: {methods: [scratch.cotann]}}\n")
    out = tmp_path / "out"
    code = main(["run", str(cfg), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2
    assert "3 problem(s)" in err and "repeats" in err and "bunyy" in err and "scratch.cotann" in err
    assert "Traceback" not in err
    assert not out.exists()


def test_bad_yaml_exit_2(tmp_path, capsys):
    cfg = tmp_path / "x.yaml"
    cfg.write_text("name: [unclosed\n")
    assert main(["run", str(cfg), "--quiet"]) == 2
    assert "not valid YAML" in capsys.readouterr().err


# ----------------------------------------------------------------------------- end to end

def test_cli_end_to_end(tmp_path):
    cfg = tmp_path / "e2e.yaml"
    cfg.write_text(
        "name: e2e\nrepeats: 2\ntime_budget: 0\nsave_meshes: true\nmeshes: [knight, {procedural: plane_delaunay, n_points: 80}]\n"
        "noise: [{model: none}, {model: gaussian_normal, levels: [0.2]}]\n"
        "tasks:\n  laplacian: {methods: [scratch.uniform, scratch.cotan, libigl.cotan]}\n"
        "  smoothing: {methods: [{name: scratch.explicit, params: {iterations: [2, 4]}}]}\n"
        "  simplification: {methods: [fast_simplification.qem], params: {target_ratio: 0.5}}\n")
    out = tmp_path / "run"
    r = subprocess.run([sys.executable, "-m", "harness.cli", "run", str(cfg), "--out", str(out),
                        "--workers", "2", "--quiet"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    for task, n in (("laplacian", 12), ("smoothing", 8), ("simplification", 4)):
        df = pd.read_csv(out / f"{task}.csv")
        assert list(df.columns) == columns(task)
        assert len(df) == n and (df["status"] == "ok").all(), df[["method", "error"]]
        assert (df["repeats"] >= 2).all() and (df["time_min_s"] <= df["time_s"]).all()
        assert (df["time_q1_s"] <= df["time_s"]).all() and (df["time_s"] <= df["time_q3_s"]).all()
        assert df["time_cold_s"].gt(0).all()
        assert [len(json.loads(t)) for t in df["times"]] == df["repeats"].tolist()
        assert df["peak_rss_mb"].gt(0).all()
    lap = pd.read_csv(out / "laplacian.csv")
    plane = lap[lap["mesh"].str.startswith("plane_delaunay") & (lap["noise_model"] == "none")]
    assert len(plane) == 3 and plane["lin_error"].notna().all()      # planar: LIN measured
    assert plane.set_index("method").loc["scratch.cotan", "LIN"] == True  # noqa: E712
    assert plane.set_index("method").loc["scratch.uniform", "LIN"] == False  # noqa: E712
    assert lap[lap["mesh"] == "knight"]["lin_error"].isna().all()
    meta = json.loads((out / "run.json").read_text())
    assert meta["status"] == "finished" and meta["versions"]["libigl"] and meta["n_cases"] == 24
    assert (out / "report.html").stat().st_size > 1000
    assert len(list((out / "meshes").glob("*.ply"))) == 12 + 4   # results + distinct inputs
    # the methods and datasets commands list
    r = subprocess.run([sys.executable, "-m", "harness.cli", "methods"], capture_output=True, text=True)
    assert r.returncode == 0 and "scratch.cotan" in r.stdout and "fast_simplification.qem" in r.stdout
    r = subprocess.run([sys.executable, "-m", "harness.cli", "datasets"], capture_output=True, text=True)
    assert r.returncode == 0 and "armadillo" in r.stdout and "plane_nondelaunay" in r.stdout


def test_python_api_run_and_method_errors(tmp_path):
    import harness
    import methods
    frames = harness.run({**GOOD, "name": "api"}, out=tmp_path / "api", workers=1, quiet=True)
    assert set(frames) == {"laplacian"} and frames["laplacian"]["status"].tolist() == ["ok"]
    m = methods.get("scratch.cotan")
    V, F = datasets.icosphere(1)
    with pytest.raises(ValueError, match="NaN"):
        m(np.where(np.arange(len(V))[:, None] == 0, np.nan, V), F)
    with pytest.raises(ValueError, match="out of range"):
        m(V, F + 100)
    with pytest.raises(ValueError, match="shape"):
        m(V[:, :2], F)
    with pytest.raises(KeyError, match="did you mean scratch.cotan"):
        methods.get("scratch.cotann")
    taubin = methods.get("scratch.taubin")     # the alias and the name at once: the last one won, silently
    assert np.array_equal(taubin(V, F, lam=0.6).V, taubin(V, F, **{"lambda": 0.6}).V)
    with pytest.raises(ValueError, match="lam and lambda: the same parameter given twice"):
        taubin(V, F, lam=0.5, **{"lambda": 0.6})


def test_unavailable_library_is_a_row_not_a_crash(tmp_path):
    import methods
    from methods import LaplacianResult, register
    from methods.scratch.operators import cotan_weights

    name = "testlib.needs_missing"
    if name not in [m.name for m in methods.all_methods()]:
        @register(name, task="laplacian", library="nolib", requires=("no_such_library_qq",))
        def _f(V, F):
            return LaplacianResult(cotan_weights(V, F))
    assert name not in methods.available()
    frames = harness_run_serial({**GOOD, "name": "u", "tasks": {"laplacian": {"methods": [name]}}}, tmp_path)
    row = frames["laplacian"].iloc[0]
    assert row["status"] == "unavailable" and "no_such_library_qq" in row["error"]


def harness_run_serial(cfg, tmp_path):
    import harness
    return harness.run(cfg, out=tmp_path / "s", executor="serial", quiet=True)


def test_ply_ascii_binary_and_stl_round_trip(tmp_path):
    import igl
    import pymeshlab
    V, F = datasets.icosphere(2)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F))
    for binary in (True, False):
        p = tmp_path / f"m{int(binary)}.ply"
        ms.save_current_mesh(str(p), binary=binary)
        m = read_mesh(p)
        assert (m.n_vertices, m.n_faces) == (162, 320) and np.array_equal(m.F, F)
        assert np.abs(m.V - V).max() < 1e-6
    p = tmp_path / "hand.ply"
    head = (f"ply\nformat ascii 1.0\nelement vertex {len(V)}\nproperty float x\nproperty float y\n"
            f"property float z\nelement face {len(F)}\nproperty list uchar int vertex_indices\nend_header\n")
    p.write_text(head + "".join("%.17g %.17g %.17g\n" % tuple(v) for v in V) + "".join("3 %d %d %d\n" % tuple(t) for t in F))
    assert np.array_equal(read_mesh(p).F, F)
    p = tmp_path / "s.stl"
    igl.write_triangle_mesh(str(p), V, F)
    m = read_mesh(p)
    t = topology(m.V, m.F)
    assert (m.n_vertices, m.n_faces) == (162, 320) and t["boundary_edges"] == 0 and t["components"] == 1
    assert any("welded" in r for r in m.repairs)


def test_case_ids_follow_file_contents_not_location(tmp_path):
    import shutil
    src = datasets.DATA_DIR / "decimated-knight.off"
    for d in ("a", "b"):
        (tmp_path / d).mkdir()
        shutil.copy(src, tmp_path / d / "k.off")
    ids = [[c.case_id for c in load_config({**GOOD, "meshes": [{"file": f"{d}/k.off"}]},
                                           base_dir=tmp_path).cases] for d in ("a", "b")]
    assert ids[0] == ids[1]
    (tmp_path / "b" / "k.off").write_text(src.read_text().replace("OFF", "OFF\n# changed", 1))
    changed = [c.case_id for c in load_config({**GOOD, "meshes": [{"file": "b/k.off"}]}, base_dir=tmp_path).cases]
    assert changed != ids[0]          # the id hashes the file's bytes: an edited file is a new case


def test_a_procedural_parameter_written_as_an_integer_is_the_same_case():
    """Before: `radius: 1` and the default `radius: 1.0` gave two case ids under one label (a
    false 'missing' regression in compare, a refused --resume, two rows of one input)."""
    ids = [[c.case_id for c in load_config({**GOOD, "meshes": [{"procedural": "sphere", "subdivisions": 1, **r}]}).cases]
           for r in ({"radius": 1}, {"radius": 1.0}, {})]
    assert ids[0] == ids[1] == ids[2]
    with pytest.raises(ConfigError, match="also a test mesh"):
        load_config({**GOOD, "meshes": [{"procedural": "sphere", "subdivisions": 1, "radius": 1}],
                     "tune": {"metric": "dist_mean", "train": [{"procedural": "sphere", "subdivisions": 1}],
                              "params": {"scratch.taubin": {"iterations": [1, 2]}}},
                     "tasks": {"smoothing": {"methods": ["scratch.taubin"]}}})


def test_same_stem_files_get_distinct_labels_and_defaults_dedupe(tmp_path):
    import shutil
    for d in ("d1", "d2"):
        (tmp_path / d).mkdir()
        shutil.copy(datasets.DATA_DIR / "decimated-knight.off", tmp_path / d / "Noisy.off")
    (tmp_path / "d2" / "Noisy.off").write_text(
        (tmp_path / "d2" / "Noisy.off").read_text().replace("\n", "\n# x\n", 1))
    cfg = load_config({**GOOD, "meshes": [{"file": "d1/Noisy.off"}, {"file": "d2/Noisy.off"}]}, base_dir=tmp_path)
    assert sorted({c.mesh_key for c in cfg.cases}) == ["d1-Noisy", "d2-Noisy"]
    cfg = load_config({**GOOD, "tasks": {"laplacian": {"methods": [
        "scratch.cotan", {"name": "scratch.cotan", "params": {"mass": "voronoi"}}]}}})
    assert len(cfg.cases) == 1


@pytest.mark.parametrize("name", ["..", ".hidden", "a/b", "a\\b", ""])
def test_unsafe_run_names_rejected(name):
    assert any(p.startswith("name:") for p in _problems({**GOOD, "name": name}))


def test_in_place_method_does_not_spoil_repeats_or_input(tmp_path):
    import harness
    import methods
    from methods import SmoothingResult, register
    name = "testlib.inplace_halve"
    if name not in [m.name for m in methods.all_methods()]:
        @register(name, task="smoothing", library="testlib")
        def _halve(V, F):
            """Scale in place by 1/2 (a rude method)."""
            V *= 0.5
            return SmoothingResult(V)
    cfg = {**GOOD, "name": "inplace", "repeats": 3, "noise": [{"model": "gaussian_normal", "levels": [0.1]}],
           "tasks": {"smoothing": {"methods": [name]}}}
    row = harness.run(cfg, out=tmp_path / "r", executor="serial", quiet=True)["smoothing"].iloc[0]
    assert row["status"] == "ok"
    assert row["input_ev_mean"] < 0.01                 # the noisy input itself, not a halved copy
    assert row["volume_ratio"] == pytest.approx(0.125, rel=0.05)   # one halving, not three


def test_stl_binary_ascii_and_truncated(tmp_path):
    V, F = datasets.icosphere(1)
    tri = V[F].astype("<f4")
    rec = np.zeros(len(F), dtype=[("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    rec["v"] = tri
    b = tmp_path / "b.stl"
    b.write_bytes(b"\0" * 80 + np.uint32(len(F)).tobytes() + rec.tobytes())
    m = read_mesh(b)
    assert (m.n_vertices, m.n_faces) == (42, 80) and topology(m.V, m.F)["manifold"]
    b.write_bytes(b.read_bytes()[:-30])                      # a binary file cut short
    with pytest.raises(InvalidMeshError, match="unreadable STL"):
        read_mesh(b)
    a = tmp_path / "a.stl"
    body = "".join(" facet normal 0 0 1\n  outer loop\n" + "".join(
        "   vertex %.9g %.9g %.9g\n" % tuple(v) for v in t) + "  endloop\n endfacet\n" for t in tri)
    a.write_text("solid t\n" + body + "endsolid t\n")
    assert read_mesh(a).n_faces == 80
    a.write_text("solid t\n" + body[: len(body) // 2])
    with pytest.raises(InvalidMeshError, match="truncated ASCII STL"):
        read_mesh(a)


def test_nan_output_on_degenerate_input_is_an_error_row_not_divergence(tmp_path):
    """PyGEL's anisotropic filter and MeshLab's scale-dependent Laplacian divide by zero on a
    zero-length edge; that is an error naming the faces, not 'diverged' (instability)."""
    import harness
    m = datasets.load("woody").clean
    V = m.V.copy()
    V[m.F[0, 1]] = V[m.F[0, 0]]                        # a zero-length edge
    p = tmp_path / "woody_flat.obj"
    from harness.mesh import write_obj
    write_obj(p, V, m.F)
    cfg = {**GOOD, "name": "deg", "meshes": [{"file": str(p)}],
           "tasks": {"smoothing": {"methods": ["pygel.anisotropic", "meshlab.scale_dependent", "scratch.explicit"]}}}
    df = harness.run(cfg, out=tmp_path / "r", workers=1, quiet=True)["smoothing"].set_index("method")
    for name in ("pygel.anisotropic", "meshlab.scale_dependent"):
        assert df.loc[name, "status"] == "error" and "zero-area face" in df.loc[name, "error"], df.loc[name, "error"]
    assert df.loc["scratch.explicit", "status"] == "ok" and df.loc["scratch.explicit", "diverged"] == False  # noqa: E712


def test_compiled_triangle_quality_equals_numpy():
    """The compiled per-face pass (used from 20k faces) gives the numpy path's angles and radius
    ratios to 1e-12 on a noisy real mesh, on degenerate faces (zero area, repeated vertex,
    zero-length edge) and with a NaN vertex (NaN propagates, as in numpy)."""
    from harness.metrics import triangle_quality as tq
    from harness.metrics._quality_kernel import face_quality
    clean = datasets.load({"bundled": "armadillo"}).clean
    Vn = apply_noise(clean.V, clean.F, "gaussian_normal", 0.3, 0)
    degenerate_V = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 0, 0], [np.nan, 0, 0],
                             [0, 0, 0], [-1, -2, -3]], float)
    # the last two faces have a zero-length edge whose dot products sum to -0.0 in plain order
    degenerate_F = np.array([[0, 1, 2], [0, 1, 3], [1, 1, 3], [1, 4, 3], [0, 5, 3], [0, 6, 7],
                             [7, 7, 6]], np.int64)
    for V, F in ((Vn, clean.F), (degenerate_V, degenerate_F)):
        got = face_quality(V, F)
        want = tq._face_quality(V, F)
        for g, w in zip(got, want):
            assert np.array_equal(np.isnan(g), np.isnan(w))
            ok = ~np.isnan(w)
            assert np.abs(g[ok] - w[ok]).max() <= 1e-12
    assert face_quality(degenerate_V, degenerate_F)[1][5:].tolist() == [0.0, 0.0]   # not 180
    assert len(clean.F) >= tq.COMPILED_FROM
    q = triangle_quality(Vn, clean.F)
    fmin, fmax, rr = tq._face_quality(Vn, clean.F)
    assert abs(q["min_angle"] - fmin.min()) <= 1e-12 and abs(q["radius_ratio_mean"] - rr.mean()) <= 1e-12


@pytest.mark.parametrize("name", ["armadillo", "camelhead"])
def test_compiled_face_terms_equal_numpy_definitions(name):
    """The smoothing task's compiled face pass gives the numpy definitions: unit normals and double
    areas bit for bit, volume terms to 1e-15 of their products' size and normal angles to 1e-12 degrees, on
    a noisy real mesh (camelhead is open) far from the origin, with degenerate faces (zero area,
    repeated vertex: normal 0, no angle where the reference has none) appended."""
    from harness.core.geometry import cross_rows, double_areas, face_normals, volume
    from harness.metrics._quality_kernel import face_terms
    from harness.metrics.normal_error import normal_error
    clean = datasets.load({"bundled": name}).clean
    shift = np.array([1e3, -2e3, 5e2])
    F = np.vstack([clean.F, [[0, 1, 1], [2, 2, 2]]]).astype(np.int64)
    Vc = clean.V + shift
    Vn = apply_noise(clean.V, clean.F, "gaussian_normal", 0.5, 1) + shift
    o = Vc.mean(0)
    C = face_normals(Vc, F)
    N, dbl, vol, ang = face_terms(Vn, F, o, C)
    assert np.array_equal(N, face_normals(Vn, F)) and np.array_equal(dbl, double_areas(Vn, F))
    S = Vn - o
    want = np.einsum("ij,ij->i", S[F[:, 0]], cross_rows(S[F[:, 1]], S[F[:, 2]]))
    r3 = np.linalg.norm(S, axis=1).max() ** 3           # the size of the products summed
    assert np.abs(vol - want).max() <= 1e-15 * r3
    assert abs(vol.sum() / 6 - volume(S, F)) <= 1e-12 * abs(volume(S, F))
    assert np.isnan(ang[-2:]).all() and ang[:-2].min() >= 0 and np.nanmax(ang) <= 180   # no reference normal
    ref = normal_error(Vn, Vc, F)
    assert abs(np.nanmean(ang) - ref["normal_error_deg"]) <= 1e-12
    assert abs(np.sqrt(np.nanmean(ang ** 2)) - ref["normal_error_rms_deg"]) <= 1e-12
    Vd = Vn.copy()
    Vd[F[0, 1]] = Vd[F[0, 0]]                            # a face the result collapsed: 90 degrees
    assert face_terms(Vd, F, o, C)[3][0] == 90.0
    assert face_terms(Vn, F, o, np.zeros((0, 3)))[3].size == 0


def test_methods_lists_a_plugins_methods(tmp_path):
    """`shootout methods --plugin MODULE` lists the methods a plugin registers (as a config's
    plugins: would load them); a module that cannot be imported is exit 2 naming it."""
    from pathlib import Path
    (tmp_path / "mylab_listed.py").write_text(
        "from methods import register\nfrom harness.tasks.smoothing import SmoothingResult\n\n"
        "@register('mylab_listed.same', task='smoothing', library='mylab')\n"
        "def same(V, F):\n    \"\"\"Returns its input.\"\"\"\n    return SmoothingResult(V=V.copy())\n")
    root = Path(__file__).resolve().parents[1]
    env = {**__import__("os").environ, "PYTHONPATH": str(root)}
    r = subprocess.run([sys.executable, "-m", "harness.cli", "methods", "--plugin", "mylab_listed", "--task", "smoothing"],
                       cwd=tmp_path, capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0 and "mylab_listed.same" in r.stdout, r.stderr
    r = subprocess.run([sys.executable, "-m", "harness.cli", "methods", "--plugin", "no_such_mod_zz", "--plugin",
                        "no_such_mod_yy"], cwd=tmp_path, capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 2 and "--plugin no_such_mod_zz: cannot import it" in r.stderr
    assert "--plugin no_such_mod_yy: cannot import it" in r.stderr, r.stderr     # each one (a review)


def test_an_entry_point_module_is_tried_in_another_process_before_it_is_imported(tmp_path):
    """Installed packages' ``mesh_shootout.methods`` entry points load with the registry: each
    module is first imported in a throwaway process, as a config's plugins are, so one that ends
    the process on import (``os._exit``) or calls ``sys.exit`` is named in a warning and left
    out, and the others' methods are listed; before, the first ended every command silently."""
    from pathlib import Path
    site = tmp_path / "site"
    dist = site / "mylab_eps-0.1.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: mylab-eps\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text("[mesh_shootout.methods]\nends = mylab_ep_ends\n"
                                           "exits = mylab_ep_exits\ngood = mylab_ep_good\n")
    (site / "mylab_ep_ends.py").write_text("import os\nos._exit(7)\n")
    (site / "mylab_ep_exits.py").write_text("import sys\nsys.exit(3)\n")
    (site / "mylab_ep_good.py").write_text(
        "from methods import register\nfrom harness.tasks.smoothing import SmoothingResult\n\n"
        "@register('mylab_ep_good.same', task='smoothing', library='mylab')\n"
        "def same(V, F):\n    \"\"\"Returns its input.\"\"\"\n    return SmoothingResult(V=V.copy())\n")
    root = Path(__file__).resolve().parents[1]
    env = {**__import__("os").environ, "PYTHONPATH": f"{site}:{root}"}
    r = subprocess.run([sys.executable, "-m", "harness.cli", "methods", "--task", "smoothing"],
                       cwd=tmp_path, capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0 and "mylab_ep_good.same" in r.stdout, (r.returncode, r.stderr)
    assert "entry point ends (mylab_ep_ends)" in r.stderr and "exit status 7" in r.stderr, r.stderr
    assert "entry point exits (mylab_ep_exits)" in r.stderr and "sys.exit(3)" in r.stderr, r.stderr


def test_method_sources_name_each_methods_module_and_distribution(monkeypatch):
    """run.json's method_sources: our methods are mesh-shootout's at its version; a plugin's
    module is looked up among the installed distributions (none for the test plugins)."""
    from importlib import metadata

    from harness.config import load_config
    from harness.session import method_sources
    calls = []
    real = metadata.packages_distributions
    monkeypatch.setattr(metadata, "packages_distributions", lambda: calls.append(1) or real())
    cfg = load_config({"meshes": ["knight"], "noise": [{"model": "none"}],
                       "tasks": {"smoothing": {"methods": ["scratch.explicit"]}}})
    got = method_sources(cfg)
    assert got["scratch.explicit"]["module"].startswith("methods.") and not calls     # no scan of every distribution
    assert got["scratch.explicit"]["distribution"] == "mesh-shootout"
    assert got["scratch.explicit"]["version"] == metadata.version("mesh-shootout")
    cfg = load_config({"plugins": ["tests.plugins.crashy"], "meshes": ["knight"], "noise": [{"model": "none"}],
                       "tasks": {"smoothing": {"methods": ["scratch.explicit", "crashy.nan_smooth"]}}})
    got = method_sources(cfg)
    assert got["crashy.nan_smooth"] == {"module": "tests.plugins.crashy", "distribution": None, "version": None} and calls


def test_a_methods_summary_is_its_first_sentence_whole():
    """A review: `shootout methods` printed the docstring's first line, cut mid-sentence
    ("... scipy's ``eigsh`` in")."""
    import methods
    s = methods.get("libigl.eigsh").summary
    assert s.startswith("What a user would write") and s.endswith("with scipy's own sparse LU inside."), s
    assert methods.get("scratch.umbrella").summary.endswith("``D = 1/N_i``.")   # not cut at "i.e." (diff review)
    for m in methods.all_methods():                  # (another test may register one without a docstring)
        assert "\n" not in m.summary and (m.summary or not m.doc.strip()), m.name


def test_an_unknown_task_kind_is_refused_not_an_empty_list():
    """A review: methods.available('smoothin') returned [] as if no method were registered."""
    import methods
    with pytest.raises(KeyError, match="unknown task 'smoothin'; did you mean smoothing"):
        methods.available("smoothin")
    assert "scratch.taubin" in methods.available("smoothing")


def test_case_ids_of_recorded_runs_survive_renamed_and_added_parameters():
    """A diff review: renaming a parameter to the shared vocabulary (fast-simplification's agg,
    meshoptimizer's lock_border, MeshLab's fit_iterations) and adding one (cotan_mean's signed)
    changed every such case id, so compare against an older run reported each as missing. A case
    id records a renamed parameter under its old name (Param.id_as) and leaves an added one out
    at its default (Param.id_omit_default): these ids are the ones 9a2b2a5 computed."""
    from harness.config import load_config
    cfg = {"name": "ids", "meshes": ["knight"], "noise": [{"model": "none"}],
           "tasks": {"simplification": {"methods": ["fast_simplification.qem", "meshoptimizer.qem"],
                                        "params": {"target_ratio": 0.5}},
                     "smoothing": {"noise": [{"model": "gaussian_normal", "levels": [0.3]}],
                                   "methods": ["meshlab.two_steps"]},
                     "curvature": {"methods": ["scratch.cotan_mean"]}}}
    ids = {c.method: c.case_id for c in load_config(cfg).cases}
    assert ids == {"fast_simplification.qem": "0dad1ef56f79", "meshoptimizer.qem": "93678298df1b",
                   "scratch.cotan_mean": "a79a42884ab5", "meshlab.two_steps": "7e820199d4df"}
    cfg["tasks"] = {"curvature": {"methods": [{"name": "scratch.cotan_mean", "params": {"signed": [True, False]}}]}}
    assert len({c.case_id for c in load_config(cfg).cases}) == 2          # away from its default: in the id


def test_run_json_records_the_solver_backends_the_cases_used(tmp_path):
    """run.json's ``solver.used`` names each backend the cases factored with through the
    harness's solver layer (the automatic choice resolved), with its cases, methods and largest
    system, from the forked case processes (the driver's own record saw none of them); a
    method that factors nothing adds nothing."""
    import json

    import harness
    from harness.core.solvers import auto_solver
    cfg = {"name": "solvers", "repeats": 1, "time_budget": 0, "meshes": ["knight", "bunny"],
           "noise": [{"model": "gaussian_normal", "levels": [0.3]}],
           "tasks": {"smoothing": {"methods": ["scratch.implicit", "scratch.taubin"]}}}
    frames = harness.run(cfg, out=tmp_path, quiet=True, workers=2)
    df = frames["smoothing"]
    assert (df.status == "ok").all()
    n = df.loc[df.method == "scratch.implicit", "n_vertices"].astype(int)
    want = {}
    for k in n:
        name = auto_solver(k)
        w = want.setdefault(name, {"cases": 0, "unknowns_max": 0, "methods": ["scratch.implicit"]})
        w["cases"] += 1
        w["unknowns_max"] = max(w["unknowns_max"], k)
    meta = json.loads((tmp_path / "run.json").read_text())
    assert meta["solver"]["used"] == want and meta["sessions"][-1]["solver_used"] == want
    harness.run(cfg, out=tmp_path, quiet=True, workers=2, resume=True)      # nothing left to run: kept
    assert json.loads((tmp_path / "run.json").read_text())["solver"]["used"] == want
    from harness.report.overview import _solver_text
    text = _solver_text(meta["solver"])
    assert all(f"{b} in {w['cases']} case(s) of scratch.implicit (up to {w['unknowns_max']} unknowns)" in text
               for b, w in want.items()), text
