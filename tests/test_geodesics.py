"""Task ``geodesics``: exact methods against the great-circle distance, the heat method against
libigl's (same operator, t and boundary condition), the intrinsic Delaunay Laplacian on obtuse
meshes, and the task through the whole pipeline."""
import numpy as np
import pandas as pd
import pytest

import harness
import methods
from harness import datasets, run
from harness.core.geometry import mean_edge_length
from harness.tasks.geodesics import analytic, source_vertices


def rel_errors(shape, name, k=3, **kw):
    s = datasets.load(shape)
    V, F = s.clean.V, s.clean.F
    src = source_vertices(len(V), k, 0)
    D = methods.get(name)(V, F, sources=k, **kw).D
    h = mean_edge_length(V, F)
    out = []
    for i, sv in enumerate(src):
        ref = analytic(s.shape, V, V[sv])
        far = ref > 3 * h
        out.append(np.abs(D[i] - ref)[far] / ref[far])
    return np.concatenate(out)


SPHERE5 = {"procedural": "sphere", "subdivisions": 5}


@pytest.mark.parametrize("name", ["libigl.exact_geodesic", "pygeodesic.exact"])
def test_exact_methods_match_great_circles(name):
    """Exact polyhedral distances on a subdivision-5 unit icosphere are within 1e-3 (relative) of
    the great-circle distance beyond 3 edge lengths of the source (measured: mean 1.5e-4, max
    1.8e-4; polyhedral paths are chords, slightly shorter)."""
    e = rel_errors(SPHERE5, name, k=2)
    assert e.max() <= 1e-3


def test_heat_method_accuracy_on_the_sphere():
    """The heat method with its default t = h^2 on the subdivision-5 icosphere: mean relative error
    0.69% and max 4% (measured) against great circles; geometry-central's is 1.02 times it."""
    e = rel_errors(SPHERE5, "scratch.heat", k=2)
    assert 0.004 < e.mean() < 0.012 and e.max() < 0.06


@pytest.mark.parametrize("shape,kw", [(SPHERE5, {}), ("camelhead", {}), ({"procedural": "plane_nondelaunay", "n_points": 2000},
                                                                       {"laplacian": "intrinsic_delaunay"}),
                                      ({"procedural": "cylinder"}, {"t_factor": 4.0})],
                         ids=["sphere", "open-camelhead", "obtuse-intrinsic", "cylinder-t4"])
def test_scratch_heat_equals_libigl_heat(shape, kw):
    """Same operator, t and boundary condition (libigl averages Neumann and Dirichlet on open
    meshes): equal to 1e-6 relative (measured ~1e-13)."""
    s = datasets.load(shape if isinstance(shape, dict) else {"bundled": shape})
    V, F = s.clean.V, s.clean.F
    a = methods.get("scratch.heat")(V, F, sources=3, **kw).D
    b = methods.get("libigl.heat")(V, F, sources=3, **kw).D
    assert np.abs(a - b).max() <= 1e-6 * np.abs(b).max()


def test_intrinsic_delaunay_fixes_the_heat_method_on_obtuse_meshes():
    """Sharp & Crane 2020's finding: on a planar mesh with 30% of its edges flipped (many obtuse,
    non-Delaunay triangles) the cotan heat method's mean error is several times larger than with
    the intrinsic Delaunay Laplacian, which recovers the accuracy of the Delaunay mesh (measured
    on 3,000 points: 11.6% vs 1.56%; the Delaunay mesh itself 1.69%)."""
    shape = {"procedural": "plane_nondelaunay", "n_points": 3000, "flip_fraction": 0.3}
    cot = rel_errors(shape, "scratch.heat", k=4).mean()
    idt = rel_errors(shape, "scratch.heat", k=4, laplacian="intrinsic_delaunay").mean()
    dela = rel_errors({"procedural": "plane_delaunay", "n_points": 3000}, "scratch.heat", k=4).mean()
    assert cot > 4 * idt and idt < 1.2 * dela


def test_the_task_runs_through_the_pipeline(tmp_path):
    """Analytic reference on the sphere, exact polyhedral reference on a file mesh, the time split
    reported, symmetry measured with two sources."""
    run({"name": "geo", "repeats": 1, "meshes": [{"procedural": "sphere", "subdivisions": 3}, "knight"],
         "noise": [{"model": "none"}],
         "tasks": {"geodesics": {"methods": ["scratch.heat", "libigl.heat", "libigl.exact_geodesic", "potpourri3d.heat",
                                             "pygeodesic.exact"], "params": {"sources": 2}}}}, out=tmp_path, quiet=True)
    df = pd.read_csv(tmp_path / "geodesics.csv")
    assert len(df) == 10 and (df["status"] == "ok").all(), df[["method", "error"]]
    sphere = df[df["mesh"].str.startswith("sphere")].set_index("method")
    knight = df[df["mesh"] == "knight"].set_index("method")
    assert not sphere["reference_exact"].any() and knight["reference_exact"].all()
    # the column naming what the error is measured against
    assert (sphere["reference"] == "analytic").all() and (knight["reference"] == "libigl.exact_geodesic").all()
    assert knight.loc["libigl.exact_geodesic", "rel_error_max"] < 1e-9        # its own reference
    assert knight.loc["pygeodesic.exact", "rel_error_max"] < 1e-6
    assert (sphere["rel_error_mean"] < 0.05).all() and (sphere["symmetry_error"] >= 0).all()
    assert (df["precompute_s"] >= 0).all() and (df["per_source_s"] > 0).all()
    assert "Geodesic distance" in (tmp_path / "report.html").read_text()


