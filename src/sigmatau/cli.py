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
import tempfile
import textwrap
import threading
import warnings
from pathlib import Path
from typing import Any, NoReturn, Optional, Sequence

from . import __version__
from .outputs import printable

__all__ = ["main"]

EXIT_OK, EXIT_DATA, EXIT_USAGE, EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_TERMINATED = 0, 1, 2, 3, 130, 143

#: The demo's simulated IMU: LSM6DSL datasheet noise densities (as quoted in
#: ST DT0064) with bias instability and random walk of a typical consumer MEMS
#: part added so the σ–τ curves show the whole bathtub. Illustrative values, SI.
DEMO_IMU = {
    "gyro": {"preset": "lsm6dsl-gyro", "B": 2.4e-5, "K": 1.5e-6},    # B ≈ 5 °/h, K ≈ 18.6 °/h/√h
    "accel": {"preset": "lsm6dsl-accel", "B": 2.0e-4, "K": 2.0e-5},  # B ≈ 20 µg, K ≈ 2 µg/√s
}


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


# --------------------------------------------------------------------- messages


class _Console:
    def __init__(self, quiet: bool) -> None:
        self.quiet = quiet
        self.tty = sys.stderr.isatty()

    def progress(self, text: str) -> None:
        if not self.quiet and self.tty:
            _say(f"  {text}", err=True, flush=True)


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


# ---------------------------------------------------------------------- options


def _add_input_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("input")
    g.add_argument("log", help="the log: CSV/TSV/text, .npy/.npz, Stable32 data, ROS 1 .bag, ROS 2 bag directory"
                               " (sqlite3 or MCAP), HDF5 (.h5) or Parquet")
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
    t.add_argument("--gaps", choices=["refuse", "split", "ignore"], default="refuse",
                   help="missing samples: refuse (default, the message says where), split (analyse the longest"
                        " gap-free segment) or ignore (analyse as if evenly spaced)")
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


def _add_analysis_options(p: argparse.ArgumentParser, default_stats: str) -> None:
    g = p.add_argument_group("analysis")
    g.add_argument("--stat", default=default_stats,
                   help=f"statistics, comma-separated (default {default_stats}); any of stdev, ostdev, adev, oadev,"
                        " mdev, tdev, hdev, ohdev, totdev, mtotdev, ttotdev, htotdev, theo1, theobr, theoh, mtie,"
                        " tierms")
    g.add_argument("--taus", default="octave", help="τ grid: octave (default), decade, all, log")
    g.add_argument("--confidence", type=float, default=0.6827, help="two-sided coverage of the intervals"
                                                                     " (default 0.6827, ±1σ)")
    g.add_argument("--workers", type=int, help="channels analysed at once (default: the cores)")


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
    from . import io

    return io.read(args.log, progress=False if console.quiet else None, **_read_options(args))


def _list_topics(args: argparse.Namespace) -> int:
    from . import io

    topics = io.list_topics(args.log)
    for t in topics:
        _say_row([t.topic, t.msgtype, f"{t.count} messages"])
    return EXIT_OK


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
    m.add_argument("--datasheet", action="append", default=[], metavar="PART|GROUP.TERM=VALUE UNIT",
                   help="datasheet figures to compare and overlay: a part (lsm6dsl, lsm6dsm, adis16448, euroc) or"
                        " a value such as 'gyro.N=4 mdps/sqrt(Hz)' (repeatable)")


def _datasheet(specs: Sequence[str]) -> Any:
    from .analysis import datasheet_reference

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


def _run_analysis(log: Any, args: argparse.Namespace, console: _Console, out: Path) -> int:
    from .analysis import analyze_log
    from .outputs import write_outputs

    analysis = analyze_log(log, statistics=args.stat, taus=args.taus, confidence=args.confidence,
                           model=not args.no_model, axis_rule=args.axis_rule, inflate=args.inflate,
                           rostopic=args.rostopic, datasheet=_datasheet(args.datasheet), workers=args.workers,
                           progress=console.progress)
    protect = [] if log.source.format == "memory" else [log.source.path]
    files = write_outputs(analysis, out, force=args.force, figures=_figure_formats(args),
                          report=not args.no_report, protect=protect)
    _say(analysis.summary(), multiline=True)
    _say("")
    _say(f"wrote {len(files)} files to {out}/: {', '.join(f.name for f in files)}")
    return EXIT_OK


