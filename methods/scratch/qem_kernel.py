"""The sequential part of `scratch.qem`: the edge-collapse loop, compiled with numba.

Everything here is plain Python until `kernel()` is called: it imports numba and replaces the
module's functions by ``numba.njit(cache=True)`` versions (helpers first, so the callers see
compiled callees when they are compiled on first use). The registry imports every module of
`methods`, so importing numba lazily keeps ``shootout methods`` fast and makes a missing numba an
"unavailable" method rather than an import error.

Data structures (all flat arrays, no Python objects):

* ``F`` (m, 3) faces, edited in place (a collapsed vertex is replaced by the survivor, so face
  orientation is never changed); ``falive`` (m,) marks live faces.
* per-vertex lists of face corners in one int32 arena: corner ``c = 3 f + k`` belongs to
  vertex ``F[f, k]``; the corners of the live faces of ``v`` are
  ``L[start[v] : start[v] + deg[v]]``. A collapse of ``v`` into ``u`` rewrites ``v``'s corners
  and appends ``u``'s new list (``v``'s corners off the edge's faces, then ``u``'s) at the end
  of the arena; the third vertex of each removed face drops that corner in place. When the
  arena is full, the live lists are copied to a fresh one in vertex order (`arena_gc`).
  Contiguous lists make the faces of a vertex independent loads: before a candidate is
  tested, the faces of both ends and then their vertices' data are prefetched
  (`prefetch_ring`), so the memory latencies overlap instead of adding up face after face.
* quadrics ``Q`` (n, 10): ``a11 a12 a13 a22 a23 a33 b1 b2 b3 c`` of
  ``x^T A x + 2 b^T x + c``.
* the priority queue of candidate collapses: a 4-ary min-heap holding the cheapest entries
  plus an unordered, append-only pool holding the others (a two-level queue). Entries are two
  int64 words: ``key code << 30 | stamp sum`` and ``u << 32 | v`` (survivor, removed vertex);
  the key code is an order-preserving 32-bit code of the quadric error (exponent and 21
  mantissa bits, see `key_code`), so integer comparison of the first word orders by error.
  Every entry with key code <= ``tau`` is in the heap, every other one in the pool; a new
  entry goes to the heap or the pool accordingly. When the heap runs empty, ``tau`` is raised
  to about the ``max(2^15, pool / 10)``-th smallest key of the pool (estimated from a sample)
  and those entries are moved into the heap (`refill`). Pops therefore come out in exactly
  the order of a single heap, but the heap stays small (cache resident) and most pushes are a
  sequential append. 16-byte entries put a node's 4 children in one 64-byte cache line (the
  heap array is aligned for that).
* lazy invalidation with version stamps: every vertex has a counter ``stamp`` that grows
  whenever the vertex changes (it survives a collapse: new position, new quadric) and is set
  to a large negative value when it dies. An entry stores ``stamp[u] + stamp[v]`` at push
  time and is stale when the sum differs at pop time (live counters only grow, so any change
  shows in the sum); stale entries are skipped when popped, dropped when moved from the pool,
  and the pool is purged of them whenever it has grown by a quarter since the last purge
  (`pool_compact`). Every collapse queues fresh entries for all edges around the survivor.
"""
from __future__ import annotations

import functools
import math

import numpy as np

INF = np.inf
DEAD = -(1 << 40)   # stamp of a removed vertex: no stamp sum of live vertices can match it


