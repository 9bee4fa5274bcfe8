"""Provenance of a run: package versions, git commit, machine, timestamps."""
from __future__ import annotations

import os
import platform
import subprocess
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path

VERSION_PACKAGES = ["numpy", "scipy", "pandas", "libigl", "pymeshlab", "fast-simplification", "pygel3d",
                    "numba", "robust-laplacian", "pyfqmr", "distributed", "mesh-shootout",
                    # the other backends and the sparse solvers the methods may call
                    "potpourri3d", "pygeodesic", "meshoptimizer", "trimesh", "open3d-cpu", "open3d",
                    "cholespy", "qdldl", "pypardiso", "mkl"]


def package_versions() -> dict:
    out = {}
    for name in VERSION_PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = None
    out["python"] = platform.python_version()
    return out


def git_commit() -> str | None:
    try:
        here = Path(__file__).resolve().parent
        r = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True, timeout=5)
        return r.stdout.strip() or None if r.returncode == 0 else None
    except (OSError, subprocess.SubprocessError):
        return None


def code_hash(plugins=()) -> str:
    """SHA-256 (first 16 hex digits) of the source that runs the cases: every ``.py`` file of the
    ``harness`` and ``methods`` packages and of each plugin module (a package: its ``.py`` files),
    names and bytes (a file that cannot be read counts by its name). Two sessions with different
    uncommitted edits, or different plugin code, differ here though ``git_commit`` and
    ``git_dirty`` agree. Modules a plugin imports from elsewhere are not covered."""
    import hashlib
    import importlib.util
    root = Path(__file__).resolve().parent.parent
    files = [(f"{d}/{p.relative_to(root / d)}", p) for d in ("harness", "methods") for p in (root / d).rglob("*.py")]
    for mod in plugins:
        try:
            spec = importlib.util.find_spec(mod)
        except (ImportError, ValueError):
            spec = None
        origin = Path(spec.origin) if spec is not None and spec.origin and spec.origin.endswith(".py") else None
        dirs = ([origin.parent] if origin is not None and origin.name == "__init__.py" else
                [Path(d) for d in (spec.submodule_search_locations or [])] if spec is not None and origin is None else [])
        if dirs:                                       # a package, a namespace package too: all its files
            files += [(f"plugin {mod}/{p.relative_to(d)}", p) for d in dirs for p in d.rglob("*.py")]
        else:
            files.append((f"plugin {mod}", origin))
    h = hashlib.sha256()
    for name, path in sorted(files, key=lambda x: x[0]):
        try:
            data = path.read_bytes() if path is not None else b"<not found>"
        except OSError as exc:
            data = f"<unreadable: {exc.strerror}>".encode()
        h.update(name.encode() + b"\0" + data + b"\0")
    return h.hexdigest()[:16]


def git_dirty() -> bool | None:
    """Whether the checkout's tracked files differ from its commit (the code that ran is not the
    commit's), or None outside a git checkout."""
    try:
        here = Path(__file__).resolve().parent
        r = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=here, capture_output=True,
                           text=True, timeout=5, env={**os.environ, "GIT_OPTIONAL_LOCKS": "0"})   # never takes the index lock
        return bool(r.stdout.strip()) if r.returncode == 0 else None
    except (OSError, subprocess.SubprocessError):
        return None


def usable_cpus() -> int:
    """CPUs this process may run on: its affinity set (``taskset``, a container's cpuset), at
    most its cgroup's CPU quota (``cpu.max``, or v1's ``cfs_quota_us / cfs_period_us``, rounded
    up); ``os.cpu_count()`` counts the machine's instead."""
    try:
        n = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        n = os.cpu_count() or 1
    quota = _cgroup_quota()
    if quota is not None:
        n = min(n, max(1, -int(-quota // 1)))
    return max(1, n)


def _cgroup_quota(root: Path = Path("/sys/fs/cgroup"), proc: Path = Path("/proc/self/cgroup")) -> float | None:
    """The smallest CPU quota (cores) of this process's cgroup and its ancestors (a quota on a
    parent slice binds too), v2 (``cpu.max``) or v1 (``cpu.cfs_quota_us / cpu.cfs_period_us``),
    looked up under the path ``/proc/self/cgroup`` names and, for a container that sees its
    own cgroup as the mount's root, at the root itself; None when unlimited or unknown."""
    try:
        lines = proc.read_bytes().decode("utf-8", "surrogateescape").splitlines()   # a cgroup name is any bytes
    except OSError:
        return None
    found = []
    for line in lines:
        parts = line.split(":", 2)
        if len(parts) != 3:
            continue
        _, ctrl, rel = parts
        rel_parts = [p for p in rel.split("/") if p]
        if ctrl == "":
            bases, read = [root], _v2_quota
        elif "cpu" in ctrl.split(","):
            bases, read = [root / ctrl, root / "cpu", root / "cpu,cpuacct"], _v1_quota
        else:
            continue
        for base in bases:
            for k in range(len(rel_parts), -1, -1):          # the cgroup, then each ancestor up to the root
                q = read(base.joinpath(*rel_parts[:k]))
                if q is not None:
                    found.append(q)
    return min(found) if found else None


def _ratio(quota: int, period: int) -> float | None:
    """Cores of a quota; None (no limit known) unless both are positive."""
    return quota / period if quota > 0 and period > 0 else None


def _v2_quota(d: Path) -> float | None:
    try:
        quota, period = (d / "cpu.max").read_text().split()[:2]
        return None if quota == "max" else _ratio(int(quota), int(period))
    except (OSError, ValueError, UnicodeDecodeError):
        return None


def _v1_quota(d: Path) -> float | None:
    try:
        return _ratio(int((d / "cpu.cfs_quota_us").read_text()), int((d / "cpu.cfs_period_us").read_text()))
    except (OSError, ValueError, UnicodeDecodeError):
        return None


def machine_info() -> dict:
    import psutil
    freq = psutil.cpu_freq()
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"node": platform.node(), "system": platform.system(), "release": platform.release(),
            "machine": platform.machine(), "cpu": cpu, "cpu_count": os.cpu_count(), "usable_cpus": usable_cpus(),
            "cpu_freq_mhz": freq.max if freq else None,
            "memory_gb": round(psutil.virtual_memory().total / 2 ** 30, 1)}


def now_iso() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")
