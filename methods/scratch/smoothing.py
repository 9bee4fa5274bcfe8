"""Laplacian smoothing from scratch: explicit and implicit diffusion, Taubin, screened Poisson.

All diffusion methods here run on one operator family, chosen by the ``weights`` parameter
always written as ``L = M^-1 W`` with a *symmetric* ``W`` in libigl's sign
convention (off-diagonal weights positive, rows summing to zero) and a diagonal ``M``:

``uniform``
    umbrella operator: ``W = A - diag(deg)`` (A the 0/1 vertex adjacency), ``M = diag(deg)``,
    so ``(L X)_i = mean of the neighbours - x_i`` (Taubin 1995).
``cotan``
    row-normalized cotangent weights: ``W`` = the cotangent matrix (``igl.cotmatrix``),
    ``M = diag(sum_{j != i} W_ij)``, so ``(L X)_i`` = cotangent-weighted neighbour mean - x_i
    (MeshLab's cotangent Laplacian smoothing normalizes this way; Desbrun et al. 1999 normalize
    the umbrella and their edge-length "scale-dependent" operator, and divide the cotangent one by
    the one-ring area).
``cotan_area``
    the Laplace-Beltrami operator: ``W`` = cotangent matrix, ``M`` = mixed Voronoi mass
    (Meyer et al. 2003; ``igl.massmatrix(..., VORONOI)``), as `libigl.implicit` (libigl's own
    tutorial uses the barycentric mass); Desbrun et al. 1999's curvature flow divides by the
    one-ring area instead, a multiple of the barycentric mass (Voronoi and barycentric masses at
    step 1: about 1e-3 of the diagonal apart on noisy bunny and camelhead, 4e-3 on an obtuse
    plane).

Time step (the shared, dimensionless ``step`` parameter): ``uniform`` and ``cotan`` are
row-normalized (``L`` has eigenvalues in ``[-2, 0]`` for non-negative weights), so the time
step is ``h = step``. ``cotan_area`` is area-normalized (``L`` has units 1/length^2), so the
time step is ``h = step * lbar^2`` with ``lbar`` the mean edge length of the *input* mesh;
that makes one ``step`` value mean the same amount of smoothing on meshes of any scale and
resolution. For an equilateral (valence-6) triangulation the forward-Euler stability limit
is ``step < 1/3`` for ``cotan_area`` (largest eigenvalue 6 / l^2) and ``step < 4/3`` for
``uniform`` (spectrum [-1.5, 0]; measured on the procedural torus: 1.3 stable, 1.4
diverges); ``step < 1`` is the bound for any mesh from the general [-2, 0] spectrum.

Degenerate rows: a vertex whose mass is zero (isolated vertex; vertex only in zero-area
faces) has an all-zero ``W`` row; its mass is set to 1 so it simply stays put. With ``cotan``
weights a vertex whose off-diagonal cotangent sum is <= 0 (negative weights dominating, only
on very bad triangles) is normalized by the sum of absolute weights instead.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from methods import Param, SmoothingResult, register
from harness.core.geometry import boundary_vertices, edge_face_counts, mean_edge_length
from harness.core.solvers import backward_euler
from methods.vocabulary import boundary_rule_param, solver_param
from methods.scratch.laplacians import FAST_MIN_FACES
from methods.scratch.operators import cotan_laplacian, cotan_weights, uniform_weights, voronoi_areas

WEIGHTS = ("uniform", "cotan", "cotan_area")

_WEIGHTS_DOC = ("operator L = M^-1 W: uniform (umbrella, M = diag(deg)), cotan (cotangent W, "
                "M = diag of its off-diagonal row sums), cotan_area (cotangent W, Voronoi mass)")
_STEP_DOC = ("dimensionless step: time step h = step for uniform/cotan, "
             "h = step * (mean edge length)^2 for cotan_area")


def smoothing_operator(V: np.ndarray, F: np.ndarray, weights: str = "cotan_area"
                       ) -> tuple[sp.csr_matrix, np.ndarray]:
    """The pair ``(W, m)`` defining ``L = diag(m)^-1 W`` for the given ``weights`` choice.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    weights : {"uniform", "cotan", "cotan_area"}
        See the module docstring for the definitions.

    Returns
    -------
    W : (n, n) scipy.sparse.csr_matrix
        Symmetric, rows sum to zero, libigl sign convention (negative semi-definite).
    m : (n,) float64
        Strictly positive diagonal of the mass matrix ``M``.
    """
    n = V.shape[0]
    if weights == "uniform":
        W = uniform_weights(F, n)
        m = -W.diagonal()
    elif weights == "cotan":
        W = cotan_weights(V, F)
        m = -W.diagonal()
        bad = m <= 0
        if bad.any():
            absW = abs(W)
            absW.setdiag(0)
            m = np.where(bad, np.asarray(absW.sum(axis=1)).ravel(), m)
    elif weights == "cotan_area":
        if F.shape[0] >= FAST_MIN_FACES and 6 * F.shape[0] + n < 2**31 - 1:   # one compiled pass, W and M
            W, M = cotan_laplacian(V, F, "voronoi")
            m = M.diagonal()
        else:
            W = cotan_weights(V, F)
            m = voronoi_areas(V, F)
    else:
        raise ValueError(f"unknown weights {weights!r}; expected one of {WEIGHTS}")
    m = np.asarray(m, dtype=np.float64)
    m = np.where((m > 0) & np.isfinite(m), m, 1.0)
    return W.tocsr(), m


def time_step(V: np.ndarray, F: np.ndarray, step: float, weights: str) -> float:
    """Physical time step ``h``: ``step`` (row-normalized) or ``step * lbar^2`` (cotan_area)."""
    if weights == "cotan_area":
        return float(step) * mean_edge_length(V, F) ** 2
    return float(step)


def curve_rows(F: np.ndarray, n: int) -> tuple[np.ndarray, sp.csr_matrix, np.ndarray]:
    """The boundary-curve rule: ``(mask, Wb, mb)`` for the boundary vertices.

    For a vertex ``i`` on ``n_b`` boundary edges (edges with one face) ``Wb[i, j] = 1/2`` per
    boundary-edge neighbour ``j``, ``Wb[i, i] = -n_b / 2`` and ``mb[i] = (1 + n_b) / 2``: the
    vertex is counted once in its own boundary average, with the weight a boundary edge gets
    (half an interior edge's, since weights count incident faces), so
    ``(Wb x)_i / mb_i = (x_i + sum_b x_j) / (1 + n_b) - x_i``. This is VCGLib's
    ``AccumulateLaplacianInfo`` boundary reset: MeshLab's Taubin step is
    ``x += lambda (Wb x / mb)`` there, and its classic Laplacian
    ``x' = (2 x + sum_b x_j) / (n_b + 2)`` is ``x + mb / (mb + 1/2) (Wb x / mb)``, the
    ``self_weight = 0.5`` update. Rows of non-boundary vertices are zero (mb 1).
    """
    E, counts = edge_face_counts(F)
    B = E[counts == 1]
    mask = np.zeros(n, bool)
    mask[B.ravel()] = True
    A = sp.coo_matrix((np.full(2 * len(B), 0.5), (np.r_[B[:, 0], B[:, 1]], np.r_[B[:, 1], B[:, 0]])),
                      shape=(n, n)).tocsr()
    nb2 = np.asarray(A.sum(axis=1)).ravel()
    Wb = (A - sp.diags(nb2)).tocsr()
    mb = np.where(mask, 0.5 + nb2, 1.0)
    return mask, Wb, mb


def apply_boundary_rule(W: sp.csr_matrix, m: np.ndarray, F: np.ndarray, rule: str,
                        unit: float = 1.0) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray | None]:
    """``(W, m, fixed)`` with the boundary rule applied (`methods.vocabulary.boundary_rule_param`).

    ``curve`` replaces the boundary rows of ``W`` and entries of ``m`` by `curve_rows`, the mass
    multiplied by ``unit`` (``lbar^2`` for area-weighted operators, so ``h / m`` keeps its
    scale); ``fixed`` returns the boundary mask as ``fixed`` (their steps are zeroed by the
    caller); ``free`` changes nothing.
    """
    n = W.shape[0]
    if rule == "fixed":
        return W, m, boundary_vertices(F, n)
    if rule == "curve":
        mask, Wb, mb = curve_rows(F, n)
        keep = sp.diags((~mask).astype(np.float64))
        W = (keep @ W + sp.diags(mask.astype(np.float64)) @ Wb).tocsr()
        m = np.where(mask, mb * unit, m)
    return W, m, None


def _finite(X: np.ndarray) -> bool:
    return bool(np.isfinite(X).all())


@register("scratch.explicit", task="smoothing", library="scratch",
          params={"weights": Param("weights", "uniform", choices=WEIGHTS, doc=_WEIGHTS_DOC),
                  "step": Param("step", 0.25, "float", low=0.0, doc=_STEP_DOC),
                  "iterations": Param("iterations", 10, "int", low=0, high=100000,
                                      doc="number of forward-Euler steps"),
                  "self_weight": Param("self_weight", 0.0, "float", low=0.0,
                                       doc="weight of the vertex itself in the neighbour "
                                           "average, in units of M (of lbar^2 for cotan_area; "
                                           "MeshLab's Laplacian: 0.5)"),
                  "boundary": boundary_rule_param(),
                  "reassemble": Param("reassemble", False, "bool",
                                      doc="rebuild the operator from the current positions "
                                          "every step (MeshLab's cotangent Laplacian does)")})
def explicit(V, F, *, weights="uniform", step=0.25, iterations=10, self_weight=0.0,
             boundary="free", reassemble=False):
    """Explicit (forward Euler) Laplacian smoothing ``X <- X + h L X``.

    Parameters
    ----------
    V : (n, 3) float64
        Vertex positions.
    F : (m, 3) int64
        Triangles (unchanged).
    weights : {"uniform", "cotan", "cotan_area"}
        Operator ``L = M^-1 W`` (module docstring); built once from the input positions.
    step : float
        Dimensionless step; ``h = step`` for uniform/cotan, ``h = step * lbar^2`` for
        cotan_area (``lbar`` = mean input edge length).
    iterations : int
        Number of steps.
    self_weight : float
        ``s >= 0``: the step of vertex ``i`` is scaled by ``m_i / (m_i + s u)``, ``u`` the
        unit of ``m`` (``lbar^2`` for cotan_area, whose ``m`` is an area; 1 otherwise), so a
        setting means the same at any scale of the mesh. With uniform or cotan weights and
        ``step = 1`` the update is ``x' = (s x + sum_j W_ij x_j) / (s + m_i)``: the vertex
        itself joins the weighted average with weight ``s``. 0 (default) is the plain
        Laplacian step; MeshLab's classic Laplacian is ``step 1, self_weight 0.5``.
    boundary : {"free", "fixed", "curve"}
        Boundary vertices (on an edge with one incident face): rows of the operator as built
        (``free``), not moved (``fixed``), or moved along the boundary curve (``curve``, see
        `curve_rows`; with ``step 1, self_weight 0.5`` this is MeshLab's classic Laplacian with
        ``boundary: true``).
    reassemble : bool
        Rebuild ``W`` and ``M`` from the current positions before every step (no effect for
        uniform weights). ``h`` stays the one of the input.

    Returns
    -------
    SmoothingResult
        ``V`` (n, 3). Unstable steps are *not* clamped: coordinates may grow without bound
        (forward Euler is stable only for ``h * |lambda_max(L)| < 2``); iteration stops early
        once a coordinate is non-finite.

    Notes
    -----
    Forward Euler on the diffusion equation ``dX/dt = L X`` (Taubin 1995; Desbrun et al.
    1999, Sec. 2). One sparse mat-vec per step. With ``uniform`` weights and ``step = 1`` each
    vertex moves to the mean of its neighbours (the vertex itself not averaged in).
    """
    h = time_step(V, F, step, weights)
    unit = time_step(V, F, 1.0, weights)

    def operator(P):
        W, m = smoothing_operator(P, F, weights)
        W, m, fixed = apply_boundary_rule(W, m, F, boundary, unit)
        scale = h / (m + float(self_weight) * unit)
        if fixed is not None:
            scale = np.where(fixed, 0.0, scale)
        return (sp.diags(scale) @ W).tocsr()

    L = operator(V)
    X = V.copy()
    with np.errstate(over="ignore", invalid="ignore"):
        for it in range(iterations):
            if reassemble and it > 0 and weights != "uniform":
                L = operator(X)
            X = X + L @ X
            if not _finite(X):
                break
    return SmoothingResult(V=X)


@register("scratch.implicit", task="smoothing", library="scratch",
          params={"weights": Param("weights", "cotan_area", choices=WEIGHTS, doc=_WEIGHTS_DOC),
                  "step": Param("step", 1.0, "float", low=0.0, doc=_STEP_DOC),
                  "iterations": Param("iterations", 1, "int", low=0, high=10000,
                                      doc="number of backward-Euler steps"),
                  "reassemble": Param("reassemble", False, "bool",
                                      doc="rebuild W and M from the current positions each step "
                                          "(mean-curvature flow)"),
                  "solver": solver_param()})
def implicit(V, F, *, weights="cotan_area", step=1.0, iterations=1, reassemble=False,
             solver="auto"):
    """Implicit (backward Euler) Laplacian smoothing, symmetric form ``(M - h W) X' = M X``.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    weights : {"uniform", "cotan", "cotan_area"}
        Operator (module docstring); default the Laplace-Beltrami operator ``cotan_area``.
    step : float
        Dimensionless step: ``h = step * lbar^2`` for cotan_area, ``h = step`` otherwise
        (``lbar`` = mean edge length of the input; ``h`` is kept for every step).
    iterations : int
        Number of backward-Euler steps.
    reassemble : bool
        False: ``W`` and ``M`` from the input positions, one factorization for all steps
        (linear diffusion). True: rebuilt from the current positions before each step
        (mean-curvature flow, Desbrun et al. 1999 Sec. 5).
    solver : str
        Sparse SPD solver (``harness.core.solvers``), ``auto`` by default.

    Returns
    -------
    SmoothingResult

    Notes
    -----
    Desbrun, Meyer, Schroeder, Barr, "Implicit fairing of irregular meshes using diffusion
    and curvature flow", SIGGRAPH 1999. ``(I - h M^-1 W) X' = X`` multiplied by ``M`` gives
    the symmetric positive-definite system ``(M - h W) X' = M X`` (``-W`` is positive
    semi-definite for all three operators), solved by sparse Cholesky / LDL^T for the three
    coordinates at once. Unconditionally stable: no step size diverges. No volume rescaling.
    """
    h = time_step(V, F, step, weights)
    X = backward_euler(V, F, lambda P: smoothing_operator(P, F, weights), h, iterations,
                       reassemble, solver)
    return SmoothingResult(V=X)


@register("scratch.taubin", task="smoothing", library="scratch",
          params={"lambda": Param("lambda", 0.5, "float", low=0.0,
                                  doc="shrinking step (positive); times lbar^2 for cotan_area"),
                  "mu": Param("mu", -0.53, "float", high=0.0,
                              doc="inflating step (negative, |mu| > lambda)"),
                  "iterations": Param("iterations", 10, "int", low=0, high=100000,
                                      doc="number of (lambda, mu) step pairs"),
                  "weights": Param("weights", "uniform", choices=WEIGHTS, doc=_WEIGHTS_DOC),
                  "boundary": boundary_rule_param()})
def taubin(V, F, **params):
    """Taubin's lambda|mu smoothing: ``X <- X + lambda L X`` then ``X <- X + mu L X``. The defaults
    are MeshLab's (lambda 0.5, mu -0.53: pass-band frequency ``k_PB = 1/lambda + 1/mu = 0.113``).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    lambda : float
        Positive (shrinking) factor; the pass-band frequency is
        ``k_PB = 1/lambda + 1/mu`` (Taubin 1995). ``lambda`` is a Python keyword, hence the
        ``**params`` signature.
    mu : float
        Negative (un-shrinking) factor, ``mu < -lambda``.
    iterations : int
        Number of (lambda, mu) pairs, i.e. ``2 * iterations`` Laplacian steps.
    weights : {"uniform", "cotan", "cotan_area"}
        Operator (module docstring), built once from the input. For cotan_area the factors are
        multiplied by ``lbar^2`` like ``step``.
    boundary : {"free", "fixed", "curve"}
        Boundary vertices: operator rows as built (``free``), not moved (``fixed``), or moved
        along the boundary curve (``curve``, `curve_rows`).

    Returns
    -------
    SmoothingResult

    Notes
    -----
    Taubin, "A signal processing approach to fair surface design", SIGGRAPH 1995. With
    uniform weights ``(L X)_i = mean of neighbours - x_i``; MeshLab's
    ``apply_coord_taubin_smoothing`` computes the same steps (``boundary: curve`` on open
    meshes), PyGEL3D's ``taubin_smooth`` is this with ``lambda 0.5, mu -0.52`` and ``boundary:
    free`` on any mesh. At the defaults (``boundary: free``) this and ``meshlab.taubin`` differ
    on an open mesh (camelhead: 1.1e-2 of the diagonal after 10 pairs; 1e-9 with ``boundary:
    curve``): compare them with ``boundary: curve``.
    """
    lam = float(params.get("lambda", 0.5))
    mu = float(params.get("mu", -0.53))
    iterations = int(params.get("iterations", 10))
    weights = params.get("weights", "uniform")
    unit = time_step(V, F, 1.0, weights)
    W, m = smoothing_operator(V, F, weights)
    W, m, fixed = apply_boundary_rule(W, m, F, params.get("boundary", "free"), unit)
    scale = unit / m
    if fixed is not None:
        scale = np.where(fixed, 0.0, scale)
    L = (sp.diags(scale) @ W).tocsr()
    X = V.copy()
    with np.errstate(over="ignore", invalid="ignore"):
        for _ in range(iterations):
            X = X + lam * (L @ X)
            X = X + mu * (L @ X)
            if not _finite(X):
                break
    return SmoothingResult(V=X)


@register("scratch.screened_poisson", task="smoothing", library="scratch",
          params={"alpha": Param("alpha", 1.0, "float", low=1e-6, high=1e6,
                                 doc="screening weight, dimensionless: alpha_phys = alpha / lbar"),
                  "weights": Param("weights", "cotan_area", choices=WEIGHTS, doc=_WEIGHTS_DOC),
                  "solver": solver_param()})
def screened_poisson(V, F, *, alpha=1.0, weights="cotan_area", solver="auto"):
    """Screened-Poisson smoothing ``(a^2 M - W) X = a^2 M X0``.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    alpha : float
        Dimensionless screening weight: the physical ``a = alpha / lbar`` for cotan_area
        (``lbar`` = mean edge length), ``a = alpha`` for the row-normalized operators. Large
        alpha keeps the input, small alpha smooths more.
    weights : {"uniform", "cotan", "cotan_area"}
    solver : str

    Returns
    -------
    SmoothingResult

    Notes
    -----
    Chuang & Kazhdan, "Interactive and anisotropic geometry processing using the screened
    Poisson equation", SIGGRAPH 2011: minimise ``a^2 |X - X0|_M^2 + |grad X|^2``, whose
    normal equations are the system above. Dividing by ``a^2`` shows it is exactly one
    backward-Euler step with ``h = 1 / a^2``, i.e. ``scratch.implicit`` with
    ``step = 1 / alpha^2`` and one iteration (tested: equal to rounding; on a mesh with a
    numerically flat face, whose cotangent weights reach 1e15, the two solves of the same
    system differ by the conditioning, up to 1e-2 of the diagonal, as two solvers do).
    """
    a2 = float(alpha) ** 2
    if weights == "cotan_area":
        a2 = a2 / mean_edge_length(V, F) ** 2
    W, m = smoothing_operator(V, F, weights)
    from harness.core.solvers import factorize
    X = factorize(a2 * sp.diags(m) - W, solver).solve(a2 * m[:, None] * V)
    return SmoothingResult(V=X)
