"""``sigmatau compare``: each device's own noise from simultaneous records (cornered hat)."""

from __future__ import annotations

import argparse
import textwrap
from pathlib import Path
from typing import Any, Sequence

from ..report.outputs import printable
from .common import (
    EXIT_OK, _Console, _EPILOG_ERRORS, _Formatter, _UsageError, _add_folder_outputs, _add_input_options,
    _check_folder_outputs, _emit_csv, _read_options, _say,
)

__all__ = ["add_cli"]

#: Statistics the cornered hat takes (those with a pair covariance and a Greenhall EDF).
HAT_STATISTICS = ("oadev", "adev", "mdev", "hdev", "ohdev")


def _read_all(args: argparse.Namespace, console: _Console) -> list[Any]:
    from .. import io

    kw = _read_options(args)
    return [io.read(path, progress=False if console.quiet else None, **kw) for path in args.logs]


def _series(logs: Sequence[Any]) -> tuple[list[str], list[Any], Any]:
    """The names and series of every input: the channels of one log, or one channel of each of several."""
    if len(logs) == 1:
        log = logs[0]
        return list(log.names), [log[n] for n in log.names], log
    names, series = [], []
    for log in logs:
        if len(log.names) != 1:
            shown = ", ".join(printable(n) for n in log.names)
            raise _UsageError(f"{printable(log.source.path)} has {len(log.names)} channels ({shown}); choose one"
                              " with --columns (the same column is read from every log)")
        stem = Path(log.source.path).stem or log.source.path
        names.append(stem if stem not in names else f"{stem}#{len(names) + 1}")
        series.append(log[log.names[0]])
    return names, series, logs[0]


def _check_alike(logs: Sequence[Any], series: Sequence[Any]) -> None:
    """Simultaneous records: one rate, one length, one data type and one unit."""
    first = logs[0]
    for log in logs[1:]:
        if abs(log.rate - first.rate) > 1e-9 * first.rate:
            raise _UsageError(f"{printable(log.source.path)} is sampled at {log.rate:.9g} Hz and"
                              f" {printable(first.source.path)} at {first.rate:.9g} Hz; simultaneous records"
                              " must share one rate")
        if log.data_type != first.data_type:
            raise _UsageError(f"{printable(log.source.path)} holds {log.data_type} data and"
                              f" {printable(first.source.path)} {first.data_type} data; give --data-type")
    lengths = {len(s) for s in series}
    if len(lengths) != 1:
        raise _UsageError(f"the records have different lengths ({', '.join(f'{n:,}' for n in sorted(lengths))}"
                          " samples); simultaneous records must cover the same samples (use --part on each first)")
    units = {log.units.get(n, "") for log in logs for n in log.names}
    if len(units) > 1:
        raise _UsageError(f"the records are in different units ({', '.join(sorted(printable(u) for u in units))});"
                          " set one unit for all with --unit or --gyro-unit/--accel-unit")


def _pair_names(spec: str, count: int) -> list[tuple[str, str]]:
    pairs = []
    for item in spec.split(","):
        a, sep, b = item.strip().partition("-")
        if not sep or not a.strip() or not b.strip() or a.strip() == b.strip():
            raise _UsageError(f"--pairs: {item!r} must be DEVICE-DEVICE, e.g. A-B,B-C,C-A")
        pairs.append((a.strip(), b.strip()))
    if len(pairs) != count:
        raise _UsageError(f"--pairs names {len(pairs)} pairs but {count} difference series were given")
    if len(set(pairs)) != len(pairs):
        raise _UsageError("--pairs names a pair twice")
    return pairs


