"""``sigmatau analyze``: the full analysis of a log (:func:`sigmatau.analysis.analyze_log`), written out."""

from __future__ import annotations

import argparse
import textwrap
from pathlib import Path
from typing import Any

from .common import (
    EXIT_OK, _Console, _EPILOG_ERRORS, _Formatter, _StepDisplay, _UsageError, _add_analysis_options,
    _add_input_options, _add_output_options, _analysis_options, _check_out, _read, _read_options, _run_analysis,
    _say, _say_row, _write_analysis,
)

__all__ = ["add_cli"]


def _list_topics(args: argparse.Namespace) -> int:
    from .. import io

    topics = io.list_topics(args.log)
    for t in topics:
        _say_row([t.topic, t.msgtype, f"{t.count} messages"])
    return EXIT_OK


def _cmd_analyze(args: argparse.Namespace, console: _Console) -> int:
    if args.list_topics:
        return _list_topics(args)
    default = Path(Path(args.log).name.split(".")[0] + "-sigmatau")
    out = _check_out(args, default, protect=[args.log])
    plan = _memory_plan(args)
    if plan.mode == "in":
        log = _read(args, console)
        return _run_analysis(log, args, console, out)
    return _run_out_of_core(args, console, out, plan)


def _memory_plan(args: argparse.Namespace) -> Any:
    """In memory or out of core (:func:`sigmatau.chunked.memory_plan`), decided before reading."""
    from ..errors import ParameterError
    from ..scale.outofcore import memory_plan, parse_size

    if args.chunk_size is not None and args.chunk_size < 16:
        raise _UsageError(f"--chunk-size {args.chunk_size!r} must be at least 16 samples")
    try:
        limit = None if args.memory_limit is None else parse_size(args.memory_limit)
    except ParameterError:
        raise _UsageError(f"--memory-limit {args.memory_limit!r} must be a size such as 1GiB, 512MiB, 2G or 2e9"
                          " (bytes)") from None
    return memory_plan(args.log, memory=args.memory, memory_limit=limit, **_read_options(args))


def _run_out_of_core(args: argparse.Namespace, console: _Console, out: Path, plan: Any) -> int:
    """The analysis of a log read in chunks (:func:`sigmatau.chunked.analyze_disk_log`); the temporary
    files of a text log go next to the output directory and are removed however the run ends."""
    from .. import io
    from ..scale.chunked import DEFAULT_CHUNK
    from ..scale.outofcore import analyze_disk_log

    chunk = args.chunk_size or DEFAULT_CHUNK
    if not console.quiet:
        _say(f"sigmatau: {plan.describe(chunk)}", err=True)
    display = _StepDisplay(console)
    options = _analysis_options(args, display)
    workdir = out.resolve().parent
    with io.open_log(args.log, workdir=workdir if workdir.is_dir() else None,
                     progress=False if console.quiet else None, **_read_options(args)) as log:
        try:
            analysis = analyze_disk_log(log, chunk_size=chunk, plan=plan, **options)
        finally:
            display.close()
    return _write_analysis(analysis, args, out, [log.source.path])


def add_cli(sub: Any) -> None:
    """Register ``sigmatau analyze`` on the command's subparsers."""
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
              sigmatau analyze log.csv --export kalibr,vins,openvins  the estimators' parameter files
              sigmatau analyze day.npz --memory-limit 1GiB        out of core when it would need more
            """) + _EPILOG_ERRORS)
    _add_input_options(analyze)
    _add_analysis_options(analyze, "oadev,mdev,tdev,ohdev,totdev,theoh")
    _add_output_options(analyze)
    big = analyze.add_argument_group(
        "records larger than memory (docs/guide/chunked.md)",
        textwrap.fill(  # the formatter keeps descriptions as written: wrapped here
        "Before reading, the peak of the in-memory analysis (samples x columns x 8 bytes x 1.75 with the"
        " compiled kernels, 2.6 without) is compared with the memory available; a log that would not fit is"
        " analysed out of core, read in chunks: .npy, .npz (stored, not compressed), HDF5, and text (converted"
        " once into temporary float64 files next to the output directory, removed afterwards). Out of core:"
        " oadev, mdev, tdev, ohdev, totdev (adev, hdev) and the IMU model as in memory; TheoH, the warm-up search,"
        " the other preparation steps, --dynamic and the signal figures are skipped, each with a note.", width=96))
    big.add_argument("--memory", choices=["auto", "in", "chunked"], default="auto",
                     help="auto (default): out of core when the in-memory analysis would not fit; in: always read"
                          " the log whole; chunked: always read it in chunks")
    big.add_argument("--memory-limit", metavar="SIZE",
                     help="the memory the analysis may use, instead of the memory available (e.g. 1GiB, 512MiB,"
                          " 2G); decides --memory auto")
    big.add_argument("--chunk-size", type=int, metavar="N", help="samples per read out of core (default 65536)")
    analyze.set_defaults(func=_cmd_analyze)
