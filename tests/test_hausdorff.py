"""The certified Hausdorff distance: closed forms, an independent C++ implementation (Sacht &
Jacobson 2024, cascading upper bounds, PyPI ``cascading-upper-bounds``), dense sampling, exact
reconstructions and budgets."""

import numpy as np
import pytest

import methods
from harness import datasets
from harness.core.geometry import sample_surface
from harness.metrics.hausdorff import _Surface, hausdorff, one_sided
from harness.provenance import usable_cpus


def test_plane_and_displaced_copy_bracket_the_offset():
    V, F = datasets.plane_delaunay(2000, 1)
    h = hausdorff(V, F, V + [0, 0, 0.0123], F)
    assert h["hausdorff"] <= 0.0123 + 1e-15 <= h["hausdorff_upper"] + 2e-15
    assert h["hausdorff_gap"] <= 1e-3 and h["hausdorff_certified"]


@pytest.mark.parametrize("s", [1, 2])
def test_inscribed_icosphere(s):
    """An icosphere inscribed in the unit sphere is at Hausdorff distance ``1 - min_f d(O, f)``
    (the face plane nearest the centre) from it, both ways. The sphere is a 7-times subdivided
    icosphere, itself within ``e = 1.8e-5`` of the sphere, so the certified bracket must meet
    ``[exact - e, exact + e]``."""
    A, FA = datasets.icosphere(s)
    S, FS = datasets.icosphere(7)

    def gap_to_sphere(V, F):
        n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        return 1 - np.abs(np.einsum("ij,ij->i", n, V[F[:, 0]])).min()

    exact, e = gap_to_sphere(A, FA), gap_to_sphere(S, FS)
    h = hausdorff(A, FA, S, FS, n_samples=0)
    assert h["hausdorff_certified"] and h["hausdorff_gap"] <= 1e-3
    assert h["hausdorff"] <= exact + e and h["hausdorff_upper"] >= exact - e


@pytest.fixture(scope="module")
def simplified():
    clean = datasets.load("bunny").clean
    return {m: (methods.get(m)(clean.V, clean.F, target_ratio=0.1), clean) for m in ("meshlab.qem", "scratch.qem")}


@pytest.mark.parametrize("method", ["meshlab.qem", "scratch.qem"])
def test_brackets_agree_with_cascading_upper_bounds(simplified, method):
    """Each one-sided bracket overlaps the one of the independent C++ implementation (both are
    certified, so the true value lies in both) and is at most 1e-3 wide (relative)."""
    import cascading_upper_bounds as cub
    r, clean = simplified[method]
    h = hausdorff(r.V, r.F, clean.V, clean.F)
    A = (np.ascontiguousarray(r.V), np.ascontiguousarray(r.F, dtype=np.int32))
    B = (np.ascontiguousarray(clean.V), np.ascontiguousarray(clean.F, dtype=np.int32))
    for (X, Y) in ((A, B), (B, A)):
        lo, hi = cub.pompeiu_hausdorff(X[0], X[1], Y[0], Y[1], tol=1e-7)[:2]
        ours = one_sided(X[0], X[1].astype(np.int64), _Surface(*Y))
        assert ours["certified"] and ours["upper"] <= ours["lower"] * (1 + 1e-3) + 1e-15
        assert ours["lower"] <= hi * (1 + 1e-12) and lo <= ours["upper"] * (1 + 1e-12), (ours, lo, hi)
    assert h["hausdorff"] == pytest.approx(max(h["hausdorff_ab"], h["hausdorff_ba"]))


