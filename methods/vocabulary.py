"""Parameters shared by several backends, declared once (one name per concept; each adapter
maps it to its library's own spelling)."""
from __future__ import annotations

from harness.core.params import Param
from harness.core.solvers import SOLVER_CHOICES


def solver_param() -> Param:
    """``solver``: the sparse SPD direct solver of `harness.core.solvers` (``auto`` by default)."""
    return Param("solver", "auto", choices=SOLVER_CHOICES,
                 doc="sparse SPD solver: auto (fastest installed, see harness/core/solvers.py) or a backend name")


def preserve_boundary_param(doc: str = "keep boundary vertices and edges in place") -> Param:
    """``preserve_boundary``: whether boundary vertices may move or be removed."""
    return Param("preserve_boundary", False, "bool", doc=doc)


BOUNDARY_RULES = ("free", "fixed", "curve")


def boundary_rule_param() -> Param:
    """``boundary``: how a smoothing operator treats boundary vertices (open meshes).

    ``free``: boundary rows of the operator as built from the mesh (one-sided neighbourhoods);
    ``fixed``: boundary vertices do not move; ``curve``: boundary vertices move along the
    boundary curve only, averaging themselves with their boundary-edge neighbours (the rule of
    VCGLib/MeshLab's Laplacian and Taubin filters).
    """
    return Param("boundary", "free", choices=BOUNDARY_RULES,
                 doc="boundary vertices: free (mesh operator rows), fixed (do not move), curve "
                     "(average with boundary-edge neighbours only, as MeshLab)")