# ----------------------------------------------------------------------------- placement
def place(Q, V, u, v, cond_max, dist_max):
    """Position and quadric error of collapsing edge (u, v).

    Optimal placement ``p = -A^-1 b`` for the summed quadric when ``A`` is well conditioned
    (Frobenius condition number ``|A|_F |adj A|_F / |det A| <= cond_max``) and ``p`` lies
    within ``dist_max`` edge lengths of the midpoint; otherwise the best of the endpoints, the
    midpoint and the quadric's minimiser on the segment (clamped to [0, 1]).
    """
    a11 = Q[u, 0] + Q[v, 0]
    a12 = Q[u, 1] + Q[v, 1]
    a13 = Q[u, 2] + Q[v, 2]
    a22 = Q[u, 3] + Q[v, 3]
    a23 = Q[u, 4] + Q[v, 4]
    a33 = Q[u, 5] + Q[v, 5]
    b1 = Q[u, 6] + Q[v, 6]
    b2 = Q[u, 7] + Q[v, 7]
    b3 = Q[u, 8] + Q[v, 8]
    c = Q[u, 9] + Q[v, 9]
    ux, uy, uz = V[u, 0], V[u, 1], V[u, 2]
    vx, vy, vz = V[v, 0], V[v, 1], V[v, 2]
    mx, my, mz = 0.5 * (ux + vx), 0.5 * (uy + vy), 0.5 * (uz + vz)
    ex, ey, ez = vx - ux, vy - uy, vz - uz
    elen2 = ex * ex + ey * ey + ez * ez

    # cofactors (adjugate of the symmetric A)
    c11 = a22 * a33 - a23 * a23
    c12 = a13 * a23 - a12 * a33
    c13 = a12 * a23 - a13 * a22
    c22 = a11 * a33 - a13 * a13
    c23 = a12 * a13 - a11 * a23
    c33 = a11 * a22 - a12 * a12
    det = a11 * c11 + a12 * c12 + a13 * c13
    nA2 = a11 * a11 + a22 * a22 + a33 * a33 + 2.0 * (a12 * a12 + a13 * a13 + a23 * a23)
    nC2 = c11 * c11 + c22 * c22 + c33 * c33 + 2.0 * (c12 * c12 + c13 * c13 + c23 * c23)
    if det > 0.0 and nA2 * nC2 <= cond_max * cond_max * det * det:
        inv = 1.0 / det
        px = -(c11 * b1 + c12 * b2 + c13 * b3) * inv
        py = -(c12 * b1 + c22 * b2 + c23 * b3) * inv
        pz = -(c13 * b1 + c23 * b2 + c33 * b3) * inv
        dx, dy, dz = px - mx, py - my, pz - mz
        if dx * dx + dy * dy + dz * dz <= dist_max * dist_max * elen2:
            err = (a11 * px * px + a22 * py * py + a33 * pz * pz
                   + 2.0 * (a12 * px * py + a13 * px * pz + a23 * py * pz)
                   + 2.0 * (b1 * px + b2 * py + b3 * pz) + c)
            return px, py, pz, max(err, 0.0)
    # fallback: candidates on the segment u + t (v - u)
    best = INF
    bx, by, bz = mx, my, mz
    # error(t) = e0 + 2 t g + t^2 h
    Aex = a11 * ex + a12 * ey + a13 * ez
    Aey = a12 * ex + a22 * ey + a23 * ez
    Aez = a13 * ex + a23 * ey + a33 * ez
    h = ex * Aex + ey * Aey + ez * Aez
    g = (ux * Aex + uy * Aey + uz * Aez) + (b1 * ex + b2 * ey + b3 * ez)
    e0 = (a11 * ux * ux + a22 * uy * uy + a33 * uz * uz
          + 2.0 * (a12 * ux * uy + a13 * ux * uz + a23 * uy * uz)
          + 2.0 * (b1 * ux + b2 * uy + b3 * uz) + c)
    tstar = 0.5
    if h > 0.0:
        tstar = min(1.0, max(0.0, -g / h))
    for k in range(4):
        t = 0.0 if k == 0 else (1.0 if k == 1 else (0.5 if k == 2 else tstar))
        err = e0 + 2.0 * t * g + t * t * h
        if err < best:
            best = err
            bx, by, bz = ux + t * ex, uy + t * ey, uz + t * ez
    return bx, by, bz, max(best, 0.0)


# ----------------------------------------------------------------------------- heap
HB = 6        # heap position p lives at words HB + 2 p, HB + 2 p + 1 (see `heap_alloc`)
SMASK = (1 << 30) - 1
HEAP_K = 1 << 15   # minimum number of entries moved from the pool into the heap per refill


def key_code(err):
    """Order-preserving 32-bit integer code of a non-negative error (relative step 2.4e-7)."""
    if not err > 0.0:
        return 0
    m, e = math.frexp(err)              # err = m 2^e, 0.5 <= m < 1
    e = min(max(e + 1024, 0), 2047)
    return (e << 21) | int((m - 0.5) * 4194304.0)


def heap_alloc(cap):
    """Heap array for ``cap`` entries, aligned so that the 4 children of every node (words
    HB + 8 p + 2 .. HB + 8 p + 9) share one 64-byte cache line."""
    buf = np.empty(2 * cap + HB + 16, dtype=np.int64)
    o = ((-buf.ctypes.data) % 64) // 8
    return buf[o:]


