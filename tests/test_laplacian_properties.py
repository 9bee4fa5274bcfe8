"""laplacian_properties on closed-form cases: Wardetzky et al. 2007's table on planar meshes.

Planar meshes are built here (seeded): a Delaunay triangulation of random points in the unit
square whose boundary edges all have opposite angles <= pi/2 (interior points kept at least
half a boundary spacing away from the sides, so no point lies in a boundary edge's diametral
disk: POS then holds for the cotangent weights on *every* edge, boundary included), and a
non-Delaunay copy with a set of independent convex interior edges flipped (opposite angles
then sum above pi).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.spatial import Delaunay

import methods
from harness.metrics.laplacian_properties import COLUMNS, laplacian_properties

MESH_DIR = Path(__file__).resolve().parents[1] / "harness" / "data" / "meshes"


def plane_delaunay(n_inner=250, k=8, seed=0):
    rng = np.random.default_rng(seed)
    s = np.arange(k) / k
    border = np.concatenate([np.c_[s, 0 * s], np.c_[1 + 0 * s, s], np.c_[1 - s, 1 + 0 * s],
                             np.c_[0 * s, 1 - s]])
    margin = 0.6 / k                      # > half the boundary spacing 1/k
    inner = rng.uniform(margin, 1 - margin, size=(n_inner, 2))
    P = np.concatenate([border, inner])
    F = Delaunay(P).simplices.astype(np.int64)
    V = np.c_[P, np.zeros(len(P))]
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])[:, 2]
    F[n < 0] = F[n < 0][:, [0, 2, 1]]
    return V, F


def plane_nondelaunay(seed=0, fraction=0.3):
    V, F = plane_delaunay(seed=seed)
    rng = np.random.default_rng(seed + 1)
    m = len(F)
    he = np.concatenate([F[:, [1, 2]], F[:, [2, 0]], F[:, [0, 1]]])
    opp = np.concatenate([F[:, 0], F[:, 1], F[:, 2]])
    fid = np.tile(np.arange(m), 3)
    key = np.sort(he, axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    same = np.all(key[order][1:] == key[order][:-1], axis=1)
    h1, h2 = order[:-1][same], order[1:][same]
    used = np.zeros(m, bool)
    P = V[:, :2]

    def orient(a, b, c):
        return (P[b, 0] - P[a, 0]) * (P[c, 1] - P[a, 1]) - (P[b, 1] - P[a, 1]) * (P[c, 0] - P[a, 0])

    flipped = 0
    for s in rng.permutation(len(h1))[: int(fraction * len(h1))]:   # test setup, not a hot path
        a, b = h1[s], h2[s]
        f1, f2 = fid[a], fid[b]
        p, q = he[a]
        x, y = opp[a], opp[b]
        if used[f1] or used[f2]:
            continue
        if orient(p, q, x) * orient(p, q, y) >= 0 or orient(x, y, p) * orient(x, y, q) >= 0:
            continue
        F[f1], F[f2] = [x, p, y], [y, q, x]
        used[f1] = used[f2] = True
        flipped += 1
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])[:, 2]
    F[n < 0] = F[n < 0][:, [0, 2, 1]]
    assert flipped > 10
    return V, F


@pytest.fixture(scope="module")
def planes():
    return {"D": plane_delaunay(), "N": plane_nondelaunay()}


def props(name, V, F, **params):
    r = methods.get(name)(V, F, **params)
    p = laplacian_properties(r.W, r.M, V, F)
    assert set(p) == set(COLUMNS)
    return p


def flags(p):
    return (p["SYM"], p["LOC"], p["LIN"], p["POS"])


def test_planes_are_what_they_claim(planes):
    igl = pytest.importorskip("igl")
    V, F = planes["D"]
    assert igl.is_intrinsic_delaunay(igl.edge_lengths(V, F), F).all()
    W = igl.cotmatrix(V, F)
    assert W[~np.eye(W.shape[0], dtype=bool)].min() >= -1e-12   # all weights >= 0
    V, F = planes["N"]
    assert not igl.is_intrinsic_delaunay(igl.edge_lengths(V, F), F).all()
    assert np.all(igl.doublearea(V, F) > 0)


@pytest.mark.parametrize("name", ["scratch.cotan", "libigl.cotan"])
def test_cotan_on_delaunay_plane_has_all_four(planes, name):
    p = props(name, *planes["D"])
    assert flags(p) == (True, True, True, True)
    assert p["psd"] is True and p["min_eig"] >= -1e-10
    assert p["sym_error"] <= 1e-14 and p["lin_error"] < 1e-13 and p["neg_weights"] == 0
    assert p["operator_symmetric"] is False        # M^-1 W with non-uniform Voronoi areas
    assert laplacian_properties(methods.get(name)(*planes["D"], mass="none").W, None,
                                *planes["D"])["operator_symmetric"] is True


def test_cotan_on_nondelaunay_plane_loses_pos_only(planes):
    p = props("scratch.cotan", *planes["N"])
    assert flags(p) == (True, True, True, False)
    assert p["neg_weights"] > 0.01
    assert p["psd"] is True        # the FEM stiffness matrix is PSD even with negative weights


def test_uniform_fails_lin_and_umbrella_is_not_pointwise_symmetric(planes):
    for key in "DN":
        V, F = planes[key]
        p = props("scratch.uniform", V, F)
        assert flags(p) == (True, True, False, True)
        assert p["lin_error"] > 1e-3 and p["sym_error"] == 0.0
        assert p["operator_symmetric"] is True and p["psd"] is True
        q = props("scratch.umbrella", V, F)
        assert flags(q) == flags(p) and q["lin_error"] == p["lin_error"]
        assert q["operator_symmetric"] is False     # D W with D = 1/N_i


def test_mean_value_is_lin_pos_loc_but_not_sym(planes):
    for key in "DN":
        p = props("scratch.mean_value", *planes[key])
        assert flags(p) == (False, True, True, True)
        assert p["sym_error"] > 0.1 and p["lin_error"] < 1e-12


def test_intrinsic_delaunay_is_pos_lin_sym_but_not_loc(planes):
    for name in ("scratch.intrinsic_delaunay", "libigl.intrinsic_delaunay"):
        p = props(name, *planes["N"])
        assert flags(p) == (True, False, True, True)
        assert p["loc_violations"] > 0 and p["psd"] is True
        # already Delaunay: no flips, so it is the cotangent Laplacian (local)
        assert flags(props(name, *planes["D"])) == (True, True, True, True)


def test_cotan_normalized_is_lin_not_sym(planes):
    p = props("scratch.cotan_normalized", *planes["D"])
    assert flags(p) == (False, True, True, True)


def test_lin_is_rotation_invariant_and_blank_off_plane(planes):
    V, F = planes["N"]
    c, s = np.cos(0.7), np.sin(0.7)
    R = np.array([[1, 0, 0], [0, c, -s], [0, s, c]]) @ np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    Vr = V @ R.T + [3.0, -2.0, 1.0]
    p0 = props("scratch.uniform", V, F)
    p1 = props("scratch.uniform", Vr, F)
    # |W X| is invariant; the normalising bbox diagonal (world axes, CONTRACT) is not
    diag = lambda P: np.linalg.norm(P.max(0) - P.min(0))
    assert p1["lin_error"] * diag(Vr) == pytest.approx(p0["lin_error"] * diag(V), rel=1e-9)
    assert props("scratch.cotan", Vr, F)["LIN"] is True
    Vb = V.copy()
    Vb[:, 2] = 0.1 * np.sin(5 * V[:, 0])             # bent: not planar
    pb = props("scratch.cotan", Vb, F)
    assert pb["lin_error"] is None and pb["LIN"] is None
    # forcing planar=False blanks it too
    r = methods.get("scratch.cotan")(V, F)
    assert laplacian_properties(r.W, r.M, V, F, planar=False)["LIN"] is None


def test_min_eig_closed_form():
    """Small matrices with known spectra: path graph (PSD, eigenvalue 0) and a path whose
    middle edge has a negative weight (one negative eigenvalue), checked against a dense
    eigensolver to 1e-8."""
    n = 40
    V = np.c_[np.arange(n, dtype=float), np.zeros(n), np.zeros(n)]
    F = np.c_[np.arange(n - 2), np.arange(1, n - 1), np.arange(2, n)]   # collinear: no area
    w = np.ones(n - 1)
    A = sp.diags([w, w], [1, -1], shape=(n, n)).tocsr()
    W = A - sp.diags(np.asarray(A.sum(1)).ravel())
    p = laplacian_properties(W, None, V, F, planar=False)
    assert p["psd"] is True and abs(p["min_eig"]) < 1e-12
    w[n // 2] = -0.5
    A = sp.diags([w, w], [1, -1], shape=(n, n)).tocsr()
    W = A - sp.diags(np.asarray(A.sum(1)).ravel())
    ev = np.linalg.eigvalsh(-W.toarray())
    p = laplacian_properties(W, None, V, F, planar=False)
    assert p["psd"] is False and p["POS"] is False
    assert p["min_eig"] == pytest.approx(ev.min() / np.abs(ev).max(), rel=1e-8)


def test_min_eig_when_lanczos_stalls_on_the_largest_eigenvalue():
    """A symmetric, indefinite perturbation of the cotan W of a 42-vertex icosphere (an outside
    review's adversarial case; rows sum to zero) whose two largest eigenvalues nearly tie
    (4.82670, 4.82678): ARPACK's 8-vector Lanczos does not converge on ``lam_max``, and its
    Gershgorin bound (6.86) was used instead, printing min_eig -0.605 where it is -0.8595. Now
    a larger Krylov space (or a dense solver) gives it, or min_eig is blank."""
    z = np.load(Path(__file__).parent / "data" / "arpack_lm_stall.npz")
    n = len(z["V"])
    W = sp.csr_matrix((z["data"], z["indices"], z["indptr"]), shape=(n, n))
    ev = np.linalg.eigvalsh(-W.toarray())
    p = laplacian_properties(W, None, z["V"], z["F"])
    assert p["psd"] is False
    assert p["min_eig"] == pytest.approx(ev.min() / np.abs(ev).max(), rel=1e-8)


def test_bunny_spectrum_against_dense():
    """On knight (1k faces): min_eig of the (symmetric) cotan W equals the dense eigvalsh value; for the
    non-symmetric mean value W, psd follows the real parts of -W's dense eigenvalues."""
    igl = pytest.importorskip("igl")
    V, F = igl.read_triangle_mesh(str(MESH_DIR / "decimated-knight.off"))
    W = methods.get("scratch.cotan")(V, F).W
    ev = np.linalg.eigvalsh(-W.toarray())
    p = laplacian_properties(W, None, V, F)
    assert p["min_eig"] == pytest.approx(ev.min() / np.abs(ev).max(), rel=1e-6, abs=1e-12)
    assert p["psd"] is bool(ev.min() >= -1e-10 * np.abs(ev).max())
    W = methods.get("scratch.mean_value")(V, F).W
    ev = np.linalg.eigvals(-W.toarray())
    p = laplacian_properties(W, None, V, F)
    assert p["psd"] is bool(ev.real.min() >= -1e-10 * np.abs(ev).max()) is True
    S = -(W + W.T).toarray() / 2                  # the symmetric part alone is indefinite here
    assert np.linalg.eigvalsh(S).min() < -1e-6 * np.abs(ev).max()


def test_nonfinite_and_isolated_do_not_crash():
    """libigl on a zero-area face gives NaN/inf: value columns blank, pattern columns kept.
    Isolated vertices and a zero matrix are measured without errors."""
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0], [7, 7, 7]], float)
    F = np.array([[0, 1, 2], [0, 1, 3]], np.int64)          # second face is flat
    W = sp.csr_matrix(np.array([[np.nan, 1, 1, np.inf, 0], [1, -2, 1, 0, 0],
                                [1, 1, -2, 0, 0], [np.inf, 0, 0, -np.inf, 0], [0] * 5]))
    p = laplacian_properties(W, None, V, F)
    assert p["nnz"] == 12 and p["LOC"] is True
    assert p["sym_error"] is None and p["SYM"] is None and p["psd"] is None and p["POS"] is None
    p = laplacian_properties(sp.csr_matrix((5, 5)), None, V, F)
    assert p["SYM"] is True and p["nnz"] == 0
    r = methods.get("scratch.cotan")(V, F)
    p = laplacian_properties(r.W, r.M, V, F)
    assert p["psd"] is True and p["LOC"] is True and p["operator_symmetric"] is not None


