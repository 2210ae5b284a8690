"""What every ``sigmatau`` command shares: exit codes, the parser and console, input and output options,
atomic writes, and the one-line error type for a usage error."""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
from pathlib import Path
from typing import Any, NoReturn, Optional, Sequence

from ..errors import ParameterError
from ..report.outputs import printable

EXIT_OK, EXIT_DATA, EXIT_USAGE, EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_TERMINATED = 0, 1, 2, 3, 130, 143


class _Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread so that the same clean-up as for Ctrl-C runs."""


def _on_sigterm(signum: int, frame: Any) -> None:
    raise _Terminated()


class _UsageError(Exception):
    """Raised by the parser instead of exiting, so ``main`` returns the code."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:
        raise _UsageError(f"{self.prog}: error: {message}")


class _Formatter(argparse.RawDescriptionHelpFormatter):
    def __init__(self, prog: str) -> None:
        super().__init__(prog, max_help_position=32, width=100)


class _Console:
    def __init__(self, quiet: bool) -> None:
        self.quiet = quiet
        self.tty = sys.stderr.isatty()

    def progress(self, text: str) -> None:
        if not self.quiet and self.tty:
            _say(f"  {text}", err=True, flush=True)


class _StepDisplay:
    """The analysis's progress on a terminal: one tqdm bar with the steps running and the time left.

    Fed with :class:`sigmatau.analysis.StepEvent` from the worker threads. Drawn only on a
    terminal, without ``--quiet`` and with tqdm installed (the ``progress`` extra, part of
    ``plot`` and ``all``); otherwise the console prints a line per channel as before. The time
    left is tqdm's, in units of :data:`sigmatau.analysis.STEP_COST` (measured seconds per step).
    """

    #: Seconds between redraws (tqdm's ``mininterval``).
    MININTERVAL = 0.5

    def __init__(self, console: _Console) -> None:
        import threading

        self.console = console
        self.lock = threading.Lock()
        self.running: dict[tuple[str, str], None] = {}
        self.bar: Any = None
        self.enabled = False
        if not console.quiet and console.tty:
            import importlib.util

            self.enabled = importlib.util.find_spec("tqdm") is not None

    def event(self, ev: Any) -> None:
        if not self.enabled:
            return
        with self.lock:
            if self.bar is None:
                import shutil

                from tqdm import tqdm

                # The size once, with a fallback: a terminal that reports 0 × 0 (a pty without a size,
                # as under `script` or some CI runners) makes tqdm draw nothing at all.
                size = shutil.get_terminal_size((100, 24))
                self.bar = tqdm(total=ev.total, file=sys.stderr, leave=False, mininterval=self.MININTERVAL,
                                ncols=size.columns or 100, nrows=size.lines or 24,
                                bar_format="analysing {percentage:3.0f}%|{bar:20}| {elapsed} elapsed,"
                                           " ≈{remaining} left{postfix}")
            if ev.done:
                self.running.pop((ev.channel, ev.step), None)
                self.bar.update(ev.weight)
            else:
                self.running[(ev.channel, ev.step)] = None
            now = ", ".join(f"{c}: {'IMU model' if s == 'model' else s}" for c, s in self.running)
            self.bar.set_postfix_str(printable(now), refresh=False)

    def line(self, text: str) -> None:
        """A line per finished channel: above the bar when it is drawn."""
        if self.bar is not None:
            with self.lock:
                self.bar.write(printable(f"  {text}"), file=sys.stderr)
        else:
            self.console.progress(text)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def _say(text: str, *, err: bool = False, multiline: bool = False, flush: bool = False) -> None:
    """Print one message (stdout, or stderr with ``err``) with its control characters escaped.

    Every line the command prints goes through here: names and messages come from the user's
    files, and an escape sequence in them must not drive the terminal (:func:`printable`).
    ``multiline`` keeps the newlines of our own multi-line text (summary, tables).
    """
    print(printable(text, multiline=multiline), file=sys.stderr if err else sys.stdout, flush=flush)


def _say_row(fields: Sequence[Any]) -> None:
    """One tab-separated line on stdout, each field escaped as by :func:`_say` (the tabs are ours)."""
    print("\t".join(printable(f) for f in fields))


