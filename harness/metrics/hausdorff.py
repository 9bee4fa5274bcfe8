"""Certified symmetric Hausdorff distance between two triangle meshes, by branch and bound.

``H(A, B) = max(h(A, B), h(B, A))`` with ``h(X, Y) = max_{p in X} d(p, Y)``, ``d`` the exact
Euclidean distance to the surface ``Y`` (a union of closed triangles). Both directions are
bracketed, ``lower <= h <= upper``:

- **lower bound**: the largest distance found at evaluated points of ``X`` (its vertices, face
  centroids and the corners of refined sub-triangles);
- **upper bound per triangle** ``T`` of ``X`` (corners ``p_0, p_1, p_2``), the smaller of
  * convexity: for a fixed triangle ``t`` of ``Y`` the distance ``d(p, t)`` is convex in ``p``,
    so ``max_{p in T} d(p, Y) <= max_{p in T} d(p, t) = max_i d(p_i, t)``; ``t`` runs over the
    triangles of ``Y`` closest to the corners and to the centroid of ``T``;
  * Lipschitz: ``d(., Y)`` is 1-Lipschitz, so ``max_{p in T} d(p, Y) <= d(c, Y) + max_i |p_i - c|``
    at the centroid ``c``;
  * covering: where the triangles of ``Y`` seen along ``T``'s normal certifiably cover ``T``
    (a winding-number test on the boundary of the set of triangles, no assumption on ``Y``),
    ``max_{p in T} d(p, Y)`` is at most the largest height of ``Y`` above or below ``T`` over
    ``T`` (`harness.metrics._cover_bound`). This settles coarse triangles over a finer surface
    without subdividing them to the finer mesh's scale.

Triangles whose upper bound exceeds ``(1 + eps) * lower + atol`` are split into four (edge
midpoints) and bounded again, the one with the largest bound first (best first), until none is
left (the result is then certified: the true value lies in ``[lower, (1 + eps) lower + atol]``;
with a ``floor``, below, ``max(lower, floor)`` takes the place of ``lower`` in the upper end)
or the point budget (``max_points`` evaluations per
direction) or ``max_seconds`` runs out, which leaves a wider but still valid bracket. The
bounds are weakest where the distance is tiny against the triangles' size and the covering
bound cannot be certified (an exact or near-exact reconstruction of a region with folds or
gaps seen along the normal): there the budget may end the search with a wide bracket, which
is what is known. For the symmetric ``H`` the direction that looks larger (by its samples) is
bracketed first; its lower bound also closes the other direction's triangles (a triangle
whose bound is within ``(1 + eps)`` of it cannot raise ``H`` beyond the bracket), so the
second stops as soon as it is inside the symmetric bracket. The method
follows the bounded-error Hausdorff of Tang, Lee & Kim 2009 (interactive Hausdorff distance
computation for general polygonal models, SIGGRAPH) with the simpler per-triangle bounds above;
distances come from our compiled bounding-volume hierarchy (`harness.metrics._bvh_kernel`).
Units: input units (the caller divides by the diagonal).
"""
from __future__ import annotations

import time

import numpy as np

from ..core.geometry import face_around_vertex, morton_order, referenced, sample_surface
from .surface_distance import Surface


_Surface = Surface           # the AABB-backed surface (harness.metrics.surface_distance)


