"""A case's input and the meshes it saves: the clean mesh and the input positions (the noise
applied with the case's seed, or the noisy mesh of a given pair), the saved input's file name
(one per mesh, noise, level and seed), and the input and output meshes ``save_meshes`` writes,
each with a per-vertex quality (by default the distance of each vertex to the clean surface)."""
from __future__ import annotations

import math

from .config import Case
from .tasks.base import CaseInput


def prepare_input(case: Case) -> tuple[CaseInput, float | None]:
    """The case's input (clean mesh, input positions) and the noise level of a given pair."""
    from . import datasets
    from .noise import apply_noise
    src = datasets.cached(case.mesh)
    clean = src.clean
    settings = {"hausdorff_samples": case.hausdorff_samples, "hausdorff_eps": case.hausdorff_eps}
    if src.noisy_V is not None:
        return CaseInput(clean, src.noisy_V, clean.F, clean.diagonal(), settings), src.pair_level
    frame = clean.noise_frame if case.adds_noise else None
    V_in = apply_noise(clean.V, clean.F, case.noise_model, case.noise_level, case.seed,
                       mesh_key=case.mesh_key, fraction=case.fraction, frame=frame)
    return CaseInput(clean, V_in, clean.F, clean.diagonal(), settings, shape=src.shape), None


def input_mesh_name(case: Case) -> str:
    """The saved input's file name: one per (mesh, noise, level, seed), the level as ``%g`` where
    that reads back as the level, else whole (``repr``: two levels that differ past 6 digits are
    two files)."""
    x = float(case.noise_level)
    lvl = "pair" if math.isnan(x) else f"{x:g}" if float(f"{x:g}") == x else repr(x)
    model = case.noise_model if case.noise_name == case.noise_model else f"{case.noise_model}-fraction{float(case.fraction)!r}"
    return f"{case.mesh_key}-{model}-{lvl}-{case.seed}-input.ply"


QUALITY = "quality = unsigned distance of each vertex to the clean surface (mesh units)"


def saved_meshes(case: Case, task, inp: CaseInput, result) -> dict:
    """The meshes ``save_meshes`` writes: ``{file name: (V, F, quality, comment)}``.

    The input and the task's output mesh, each with a per-vertex quality: by default the
    distance of each vertex to the clean surface (`QUALITY`); a task's ``output_mesh`` may
    return ``(V, F, quality, comment)`` to store its own per-vertex value instead.
    """
    from .metrics.surface_distance import point_surface_distance
    out = task.output_mesh(inp, result)
    if len(out) == 2:
        out = (*out, point_surface_distance(out[0], inp.clean.V, inp.clean.F), QUALITY)
    return {input_mesh_name(case): (inp.V, inp.F, point_surface_distance(inp.V, inp.clean.V, inp.clean.F), QUALITY),
            f"{case.case_id}.ply": out}