def _cmd_compare(args: argparse.Namespace, console: _Console) -> int:
    import numpy as np

    from .._version import __version__
    from ..compare import cornered_hat
    from ..report.comparison import hat_csv, hat_table, write_comparison
    from ..stats import FUNCTIONS

    stat = args.stat.strip().lower()
    if stat not in HAT_STATISTICS:
        raise _UsageError(f"--stat {args.stat!r}: the cornered hat takes one of {', '.join(HAT_STATISTICS)}")
    inputs = [Path(p).resolve() for p in args.logs]
    fmts = _check_folder_outputs(args, inputs)
    logs = _read_all(args, console)
    names, series, first = _series(logs)
    _check_alike(logs, series)
    if args.names:
        given = [n.strip() for n in args.names.split(",")]
        if len(given) != len(series) or len(set(given)) != len(given) or not all(given):
            raise _UsageError(f"--names gives {len(given)} names for {len(series)} series; give one distinct name"
                              " for each")
        names = given
    if args.pairs:
        pairs = _pair_names(args.pairs, len(series))
        data: dict[Any, Any] = {p: s for p, s in zip(pairs, series)}
        shown = {f"{a}−{b}": s for (a, b), s in zip(pairs, series)}
    else:
        if len(series) < 3:
            raise _UsageError(f"a cornered hat needs at least 3 devices; got {len(series)}"
                              " (give more logs, more --columns, or difference series with --pairs)")
        data = dict(zip(names, series))
        shown = {f"{names[i]}−{names[j]}": np.asarray(series[i], float) - np.asarray(series[j], float)
                 for i in range(len(series)) for j in range(i + 1, len(series))}
    result = cornered_hat(data, rate=first.rate, data_type=first.data_type, statistic=stat, taus=args.taus,
                          confidence=args.confidence)
    unit = first.units.get(first.names[0], "")
    if args.csv:
        _emit_csv(args, hat_csv(result, unit))
    else:
        _say(f"{len(result.names)} devices, {len(series[0]):,} samples at {first.rate:.6g} Hz, {first.data_type}"
             f" data, {stat.upper()}, {args.confidence:.2%} intervals")
        _say("")
        _say(hat_table(result, unit), multiline=True)
    if args.out:
        fn = FUNCTIONS[stat]
        pair_curves = {}
        for label, s in shown.items():
            r = fn(s, rate=first.rate, data_type=first.data_type, taus=args.taus, ci=None)
            pair_curves[label] = (r.taus, r.dev)
        sources = [{"name": log.source.path, "sha256": log.source.sha256, "samples": len(log), "rate": log.rate,
                    "data_type": log.data_type} for log in logs]
        settings = {"statistic": stat, "taus": args.taus, "confidence": args.confidence,
                    "devices": list(result.names), "pairs": args.pairs or None}
        written = write_comparison(result, args.out, unit=unit, inputs=sources, settings=settings,
                                   pairs=pair_curves, version=__version__, figures=fmts, report=not args.no_report,
                                   force=args.force, protect=inputs)
        _say(f"wrote {len(written)} files to {printable(args.out)}", err=True)
    return EXIT_OK


def add_cli(sub: Any) -> None:
    """Register ``sigmatau compare`` on the command's subparsers."""
    p = sub.add_parser(
        "compare", help="each device's own noise from simultaneous records (three- or N-cornered hat)",
        formatter_class=_Formatter,
        description="Separate the noise of each of three or more devices recorded at the same time (clocks against"
                    " one reference, gyros on one table): the pairwise differences cancel the common part, and the"
                    " cornered hat splits what remains. Prints, for each device, the classical signed estimate and"
                    " a non-negative estimate with its interval (never below zero) at every τ.",
        epilog=textwrap.dedent("""
            examples:
              sigmatau compare a.csv b.csv c.csv --columns gyro_z --out hat
              sigmatau compare rig.csv --columns gyro_z_1,gyro_z_2,gyro_z_3,gyro_z_4
              sigmatau compare ab.dat bc.dat ca.dat --pairs A-B,B-C,C-A --rate 1 --data-type phase
            """) + _EPILOG_ERRORS)
    _add_input_options(p, many=True)
    g = p.add_argument_group("comparison")
    g.add_argument("--names", help="device names, comma-separated (default: the file stems, or the channels)")
    g.add_argument("--pairs", help="the inputs are difference series of these pairs, in order: A-B,B-C,C-A")
    g.add_argument("--stat", default="oadev", help=f"variance used: {', '.join(HAT_STATISTICS)} (default oadev)")
    g.add_argument("--taus", default="octave", help="τ grid: octave (default), decade, all, log")
    g.add_argument("--confidence", type=float, default=0.6827, help="coverage of the intervals (default ±1σ)")
    _add_folder_outputs(p, "compare.csv, compare.json", "every device's rows")
    p.set_defaults(func=_cmd_compare)
