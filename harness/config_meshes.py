"""Validation of a config's mesh lists (``meshes``, ``tune.train``): bundled names, procedural
meshes with bounded parameters, and files (or noisy/clean pairs) that exist, can be read and
have a supported extension; then one mesh listed twice, and a ``name:`` another mesh goes by.
Each function appends its problems, named by key path, to the caller's list."""
from __future__ import annotations

import json
import re
from pathlib import Path

from . import datasets, yaml_input
from .cases import _identity, _unique_labels
from .config_values import _close, _is_int, _is_num
from .errors import ShootoutError
from .mesh import SUPPORTED, file_sha1, missing_file_problem


def _numbered(listed, valid: list, base_dir: Path, key: str) -> dict:
    """``{index as listed: spec}`` of a mesh list's valid entries: ``valid`` (`_check_meshes`'s
    result) when every entry was, else each entry checked alone (their problems are listed
    already), so a message names an entry by its place in the config."""
    if not isinstance(listed, list):
        return {}
    if len(valid) == len(listed):
        return dict(enumerate(valid))
    return {i: alone[0] for i, e in enumerate(listed) if (alone := _check_meshes([e], base_dir, [], key))}


def _check_meshes(meshes, base_dir: Path, P: list, key: str = "meshes") -> list[dict]:
    """The mesh list at ``key`` (``meshes``, ``tune.train``): specs of the good entries, a problem
    in ``P`` for each bad one, named by its key path."""
    out, where = [], []
    if not isinstance(meshes, list) or not meshes:
        P.append(f"{key}: expected a non-empty list of meshes")
        return out
    marks = []                                   # (specs, problems) so far as each entry starts
    for i, m in enumerate(meshes):
        at = f"{key}[{i}]"
        marks.append((len(out), len(P)))
        if isinstance(m, str):
            if datasets.resolve_bundled(m):
                out.append({"bundled": datasets.resolve_bundled(m)})
                where.append(at)
            elif m in datasets.PROCEDURAL:
                out.append({"procedural": m, **datasets.PROCEDURAL[m]})
                where.append(at)
            else:
                opts = datasets.bundled_names() + list(datasets.PROCEDURAL)
                P.append(f"{at}: unknown mesh {yaml_input.short(m)}{_close(m, opts)}; see `shootout datasets`")
        elif isinstance(m, dict) and "procedural" in m:
            kind = m["procedural"]
            if not isinstance(kind, str) or kind not in datasets.PROCEDURAL:
                P.append(f"{at}.procedural: unknown procedural mesh {yaml_input.short(kind)}{_close(kind, datasets.PROCEDURAL)}; "
                         f"expected one of {sorted(datasets.PROCEDURAL)}")
                continue
            spec = {"procedural": kind}
            for k, v in m.items():
                if k == "procedural":
                    continue
                if k not in datasets.PROCEDURAL[kind]:
                    P.append(f"{at}.{k}: unknown parameter of {kind}{_close(k, datasets.PROCEDURAL[kind])}; "
                             f"expected {sorted(datasets.PROCEDURAL[kind])}")
                    continue
                lo, hi = datasets.PROCEDURAL_BOUNDS[k]
                want_int = _is_int(datasets.PROCEDURAL[kind][k])
                if not (_is_int(v) if want_int else _is_num(v)) or not lo <= v <= hi:
                    P.append(f"{at}.{k}: expected {'an integer' if want_int else 'a number'} in [{lo}, {hi}], got {yaml_input.short(v)}")
                    continue
                spec[k] = v if want_int else float(v)      # `radius: 1` is the default 1.0: one case id
            out.append({**{"procedural": kind}, **datasets.PROCEDURAL[kind], **spec})
            where.append(at)
        elif isinstance(m, dict) and "file" in m:
            extra = set(m) - {"file", "clean", "name", "level"}
            if extra:
                P.append(f"{at}: unknown key(s) {sorted(extra)}; a file mesh takes 'file' and optional "
                         "'clean', 'name', 'level'")
            spec = {}
            if "name" in m:
                nm = m["name"]
                if not isinstance(nm, str) or not re.fullmatch(r"[A-Za-z0-9_.\-]{1,80}", nm):
                    P.append(f"{at}.name: expected 1-80 letters, digits, '_', '-' or '.', got {yaml_input.short(nm)}")
                else:
                    spec["name"] = nm
            if "level" in m:
                lv = m["level"]
                if "clean" not in m:
                    P.append(f"{at}.level: the noise level of a given pair needs 'clean' (the noise-free mesh)")
                elif not _is_num(lv) or not 0 <= lv <= 1e6:
                    P.append(f"{at}.level: expected a number >= 0 (sigma / mean edge length), got {yaml_input.short(lv)}")
                else:
                    spec["level"] = float(lv)
            for k in ("file", "clean"):
                if k not in m:
                    continue
                f = m[k]
                if not isinstance(f, str):
                    P.append(f"{at}.{k}: expected a path string, got {yaml_input.short(f)}")
                    continue
                path = Path(f) if Path(f).is_absolute() else base_dir / f
                if not path.is_file() and Path(f).is_file():
                    path = Path(f).resolve()
                if path.is_dir():
                    P.append(f"{at}.{k}: {f} {missing_file_problem(path)}")
                    continue
                if not path.is_file():
                    if path.exists() or path.is_symlink():     # a pipe, a device, a dangling or looping link
                        why = missing_file_problem(path) if path.exists() else "is a symbolic link to nothing readable"
                        P.append(f"{at}.{k}: {f} {why}")
                    else:
                        P.append(f"{at}.{k}: file not found: {f} (relative paths are resolved against {base_dir})")
                    continue
                if path.suffix.lower() not in SUPPORTED:
                    P.append(f"{at}.{k}: unsupported extension {yaml_input.short(path.suffix)} of {f}; expected one of {list(SUPPORTED)}")
                    continue
                try:
                    with open(path, "rb") as fh:
                        fh.read(1)
                except OSError as exc:
                    P.append(f"{at}.{k}: cannot read {f}: {exc.strerror or exc}")
                    continue
                spec[k] = str(path.resolve())
            if "file" in spec and "clean" in spec:
                try:
                    datasets.cached(spec)
                except ShootoutError as exc:
                    P.append(f"{at}: {exc}")
                    continue
            if "file" in spec and ("clean" in spec or "clean" not in m):
                out.append(spec)
                where.append(at)
        else:
            P.append(f"{at}: expected a bundled name, {{procedural: ...}} or {{file: ...}}, got {yaml_input.short(m)}")
    marks.append((len(out), len(P)))
    ok = [j for (k0, p0), (k1, p1) in zip(marks, marks[1:]) if p1 == p0 for j in range(k0, k1)]
    # (an entry with a problem of its own may stand for another mesh than it reads as: not compared)
    P += _same_mesh_problems([out[j] for j in ok], [where[j] for j in ok])
    return out