def one_sided(VX: np.ndarray, FX: np.ndarray, Y: Surface, eps: float = 1e-3, atol: float = 0.0,
              max_points: int = 1_000_000, deadline: float = float("inf"), lower: float = 0.0,
              cap: np.ndarray | None = None, all_vertices: bool = False,
              hints: np.ndarray | None = None, floor: float = 0.0) -> dict:
    """Bracket ``h(X, Y) = max_{p in X} d(p, Y)`` (module docstring), compiled: the vertices of X
    are queried, every triangle gets its upper bound (one centroid query where the corners do
    not settle it), then the open sub-triangle with the largest bound is split, best first (a
    max-heap), each midpoint queried from the closest face of the nearer corner (the
    `harness.metrics._bvh_kernel` hierarchy over Y), in batches of splits between which
    ``deadline`` is checked. ``lower`` may seed the lower bound with a distance already found
    at a point of X. ``hints`` (k,): for each vertex of X a face of Y (index into Y's ``F``,
    -1 for none) near it, where its query starts. ``floor``: a lower bound of a larger distance
    this one is part of (the other direction of a symmetric Hausdorff distance): sub-triangles
    whose bound is within ``(1 + eps) max(lower, floor) + atol`` are not split further, so
    ``upper`` stays a valid bound of ``h`` but ``lower`` may stay below ``h / (1 + eps)``.

    Returns ``lower``, ``upper`` (``upper >= h >= lower``), ``certified`` (the bracket met
    ``upper <= (1 + eps) max(lower, floor) + atol``), ``points`` (distance queries made), ``rounds``
    (batches of splits) and ``vertex_distances`` (k,) (each vertex of X to Y; with
    ``all_vertices`` also the vertices in no face, else 0 there).
    """
    from . import _bracket_kernel as B
    from ._queries import query_blocks
    VX = np.ascontiguousarray(VX, dtype=np.float64)
    FX = np.ascontiguousarray(FX, dtype=np.int64)
    tree = Y.bvh()
    from ._cover_bound import work
    NY, W = Y.neighbours(), work(len(tree[1]))
    inface = referenced(FX, len(VX))
    used = np.arange(len(VX)) if (all_vertices and len(tree[1])) else np.flatnonzero(inface)
    dV = np.zeros(len(VX))
    iV = np.zeros(len(VX), np.int64)
    if len(used):
        used = used[morton_order(VX[used])]         # neighbouring queries read neighbouring nodes
        h = np.full(len(used), -1, np.int64) if hints is None else Y.leaf_faces(np.asarray(hints)[used])
        dV[used], iV[used] = query_blocks(VX[used], h, *tree)
    # state: [lower, queries, settled, open, initialised, heap size, free slots, done, floor]
    state = np.zeros(9)
    state[0] = max(lower, float(dV[inface].max()) if inface.any() else 0.0)
    state[1] = float(len(used))
    state[8] = floor
    cap = np.full(len(FX), np.inf) if cap is None else np.ascontiguousarray(cap, dtype=np.float64)
    ub = B.roots(VX, FX, dV, iV, *tree, NY, W, eps, atol, state, cap)
    thr = (1.0 + eps) * max(state[0], floor) + atol
    closed = ub <= thr
    if closed.any():
        state[2] = float(ub[closed].max())
    tris = np.flatnonzero(~closed)
    tris = np.ascontiguousarray(tris[np.argsort(-ub[tris], kind="stable")])
    cap = 2 * len(tris) + 1024
    store = (np.empty((cap, 3, 3)), np.empty((cap, 3)), np.empty((cap, 3), np.int64), np.empty(cap),
             np.empty(cap, np.int64), np.arange(cap, dtype=np.int64)[::-1].copy())
    state[6] = cap
    rounds = 0
    while True:
        rounds += 1
        store = B.best_first(tris, np.ascontiguousarray(ub[tris]), VX, FX, dV, iV, *tree, NY, W, eps, atol,
                             float(max_points), 20000, store, state)
        if state[7] or state[1] + 7 > max_points or time.perf_counter() > deadline:
            break
    low = float(state[0])
    upper = max(low, float(state[2]), float(state[3]))
    Y.count += int(state[1])
    return {"lower": low, "upper": upper, "certified": upper <= (1.0 + eps) * max(low, floor) + atol,
            "points": int(state[1]), "rounds": rounds, "vertex_distances": dV}


def _in_spatial_order(P: np.ndarray, Y: Surface, order: np.ndarray | None = None) -> np.ndarray:
    """Distances (k,) of the points P (k, 3) to Y, queried along a Morton curve (``order``, when
    known; neighbouring queries read neighbouring nodes, each starting from the previous
    point's closest face), returned in the order of P."""
    from ._queries import query_blocks
    order = morton_order(P) if order is None else order
    d = np.empty(len(P))
    d[order] = query_blocks(P[order], np.full(len(P), -1, np.int64), *Y.bvh())[0]
    Y.count += len(P)
    return d


ROUND = 256 * float(np.finfo(np.float64).eps)
"""The rounding allowance of a distance, times the largest coordinate magnitude of the vertices
the two meshes' faces use (M): a point queried on a triangle is built in absolute coordinates (off
the surface by about 3 eps M), and its distance to a triangle (`harness.metrics._bvh_kernel`) is
measured from the corners, over the inside as the distance to the plane, whose normal's direction
is known to about 3.5 eps times the condition ``|ab||ac| / |ab x ac|`` at most 16 (a sliver
beyond it is measured in double-double arithmetic): at most about 58 eps |ap|, ``|ap|`` at most
``2 sqrt(3) M``."""