def _showwarning(message: Any, category: type, filename: str, lineno: int, file: Any = None,
                 line: Optional[str] = None) -> None:
    _say(f"sigmatau: warning: {message}", err=True)


_LOG_HELP = ("CSV/TSV/text, .npy/.npz, Stable32 data, ROS 1 .bag, ROS 2 bag directory (sqlite3 or MCAP), HDF5 (.h5)"
             " or Parquet")


def _add_input_options(p: argparse.ArgumentParser, *, many: bool = False) -> None:
    g = p.add_argument_group("input")
    if many:
        g.add_argument("logs", nargs="+", metavar="LOG", help=f"the logs, read with the same options: {_LOG_HELP}")
    else:
        g.add_argument("log", help=f"the log: {_LOG_HELP}")
    g.add_argument("--format", help="reader, when detection is not wanted: csv, stable32, npy, npz, rosbag1,"
                                    " rosbag2, hdf5, parquet")
    g.add_argument("--columns", help="channels by column name or 0-based index, comma-separated"
                                     " (default: the IMU columns, else every numeric column)")
    g.add_argument("--time-column", help="the timestamp column (default: found by name); 'none' for none")
    g.add_argument("--time-unit", choices=["s", "ms", "us", "ns", "min", "h", "d"],
                   help="unit of the timestamps (default: from the name, magnitude or step)")
    g.add_argument("--rate", type=float, help="sample rate in Hz (needed without timestamps; overrides them)")
    g.add_argument("--data-type", choices=["freq", "phase"],
                   help="freq: sensor output or fractional frequency (default); phase: integrated data")
    g.add_argument("--topic", help="ROS bags: the sensor_msgs/Imu topic (needed when there are several)")
    g.add_argument("--list-topics", action="store_true", help="ROS bags: list the topics and stop")
    g.add_argument("--dataset", help="HDF5: the dataset or group to read")
    g.add_argument("--stamps", choices=["header", "bag"], help="ROS bags: header.stamp (default) or receive time")
    g.add_argument("--delimiter", help="text files: the field delimiter (default: detected)")
    t = p.add_argument_group("timing policies")
    t.add_argument("--gaps", choices=["auto", "mark", "refuse", "split", "ignore"], default="auto",
                   help="missing samples: auto (default: mark them when at most 10%% are missing, else refuse),"
                        " mark (place the samples on the time grid, each missing one a gap that every statistic"
                        " skips), refuse (the message says where), split (analyse the longest gap-free segment)"
                        " or ignore (analyse as if evenly spaced)")
    t.add_argument("--gap-threshold", type=float, default=1.5, help="a gap is a step longer than this many"
                                                                     " median steps (default 1.5)")
    t.add_argument("--unsorted", choices=["sort", "refuse"], default="sort",
                   help="timestamps going backwards: sort with a warning (default) or refuse")
    t.add_argument("--duplicates", choices=["drop", "refuse"], default="drop",
                   help="repeated timestamps: keep the first with a warning (default) or refuse")
    u = p.add_argument_group("units (defaults: the file's, else gyro rad/s and accel m/s^2 as in ROS REP 103)")
    u.add_argument("--gyro-unit", help="rad/s, mrad/s, deg/s, mdps, deg/h")
    u.add_argument("--accel-unit", help="m/s^2, mm/s^2, g, mg, ug")
    u.add_argument("--unit", action="append", default=[], metavar="CHANNEL=UNIT",
                   help="unit of one channel (repeatable)")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.add_argument("--debug", action="store_true", help="show the traceback of an error")


