"""`shootout` command line. Exit codes: 0 finished, 1 internal failure (or `compare` found a
regression), 2 bad config or arguments (one message, nothing written)."""
from __future__ import annotations

import argparse
import os
import sys

from .cli_commands import (_cmd_compare, _cmd_datasets, _cmd_eval, _cmd_methods, _cmd_report,
                           _cmd_run, _cmd_views, check_output_file, method_record)
from .errors import ShootoutError

__all__ = ["check_output_file", "main", "method_record", "threading_main"]


class _Parser(argparse.ArgumentParser):
    def error(self, message):                       # argparse exits 2 as well; keep one style
        self.print_usage(sys.stderr)
        print(f"shootout: error: {message}", file=sys.stderr)
        raise SystemExit(2)


def _number(kind):
    """An argparse type that converts to ``kind`` when it can and keeps the text otherwise, so a
    malformed number is listed with the config's and the other flags' problems in one message
    (argparse would stop at the first)."""
    def convert(text: str):
        try:
            return kind(text)
        except ValueError:
            return text
    convert.__name__ = kind.__name__
    return convert


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="shootout", description="Compare geometry-processing methods (Laplacians, smoothing, simplification, geodesics, curvature, spectra).")
    from . import __version__
    p.add_argument("--version", action="version", version=f"mesh-shootout {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    r = sub.add_parser("run", help="run a config and write its run folder")
    r.add_argument("config")
    r.add_argument("--out", help="run folder (default results/<name>)")
    r.add_argument("--workers", type=_number(int), help="cases in parallel (default: number of cores; 1 for timing-grade numbers)")
    r.add_argument("--executor", choices=["local", "dask", "serial"], default="local")
    r.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://host:8786")
    r.add_argument("--resume", action="store_true", help="skip cases already recorded with status ok")
    r.add_argument("--timeout", type=_number(float), help="seconds per case before it is killed (status timeout)")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    r.add_argument("--export-benchmark-json", metavar="FILE", help="also write timings in pytest-benchmark's JSON layout")
    m = sub.add_parser("methods", help="list registered methods")
    from . import tasks                     # here, not at import: main's Ctrl-C handler is set by now
    m.add_argument("--task", choices=tasks.names())
    m.add_argument("--json", action="store_true", help="machine-readable: one JSON list")
    m.add_argument("--plugin", action="append", default=[], metavar="MODULE",
                   help="import this plugin module first (as a config's plugins:), to list its methods")
    ds = sub.add_parser("datasets", help="list bundled and procedural meshes")
    ds.add_argument("--json", action="store_true", help="machine-readable: one JSON list")
    rp = sub.add_parser("report", help="rebuild report.html, the leaderboard and the winners from a run folder "
                                       "(reads files only, runs no code)")
    rp.add_argument("run_dir")
    vw = sub.add_parser("views", help="recompute a run folder's 3D views (runs the chosen methods again)")
    vw.add_argument("run_dir")
    ev = sub.add_parser("eval", help="score result meshes made elsewhere; writes a run folder and its report")
    ev.add_argument("results", nargs="+", metavar="RESULT", help="result mesh files (OBJ, OFF, PLY, STL)")
    ev.add_argument("--clean", required=True, help="the clean (reference) mesh")
    ev.add_argument("--noisy", help="the noisy input the results were made from (smoothing: the input_* columns; "
                    "simplification: the surface a result is compared to, as in a run; without it, the clean mesh)")
    ev.add_argument("--out", required=True, help="run folder to write")
    ev.add_argument("--task", choices=["smoothing", "simplification"],
                    help="default: smoothing when a result has the clean mesh's vertex and face counts, else simplification")
    ev.add_argument("--label", action="append", metavar="NAME",
                    help="method label of each result, in order, one per --label (--label a --label b: one name "
                         "each, so a result file after it is never read as a label; default: file stem)")
    ev.add_argument("--hausdorff-samples", type=_number(int), default=20000, help="area samples per side (as in a config)")
    ev.add_argument("--hausdorff-eps", type=_number(float), default=1e-3, metavar="EPS",
                    help="relative gap the certified Hausdorff distance aims for (as in a config; default 1e-3)")
    ev.add_argument("--target-faces", type=_number(int), default=None, metavar="N",
                    help="simplification: the face count the results were asked for (judges over_target)")
    ev.add_argument("--target-ratio", type=_number(float), default=None, metavar="R",
                    help="simplification: the fraction of the clean mesh's faces asked for (instead of --target-faces)")
    c = sub.add_parser("compare", help="compare two run folders; exit 1 on a regression")
    c.add_argument("run_a")
    c.add_argument("run_b")
    c.add_argument("--html", metavar="FILE", help="also write an HTML diff")
    c.add_argument("--time-factor", type=_number(float), default=None, metavar="X",
                   help="a time regression needs B slower than X times A (default 1.5)")
    c.add_argument("--absolute-time", action="store_true",
                   help="judge raw times (default: relative to the whole run's drift, the median B/A over cases)")
    c.add_argument("--no-time", action="store_true",
                   help="compare metrics only (runs from different or loaded machines)")
    return p


class _PipeSafe:
    """A text stream that survives its reader going away (``| head -1``, ``2>&-``): once a write
    fails with a broken pipe (or there is no stream at all), the rest goes to /dev/null, so the
    command still finishes its work and returns its own exit code (a regression found by
    `compare` is exit 1 whether or not anyone read the lines)."""

    def __init__(self, inner):
        self._inner, self.broken = inner, inner is None

    def _call(self, fn, *args):
        """``fn(*args)`` on the inner stream; a reader gone (broken pipe, closed stream) ends it."""
        try:
            return fn(*args)
        except BrokenPipeError:
            self._broke()
        except ValueError:                    # also an encoding error, which is not a reader gone
            if not getattr(self._inner, "closed", False):
                raise
            self._broke()
        return None

    def write(self, s):
        if self.broken:
            return len(s)
        try:
            n = self._call(self._inner.write, s)
        except UnicodeEncodeError:            # a name the terminal's encoding lacks: escaped, not lost
            enc = getattr(self._inner, "encoding", None) or "utf-8"
            return self.write(s.encode(enc, "backslashreplace").decode(enc))
        return len(s) if n is None else n

    def flush(self):
        if not self.broken:
            self._call(self._inner.flush)

    def isatty(self) -> bool:
        try:
            return not self.broken and self._inner.isatty()
        except (OSError, ValueError):
            return False

    def _broke(self):
        self.broken = True
        try:                                 # the interpreter's last flush must not fail either
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, self._inner.fileno())
            os.close(devnull)
        except (OSError, ValueError, AttributeError):
            pass

    def __getattr__(self, name):
        return getattr(self._inner, name)


