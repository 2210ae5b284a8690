"""The ``sigmatau`` command.

Thin layer over the public API: it parses arguments, calls the library and
prints. Errors become one line on stderr and a non-zero exit code.
"""

from __future__ import annotations

import argparse
import sys
from typing import Optional, Sequence

from . import __version__

__all__ = ["main"]

_DEMO_STATS = ("adev", "oadev", "mdev", "tdev", "hdev", "ohdev")


def _demo(args: argparse.Namespace) -> int:
    import numpy as np

    import sigmatau
    from sigmatau.datasets import nbs1000

    y = nbs1000()
    results = [getattr(sigmatau, name)(y, rate=1.0, taus="octave") for name in _DEMO_STATS]
    print("NBS 1000-point frequency test set (NIST SP 1065), rate 1 Hz, octave τ")
    header = f"{'tau [s]':>8}" + "".join(f"{name:>13}" for name in _DEMO_STATS)
    print(header)
    taus = np.unique(np.concatenate([r.taus for r in results]))
    for tau in taus:
        cells = []
        for r in results:
            hit = np.flatnonzero(r.taus == tau)
            cells.append(f"{r.dev[hit[0]]:13.6e}" if hit.size else f"{'':13}")
        print(f"{tau:8g}" + "".join(cells))
    return 0


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="sigmatau",
        description="Noise analysis of sensors with the Allan family of variances.",
    )
    parser.add_argument("--version", action="version", version=f"sigmatau {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="run the built-in example and print a table")
    demo.set_defaults(func=_demo)
    return parser


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Entry point of the ``sigmatau`` command; returns the exit code."""
    parser = _parser()
    args = parser.parse_args(argv)
    from .errors import SigmaTauError

    try:
        return int(args.func(args))
    except SigmaTauError as exc:
        print(f"sigmatau: error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