def _add_analysis_options(p: argparse.ArgumentParser, default_stats: str, theoh: str = "fast",
                          as_recorded: bool = False) -> None:
    """The analysis and preparation options; ``as_recorded`` (``stats``: Stable32-like tables of the
    record as given) makes ``--warmup keep --temperature off`` the defaults."""
    g = p.add_argument_group("analysis")
    g.add_argument("--stat", default=default_stats,
                   help=f"statistics, comma-separated (default {default_stats}); any of stdev, ostdev, adev, oadev,"
                        " mdev, tdev, hdev, ohdev, mhdev, ldev, pdev, totdev, mtotdev, ttotdev, htotdev, mhtotdev,"
                        " theo1, theobr, theoh, mtie, tierms")
    g.add_argument("--taus", default="octave", help="τ grid: octave (default), decade, all, log")
    g.add_argument("--confidence", type=float, default=0.6827, help="two-sided coverage of the intervals"
                                                                     " (default 0.6827, ±1σ)")
    g.add_argument("--workers", type=int, help="channels analysed at once (default: the cores)")
    g.add_argument("--theoh", choices=["fast", "exact"], default=theoh,
                   help=f"TheoH's TheoBR rows: fast (Fast TheoBR on block averages above 65,536 points, unless"
                        f" κ indicates phase noise) or exact (default {theoh}; docs/theoh-fast.md)")
    g.add_argument("--theo1-bias", choices=["none", "published"], default="none",
                   help="Theo1 raw (default, as Stable32 prints it with Alpha 0) or divided by Howe & Tasset's"
                        " AVAR/Theo1 bias of the noise type identified at each τ (published)")
    pr = p.add_argument_group("preparation (applied to every channel in this order; docs/prep.md)")
    pr.add_argument("--part", metavar="START:END",
                    help="keep this time range, seconds from the first sample (either side may be empty)")
    pr.add_argument("--outliers", type=float, metavar="K",
                    help="replace by gaps the samples more than K robust standard deviations (MAD) from the median")
    pr.add_argument("--drift", metavar="MODEL",
                    help="remove the drift: linear, bisection, log or diffusion (frequency/rate data);"
                         " quadratic, diff2, 3point or greenhall (phase data)")
    warm, temp = ("keep", "off") if as_recorded else ("auto", "auto")
    pr.add_argument("--warmup", default=warm, metavar="auto|keep|SECONDS",
                    help="the settling of the bias after power-on: auto (detected on the gyro and accel"
                         " channels and left out, saying so), keep, or a number of seconds to leave out"
                         f" (default {warm})")
    pr.add_argument("--temperature", choices=["auto", "off"], default=temp,
                    help="auto: with a temperature column, fit each gyro and accel channel's bias against it"
                         f" and analyse the compensated residual (the raw curve beside it); off (default {temp})")
    pr.add_argument("--average", type=int, metavar="M", help="average M consecutive samples (rate becomes rate/M)")
    g.add_argument("--gauss-markov", choices=["auto", "never", "always"], default="auto",
                   help="the IMU model's first-order Gauss–Markov term (σ, correlation time): auto (default: kept"
                        " when BIC prefers it to the five terms), never, always")
    g.add_argument("--dynamic", metavar="WINDOW:STEP",
                   help="also OADEV over sliding windows of WINDOW seconds every STEP seconds, a heat map and a"
                        " check that the windows agree within their intervals (non-stationarity)")


def _preparation(args: argparse.Namespace) -> Any:
    """The :class:`~sigmatau.pipeline.prepare.Preparation` of the preparation options (None when none)."""
    from ..pipeline.prepare import Preparation, parse_part

    if args.outliers is not None and not (math.isfinite(args.outliers) and args.outliers > 0):
        raise _UsageError(f"--outliers {args.outliers!r} must be a positive number")
    if args.average is not None and args.average < 1:
        raise _UsageError(f"--average {args.average!r} must be a positive integer")
    try:
        part = None if args.part is None else parse_part(args.part)
    except ParameterError as exc:
        raise _UsageError(f"--part: {exc}") from None
    warm: Any = args.warmup
    if warm not in ("auto", "keep"):
        try:
            warm = float(warm)
        except ValueError:
            raise _UsageError(f"--warmup {args.warmup!r} must be auto, keep or a number of seconds") from None
        if not (math.isfinite(warm) and warm >= 0):
            raise _UsageError(f"--warmup {args.warmup!r} must be auto, keep or a non-negative number of seconds")
    prep = Preparation(part=part, warmup=warm, temperature=args.temperature, outliers=args.outliers,
                       drift=args.drift, average=args.average)
    return prep if prep else None