def test_properties_on_a_real_mesh_have_expected_flags():
    """bunny (closed): cotan SYM/LOC and PSD, LIN blank, some negative weights; robust and
    intrinsic Delaunay POS but not LOC."""
    igl = pytest.importorskip("igl")
    V, F = igl.read_triangle_mesh(str(MESH_DIR / "bunny.off"))
    p = props("scratch.cotan", V, F)
    assert (p["SYM"], p["LOC"], p["LIN"], p["psd"]) == (True, True, None, True)
    assert 0 < p["neg_weights"] < 0.5
    q = props("scratch.intrinsic_delaunay", V, F)
    assert (q["SYM"], q["LOC"], q["POS"], q["psd"]) == (True, False, True, True)


def test_neg_weights_ignores_explicit_zeros():
    """fandisk has exactly-zero cotangent weights: libigl stores them, scipy drops them; the
    property values must not depend on that (equal for scratch and libigl W)."""
    igl = pytest.importorskip("igl")
    V, F = igl.read_triangle_mesh(str(MESH_DIR / "fandisk.obj"))
    a = laplacian_properties(methods.get("scratch.cotan")(V, F).W, None, V, F)
    b = laplacian_properties(igl.cotmatrix(V, F), None, V, F)
    for k in ("neg_weights", "loc_violations", "SYM", "LOC", "POS", "psd"):   # nnz is storage
        assert a[k] == b[k], k          # storage differs (explicit zeros), properties may not
    assert a["min_eig"] == pytest.approx(b["min_eig"], abs=1e-12)