def test_meshlab_geodesic_is_close_to_exact():
    """VCGLib's front propagation: 6e-7 relative on a flat Delaunay mesh, 0.25% on an icosphere
    (measured; bounds 1e-5 and 0.5%)."""
    assert rel_errors({"procedural": "plane_delaunay", "n_points": 2000}, "meshlab.geodesic", k=2).mean() < 1e-5
    assert rel_errors({"procedural": "sphere", "subdivisions": 4}, "meshlab.geodesic", k=2).mean() < 0.005


def _two_copies(name="knight"):
    s = datasets.load(name).clean
    V, F = s.V, s.F
    shift = np.array([2.0 * np.ptp(V[:, 0]) + 1.0, 0.0, 0.0])
    return np.vstack([V, V + shift]), np.vstack([F, F + len(V)]), V, F


def test_scratch_heat_on_a_disconnected_mesh_is_the_heat_method_on_the_source_component():
    """Two copies of knight: a source's distances on its own copy equal those on knight alone
    (1e-9 of the largest), +inf on the other copy. One vertex was pinned for the whole mesh and the
    sign taken from the mean over both copies: the distances came out negative."""
    V2, F2, V, F = _two_copies()
    n = len(V)
    for s in (5, n + 5):
        D2 = methods.get("scratch.heat").func(V2, F2, sources=np.array([s]))
        D1 = methods.get("scratch.heat").func(V, F, sources=np.array([s % n])).D[0]
        own = slice(0, n) if s < n else slice(n, 2 * n)
        other = slice(n, 2 * n) if s < n else slice(0, n)
        assert np.abs(D2.D[0][own] - D1).max() <= 1e-9 * D1.max()
        assert np.isinf(D2.D[0][other]).all()


def test_dirichlet_heat_with_a_boundary_source_is_an_error():
    """u = 0 on the boundary: a boundary source gives a zero heat step and D = 0 everywhere."""
    from harness.core.geometry import boundary_vertices
    s = datasets.load("woody").clean
    b = int(np.flatnonzero(boundary_vertices(s.F, len(s.V)))[0])
    with pytest.raises(ValueError, match="on the boundary"):
        methods.get("scratch.heat").func(s.V, s.F, sources=np.array([b]), boundary="dirichlet")
    D = methods.get("scratch.heat").func(s.V, s.F, sources=np.array([b]), boundary="average").D
    assert D.max() > 0


def test_unreachable_vertices_are_left_out_of_every_error(tmp_path):
    """On two copies of knight the exact reference is 0 on the other copy (libigl's convention) and
    the heat methods return inf (scratch) or a finite value there: the rows are ok, the errors are
    measured on the source's copy (scratch.heat's mean relative error was 0.7, with negative
    distances), and unreachable_fraction is 1/2; pygeodesic's library fails on a vertex it cannot
    reach, so the adapter solves the source's component alone."""
    import igl
    V2, F2, V, F = _two_copies()
    igl.write_triangle_mesh(str(tmp_path / "two.obj"), V2, F2)
    igl.write_triangle_mesh(str(tmp_path / "one.obj"), V, F)
    run({"name": "geo", "repeats": 1, "meshes": [{"file": str(tmp_path / "two.obj")}, {"file": str(tmp_path / "one.obj")}],
         "noise": [{"model": "none"}], "save_meshes": True,
         "tasks": {"geodesics": {"methods": ["scratch.heat", "libigl.heat", "meshlab.geodesic", "pygeodesic.exact"],
                                 "params": {"sources": 1}}}}, out=tmp_path / "run", quiet=True)
    df = pd.read_csv(tmp_path / "run" / "geodesics.csv")
    assert (df["status"] == "ok").all(), df[["method", "error"]]
    two, one = df[df["mesh"] == "two"].set_index("method"), df[df["mesh"] == "one"].set_index("method")
    assert (two["unreachable_fraction"] == 0.5).all() and (one["unreachable_fraction"] == 0).all()
    ply = (tmp_path / "run" / "meshes" / f"{two.loc['scratch.heat', 'case_id']}.ply").read_text()
    assert "-1 where unreachable" in ply and "inf" not in ply.split("end_header")[1]
    for t in (one, two):
        assert (t.loc[["scratch.heat", "libigl.heat"], "rel_error_mean"] < 0.1).all()
        assert t.loc["pygeodesic.exact", "rel_error_max"] < 1e-9          # an OverflowError on two copies before
        assert t.loc["scratch.heat", "rel_error_mean"] == pytest.approx(t.loc["libigl.heat", "rel_error_mean"], rel=1e-6)


