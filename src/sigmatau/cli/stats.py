"""``sigmatau stats``: Stable32-like tables per channel and statistic, in memory or chunked."""

from __future__ import annotations

import argparse
import sys
import textwrap
from pathlib import Path
from typing import Any, Sequence

from ..report.outputs import printable
from .analyze import _list_topics
from .common import (
    EXIT_OK, _Console, _EPILOG_ERRORS, _Formatter, _UsageError, _add_analysis_options, _add_input_options,
    _atomic_write, _check_replaceable, _dynamic_spec, _preparation, _read, _say,
)

__all__ = ["add_cli"]


def _cmd_stats(args: argparse.Namespace, console: _Console) -> int:
    from ..pipeline.analysis import analyze_log

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
                    workers=args.workers, progress=console.progress, theoh=args.theoh, theo1_bias=args.theo1_bias,
                    prep=_preparation(args),
                    dynamic=_dynamic_spec(args))
    corrected = ", Theo1 corrected for its bias (published)" if args.theo1_bias == "published" else ""
    missing = max((r.n_missing for ch in a.channels for r in ch.results.values()), default=0)
    gaps = f" ({missing:,} missing, NaN: gaps)" if missing else ""
    _emit_stats(args, a.channels, f"{log.source.path}: {len(log):,} samples{gaps} at {log.rate:.6g} Hz,"
                                  f" {log.data_type} data, {a.settings['confidence']:.2%} intervals{corrected}")
    for w in a.warnings:
        _say(f"sigmatau: warning: {w}", err=True)
    return EXIT_OK


def _stats_chunked(args: argparse.Namespace) -> int:
    """``stats --chunked``: one series read piecewise (:mod:`sigmatau.chunked`), never loaded whole."""
    from ..scale import chunked
    from ..pipeline.analysis import ChannelAnalysis, check_statistics

    if args.rate is None:
        raise _UsageError("--chunked needs --rate (the file has no timestamps)")
    stats = check_statistics(args.stat)
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
    missing = first.n_missing
    gaps = f" ({missing:,} missing, NaN: gaps)" if missing else ""
    _emit_stats(args, [ch], f"{args.log}: {n:,} samples{gaps} at {args.rate:.6g} Hz, {dtype} data, read in chunks,"
                            f" {args.confidence:.2%} intervals")
    return EXIT_OK


def _emit_stats(args: argparse.Namespace, channels: Sequence[Any], header: str) -> None:
    """The statistics of ``channels`` as Stable32-style tables on stdout, or as CSV (``--csv``)."""
    from ..report.outputs import statistics_csv

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


def add_cli(sub: Any) -> None:
    """Register ``sigmatau stats`` on the command's subparsers."""
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
    # Stable32-like tables: the definition, of the record as given unless a preparation is asked for
    _add_analysis_options(stats, "oadev", theoh="exact", as_recorded=True)
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