def _check_out(args: argparse.Namespace, default: Path, protect: Sequence[str] = ()) -> Path:
    """The output directory and the output options, checked before any long computation."""
    from .outputs import FIGURE_FORMATS, check_output_dir

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
    return out


# --------------------------------------------------------------------- commands


def _cmd_analyze(args: argparse.Namespace, console: _Console) -> int:
    if args.list_topics:
        return _list_topics(args)
    default = Path(Path(args.log).name.split(".")[0] + "-sigmatau")
    out = _check_out(args, default, protect=[args.log])
    log = _read(args, console)
    return _run_analysis(log, args, console, out)


def _simulated_imu(duration: float, rate: float, seed: int, *, gyro_unit: str = "rad/s",
                   accel_unit: str = "m/s^2", spec: Optional[dict] = None) -> dict[str, Any]:
    """Six channels simulated with :func:`sigmatau.imu.simulate`, independent seeded streams."""
    import numpy as np

    from .imu import simulate
    from .units import convert, term_unit

    spec = spec or DEMO_IMU
    streams = np.random.SeedSequence(seed).spawn(6)
    out: dict[str, Any] = {}
    j = 0
    for group, unit in (("gyro", gyro_unit), ("accel", accel_unit)):
        s = spec.get(group)
        if s is None:
            continue
        si = "rad/s" if group == "gyro" else "m/s^2"
        coefs = {t: float(convert(v, term_unit(si, t), term_unit(unit, t))) for t, v in s.items() if t in "QNBKR"}
        for axis in "xyz":
            out[f"{group}_{axis}"] = simulate(s.get("preset"), duration=duration, rate=rate, unit=unit,
                                              rng=np.random.default_rng(streams[j]), **coefs)
            j += 1
    return out


def _cmd_demo(args: argparse.Namespace, console: _Console) -> int:
    from .analysis import log_from_arrays

    if args.duration <= 0 or args.rate <= 0:
        raise _UsageError("--duration and --rate must be positive")
    out = _check_out(args, Path("sigmatau-demo"))
    n = int(round(args.duration * args.rate))
    _say(f"demo: simulating a 6-axis LSM6DSL-like IMU, {args.duration / 3600:.3g} h at {args.rate:g} Hz"
         f" ({n:,} samples per axis, seed {args.seed})", err=True)
    channels = _simulated_imu(args.duration, args.rate, args.seed)
    units = {k: ("rad/s" if k.startswith("gyro") else "m/s^2") for k in channels}
    log = log_from_arrays(channels, rate=args.rate, units=units,
                          name=f"demo: simulated LSM6DSL-like IMU, seed {args.seed}")
    if not args.datasheet:
        args.datasheet = ["lsm6dsl"]
    return _run_analysis(log, args, console, out)


def _cmd_stats(args: argparse.Namespace, console: _Console) -> int:
    from .analysis import analyze_log

    if args.list_topics:
        return _list_topics(args)
    if not 0 < args.confidence < 1:
        raise _UsageError(f"--confidence {args.confidence!r} must be between 0 and 1")
    if args.csv and args.csv != "-":
        target, source = Path(args.csv).resolve(), Path(args.log).resolve()
        if target == source or source in target.parents:
            raise _UsageError(f"--csv {args.csv!r} is the input; choose another file")
        _check_replaceable(Path(args.csv), "--csv", args.force, stdout_hint=True)
    if args.chunked:
        return _stats_chunked(args)
    log = _read(args, console)
    a = analyze_log(log, statistics=args.stat, taus=args.taus, confidence=args.confidence, model=False,
                    workers=args.workers, progress=console.progress)
    _emit_stats(args, a.channels, f"{log.source.path}: {len(log):,} samples at {log.rate:.6g} Hz, {log.data_type}"
                                  f" data, {a.settings['confidence']:.2%} intervals")
    for w in a.warnings:
        _say(f"sigmatau: warning: {w}", err=True)
    return EXIT_OK