def heap_sift_down(H, hn, i, w0, w1):
    """Place entry (w0, w1) at position i and sift it down a heap of size hn."""
    while True:
        c = 4 * i + 1
        if c + 3 < hn:
            # all four children: branch-free selection of the smallest (compiles to cmov;
            # data-dependent branches here mispredict about half the time)
            k0 = H[HB + 2 * c]
            k1 = H[HB + 2 * c + 2]
            k2 = H[HB + 2 * c + 4]
            k3 = H[HB + 2 * c + 6]
            m01 = c + (k1 < k0)
            k01 = min(k0, k1)
            m23 = c + 2 + (k3 < k2)
            k23 = min(k2, k3)
            m = m23 if k23 < k01 else m01
            mk = min(k01, k23)
        elif c < hn:
            m = c
            mk = H[HB + 2 * c]
            for j in range(c + 1, hn):
                kj = H[HB + 2 * j]
                if kj < mk:
                    mk = kj
                    m = j
        else:
            break
        if mk >= w0:
            break
        H[HB + 2 * i] = mk
        H[HB + 2 * i + 1] = H[HB + 2 * m + 1]
        i = m
    H[HB + 2 * i] = w0
    H[HB + 2 * i + 1] = w1


def heap_push(H, hn, w0, w1):
    """Insert entry (w0, w1) into a heap of size hn (capacity checked by the caller)."""
    i = hn
    while i > 0:
        p = (i - 1) >> 2
        if H[HB + 2 * p] <= w0:
            break
        H[HB + 2 * i] = H[HB + 2 * p]
        H[HB + 2 * i + 1] = H[HB + 2 * p + 1]
        i = p
    H[HB + 2 * i] = w0
    H[HB + 2 * i + 1] = w1


def pool_compact(P, pn, stamp):
    """Drop the stale entries of the pool (stamp sums that no longer match); returns its size."""
    j = 0
    for i in range(pn):
        w0 = P[2 * i]
        w1 = P[2 * i + 1]
        if (w0 & SMASK) == stamp[w1 >> 32] + stamp[w1 & 0xFFFFFFFF]:
            P[2 * j] = w0
            P[2 * j + 1] = w1
            j += 1
    return j


