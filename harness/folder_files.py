"""A run folder's files besides its task CSVs and plan, and which of them this project wrote.

run.json read sanely (`_sane`: a value of the wrong type is left out; `_is_ours`: only a run.json
of this project counts), the task declarations it records (`recorded_specs`); `FolderFiles`: the
run folder's run.json, its exclusive lock, its saved meshes and their manifest, leftover
temporaries and its 3D views (`harness.results.RunFolder` adds the task CSVs and the plan).
"""
from __future__ import annotations

import errno
import fcntl
import glob
import json
import os
from pathlib import Path

from . import tasks
from .errors import ShootoutError
from .run_files import _HELD_LOCKS, _TEMP, MANIFEST, RUNNING, STATUS_ROOM, _atomic_json, atomic_write, output_names
from .schema import task_file
from .tasks.base import rule_ok


def _is_ours(data) -> bool:
    """A run.json this project wrote: an object with the keys every run and eval writes (a run
    also its config hash), not merely any JSON object another tool left under that name."""
    if not isinstance(data, dict) or not {"started", "status", "versions"} <= set(data):
        return False
    return data.get("kind") == "eval" or "config_hash" in data


_NUM = (int, float)
_META_TYPES = {      # run.json's keys and the types its readers rely on
    "name": str, "status": str, "started": str, "finished": str, "command": str, "config_source": str,
    "config_dir": str, "config_hash": str, "git_commit": str, "code_sha256": str, "executor": str, "scheduler": str, "kind": str,
    "config": dict, "machine": dict, "versions": dict, "tasks": dict, "timing": dict, "solver": dict, "tune": dict,
    "fixed_cost_per_case_s": dict, "status_counts": dict, "method_sources": dict, "measurement": dict,
    "workers": int, "n_cases": int, "resumed_ok_cases": int, "wall_s": _NUM, "timeout_s": _NUM,
    "git_dirty": bool, "load_average": list, "sessions": list, "provenance_changed": list,
}
_SESSION_NUMBERS = ("wall_s", "resumed_ok_cases")


def _sane(meta: dict) -> dict:
    """run.json with every value of a wrong type left out (a hand-edited ``machine: "x"`` or
    ``sessions: 5``), so that its readers see a missing value, never a value they would crash on;
    a non-number in ``load_average`` is None in its place, sessions that are not objects are
    dropped, and a session's non-numeric ``wall_s`` is None."""
    out = {}
    for k, v in meta.items():
        want = _META_TYPES.get(k)
        if v is None or want is None:
            out[k] = v
        elif isinstance(v, want) and not (isinstance(v, bool) and want in (int, _NUM)):
            out[k] = v
    if "load_average" in out:         # [start, end]: a bad entry is None in its place
        out["load_average"] = [x if isinstance(x, _NUM) and not isinstance(x, bool) else None
                                for x in out["load_average"]]
    if "sessions" in out:
        out["sessions"] = [{**x, **{k: None for k in _SESSION_NUMBERS
                                    if k in x and (not isinstance(x[k], _NUM) or isinstance(x[k], bool))}}
                           for x in out["sessions"] if isinstance(x, dict)]
    return out


def recorded_specs(meta: dict, frames) -> dict:
    """Task declarations: those recorded in run.json (a hand-edited one whose ``metrics`` is not a
    list of declarations gives way to the installed kind's, and so do ``invalid_when`` rules that
    are not a list of rules with a column and an operator), then known tasks with a CSV in the folder."""
    recorded = meta.get("tasks") if isinstance(meta.get("tasks"), dict) else {}
    specs = {k: v for k, v in recorded.items() if isinstance(v, dict) and isinstance(v.get("metrics"), list)
             and all(isinstance(m, dict) and isinstance(m.get("name"), str) for m in v["metrics"])}
    known = tasks.all_tasks()
    for name, spec in specs.items():     # hand-edited validity rules no version writes: the installed kind's
        rules = spec.get("invalid_when", [])
        if not (isinstance(rules, list) and all(rule_ok(r) for r in rules)):
            specs[name] = {**spec, "invalid_when": known[name].spec()["invalid_when"] if name in known else []}
    for name, task in known.items():
        if name not in specs and name in frames:
            specs[name] = task.spec()
    return specs


