"""Adapters for the libigl backend (one module per task); the library is imported lazily."""

import numpy as np


def reject_zero_area(V: np.ndarray, F: np.ndarray, name: str) -> None:
    """Raise ValueError naming the zero-area faces, on which libigl's cotangent weights are
    inf/NaN (it divides by the double area); our scratch operators skip such faces instead."""
    from methods.scratch.operators import double_areas
    bad = np.flatnonzero(double_areas(V, F) == 0)
    if bad.size:
        raise ValueError(f"{name}: {bad.size} zero-area face(s) (first: {bad[:5].tolist()}); "
                         "libigl's cotangent weights are undefined there")
