"""``sigmatau analyze``: the full analysis of a log (:func:`sigmatau.analysis.analyze_log`), written out."""

from __future__ import annotations

import argparse
import textwrap
from pathlib import Path
from typing import Any

from .common import (
    EXIT_OK, _Console, _EPILOG_ERRORS, _Formatter, _add_analysis_options, _add_input_options,
    _add_output_options, _check_out, _read, _run_analysis, _say_row,
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
    log = _read(args, console)
    return _run_analysis(log, args, console, out)


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
            """) + _EPILOG_ERRORS)
    _add_input_options(analyze)
    _add_analysis_options(analyze, "oadev,mdev,tdev,ohdev,totdev,theoh")
    _add_output_options(analyze)
    analyze.set_defaults(func=_cmd_analyze)
