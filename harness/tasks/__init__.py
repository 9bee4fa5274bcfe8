"""Task kinds. Every module of this package that defines ``TASK`` (a `harness.tasks.base.Task`)
is one task kind; `get` and `all_tasks` find them, nothing else lists them."""
from __future__ import annotations

import importlib
import pkgutil

from .base import CaseInput, Invalid, Metric, Task

_TASKS: dict[str, Task] = {}


def _load() -> dict[str, Task]:
    if not _TASKS:
        found = {}
        for info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
            if info.name == "base":
                continue
            mod = importlib.import_module(f"{__name__}.{info.name}")
            task = getattr(mod, "TASK", None)
            if isinstance(task, Task):
                found[task.name] = task
        _TASKS.update(found)
    return _TASKS


def all_tasks() -> dict[str, Task]:
    """Every task kind by name (sorted)."""
    return dict(sorted(_load().items(), key=lambda kv: (kv[1].order, kv[0])))


def names() -> list[str]:
    return list(all_tasks())


def get(name: str) -> Task:
    """The task ``name``; KeyError listing the known ones otherwise."""
    tasks = _load()
    if name not in tasks:
        raise KeyError(f"unknown task {name!r}; expected one of {sorted(tasks)}")
    return tasks[name]


__all__ = ["CaseInput", "Invalid", "Metric", "Task", "all_tasks", "get", "names"]
