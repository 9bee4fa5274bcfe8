"""Symmetric Hausdorff distance between two triangle meshes, from vertices and samples."""
import numpy as np

from ..core.geometry import sample_surface
from .surface_distance import point_surface_distance


def hausdorff(VA, FA, VB, FB, n_samples: int = 20000, seed: int = 0) -> dict:
    """``hausdorff`` = max(h(A, B), h(B, A)), h(X, Y) = max over the vertices of X and
    ``n_samples`` area-uniform points of X of the exact distance to surface Y.
    ``dist_mean`` = mean of those point distances over both directions (a symmetric mean
    surface distance). Input units; the caller divides by the diagonal.
    """
    PA = np.concatenate([VA, sample_surface(VA, FA, n_samples, seed)])
    PB = np.concatenate([VB, sample_surface(VB, FB, n_samples, seed + 1)])
    dab = point_surface_distance(PA, VB, FB)
    dba = point_surface_distance(PB, VA, FA)
    return {"hausdorff": float(max(dab.max(), dba.max())),
            "hausdorff_ab": float(dab.max()), "hausdorff_ba": float(dba.max()),
            "dist_mean": float(np.concatenate([dab, dba]).mean())}
