"""Executors run cases and yield ``(case, row, extras)`` as each finishes.

The protocol is small (`Executor`): ``run(cases, want_meshes)`` is a generator, ``close()``
releases what the executor holds, ``describe()`` says how it ran (for run.json). ``local`` and
``serial`` live in `harness.executors.local`, ``dask`` in `harness.executors.dask`; all of them
isolate a case with `harness.executors.isolation`.
"""
from __future__ import annotations

from typing import Iterator, Protocol


class Executor(Protocol):
    name: str

    def run(self, cases, want_meshes: bool = False) -> Iterator[tuple]:
        ...

    def close(self) -> None:
        ...

    def describe(self) -> dict:
        ...


EXECUTORS = ("local", "serial", "dask")


def make_executor(kind: str, workers: int, timeout: float | None, scheduler=None) -> Executor:
    """Executor by name, one of `EXECUTORS` (`harness.session.run_args_problems` refuses others)."""
    if kind == "serial":
        from .local import SerialExecutor
        return SerialExecutor()
    if kind == "dask":
        from .dask import DaskExecutor
        return DaskExecutor(workers=workers, timeout=timeout, scheduler=scheduler)
    from .local import LocalExecutor
    return LocalExecutor(workers=workers, timeout=timeout)