def test_scratch_heat_with_every_vertex_on_the_boundary():
    """A strip or a single triangle has no interior vertex: the Dirichlet half of the averaged
    heat step is u = 0 (it failed: 'Matrix A is empty'). On the strip it equals libigl's heat
    method to 1e-12 (measured 1e-15); on one triangle (where libigl's precomputation fails) the
    distances are finite, positive, 0 at the source."""
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 0, 0], [2, 1, 0.3]])
    F = np.array([[0, 1, 2], [1, 3, 2], [1, 4, 3], [4, 5, 3]])
    a = methods.get("scratch.heat")(V, F, sources=2).D
    b = methods.get("libigl.heat")(V, F, sources=2).D
    assert np.abs(a - b).max() <= 1e-12 * np.abs(b).max()
    D = methods.get("scratch.heat")(V[:3], F[:1], sources=1).D
    assert np.isfinite(D).all() and (D >= 0).all() and np.count_nonzero(D == 0) == 1


def test_scratch_heat_names_vertices_that_lie_only_on_zero_area_faces():
    """A triangle with three collinear corners of its own beside a sound mesh: its vertices have
    no mass in the cotan and intrinsic Delaunay triangulations and the heat system is singular;
    the error names them (it was a factorization's 'Error in computing elimination tree'). The
    tufted cover's mollification gives them area: they are unreachable from the sphere. A
    zero-area face beside sound faces is fine."""
    from harness.datasets import icosphere
    V, F = icosphere(2)
    n = len(V)
    V2 = np.vstack([V, [[3.0, 0, 0], [4.0, 0, 0], [5.0, 0, 0]]])
    F2 = np.vstack([F, [[n, n + 1, n + 2]]])
    for lap in ("cotan", "intrinsic_delaunay"):
        with pytest.raises(ValueError, match=rf"3 vertices lie only on zero-area faces \(first: \[{n}, {n + 1}, {n + 2}\]\)"):
            methods.get("scratch.heat")(V2, F2, sources=1, laplacian=lap)
    D = methods.get("scratch.heat")(V2, F2, sources=1, laplacian="tufted").D     # mollified: some area, unreachable
    assert np.isfinite(D[:, :n]).all() and np.isinf(D[:, n:]).all()
    W = V.copy()
    W[F[0, 2]] = (W[F[0, 0]] + W[F[0, 1]]) / 2
    assert np.isfinite(methods.get("scratch.heat")(W, F, sources=1).D).all()


def test_a_mesh_the_exact_reference_cannot_take_is_an_error_row_saying_so(tmp_path):
    """libigl's exact_geodesic dies of SIGSEGV on an edge of three faces and grew to 16 GB on a
    grid with one zero-area face; as the task's reference on a file mesh it cost every method's
    row as 'worker process died (the method crashed its process)'. The reference, and the exact
    adapters as their precheck, now refuse such meshes with the reason (pygeodesic only the
    non-manifold edge: it runs on the zero-area face)."""
    nm = tmp_path / "nm_edge.obj"
    nm.write_text("v 0 0 0\nv 1 0 0\nv 0.5 1 0\nv 0.5 -1 0\nv 0.5 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n")
    n = 6
    x, y = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1), indexing="ij")
    V = np.c_[x.ravel(), y.ravel(), 0 * x.ravel()]
    idx = np.arange(len(V)).reshape(n + 1, n + 1)
    F = [f for a in range(n) for b in range(n)
         for f in ([idx[a, b], idx[a + 1, b], idx[a + 1, b + 1]], [idx[a, b], idx[a + 1, b + 1], idx[a, b + 1]])]
    m = len(V)
    V = np.vstack([V, (V[0] + V[1]) / 2])                      # the midpoint of boundary edge 0-1
    F.remove([0, 8, 1])
    F += [[0, 8, m], [m, 8, 1], [0, m, 1]]                    # the last face is collinear: zero area
    za = tmp_path / "zero_area_grid.obj"
    za.write_text("".join(f"v {a} {b} {c}\n" for a, b, c in V) + "".join(f"f {p + 1} {q + 1} {r + 1}\n" for p, q, r in F))
    run({"name": "georef", "repeats": 1, "time_budget": 0, "meshes": [{"file": str(nm)}, {"file": str(za)}],
         "noise": [{"model": "none"}],
         "tasks": {"geodesics": {"methods": ["scratch.heat", "libigl.exact_geodesic", "pygeodesic.exact"],
                                 "params": {"sources": 1}}}}, out=tmp_path / "o", quiet=True)
    df = pd.read_csv(tmp_path / "o" / "geodesics.csv").set_index(["mesh", "method"])
    assert len(df) == 6 and (df["status"] == "error").all(), df[["status", "error"]]
    assert not df["error"].str.contains("worker process").any(), df["error"].tolist()
    assert df.loc[("nm_edge", "scratch.heat"), "error"].startswith("InvalidMeshError: no geodesic reference")
    assert "1 edge(s) on more than two faces" in df.loc[("nm_edge", "pygeodesic.exact"), "error"]
    assert "zero-area face" in df.loc[("zero_area_grid", "libigl.exact_geodesic"), "error"]
    assert "no geodesic reference" in df.loc[("zero_area_grid", "pygeodesic.exact"), "error"]


