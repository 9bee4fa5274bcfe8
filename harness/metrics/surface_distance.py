"""Exact point-to-surface distance (closest point on any triangle, libigl's AABB tree)."""
import numpy as np

from ..core.geometry import double_areas


class Surface:
    """A triangle mesh with an AABB tree (libigl) for exact point-to-surface queries and our
    compiled hierarchy for the certified Hausdorff distance (each built on first use); build it
    once per surface and query it many times."""

    def __init__(self, V: np.ndarray, F: np.ndarray):
        self.V = np.ascontiguousarray(V, dtype=np.float64)
        self.F = np.ascontiguousarray(F, dtype=np.int64)
        self.tree = None                 # libigl's AABB, built on the first `query`
        self._bvh = None
        self._nb = None
        self._pos = None
        self._used = None
        self._samples = None
        self._walk = None
        self.count = 0

    def bvh(self) -> tuple:
        """Our compiled hierarchy over the same triangles (`harness.metrics._bvh_kernel`), built
        on first use: ``(V', F', B)`` where ``F'`` holds the triangles in leaf order (a leaf's
        range indexes ``F'``), ``V'`` the vertices in order of first use, so a query reads
        contiguous memory, and ``B`` the packed nodes (`harness.metrics._bvh_kernel.build`).
        Face indices it reports refer to ``F'``; distances are those to the same surface."""
        if self._bvh is None:
            from ._bvh_kernel import build, centroids, leaf_order
            order = np.arange(len(self.F), dtype=np.int64)
            nodes = build(self.V, self.F, centroids(self.V, self.F), order)
            self._bvh = (*leaf_order(self.V, self.F, order), nodes)
            self._pos = np.empty(len(order), np.int64)
            self._pos[order] = np.arange(len(order))
        return self._bvh

    def displaced(self, V: np.ndarray) -> "Surface":
        """The `Surface` of the same triangles on other positions ``V`` of the same vertices (a
        smoothed or noisy copy): its hierarchy is this one's tree with every box recomputed
        (`harness.metrics._bvh_kernel.refit`; valid for any ``V``, tight for a nearby copy),
        and it shares the face neighbours, which depend on the triangles only."""
        from ._bvh_kernel import refit
        V = np.ascontiguousarray(V, dtype=np.float64)
        if V.shape != self.V.shape:
            raise ValueError(f"displaced needs one position per vertex {self.V.shape}, got {V.shape}")
        out = Surface(V, self.F)
        Vo, Fo, nodes = self.bvh()
        if getattr(self, "_used", None) is None:    # vertex of V behind each vertex of V' (older pickles lack it)
            self._used = np.empty(len(Vo), np.int64)
            order = np.empty(len(self._pos), np.int64)
            order[self._pos] = np.arange(len(self._pos))
            self._used[Fo.ravel()] = self.F[order].ravel()
        Vd = np.ascontiguousarray(V[self._used])
        out._bvh, out._pos, out._used = (Vd, Fo, refit(nodes, Vd, Fo)), self._pos, self._used
        out._nb = self.neighbours()
        return out

    def samples(self, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
        """``(P, order)``: ``n`` area-uniform random points of the surface
        (`harness.core.geometry.sample_surface` with ``seed``) and their order along a Morton
        curve; memoised, so a surface kept per input draws its samples once."""
        key = (int(n), int(seed))
        got = getattr(self, "_samples", None)             # older pickles lack it
        if got is None or got[0] != key:
            from ..core.geometry import morton_order, sample_surface
            P = sample_surface(self.V, self.F, n, seed)
            got = self._samples = (key, P, morton_order(P))
        return got[1], got[2]

    def __getstate__(self) -> dict:
        """Pickled (e.g. kept as a per-input fact) with the hierarchy but without libigl's tree,
        which is rebuilt on the next `query`."""
        state = dict(self.__dict__)
        state["tree"] = None
        return state

    def leaf_faces(self, faces: np.ndarray) -> np.ndarray:
        """The hierarchy's indices (into ``F'``, `bvh`) of faces given by their index in ``F``
        (-1 stays -1)."""
        self.bvh()
        faces = np.asarray(faces, dtype=np.int64)
        return np.where(faces >= 0, self._pos[np.maximum(faces, 0)], -1)

    def neighbours(self) -> np.ndarray:
        """Face neighbours (m, 3) of the hierarchy's faces ``F'`` (`bvh`): the face across edge
        ``(F'[f, j], F'[f, j+1])``, -1 on a boundary or non-manifold edge."""
        if self._nb is None:
            from ._cover_bound import face_neighbours
            V, F = self.bvh()[:2]
            self._nb = face_neighbours(F, len(V))
        return self._nb

    def corresponding_distances(self, P: np.ndarray, walk: tuple | None = None) -> np.ndarray:
        """Exact distances (n,) to this surface of the vertices ``P`` (n, 3) of a mesh with the
        same faces on corresponding vertices (a displaced copy, e.g. a noisy or smoothed one):
        each query starts from a face around its vertex, so it usually prunes at once.
        ``walk``: ``P``'s `walk` when known (e.g. the clean surface's, for its own vertices)."""
        from ._queries import query_blocks
        P = np.ascontiguousarray(P, dtype=np.float64)
        if len(P) != len(self.V):
            raise ValueError(f"corresponding_distances needs one point per vertex ({len(self.V)}), got {len(P)}")
        if len(P) == 0 or len(self.F) == 0:
            return self.query(P)[0]
        order, hints = walk if walk is not None else _walk(P, self.F)
        self.count += len(P)
        d = np.empty(len(P))
        d[order] = query_blocks(P[order], self.leaf_faces(hints), *self.bvh())[0]
        return d

    def walk(self) -> tuple[np.ndarray, np.ndarray]:
        """``(order, hints)`` of this surface's own vertices for `corresponding_distances` on a
        displaced copy: their order along a Morton curve (neighbouring queries read neighbouring
        nodes) and, in that order, a face around each (-1 for none); memoised."""
        if getattr(self, "_walk", None) is None:            # older pickles lack it
            self._walk = _walk(self.V, self.F)
        return self._walk

    def query(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distances (k,) and closest face indices (k,) of points (k, 3)."""
        if len(P) == 0:
            return np.zeros(0), np.zeros(0, np.int64)
        if self.tree is None:
            import igl
            self.tree = igl.AABB()
            self.tree.init(self.V, self.F)
        self.count += len(P)
        d2, i, _ = self.tree.squared_distance(self.V, self.F, np.ascontiguousarray(P, dtype=np.float64))
        return np.sqrt(np.maximum(np.asarray(d2).ravel(), 0.0)), np.asarray(i, dtype=np.int64).ravel()


def _walk(P: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`Surface.walk` of the points ``P``, the vertices of the faces ``F``."""
    from ..core.geometry import face_around_vertex, morton_order
    order = morton_order(P)
    return order, face_around_vertex(F, len(P))[order]


def cached_surface(cache: dict, key: str, V: np.ndarray, F: np.ndarray) -> Surface:
    """The `Surface` of (V, F) memoised in ``cache`` under ``key`` (e.g. a case input's cache)."""
    if key not in cache:
        cache[key] = Surface(V, F)
    return cache[key]


def point_surface_distance(P: np.ndarray, V: np.ndarray, F: np.ndarray, surface: Surface | None = None) -> np.ndarray:
    """Unsigned distance (k,) from each point of ``P`` (k, 3) to the triangle mesh (V, F)
    (``surface``: its prebuilt `Surface`, if any)."""
    return (surface or Surface(V, F)).query(P)[0]


def surface_distance(V: np.ndarray, F: np.ndarray, V_clean: np.ndarray, F_clean: np.ndarray,
                     surface: Surface | None = None, d: np.ndarray | None = None,
                     double_areas_: np.ndarray | None = None) -> dict:
    """Distances of the result's vertices to the clean surface.

    ``dist_mean`` = mean_i d(v_i, S_clean). ``ev_sun`` (Sun et al. 2007) =
    sqrt( sum_i A_i d(v_i, S_clean)^2 / sum_i A_i ), A_i the barycentric area of vertex i on
    the result mesh (one third of its incident faces' areas). ``d``: those distances, when
    already computed (e.g. by the Hausdorff bracket's vertex queries); ``double_areas_``: the
    result's face double areas (`harness.core.geometry.double_areas`), likewise.
    """
    if d is None:
        d = point_surface_distance(V, V_clean, F_clean, surface)
    dbl = double_areas(V, F) if double_areas_ is None else double_areas_
    A = np.bincount(F.ravel(), weights=np.repeat(dbl / 6.0, 3), minlength=len(V))
    tot = A.sum()
    ev_sun = float(np.sqrt((A * d ** 2).sum() / tot)) if tot > 0 else float("nan")
    return {"dist_mean": float(d.mean()), "ev_sun": ev_sun}