@pytest.mark.parametrize("method", ["meshlab.qem", "scratch.qem"])
def test_floor_closes_the_smaller_direction_and_keeps_the_symmetric_bracket(simplified, method, monkeypatch):
    """The direction bracketed second stops at the first one's lower bound (``floor``): its
    upper bound is still a valid bound of its own distance (against the independent C++
    implementation), it makes fewer queries than bracketing it alone, and the symmetric
    bracket still holds the independent symmetric value within 1e-3."""
    import cascading_upper_bounds as cub
    r, clean = simplified[method]
    A = (np.ascontiguousarray(r.V), np.ascontiguousarray(r.F, dtype=np.int32))
    B = (np.ascontiguousarray(clean.V), np.ascontiguousarray(clean.F, dtype=np.int32))
    exact = [cub.pompeiu_hausdorff(X[0], X[1], Y[0], Y[1], tol=1e-7)[:2] for X, Y in ((A, B), (B, A))]
    small = int(exact[0][1] > exact[1][1])              # the direction with the smaller distance
    X, Y = (A, B) if small == 0 else (B, A)
    alone = one_sided(X[0], X[1].astype(np.int64), _Surface(*Y))
    floor = max(lo for lo, _ in exact)
    cut = one_sided(X[0], X[1].astype(np.int64), _Surface(*Y), floor=floor)
    assert cut["certified"] and cut["upper"] <= floor * (1 + 1e-3) + 1e-15
    assert cut["upper"] >= exact[small][0] * (1 - 1e-12) and cut["points"] < alone["points"]
    assert cut["lower"] <= exact[small][1] * (1 + 1e-12)        # still a lower bound of its own direction
    import harness.metrics.hausdorff as H
    calls, real = [], H.one_sided

    def spy(*a, **k):
        out = real(*a, **k)
        calls.append((k.get("floor", 0.0), out["lower"]))
        return out
    monkeypatch.setattr(H, "one_sided", spy)
    h = hausdorff(r.V, r.F, clean.V, clean.F)
    assert len(calls) == 2 and calls[0][0] == 0.0 and calls[1][0] == calls[0][1] > 0   # the first's lower is the floor
    lo, hi = max(e[0] for e in exact), max(e[1] for e in exact)
    assert h["hausdorff_certified"] and h["hausdorff_upper"] <= h["hausdorff"] * (1 + 1e-3) + 1e-15
    assert h["hausdorff"] <= hi * (1 + 1e-12) and lo <= h["hausdorff_upper"] * (1 + 1e-12)


def _plane_with_hole(c, r, n_sides, half=5.0, n=41):
    """A Delaunay grid of the square [-half, half]^2 (z = 0) with a regular ``n_sides``-gon hole
    of circumradius ``r`` centred at ``c``."""
    from scipy.spatial import Delaunay
    xs = np.linspace(-half, half, n)
    P = np.array([[x, y] for x in xs for y in xs])
    P = P[np.linalg.norm(P - c, axis=1) > r * 1.05]
    ang = np.arange(n_sides) * 2 * np.pi / n_sides
    P = np.vstack([P, c + r * np.c_[np.cos(ang), np.sin(ang)]])
    T = Delaunay(P).simplices
    T = T[np.linalg.norm(P[T].mean(1) - c, axis=1) > r * np.cos(np.pi / n_sides) * 0.999]
    return np.c_[P, np.zeros(len(P))], T.astype(np.int64)


@pytest.mark.parametrize("rel", [-3e-4, 3e-4, -2e-3])
@pytest.mark.parametrize("n_samples", [0, 20000])
def test_near_tie_of_the_two_directions_keeps_the_symmetric_bracket(rel, n_samples):
    """Closed forms with the two directions within eps of each other, so the floor may stop the
    truly larger one: A is a square with a hexagon-like 24-gon hole plus a small triangle at
    height t above it, B the full square. ``h(A, B) = t`` (the triangle), ``h(B, A) = r_in``
    (the hole's centre to its inscribed circle's edges). The bracket must hold
    ``max(t, r_in)``, be certified, and each one-sided value must stay a lower bound."""
    c, r, k = np.array([0.37, -0.21]), 1.0, 24
    VA, FA = _plane_with_hole(c, r, k)
    r_in = r * np.cos(np.pi / k)
    t = r_in * (1 + rel)
    VA = np.vstack([VA, [[3.0, 3.0, t], [3.2, 3.0, t], [3.0, 3.2, t]]])
    FA = np.vstack([FA, len(VA) - 3 + np.array([[0, 1, 2]])])
    VB = np.array([[-5.0, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]])
    FB = np.array([[0, 1, 2], [0, 2, 3]])
    h = hausdorff(VA, FA, VB, FB, n_samples=n_samples)
    H_exact = max(t, r_in)
    assert h["hausdorff_certified"] and h["hausdorff_upper"] <= h["hausdorff"] * (1 + 1e-3) + 1e-12
    assert h["hausdorff"] <= H_exact * (1 + 1e-12) and H_exact <= h["hausdorff_upper"] * (1 + 1e-12)
    assert h["hausdorff_ab"] <= t * (1 + 1e-12) and h["hausdorff_ba"] <= r_in * (1 + 1e-12)