def test_two_spheres_sharing_a_vertex_have_no_exact_reference():
    """Through a vertex joining two fans, libigl's exact_geodesic (the task's reference on file
    meshes) returned 0 for every vertex of the far sphere, so correct methods were charged 0.36
    of the diagonal; the reference refuses such a mesh and names the vertex."""
    from harness.errors import InvalidMeshError
    from harness.tasks.geodesics import exact_polyhedral
    s = datasets.load({"procedural": "sphere", "subdivisions": 2}).clean
    V2 = s.V.copy()
    V2[:, 0] = 2 * s.V[0, 0] - V2[:, 0]                     # mirrored about the plane through vertex 0
    n = len(s.V)
    remap = np.arange(n) + n - 1
    remap[0] = 0
    remap[1:] = np.arange(1, n) + n - 1
    V = np.vstack([s.V, V2[1:]])
    F = np.vstack([s.F, remap[s.F][:, ::-1]])               # mirrored: reversed to stay outward
    with pytest.raises(InvalidMeshError, match=r"1 vertex/vertices joining separate fans \(first: \[0\]\)"):
        exact_polyhedral(V, F, 5)
    with pytest.raises(ValueError, match="joining separate fans"):
        methods.get("libigl.exact_geodesic")(V, F, sources=1)


@pytest.mark.parametrize("boundary", ["neumann", "average", "dirichlet"])
def test_tufted_heat_takes_the_boundary_condition_it_is_given(boundary):
    """On a manifold mesh the tufted Laplacian is the intrinsic Delaunay one (Sharp & Crane 2020),
    so under one boundary condition the two heat methods agree on open meshes, obtuse ones
    included: to 1e-14 of the largest distance on the open cylinder, 2e-5 on a non-Delaunay plane
    (the cover's mollification; measured, bound 1e-4). The tufted variant used the Neumann
    solution whatever ``boundary`` said, 4-5% away on the plane."""
    heat = methods.get("scratch.heat")
    for shape, tol in (({"procedural": "cylinder"}, 1e-12), ({"procedural": "plane_nondelaunay", "n_points": 1000}, 1e-4)):
        s = datasets.load(shape).clean
        tuft = heat(s.V, s.F, sources=2, boundary=boundary, laplacian="tufted").D
        idt = heat(s.V, s.F, sources=2, boundary=boundary, laplacian="intrinsic_delaunay").D
        assert np.abs(tuft - idt).max() <= tol * idt.max(), (shape, np.abs(tuft - idt).max() / idt.max())


def test_potpourri_heat_is_the_neumann_heat_method_on_open_meshes():
    """What potpourri3d.heat's docstring says: with use_robust off, geometry-central's heat method
    equals scratch.heat with boundary: neumann and the barycentric mass (2.3e-5 of the largest
    distance on the open cylinder, 6.5e-5 on a Delaunay plane; bound 2e-4), and is 4% from the
    paper's Neumann/Dirichlet average that scratch.heat and libigl.heat use by default."""
    for shape in ({"procedural": "cylinder"}, {"procedural": "plane_delaunay", "n_points": 1000}):
        s = datasets.load(shape).clean
        pp = methods.get("potpourri3d.heat")(s.V, s.F, sources=2, robust=False).D
        neu = methods.get("scratch.heat")(s.V, s.F, sources=2, boundary="neumann", mass="barycentric").D
        avg = methods.get("scratch.heat")(s.V, s.F, sources=2).D
        assert np.abs(pp - neu).max() <= 2e-4 * pp.max()
        assert np.abs(pp - avg).max() >= 0.02 * pp.max()


def _obtuse_plane(n=30, jitter=0.6, seed=3):
    """A jittered grid of the unit square, each cell split along a random diagonal (obtuse
    triangles), z = 0."""
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    P = np.c_[x.ravel(), y.ravel()]
    inner = (P.min(1) > 0) & (P.max(1) < 1)
    P[inner] += (rng.random((inner.sum(), 2)) - 0.5) * jitter / (n - 1)
    F = []
    for i in range(n - 1):
        for j in range(n - 1):
            a = i * n + j
            b, c, d = a + 1, a + n, a + n + 1
            F += [[a, b, d], [a, d, c]] if rng.random() < 0.5 else [[a, b, c], [b, d, c]]
    return np.c_[P, np.zeros(len(P))], np.array(F, dtype=np.int64)


def test_negated_distances_on_a_disconnected_mesh_fail_the_case(tmp_path):
    """libigl's heat method takes its result's sign from the mean over all vertices: on two copies
    of a noisy obtuse plane it negated one source's distances on its own copy (min -1.18; a mean
    relative error of 0.67 in an ok row, against 0.02 for its twin). Such a row is an error naming
    the negated distances; the twin's row stays ok."""
    from harness.mesh import write_obj
    V, F = _obtuse_plane()
    write_obj(tmp_path / "disc.obj", np.r_[V, V + [2, 0, 0]], np.r_[F, F + len(V)])
    run({"name": "geo", "repeats": 1, "time_budget": 0, "meshes": [{"file": str(tmp_path / "disc.obj")}],
         "noise": [{"model": "gaussian_normal", "levels": [0.3]}],
         "tasks": {"geodesics": {"methods": ["scratch.heat", "libigl.heat"], "params": {"sources": 3}}}},
        out=tmp_path / "run", quiet=True)
    df = pd.read_csv(tmp_path / "run" / "geodesics.csv").set_index("method")
    assert df.loc["scratch.heat", "status"] == "ok" and df.loc["scratch.heat", "rel_error_mean"] < 0.05
    assert df.loc["libigl.heat", "status"] == "error"
    assert "negated distances" in df.loc["libigl.heat", "error"], df.loc["libigl.heat", "error"]