def test_uniform_is_linear_precise_on_a_regular_grid():
    """The uniform Laplacian fails LIN only on irregular meshes: on a regular grid (every
    interior one-ring point-symmetric) sum_j (x_j - x_i) = 0 exactly."""
    k = 12
    x, y = np.meshgrid(np.arange(k + 1.0), np.arange(k + 1.0), indexing="ij")
    V = np.c_[x.ravel(), y.ravel(), np.zeros(x.size)]
    idx = np.arange((k + 1) ** 2).reshape(k + 1, k + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    F = np.r_[np.c_[a, b, c], np.c_[a, c, d]].astype(np.int64)
    p = props("scratch.uniform", V, F)
    assert flags(p) == (True, True, True, True) and p["lin_error"] == 0.0


def test_large_mesh_psd_certificate_without_factorisation(monkeypatch):
    """Above EIG_MAX_N the PSD column comes from the exact certificates (diagonal dominance,
    triangle split), never a guess: a graph Laplacian and a cotangent Laplacian with negative
    weights are certified, an indefinite matrix is left blank."""
    import harness.metrics.laplacian_properties as lp
    from harness.datasets import icosphere, plane_nondelaunay
    from methods.scratch.operators import cotan_weights, uniform_weights
    monkeypatch.setattr(lp, "EIG_MAX_N", 10)
    monkeypatch.setattr(lp, "_ldlt", None)                       # never reached
    V, F = icosphere(2)
    out = lp.laplacian_properties(uniform_weights(F, len(V)), None, V, F)
    assert out["psd"] is True and out["min_eig"] == 0.0          # graph Laplacian: certified
    V, F = plane_nondelaunay(200, 0, 0.3)
    W = cotan_weights(V, F)
    out = lp.laplacian_properties(W, None, V, F)
    assert out["POS"] is False and out["psd"] is True and out["min_eig"] == 0.0   # triangle split
    W = W.tolil()
    W[3, 3] += 1.0                                               # -W gains a negative eigenvalue
    out = lp.laplacian_properties(W.tocsr(), None, V, F)
    assert out["psd"] is None and out["min_eig"] is None         # not measured


def _certified(W, V, F):
    import harness.metrics.laplacian_properties as lp
    S = (-(W + W.T) * 0.5).tocsr()
    S.eliminate_zeros()
    return lp._certificate(S, V, F)


@pytest.mark.parametrize("mesh", ["bunny", "knight", "camelhead", "woody", "fandisk"])
@pytest.mark.parametrize("name", ["scratch.cotan", "libigl.cotan", "scratch.cotan_normalized", "scratch.uniform",
                                  "scratch.intrinsic_delaunay", "robust.tufted"])
def test_certificates_agree_with_the_factorisation(monkeypatch, name, mesh):
    """On closed, open and obtuse meshes and on a noisy copy, the cheap certificates give the
    (psd, min_eig) the LDL^T inertia and shift-invert Lanczos give, within min_eig's tolerance
    (1e-10); the cotangent Laplacians (negative weights) are certified by the triangle split
    (cotan_normalized through its symmetric S = D W); the intrinsic ones (edges that are not the
    mesh's) by dominance where their weights are positive, else by the factorisation."""
    import harness.metrics.laplacian_properties as lp
    from harness import datasets
    from harness.noise import apply_noise
    m = datasets.load(mesh).clean
    method = methods.get(name)
    if method.unavailable_reason():
        pytest.skip(method.unavailable_reason())
    noisy = apply_noise(m.V, m.F, "gaussian_normal", 0.5, 0, mesh_key=mesh)
    for V in (m.V, noisy):
        W = method(V, m.F).W
        fast = laplacian_properties(W, None, V, m.F)
        with monkeypatch.context() as mp:
            mp.setattr(lp, "_certificate", lambda S, V, F: (None, False))
            slow = laplacian_properties(W, None, V, m.F)
        assert fast["psd"] is slow["psd"] is True
        assert abs(fast["min_eig"] - slow["min_eig"]) <= 1e-10 and abs(slow["min_eig"]) <= 1e-10
        if name in ("scratch.cotan", "libigl.cotan", "scratch.uniform"):     # symmetric, on the mesh's edges
            assert _certified(W, V, m.F) == (True, True) and fast["min_eig"] == 0.0


@pytest.mark.parametrize("scale", [1e-300, 1e-150, 1.0, 1e150, 1e155, 1e300])
def test_triangle_split_at_extreme_scales(scale):
    """A triangle whose weights (1, 1, -0.6) make it indefinite is never certified, however large
    the weights (products once overflowed to NaN, and NaN was read as no negative part); a cotangent
    Laplacian is certified at any scale (the matrix is scaled by a power of two first)."""
    from harness.datasets import plane_nondelaunay
    from methods.scratch.operators import cotan_weights
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]])
    F = np.array([[0, 1, 2]], np.int64)
    A = sp.csr_matrix((np.r_[1, 1, -0.6, 1, 1, -0.6] * scale, ([0, 1, 2, 1, 2, 0], [1, 2, 0, 0, 1, 2])), shape=(3, 3))
    W = (A - sp.diags(np.asarray(A.sum(1)).ravel())).tocsr()
    assert _certified(W, V, F)[0] is None
    p = laplacian_properties(W, None, V, F)
    assert p["psd"] is False and p["min_eig"] == pytest.approx(-1 / 15, rel=1e-9)
    V, F = plane_nondelaunay(60, 1, 0.4)                       # negative weights: dominance does not apply
    assert _certified(cotan_weights(V, F) * scale, V, F) == (True, True)