def threading_main() -> bool:
    import threading
    return threading.current_thread() is threading.main_thread()


def main(argv=None) -> int:
    """The ``shootout`` command: ``main()`` reads ``sys.argv`` and is the command itself (after it
    returns, a SIGINT or SIGTERM ends the process with its exit code, so a late signal cannot turn
    a 130 into an exit by SIGTERM); a caller from Python passes ``argv`` and gets its own signal
    handlers back."""
    import signal

    from . import errors
    from .errors import on_interrupt
    errors._INTERRUPTED = False
    saved = None
    if threading_main():
        # a terminated run stops like an interrupted one; both are remembered (harness.errors)
        saved = signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT)
        signal.signal(signal.SIGTERM, on_interrupt)
        signal.signal(signal.SIGINT, on_interrupt)
    streams = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = _PipeSafe(sys.stdout), _PipeSafe(sys.stderr)
    code = 1
    try:
        code = _main(argv)
        return code
    except SystemExit as exc:            # argparse: --help (0), a usage error (2)
        code = exc.code if isinstance(exc.code, int) else 1
        raise
    finally:
        sys.stdout.flush()               # a pipe is block-buffered: its break shows here, not at exit
        sys.stderr.flush()
        sys.stdout, sys.stderr = streams
        if saved is not None and argv is None:  # the command's code is known: a late signal ends it with that
            def end(*_):                        # code (the default handler made a 130 an exit by SIGTERM)
                os._exit(code)
            signal.signal(signal.SIGTERM, end)
            signal.signal(signal.SIGINT, end)
        elif saved is not None:                 # an embedding process gets its handlers back
            signal.signal(signal.SIGTERM, saved[0])
            signal.signal(signal.SIGINT, saved[1])
        errors._INTERRUPTED = False


def _main(argv) -> int:
    from .errors import interrupt_seen
    args = None
    try:                       # a Ctrl-C while the parser loads the task kinds is an interrupt too
        args = _parser().parse_args(argv)
        args.command_process = argv is None          # the `shootout` command itself, not a call from Python
        handler = {"run": _cmd_run, "methods": _cmd_methods, "datasets": _cmd_datasets,
                   "report": _cmd_report, "views": _cmd_views, "eval": _cmd_eval,
                   "compare": _cmd_compare}[args.command]
        code = handler(args)
        if interrupt_seen():             # an interrupt swallowed where exceptions are ignored
            raise KeyboardInterrupt
        return code
    except ShootoutError as exc:
        print(f"shootout: {exc}", file=sys.stderr)
        return getattr(exc, "exit_code", 2)
    except KeyboardInterrupt:
        started = getattr(args, "run_started", None)
        print("shootout: interrupted; rows finished so far are saved (use --resume)" if started == "cases" else
              "shootout: interrupted; nothing was written" if getattr(args, "command", None) == "run" and not started
              else "shootout: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:              # stdout closed early (`| head`): stop quietly, like other tools
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        except (OSError, ValueError):
            pass
        return 0
    except OSError as exc:               # a file that cannot be written or read (permissions, a folder in its place)
        if not exc.filename:             # not a file's problem: the traceback says more
            raise
        print(f"shootout: {exc.filename}: {exc.strerror or exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    _code = main()
    # Under `python -m`, CPython ends the process by SIGINT (not this exit code) when a
    # KeyboardInterrupt ever left code run by a string exec, even one caught since: dataclasses
    # build their methods that way, so a Ctrl-C during an import did it. A string exec resets that flag.
    exec("pass")  # noqa: S102
    sys.exit(_code)