@pytest.mark.parametrize("method", ["meshlab.qem", "scratch.qem"])
def test_dense_sampling_never_exceeds_the_upper_bound(simplified, method):
    """200k random points plus the vertices per side: their largest distance is a lower bound,
    so it can never exceed the certified upper bound; on these meshes it also falls short of the
    certified value (sampling misses the maximum)."""
    r, clean = simplified[method]
    h = hausdorff(r.V, r.F, clean.V, clean.F, n_samples=0)
    SA, SB = _Surface(r.V, r.F), _Surface(clean.V, clean.F)
    PA = np.concatenate([r.V, sample_surface(r.V, r.F, 200_000, 3)])
    PB = np.concatenate([clean.V, sample_surface(clean.V, clean.F, 200_000, 4)])
    sampled = max(SB.query(PA)[0].max(), SA.query(PB)[0].max())
    assert sampled <= h["hausdorff_upper"] * (1 + 1e-12)
    assert sampled <= h["hausdorff"] * (1 + 1e-3)


def test_exact_reconstruction_and_budget():
    """A mesh against itself is 0 with gap 0 (the absolute tolerance); a budget too small to
    certify leaves a valid, wider bracket and says so."""
    clean = datasets.load("knight").clean
    h = hausdorff(clean.V, clean.F, clean.V, clean.F)
    assert h["hausdorff"] <= 1e-15 * clean.diagonal() and h["hausdorff_upper"] <= 1e-12 * clean.diagonal()
    assert h["hausdorff_gap"] == 0 and h["hausdorff_certified"]
    r = methods.get("scratch.qem")(clean.V, clean.F, target_ratio=0.05)
    full = hausdorff(r.V, r.F, clean.V, clean.F, n_samples=0)
    cut = hausdorff(r.V, r.F, clean.V, clean.F, n_samples=0, max_points=50)
    assert not cut["hausdorff_certified"] and cut["hausdorff_gap"] > 1e-3
    assert cut["hausdorff"] <= full["hausdorff_upper"] and cut["hausdorff_upper"] >= full["hausdorff"]


def test_hausdorff_eps_reaches_the_case_and_is_validated(tmp_path):
    """The top-level ``hausdorff_eps`` sets the gap a simplification row is certified to; a bad
    value is a config error naming the key."""
    import pandas as pd

    import harness
    from harness.errors import ConfigError
    cfg = {"name": "eps", "time_budget": 0, "hausdorff_samples": 0, "save_meshes": False, "meshes": ["bunny"],
           "tasks": {"simplification": {"methods": ["meshlab.qem"], "params": {"target_ratio": [0.1]}}}}
    gaps = {}
    for eps in (0.3, 1e-6):
        harness.run({**cfg, "hausdorff_eps": eps}, out=tmp_path / str(eps), quiet=True, workers=1)
        row = pd.read_csv(tmp_path / str(eps) / "simplification.csv").iloc[0]
        assert row["status"] == "ok"
        gaps[eps] = row["hausdorff_gap"]
    assert gaps[0.3] <= 0.3 and gaps[1e-6] <= 1e-6 < gaps[0.3]
    for bad in (0, -1, 2, "x"):
        with pytest.raises(ConfigError, match="hausdorff_eps"):
            harness.run({**cfg, "hausdorff_eps": bad}, out=tmp_path / "bad", quiet=True)
    assert not (tmp_path / "bad").exists()


def test_compiled_hierarchy_equals_libigl_distances():
    """Our BVH's point-to-surface distances equal libigl's AABB ones (1e-15 of the diagonal) for
    points on, near and far from a real mesh, with and without hints, and on a mesh with a
    degenerate (zero-area) triangle."""
    from harness.metrics._bvh_kernel import query_many
    for name in ("armadillo", "woody"):
        m = datasets.load(name).clean
        F = np.vstack([m.F, [[0, 0, 1]]])                       # a needle: the segment 0-1
        S = _Surface(m.V, F)
        rng = np.random.default_rng(1)
        diag = m.diagonal()
        P = np.concatenate([sample_surface(m.V, m.F, 20000, 2) + rng.normal(scale=0.01 * diag, size=(20000, 3)),
                            rng.uniform(m.V.min(0) - diag, m.V.max(0) + diag, size=(500, 3)), m.V])
        ref = S.query(P)[0]
        tree = S.bvh()
        d, f = query_many(P, np.full(len(P), -1, np.int64), *tree)
        assert np.abs(d - ref).max() <= 1e-15 * diag
        hinted = query_many(P, np.roll(f, 1), *tree)[0]     # hints from other points: same answer
        assert np.abs(hinted - ref).max() <= 1e-15 * diag


