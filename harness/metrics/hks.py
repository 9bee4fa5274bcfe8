"""The heat kernel signature (Sun, Ovsjanikov & Guibas 2009, "A concise and provably informative
multi-scale signature based on heat diffusion", SGP).

``HKS(x, t) = k_t(x, x) = sum_i exp(-lambda_i t) phi_i(x)^2`` over the eigenpairs of
``-W phi = lambda M phi`` with M-orthonormal ``phi`` (units: 1/area; ``t`` in length^2). With
``k`` pairs the sum is truncated; the paper samples ``t`` log-uniformly in
``[4 ln 10 / lambda_max, 4 ln 10 / lambda_1]`` (``lambda_1`` the smallest non-zero
eigenvalue), where the first dropped term is at most ``10^-4`` of the constant term's weight.
On the sphere of radius ``r`` the HKS is constant over the surface:
``sum_l (2 l + 1) / (4 pi r^2) exp(-l (l + 1) t / r^2)`` (addition theorem of spherical
harmonics).
"""
from __future__ import annotations

import math

import numpy as np


def hks_times(lam: np.ndarray, count: int = 4) -> np.ndarray:
    """``count`` times log-spaced in ``[4 ln 10 / lambda_max, 4 ln 10 / lambda_1]`` (ascending);
    empty when there is no positive eigenvalue."""
    lam = np.asarray(lam, dtype=np.float64)
    pos = lam[lam > 1e-9 * max(float(np.abs(lam).max()), 1e-300)] if lam.size else lam
    if pos.size == 0:
        return np.zeros(0)
    lo, hi = 4 * math.log(10) / pos.max(), 4 * math.log(10) / pos.min()
    return np.geomspace(lo, hi, count) if hi > lo else np.array([lo])


def heat_kernel_signature(lam: np.ndarray, Phi: np.ndarray, times: np.ndarray) -> np.ndarray:
    """``HKS`` (n, len(times)) from eigenvalues (k,) and M-orthonormal eigenvectors (n, k)."""
    E = np.exp(-np.outer(np.maximum(np.asarray(lam, dtype=np.float64), 0.0), np.asarray(times, dtype=np.float64)))
    return (np.asarray(Phi) ** 2) @ E


def sphere_hks(times: np.ndarray, radius: float = 1.0) -> np.ndarray:
    """The exact HKS of the round sphere (constant over it) at each time, summed until the
    terms drop below 1e-17 of the total."""
    out = []
    for t in np.asarray(times, dtype=np.float64):
        s, l = 0.0, 0
        while True:
            term = (2 * l + 1) / (4 * math.pi * radius ** 2) * math.exp(-l * (l + 1) * t / radius ** 2)
            s += term
            if l > 0 and term < 1e-17 * s:
                break
            l += 1
        out.append(s)
    return np.asarray(out)