def _stats_chunked(args: argparse.Namespace) -> int:
    """``stats --chunked``: one series read piecewise (:mod:`sigmatau.chunked`), never loaded whole."""
    from . import chunked
    from .analysis import ChannelAnalysis, _check_statistics

    if args.rate is None:
        raise _UsageError("--chunked needs --rate (the file has no timestamps)")
    stats = _check_statistics(args.stat)
    bad = [s for s in stats if s not in chunked.STATISTICS]
    if bad:
        raise _UsageError(f"--chunked computes {', '.join(chunked.STATISTICS)}; not {', '.join(bad)}")
    dtype = args.data_type or "freq"
    chunk = args.chunk_size if args.chunk_size is not None else chunked.DEFAULT_CHUNK
    results = {}
    with chunked.open_series(args.log, dtype=args.dtype, offset=args.offset, count=args.count,
                             dataset=args.dataset, chunk_size=chunk) as source:
        for stat in stats:
            results[stat] = chunked.compute(stat, source, rate=args.rate, data_type=dtype, taus=args.taus,
                                            confidence=args.confidence)
    first = next(iter(results.values()))
    n = first.n_points - (1 if dtype == "freq" else 0)
    name = Path(args.log).stem
    ch = ChannelAnalysis(name=name, group=dtype, unit="", n_samples=n, results=results, skipped={})
    _emit_stats(args, [ch], f"{args.log}: {n:,} samples at {args.rate:.6g} Hz, {dtype} data, read in chunks,"
                            f" {args.confidence:.2%} intervals")
    return EXIT_OK


def _emit_stats(args: argparse.Namespace, channels: Sequence[Any], header: str) -> None:
    """The statistics of ``channels`` as Stable32-style tables on stdout, or as CSV (``--csv``)."""
    from .outputs import statistics_csv

    if args.csv:
        text = statistics_csv(argparse.Namespace(channels=list(channels)))
        if args.csv == "-":
            sys.stdout.write(printable(text, multiline=True) if sys.stdout.isatty() else text)
        else:
            _atomic_write(Path(args.csv), text.encode())
            _say(f"wrote {args.csv}", err=True)
        return
    _say(header)
    for ch in channels:
        for stat, r in ch.results.items():
            _say("")
            _say(f"{ch.name} [{ch.unit or '?'}] {stat.upper()}")
            _say(_stable32_table(r), multiline=True)
        for stat, why in ch.skipped.items():
            _say("")
            _say(f"{ch.name} {stat.upper()}: not computed — {why}")


def _stable32_table(r: Any) -> str:
    import math

    rows = [["AF", "Tau", "#", "Alpha", "Min Sigma", "Sigma", "Max Sigma"]]
    for i in range(len(r.taus)):
        a = r.alpha[i] if r.alpha is not None else math.nan
        lo = r.ci_low[i] if r.ci_low is not None else math.nan
        hi = r.ci_high[i] if r.ci_high is not None else math.nan
        rows.append([str(int(r.m[i])), f"{r.taus[i]:.4e}", str(int(r.n[i])), str(int(a)) if math.isfinite(a) else "-",
                     f"{lo:.4e}" if math.isfinite(lo) else "-", f"{r.dev[i]:.4e}",
                     f"{hi:.4e}" if math.isfinite(hi) else "-"])
    widths = [max(len(row[j]) for row in rows) for j in range(len(rows[0]))]
    return "\n".join("  ".join(c.rjust(w) for c, w in zip(row, widths)) for row in rows)


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
    from .outputs import umask

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


def _coef(text: Optional[str], group: str, term: str, unit: str) -> Optional[float]:
    """A coefficient given as 'value [unit]', in the term's unit for samples in ``unit``."""
    from .errors import SigmaTauError
    from .units import convert, term_unit

    if text is None:
        return None
    num, _, given = text.strip().partition(" ")
    try:
        value = float(num)
    except ValueError:
        raise _UsageError(f"--{group}-{term} {text!r} must be 'value [unit]', e.g. '4 mdps/sqrt(Hz)'") from None
    target = term_unit(unit, term)
    if not given.strip():
        return value
    try:
        return float(convert(value, given.strip(), target))
    except SigmaTauError as exc:
        raise _UsageError(f"--{group}-{term} {text!r}: {exc}") from None