def test_blocked_queries_give_the_same_answer_on_any_number_of_threads(monkeypatch):
    """`harness.metrics._queries.query_blocks` cuts the points into fixed blocks, so its distances
    and closest faces are identical (bit for bit) on one, two and three threads and with
    ``OMP_NUM_THREADS`` choosing; the distances equal libigl's to 1e-15 of the diagonal, with and
    without hints, and one unblocked call's (the blocks only restart the hint chain)."""
    from harness.metrics import _queries
    from harness.metrics._bvh_kernel import query_many
    m = datasets.load("armadillo").clean
    S = _Surface(m.V, m.F)
    rng = np.random.default_rng(3)
    diag = m.diagonal()
    P = sample_surface(m.V, m.F, 3 * _queries.BLOCK + 17, 4) + rng.normal(scale=0.01 * diag, size=(3 * _queries.BLOCK + 17, 3))
    tree = S.bvh()
    none = np.full(len(P), -1, np.int64)
    d1, f1 = _queries.query_blocks(P, none, *tree, threads=1)
    for n in (2, 3):
        d, f = _queries.query_blocks(P, none, *tree, threads=n)
        assert np.array_equal(d, d1) and np.array_equal(f, f1)
    monkeypatch.setenv("OMP_NUM_THREADS", "2")
    assert _queries.case_threads() == min(2, usable_cpus())
    monkeypatch.setenv("OMP_NUM_THREADS", "64")          # never more than the CPUs it may run on
    assert _queries.case_threads() == usable_cpus()
    monkeypatch.setenv("OMP_NUM_THREADS", "2")
    d, f = _queries.query_blocks(P, none, *tree)
    assert np.array_equal(d, d1) and np.array_equal(f, f1)
    monkeypatch.setenv("OMP_NUM_THREADS", "x")
    assert _queries.case_threads() == 1
    ref = S.query(P)[0]
    assert np.abs(d1 - ref).max() <= 1e-15 * diag
    assert np.abs(d1 - query_many(P, none, *tree)[0]).max() <= 1e-15 * diag
    hinted = _queries.query_blocks(P, np.roll(f1, 1), *tree, threads=2)[0]
    assert np.abs(hinted - ref).max() <= 1e-15 * diag
    assert len(_queries.query_blocks(P[:0], none[:0], *tree)[0]) == 0


@pytest.mark.parametrize("level", [0.3, 3.0, 30.0])
def test_displaced_surface_reuses_the_tree_and_gives_the_same_distances(level):
    """`Surface.displaced`: the clean mesh's tree with its boxes recomputed for a noisy copy (up to
    thirty mean edge lengths of noise, where the old tree fits badly) holds every triangle in its
    boxes, and its distances equal a freshly built surface's and libigl's (1e-15 of the diagonal)."""
    from harness.metrics._bvh_kernel import query_many
    from harness.noise import apply_noise
    m = datasets.load("armadillo").clean
    V = apply_noise(m.V, m.F, "gaussian_normal", level, 0)
    D = _Surface(m.V, m.F).displaced(V)
    Vo, Fo, B = D.bvh()
    assert np.array_equal(Vo[Fo], V[m.F][np.argsort(D._pos)])      # the same triangles, in leaf order
    for k in np.flatnonzero(B[:, 6] < 0):                           # every leaf's box holds its triangles
        P = Vo[Fo[int(-1 - B[k, 6]):int(B[k, 7])]].reshape(-1, 3)
        assert (P >= B[k, :3]).all() and (P <= B[k, 3:6]).all()
    inner = np.flatnonzero(B[:, 6] >= 0)
    for c in (6, 7):                                                # and every inner box its children's
        ch = B[inner, c].astype(np.int64)
        assert (B[ch, :3] >= B[inner, :3]).all() and (B[ch, 3:6] <= B[inner, 3:6]).all()
    rng = np.random.default_rng(3)
    diag = m.diagonal()
    P = np.concatenate([sample_surface(V, m.F, 5000, 4) + rng.normal(scale=0.01 * diag, size=(5000, 3)), V])
    if level > 10:           # every query meets hundreds of crossing triangles there: a tenth of the points
        P = P[::10]
    ref = _Surface(V, m.F).query(P)[0]
    fresh = query_many(P, np.full(len(P), -1, np.int64), *_Surface(V, m.F).bvh())[0]
    d = query_many(P, np.full(len(P), -1, np.int64), *D.bvh())[0]
    assert np.abs(d - ref).max() <= 1e-15 * diag and np.abs(d - fresh).max() <= 1e-15 * diag
    with pytest.raises(ValueError, match="one position per vertex"):
        _Surface(m.V, m.F).displaced(V[:-1])


