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


# An interrupt (SIGINT/SIGTERM) raises KeyboardInterrupt where it lands, but Python drops an
# exception raised inside a weakref callback or a __del__ ("Exception ignored in ..."), so the
# CLI's handlers also set this flag and the driver checks it at safe points: a Ctrl-C is never lost.
_INTERRUPTED = False


def on_interrupt(signum=None, frame=None):
    """Signal handler: remember the interrupt, then raise KeyboardInterrupt."""
    global _INTERRUPTED
    _INTERRUPTED = True
    raise KeyboardInterrupt


def check_interrupt() -> None:
    """Raise KeyboardInterrupt if an interrupt arrived and was swallowed on its way."""
    if _INTERRUPTED:
        raise KeyboardInterrupt


def interrupt_seen() -> bool:
    return _INTERRUPTED


def problems_error(problems: list[str]) -> ShootoutError:
    """One error (exit 2) listing every problem, one per line."""
    if len(problems) == 1:
        return ShootoutError(problems[0])
    return ShootoutError(f"{len(problems)} problems:\n" + "\n".join(f"  - {p}" for p in problems))