def _cmd_simulate(args: argparse.Namespace, console: _Console) -> int:
    import numpy as np

    from .imu import PRESETS

    out = Path(args.output)
    suffix = out.suffix.lower()
    if suffix not in (".csv", ".npy", ".npz"):
        raise _UsageError(f"output {str(out)!r} must end in .csv, .npy or .npz")
    _check_replaceable(out, "output", args.force)
    if args.duration <= 0:
        raise _UsageError(f"--duration {args.duration!r} must be positive")
    if args.rate is not None and args.rate <= 0:
        raise _UsageError(f"--rate {args.rate!r} must be positive")
    n = int(round(args.duration * (args.rate or 1.0)))
    if args.h:
        return _simulate_power_law(args, out, suffix)
    parts = sorted({k.rsplit("-", 1)[0] for k in PRESETS})
    if args.preset not in parts and args.preset != "none":
        raise _UsageError(f"--preset {args.preset!r}: choose from {', '.join(parts)} or none")
    groups = [g.strip() for g in args.sensors.split(",") if g.strip()]
    for g in groups:
        if g not in ("gyro", "accel"):
            raise _UsageError(f"--sensors: {g!r} is not gyro or accel")
    rate = args.rate or (PRESETS[f"{args.preset}-gyro"].rate if args.preset != "none" else None)
    if rate is None:
        raise _UsageError("--rate is needed with --preset none")
    spec: dict[str, dict] = {}
    units = {"gyro": args.gyro_unit or "rad/s", "accel": args.accel_unit or "m/s^2"}
    for g in groups:
        s: dict[str, Any] = {"preset": None if args.preset == "none" else f"{args.preset}-{g}"}
        si = "rad/s" if g == "gyro" else "m/s^2"
        for t in "QNBKR":
            v = _coef(getattr(args, f"{g}_{t}"), g, t, si)
            if v is not None:
                if v < 0:
                    raise _UsageError(f"--{g}-{t} must not be negative")
                s[t] = v
        spec[g] = s
    n = int(round(args.duration * rate))
    if n < 2:
        raise _UsageError(f"--duration {args.duration:g} s at {rate:g} Hz gives fewer than 2 samples")
    chans = _simulated_imu(args.duration, rate, args.seed, gyro_unit=units["gyro"], accel_unit=units["accel"],
                           spec=spec)
    t = np.arange(n) / rate
    if suffix == ".csv":
        header = ["timestamp [s]"] + [f"{k} [{units[k.split('_')[0]]}]" for k in chans]
        _write_csv(out, header, [t, *chans.values()])
    elif suffix == ".npz":
        _atomic_npz(out, {"timestamp": t, **chans, "rate": np.float64(rate)})
    else:
        _atomic_npy(out, np.column_stack(list(chans.values())))
    _say(f"wrote {out}: {len(chans)} channels ({', '.join(f'{k} [{units[k.split(chr(95))[0]]}]' for k in chans)})"
         f" × {n:,} samples at {rate:g} Hz, seed {args.seed}", err=True)
    if suffix == ".npy":
        _say(f"  columns col0..col{len(chans) - 1} = {', '.join(chans)}; no timestamps: read it with"
             f" --rate {rate:g}", err=True)
    return EXIT_OK


def _simulate_power_law(args: argparse.Namespace, out: Path, suffix: str) -> int:
    import numpy as np

    from .generate import mixed_noise

    levels: dict[int, float] = {}
    for item in args.h.split(","):
        key, sep, value = item.partition("=")
        try:
            alpha = int(key.strip().lower().lstrip("h"))
            levels[alpha] = float(value)
        except ValueError:
            raise _UsageError(f"--h {args.h!r} must be like 'h0=1e-20,h-1=1e-23' (alpha = 2 … -4)") from None
        if not sep or alpha not in (2, 1, 0, -1, -2, -3, -4):
            raise _UsageError(f"--h: {item!r} must be hALPHA=VALUE with ALPHA in 2 … -4")
    rate = args.rate or 1.0
    n = int(round(args.duration * rate))
    if n < 2:
        raise _UsageError("--duration × --rate gives fewer than 2 samples")
    y = mixed_noise(n, levels, rate=rate, data_type=args.data_type, rng=np.random.default_rng(args.seed))
    name = "phase" if args.data_type == "phase" else "freq"
    t = np.arange(n) / rate
    if suffix == ".csv":
        _write_csv(out, ["timestamp [s]", name], [t, y])
    elif suffix == ".npz":
        _atomic_npz(out, {"timestamp": t, name: y, "rate": np.float64(rate)})
    else:
        _atomic_npy(out, y)
    _say(f"wrote {out}: power-law {name} noise {args.h}, {n:,} samples at {rate:g} Hz, seed {args.seed}",
         err=True)
    return EXIT_OK


