"""The ``sigmatau`` command.

A thin layer over the public API (:mod:`sigmatau.io`, :mod:`sigmatau.analysis`,
:mod:`sigmatau.outputs`, :mod:`sigmatau.imu`): it parses arguments, calls the
library and prints. Every error is one line on stderr — exit code 2 for a
usage error (a bad option value, a column or topic that does not exist, an
output that exists), 1 for a data error (a missing, unreadable or corrupt file,
no numeric data, too few samples) — with the traceback only under ``--debug``.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import textwrap
import threading
import warnings
from typing import Optional, Sequence

from .._version import __version__
from .common import (
    EXIT_DATA, EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_OK, EXIT_TERMINATED, EXIT_USAGE, _Console,
    _EPILOG_ERRORS, _Formatter, _Parser, _Terminated, _UsageError, _on_sigterm, _say, _showwarning,
)
from . import analyze, batch, compare, demo, psd, simulate, stats, watch

__all__ = ["main"]


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="sigmatau",
        description="Noise analysis of sensors (MEMS gyroscopes, accelerometers, clocks) with the Allan family"
                    " of variances: AVAR, MVAR, TVAR, HVAR, total variances, Theo1/TheoBR/TheoH, noise"
                    " identification, confidence intervals and the IMU noise model (ST DT0064).",
        formatter_class=_Formatter,
        epilog=textwrap.dedent("""
            examples:
              sigmatau demo                          simulate an IMU and write the full analysis to sigmatau-demo/
              sigmatau analyze imu0/data.csv --out euroc
              sigmatau analyze run.bag --topic /imu/data --gyro-unit rad/s --out run
              sigmatau stats clock.txt --stat adev,mdev,theo1
              sigmatau compare a.csv b.csv c.csv --columns gyro_z --out hat
              sigmatau psd imu.csv --out imu-psd
              sigmatau simulate imu.csv --preset lsm6dsl --duration 3600
              sigmatau watch imu.csv --serve                σ–τ live while the log is written
            """) + _EPILOG_ERRORS,
    )
    parser.add_argument("--version", action="version", version=f"sigmatau {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    for command in (demo, analyze, stats, compare, psd, simulate, batch, watch):  # the order of `sigmatau --help`
        command.add_cli(sub)
    return parser


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Entry point of the ``sigmatau`` command; returns the exit code."""
    from ..errors import DataError, ParameterError, SigmaTauError
    from ..io import InputNotFoundError, MissingDependencyError
    from ..report.outputs import OutputExistsError

    for stream in (sys.stdout, sys.stderr):  # a terminal that cannot show µ or τ gets '?', not a crash
        reconfigure = getattr(stream, "reconfigure", None)
        if reconfigure is not None:
            try:
                reconfigure(errors="replace")
            except (ValueError, OSError):
                pass
    parser = _parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv
    try:
        args = parser.parse_args(argv)
    except _UsageError as exc:
        _say(str(exc), err=True)
        return EXIT_USAGE
    except SystemExit as exc:  # --help, --version
        return int(exc.code or 0)
    if args.command is None:
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    console = _Console(getattr(args, "quiet", False))
    old_show = warnings.showwarning
    warnings.showwarning = _showwarning
    old_term = None
    if threading.current_thread() is threading.main_thread():  # `kill` removes temporary files as Ctrl-C does
        old_term = signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        return int(args.func(args, console))
    except _UsageError as exc:
        code, msg = EXIT_USAGE, str(exc)
        if debug:
            raise
    except (ParameterError, OutputExistsError) as exc:
        code, msg = EXIT_USAGE, str(exc)
        if debug:
            raise
    except (DataError, InputNotFoundError, MissingDependencyError, SigmaTauError) as exc:
        code, msg = EXIT_DATA, str(exc)
        if debug:
            raise
    except BrokenPipeError:  # `sigmatau ... | head`: the reader left; not an error of ours
        try:
            sys.stdout = open(os.devnull, "w")
        except OSError:
            pass
        return EXIT_OK
    except OSError as exc:
        code, msg = EXIT_DATA, f"{exc.strerror or exc}: {exc.filename}" if exc.filename else str(exc)
        if debug:
            raise
    except _Terminated:
        _say("sigmatau: terminated (SIGTERM)", err=True)
        return EXIT_TERMINATED
    except KeyboardInterrupt:
        _say("sigmatau: interrupted", err=True)
        return EXIT_INTERRUPTED
    except Exception as exc:  # a bug: say so in one line, traceback with --debug
        if debug:
            raise
        code, msg = EXIT_INTERNAL, f"internal error: {type(exc).__name__}: {exc} (run with --debug for details)"
    finally:
        warnings.showwarning = old_show
        if old_term is not None:
            signal.signal(signal.SIGTERM, old_term)
    _say(f"sigmatau: error: {msg.strip() or 'failed'}", err=True)  # a newline in a file name stays "\\n"
    return code
