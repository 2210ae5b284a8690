"""``sigmatau batch``: its parser and command (the work is :func:`sigmatau.batch.analyze_many`)."""

from __future__ import annotations

import math
import sys
from typing import Any

from ..scale.batch import (
    CONNECT_TIMEOUT, LIMIT_MARGIN, LOGS_DIR, OUTLIER_Z, analyze_many, check_scheduler_address, expand_patterns,
    local_worker_count, usable_cores,
)
from .common import EXIT_DATA, EXIT_OK, _datasheet, _exports, _Formatter, _read_options, _UsageError

__all__ = ["add_cli"]


def add_cli(subparsers: Any) -> None:
    """Register ``sigmatau batch`` on the ``sigmatau`` command's subparsers."""
    import textwrap

    p = subparsers.add_parser(
        "batch", help="analyse many logs on a Dask cluster (local or existing) and summarise the fleet",
        formatter_class=_Formatter,
        description="Run the analysis of 'sigmatau analyze' on every log named by the patterns, one Dask task per"
                    " log, on a LocalCluster of single-threaded worker processes (default) or on an existing cluster"
                    " (--scheduler). Each log's outputs go to OUT/logs/<name>-<sha256>/ as it finishes; a rerun skips"
                    " the logs already done. Then a fleet summary: fleet.csv (per log, channel and term), fleet.json,"
                    " fleet_logs.csv, histograms and fleet.html with outliers, pass/fail against --limits and the"
                    " logs that failed with their reason. Needs the extra dask: pip install \"sigmatau[dask]\".",
        epilog=textwrap.dedent("""
            examples:
              sigmatau batch 'line3/*.csv' --out line3-fleet --limits lsm6dsl
              sigmatau batch 'bags/**/rosbag2_*' --topic /imu/data --out fleet --workers 8 --no-figures
              sigmatau batch 'logs/*.csv' --out fleet --scheduler tcp://10.0.0.5:8786
            exit codes: 0 every log analysed; 1 some log failed (the summary is still written) or a data error;
            2 usage error (bad option, pattern matching nothing, OUT made with other settings);
            130 interrupted (rerun the same command to resume).
            """))
    p.add_argument("patterns", nargs="+", metavar="PATTERN",
                   help="logs: files, ROS 2 bag directories or glob patterns (expanded by sigmatau; quote them)")
    p.add_argument("--out", required=True, help="output directory (created; reused by a rerun, which resumes)")
    c = p.add_argument_group("cluster").add_mutually_exclusive_group()
    c.add_argument("--scheduler", metavar="ADDRESS",
                   help=f"address of an existing Dask scheduler, tcp://host:8786 (reached within"
                        f" {CONNECT_TIMEOUT:g} s or the run stops)")
    c.add_argument("--workers", type=int, help="local cluster of N single-threaded worker processes"
                                               " (default: the cores; at most the cores and the logs)")
    g = p.add_argument_group("input (the same for every log)")
    g.add_argument("--format", help="reader: csv, stable32, npy, npz, rosbag1, rosbag2, hdf5, parquet")
    g.add_argument("--columns", help="channels by column name or 0-based index, comma-separated")
    g.add_argument("--time-column", help="the timestamp column (default: found by name); 'none' for none")
    g.add_argument("--time-unit", choices=["s", "ms", "us", "ns", "min", "h", "d"], help="unit of the timestamps")
    g.add_argument("--rate", type=float, help="sample rate in Hz (needed without timestamps)")
    g.add_argument("--data-type", choices=["freq", "phase"], help="freq (default) or phase data")
    g.add_argument("--topic", help="ROS bags: the sensor_msgs/Imu topic")
    g.add_argument("--dataset", help="HDF5: the dataset or group")
    g.add_argument("--stamps", choices=["header", "bag"], help="ROS bags: header.stamp (default) or receive time")
    g.add_argument("--delimiter", help="text files: the field delimiter")
    g.add_argument("--gaps", choices=["auto", "mark", "refuse", "split", "ignore"], default="auto",
                   help="missing samples: auto (default: mark up to 10%%, else refuse), mark (gaps every"
                        " statistic skips), refuse, split (longest segment) or ignore")
    g.add_argument("--gap-threshold", type=float, default=1.5, help="gap: a step above this many median steps")
    g.add_argument("--unsorted", choices=["sort", "refuse"], default="sort", help="timestamps going backwards")
    g.add_argument("--duplicates", choices=["drop", "refuse"], default="drop", help="repeated timestamps")
    g.add_argument("--gyro-unit", help="rad/s, mrad/s, deg/s, mdps, deg/h")
    g.add_argument("--accel-unit", help="m/s^2, mm/s^2, g, mg, ug")
    g.add_argument("--unit", action="append", default=[], metavar="CHANNEL=UNIT", help="unit of one channel")
    a = p.add_argument_group("analysis (as sigmatau analyze)")
    a.add_argument("--warmup", default="auto", metavar="auto|keep|SECONDS",
                   help="the settling after power-on: auto (default: detected and left out), keep, or seconds")
    a.add_argument("--temperature", choices=["auto", "off"], default="auto",
                   help="auto (default): compensate gyro and accel against a temperature column; off")
    a.add_argument("--stat", default="oadev,mdev,tdev,ohdev,totdev,theoh",
                   help="statistics, comma-separated (default oadev,mdev,tdev,ohdev,totdev,theoh)")
    a.add_argument("--taus", default="octave", help="τ grid: octave (default), decade, all, log")
    a.add_argument("--confidence", type=float, default=0.6827, help="coverage of the intervals (default ±1σ)")
    a.add_argument("--no-model", action="store_true", help="statistics only, no IMU noise model")
    a.add_argument("--axis-rule", choices=["max", "rms", "mean"], default="max", help="Kalibr axis rule")
    a.add_argument("--inflate", type=float, default=1.0, help="inflation factor of the Kalibr values")
    a.add_argument("--rostopic", default="/imu0", help="rostopic written to imu.yaml")
    a.add_argument("--export", default="kalibr", metavar="LIST",
                   help="estimator parameter files per log: kalibr, vins, openvins, matlab, gtsam, comma-separated,"
                        " or none (default kalibr)")
    a.add_argument("--datasheet", action="append", default=[], metavar="PART|GROUP.TERM=VALUE UNIT",
                   help="datasheet figures compared in each log's report (repeatable)")
    o = p.add_argument_group("outputs and fleet summary")
    o.add_argument("--figures", default="png", help="per-log figure formats: png, svg, pdf (default png)")
    o.add_argument("--no-figures", action="store_true", help="no per-log figures (faster); fleet figures still made")
    o.add_argument("--no-report", action="store_true", help="no per-log report.html")
    o.add_argument("--limits", metavar="PART|FILE",
                   help="pass/fail limits: a datasheet part (lsm6dsl, lsm6dsm, adis16448, euroc; typical × margin)"
                        " or a JSON/YAML/CSV file (group, term, max, unit)")
    o.add_argument("--limit-margin", type=float, default=LIMIT_MARGIN,
                   help=f"factor on a part's typical datasheet values (default {LIMIT_MARGIN:g})")
    o.add_argument("--outlier-z", type=float, default=OUTLIER_Z,
                   help=f"robust z beyond which a term is a fleet outlier (default {OUTLIER_Z:g})")
    o.add_argument("--force-rerun", action="store_true", help="recompute every log, also those already done")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.add_argument("--debug", action="store_true", help="show the traceback of an error")
    p.set_defaults(func=_cmd_batch)


