"""Compiled covering bound of the certified Hausdorff distance (`harness.metrics.hausdorff`).

For a triangle ``T`` of X (unit normal ``n``, plane coordinates ``(x, y)`` and height
``h = n . (p - p_0)``) and a triangle ``t`` of Y whose projection onto the plane of ``T`` is
not degenerate, the point of ``t`` straight above or below a point ``q`` of ``T`` inside the
projection of ``t`` is at height ``h_t(q)`` (``h_t`` linear in ``(x, y)``), so
``d(q, Y) <= |h_t(q)| <= b_t = min(max_{v in t} |h_v|, max_{c corner of T} |h_t(c)|)`` (a
linear function's largest magnitude over a triangle is at a corner; the second term extends
``h_t`` linearly over ``T``). If the projections of a set ``S`` of such triangles cover ``T``,
then ``max_{q in T} d(q, Y) <= max_{t in S} b_t``.

Covering is certified without any assumption on Y (orientation, manifoldness): orient every
projected triangle of ``S`` counter-clockwise; as 2-chains, ``sum_t [q in t] =
wind(boundary(S), q)`` for ``q`` off the projected edges, where ``boundary(S)`` is the sum of
the oriented edges with shared edges (same two vertex indices, opposite directions)
cancelled. When no edge of ``boundary(S)`` meets ``T`` the winding number is constant on
``T``; if it is at least 1 at ``T``'s centroid, every point of ``T`` lies in some projected
triangle (every term is 0 or 1). Points on projected edges follow by continuity.

``T``'s frame is made orthonormal by Gram-Schmidt and the rounding residue of its corners' heights
is added to the bound; a sliver (``|u x v| <= 1e-6 |u| |v|``), whose computed normal is noise,
gets no covering bound.

This bound is tight where Y is locally a graph over the plane of ``T`` at a small height (a
coarse triangle over the finer surface it simplifies: there corner-based bounds need
subdivision down to the scale of Y's triangles); it overestimates by ``1 / cos`` of Y's tilt.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

CAP = 384                                   # most triangles of Y gathered for one triangle of X


@njit(cache=True)
def face_neighbours(F, n):
    """``N`` (m, 3): the face across edge ``(F[f, j], F[f, j+1])`` of face ``f``, or -1 where
    that edge has one face or more than two (faces ``F`` (m, 3) on vertices ``[0, n)``)."""
    m = F.shape[0]
    start = np.zeros(n + 1, np.int64)
    for f in range(m):
        for j in range(3):
            start[min(F[f, j], F[f, (j + 1) % 3]) + 1] += 1
    for i in range(n):
        start[i + 1] += start[i]
    fill = start[:-1].copy()
    slot = np.empty(3 * m, np.int64)          # half-edges grouped by their smaller vertex
    for f in range(m):
        for j in range(3):
            a = min(F[f, j], F[f, (j + 1) % 3])
            slot[fill[a]] = 3 * f + j
            fill[a] += 1
    N = np.full((m, 3), -1, np.int64)
    key = np.empty(3 * m, np.int64)
    for p in range(3 * m):                    # the larger vertex of each half-edge
        h = slot[p]
        key[p] = max(F[h // 3, h % 3], F[h // 3, (h % 3 + 1) % 3])
    for v in range(n):
        s0, s1 = start[v], start[v + 1]
        if s1 - s0 > 16:                      # sort the bucket by its larger vertex
            o = np.argsort(key[s0:s1], kind="mergesort")
            key[s0:s1] = key[s0:s1][o]
            slot[s0:s1] = slot[s0:s1][o]
        else:
            for p in range(s0 + 1, s1):       # insertion sort: buckets hold about 3 half-edges
                k, h = key[p], slot[p]
                q = p - 1
                while q >= s0 and key[q] > k:
                    key[q + 1], slot[q + 1] = key[q], slot[q]
                    q -= 1
                key[q + 1], slot[q + 1] = k, h
        p = s0
        while p < s1:                         # runs of equal edges: exactly two are neighbours
            e = p
            while e < s1 and key[e] == key[p]:
                e += 1
            if e - p == 2:
                g, h = slot[p], slot[p + 1]
                N[g // 3, g % 3] = h // 3
                N[h // 3, h % 3] = g // 3
            p = e
    return N


@njit(cache=True)
def cover_bound(P, seeds, VY, FY, NY, r, W):
    """``max_{t in S} b_t`` (module docstring), or ``inf`` when covering is not certified (or
    ``P`` (3, 3) is degenerate, or more than ``CAP`` triangles qualify). ``S`` is grown from
    ``seeds`` (faces of Y near ``P``, -1 for none) across the edges of Y (``NY``,
    `face_neighbours`) through the triangles whose projections meet ``P`` with ``b_t <= r``.
    ``W`` = `work`. Predicates carry a tolerance of ``1e-10 * size^2`` in area units on the safe
    side (a doubtful triangle is kept, a doubtful boundary edge fails the bound)."""
    seen, slot, stamp, queue, KXY, KS = W
    ux, uy, uz = P[1, 0] - P[0, 0], P[1, 1] - P[0, 1], P[1, 2] - P[0, 2]
    vx, vy, vz = P[2, 0] - P[0, 0], P[2, 1] - P[0, 1], P[2, 2] - P[0, 2]
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    lu = math.sqrt(ux * ux + uy * uy + uz * uz)
    lv = math.sqrt(vx * vx + vy * vy + vz * vz)
    if not nn > 1e-6 * lu * lv:              # a sliver: its normal is rounding noise
        return np.inf
    nx, ny, nz = nx / nn, ny / nn, nz / nn
    # an orthonormal frame (u, w, n) by Gram-Schmidt; the corners' residual heights h1, h2
    # (rounding) are added to the bound: a point q of T is |h(q)| <= max(|h1|, |h2|) off the
    # plane, so its distance to t's point along n is at most |h_t| + |h(q)|
    h1 = ux * nx + uy * ny + uz * nz
    h2 = vx * nx + vy * ny + vz * nz
    ux, uy, uz = ux - h1 * nx, uy - h1 * ny, uz - h1 * nz
    lu = math.sqrt(ux * ux + uy * uy + uz * uz)
    if lu == 0.0:
        return np.inf
    ux, uy, uz = ux / lu, uy / lu, uz / lu
    wx, wy, wz = ny * uz - nz * uy, nz * ux - nx * uz, nx * uy - ny * ux
    # T projected on its plane: (0, 0), (lu, 0), (cx, cy) with cy > 0
    cx = vx * ux + vy * uy + vz * uz
    cy = vx * wx + vy * wy + vz * wz
    if not cy > 1e-6 * lv:
        return np.inf
    margin = max(abs(h1), abs(h2)) + 1e-14 * (lu + lv)
    size = max(lu, math.sqrt(cx * cx + cy * cy)) + r
    ta = 1e-10 * size * size
    px0, py0, pz0 = P[0, 0], P[0, 1], P[0, 2]
    stamp[0] += 1
    st = stamp[0]
    nk = 0
    nq = 0
    bound = 0.0
    for i in range(seeds.size):
        f = seeds[i]
        if f >= 0 and seen[f] != st:
            seen[f] = st
            slot[f] = -1
            queue[nq] = f
            nq += 1
    qi = 0
    while qi < nq:
        f = queue[qi]
        qi += 1
        if slot[f] == -1:                    # not evaluated yet (a seed)
            slot[f] = -2
            a, b, d = FY[f, 0], FY[f, 1], FY[f, 2]
            dx, dy, dz = VY[a, 0] - px0, VY[a, 1] - py0, VY[a, 2] - pz0
            x0, y0, h0 = dx * ux + dy * uy + dz * uz, dx * wx + dy * wy + dz * wz, dx * nx + dy * ny + dz * nz
            dx, dy, dz = VY[b, 0] - px0, VY[b, 1] - py0, VY[b, 2] - pz0
            x1, y1, h1 = dx * ux + dy * uy + dz * uz, dx * wx + dy * wy + dz * wz, dx * nx + dy * ny + dz * nz
            dx, dy, dz = VY[d, 0] - px0, VY[d, 1] - py0, VY[d, 2] - pz0
            x2, y2, h2 = dx * ux + dy * uy + dz * uz, dx * wx + dy * wy + dz * wz, dx * nx + dy * ny + dz * nz
            if min(h0, h1, h2) > r or max(h0, h1, h2) < -r:
                continue                     # every point of it is farther than r from the plane
            area2 = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
            sg = 1
            if area2 < 0.0:                  # clockwise in the plane: evaluate it reversed
                sg = -1
                x1, y1, h1, x2, y2, h2 = x2, y2, h2, x1, y1, h1
                area2 = -area2
            ext = max(abs(x1 - x0), abs(x2 - x0), abs(y1 - y0), abs(y2 - y0))
            if area2 <= 1e-9 * ext * ext:
                continue                     # seen edge-on: covers nothing
            if not _overlaps(x0, y0, x1, y1, x2, y2, lu, cx, cy, ta):
                continue                     # covers no point of T (its edges then miss T too)
            bt = _clip_max(x0, y0, h0, x1, y1, h1, x2, y2, h2, area2, lu, cx, cy, ta)
            if bt > r:
                continue
            if nk >= KS.size:
                return np.inf
            if sg < 0:                       # back to the face's own vertex order
                x1, y1, x2, y2 = x2, y2, x1, y1
            KXY[nk, 0, 0], KXY[nk, 0, 1] = x0, y0
            KXY[nk, 1, 0], KXY[nk, 1, 1] = x1, y1
            KXY[nk, 2, 0], KXY[nk, 2, 1] = x2, y2
            KS[nk] = f if sg > 0 else -f - 1
            slot[f] = nk
            nk += 1
            bound = max(bound, bt)
            for j in range(3):               # grow across its edges
                g = NY[f, j]
                if g >= 0 and seen[g] != st:
                    seen[g] = st
                    slot[g] = -1
                    if nq >= queue.size:
                        return np.inf
                    queue[nq] = g
                    nq += 1
    if nk == 0:
        return np.inf
    # boundary of the chain: each kept face's edges, counter-clockwise in the plane, minus those
    # a kept neighbour traverses the other way
    wind = 0
    gx, gy = (lu + cx) / 3.0, cy / 3.0
    for k in range(nk):
        f = KS[k] if KS[k] >= 0 else -KS[k] - 1
        sg = 1 if KS[k] >= 0 else -1
        for j in range(3):
            a, b = FY[f, j], FY[f, (j + 1) % 3]
            g = NY[f, j]
            if g >= 0 and seen[g] == st and slot[g] >= 0:
                sh = 1 if KS[slot[g]] >= 0 else -1
                same = False                 # does g list the edge as a -> b too?
                for i in range(3):
                    if FY[g, i] == a and FY[g, (i + 1) % 3] == b:
                        same = True
                if (sg == sh) != same:       # opposite directions in the plane: cancelled
                    continue
            jn = (j + 1) % 3
            if sg > 0:
                ax, ay, bx, by = KXY[k, j, 0], KXY[k, j, 1], KXY[k, jn, 0], KXY[k, jn, 1]
            else:
                ax, ay, bx, by = KXY[k, jn, 0], KXY[k, jn, 1], KXY[k, j, 0], KXY[k, j, 1]
            if _meets(ax, ay, bx, by, lu, cx, cy, ta):
                return np.inf
            wind += _crossing(ax, ay, bx, by, gx, gy)
    return bound + margin if wind >= 1 else np.inf


def work(n_faces: int) -> tuple:
    """Scratch of `cover_bound` for a surface of ``n_faces`` triangles."""
    return (np.zeros(n_faces, np.int64), np.zeros(n_faces, np.int64), np.zeros(1, np.int64),
            np.empty(4 * CAP, np.int64), np.empty((CAP, 3, 2)), np.empty(CAP, np.int64))


@njit(cache=True, inline="always")
def _orient(ax, ay, bx, by, px, py):
    return (bx - ax) * (py - ay) - (by - ay) * (px - ax)


@njit(cache=True, inline="always")
def _outside(ax, ay, bx, by, x0, y0, x1, y1, x2, y2, ta):
    """All three points lie strictly right of the directed line ab (by more than ``ta``)."""
    return (_orient(ax, ay, bx, by, x0, y0) < -ta and _orient(ax, ay, bx, by, x1, y1) < -ta
            and _orient(ax, ay, bx, by, x2, y2) < -ta)


@njit(cache=True)
def _overlaps(x0, y0, x1, y1, x2, y2, lu, cx, cy, ta):
    """The counter-clockwise triangles (x0, y0), (x1, y1), (x2, y2) and T = (0, 0), (lu, 0),
    (cx, cy) may meet: no edge of either separates them (separating axes; touching, or
    doubt within ``ta``, counts as meeting)."""
    if (_outside(0.0, 0.0, lu, 0.0, x0, y0, x1, y1, x2, y2, ta)
            or _outside(lu, 0.0, cx, cy, x0, y0, x1, y1, x2, y2, ta)
            or _outside(cx, cy, 0.0, 0.0, x0, y0, x1, y1, x2, y2, ta)):
        return False
    return not (_outside(x0, y0, x1, y1, 0.0, 0.0, lu, 0.0, cx, cy, ta)
                or _outside(x1, y1, x2, y2, 0.0, 0.0, lu, 0.0, cx, cy, ta)
                or _outside(x2, y2, x0, y0, 0.0, 0.0, lu, 0.0, cx, cy, ta))


@njit(cache=True)
def _clip_max(x0, y0, h0, x1, y1, h1, x2, y2, h2, area2, lu, cx, cy, ta):
    """``max |h_t|`` over the projection of t (counter-clockwise (x_i, y_i), heights h_i, doubled
    area ``area2``) intersected with T = (0, 0), (lu, 0), (cx, cy): the largest magnitude of a
    linear function over a convex polygon is at one of its corners, which are t's corners in
    T, T's corners in t and crossings of their edges. Inclusion tests are inclusive within
    ``ta`` (a point taken in excess only raises the value)."""
    X = (x0, x1, x2)
    Y = (y0, y1, y2)
    Hh = (h0, h1, h2)
    TX = (0.0, lu, cx)
    TY = (0.0, 0.0, cy)
    w = 0.0
    for i in range(3):                       # t's corners inside T
        if (_orient(0.0, 0.0, lu, 0.0, X[i], Y[i]) >= -ta and _orient(lu, 0.0, cx, cy, X[i], Y[i]) >= -ta
                and _orient(cx, cy, 0.0, 0.0, X[i], Y[i]) >= -ta):
            w = max(w, abs(Hh[i]))
    for c in range(3):                       # T's corners inside t: h_t by barycentric coordinates
        qx, qy = TX[c], TY[c]
        o0 = _orient(x1, y1, x2, y2, qx, qy)
        o1 = _orient(x2, y2, x0, y0, qx, qy)
        o2 = _orient(x0, y0, x1, y1, qx, qy)
        if o0 >= -ta and o1 >= -ta and o2 >= -ta:
            w = max(w, abs((o0 * h0 + o1 * h1 + o2 * h2) / area2))
    for i in range(3):                       # crossings of t's edge i, i+1 with T's edges
        px, py, ph = X[i], Y[i], Hh[i]
        qx, qy, qh = X[(i + 1) % 3], Y[(i + 1) % 3], Hh[(i + 1) % 3]
        for e in range(3):
            ax, ay, bx, by = TX[e], TY[e], TX[(e + 1) % 3], TY[(e + 1) % 3]
            d1 = _orient(ax, ay, bx, by, px, py)
            d2 = _orient(ax, ay, bx, by, qx, qy)
            d3 = _orient(px, py, qx, qy, ax, ay)
            d4 = _orient(px, py, qx, qy, bx, by)
            if not (min(d1, d2) <= ta and max(d1, d2) >= -ta and min(d3, d4) <= ta and max(d3, d4) >= -ta):
                continue
            if d1 == d2:                     # parallel: the overlap lies within pq
                w = max(w, abs(ph), abs(qh))
            else:
                s = min(1.0, max(0.0, d1 / (d1 - d2)))
                w = max(w, abs(ph + s * (qh - ph)))
    return w


@njit(cache=True)
def _meets(ax, ay, bx, by, lu, cx, cy, ta):
    """The segment ab meets T = (0, 0), (lu, 0), (cx, cy) (counter-clockwise) or passes within
    about ``ta`` of it (on the safe side): no edge of T and not the line ab separates them."""
    if (_outside(0.0, 0.0, lu, 0.0, ax, ay, bx, by, bx, by, ta)
            or _outside(lu, 0.0, cx, cy, ax, ay, bx, by, bx, by, ta)
            or _outside(cx, cy, 0.0, 0.0, ax, ay, bx, by, bx, by, ta)):
        return False
    o0 = _orient(ax, ay, bx, by, 0.0, 0.0)
    o1 = _orient(ax, ay, bx, by, lu, 0.0)
    o2 = _orient(ax, ay, bx, by, cx, cy)
    return not ((o0 < -ta and o1 < -ta and o2 < -ta) or (o0 > ta and o1 > ta and o2 > ta))


@njit(cache=True, inline="always")
def _crossing(ax, ay, bx, by, px, py):
    """Contribution of the directed segment ab to the winding number around p."""
    if ay <= py:
        if by > py and _orient(ax, ay, bx, by, px, py) > 0.0:
            return 1
    elif by <= py and _orient(ax, ay, bx, by, px, py) < 0.0:
        return -1
    return 0
