"""``sigmatau demo``: a simulated 6-axis IMU through the full analysis, no input needed."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from .common import (
    _Console, _EPILOG_ERRORS, _Formatter, _UsageError, _add_analysis_options, _add_output_options,
    _check_out, _run_analysis, _say,
)
from .simulate import _simulated_imu

__all__ = ["add_cli"]


def _cmd_demo(args: argparse.Namespace, console: _Console) -> int:
    from ..pipeline.analysis import log_from_arrays

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


def add_cli(sub: Any) -> None:
    """Register ``sigmatau demo`` on the command's subparsers."""
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
