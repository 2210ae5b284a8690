"""Stable32 data files out of ``sigmatau simulate`` and back in: same samples, same statistics."""

from __future__ import annotations

import numpy as np
from helpers import cli_error_line, run_cli

import sigmatau
from sigmatau import io


def test_simulated_phase_file_reads_back_bit_identical(tmp_path, capsys):
    out = tmp_path / "clock-phase.dat"
    code, _, err = run_cli(["simulate", str(out), "--h", "h2=1e-20,h0=1e-22", "--data-type", "phase",
                            "--duration", "2000", "--seed", "7"], capsys)
    assert code == 0, err
    raw = out.read_bytes()
    assert raw.count(b"\r\n") == 2000 and b"#" not in raw  # one value per CRLF line, no header
    log = io.read(out, rate=1.0)
    assert log.data_type == "phase"  # from the word "phase" in the name, as Stable32 users name files
    written = np.array([float(v) for v in raw.split()])
    np.testing.assert_array_equal(log[log.names[0]], written)
    code, table, err = run_cli(["stats", str(out), "--rate", "1", "--stat", "oadev", "--taus", "octave"], capsys)
    assert code == 0, err
    expected = sigmatau.oadev(written, rate=1.0, data_type="phase", taus="octave")
    sigma = [float(line.split()[5]) for line in table.splitlines() if line[:3].strip().isdigit()]
    np.testing.assert_allclose(sigma, expected.dev, rtol=5e-5)  # the table prints 5 digits


def test_a_stable32_file_holds_one_series(tmp_path, capsys):
    code, _, err = run_cli(["simulate", str(tmp_path / "imu.dat"), "--duration", "10"], capsys)
    assert code == 2 and "one series" in cli_error_line(err)
    assert not (tmp_path / "imu.dat").exists()
