"""Helpers shared by the test modules (import as ``from helpers import ...``).

- :func:`half_unit` and :func:`assert_printed`: compare with a published number to the digits
  printed in the source, the tolerance every reference-table test uses.
- :func:`assert_one_line_error`: what the CLI promises for bad input — a non-zero exit, one line
  on stderr that names what is wrong, no traceback.
"""

from __future__ import annotations

import re
import subprocess
from decimal import Decimal

import numpy as np


def half_unit(printed: str) -> float:
    """Half a unit in the last digit of a printed number (trailing zeros count).

    >>> half_unit("2.922319e-01")
    5e-08
    >>> half_unit("0.0100")
    5e-05
    """
    return 0.5 * 10.0 ** Decimal(printed.strip()).as_tuple().exponent


def assert_printed(value: float, printed: str) -> None:
    """``value`` rounds to ``printed`` at the digits shown there (half a unit in the last one)."""
    ref = float(printed)
    np.testing.assert_allclose(value, ref, rtol=half_unit(printed) / abs(ref), atol=0.0)


def assert_one_line_error(result: subprocess.CompletedProcess | tuple[int, str], *,
                          code: int | None = None, match: str | None = None) -> str:
    """A failed CLI run: non-zero exit (``code`` if given), one stderr line, no traceback.

    ``result`` is a finished subprocess or ``(exit_code, stderr)`` from calling ``main`` in
    process. ``match`` is a regular expression the line must contain. Returns the line.
    """
    rc, err = (result.returncode, result.stderr) if hasattr(result, "returncode") else result
    assert rc != 0, "expected a failure"
    if code is not None:
        assert rc == code, f"exit {rc}, expected {code}: {err!r}"
    assert "Traceback" not in err, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, f"expected one line on stderr, got {len(lines)}: {err!r}"
    if match is not None:
        assert re.search(match, lines[0]), f"{match!r} not in {lines[0]!r}"
    return lines[0]


def run_cli(argv, capsys) -> tuple[int, str, str]:
    """``sigmatau.cli.main`` on ``argv`` (items made strings) in process: (exit code, stdout, stderr)."""
    from sigmatau.cli import main

    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def cli_error_line(err: str, *patterns: str) -> str:
    """The one error line of a CLI run's stderr (warning lines aside), containing every pattern."""
    lines = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith("sigmatau: warning:")]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    for p in patterns:
        assert p in lines[0], (p, lines[0])
    return lines[0]