def _dynamic_spec(args: argparse.Namespace) -> Optional[tuple[float, float]]:
    """``--dynamic WINDOW:STEP`` in seconds as ``(window, step)``, None when not given."""
    if args.dynamic is None:
        return None
    parts = args.dynamic.split(":")
    try:
        window, step = (float(v) for v in parts)
    except ValueError:
        raise _UsageError(f"--dynamic {args.dynamic!r} must be WINDOW:STEP in seconds, e.g. 600:60") from None
    if not (math.isfinite(window) and math.isfinite(step) and window > 0 and step > 0):
        raise _UsageError(f"--dynamic {args.dynamic!r}: window and step must be positive numbers of seconds")
    return window, step


def _read_options(args: argparse.Namespace) -> dict[str, Any]:
    """The keyword arguments of :func:`sigmatau.io.read` given by the input options (shared with batch)."""
    kw: dict[str, Any] = {}
    for name in ("format", "time_unit", "rate", "data_type", "topic", "dataset", "stamps", "delimiter"):
        if getattr(args, name) is not None:
            kw[name] = getattr(args, name)
    if args.columns:
        kw["columns"] = [int(c) if c.strip().lstrip("-").isdigit() else c.strip() for c in args.columns.split(",")]
    if args.time_column is not None:
        tc = args.time_column
        kw["time_column"] = False if tc.lower() == "none" else (int(tc) if tc.isdigit() else tc)
    kw.update(gaps=args.gaps, gap_threshold=args.gap_threshold, unsorted=args.unsorted, duplicates=args.duplicates)
    units: dict[str, str] = {}
    if args.gyro_unit:
        units["gyro"] = args.gyro_unit
    if args.accel_unit:
        units["accel"] = args.accel_unit
    for spec in args.unit:
        name, sep, unit = spec.partition("=")
        if not sep or not name or not unit:
            raise _UsageError(f"--unit {spec!r} must be CHANNEL=UNIT")
        units[name.strip()] = unit.strip()
    if units:
        kw["units"] = units
    return kw


def _read(args: argparse.Namespace, console: _Console) -> Any:
    from .. import io

    return io.read(args.log, progress=False if console.quiet else None, **_read_options(args))


def _figure_formats(args: argparse.Namespace) -> list[str]:
    if args.no_figures:
        return []
    fmts = [f.strip().lower() for f in args.figures.split(",") if f.strip()]
    return fmts


def _add_output_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("outputs")
    g.add_argument("--out", help="output directory (default: <log name>-sigmatau); written atomically")
    g.add_argument("--force", action="store_true", help="replace an existing output directory")
    g.add_argument("--figures", default="png,svg", help="figure formats: png, svg, pdf (default png,svg)")
    g.add_argument("--no-figures", action="store_true", help="no figures (and no figures in the report)")
    g.add_argument("--no-report", action="store_true", help="no report.html")
    m = p.add_argument_group("IMU model and Kalibr")
    m.add_argument("--no-model", action="store_true", help="statistics only, no IMU noise model")
    m.add_argument("--axis-rule", choices=["max", "rms", "mean"], default="max",
                   help="how the three axes combine into the Kalibr values (default: the largest)")
    m.add_argument("--inflate", type=float, default=1.0, help="inflation factor of the Kalibr values (default 1)")
    m.add_argument("--rostopic", default="/imu0", help="rostopic written to imu.yaml (default /imu0)")
    m.add_argument("--export", default="kalibr", metavar="LIST",
                   help="estimator parameter files: kalibr (imu.yaml), vins (vins_imu.yaml), openvins"
                        " (kalibr_imu_chain.yaml), matlab (imu_params.m), gtsam (gtsam_imu_params.py),"
                        " comma-separated, or none (default kalibr)")
    m.add_argument("--datasheet", action="append", default=[], metavar="PART|GROUP.TERM=VALUE UNIT",
                   help="datasheet figures to compare and overlay: a part (lsm6dsl, lsm6dsm, adis16448, euroc) or"
                        " a value such as 'gyro.N=4 mdps/sqrt(Hz)' (repeatable)")


