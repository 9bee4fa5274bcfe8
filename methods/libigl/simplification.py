"""libigl's edge-collapse decimation: ``igl.qslim`` (quadric error) and ``igl.decimate``
(shortest edge first, midpoint placement).

The library is imported lazily so a missing install makes the methods `unavailable`.
"""
from __future__ import annotations

import numpy as np

from methods import SimplificationResult, register


def oriented_manifold(V, F, name) -> None:
    """``precheck`` of libigl's collapse loops: they walk the half-edge structure and need every
    edge on at most two faces traversed in opposite directions (with a third of a sphere's faces
    reversed, ``qslim`` allocated until the machine ran out of memory; on an edge of three faces
    it returned an empty mesh)."""
    from harness.core.geometry import orientation_problem
    why = orientation_problem(np.asarray(F))
    if why:
        raise ValueError(f"{name}: {why}: libigl's decimation needs a consistently oriented edge-manifold mesh")


@register("libigl.qslim", task="simplification", library="libigl", params={},
          requires=("igl",), precheck=oriented_manifold)
def qslim(V, F, *, target_faces):
    """libigl's QSlim (Garland & Heckbert 1997) edge collapse.

    Per-vertex quadrics from the incident face planes in the formulation of Garland &
    Heckbert's follow-up, "Simplifying surfaces with color and texture using quadric error
    metrics" (1998; libigl's ``per_vertex_point_to_plane_quadrics``), with the boundary closed by
    faces to points at infinity (``connect_boundary_to_infinity``), which give boundary edges
    quadrics of their own (a boundary-preserving term, fixed: no weight to set, unlike
    ``scratch.qem``'s ``boundary_weight`` or MeshLab's ``preserve_boundary``); edge cost =
    quadric error at the optimal placement (minimiser of the summed quadric); a heap with lazy
    invalidation; collapses that would break the link condition are skipped.

    Parameters
    ----------
    V : (n, 3) float64 array
    F : (m, 3) int64 array (passed as int32, which the binding requires)
    target_faces : int
        ``max_m``.

    Returns
    -------
    SimplificationResult
        As the library returns it; the task drops unreferenced vertices (untimed).
    """
    import igl

    U, G, _, _ = igl.qslim(V, F.astype(np.int32), int(target_faces))
    return SimplificationResult(V=U, F=G)


@register("libigl.decimate", task="simplification", library="libigl", params={},
          requires=("igl",), precheck=oriented_manifold)
def decimate(V, F, *, target_faces):
    """libigl's ``decimate``: collapse the shortest edge first, new vertex at the midpoint.

    A baseline with no error metric: cost = edge length, placement = midpoint.

    Parameters
    ----------
    V : (n, 3) float64 array
    F : (m, 3) int64 array (passed as int32)
    target_faces : int
        ``max_m``.

    Returns
    -------
    SimplificationResult
        As the library returns it; the task drops unreferenced vertices (untimed).
    """
    import igl

    U, G, _, _ = igl.decimate(V, F.astype(np.int32), int(target_faces))
    return SimplificationResult(V=U, F=G)
