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

from .core.geometry import mean_edge_length, vertex_normals

MODELS = ("gaussian_normal", "gaussian_random", "impulsive", "none")


def rng_for(mesh_key: str, model: str, level: float, seed: int) -> np.random.Generator:
    """A generator determined only by its arguments (stable across processes and platforms)."""
    digest = hashlib.sha256(f"{mesh_key}|{model}|{float(level)!r}".encode()).digest()
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(
        [int(seed) & 0xFFFFFFFF, int.from_bytes(digest[:8], "little")])))


def apply_noise(V: np.ndarray, F: np.ndarray, model: str, level: float, seed: int,
                mesh_key: str = "", fraction: float = 1.0, frame=None) -> np.ndarray:
    """Noisy copy of ``V`` (n, 3) under ``model`` at ``level`` (multiples of the mean edge length).

    ``frame``: ``(mean edge length, vertex normals)`` of ``(V, F)`` if already known
    (`harness.mesh.Mesh.noise_frame`); computed here otherwise.
    """
    if model == "none" or level == 0:
        return V.copy()
    if model not in MODELS:
        raise ValueError(f"unknown noise model {model!r}; expected one of {MODELS}")
    rng = rng_for(mesh_key, model, level, seed)
    mean_edge, normals = frame if frame is not None else (mean_edge_length(V, F), None)
    sigma = float(level) * mean_edge
    n = len(V)
    g = rng.standard_normal(n)
    if model == "gaussian_random":
        d = rng.standard_normal((n, 3))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
    else:
        d = normals if normals is not None else vertex_normals(V, F)
    if model == "impulsive":
        mask = np.zeros(n, bool)
        mask[rng.permutation(n)[: int(round(fraction * n))]] = True
        g = np.where(mask, g, 0.0)
    return V + (sigma * g)[:, None] * d