def pool_threshold(P, pn, k):
    """A key code with about k of the pool's pn entries at or below it (from a sample)."""
    ns = min(pn, 4096)
    sample = np.empty(ns, dtype=np.int64)
    for i in range(ns):
        sample[i] = P[2 * ((i * pn) // ns)] >> 30
    sample.sort()
    idx = min(ns - 1, (k * ns) // pn)
    return sample[idx]


def refill(H, hcap, P, pn, tau, stamp):
    """Move the fresh pool entries with key code <= tau into the (empty) heap, drop the stale
    ones among them, keep the rest in the pool; heapify. Returns (H, hcap, hn, pn)."""
    cnt = 0
    for i in range(pn):
        if (P[2 * i] >> 30) <= tau:
            cnt += 1
    if cnt + 64 > hcap:
        hcap = cnt + cnt // 2 + 64
        H = heap_alloc(hcap)
    hn = 0
    j = 0
    for i in range(pn):
        w0 = P[2 * i]
        w1 = P[2 * i + 1]
        if (w0 >> 30) <= tau:
            if (w0 & SMASK) == stamp[w1 >> 32] + stamp[w1 & 0xFFFFFFFF]:
                H[HB + 2 * hn] = w0
                H[HB + 2 * hn + 1] = w1
                hn += 1
        else:
            P[2 * j] = w0
            P[2 * j + 1] = w1
            j += 1
    if hn > 1:
        for i in range((hn - 2) // 4, -1, -1):
            heap_sift_down(H, hn, i, H[HB + 2 * i], H[HB + 2 * i + 1])
    return H, hcap, hn, j


def grow_pool(P, pn, cap):
    P2 = np.empty(2 * cap, dtype=np.int64)
    P2[:2 * pn] = P[:2 * pn]
    return P2


def heap_grow(H, hn, cap):
    """A larger heap array holding the same hn entries."""
    H2 = heap_alloc(cap)
    H2[:HB + 2 * hn] = H[:HB + 2 * hn]
    return H2


def prefetch(a, i):
    """Hint that the cache line of ``a[i]`` (row i of a 2-D array) is needed soon; compiled to
    ``llvm.prefetch`` by `kernel` (no-op in plain Python)."""


def _prefetch_intrinsic():
    import llvmlite.binding
    from llvmlite import ir
    from numba.core import cgutils, types
    from numba.extending import intrinsic

    # the intrinsic's name carries its pointer type: ``p0`` with the opaque pointers of LLVM 17
    # and later, ``p0i8`` with the typed pointers that llvmlite uses on older LLVM
    name = "llvm.prefetch.p0" if llvmlite.binding.llvm_version_info[0] >= 17 else "llvm.prefetch.p0i8"

    @intrinsic
    def prefetch_(typingctx, arr, idx):
        def codegen(context, builder, signature, args):
            aryty = signature.args[0]
            ary = context.make_array(aryty)(context, builder, args[0])
            zero = context.get_constant(types.intp, 0)
            idx = context.cast(builder, args[1], signature.args[1], types.intp)
            ptr = cgutils.get_item_pointer2(
                context, builder, ary.data, cgutils.unpack_tuple(builder, ary.shape),
                cgutils.unpack_tuple(builder, ary.strides), aryty.layout,
                [idx] + [zero] * (aryty.ndim - 1))
            i32 = ir.IntType(32)
            ptr = builder.bitcast(ptr, ir.IntType(8).as_pointer())
            fn = cgutils.get_or_insert_function(
                builder.module, ir.FunctionType(ir.VoidType(), [ptr.type, i32, i32, i32]),
                name)
            builder.call(fn, [ptr, i32(0), i32(3), i32(1)])
            return context.get_dummy_value()
        return types.void(arr, idx), codegen
    return prefetch_


def prefetch_ring(V, Q, F, L, start, deg, tag, stamp, u, v):
    """Prefetch what the test and the collapse of edge (u, v) will read: the faces of u and v,
    then the positions, quadrics, tags, stamps and list headers of their vertices. The loads
    are independent, so their memory latencies overlap (the walks that follow would otherwise
    wait for them one face at a time)."""
    for side in range(2):
        w = u if side == 0 else v
        s0 = start[w]
        for i in range(s0, s0 + deg[w]):
            prefetch(F, L[i] // 3)
    for side in range(2):
        w = u if side == 0 else v
        s0 = start[w]
        for i in range(s0, s0 + deg[w]):
            f = L[i] // 3
            for k in range(3):
                x = F[f, k]
                prefetch(V, x)
                prefetch(Q, x)
                prefetch(Q[x], 9)
                prefetch(tag, x)
                prefetch(stamp, x)
                prefetch(start, x)
                prefetch(deg, x)


def prefetch_ends(V, Q, start, deg, stamp, u, v):
    """Prefetch the stamps, list headers, positions and quadrics of u and v."""
    for side in range(2):
        w = u if side == 0 else v
        prefetch(stamp, w)
        prefetch(start, w)
        prefetch(deg, w)
        prefetch(V, w)
        prefetch(Q, w)
        prefetch(Q[w], 9)


def drop_dead(L, start, deg, falive, w):
    """Remove the corners of dead faces from w's list, in place (order kept)."""
    j = start[w]
    e = j + deg[w]
    for i in range(j, e):
        c = L[i]
        if falive[c // 3]:
            L[j] = c
            j += 1
    deg[w] = j - start[w]


def arena_gc(L, start, deg, n, need):
    """A fresh arena holding every vertex's list in vertex order, with room for at least
    ``need`` more corners; returns (arena, used length)."""
    live = 0
    for w in range(n):
        live += deg[w]
    L2 = np.empty(2 * live + need + 1024, dtype=np.int32)
    e = 0
    for w in range(n):
        s0 = start[w]
        d = deg[w]
        for i in range(d):
            L2[e + i] = L[s0 + i]
        start[w] = e
        e += d
    return L2, e


def tri_quality(ax, ay, az, bx, by, bz, cx, cy, cz):
    """Normal (unnormalised, twice the area) and quality 4 sqrt(3) A / sum(l^2) in [0, 1]."""
    e1x, e1y, e1z = bx - ax, by - ay, bz - az
    e2x, e2y, e2z = cx - ax, cy - ay, cz - az
    e3x, e3y, e3z = cx - bx, cy - by, cz - bz
    nx = e1y * e2z - e1z * e2y
    ny = e1z * e2x - e1x * e2z
    nz = e1x * e2y - e1y * e2x
    dbl = math.sqrt(nx * nx + ny * ny + nz * nz)
    s = (e1x * e1x + e1y * e1y + e1z * e1z + e2x * e2x + e2y * e2y + e2z * e2z
         + e3x * e3x + e3y * e3y + e3z * e3z)
    q = 0.0
    if s > 0.0:
        q = 2.0 * math.sqrt(3.0) * dbl / s
    return nx, ny, nz, dbl, q


def face_after(V, F, f, k, px, py, pz, cos_max):
    """Face f with its corner k moved to p: (rejected, new quality).

    Rejected when its normal turns by more than acos(cos_max) or its area vanishes. The old
    face's quality is not computed here (only needed when the new one is poor: `face_quality`).
    """
    i0 = F[f, 0]
    i1 = F[f, 1]
    i2 = F[f, 2]
    ax, ay, az = V[i0, 0], V[i0, 1], V[i0, 2]
    bx, by, bz = V[i1, 0], V[i1, 1], V[i1, 2]
    cx, cy, cz = V[i2, 0], V[i2, 1], V[i2, 2]
    e1x, e1y, e1z = bx - ax, by - ay, bz - az
    e2x, e2y, e2z = cx - ax, cy - ay, cz - az
    onx = e1y * e2z - e1z * e2y
    ony = e1z * e2x - e1x * e2z
    onz = e1x * e2y - e1y * e2x
    if k == 0:
        ax, ay, az = px, py, pz
    elif k == 1:
        bx, by, bz = px, py, pz
    else:
        cx, cy, cz = px, py, pz
    nnx, nny, nnz, ndbl, qn = tri_quality(ax, ay, az, bx, by, bz, cx, cy, cz)
    oo = onx * onx + ony * ony + onz * onz
    bad = False
    if oo > 0.0:
        if ndbl <= 0.0:
            bad = True
        elif onx * nnx + ony * nny + onz * nnz < cos_max * math.sqrt(oo) * ndbl:
            bad = True
    return bad, qn


def face_quality(V, F, f):
    i0 = F[f, 0]
    i1 = F[f, 1]
    i2 = F[f, 2]
    _, _, _, _, q = tri_quality(V[i0, 0], V[i0, 1], V[i0, 2], V[i1, 0], V[i1, 1], V[i1, 2],
                                V[i2, 0], V[i2, 1], V[i2, 2])
    return q


def min_quality_around(V, F, L, start, deg, u, v):
    """Worst face quality among the faces of u and v (before the collapse)."""
    q = INF
    for side in range(2):
        w = u if side == 0 else v
        for i in range(start[w], start[w] + deg[w]):
            q = min(q, face_quality(V, F, L[i] // 3))
    return q


def can_collapse(V, F, L, start, deg, bnd, tag, token, u, v, px, py, pz,
                 cos_max, q_min):
    """Topological (link condition) and geometric (normal flip, needle) tests of u <- v at p.

    Returns 0 when the collapse is allowed, else a reason code: 1 link condition / non-manifold
    result, 2 would shrink a closed fan below a tetrahedron (or orphan a vertex), 3 normal
    flip beyond the threshold, 4 needle below the quality threshold. One walk over the faces
    of u and one over those of v do both the link and the geometric tests.
    """
    qnew = INF
    # --- faces of u: tag u's neighbours, find the faces shared with v and their apexes
    n_uv = 0
    o0 = -1
    o1 = -1
    for i in range(start[u], start[u] + deg[u]):
        c = L[i]
        f = c // 3
        i0 = F[f, 0]
        i1 = F[f, 1]
        i2 = F[f, 2]
        tag[i0] = token
        tag[i1] = token
        tag[i2] = token
        if i0 == v or i1 == v or i2 == v:
            n_uv += 1
            if n_uv == 1:
                o0 = i0 + i1 + i2 - u - v
            elif n_uv == 2:
                o1 = i0 + i1 + i2 - u - v
            else:
                return 1
        else:
            bad, qn = face_after(V, F, f, c % 3, px, py, pz, cos_max)
            if bad:
                return 3
            qnew = min(qnew, qn)
    if n_uv == 0:
        return 1
    if n_uv == 2 and bnd[u] and bnd[v]:
        return 1
    # --- faces of v: common neighbours of u and v must be exactly the apexes
    common = 0
    for i in range(start[v], start[v] + deg[v]):
        c = L[i]
        f = c // 3
        i0 = F[f, 0]
        i1 = F[f, 1]
        i2 = F[f, 2]
        for k in range(3):
            w = F[f, k]
            if w != v and w != u and tag[w] == token:
                tag[w] = token + 1
                common += 1
        if not (i0 == u or i1 == u or i2 == u):
            bad, qn = face_after(V, F, f, c % 3, px, py, pz, cos_max)
            if bad:
                return 3
            qnew = min(qnew, qn)
    if common != n_uv:
        return 1
    if qnew < q_min and qnew < min_quality_around(V, F, L, start, deg, u, v):
        return 4
    # --- the apexes must keep a valid fan
    for j in range(n_uv):
        w = o0 if j == 0 else o1
        cnt = deg[w]
        if cnt <= 1 or ((not bnd[w]) and cnt <= 3):
            return 2
    return 0


def push_ring(Q, V, F, L, start, deg, bnd, stamp, tag, token, u, H, hn, P, pn, tau,
              cond_max, dist_max, fix_boundary):
    """Queue the collapses of every edge (u, w) of u's ring; returns the new (heap size,
    pool size). The caller guarantees capacity for 2 valence(u) more entries in each.
    """
    for i in range(start[u], start[u] + deg[u]):
        f = L[i] // 3
        for k in range(3):
            w = F[f, k]
            if w != u and tag[w] != token:
                tag[w] = token
                hn, pn = push_edge(Q, V, bnd, stamp, u, w, H, hn, P, pn, tau, cond_max,
                                   dist_max, fix_boundary)
    return hn, pn


def edge_cost(Q, V, bnd, a, b, cond_max, dist_max, fix_boundary):
    """(survivor, removed, error) of collapsing edge (a, b); error inf if it is not allowed.

    With ``fix_boundary`` a boundary vertex never moves: an edge with one boundary end keeps
    that end (error = the summed quadric at its position) and an edge with two is never
    collapsed.
    """
    if fix_boundary:
        if bnd[a] and bnd[b]:
            return a, b, INF
        if bnd[b]:
            a, b = b, a
        if bnd[a]:
            x, y, z = V[a, 0], V[a, 1], V[a, 2]
            err = 0.0
            for j in range(2):
                w = a if j == 0 else b
                err += (Q[w, 0] * x * x + Q[w, 3] * y * y + Q[w, 5] * z * z
                        + 2.0 * (Q[w, 1] * x * y + Q[w, 2] * x * z + Q[w, 4] * y * z)
                        + 2.0 * (Q[w, 6] * x + Q[w, 7] * y + Q[w, 8] * z) + Q[w, 9])
            return a, b, max(err, 0.0)
    _, _, _, err = place(Q, V, a, b, cond_max, dist_max)
    return a, b, err


def push_edge(Q, V, bnd, stamp, a, b, H, hn, P, pn, tau, cond_max, dist_max, fix_boundary):
    """Queue the collapse of edge (a, b) (survivor chosen by `edge_cost`): into the heap if
    its key code is <= tau, else appended to the pool. Returns (heap size, pool size)."""
    a, b, err = edge_cost(Q, V, bnd, a, b, cond_max, dist_max, fix_boundary)
    if err == INF:
        return hn, pn
    code = key_code(err)
    w0 = (code << 30) | (stamp[a] + stamp[b])
    w1 = (a << 32) | b
    if code <= tau:
        heap_push(H, hn, w0, w1)
        return hn + 1, pn
    P[2 * pn] = w0
    P[2 * pn + 1] = w1
    return hn, pn + 1


def placement_of(Q, V, bnd, u, v, cond_max, dist_max, fix_boundary):
    if fix_boundary and bnd[u]:
        return V[u, 0], V[u, 1], V[u, 2]
    px, py, pz, _ = place(Q, V, u, v, cond_max, dist_max)
    return px, py, pz


# ----------------------------------------------------------------------------- main loop
def workspace(n, m):
    """Arrays of the collapse loop for n vertices and m faces, allocated by numpy (which
    advises huge pages for large arrays; numba's allocator does not): the corner-list arena
    L (2 x 3m), start (n,), deg (n,), falive (m,), stamp (n,), tag (n,)."""
    return (np.empty(6 * m + 1024, dtype=np.int32), np.empty(n, dtype=np.int64),
            np.zeros(n, dtype=np.int32), np.ones(m, dtype=np.bool_), np.zeros(n, dtype=np.int64),
            np.zeros(n, dtype=np.int64))


def build_lists(F, L, start, deg):
    """Per-vertex corner lists in one arena: vertex v's corners, in increasing order, are
    ``L[start[v] : start[v] + deg[v]]`` (filled in place; deg must be zero)."""
    m = F.shape[0]
    n = start.shape[0]
    for c in range(3 * m):
        deg[F[c // 3, c % 3]] += 1
    e = 0
    for v in range(n):
        start[v] = e
        e += deg[v]
    for c in range(3 * m):
        v = F[c // 3, c % 3]
        L[start[v]] = c
        start[v] += 1
    for v in range(n):
        start[v] -= deg[v]


def collapse_loop(V, F, Q, bnd, E, L, start, deg, falive, stamp, tag, target, cos_stages,
                  q_stages, cond_max, dist_max, fix_boundary):
    """Collapse edges in order of quadric error until ``target`` faces remain.

    ``V``, ``F``, ``Q``, ``bnd`` and the `workspace` arrays (lists filled by `build_lists`) are
    modified in place. ``E`` (e, 2) are the initial edges. ``cos_stages``/``q_stages``:
    geometric thresholds of successive stages. A round ends when the queue empties; the next
    round re-queues every live edge (rejected collapses may have become valid): the same stage
    once more if the round made progress, else the next stage. The loop stops at the target or
    when no stage is left.

    Returns (falive, n_faces, n_collapses, stage reached, rejections per reason (5,)).
    """
    n = V.shape[0]
    m = F.shape[0]
    token = 1
    nfaces = m
    ncoll = 0
    reasons = np.zeros(5, dtype=np.int64)
    ae = 3 * m               # used length of the arena (lists are appended at the end)

    pcap = max(64, E.shape[0] + E.shape[0] // 2)
    P = np.empty(2 * pcap, dtype=np.int64)
    pn = 0
    hcap = HEAP_K + HEAP_K // 2
    H = heap_alloc(hcap)
    hn = 0
    tau = -1

    stage = 0
    rounds = 0
    rounds_at_stage = 0
    nstages = cos_stages.shape[0]
    while stage < nstages and nfaces > target:
        cos_max = cos_stages[stage]
        q_min = q_stages[stage]
        # (re)build the queue from all live edges (the initial E, later every face's
        # edges, interior ones twice: the duplicate is harmless), heapified bottom-up
        need = E.shape[0] if rounds == 0 else 3 * nfaces
        if need + 64 > pcap:
            pcap = need + need // 2 + 64
            P = np.empty(2 * pcap, dtype=np.int64)
        hn = 0
        pn = 0
        tau = -1
        nedge = E.shape[0] if rounds == 0 else 3 * m
        for i in range(nedge):
            if rounds == 0:
                a = E[i, 0]
                b = E[i, 1]
            else:
                f = i // 3
                if not falive[f]:
                    continue
                a = F[f, i % 3]
                b = F[f, (i + 1) % 3]
            a, b, err = edge_cost(Q, V, bnd, a, b, cond_max, dist_max, fix_boundary)
            if err != INF:
                P[2 * pn] = (key_code(err) << 30) | (stamp[a] + stamp[b])
                P[2 * pn + 1] = (a << 32) | b
                pn += 1
        next_compact = pn + pn // 4 + 4096

        done_in_stage = 0
        while nfaces > target:
            if hn == 0:
                if pn == 0:
                    break
                tau = pool_threshold(P, pn, max(HEAP_K, pn // 10))
                H, hcap, hn, pn = refill(H, hcap, P, pn, tau, stamp)
                next_compact = pn + pn // 4 + 4096
                continue
            s = H[HB] & SMASK
            uv = H[HB + 1]
            hn -= 1
            if hn > 0:
                heap_sift_down(H, hn, 0, H[HB + 2 * hn], H[HB + 2 * hn + 1])
                # the next entry to pop (unless a push undercuts it): start loading its ends
                nuv = H[HB + 1]
                prefetch_ends(V, Q, start, deg, stamp, nuv >> 32, nuv & 0xFFFFFFFF)
            u = uv >> 32
            v = uv & 0xFFFFFFFF
            if s != stamp[u] + stamp[v]:
                continue  # stale entry (a dead vertex has a hugely negative stamp)
            prefetch_ring(V, Q, F, L, start, deg, tag, stamp, u, v)
            px, py, pz = placement_of(Q, V, bnd, u, v, cond_max, dist_max, fix_boundary)
            token += 2
            why = can_collapse(V, F, L, start, deg, bnd, tag, token, u, v, px, py, pz,
                               cos_max, q_min)
            if why != 0:
                reasons[why] += 1
                continue
            # --- collapse v into u at p
            V[u, 0] = px
            V[u, 1] = py
            V[u, 2] = pz
            for j in range(10):
                Q[u, j] += Q[v, j]
            if ae + deg[u] + deg[v] > L.shape[0]:
                L, ae = arena_gc(L, start, deg, n, deg[u] + deg[v])
            # u's new list (at the end of the arena): v's corners off the edge's faces
            # (rewritten to u), then u's corners off those faces; the faces of the edge die
            # and leave their third vertices' lists
            e = ae
            for i in range(start[v], start[v] + deg[v]):
                c = L[i]
                f = c // 3
                if F[f, 0] == u or F[f, 1] == u or F[f, 2] == u:
                    falive[f] = False
                    nfaces -= 1
                else:
                    F[f, c % 3] = u
                    L[e] = c
                    e += 1
            for i in range(start[u], start[u] + deg[u]):
                c = L[i]
                if falive[c // 3]:
                    L[e] = c
                    e += 1
            for i in range(start[v], start[v] + deg[v]):
                f = L[i] // 3
                if not falive[f]:
                    for k in range(3):
                        w = F[f, k]
                        if w != u and w != v:
                            drop_dead(L, start, deg, falive, w)
            start[u] = ae
            deg[u] = e - ae
            ae = e
            deg[v] = 0
            stamp[v] = DEAD
            stamp[u] += 1
            if bnd[v]:
                bnd[u] = True
            ncoll += 1
            done_in_stage += 1
            val = deg[u]
            if pn > next_compact:
                pn = pool_compact(P, pn, stamp)
                next_compact = pn + pn // 4 + 4096
            if hn + 2 * val + 4 > hcap:
                hcap = 2 * hcap
                H = heap_grow(H, hn, hcap)
            if pn + 2 * val + 4 > pcap:
                pcap = 2 * pcap
                P = grow_pool(P, pn, pcap)
            token += 2
            hn, pn = push_ring(Q, V, F, L, start, deg, bnd, stamp, tag, token, u, H, hn,
                               P, pn, tau, cond_max, dist_max, fix_boundary)
        rounds += 1
        rounds_at_stage += 1
        if done_in_stage == 0 or rounds_at_stage >= 2:
            stage += 1
            rounds_at_stage = 0
    return falive, nfaces, ncoll, stage, reasons


# explicit signatures for the helpers: one specialisation each (numba would otherwise
# compile separate versions for int32/int64/literal arguments, doubling the compile time)
_SIGS = {
    "place": "UniTuple(f8, 4)(f8[:, ::1], f8[:, ::1], i8, i8, f8, f8)",
    "key_code": "i8(f8)",
    "heap_alloc": "i8[::1](i8)",
    "heap_sift_down": "void(i8[::1], i8, i8, i8, i8)",
    "heap_push": "void(i8[::1], i8, i8, i8)",
    "heap_grow": "i8[::1](i8[::1], i8, i8)",
    "pool_compact": "i8(i8[::1], i8, i8[::1])",
    "pool_threshold": "i8(i8[::1], i8, i8)",
    "refill": "Tuple((i8[::1], i8, i8, i8))(i8[::1], i8, i8[::1], i8, i8, i8[::1])",
    "grow_pool": "i8[::1](i8[::1], i8, i8)",
    "drop_dead": "void(i4[::1], i8[::1], i4[::1], b1[::1], i8)",
    "arena_gc": "Tuple((i4[::1], i8))(i4[::1], i8[::1], i4[::1], i8, i8)",
    "tri_quality": "UniTuple(f8, 5)(f8, f8, f8, f8, f8, f8, f8, f8, f8)",
    "face_after": "Tuple((b1, f8))(f8[:, ::1], i8[:, ::1], i8, i8, f8, f8, f8, f8)",
    "face_quality": "f8(f8[:, ::1], i8[:, ::1], i8)",
    "min_quality_around": "f8(f8[:, ::1], i8[:, ::1], i4[::1], i8[::1], i4[::1], i8, i8)",
    "edge_cost": "Tuple((i8, i8, f8))(f8[:, ::1], f8[:, ::1], b1[::1], i8, i8, f8, f8, b1)",
    "placement_of": "UniTuple(f8, 3)(f8[:, ::1], f8[:, ::1], b1[::1], i8, i8, f8, f8, b1)",
    "build_lists": "void(i8[:, ::1], i4[::1], i8[::1], i4[::1])",
}
_JIT_ORDER = ("place", "key_code", "heap_alloc", "heap_sift_down", "heap_push", "heap_grow",
              "pool_compact", "pool_threshold", "refill", "grow_pool", "prefetch_ring",
              "prefetch_ends", "drop_dead", "arena_gc",
              "tri_quality", "face_after", "face_quality", "min_quality_around",
              "can_collapse", "edge_cost", "push_edge", "push_ring", "placement_of",
              "build_lists", "collapse_loop")


@functools.lru_cache(maxsize=None)
def kernel():
    """Compile (or load from numba's on-disk cache); returns (`build_lists`, `collapse_loop`)
    (`workspace`, plain numpy, allocates their arrays)."""
    import numba

    g = globals()
    g["prefetch"] = _prefetch_intrinsic()
    for name in _JIT_ORDER:
        if name in _SIGS:
            g[name] = numba.njit(_SIGS[name], cache=True)(g[name])
        else:
            g[name] = numba.njit(cache=True)(g[name])
    return g["build_lists"], g["collapse_loop"]
