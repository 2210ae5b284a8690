"""``sigmatau psd``: the power spectral density of each channel, log-binned with intervals and a power-law fit."""

from __future__ import annotations

import argparse
import textwrap
from pathlib import Path
from typing import Any

from ..report.outputs import printable
from .common import (
    EXIT_OK, _Console, _EPILOG_ERRORS, _Formatter, _UsageError, _add_folder_outputs, _add_input_options,
    _check_folder_outputs, _emit_csv, _read, _say,
)

__all__ = ["add_cli"]


def _check_args(args: argparse.Namespace) -> list[str]:
    if args.segments < 1:
        raise _UsageError(f"--segments {args.segments!r} must be at least 1")
    if not args.bins_per_decade > 0:
        raise _UsageError(f"--bins-per-decade {args.bins_per_decade!r} must be positive")
    if args.carrier is not None and not args.carrier > 0:
        raise _UsageError(f"--carrier {args.carrier!r} must be a positive frequency in Hz")
    return _check_folder_outputs(args, [Path(args.log).resolve()])


def _cmd_psd(args: argparse.Namespace, console: _Console) -> int:
    from .._version import __version__
    from ..report.spectrum import psd_csv, psd_summary, write_spectra
    from ..spectral import psd

    fmts = _check_args(args)
    log = _read(args, console)
    spectra, units = {}, {}
    for name in log.names:
        spectra[name] = psd(log[name], rate=log.rate, data_type=log.data_type, segments=args.segments,
                            bins_per_decade=args.bins_per_decade, confidence=args.confidence, carrier=args.carrier)
        units[name] = log.units.get(name, "")
    if args.csv:
        _emit_csv(args, psd_csv(spectra, units))
    else:
        _say(f"{printable(log.source.path)}: {len(log):,} samples at {log.rate:.6g} Hz, {log.data_type} data;"
             f" Welch, {args.segments} segments, {args.bins_per_decade:g} bins per decade")
        for name, r in spectra.items():
            _say("")
            _say(psd_summary(name, r, units[name]), multiline=True)
    if args.out:
        source = {"name": log.source.path, "sha256": log.source.sha256, "samples": len(log), "rate": log.rate,
                  "data_type": log.data_type}
        settings = {"segments": args.segments, "bins_per_decade": args.bins_per_decade,
                    "confidence": args.confidence, "carrier": args.carrier}
        written = write_spectra(spectra, args.out, units=units, source=source, settings=settings,
                                version=__version__, figures=fmts, report=not args.no_report, force=args.force,
                                protect=[Path(args.log).resolve()])
        _say(f"wrote {len(written)} files to {printable(args.out)}", err=True)
    return EXIT_OK


def add_cli(sub: Any) -> None:
    """Register ``sigmatau psd`` on the command's subparsers."""
    p = sub.add_parser(
        "psd", help="power spectral density per channel: log-binned with intervals, power-law fit h_alpha",
        formatter_class=_Formatter,
        description="Welch's power spectral density of each channel (one-sided S_y), averaged in log-frequency"
                    " bins with a chi-squared interval on each bin, and a fit of the power laws h_α f^α"
                    " (α = 2 … −2) with intervals and the dominant noise type in each decade.",
        epilog=textwrap.dedent("""
            examples:
              sigmatau psd imu.csv --out imu-psd
              sigmatau psd clock.dat --rate 1 --data-type phase --carrier 10e6 --csv psd.csv
            """) + _EPILOG_ERRORS)
    _add_input_options(p)
    g = p.add_argument_group("spectrum")
    g.add_argument("--segments", type=int, default=8, help="Welch segments (50 %% overlap; default 8)")
    g.add_argument("--bins-per-decade", type=float, default=10.0, help="log-frequency bins per decade (default 10)")
    g.add_argument("--confidence", type=float, default=0.6827, help="coverage of the intervals (default ±1σ)")
    g.add_argument("--carrier", type=float, metavar="HZ", help="carrier frequency ν0, for S_φ and L(f) in the outputs")
    _add_folder_outputs(p, "psd.csv, psd.json", "every bin")
    p.set_defaults(func=_cmd_psd)