def _add_folder_outputs(p: argparse.ArgumentParser, files: str, rows: str) -> None:
    """The outputs of a command that prints a table: ``--csv`` instead, or ``--out`` a folder besides."""
    o = p.add_argument_group("outputs")
    o.add_argument("--out", help=f"also write {files}, the figure and report.html here (atomically)")
    o.add_argument("--csv", help=f"write {rows} as CSV to this file ('-' for stdout) instead of printing")
    o.add_argument("--force", action="store_true", help="replace an existing output")
    o.add_argument("--figures", default="png,svg", help="figure formats: png, svg, pdf (default png,svg)")
    o.add_argument("--no-figures", action="store_true", help="no figures")
    o.add_argument("--no-report", action="store_true", help="no report.html")


def _check_folder_outputs(args: argparse.Namespace, inputs: Sequence[Path]) -> list[str]:
    """The figure formats of :func:`_add_folder_outputs`, after refusing, before any work, an
    output folder or CSV file that is an input, exists without ``--force`` or is not ours."""
    from ..report.outputs import FIGURE_FORMATS, check_output_dir

    if not 0 < args.confidence < 1:
        raise _UsageError(f"--confidence {args.confidence!r} must be between 0 and 1")
    fmts = [] if args.no_figures else [f.strip().lower() for f in args.figures.split(",") if f.strip()]
    for f in fmts:
        if f not in FIGURE_FORMATS:
            raise _UsageError(f"--figures: {f!r} is not one of {', '.join(FIGURE_FORMATS)}")
    if args.out:
        check_output_dir(Path(args.out), force=args.force, protect=list(inputs))
    if args.csv and args.csv != "-":
        if Path(args.csv).resolve() in inputs:
            raise _UsageError(f"--csv {args.csv!r} is an input; choose another file")
        _check_replaceable(Path(args.csv), "--csv", args.force, stdout_hint=True)
    return fmts


def _emit_csv(args: argparse.Namespace, text: str) -> None:
    """``--csv`` text to standard output (escaped on a terminal) or, atomically, to its file."""
    from ..report.outputs import printable

    if args.csv == "-":
        sys.stdout.write(printable(text, multiline=True) if sys.stdout.isatty() else text)
    else:
        _atomic_write(Path(args.csv), text.encode())
        _say(f"wrote {args.csv}", err=True)


def _datasheet(specs: Sequence[str]) -> Any:
    from ..pipeline.analysis import datasheet_reference

    if not specs:
        return None
    merged: dict[str, dict[str, Any]] = {}
    for spec in specs:
        if "=" in spec:
            key, _, value = spec.partition("=")
            group, dot, term = key.strip().partition(".")
            if not dot:
                raise _UsageError(f"--datasheet {spec!r} must be PART or GROUP.TERM=VALUE UNIT")
            merged.setdefault(group, {})[term.strip()] = value.strip()
        else:
            for group, terms in datasheet_reference(spec).items():
                merged.setdefault(group, {}).update({t: v for t, v in terms.items()})
    return merged


def _check_out(args: argparse.Namespace, default: Path, protect: Sequence[str] = ()) -> Path:
    """The output directory and the output options, checked before any long computation."""
    from ..report.outputs import FIGURE_FORMATS, check_output_dir

    out = Path(args.out) if args.out else default
    check_output_dir(out, force=args.force, protect=protect)
    for f in args.figures.split(","):
        if f.strip().lower() not in FIGURE_FORMATS:
            raise _UsageError(f"--figures: {f!r} is not one of {', '.join(FIGURE_FORMATS)}")
    if not 0 < args.confidence < 1:
        raise _UsageError(f"--confidence {args.confidence!r} must be between 0 and 1")
    if printable(args.rostopic) != args.rostopic:  # it goes into imu.yaml: one line, as ROS names are
        raise _UsageError(f"--rostopic '{printable(args.rostopic)}' contains a control character (newline, tab,"
                          " escape, …); give the topic name alone")
    _exports(args)
    return out


def _exports(args: argparse.Namespace) -> tuple[str, ...]:
    """``--export`` as a tuple of targets; a usage error naming the known ones."""
    from ..report.outputs import parse_exports

    try:
        return parse_exports(args.export)
    except ParameterError as exc:
        raise _UsageError(f"--export: {exc}") from None