def _cmd_batch(args: Any, console: Any) -> int:
    if args.workers is not None and args.workers < 1:
        raise _UsageError(f"--workers {args.workers!r} must be at least 1")
    if not 0 < args.confidence < 1:
        raise _UsageError(f"--confidence {args.confidence!r} must be between 0 and 1")
    if not (math.isfinite(args.limit_margin) and args.limit_margin > 0):
        raise _UsageError(f"--limit-margin {args.limit_margin!r} must be a positive finite number")
    if args.scheduler is not None:
        check_scheduler_address(args.scheduler, name="--scheduler")
    _exports(args)  # checked before any log is read
    figures = [] if args.no_figures else [f.strip().lower() for f in args.figures.split(",") if f.strip()]
    if console.quiet:
        progress: Any = "none"
    else:
        progress = "bar" if sys.stderr.isatty() else "lines"
    if args.scheduler:
        where = f"the Dask scheduler at {args.scheduler}"
    else:  # as analyze_many caps it (it warns when a --workers request is capped)
        n_logs = len(expand_patterns(args.patterns, exclude=args.out))
        where = f"a local Dask cluster of up to {local_worker_count(args.workers, n_logs, usable_cores())[0]} worker process(es)"
    if not console.quiet:
        print(f"sigmatau batch: {args.out} on {where}", file=sys.stderr, flush=True)
    fleet = analyze_many(
        args.patterns, args.out, scheduler=args.scheduler, workers=args.workers, read=_read_options(args),
        statistics=args.stat, taus=args.taus, confidence=args.confidence, model=not args.no_model,
        axis_rule=args.axis_rule, inflate=args.inflate, rostopic=args.rostopic, datasheet=_datasheet(args.datasheet),
        figures=figures, report=not args.no_report, exports=_exports(args), limits=args.limits,
        limit_margin=args.limit_margin, outlier_z=args.outlier_z, force=args.force_rerun, progress=progress,
        warmup=_warmup_option(args.warmup), temperature=args.temperature)
    print(fleet.summary())
    print(f"wrote {args.out}/fleet.html, fleet.csv, fleet_logs.csv, fleet.json; per log: {args.out}/{LOGS_DIR}/")
    return EXIT_OK if fleet.ok else EXIT_DATA


def _warmup_option(text: str) -> Any:
    """``--warmup`` as :class:`sigmatau.analysis.Preparation` takes it: auto, keep or seconds."""
    if text in ("auto", "keep"):
        return text
    try:
        return float(text)
    except ValueError:
        raise _UsageError(f"--warmup {text!r} must be auto, keep or a number of seconds") from None