def test_negated_distances_fail_and_a_dip_near_the_source_does_not():
    """The task's own check on two copies of a plane: a source's distances negated on its copy
    fail naming it; a dip of -0.25 of the largest distance at a few vertices (the cotan heat
    method's at small t on a non-Delaunay plane, a review: a check at -1e-6 failed the shipped
    geodesics config's cotan rows) is measured, not refused; -5 at unreachable vertices passes."""
    from harness import tasks
    from harness.errors import MethodFailed
    from harness.mesh import validate
    from harness.tasks.base import CaseInput
    from harness.tasks.geodesics import GeodesicResult
    task = tasks.get("geodesics")
    V, F = _obtuse_plane(12)
    clean = validate(np.r_[V, V + [2, 0, 0]], np.r_[F, F + len(V)], repair=False)
    inp = CaseInput(clean, clean.V, clean.F, clean.diagonal(), {})
    params = {"sources": 1, "source_seed": 0}
    s = int(source_vertices(len(clean.V), 1, 0)[0])
    own = np.arange(len(clean.V)) // len(V) == s // len(V)
    D = np.where(own, np.linalg.norm(clean.V - clean.V[s], axis=1), -5.0)
    assert task.measure(inp, GeodesicResult(D[None, :].copy()), params)["rel_error_max"] < 1e-12
    dip = D.copy()
    near = np.flatnonzero(own)[np.argsort(D[own])[1:6]]           # the five vertices nearest the source
    dip[near] = -0.25 * D.max()
    row = task.measure(inp, GeodesicResult(dip[None, :]), params)
    assert row["unreachable_fraction"] == 0.5 and row["abs_error_mean"] > 0
    with pytest.raises(MethodFailed, match=f"negated distances from source {s}"):
        task.measure(inp, GeodesicResult(np.where(own, -D, -5.0)[None, :]), params)


def test_meshlab_geodesic_refuses_a_source_with_a_twin_vertex():
    """MeshLab's filter starts from the vertex nearest a point: on a mesh cut along a seam (the
    seam's vertices doubled) a source on the seam measured from its other copy, 0 over its whole
    side, in an ok row. It is an error naming the twin; a source off the seam still runs."""
    V, F = _obtuse_plane(12)
    seam = np.flatnonzero(np.isclose(V[:, 0], V[5, 0]))            # the grid column of vertex 5
    copy = {int(v): len(V) + i for i, v in enumerate(seam)}
    V2 = np.r_[V, V[seam]]
    side = (V[F][:, :, 0].mean(axis=1) > V[5, 0])
    F2 = F.copy()
    for f in np.flatnonzero(side):
        F2[f] = [copy.get(int(v), int(v)) for v in F[f]]
    geo = methods.get("meshlab.geodesic")
    with pytest.raises(ValueError, match=f"source vertex 5 shares its position with vertex/vertices \\[{copy[5]}\\]"):
        geo.func(V2, F2, sources=np.array([5]))
    D = geo.func(V2, F2, sources=np.array([1])).D
    assert D[0, 1] == 0 and D.max() > 0
    V3 = V2.copy()
    V3[copy[5]] += 1e-12                          # a near twin, within the adapter's margin (a review)
    with pytest.raises(ValueError, match="source vertex 5 shares its position"):
        geo.func(V3, F2, sources=np.array([5]))


def test_the_exact_reference_does_not_depend_on_the_mesh_scale():
    """Kirsanov's code (libigl's exact_geodesic) has absolute tolerances: on a noisy obtuse plane
    scaled by 1e-6 its answer was 1.4e-3 (max relative) off its unit-scale answer. The reference is
    computed on the mesh scaled to a unit diagonal: equal to 1e-9 at 1e-6, 1 and 1e6, and 1e6
    away from the origin."""
    from harness.tasks.geodesics import exact_polyhedral
    V, F = _obtuse_plane()
    V = V + 0.3 / 29 * np.random.default_rng(0).standard_normal(V.shape) * [0, 0, 1]
    src = np.array([0, 400])
    base = exact_polyhedral(V, F, src)
    for scale, shift in ((1e-6, 0.0), (1e6, 0.0), (1.0, 1e6)):
        D = exact_polyhedral(V * scale + shift, F, src) / scale
        assert np.abs(D - base).max() <= 1e-9 * base.max(), (scale, shift, np.abs(D - base).max() / base.max())