def test_triangle_split_never_certifies_an_indefinite_matrix():
    """Cotangent weights of small meshes with random symmetric perturbations (edge weights
    made negative, diagonal shifts from 1e-13 to 1e-3 of the scale): whenever the triangle
    split says psd, the dense smallest eigenvalue is >= -1e-10 * the largest; and it does
    certify most unperturbed and mildly perturbed cases (the test can fail both ways)."""
    from harness.datasets import icosphere, plane_nondelaunay
    from methods.scratch.operators import cotan_weights
    rng = np.random.default_rng(7)
    meshes = [icosphere(1), plane_nondelaunay(60, 1, 0.4), plane_nondelaunay(60, 2, 0.6)]
    certified = indefinite = 0
    for trial in range(300):
        V, F = meshes[trial % 3]
        V = V + rng.normal(scale=0.02, size=V.shape) * (trial % 2)
        W = cotan_weights(V, F).tolil()
        n = len(V)
        kind = trial % 4
        if kind == 1:                                             # one edge made more negative
            i, j = F[rng.integers(len(F)), :2]
            w = rng.uniform(0.0, 3.0) * abs(W[i, j]) + 1e-3
            W[i, j] -= w
            W[j, i] -= w
            W[i, i] += w
            W[j, j] += w
        elif kind == 2:                                           # diagonal shift
            d = 10.0 ** rng.uniform(-13, -3) * abs(W).max()
            W = W + d * sp.identity(n, format="lil")          # S - d I
        W = W.tocsr()
        psd, _ = _certified(W, V, F)
        ev = np.linalg.eigvalsh(-((W + W.T) / 2).toarray())
        truly = ev.min() >= -1e-10 * np.abs(ev).max()
        indefinite += not truly
        if psd:
            certified += 1
            assert truly, (trial, ev.min() / np.abs(ev).max())
    assert certified >= 150 and indefinite >= 60