def _used_max(V, F) -> float:
    """The largest coordinate magnitude of the vertices the faces ``F`` use (0 without faces)."""
    return float(np.abs(V[referenced(F, len(V))]).max(initial=0.0))


def hausdorff(VA, FA, VB, FB, eps: float = 1e-3, atol: float | None = None, max_points: int = 1_000_000,
              max_seconds: float = 30.0, n_samples: int = 20000, seed: int = 0,
              surface_b: Surface | None = None, corresponding: bool = False,
              vertex_distances: bool = False, surface_a: Surface | None = None) -> dict:
    """Certified symmetric Hausdorff distance and sampled mean surface distances.

    ``hausdorff``: the largest distance found (a lower bound), with ``hausdorff_upper`` the
    certified upper bound and ``hausdorff_gap = (upper - lower) / lower`` (0 when
    ``upper - lower <= atol + 2 r``, ``r`` below);
    Both ends carry the rounding of the points queried and of their distances: the lower end is
    the largest distance found less ``r = ROUND * max |coordinate|`` (over the vertices the faces
    use; at least 0), the upper end the bound plus ``r`` (about 5.7e-14 for coordinates up to 1,
    5.7e-9 at 1e5); ``hausdorff_ab``/``_ba`` less ``r`` too.
    ``hausdorff_certified``: the search closed, ``upper <= (1 + eps) lower + atol`` before the
    ends are widened by ``r`` (``atol`` default ``1e-12`` times the larger bounding-box diagonal
    plus ``2 r``, for exact reconstructions; the gap is 0 within ``atol + 2 r``) before the budget
    (``max_points`` distance queries per direction, ``max_seconds`` in all) ran out: the gap
    is at most ``eps``, except for a distance near rounding level, where ``atol`` may certify
    a bracket whose relative gap is larger (e.g. ``[1e-12, 2.4e-12]`` of the diagonal).
    ``hausdorff_ab``/``_ba``: the one-sided lower bounds (A to B, B to A). Only the symmetric
    distance is certified: without ``corresponding`` the direction with the larger sampled
    maximum (A to B without samples) is bracketed first and the other only until its bound is
    within ``(1 + eps) max(its own lower bound, the first one's) + atol``, so the larger of the
    two lower bounds is within the certified gap of ``H`` and the other may be looser than
    ``eps`` (when the two directions are within ``eps`` of each other it may even be the truly
    larger one); with ``corresponding``, B to A covers only the triangles whose
    displacement cap exceeds ``(1 + eps) max(lower_ab, sampled) + atol`` (0 when none does and
    no samples were taken: valid but uninformative).

    ``surface_b``: a prebuilt `Surface` of (VB, FB) to reuse (e.g. the clean mesh's, shared by
    every metric of a case; it also keeps B's samples, `Surface.samples`). ``corresponding``: A
    and B have the same faces on corresponding vertices (a smoothed mesh and its clean
    original); then the barycentric map of each
    triangle onto its twin bounds its distance to the other surface by its corners' largest
    displacement ``max_i |a_i - b_i|`` (the norm is convex), which closes most triangles
    without a query.

    ``surface_a``: likewise a prebuilt `Surface` of (VA, FA) (with ``corresponding``, e.g.
    ``surface_b.displaced(VA)``).

    ``vertex_distances``: also return ``"vertex_distances_ab"``, the exact distance of every
    vertex of A to B (k,) (the bracket queries them anyway; vertices in no face included).

    ``surface_dist_mean``: the symmetric mean surface distance, the average of the two one-sided
    area-weighted means ``mean_{p in A} d(p, B)`` and ``mean_{p in B} d(p, A)``, each estimated
    from ``n_samples`` area-uniform random points (seeded; no vertices mixed in), with
    ``surface_dist_mean_se`` its standard error (``sqrt(se_ab^2 + se_ba^2) / 2``). Input units.
    """
    VA, VB = np.asarray(VA, dtype=np.float64), np.asarray(VB, dtype=np.float64)
    rnd = ROUND * max(_used_max(VA, FA), _used_max(VB, FB))
    if atol is None:
        atol = 1e-12 * max(float(np.linalg.norm(np.ptp(VA, axis=0))), float(np.linalg.norm(np.ptp(VB, axis=0)))) + 2 * rnd
    deadline = time.perf_counter() + max_seconds
    if corresponding and (VA.shape != VB.shape or not np.array_equal(FA, FB)):
        raise ValueError("corresponding=True needs the same faces on the same number of vertices")
    SB = surface_b if surface_b is not None else Surface(VB, FB)
    SA = (surface_a if surface_a is not None else
          SB.displaced(VA) if corresponding else Surface(VA, FA))      # same triangles: B's tree, refitted
    out = {}
    seed_ab = seed_ba = 0.0
    if n_samples:
        # the distances are exact in any order; a spatial one is faster
        PA = sample_surface(VA, FA, n_samples, seed)
        PB, order_b = SB.samples(n_samples, seed + 1)          # drawn once per surface_b
        dab, dba = _in_spatial_order(PA, SB), _in_spatial_order(PB, SA, order_b)
        seed_ab = float(dab.max()) if dab.size else 0.0        # no samples on a zero-area surface
        seed_ba = float(dba.max()) if dba.size else 0.0
        if dab.size and dba.size:
            se = np.sqrt(dab.var(ddof=1) / dab.size + dba.var(ddof=1) / dba.size) / 2 if n_samples > 1 else float("nan")
            out.update(surface_dist_mean=float((dab.mean() + dba.mean()) / 2), surface_dist_mean_se=float(se))
        else:
            out.update(surface_dist_mean=float("nan"), surface_dist_mean_se=float("nan"))
    cap_ab = cap_ba = hints = None
    if corresponding:
        FA = np.asarray(FA, dtype=np.int64)
        disp = np.linalg.norm(VA - VB, axis=1)
        cap_ab = cap_ba = disp[FA].max(axis=1) if len(FA) else None
        hints = face_around_vertex(FA, len(VA))        # on both sides
    def a_to_b(floor=0.0):
        return one_sided(VA, FA, SB, eps, atol, max_points, deadline, lower=seed_ab, cap=cap_ab,
                         all_vertices=vertex_distances, hints=hints, floor=floor)

    def b_to_a(floor=0.0):
        return one_sided(VB, FB, SA, eps, atol, max_points, deadline, lower=seed_ba, cap=cap_ba, hints=hints,
                         floor=floor)
    if corresponding and len(FB):
        ab = a_to_b()
        # B's triangles whose displacement cap is already within the symmetric threshold need
        # no query: only the others are bracketed
        open_ = cap_ba > (1.0 + eps) * max(ab["lower"], seed_ba) + atol
        settled = float(cap_ba[~open_].max()) if not open_.all() else 0.0
        if open_.any():
            ba = one_sided(VB, np.asarray(FB)[open_], SA, eps, atol, max_points, deadline, lower=seed_ba,
                           cap=cap_ba[open_], hints=hints)
        else:
            ba = {"lower": seed_ba, "upper": seed_ba, "points": 0}
        ba["upper"] = max(ba["upper"], settled)
    elif seed_ba > seed_ab:
        # the direction that looks larger first; the other is only bracketed to the symmetric threshold
        ba = b_to_a()
        ab = a_to_b(floor=ba["lower"])
    else:
        ab = a_to_b()
        ba = b_to_a(floor=ab["lower"])
    lo, up = max(ab["lower"], ba["lower"]), max(ab["upper"], ba["upper"])
    certified = bool(up <= (1.0 + eps) * lo + atol)              # the search's own criterion
    lower, upper = max(lo - rnd, 0.0), up + rnd                  # with the rounding of what it measured
    gap = 0.0 if upper - lower <= atol + 2 * rnd else ((upper - lower) / lower if lower > 0 else float("inf"))
    out.update({"hausdorff": lower, "hausdorff_upper": upper, "hausdorff_gap": gap,
                "hausdorff_certified": certified,
                "hausdorff_ab": max(ab["lower"] - rnd, 0.0), "hausdorff_ba": max(ba["lower"] - rnd, 0.0),
                "hausdorff_points": ab["points"] + ba["points"]})
    if vertex_distances:
        out["vertex_distances_ab"] = ab["vertex_distances"]
    return out


def warm() -> None:
    """Load (or compile) the compiled bounds once, e.g. in a driver before it forks case processes."""
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], dtype=np.int64)
    hausdorff(V, F, V * 1.1, F, n_samples=0)
    hausdorff(V * 1.1, F, V, F, n_samples=0, corresponding=True)