def test_a_direct_call_with_an_unreferenced_vertex_says_so():
    """A review: called from Python on a mesh with a vertex no face uses (a run drops them on
    loading), scratch.heat failed inside the solver ("Error in computing elimination tree") and
    scratch.spectrum with "Matrix is not positive definite"; both now name the vertex."""
    s = datasets.load("knight").clean
    V = np.r_[s.V, [[9.0, 9.0, 9.0]]]
    with pytest.raises(ValueError, match=f"1 vertices no face uses \\(first: \\[{len(s.V)}\\]\\)"):
        methods.get("scratch.heat").func(V, s.F, sources=np.array([0]))
    with pytest.raises(ValueError, match=f"1 vertices no face uses \\(first: \\[{len(s.V)}\\]\\)"):
        methods.get("scratch.spectrum").func(V, s.F, k=5)


def test_rel_error_mean_carries_its_standard_error_over_the_sources(tmp_path):
    """An outside review: ``rel_error_mean`` is a mean over a few random sources and printed
    without an error bar, while on camelhead one source's mean ranged 0.008-0.016 and which of
    two heat methods was better flipped with the source. Its standard error over the sources
    (cluster sampling) is now a column: with equal counts per source it is the textbook
    ``std(per-source means) / sqrt(k)``; through a run it is what the per-source errors,
    recomputed here against the great circles, give; blank for one source. The sources are
    fixed by the case and shared by every method of the cell, so compare (two runs of one
    case) does not widen its tolerance by it (nor do the ties: the next test)."""
    from harness.compare import rules_from_specs
    from harness.tasks import get
    from harness.tasks.geodesics import source_se
    rng = np.random.default_rng(1)
    vals = rng.random((5, 40))
    assert source_se(vals, np.ones_like(vals, bool)) == pytest.approx(vals.mean(1).std(ddof=1) / np.sqrt(5), rel=1e-12)
    assert source_se(vals[:1], np.ones((1, 40), bool)) is None

    run({"name": "geo", "repeats": 1, "meshes": [{"procedural": "sphere", "subdivisions": 3}],
         "noise": [{"model": "none"}],
         "tasks": {"geodesics": {"methods": ["scratch.heat"], "params": {"sources": [1, 3]}}}},
        out=tmp_path, quiet=True)
    df = pd.read_csv(tmp_path / "geodesics.csv").set_index("params")
    one = df[df.index.str.contains('"sources": 1')].iloc[0]
    three = df[df.index.str.contains('"sources": 3')].iloc[0]
    assert pd.isna(one["rel_error_mean_se"])
    s = datasets.load({"procedural": "sphere", "subdivisions": 3})
    V, F = s.clean.V, s.clean.F
    D = methods.get("scratch.heat")(V, F, sources=3).D
    h = mean_edge_length(V, F)
    y, n = [], []
    for i, sv in enumerate(source_vertices(len(V), 3, 0)):
        ref = analytic(s.shape, V, V[sv])
        far = ref > 3 * h
        y.append((np.abs(D[i] - ref)[far] / ref[far]).sum())
        n.append(far.sum())
    y, n = np.array(y), np.array(n, float)
    r = y.sum() / n.sum()
    expect = np.sqrt(3 / 2 * ((y - r * n) ** 2).sum()) / n.sum()
    assert three["rel_error_mean"] == pytest.approx(r, rel=1e-9)
    assert three["rel_error_mean_se"] == pytest.approx(expect, rel=1e-6) and expect > 0
    rule = rules_from_specs({"geodesics": get("geodesics").spec()})["geodesics"]["rel_error_mean"]
    assert rule.se == ""
    assert next(m for m in get("geodesics").spec()["metrics"] if m["name"] == "rel_error_mean")["se"] == "rel_error_mean_se"


def test_an_exact_method_off_its_own_reference_is_measured_not_hidden(tmp_path):
    """An outside review: libigl.exact_geodesic runs on the mesh as given, the reference on the
    mesh scaled to a unit diagonal; on knight scaled by 1e-3 the library's absolute tolerances
    put the method 2.3e-4 off the reference, yet the row was hidden as "0 by construction". Such
    a row is now a measurement, ranked like any other; at knight's own scale it is still no
    measurement (`equals_reference`)."""
    from harness.mesh import write_obj
    V, F = datasets.load("knight").clean.V, datasets.load("knight").clean.F
    write_obj(tmp_path / "small.obj", V * 1e-3, F)
    run({"name": "geo", "repeats": 1, "time_budget": 0, "meshes": [{"file": str(tmp_path / "small.obj")}, "knight"],
         "noise": [{"model": "none"}], "tasks": {"geodesics": {"methods": ["libigl.exact_geodesic", "scratch.heat"],
                                                                 "params": {"sources": 2}}}},
        out=tmp_path / "out", quiet=True)
    df = pd.read_csv(tmp_path / "out" / "geodesics.csv").set_index(["mesh", "method"])
    small = df.loc[(df.index.get_level_values(0) != "knight")].xs("libigl.exact_geodesic", level=1).iloc[0]
    own = df.loc[("knight", "libigl.exact_geodesic")]
    assert 1e-6 < small["rel_error_max"] < 1e-2 and not small["equals_reference"], small
    assert own["rel_error_max"] < 1e-12 and own["equals_reference"]
    w = pd.read_csv(tmp_path / "out" / "winners.csv")
    w = w[w.metric == "rel_error_mean"].set_index("mesh")
    assert w.loc["knight", "best"] == "scratch.heat"
    assert "libigl.exact_geodesic" in str(w.loc[w.index != "knight", "best"].iloc[0])