def _check_replaceable(path: Path, what: str, force: bool, *, stdout_hint: bool = False) -> None:
    """A file the command may write: new, or with ``force`` an existing regular file (never a
    directory, device or pipe, which renaming over would destroy); --force is offered only where
    it would be accepted."""
    if not os.path.lexists(path):
        return
    if path.is_symlink() or not path.is_file():
        kind = "a directory" if path.is_dir() else "not a regular file"
        hint = "; use '-' for standard output" if stdout_hint else "; choose a file name"
        raise _UsageError(f"{what} {str(path)!r} is {kind}{hint}")
    if not force:
        raise _UsageError(f"{what} {str(path)!r} exists; use --force to replace it")


def _atomic_write(path: Path, data: bytes) -> None:
    """Write through a temporary file in the same directory and rename it into place."""
    from ..report.outputs import umask

    parent = path.resolve().parent
    if not parent.is_dir():
        raise _UsageError(f"{str(path)!r}: the directory does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".partial", dir=parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.chmod(tmp, 0o666 & ~umask())  # mkstemp makes 0600; give the file the usual mode
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _write_csv(path: Path, header: list[str], columns: list[Any]) -> None:
    import io as _io

    import numpy as np

    buf = _io.StringIO()
    np.savetxt(buf, np.column_stack(columns), delimiter=",", fmt="%.10g", header=",".join(header), comments="")
    _atomic_write(path, buf.getvalue().encode())


def _write_stable32(path: Path, values: Any) -> None:
    """A Stable32 data file: one value per line, no header, CRLF (Stable32 is a Windows program).

    17 significant digits: a float64 phase record read back is bit-identical, so
    statistics computed by Stable32 and by sigmatau on the file see the same samples.
    """
    import io as _io

    import numpy as np

    buf = _io.StringIO()
    np.savetxt(buf, np.asarray(values, dtype=np.float64), fmt="%.17g", newline="\r\n")
    _atomic_write(path, buf.getvalue().encode("ascii"))


def _atomic_npy(path: Path, array: Any) -> None:
    import io as _io

    import numpy as np

    buf = _io.BytesIO()
    np.save(buf, array)
    _atomic_write(path, buf.getvalue())


def _atomic_npz(path: Path, arrays: dict) -> None:
    import io as _io

    import numpy as np

    buf = _io.BytesIO()
    np.savez(buf, **arrays)
    _atomic_write(path, buf.getvalue())


_EPILOG_ERRORS = """
exit codes: 0 success; 1 data error (missing, unreadable or corrupt file, no numeric data, too few
samples); 2 usage error (bad option value, unknown column or topic, output exists); 3 internal error.
"""


def _analysis_options(args: argparse.Namespace, display: "_StepDisplay") -> dict[str, Any]:
    """The keyword arguments of :func:`sigmatau.analysis.analyze_log` given by the options (shared by the
    in-memory and the out-of-core runs of ``sigmatau analyze``)."""
    return dict(statistics=args.stat, taus=args.taus, confidence=args.confidence, model=not args.no_model,
                axis_rule=args.axis_rule, inflate=args.inflate, rostopic=args.rostopic,
                datasheet=_datasheet(args.datasheet), workers=args.workers, progress=display.line,
                theoh=args.theoh, theo1_bias=args.theo1_bias, on_step=display.event, prep=_preparation(args),
                dynamic=_dynamic_spec(args), gauss_markov=args.gauss_markov)


def _run_analysis(log: Any, args: argparse.Namespace, console: _Console, out: Path) -> int:
    from ..pipeline.analysis import analyze_log

    display = _StepDisplay(console)
    try:
        analysis = analyze_log(log, **_analysis_options(args, display))
    finally:
        display.close()
    protect = [] if log.source.format == "memory" else [log.source.path]
    return _write_analysis(analysis, args, out, protect)


def _write_analysis(analysis: Any, args: argparse.Namespace, out: Path, protect: Sequence[str]) -> int:
    """Write the outputs of ``analysis`` (atomically) and print its summary."""
    from ..report.outputs import write_outputs

    files = write_outputs(analysis, out, force=args.force, figures=_figure_formats(args),
                          report=not args.no_report, protect=protect, exports=_exports(args))
    _say(analysis.summary(), multiline=True)
    _say("")
    _say(f"wrote {len(files)} files to {out}/: {', '.join(f.name for f in files)}")
    return EXIT_OK
