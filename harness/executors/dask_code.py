"""Whether a worker ran the driver's code: the sources' `harness.provenance.code_hash` and the
package versions a worker's row carries (under `CODE_KEY`), compared with the driver's
(`other_code`): a row made by other sources, or by other versions of a package both sides
have (Python: another major or minor version), is not kept.
"""
from __future__ import annotations

from ..config import Case


CODE_KEY = "_worker_code"   # a row's (code_sha256, worker, package versions) from `run_task`, checked and dropped by the driver
_CODE: dict = {}


def _versions() -> dict:
    """`harness.provenance.package_versions` of this process, once (what its cases import)."""
    if "versions" not in _CODE:
        from ..provenance import package_versions
        _CODE["versions"] = package_versions()
    return _CODE["versions"]


def _code_of(plugins) -> str:
    """`harness.provenance.code_hash` of this process's sources and ``plugins``, once per process
    and plugin list: for the driver and a forking worker, after their modules are loaded (their
    cases run that code, whatever the files become); a case in a subprocess hashes its own."""
    key = tuple(plugins)
    if key not in _CODE:
        from ..provenance import code_hash
        _CODE[key] = code_hash(key)
    return _CODE[key]


def other_code(row: dict, case: Case) -> str | None:
    """Why ``row`` is not kept: the worker that made it ran other sources (`code_hash`) than this
    driver, e.g. an older checkout on its PYTHONPATH; None when they agree or the row says nothing."""
    theirs = row.pop(CODE_KEY, None)
    if not isinstance(theirs, (tuple, list)) or len(theirs) not in (2, 3):
        return None
    ours = _code_of(case.plugins)
    if theirs[0] != ours:
        return (f"the Dask worker ({theirs[1]}) ran other code than the driver (code_sha256 {theirs[0]}, the "
                f"driver's {ours}: its harness, methods or plugins differ); its row is not kept: give every "
                "worker the driver's code")
    mine, versions = _versions(), theirs[2] if len(theirs) == 3 else None
    other = sorted(k for k in mine if isinstance(versions, dict) and _differ(k, versions.get(k), mine[k]))
    if other:
        return (f"the Dask worker ({theirs[1]}) has other package versions than the driver ("
                + ", ".join(f"{k} {versions[k]}, the driver's {mine[k]}" for k in other)
                + "): the metrics may differ; its row is not kept: give every worker the driver's environment")
    return None


def _differ(package: str, theirs, ours) -> bool:
    """Whether a worker's version of ``package`` differs from the driver's in a way the metrics
    could show: both installed and not equal (Python: another major or minor version). A package
    missing on one side is not compared: a method that needs it is `unavailable` there."""
    if theirs is None or ours is None:
        return False
    if package == "python":
        return str(theirs).split(".")[:2] != str(ours).split(".")[:2]
    return theirs != ours