def _write_csv(path: Path, header: list[str], columns: list[Any]) -> None:
    import io as _io

    import numpy as np

    buf = _io.StringIO()
    np.savetxt(buf, np.column_stack(columns), delimiter=",", fmt="%.10g", header=",".join(header), comments="")
    _atomic_write(path, buf.getvalue().encode())


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


# ----------------------------------------------------------------------- parser

_EPILOG_ERRORS = """
exit codes: 0 success; 1 data error (missing, unreadable or corrupt file, no numeric data, too few
samples); 2 usage error (bad option value, unknown column or topic, output exists); 3 internal error.
"""


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
              sigmatau simulate imu.csv --preset lsm6dsl --duration 3600
            """) + _EPILOG_ERRORS,
    )
    parser.add_argument("--version", action="version", version=f"sigmatau {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    demo = sub.add_parser(
        "demo", help="simulate a 6-axis LSM6DSL-like IMU and run the full analysis (no input needed)",
        formatter_class=_Formatter,
        description="Simulate a 6-axis LSM6DSL-like IMU (datasheet noise densities as quoted in ST DT0064, plus"
                    " an illustrative bias instability and random walk), seeded, and run the full analysis:"
                    " statistics, noise identification, IMU model, figures, report.html and imu.yaml.",
        epilog="examples:\n  sigmatau demo\n  sigmatau demo --out /tmp/demo --force --duration 1800\n" + _EPILOG_ERRORS)
    demo.add_argument("--duration", type=float, default=7200.0, help="seconds simulated (default 7200, 2 h)")
    demo.add_argument("--rate", type=float, default=104.0, help="sample rate in Hz (default 104, an LSM6DSL ODR)")
    demo.add_argument("--seed", type=int, default=2017, help="random seed (default 2017)")
    _add_analysis_options(demo, "oadev,mdev,tdev,ohdev,totdev,theoh")
    _add_output_options(demo)
    demo.set_defaults(out=None)
    demo.add_argument("--quiet", action="store_true", help="no progress output")
    demo.add_argument("--debug", action="store_true", help="show the traceback of an error")
    demo.set_defaults(func=_cmd_demo)

    analyze = sub.add_parser(
        "analyze", help="the full analysis of a log: statistics, noise types, IMU model, figures, report, imu.yaml",
        formatter_class=_Formatter,
        description="Read a log, check its timing, compute the statistics of every channel with noise types and"
                    " intervals, fit the IMU noise model to gyro and accel channels, and write results.json, CSV"
                    " tables, figures, report.html and imu.yaml (Kalibr) into the output directory.",
        epilog=textwrap.dedent("""
            examples:
              sigmatau analyze imu0/data.csv                      EuRoC: units and timestamps from the header
              sigmatau analyze log.csv --columns gx,gy,gz --gyro-unit deg/s --time-unit ms
              sigmatau analyze run.bag --list-topics
              sigmatau analyze rosbag2_dir --topic /imu --out run --force --figures png,svg,pdf
              sigmatau analyze log.csv --datasheet lsm6dsl --axis-rule rms
            """) + _EPILOG_ERRORS)
    _add_input_options(analyze)
    _add_analysis_options(analyze, "oadev,mdev,tdev,ohdev,totdev,theoh")
    _add_output_options(analyze)
    analyze.set_defaults(func=_cmd_analyze)

    stats = sub.add_parser(
        "stats", help="Stable32-like tables (AF, tau, n, alpha, min sigma, sigma, max sigma) per channel",
        formatter_class=_Formatter,
        description="Compute statistics with noise identification and intervals and print one table per channel"
                    " and statistic, or write them all as CSV.",
        epilog=textwrap.dedent("""
            examples:
              sigmatau stats phase.dat --data-type phase --rate 1 --stat adev,oadev,mdev,tdev
              sigmatau stats imu.csv --stat oadev,theo1 --csv stats.csv
              sigmatau stats month.npy --chunked --rate 1000 --stat oadev,mdev,totdev
              sigmatau stats gyro.bin --chunked --dtype '<f4' --offset 512 --rate 200
            """) + _EPILOG_ERRORS)
    _add_input_options(stats)
    _add_analysis_options(stats, "oadev")
    stats.add_argument("--csv", help="write every table to this CSV file ('-' for stdout) instead of printing")
    stats.add_argument("--force", action="store_true", help="replace an existing CSV file")
    big = stats.add_argument_group("records larger than memory (sigmatau.chunked)")
    big.add_argument("--chunked", action="store_true",
                     help="read one series piecewise instead of loading it: a 1-D .npy, an HDF5 dataset (--dataset)"
                          " or raw binary (--dtype); adev, oadev, mdev, tdev, hdev, ohdev, totdev; needs --rate")
    big.add_argument("--dtype", help="raw binary: sample type, e.g. <f8, <f4, >i4")
    big.add_argument("--offset", type=int, default=0, help="raw binary: header bytes to skip (default 0)")
    big.add_argument("--count", type=int, help="raw binary: number of samples (default: to the end)")
    big.add_argument("--chunk-size", type=int, help="samples per read (default 65536)")
    stats.set_defaults(func=_cmd_stats)

    sim = sub.add_parser(
        "simulate", help="write a simulated log (IMU presets, explicit Q/N/B/K/R, or power-law h_alpha)",
        formatter_class=_Formatter,
        description="Write a seeded simulated log as CSV (with timestamps and units in the header), .npz or .npy."
                    " IMU channels follow the five-term model (quantisation Q, white noise N, bias instability B,"
                    " random walk K, ramp R) from a part's preset with any term overridden; --h writes one"
                    " power-law noise channel instead.",
        epilog=textwrap.dedent("""
            examples:
              sigmatau simulate imu.csv --preset lsm6dsl --duration 7200
              sigmatau simulate gyro.csv --preset none --sensors gyro --rate 200 --gyro-N '0.2 deg/sqrt(h)' \\
                  --gyro-B '3 deg/h' --gyro-K '1e-5'
              sigmatau simulate clock.npy --h 'h0=1e-22,h-1=1e-26' --duration 100000 --rate 1
            """) + _EPILOG_ERRORS)
    sim.add_argument("output", help="file to write: .csv, .npz or .npy")
    sim.add_argument("--preset", default="lsm6dsl", help="part: lsm6dsl (default), lsm6dsm, adis16448, euroc, none")
    sim.add_argument("--sensors", default="gyro,accel", help="gyro, accel or both (default); three axes each")
    sim.add_argument("--duration", type=float, default=3600.0, help="seconds (default 3600)")
    sim.add_argument("--rate", type=float, help="Hz (default: the preset's)")
    sim.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    sim.add_argument("--gyro-unit", help="unit of the gyro samples written (default rad/s)")
    sim.add_argument("--accel-unit", help="unit of the accel samples written (default m/s^2)")
    for g in ("gyro", "accel"):
        for t, what in (("Q", "quantisation"), ("N", "white noise density"), ("B", "bias instability"),
                        ("K", "random walk"), ("R", "ramp")):
            sim.add_argument(f"--{g}-{t}", dest=f"{g}_{t}", metavar="'VALUE [UNIT]'",
                             help=f"{g} {what} (SI when no unit)")
    sim.add_argument("--h", help="power-law noise instead: levels like 'h0=1e-20,h-1=1e-23' (alpha 2 … -4)")
    sim.add_argument("--data-type", choices=["freq", "phase"], default="freq", help="with --h: what to write")
    sim.add_argument("--force", action="store_true", help="replace an existing file")
    sim.add_argument("--quiet", action="store_true", help="no progress output")
    sim.add_argument("--debug", action="store_true", help="show the traceback of an error")
    sim.set_defaults(func=_cmd_simulate)
    from .batch import add_cli as _add_batch_cli  # `sigmatau batch`: parser and command live in sigmatau.batch

    _add_batch_cli(sub)
    return parser


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Entry point of the ``sigmatau`` command; returns the exit code."""
    from .errors import DataError, ParameterError, SigmaTauError
    from .io import InputNotFoundError, MissingDependencyError
    from .outputs import OutputExistsError

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


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
