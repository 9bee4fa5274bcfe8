"""Task kinds. Every module of this package that defines ``TASK`` (a `harness.tasks.base.Task`)
is one task kind; `get` and `all_tasks` find them, nothing else lists them."""
from __future__ import annotations

import importlib
import pkgutil
import re
import sys

from .base import COMMON_COLUMNS, CaseInput, Invalid, Metric, Task, rule_ok

_TASKS: dict[str, Task] = {}
BROKEN: dict[str, str] = {}         # module name -> why it is not a task kind (import error, bad declaration)


def declaration_problems(task: Task) -> list[str]:
    """What is wrong with a `Task` declaration: a name that is not a plain identifier (it names the
    task's CSV in the run folder), metrics that are not a tuple of `Metric`, metric names repeated
    or taken by a common column, a view metric or ``Invalid`` column that is not a column."""
    if not isinstance(task.name, str) or not re.fullmatch(r"[a-z][a-z0-9_]{0,39}", task.name):
        return [f"name {task.name!r} is not a lower-case identifier (letters, digits, '_'; it names the task's "
                "CSV file in the run folder)"]
    if not isinstance(task.metrics, (tuple, list)) or not all(isinstance(m, Metric) for m in task.metrics):
        return [f"metrics must be a tuple of Metric, got {type(task.metrics).__name__} (one Metric needs a "
                "trailing comma: metrics=(Metric(...),))"]
    P, names = [], [m.name for m in task.metrics]
    P += [f"metric {n!r} is declared twice" for n in sorted({n for n in names if names.count(n) > 1})]
    P += [f"metric {n!r} is a common column of every task CSV; name it otherwise" for n in names
          if n in COMMON_COLUMNS]
    if task.view_metric is not None and task.view_metric not in names:
        P.append(f"view_metric {task.view_metric!r} is not one of its metrics {names}")
    P += [f"invalid_when column {r.column!r} is not one of its metrics" for r in task.invalid_when
          if r.column not in names]
    P += [f"invalid_when rule on {r.column!r}: op must be '==', '>' (with a number, or than=another column) "
          f"or 'blank', not {r.op!r} with value {r.value!r}" for r in task.invalid_when if not rule_ok(r.spec())]
    return P


def _load() -> dict[str, Task]:
    if not _TASKS:
        found = {}
        for info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
            if info.name == "base":
                continue
            try:                             # one broken task module costs that task kind, not every command
                mod = importlib.import_module(f"{__name__}.{info.name}")
                task = getattr(mod, "TASK", None)
                problems = declaration_problems(task) if isinstance(task, Task) else []
            except Exception as exc:  # noqa: BLE001
                task, problems = None, [f"importing it failed ({type(exc).__name__}: {exc})"]
            if isinstance(task, Task) and not problems and task.name in found:
                # two modules declare one name: the module named after it keeps it (the other could
                # otherwise replace a built-in kind by the order of the file names)
                other = found[task.name][1]
                if info.name == task.name:
                    BROKEN[other] = f"its name {task.name!r} is the task kind of {info.name}.py"
                    print(f"shootout: warning: harness/tasks/{other}.py is not loaded as a task kind: "
                          f"{BROKEN[other]}", file=sys.stderr)
                else:
                    problems = [f"its name {task.name!r} is the task kind of {other}.py"]
            if problems:
                BROKEN[info.name] = "; ".join(problems)
                print(f"shootout: warning: harness/tasks/{info.name}.py is not loaded as a task kind: "
                      f"{BROKEN[info.name]}", file=sys.stderr)
            elif isinstance(task, Task):
                found[task.name] = (task, info.name)
        _TASKS.update({name: task for name, (task, _) in found.items()})
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
        broken = f" (not loaded: {', '.join(f'{m}.py: {why}' for m, why in BROKEN.items())})" if BROKEN else ""
        raise KeyError(f"unknown task {name!r}; expected one of {sorted(tasks)}{broken}")
    return tasks[name]


__all__ = ["CaseInput", "Invalid", "Metric", "Task", "all_tasks", "get", "names"]