def test_corresponding_vertices_give_a_valid_tighter_bracket():
    """A smoothed mesh against its clean original (same faces): the displacement cap gives a
    bracket that overlaps the one found without it and is no wider; mismatched faces are refused."""
    from harness.noise import apply_noise
    m = datasets.load("bunny").clean
    V = methods.get("scratch.taubin")(apply_noise(m.V, m.F, "gaussian_normal", 0.3, 0), m.F).V
    a = hausdorff(V, m.F, m.V, m.F, n_samples=0)
    b = hausdorff(V, m.F, m.V, m.F, n_samples=0, corresponding=True)
    assert a["hausdorff_certified"] and b["hausdorff_certified"]
    assert max(a["hausdorff"], b["hausdorff"]) <= min(a["hausdorff_upper"], b["hausdorff_upper"]) * (1 + 1e-12)
    assert b["hausdorff_upper"] - b["hausdorff"] <= a["hausdorff_upper"] - a["hausdorff"] + 1e-15
    assert b["hausdorff_points"] < a["hausdorff_points"]
    with pytest.raises(ValueError, match="corresponding"):
        hausdorff(V[:-1], m.F[:10], m.V, m.F, n_samples=0, corresponding=True)


@pytest.mark.parametrize("level", [0.0, 0.3, 3.0])
def test_corresponding_bracket_skips_settled_triangles_and_stays_valid(level):
    """With corresponding vertices, B's triangles whose displacement cap is within the threshold
    set by the A-to-B bound are not queried; the symmetric bracket still contains the bracket
    found without the correspondence (noise from none to three mean edge lengths)."""
    from harness.noise import apply_noise
    from harness.metrics.surface_distance import Surface
    m = datasets.load("bunny").clean
    V = apply_noise(m.V, m.F, "gaussian_normal", level, 0) if level else m.V.copy()
    a = hausdorff(V, m.F, m.V, m.F, n_samples=0)
    SB = Surface(m.V, m.F)
    b = hausdorff(V, m.F, m.V, m.F, n_samples=0, corresponding=True, surface_b=SB)
    assert b["hausdorff_certified"]
    assert max(a["hausdorff"], b["hausdorff"]) <= min(a["hausdorff_upper"], b["hausdorff_upper"]) * (1 + 1e-12) + 1e-15
    assert b["hausdorff_points"] < a["hausdorff_points"]
    if level == 0.0:                                    # nothing but the rounding allowance of the points queried
        from harness.metrics.hausdorff import ROUND
        assert b["hausdorff"] == 0.0 and b["hausdorff_upper"] <= ROUND * np.abs(m.V).max()


def test_a_zero_area_side_has_no_samples_but_a_certified_bracket():
    """A collinear triangle (zero area: no area-uniform samples) against a right triangle: the
    mean surface distance is NaN, the Hausdorff distance exact (1: from (2, 0, 0) and from
    (0, 1, 0))."""
    V = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0.0]])
    VB = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]])
    F = np.array([[0, 1, 2]])
    h = hausdorff(V, F, VB, F, n_samples=100)
    assert np.isnan(h["surface_dist_mean"]) and h["hausdorff_certified"]
    assert h["hausdorff"] == pytest.approx(1.0, abs=1e-12) and h["hausdorff_upper"] == pytest.approx(1.0, abs=1e-12)


