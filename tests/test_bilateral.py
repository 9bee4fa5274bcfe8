"""scratch.bilateral against an independent implementation of Zheng et al. 2011's local scheme,
written here from the paper and Zhang et al. 2015's reimplementation (GuidedDenoising's
``BilateralNormalFilteringForMeshDenoising``): neighbourhood = faces sharing a vertex with the
centre face, the centre face excluded; ``sigma_c`` = mean centroid distance over (face,
edge-adjacent face) pairs; weights ``A_j W_s W_r``; 20 Jacobi normal passes on fixed areas and
centroids; then 10 Sun et al. 2007 vertex updates with boundary vertices fixed.

The reference builds neighbour lists with Python sets per face and vertex (like OpenMesh's
circulators) and iterates on padded arrays, so it shares no code with the method."""
from pathlib import Path

import igl
import numpy as np
import pytest

import methods

MESHES = Path(__file__).resolve().parents[1] / "harness" / "data" / "meshes"


def load(name):
    V, F = igl.read_triangle_mesh(str(MESHES / name))
    return np.asarray(V, np.float64), np.asarray(F, np.int64)


def padded(lists):
    k = max(len(x) for x in lists)
    idx = np.zeros((len(lists), k), np.int64)
    ok = np.zeros((len(lists), k), bool)
    for i, x in enumerate(lists):
        idx[i, :len(x)] = sorted(x)
        ok[i, :len(x)] = True
    return idx, ok


def reference_bilateral(V, F, sigma_r=0.35, multiple=1.0, normal_iter=20, vertex_iter=10):
    n, m = len(V), len(F)
    vf = [[] for _ in range(n)]
    for f, (a, b, c) in enumerate(F.tolist()):
        vf[a].append(f), vf[b].append(f), vf[c].append(f)
    edge_faces = {}
    for f, tri in enumerate(F.tolist()):
        for k in range(3):
            e = tuple(sorted((tri[k], tri[(k + 1) % 3])))
            edge_faces.setdefault(e, []).append(f)
    nbr = []                                                # faces sharing a vertex, minus self
    for f, tri in enumerate(F.tolist()):
        s = set()
        for v in tri:
            s.update(vf[v])
        s.discard(f)
        nbr.append(s)
    adj = [set() for _ in range(m)]                         # faces sharing an edge
    for fs in edge_faces.values():
        for f in fs:
            adj[f].update(g for g in fs if g != f)
    boundary = np.zeros(n, bool)
    for e, fs in edge_faces.items():
        if len(fs) == 1:
            boundary[list(e)] = True

    P = V[F]
    cen = P.mean(axis=1)
    cr = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    area = 0.5 * np.linalg.norm(cr, axis=1)
    normal = cr / np.linalg.norm(cr, axis=1, keepdims=True)
    pairs = [(i, j) for i in range(m) for j in adj[i]]
    pi, pj = np.array(pairs).T
    sigma_c = multiple * np.linalg.norm(cen[pi] - cen[pj], axis=1).mean()

    J, ok = padded(nbr)
    ws = np.where(ok, area[J] * np.exp(-0.5 * np.sum((cen[:, None] - cen[J]) ** 2, -1) / sigma_c ** 2), 0.0)
    prev = normal
    for _ in range(normal_iter):
        wr = np.exp(-0.5 * np.sum((prev[:, None] - prev[J]) ** 2, -1) / sigma_r ** 2)
        t = np.einsum("ik,ikd->id", ws * wr, prev[J])
        prev = t / np.linalg.norm(t, axis=1, keepdims=True)

    VF, vok = padded(vf)
    X = V.copy()
    for _ in range(vertex_iter):
        c = X[F].mean(axis=1)
        nf = prev[VF]                                        # (n, k, 3)
        d = np.einsum("ikd,ikd->ik", nf, c[VF] - X[:, None])
        move = np.einsum("ik,ikd->id", np.where(vok, d, 0.0), nf) / vok.sum(1)[:, None]
        move[boundary] = 0.0
        X = X + move
    return X


def mean_angle_error(X, F, C):
    from harness.core.geometry import face_normals
    a, b = face_normals(X, F), face_normals(C, F)
    return float(np.degrees(np.arccos(np.clip((a * b).sum(1), -1, 1))).mean())


@pytest.mark.parametrize("pair", ["Fandisk0.3", "SharpSphere0.3"])
def test_bilateral_matches_independent_reference(pair):
    """Same vertices to 1e-12 of the diagonal and the same mean angle error (well within the
    required 1%) on the published Zhang et al. 2015 pairs. Measured mean angle error (degrees):
    Fandisk0.3 input 28.4 -> 3.49, SharpSphere0.3 input 33.0 -> 8.29 (printed with -s)."""
    N, F = load(f"denoise/{pair}/Noisy.obj")
    C, F2 = load(f"denoise/{pair}/Original.obj")
    assert np.array_equal(F, F2)
    ref = reference_bilateral(N, F)
    out = methods.get("scratch.bilateral")(N, F).V
    diag = np.linalg.norm(C.max(0) - C.min(0))
    assert np.abs(out - ref).max() <= 1e-12 * diag
    e_ref, e_out, e_in = mean_angle_error(ref, F, C), mean_angle_error(out, F, C), mean_angle_error(N, F, C)
    print(pair, "input", e_in, "reference", e_ref, "scratch.bilateral", e_out)
    assert abs(e_out - e_ref) <= 0.01 * e_ref
    assert e_out < 0.3 * e_in


def test_bilateral_open_mesh_keeps_boundary():
    """With the reference's fixed boundary an open mesh's boundary vertices do not move; with
    ``boundary: free`` they do; the edge neighbourhood is a strict subset and gives a
    different result."""
    from harness.core.geometry import boundary_vertices
    V, F = load("camelhead.off")
    rng = np.random.default_rng(0)
    N = V + rng.normal(scale=2e-3 * np.linalg.norm(V.max(0) - V.min(0)), size=V.shape)
    b = boundary_vertices(F, len(V))
    out = methods.get("scratch.bilateral")(N, F).V
    assert np.array_equal(out[b], N[b]) and not np.allclose(out[~b], N[~b])
    free = methods.get("scratch.bilateral")(N, F, boundary="free").V
    assert not np.allclose(free[b], N[b])
    edge = methods.get("scratch.bilateral")(N, F, neighbourhood="edge").V
    assert np.abs(edge - out).max() > 1e-6


def test_bilateral_widths_are_named_by_what_they_weigh():
    """The paper's sigma_s is the width on normal differences; the image bilateral filter's
    convention reads sigma_s as spatial, and the parameters were once named that way round
    (``sigma_r`` normal, ``sigma_s`` spatial): a reader who gave the paper's sigma_s = 0.35 got a
    spatial width of 0.35 sigma_c (Fandisk0.3: normal error 3.5 -> 11.1 degrees, an outside
    review). The widths are now ``normal_sigma`` and ``spatial_multiple``; non-default values
    match the independent reference given the same widths, and ``sigma_s`` is refused."""
    N, F = load("denoise/Fandisk0.3/Noisy.obj")
    m = methods.get("scratch.bilateral")
    ref = reference_bilateral(N, F, sigma_r=0.5, multiple=2.0, normal_iter=5, vertex_iter=5)
    out = m(N, F, normal_sigma=0.5, spatial_multiple=2.0, normal_iterations=5, vertex_iterations=5).V
    assert np.abs(out - ref).max() <= 1e-12 * np.linalg.norm(N.max(0) - N.min(0))
    assert any("unknown parameter 'sigma_s'" in p for p in m.param_problems({"sigma_s": 0.35}))
