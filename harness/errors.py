"""Exceptions of the harness: each becomes a one-line user message, never a traceback."""
import contextlib


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


@contextlib.contextmanager
def interrupts_deferred():
    """While compiled code is loaded (numba through llvmlite), an interrupt only sets the flag:
    a KeyboardInterrupt raised inside llvmlite's callbacks crashed the process (SIGSEGV). The
    interrupt is raised when the block ends; a second one ends the process at once (exit 130,
    its run folder as an interrupted driver leaves it: ``--resume`` continues). Only in the main
    thread where `on_interrupt` is installed; elsewhere nothing changes."""
    import signal
    import threading
    sigs = (signal.SIGINT, signal.SIGTERM)
    if threading.current_thread() is not threading.main_thread() or \
            any(signal.getsignal(s) is not on_interrupt for s in sigs):
        yield
        return

    def remember(signum=None, frame=None):
        global _INTERRUPTED
        if _INTERRUPTED:
            import os
            os.write(2, b"shootout: interrupted again while compiled code was loading: stopped at once "
                        b"(continue with --resume)\n")
            os._exit(130)
        _INTERRUPTED = True
    for s in sigs:
        signal.signal(s, remember)
    try:
        yield
    finally:
        for s in sigs:
            signal.signal(s, on_interrupt)
    check_interrupt()


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