def test_the_brackets_numba_cache_is_dropped_when_a_kernel_it_compiles_in_changes(tmp_path):
    """numba keys _bracket_kernel's cache by that file alone, but its functions compile
    _bvh_kernel's and cover_bound's in: an edited dependency must not leave the old machine code
    running."""
    from harness.metrics._kernel_cache import drop_stale_cache
    here, cache = tmp_path / "_bracket_kernel.py", tmp_path / "__pycache__"
    deps = {name: tmp_path / name for name in ("_bvh_kernel.py", "_cover_bound.py")}
    here.write_text("# kernel\n")
    for name, dep in deps.items():
        dep.write_text(f"# {name} v1\n")
    cache.mkdir()

    def fake_cache():
        for name in ("_bracket_kernel._upper-324.py311.nbi", "_bracket_kernel._upper-324.py311.1.nbc",
                     "_cover_bound.cover_bound-38.py311.nbi", "_bracket_kernel.cpython-311.pyc"):
            (cache / name).write_text("x")
    fake_cache()
    assert drop_stale_cache(here, tuple(deps))             # no record yet: cannot vouch for the files
    assert sorted(p.name for p in cache.iterdir()) == ["_bracket_kernel.cpython-311.pyc", "_bracket_kernel.deps",
                                                        "_cover_bound.cover_bound-38.py311.nbi"]
    for name, dep in deps.items():
        fake_cache()
        assert not drop_stale_cache(here, tuple(deps)) and (cache / "_bracket_kernel._upper-324.py311.nbi").exists()
        dep.write_text(f"# {name} v2\n")
        assert drop_stale_cache(here, tuple(deps)) and not (cache / "_bracket_kernel._upper-324.py311.nbi").exists()


def test_surface_b_keeps_its_samples_through_a_pickle_with_the_same_result(simplified):
    """B's samples are drawn once per `Surface` (memoised, and kept when the surface is pickled
    as a per-input fact): a second bracket through the same or an unpickled surface, and one
    through a fresh surface, give the same values bit for bit; the samples are
    `sample_surface`'s."""
    import pickle
    from harness.core.geometry import morton_order
    r, clean = simplified["scratch.qem"]
    V, F, Vo, Fo = clean.V, clean.F, r.V, r.F
    S = _Surface(V, F)
    first = hausdorff(Vo, Fo, V, F, surface_b=S, n_samples=5000, seed=3)
    P, order = S.samples(5000, 4)
    assert np.array_equal(P, sample_surface(V, F, 5000, 4)) and np.array_equal(order, morton_order(P))
    assert S.samples(5000, 4)[0] is P                            # memoised
    again = pickle.loads(pickle.dumps(S))
    assert again.samples(5000, 4)[0] is not P and np.array_equal(again.samples(5000, 4)[0], P)
    for other in (S, again, _Surface(V, F)):
        assert hausdorff(Vo, Fo, V, F, surface_b=other, n_samples=5000, seed=3) == first
    assert S.samples(100, 4)[0].shape == (100, 3)                # another size: drawn anew


def _flat_grid(n, m):
    """A 1 x 1e-5 rectangle at z = 0 cut into 2 n m triangles (slivers for small m)."""
    xs, ys = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1e-5, m + 1), indexing="ij")
    V = np.c_[xs.ravel(), ys.ravel(), np.zeros(xs.size)]
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    k = (i * (m + 1) + j).ravel()
    F = np.r_[np.c_[k, k + m + 1, k + m + 2], np.c_[k, k + m + 2, k + 1]]
    return V, F.astype(np.int64)


