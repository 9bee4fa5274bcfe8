"""Exceptions of the harness: each becomes a one-line user message, never a traceback."""


class ShootoutError(Exception):
    """Base class for errors the CLI reports as a message."""


class ConfigError(ShootoutError):
    """A config with problems; ``problems`` lists every one as 'key.path: what was expected'."""

    def __init__(self, source: str, problems: list[str]):
        self.source = source
        self.problems = list(problems)
        lines = "\n".join(f"  - {p}" for p in self.problems)
        super().__init__(f"{source}: {len(self.problems)} problem(s) in config:\n{lines}")


class InvalidMeshError(ShootoutError, ValueError):
    """A mesh that cannot be used (unreadable, empty, NaN, non-triangle, out-of-range indices)."""


class MethodFailed(ShootoutError):
    """A method raised, crashed its process, or returned malformed output."""


class RunInterrupted(ShootoutError):
    """The run cannot go on (e.g. the Dask scheduler was lost): it is marked interrupted and can be
    continued with ``--resume``. Exit 1."""

    exit_code = 1
