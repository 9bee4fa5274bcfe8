"""Noise models. sigma = level x mean edge length of the clean mesh; seeded and bit-reproducible.

- ``gaussian_normal``: every vertex moves by sigma * g along its area-weighted vertex normal
  (sum of the incident faces' cross products, normalised), g ~ N(0, 1);
- ``gaussian_random``: every vertex moves by sigma * g along a uniformly random unit direction;
- ``impulsive``: a seeded ``fraction`` of the vertices moves by sigma * g along its normal;
- ``none``: the clean mesh itself.
The generator is numpy's PCG64 seeded from (seed, a stable hash of mesh key, model and level),
so the same (mesh, model, level, seed) gives the same coordinates in any process or machine.
"""
from __future__ import annotations

import hashlib

import numpy as np

from .mesh import mean_edge_length

MODELS = ("gaussian_normal", "gaussian_random", "impulsive", "none")


def vertex_normals(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals (n, 3); zero for vertices with no area around them."""
    C = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])   # 2 x area x unit normal
    idx = F.ravel()
    CC = np.repeat(C, 3, axis=0)
    N = np.stack([np.bincount(idx, weights=CC[:, j], minlength=len(V)) for j in range(3)], 1)
    nrm = np.linalg.norm(N, axis=1, keepdims=True)
    return np.divide(N, nrm, out=np.zeros_like(N), where=nrm > 0)


def rng_for(mesh_key: str, model: str, level: float, seed: int) -> np.random.Generator:
    """A generator determined only by its arguments (stable across processes and platforms)."""
    digest = hashlib.sha256(f"{mesh_key}|{model}|{float(level)!r}".encode()).digest()
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(
        [int(seed) & 0xFFFFFFFF, int.from_bytes(digest[:8], "little")])))


def apply_noise(V: np.ndarray, F: np.ndarray, model: str, level: float, seed: int,
                mesh_key: str = "", fraction: float = 1.0) -> np.ndarray:
    """Noisy copy of ``V`` (n, 3) under ``model`` at ``level`` (multiples of the mean edge length)."""
    if model == "none" or level == 0:
        return V.copy()
    if model not in MODELS:
        raise ValueError(f"unknown noise model {model!r}; expected one of {MODELS}")
    rng = rng_for(mesh_key, model, level, seed)
    sigma = float(level) * mean_edge_length(V, F)
    n = len(V)
    g = rng.standard_normal(n)
    if model == "gaussian_random":
        d = rng.standard_normal((n, 3))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
    else:
        d = vertex_normals(V, F)
    if model == "impulsive":
        mask = np.zeros(n, bool)
        mask[rng.permutation(n)[: int(round(fraction * n))]] = True
        g = np.where(mask, g, 0.0)
    return V + (sigma * g)[:, None] * d