class FolderFiles:
    """A run folder's paths, run.json, lock, saved meshes, temporaries and views."""

    def __init__(self, path):
        self.path = Path(path)

    def csv_path(self, task: str) -> Path:
        return self.path / task_file(task)

    @property
    def run_json(self) -> Path:
        return self.path / "run.json"

    def read_run_json(self) -> dict | None:
        """The run's metadata; None when missing, unreadable or not one this project wrote (see
        `run_json_state`)."""
        try:
            data = json.loads(self.run_json.read_text())
        except (OSError, ValueError):
            return None
        return _sane(data) if _is_ours(data) else None

    def run_json_state(self) -> str:
        """``missing``, ``ok`` (a run.json this project wrote) or ``corrupt`` (unreadable, or
        another tool's: nothing in the folder is then taken for ours)."""
        if not self.run_json.exists():
            return "missing"
        return "ok" if self.read_run_json() is not None else "corrupt"

    def write_run_json(self, data: dict) -> None:
        """run.json, indented; a ``"status": "running"`` is followed by `STATUS_ROOM` spaces (JSON
        whitespace), room for a longer status written in place when a full disk refuses a new file."""
        self.path.mkdir(parents=True, exist_ok=True)
        text = json.dumps(data, indent=2, default=str).replace(RUNNING, RUNNING + " " * STATUS_ROOM, 1)
        atomic_write(self.run_json, lambda fh: fh.write(text))

    # ------------------------------------------------------------------------- ownership

    def lock(self, advice: str = "wait for it to finish or choose another --out"):
        """Take the folder's exclusive lock (held until the returned file is closed or the process
        ends); `ShootoutError` naming the holder's pid and ``advice`` when another run holds it, or
        saying why the folder cannot be made."""
        try:
            self.path.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ShootoutError(f"--out {self.path}: cannot make this folder ({exc.strerror or exc})") from None
        try:                             # never through a symlink (it would truncate its target)
            fd = os.open(self.path / ".shootout.lock", os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o644)
            fh = os.fdopen(fd, "r+")
        except OSError as exc:
            why = "it is a symbolic link" if exc.errno == errno.ELOOP else (exc.strerror or str(exc))
            raise ShootoutError(f"{self.path}: cannot take the run folder's lock {self.path / '.shootout.lock'} "
                                f"({why}); every command that writes in a run folder takes it") from None
        try:
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            if exc.errno not in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                fh.close()
                raise
            fh.seek(0)
            holder = fh.read().strip() or "unknown"
            fh.close()
            raise ShootoutError(f"{self.path}: another run is using this folder (pid {holder}); {advice}") from None
        fh.seek(0)
        fh.truncate()
        fh.write(str(os.getpid()))
        fh.flush()
        _HELD_LOCKS[:] = [f for f in _HELD_LOCKS if not f.closed] + [fh]
        return fh

    def foreign_files(self) -> list[str]:
        """Files with the names of a run's outputs (task CSVs, run.json, reports, leaderboard and
        winners tables, ``views/``, ``tune/``) present without a run.json of ours: files this
        project cannot prove it wrote, which a run would overwrite or delete. (``meshes/`` may
        hold the user's meshes: a run only ever removes the files its manifest lists.)"""
        if self.run_json_state() == "ok":
            return []
        found = [n for n in output_names() if (self.path / n).exists()]
        for d in ("views", "tune"):
            p = self.path / d
            if p.exists() and (not p.is_dir() or any(p.iterdir())):
                found.append(d + "/")
        return found

    def foreign_error(self) -> ShootoutError:
        """The refusal of this folder when `foreign_files` lists anything (exit 2)."""
        return ShootoutError(f"--out {self.path}: holds {', '.join(self.foreign_files())} and no run.json written by "
                             "mesh-shootout; these may be your files: choose another --out, or remove them")

    def save_mesh(self, name: str, write) -> Path:
        """Write ``meshes/<name>`` atomically (``write(fh)``), listed in the manifest first."""
        mdir = self.path / "meshes"
        mdir.mkdir(parents=True, exist_ok=True)
        name = Path(name).name
        with open(mdir / MANIFEST, "a") as fh:
            fh.write(name + "\n")
            fh.flush()
            os.fsync(fh.fileno())
        atomic_write(mdir / name, write)
        return mdir / name

    def written_meshes(self) -> set[str]:
        try:
            return {ln.strip() for ln in (self.path / "meshes" / MANIFEST).read_text().splitlines() if ln.strip()}
        except OSError:
            return set()

    def remove_temporaries(self) -> None:
        """Leftover temporary files of ours (`atomic_write`'s ``.<name>.*.tmp``, from a write
        interrupted by a full disk or a kill): those of the run's own file names at the top and
        of the meshes its manifest lists, and any in ``views/`` of a folder whose run.json is ours."""
        where = [(self.path, n) for n in output_names()] + [(self.path / "meshes", Path(n).name)
                                                              for n in self.written_meshes()]
        for d, n in where:
            for f in d.glob(f".{glob.escape(n)}.*.tmp"):
                if _TEMP.fullmatch(f.name[len(n) + 1:]):           # exactly `atomic_write`'s name
                    f.unlink(missing_ok=True)
        vdir = self.path / "views"
        if vdir.is_dir() and self.run_json_state() == "ok":
            for f in vdir.glob(".*.tmp"):
                f.unlink(missing_ok=True)

    # ------------------------------------------------------------------------- views

    def write_views(self, views: list[dict]) -> None:
        """``views/NN-<case_id>.json`` for each view and ``views/index.json`` listing them in order."""
        vdir = self.path / "views"
        vdir.mkdir(parents=True, exist_ok=True)
        index = []
        for i, v in enumerate(views):
            cid = str(v.get("case_id", ""))
            name = f"{i:02d}-{cid}.json" if cid.isalnum() else f"{i:02d}.json"
            _atomic_json(vdir / name, v)
            index.append({"file": name, "case_id": cid, "why": v.get("why")})
        keep = {e["file"] for e in index} | {"index.json"}
        for name in self._written_views() - keep:
            (vdir / name).unlink(missing_ok=True)
        _atomic_json(vdir / "index.json", {"views": index})

    def _written_views(self) -> set[str]:
        """The view files the stored ``views/index.json`` lists (ours: every other file there is the user's)."""
        try:
            index = json.loads((self.path / "views" / "index.json").read_text())["views"]
        except (OSError, ValueError, KeyError, TypeError):
            return set()
        if not isinstance(index, list):
            return set()
        vdir = self.path / "views"
        names = {Path(str(e["file"])).name for e in index if isinstance(e, dict) and "file" in e}
        return {n for n in names if n not in ("", ".", "..") and ((vdir / n).is_file() or (vdir / n).is_symlink())}

    def read_views(self) -> list[dict]:
        """The stored views in order ([] when there are none); an unreadable one is a view with an error."""
        vdir = self.path / "views"
        try:
            index = json.loads((vdir / "index.json").read_text())["views"]
        except (OSError, ValueError, KeyError, TypeError):
            return []
        out = []
        for e in index if isinstance(index, list) else []:
            try:
                out.append(json.loads((vdir / Path(str(e["file"])).name).read_text()))   # never leave views/
            except (OSError, ValueError, KeyError, TypeError) as exc:
                cid = str(e.get("case_id", "?")) if isinstance(e, dict) else "?"
                out.append({"case_id": cid, "why": "", "error": f"view file unreadable ({type(exc).__name__})"})
        return out
