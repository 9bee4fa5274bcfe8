"""`Case` (one picklable unit of work) and the expansion of a validated grid into cases.

A case's id is the sha1 of the canonical JSON of everything that defines it: the task, the
mesh's identity (file contents, not paths or labels), the noise model, level, seed and
fraction, the method and its parameters as `harness.core.params.id_form` records them.
Cases with equal ids are kept once.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

from . import datasets
from .mesh import file_sha1


@dataclass(frozen=True)
class Case:
    """One (mesh, noise model, level, seed, method, params): small, picklable, self-describing."""

    case_id: str
    task: str
    mesh: dict                      # spec, see harness.datasets
    mesh_key: str
    noise_model: str
    noise_level: float
    seed: int
    fraction: float
    method: str
    params: dict
    repeats: int = 1
    plugins: tuple = ()
    hausdorff_samples: int = 20000
    time_budget: float = 0.25       # seconds of samples to aim for (timeit-like autorange)
    threads: int = 0                # BLAS/OpenMP threads of the case process (0: no limit)
    hausdorff_eps: float = 1e-3     # relative gap the certified Hausdorff distance aims for

    @property
    def noise_name(self) -> str:
        """The noise as rows name it: the model, with its fraction when it moves only part of
        the vertices (``impulsive(fraction=0.3)``), so that entries differing only in their
        fraction are different inputs in every table and cell."""
        return noise_name(self.noise_model, self.fraction)

    @property
    def adds_noise(self) -> bool:
        """Whether the harness adds noise to the clean mesh (it then uses the mesh's noise frame);
        False for a clean input and for a given noisy/clean pair (model ``given``)."""
        return self.noise_model not in ("none", "given") and self.noise_level != 0


def noise_name(model: str, fraction: float = 1.0) -> str:
    """``model``, or ``model(fraction=f)`` when ``f`` < 1 (the impulsive model's moved share)."""
    return model if fraction is None or float(fraction) == 1.0 else f"{model}(fraction={float(fraction)!r})"


def case_id(task, mesh_spec, model, level, seed, fraction, method, params) -> str:
    """Stable 12-hex id: sha1 of the canonical JSON of everything that defines the case."""
    blob = json.dumps([task, mesh_spec, model, level, seed, fraction, method, params],
                      sort_keys=True, default=str)
    return hashlib.sha1(blob.encode()).hexdigest()[:12]


def method_id_spec(method: str) -> dict:
    """How a case id records ``method``'s parameters (`harness.core.params.id_spec`: a parameter
    under its ``id_as`` name, one with ``id_omit_default`` left out at its default)."""
    from .core.params import id_spec
    from .plugins import import_methods
    try:
        return id_spec(import_methods().get(method).params)
    except KeyError:
        return {}


def _identity(spec: dict) -> dict:
    """What defines a mesh for the case id: file contents (sha1), not where the file lies."""
    out = {}
    for k, v in spec.items():
        if k.endswith("_sha1"):
            continue                      # a case's record of the bytes it must read (`expand_cases`)
        if k in ("file", "clean"):
            out[k + "_sha1"] = file_sha1(v)
        elif k == "name":
            continue                      # a label only: renaming a mesh keeps its case ids
        else:
            out[k] = v
    return out


def _unique_labels(meshes: list[dict]) -> list[str]:
    """``mesh`` column labels; file meshes with the same stem get their parent folder prepended
    (``d1-Noisy``), then an index, so no two different meshes share a label."""
    from collections import Counter
    base = [datasets.spec_key(s) for s in meshes]
    nbase = Counter(base)
    labels = [f"{Path(s['file']).parent.name}-{b}" if "file" in s and nbase[b] > 1 else b
              for s, b in zip(meshes, base)]
    nlab = Counter(labels)
    first: dict[str, int] = {}
    seen: dict[str, int] = {}
    for i, lab in enumerate(labels):
        if nlab[lab] > 1:
            j = first.setdefault(lab, i)
            if j != i and _identity(meshes[i]) != _identity(meshes[j]):
                seen[lab] = seen.get(lab, 0) + 1
                labels[i] = f"{lab}-{seen[lab]}"
    return labels


def _noise_of(noises, task: str) -> list:
    """The noise list of ``task``: ``noises`` itself, or its entry when it maps tasks to lists."""
    return noises.get(task, []) if isinstance(noises, dict) else noises


def _count_cases(meshes: list, noises, tasks: dict) -> int:
    def per_mesh(nl):
        return sum(len(n.get("levels") or [0.0]) * (1 if n["model"] == "none" else n.get("seeds", 1)) for n in nl)
    return len(meshes) * sum(per_mesh(_noise_of(noises, task)) * len(grid)
                             for task, entries in tasks.items() for _, grid in entries)


def expand_cases(meshes: list, noises, tasks: dict, seed: int, repeats: int, plugins: tuple, hs: int,
                 budget: float, eps: float = 1e-3) -> list:
    """Every (mesh, noise model, level, seed, task, method, params) case, duplicates removed;
    ``noises`` is one list for every task or a mapping task -> list."""
    from .core.params import id_form
    cases = []
    ids: dict = {}                  # method -> how its case ids record its parameters (`method_id_spec`)
    labels = _unique_labels(meshes)
    for spec, key in zip(meshes, labels):
        ident = _identity(spec)
        spec = {**spec, **{k: v for k, v in ident.items() if k.endswith("_sha1")}}   # the bytes each case must read
        is_pair = "clean" in spec or datasets.resolve_bundled(spec.get("bundled", "")) in datasets.PAIRS
        given = ("given", float("nan"), seed, 1.0)          # one NaN object: tuples compare by identity first

        def noise_list(task):
            return [given] if is_pair else [
                (n["model"], float(lv), seed + s, float(n.get("fraction", 1.0)))
                for n in _noise_of(noises, task) for lv in (n.get("levels") or [0.0])
                for s in range(1 if n["model"] == "none" else n.get("seeds", 1))]
        lists = {task: noise_list(task) for task in tasks}
        for model, level, s, frac in dict.fromkeys(x for nl in lists.values() for x in nl):
            for task, entries in tasks.items():
                if (model, level, s, frac) not in lists[task]:
                    continue
                for mname, grid in entries:
                    if mname not in ids:
                        ids[mname] = method_id_spec(mname)
                    for params in grid:
                        cid = case_id(task, ident, model, level, s, frac, mname, id_form(params, ids[mname]))
                        cases.append(Case(cid, task, spec, key, model, level, s, frac, mname,
                                          params, repeats, plugins, hs, budget, hausdorff_eps=eps))
    seen = set()
    return [c for c in cases if not (c.case_id in seen or seen.add(c.case_id))]