def test_a_sliver_or_a_mesh_far_from_the_origin_keeps_the_true_value_in_its_bracket():
    """A review: two triangulations of one flat sliver rectangle (true distance 0) were bracketed
    [2.8e-8, 2.8e-8] (the barycentric coordinates of a sliver lost their digits), and a permuted
    copy of bunny moved 1e5 from the origin [1.3e-10, 1.3e-10] of the diagonal (points rebuilt in
    absolute coordinates), both 'certified'. The kernel now measures from the corners and to the
    plane, and both ends carry the queried points' rounding (`ROUND`)."""
    from harness.metrics._bvh_kernel import _seg2, _tri_dist2
    from harness.metrics.hausdorff import ROUND
    VA, FA = _flat_grid(8, 2)
    VB, FB = _flat_grid(5, 3)
    h = hausdorff(VA, FA, VB, FB, n_samples=200)
    assert h["hausdorff"] == 0.0 and h["hausdorff_upper"] < 1.01e-12 + 3 * ROUND and h["hausdorff_certified"], h
    # the diff review: a sliver in general orientation (0.5 long, 5e-9 wide, rotated at random);
    # A is it lifted by h along its normal plus a vertex over its inside lifted by 2h: H = 2h.
    # The plane distance from a sliver's rounded normal was 4.1e-11 short, 35,000 allowances.
    for seed in range(40):
        rng = np.random.default_rng(seed)
        Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        VS = np.array([[0, 0, 0], [1, 0, 0], [0.3, 1e-8, 0]]) @ Q.T * 0.5 + np.array([0.1, 0.2, 0.3])
        lift = 1e-4
        c = np.array([0.4, 0.3, 0.3]) @ VS + Q[:, 2] * 2 * lift
        VL = np.r_[VS + Q[:, 2] * lift, [c]]
        h = hausdorff(VL, np.array([[0, 1, 3], [1, 2, 3], [2, 0, 3]]), VS, np.array([[0, 1, 2]]), n_samples=200)
        assert h["hausdorff"] <= 2 * lift * (1 + 1e-12) <= h["hausdorff_upper"] * (1 + 2e-12), (seed, h)
    # a nearly flat triangle with coordinates near 700, a point 1.1e-6 from its edges: was 0.13 away
    V = np.array([[-638.1019436800368, -780.8370648190593, 348.72056527791347],
                  [-637.78394701434, -781.4099567673383, 348.37843678878835],
                  [-638.201257121118, -780.6581451104942, 348.82741532136384]])
    p = np.array([-638.0290485147207, -780.9683923430009, 348.6421378876526])
    edges = min(_seg2.py_func(*p, V, i, j) for i, j in ((0, 1), (1, 2), (2, 0)))
    assert np.sqrt(_tri_dist2.py_func(*p, V, 0, 1, 2)) <= np.sqrt(edges) + 1e-12
    m = datasets.load("bunny").clean
    rng = np.random.default_rng(0)
    perm = rng.permutation(len(m.V))
    Vp, Fp = m.V[perm], np.argsort(perm)[m.F][rng.permutation(len(m.F))]
    for off in (1e3, 1e5):
        o = np.array([off, -0.7 * off, 0.3 * off])
        h = hausdorff(Vp + o, Fp, m.V + o, m.F, n_samples=500)
        assert h["hausdorff"] == 0.0 and h["hausdorff_certified"], h
        assert h["hausdorff_upper"] <= 3 * ROUND * np.abs(m.V + o).max(), h


def test_a_triangle_with_exactly_collinear_corners_is_measured_by_its_edges():
    """The second diff review: corners (x, 3x, z) are exactly collinear, but their rounded
    differences' cross product is not 0, so the triangle took the double-double path, whose
    exact normal is 0: 0 / 0 raised ZeroDivisionError in hausdorff."""
    from harness.metrics._bvh_kernel import _seg2, _tri_dist2
    V = np.array([[float.fromhex("0x1.01ec693f1ac50p-9"), float.fromhex("0x1.82e29ddea8278p-8"),
                   -float.fromhex("0x1.94556bc2d0d6fp+0")],
                  [float.fromhex("0x1.9f12f84e5eb40p-10"), float.fromhex("0x1.374e3a3ac7070p-8"),
                   -float.fromhex("0x1.94556bc2d0d6fp+0")],
                  [float.fromhex("0x1.8133286474ee0p+0"), float.fromhex("0x1.20e65e4b57b28p+2"),
                   -float.fromhex("0x1.94556bc2d0d6fp+0")]])
    p = V.mean(0) + np.array([0.0, 0.0, 0.3])
    edges = min(_seg2.py_func(*p, V, i, j) for i, j in ((0, 1), (1, 2), (2, 0)))
    assert _tri_dist2(p[0], p[1], p[2], V, 0, 1, 2) == pytest.approx(edges, rel=1e-12)
    VA = np.r_[V, [V.mean(0) + [0.0, 0.0, 1.0]]]
    FA = np.array([[0, 1, 2], [0, 1, 3], [1, 2, 3]])
    h = hausdorff(VA, FA, VA + [0.0, 0.0, 0.01], FA, n_samples=100)       # a translated copy: H <= 0.01
    assert h["hausdorff"] <= 0.01 * (1 + 1e-12) and h["hausdorff"] <= h["hausdorff_upper"] < 0.011, h
