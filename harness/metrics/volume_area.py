"""Enclosed volume and surface area."""
import numpy as np


def area(V: np.ndarray, F: np.ndarray) -> float:
    """Total surface area: sum_f |(v1 - v0) x (v2 - v0)| / 2."""
    return float(np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1).sum() / 2)


def volume(V: np.ndarray, F: np.ndarray) -> float:
    """Signed enclosed volume by the divergence theorem: sum_f v0 . (v1 x v2) / 6 (closed meshes)."""
    return float(np.einsum("ij,ij->i", V[F[:, 0]], np.cross(V[F[:, 1]], V[F[:, 2]])).sum() / 6.0)
