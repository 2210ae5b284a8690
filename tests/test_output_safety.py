"""Hostile names and interrupted runs: every output is read back the way its consumer reads it.

- CSV through the ``csv`` module (a spreadsheet would evaluate a cell starting with ``=+-@``);
- ``imu.yaml`` through PyYAML's ``safe_load`` and its unsafe ``Loader`` (what old Kalibr scripts use);
- terminal output scanned for control characters;
- ``--force`` and interrupted runs checked for what survives in the output directory.
"""

from __future__ import annotations

import csv
import io
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from sigmatau.cli import main

FORMULA_START = ("=", "+", "-", "@", "\t", "\r")


def _run(argv, capsys):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _one_line_error(err: str, *patterns: str) -> str:
    lines = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith("sigmatau: warning:")]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    for p in patterns:
        assert p in lines[0], (p, lines[0])
    return lines[0]


def _log(path: Path, names: list[str], rng: np.random.Generator, n: int = 2000) -> Path:
    """A CSV log at 100 Hz with a time column and one white-noise column per name."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["t", *names])
    for i, row in enumerate(rng.standard_normal((n, len(names)))):
        w.writerow([f"{i / 100:.2f}", *(repr(float(v)) for v in row)])
    path.write_text(buf.getvalue(), encoding="utf-8")
    return path


# --------------------------------------------------------------------------- CSV


@pytest.mark.parametrize("value, expected", [
    ("=1+2", "'=1+2"), ("+SUM(A1)", "'+SUM(A1)"), ("-2+3", "'-2+3"), ("@cmd", "'@cmd"),
    ("\tx", "'\tx"), ("\rx", "'\rx"), ("gyro_x", "gyro_x"), ("a=b", "a=b"), ("", ""),
    (-1.5, "-1.5"), (-3, "-3"), (np.float64(-2.5e-7), "-2.5e-07"), (np.int64(-4), "-4"),
    (float("nan"), ""), (None, ""), (True, "True"),
])
def test_csv_cell_owasp_rule(value, expected):
    from sigmatau.outputs import csv_cell

    assert csv_cell(value) == expected


HOSTILE_COLUMNS = ["=1+2", "+SUM(A1)", "-2+3", "@cmd"]


def test_csv_outputs_never_start_a_formula(tmp_path, capsys, rng):
    src = _log(tmp_path / "h.csv", HOSTILE_COLUMNS, rng)
    cols = ",".join(str(i) for i in range(1, len(HOSTILE_COLUMNS) + 1))
    code, _, err = _run(["analyze", src, "--out", tmp_path / "o", "--no-figures", "--stat", "oadev",
                         "--columns", cols, "--quiet"], capsys)
    assert code == 0, err
    code, stdout, err = _run(["stats", src, "--stat", "oadev", "--columns", cols, "--csv", "-"], capsys)
    assert code == 0, err
    for text in ((tmp_path / "o" / "statistics.csv").read_text(encoding="utf-8"), stdout):
        rows = list(csv.reader(io.StringIO(text)))
        assert {r[0] for r in rows[1:]} == {"'" + c for c in HOSTILE_COLUMNS}
        for r in rows:
            for cell in r:
                try:
                    float(cell)
                except ValueError:
                    assert not cell.startswith(FORMULA_START), cell