def test_a_shared_sample_error_is_printed_not_used_for_ties(tmp_path):
    """A diff review of the standard error over sources: every method and seed of a cell has the
    same sources, so (1) over two noise seeds the error of the mean is not sqrt(sum se^2) / n,
    which assumes independent seeds (2.7x too small over 12 source sets), and is printed as the
    mean of the seeds' errors, its upper bound; (2) comparing methods on the same sources is
    paired: t_factor 1 beats 2 on every one of 6 sources on bunny, yet the unpaired 3 x combined
    error called them tied, and tune kept the worse configured value. Ties and tune now ignore
    this error, and compare too."""
    import json as _json
    run({"name": "g", "repeats": 1, "time_budget": 0, "meshes": ["bunny"],
         "noise": [{"model": "gaussian_normal", "levels": [0.1], "seeds": 2}],
         "tasks": {"geodesics": {"params": {"sources": 6}, "methods": [
             {"name": "scratch.heat", "params": {"laplacian": "intrinsic_delaunay", "t_factor": [1.0, 2.0]}}]}}},
        out=tmp_path / "a", quiet=True)
    df = pd.read_csv(tmp_path / "a" / "geodesics.csv")
    df["t"] = [_json.loads(p)["t_factor"] for p in df["params"]]
    w = pd.read_csv(tmp_path / "a" / "winners.csv")
    w = w[w.metric == "rel_error_mean"].iloc[0]
    one, two = df[df.t == 1.0], df[df.t == 2.0]
    assert "t_factor=1.0" in w["best"] and pd.isna(w["tied_with_best"]), w
    assert w["value"] == pytest.approx(one["rel_error_mean"].mean(), rel=1e-12)
    assert w["value_se"] == pytest.approx(one["rel_error_mean_se"].mean(), rel=1e-9)          # the mean, not / sqrt(2)
    assert (two["rel_error_mean"].mean() - one["rel_error_mean"].mean()
            < 3 * np.hypot(one["rel_error_mean_se"].mean(), two["rel_error_mean_se"].mean()))   # unpaired: a tie
    md = (tmp_path / "a" / "winners.md").read_text()
    assert "± its standard error over the sample every method of the cell shares" in md, md
    from harness.leaderboard import winners_latex, winners_markdown       # without specs: the installed kind's
    frame = pd.read_csv(tmp_path / "a" / "winners.csv")
    assert "over the sample every method of the cell shares" in winners_markdown(frame)
    assert "over seeds the mean of theirs" in winners_latex(frame)

    run({"name": "t", "repeats": 1, "time_budget": 0, "meshes": ["knight"], "noise": [{"model": "none"}],
         "tasks": {"geodesics": {"params": {"sources": 6}, "methods": [
             {"name": "scratch.heat", "params": {"laplacian": "intrinsic_delaunay", "t_factor": 2.0}}]}},
         "tune": {"metric": "rel_error_mean", "train": ["bunny"], "budget": 4, "seed": 0,
                  "params": {"scratch.heat": {"t_factor": [2.0, 1.0]}}}}, out=tmp_path / "t", quiet=True)
    chosen = _json.loads((tmp_path / "t" / "run.json").read_text())["tune"]["methods"]["scratch.heat"]
    assert chosen["chosen"] == {"t_factor": 1.0} and chosen["train_score"] < chosen["default_train_score"], chosen


def test_an_exact_method_on_a_mesh_too_small_for_relative_errors_is_still_no_measurement(tmp_path):
    """A diff review: on an icosahedron no vertex lies 3 mean edge lengths from a source, so the
    relative errors are blank; equals_reference was then False and the exact methods, 0 by
    construction (abs_error_mean 4e-17), were named best by abs_error_mean. Without relative
    errors the largest absolute error decides, against the diagonal."""
    run({"name": "g", "repeats": 1, "time_budget": 0, "meshes": [{"procedural": "sphere", "subdivisions": 0}],
         "noise": [{"model": "gaussian_normal", "levels": [0.3]}],
         "tasks": {"geodesics": {"params": {"sources": 2},
                                 "methods": ["libigl.exact_geodesic", "pygeodesic.exact", "scratch.heat"]}}},
        out=tmp_path, quiet=True)
    df = pd.read_csv(tmp_path / "geodesics.csv").set_index("method")
    assert df["rel_error_mean"].isna().all() and df["reference_exact"].all()
    assert df.loc["libigl.exact_geodesic", "equals_reference"] and df.loc["pygeodesic.exact", "equals_reference"]
    assert not df.loc["scratch.heat", "equals_reference"]