def _same_mesh_key(spec: dict) -> dict:
    """What makes two mesh entries one mesh: `_identity`, where a bundled mesh is the file it reads
    and a bundled pair its noisy and clean files, so that the same bytes given as ``file:`` (and
    ``clean:``) are the same mesh too."""
    if set(spec) <= {"bundled", "name"}:
        files = datasets._spec_files(spec)
        if len(files) in (1, 2):
            try:
                return dict(zip(("file_sha1", "clean_sha1"), map(file_sha1, files)))
            except OSError:
                pass
    return _identity(spec)


def _same_mesh_problems(specs: list[dict], where: list[str]) -> list[str]:
    """One mesh listed twice (same spec, or files with the same bytes: its cases would run once,
    whatever its names), and a ``name:`` that another, different mesh also goes by (the ``mesh``
    column and the noise seed come from it; it would be changed silently to tell them apart)."""
    P, again = [], {}
    memo: dict[str, str] = {}                  # a long list repeats a few specs: each is keyed once

    def key(s: dict) -> str:
        raw = json.dumps(s, sort_keys=True, default=str)
        if raw not in memo:
            memo[raw] = json.dumps(_same_mesh_key(s), sort_keys=True, default=str)
        return memo[raw]
    ids = [key(s) for s in specs]
    for i, ident in enumerate(ids):
        again.setdefault(ident, []).append(i)
    for ident, at in again.items():
        if len(at) > 1:
            more = f" and {len(at) - 4} more" if len(at) > 4 else ""
            P.append(f"{', '.join(where[i] for i in at[1:4])}{more}: the same mesh as {where[at[0]]} (the same "
                     f"{'spec' if len({json.dumps(_identity(specs[i]), sort_keys=True, default=str) for i in at[:4]}) == 1 else 'file bytes'}"
                     "): list it once")
    base, final = [datasets.spec_key(s) for s in specs], _unique_labels(specs)
    for i, s in enumerate(specs):
        if "name" not in s or final[i] == s["name"]:
            continue                              # a name the run keeps as it is
        other = next((j for j in range(len(specs)) if j != i and ids[j] != ids[i] and s["name"] in (base[j], final[j])),
                     None)
        whose = f"the label of {where[other]}, another mesh" if other is not None else "another mesh's label"
        P.append(f"{where[i]}.name: {s['name']!r} is also {whose} (the run would call this one {final[i]!r}): give "
                 "each mesh a label of its own (it names the mesh column and seeds the noise)")
    return P