@pytest.mark.parametrize("name", ["scratch.mean_value", "scratch.cotan_normalized"])
@pytest.mark.parametrize("mesh", ["knight", "woody"])
def test_psd_of_nonsymmetric_operators_is_the_real_part_of_their_spectrum(name, mesh):
    """Non-symmetric W: psd means every eigenvalue of -W has a non-negative real part, checked
    against a dense eigendecomposition; the symmetric part alone would not decide it."""
    import methods
    from harness import datasets
    m = datasets.load(mesh).clean
    r = methods.get(name)(m.V, m.F)
    props = laplacian_properties(r.W, r.M, m.V, m.F)
    ev = np.linalg.eigvals(-r.W.toarray())
    scale = np.abs(ev).max()
    assert not props["SYM"]
    assert props["psd"] is True and ev.real.min() >= -1e-10 * scale
    assert props["min_eig"] is not None and abs(props["min_eig"]) <= 1e-9


def test_nonsymmetric_operator_with_a_negative_real_eigenvalue_is_not_psd():
    """W = D^-1 S with S indefinite: symmetrizable, so decided exactly (False)."""
    import scipy.sparse as sp
    S = np.array([[-1.0, 2.0, 0.0], [2.0, -1.0, 0.5], [0.0, 0.5, -1.0]])       # -S has a negative eigenvalue
    d = np.array([1.0, 3.0, 0.5])
    W = sp.csr_matrix(np.diag(1 / d) @ S)
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    F = np.array([[0, 1, 2]])
    props = laplacian_properties(W, None, V, F)
    assert np.linalg.eigvals(-W.toarray()).real.min() < 0
    assert props["SYM"] is False and props["psd"] is False


def test_mesh_terms_are_computed_once_per_mesh_and_change_nothing(monkeypatch):
    """The edge keys of F go into the ``mesh`` dict on the first call and are reused by the
    next Laplacians of the same mesh; every property equals a call without the dict (open
    camelhead, with cotangent, uniform and the non-symmetric normalised cotangent)."""
    from harness import datasets
    from harness.metrics import laplacian_properties as lp
    m = datasets.load("camelhead").clean
    calls = []
    real = lp._edge_keys
    monkeypatch.setattr(lp, "_edge_keys", lambda F, n: calls.append(n) or real(F, n))
    shared = {}
    for name in ("scratch.cotan", "scratch.uniform", "scratch.cotan_normalized"):
        r = methods.get(name)(m.V, m.F)
        got = lp.laplacian_properties(r.W, r.M, m.V, m.F, mesh=shared)
        assert got == lp.laplacian_properties(r.W, r.M, m.V, m.F), name
    assert len(calls) == 1 + 3 and "edge_keys" in shared      # once for the shared dict, once per plain call