def test_sources_given_as_vertices(tmp_path):
    """The issue asks for sources as a count (a seeded choice) or given in the config: given as
    ``{vertices: [...]}`` (a mapping: a list of values is a sweep), they are the rows of ``D`` in
    their order, score exactly as the same vertices chosen by count, and carry no error over the
    choice of sources (no random sample); a bad form is a config problem with its key path, an
    index the mesh does not have the case's error row."""
    from harness.errors import ConfigError
    s = datasets.load({"procedural": "sphere", "subdivisions": 3})
    V, F = s.clean.V, s.clean.F
    chosen = source_vertices(len(V), 3, 0)
    D = methods.get("scratch.heat")(V, F, sources={"vertices": chosen[::-1].tolist()}).D
    D_arr = methods.get("scratch.heat")(V, F, sources={"vertices": chosen[::-1]}).D     # from Python: an array
    assert np.array_equal(D, methods.get("scratch.heat")(V, F, sources=3).D[::-1]) and np.array_equal(D, D_arr)
    for bare in (chosen[::-1], chosen[::-1].tolist(), tuple(chosen[::-1].tolist())):    # the list itself, from Python
        assert np.array_equal(D, methods.get("scratch.heat")(V, F, sources=bare).D)

    cfg = {"name": "g", "repeats": 1, "time_budget": 0, "meshes": [{"procedural": "sphere", "subdivisions": 3}],
           "noise": [{"model": "none"}],
           "tasks": {"geodesics": {"methods": ["scratch.heat"],
                                   "params": {"sources": [3, {"vertices": chosen.tolist()}, [1, 10 ** 6]]}}}}
    run(cfg, out=tmp_path / "o", quiet=True)
    df = pd.read_csv(tmp_path / "o" / "geodesics.csv")
    by_count = df[df["params"].str.contains('"sources": 3')].iloc[0]
    given = df[df["params"].str.contains(f'"vertices": {chosen.tolist()}', regex=False)].iloc[0]
    far = df[df["params"].str.contains("1000000")].iloc[0]
    assert given["status"] == by_count["status"] == "ok"
    assert given["rel_error_mean"] == by_count["rel_error_mean"] and given["rel_error_max"] == by_count["rel_error_max"]
    assert by_count["rel_error_mean_se"] > 0 and pd.isna(given["rel_error_mean_se"])
    assert far["status"] == "error" and "source vertex 1000000 is not a vertex of this mesh" in far["error"]

    bad = {**cfg, "tasks": {"geodesics": {"methods": ["scratch.heat",
                                                      {"name": "libigl.heat", "params": {"sources": {"verts": [1]}}}],
                                          "params": {"sources": [{"vertices": []}, {"vertices": [-1]},
                                                                 {"vertices": [4, 4]}, {"vertices": [1.5]},
                                                                 {"vertices": list(range(65))}]}}}}
    with pytest.raises(ConfigError) as e:
        run(bad, out=tmp_path / "bad", quiet=True)
    msg = str(e.value)
    assert not (tmp_path / "bad").exists()
    for needle in ("tasks.geodesics.methods[1].params.sources: parameter 'sources': expected a count of sources",
                   "vertices: expected a non-empty list of vertex indices (ints), got []",
                   "a vertex index is >= 0, got -1", "[4] given more than once",
                   "got [1.5]", "at most 64 sources, got 65"):
        assert needle in msg, msg


def test_a_skinny_remesh_of_the_plane_and_intrinsic_delaunay():
    """The geodesics issue's obtuse-mesh study asks for a deliberately skinny-triangle remesh
    beside the flipped plane: plane_skinny splits half the plane's faces next to their longest
    edge (slivers near 180 degrees, the same unit square, so the analytic reference holds), and
    the intrinsic Delaunay Laplacian improves the heat method there (measured 5.1% -> 1.1% mean
    relative error with 4 sources at 3,000 points)."""
    from harness.core.geometry import corner_angles
    from harness.mesh import topology
    s = datasets.load({"procedural": "plane_skinny", "n_points": 1500})
    V, F = s.clean.V, s.clean.F
    t = topology(V, F)
    assert t["manifold"] and t["boundary_loops"] == 1 and t["euler"] == 1
    assert V[:, :2].min() >= 0 and V[:, :2].max() <= 1 and not V[:, 2].any()
    assert corner_angles(V, F).max() > 175
    err = {lap: rel_errors({"procedural": "plane_skinny", "n_points": 1500}, "scratch.heat", k=4, laplacian=lap).mean()
           for lap in ("cotan", "intrinsic_delaunay")}
    assert err["intrinsic_delaunay"] < 0.5 * err["cotan"], err


def test_symmetry_error_leaves_out_sources_next_to_each_other(tmp_path):
    """An outside audit: the relative errors leave out 3 mean edge lengths around each source,
    symmetry_error did not, and two adjacent sources on bunny scored 0.127 (scratch.heat) and
    0.308 (potpourri3d) against 0.015 and 0.016 for a pair far apart. Pairs closer than that
    are left out now: blank when none is left."""
    got = {}
    for srcs in ([940, 2947], [940, 2961]):
        out = tmp_path / str(srcs[1])
        harness.run({"name": "s", "repeats": 1, "time_budget": 0, "meshes": ["bunny"], "noise": [{"model": "none"}],
                     "tasks": {"geodesics": {"methods": ["scratch.heat"], "params": {"sources": [{"vertices": srcs}]}}}},
                    out=out, quiet=True)
        got[srcs[1]] = pd.read_csv(out / "geodesics.csv").iloc[0]
    assert got[2947]["status"] == "ok" and pd.isna(got[2947]["symmetry_error"])
    assert 0.005 < got[2961]["symmetry_error"] < 0.03
