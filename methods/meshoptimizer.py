"""meshoptimizer's simplifier (task ``simplification``; PyPI ``meshoptimizer``).

``meshoptimizer.qem``: ``meshoptimizer.simplify`` (Kapoulkine's edge-collapse simplifier with
quadric error metrics). It collapses edges onto existing vertices, so the output keeps a subset
of the input positions (no optimal placement); it computes in single precision (positions are
handed over as float32, the output uses the caller's float64 positions of the kept vertices), and
it may leave edge-non-manifold output. ``target_error`` is its relative error limit (fraction of
the mesh extent); 1 lets the face target decide. It can stop above the target when no collapse is
allowed (the row's ``out_faces`` shows it).
"""
from __future__ import annotations

import numpy as np

from methods import Param, SimplificationResult, register


@register("meshoptimizer.qem", task="simplification", library="meshoptimizer", requires=("meshoptimizer",),
          cite="A. Kapoulkine, meshoptimizer (simplifier.cpp)",
          params={"target_error": Param("target_error", 1.0, "float", low=0.0, high=1.0,
                                        doc="relative error limit (fraction of the mesh extent)"),
                  "preserve_boundary": Param("preserve_boundary", False, "bool", id_as="lock_border",
                                             doc="keep border vertices (the library's SIMPLIFY_LOCK_BORDER)")})
def qem(V, F, *, target_faces, target_error=1.0, preserve_boundary=False):
    """``meshoptimizer.simplify`` to ``target_faces`` (module docstring)."""
    import meshoptimizer as mo
    idx = np.ascontiguousarray(F, dtype=np.uint32).ravel()
    dest = np.zeros_like(idx)
    opts = mo.SIMPLIFY_LOCK_BORDER if preserve_boundary else 0
    count = mo.simplify(dest, idx, np.ascontiguousarray(V, dtype=np.float32), target_index_count=3 * int(target_faces),
                        target_error=float(target_error), options=opts)
    from harness.core.geometry import compact
    Vo, Fo = compact(V, dest[:count].reshape(-1, 3))   # the input positions, the unused dropped (timed, as the
    return SimplificationResult(V=Vo, F=Fo)            # libraries that return a compact mesh do it in theirs)
