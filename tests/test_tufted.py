"""The tufted-cover Laplacian (`methods.scratch.tufted`) against robust-laplacian, and the heat
method on it against geometry-central's (potpourri3d, ``use_robust``), on manifold, open,
non-manifold and degenerate meshes."""
import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as sla

import methods
from harness import datasets

robust_laplacian = pytest.importorskip("robust_laplacian")


def _knight_with_fin():
    """The closed knight plus one triangle on an existing edge: a non-manifold edge of 3 faces."""
    m = datasets.load("knight").clean
    V, F = m.V.copy(), m.F.copy()
    e = F[0, :2]
    w = V[e].mean(0) + 5 * np.cross(V[e[1]] - V[e[0]], V[F[0, 2]] - V[e[0]])
    return np.vstack([V, w]), np.vstack([F, [e[0], e[1], len(V)]])


def _fan():
    """Four triangles on one edge, one of them oriented the other way, plus a free triangle."""
    V = np.array([[0, 0, 0], [0, 0, 1], [1, 0, 0.3], [0, 1, 0.5], [-1, -0.2, 0.4], [0.3, -1, 0.6]], float)
    return V, np.array([[0, 1, 2], [1, 0, 3], [0, 4, 1], [5, 1, 0], [2, 1, 3]])


def _meshes():
    out = {nm: (datasets.load(nm).clean.V, datasets.load(nm).clean.F) for nm in ("bunny", "camelhead", "knight")}
    out["plane_nondelaunay"] = datasets.plane_nondelaunay(300, 0)
    out["knight_fin"] = _knight_with_fin()
    out["fan"] = _fan()
    A, FA = datasets.icosphere(2)
    out["two_spheres_one_flipped"] = (np.vstack([A, A + [2, 0, 0]]), np.vstack([FA, FA[:, ::-1] + len(A)]))
    V, F = datasets.load("knight").clean.V.copy(), datasets.load("knight").clean.F
    V[F[10, 2]] = 0.5 * (V[F[10, 0]] + V[F[10, 1]]) + 1e-9        # a needle: mollification acts
    out["knight_needle"] = (V, F)
    return out


MESHES = _meshes()


@pytest.mark.parametrize("name", sorted(MESHES))
@pytest.mark.parametrize("mollify", [0.0, 1e-5])
def test_equals_robust_laplacian(name, mollify):
    V, F = MESHES[name]
    L, M = robust_laplacian.mesh_laplacian(np.ascontiguousarray(V, float), np.ascontiguousarray(F, np.int64),
                                           mollify_factor=mollify)
    r = methods.get("scratch.tufted")(V, F, mollify_factor=mollify)
    # an unmollified 1e-9 needle: its cotangents are ill-conditioned at about 1e-9 relative
    tol = 1e-8 if (name == "knight_needle" and not mollify) else 1e-10
    assert abs(-L - r.W).max() <= tol * abs(L).max()
    assert abs(M - r.M).max() <= tol * M.max()
    off = r.W - sp.diags(r.W.diagonal())
    assert off.min() >= -1e-12 * abs(L).max()                     # POS on every input


def test_cocircular_quads_change_the_mass_not_the_weights():
    """fandisk has cocircular quads, where either diagonal is Delaunay: W agrees, the total mass
    agrees, the per-vertex mass may follow the flip order."""
    m = datasets.load("fandisk").clean
    L, M = robust_laplacian.mesh_laplacian(m.V, m.F)
    r = methods.get("scratch.tufted")(m.V, m.F)
    assert abs(-L - r.W).max() <= 1e-7 * abs(L).max()
    assert r.M.sum() == pytest.approx(M.sum(), rel=1e-12)


def test_equals_intrinsic_delaunay_on_a_closed_manifold():
    """The cover of a closed manifold is two copies of it: the same flips, half the sum."""
    m = datasets.load("knight").clean
    a = methods.get("scratch.tufted")(m.V, m.F, mollify_factor=0.0)
    b = methods.get("scratch.intrinsic_delaunay")(m.V, m.F, mass="barycentric")
    assert abs(a.W - b.W).max() <= 1e-12 * abs(b.W).max()
    assert abs(a.M - b.M).max() <= 1e-14 * b.M.max()


def _geometry_central_heat(V, F, s):
    """The heat method with geometry-central's conventions on our tufted cover: t = (mean cover
    edge length)^2, lumped cover mass, Poisson matrix shifted by 1e-6 I, zero at the source."""
    from methods.scratch import geodesics as G
    n = len(V)
    l, F2, W, m, C, _ = G._operators(V, F, "tufted", "barycentric")
    t = l.mean() ** 2
    u = sla.spsolve((sp.diags(m) - t * W).tocsc(), np.eye(n)[s])
    b = G._unit_gradient_divergence(u, F2, l, C, n)
    phi = sla.spsolve((-W + 1e-6 * sp.eye(n)).tocsc(), b)
    phi -= phi[s]
    return -phi if phi.mean() < 0 else phi


@pytest.mark.parametrize("name", ["knight", "knight_fin", "camelhead"])
def test_heat_on_the_cover_equals_geometry_central(name):
    """potpourri3d's robust heat method is this computation (to 1e-10 of the largest distance);
    ``scratch.heat`` with the same (Neumann) boundary condition differs from it only by its
    unshifted Poisson solve and t from the input's mean edge length."""
    pytest.importorskip("potpourri3d")
    V, F = MESHES[name]
    ref = methods.get("potpourri3d.heat").func(V, F, sources=np.array([5]), robust=True).D[0]
    ours = _geometry_central_heat(V, F, 5)
    assert abs(ours - ref).max() <= 1e-10 * ref.max()
    d = methods.get("scratch.heat").func(V, F, sources=np.array([5]), laplacian="tufted", mass="barycentric",
                                                boundary="neumann").D[0]
    assert abs(d - ref).max() <= 5e-3 * ref.max()


def test_heat_tufted_equals_intrinsic_delaunay_on_a_closed_manifold():
    m = datasets.load("knight").clean
    kw = dict(sources=np.array([0, 9]), mass="barycentric")
    a = methods.get("scratch.heat").func(m.V, m.F, laplacian="tufted", **kw).D
    b = methods.get("scratch.heat").func(m.V, m.F, laplacian="intrinsic_delaunay", **kw).D
    assert abs(a - b).max() <= 1e-9 * b.max()
