"""Provenance of a run: package versions, git commit, machine, timestamps."""
from __future__ import annotations

import os
import platform
import subprocess
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path

VERSION_PACKAGES = ["numpy", "scipy", "pandas", "libigl", "pymeshlab", "fast-simplification", "pygel3d",
                    "numba", "robust-laplacian", "pyfqmr", "distributed", "mesh-shootout"]


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
            "machine": platform.machine(), "cpu": cpu, "cpu_count": os.cpu_count(),
            "cpu_freq_mhz": freq.max if freq else None,
            "memory_gb": round(psutil.virtual_memory().total / 2 ** 30, 1)}


def now_iso() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")
