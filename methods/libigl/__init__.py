"""Adapters for the libigl backend (one module per task); the library is imported lazily."""

import numpy as np


def reject_zero_area(V: np.ndarray, F: np.ndarray, name: str) -> None:
    """Raise ValueError naming the zero-area faces, on which libigl's cotangent weights are
    inf/NaN (it divides by the double area); our scratch operators skip such faces instead.
    The libigl adapters declare it as their ``precheck`` (run untimed before every call).

    A face counts as zero-area when either its cross product or, as libigl computes it,
    Kahan's Heron formula on its edge lengths gives 0 (a numerically flat face can have a
    cross-product area of 1e-20 and a Heron area of exactly 0).
    """
    refuse_zero_area(V, F, name, "libigl's cotangent weights are undefined there")


def refuse_zero_area(V: np.ndarray, F: np.ndarray, name: str, why: str) -> None:
    """ValueError naming the zero-area faces (`harness.core.geometry.zero_area_faces`) and ``why``
    the library cannot take them; the shared body of the zero-area prechecks."""
    from harness.core.geometry import zero_area_faces
    bad = zero_area_faces(V, F)
    if bad.size:
        raise ValueError(f"{name}: {bad.size} zero-area face(s) (first: {bad[:5].tolist()}); {why}")


def reject_zero_area_or_unreferenced(V: np.ndarray, F: np.ndarray, name: str) -> None:
    """`reject_zero_area`, and a ValueError for vertices no face uses (libigl sizes its matrices
    by the largest index in F, and its heat precomputation fails or crashes on them); a run's
    inputs never have them (they are dropped when the mesh is loaded)."""
    reject_zero_area(V, F, name)
    from harness.core.geometry import referenced
    unused = np.flatnonzero(~referenced(np.asarray(F), len(V)))
    if unused.size:
        raise ValueError(f"{name}: {unused.size} vertices no face uses (first: {unused[:5].tolist()}); "
                         "drop them first (harness.core.geometry.compact)")


def check_finite(A, V: np.ndarray, F: np.ndarray, name: str) -> None:
    """Raise ValueError naming the faces when a libigl matrix came back with inf/NaN entries."""
    import scipy.sparse as sp
    data = A.data if sp.issparse(A) else np.asarray(A)        # any sparse format: no conversion
    if np.isfinite(data).all():
        return
    import igl
    C = np.asarray(igl.cotmatrix_entries(V, F))
    bad = np.flatnonzero(~np.isfinite(C).all(axis=1))
    raise ValueError(f"{name}: libigl returned {int((~np.isfinite(data)).sum())} non-finite entries "
                     f"from {bad.size} degenerate face(s) (first: {bad[:5].tolist()})")
