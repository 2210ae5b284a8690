"""``sigmatau compare`` and ``sigmatau psd``: the library's numbers, the folder, hostile names, bad input.

The numbers themselves are validated in tests/test_compare.py and tests/test_spectral.py;
here the commands must print and write exactly what the library returns for the same samples.
"""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest
from helpers import cli_error_line, run_cli

import sigmatau
import sigmatau.io
from sigmatau.compare import cornered_hat
from sigmatau.spectral import psd

pytest.importorskip("matplotlib")

RATE = 50.0
N = 20_000
#: White-noise levels of the four simulated gyros (rad/s per sample): one much quieter.
LEVELS = {"g1": 1e-3, "g2": 2e-3, "g3": 3e-3, "q": 2e-4}


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    """Four gyros on one table: a common table motion (random walk) plus each gyro's own white noise."""
    rng = np.random.default_rng(20261125)
    common = np.cumsum(rng.normal(0.0, 1e-4, N))
    cols = {name: common + rng.normal(0.0, s, N) for name, s in LEVELS.items()}
    folder = tmp_path_factory.mktemp("rig")
    path = folder / "rig.csv"
    t = np.arange(N) / RATE
    with open(path, "w") as fh:
        fh.write("timestamp [s]," + ",".join(cols) + "\n")
        np.savetxt(fh, np.column_stack([t, *cols.values()]), delimiter=",", fmt="%.17g")
    return path, cols


@pytest.mark.slow
def test_compare_prints_and_writes_the_library_result(rig, tmp_path, capsys):
    path, cols = rig
    out = tmp_path / "hat"
    code, text, err = run_cli(["compare", path, "--out", out, "--figures", "png"], capsys)
    assert code == 0, err
    expected = cornered_hat(cols, rate=RATE, data_type="freq", statistic="oadev", taus="octave", confidence=0.6827)
    assert sum(line.endswith(" OADEV") for line in text.splitlines()) == 4
    files = sorted(p.name for p in out.iterdir())
    assert files == ["compare.csv", "compare.json", "compare.png", "report.html", "sigmatau-manifest.json"]
    rows = list(csv.DictReader(io.StringIO((out / "compare.csv").read_text())))
    assert len(rows) == expected.tau.size * 4
    for row in rows:
        j = expected.names.index(row["device"])
        i = int(np.flatnonzero(expected.m == int(row["m"]))[0])
        assert float(row["dev"]) == expected.dev[i, j]
        assert float(row["classical_var"]) == expected.classical_var[i, j]
    data = json.loads((out / "compare.json").read_text())
    assert set(data["devices"]) == set(LEVELS)
    # the quiet gyro's own noise at τ0 is resolved, far below the pairs it is part of
    q = expected.device("q")
    assert q.dev[0] < 0.25 * LEVELS["g1"]


def test_compare_several_logs_and_pairs(tmp_path, capsys):
    rng = np.random.default_rng(7)
    clocks = [rng.normal(0, s, 4000).cumsum() for s in (1.0, 2.0, 4.0)]
    names = ["A", "B", "C"]
    files = []
    for i, j in ((0, 1), (1, 2), (2, 0)):
        f = tmp_path / f"{names[i]}{names[j]}-phase.dat"
        np.savetxt(f, clocks[i] - clocks[j], fmt="%.17g")
        files.append(f)
    code, text, err = run_cli(["compare", *files, "--pairs", "A-B,B-C,C-A", "--rate", "1", "--data-type", "phase",
                               "--csv", "-"], capsys)
    assert code == 0, err
    expected = cornered_hat({("A", "B"): clocks[0] - clocks[1], ("B", "C"): clocks[1] - clocks[2],
                             ("C", "A"): clocks[2] - clocks[0]}, rate=1.0, data_type="phase", confidence=0.6827)
    rows = list(csv.DictReader(io.StringIO(text)))
    got = {(r["device"], int(r["m"])): float(r["dev"]) for r in rows}
    for j, name in enumerate(expected.names):
        for i, m in enumerate(expected.m):
            assert got[(name, int(m))] == expected.dev[i, j]


def test_compare_escapes_hostile_device_names(tmp_path, capsys):
    rng = np.random.default_rng(3)
    path = tmp_path / "hostile.csv"
    names = ["=HYPERLINK", "<script>x</script>", "plain"]
    data = rng.normal(size=(3000, 3))
    with open(path, "w") as fh:
        fh.write(",".join(names) + "\n")
        np.savetxt(fh, data, delimiter=",", fmt="%.17g")
    out = tmp_path / "out"
    code, _, err = run_cli(["compare", path, "--rate", "10", "--out", out, "--no-figures"], capsys)
    assert code == 0, err
    text = (out / "compare.csv").read_text()
    assert "\n'=HYPERLINK," in text  # a spreadsheet shows it, never runs it
    page = (out / "report.html").read_text()
    assert "<script>" not in page and "&lt;script&gt;" in page


@pytest.mark.parametrize("extra, pattern", [
    (["--columns", "g1,g2"], "at least 3 devices"),
    (["--stat", "totdev"], "--stat"),
    (["--pairs", "A-B,B-C"], "--pairs"),
    (["--names", "a,b"], "--names"),
    (["--confidence", "1.5"], "--confidence"),
])
def test_compare_refuses_bad_requests_in_one_line(rig, capsys, extra, pattern):
    path, _ = rig
    code, _, err = run_cli(["compare", path, *extra], capsys)
    assert code == 2
    cli_error_line(err, pattern)


def test_compare_refuses_records_that_are_not_simultaneous(tmp_path, capsys):
    files = []
    for k, n in enumerate((1000, 1000, 900)):
        f = tmp_path / f"c{k}.csv"
        np.savetxt(f, np.random.default_rng(k).normal(size=n), header="y", comments="")
        files.append(f)
    code, _, err = run_cli(["compare", *files, "--rate", "1", "--data-type", "freq"], capsys)
    assert code == 2
    cli_error_line(err, "different lengths")


def test_compare_never_overwrites_an_input_or_a_foreign_folder(rig, tmp_path, capsys):
    path, _ = rig
    before = path.read_bytes()
    code, _, err = run_cli(["compare", path, "--csv", path, "--force"], capsys)
    assert code == 2 and path.read_bytes() == before
    foreign = tmp_path / "thesis"
    foreign.mkdir()
    (foreign / "thesis.tex").write_text("x")
    code, _, err = run_cli(["compare", path, "--out", foreign, "--force"], capsys)
    assert code == 2 and (foreign / "thesis.tex").read_text() == "x"


def test_psd_prints_and_writes_the_library_result(rig, tmp_path, capsys):
    path, cols = rig
    out = tmp_path / "psd"
    code, text, err = run_cli(["psd", path, "--out", out, "--figures", "png"], capsys)
    assert code == 0, err
    files = sorted(p.name for p in out.iterdir())
    assert files == ["psd.csv", "psd.json", "psd.png", "report.html", "sigmatau-manifest.json"]
    rows = list(csv.DictReader(io.StringIO((out / "psd.csv").read_text())))
    rate = sigmatau.io.read(path).rate  # from the timestamps, as the command takes it
    for name, y in cols.items():
        r = psd(y, rate=rate, data_type="freq", confidence=0.6827)  # the command's default
        mine = [row for row in rows if row["channel"] == name]
        assert len(mine) == r.f.size
        np.testing.assert_array_equal([float(row["s_y"]) for row in mine], r.s_y)
        np.testing.assert_array_equal([float(row["s_y_low"]) for row in mine], r.lo)
        assert f"h+0 = {r.h[0]:.4e}" in text
    data = json.loads((out / "psd.json").read_text())
    assert set(data["channels"]) == set(LEVELS)


def test_psd_white_level_matches_the_simulated_noise(rig, capsys):
    path, cols = rig
    code, text, _ = run_cli(["psd", path, "--columns", "g3", "--csv", "-"], capsys)
    assert code == 0
    rows = list(csv.DictReader(io.StringIO(text)))
    # one-sided white level h0 = 2σ²/rate; the top decade is far above the table motion
    top = [float(r["s_y"]) for r in rows if float(r["f_hz"]) > RATE / 20]
    assert np.mean(top) == pytest.approx(2 * LEVELS["g3"] ** 2 / RATE, rel=0.05)


@pytest.mark.parametrize("extra, pattern", [
    (["--segments", "0"], "--segments"),
    (["--carrier", "-1"], "--carrier"),
    (["--bins-per-decade", "0"], "--bins-per-decade"),
    (["--figures", "gif", "--out", "x"], "--figures"),
])
def test_psd_refuses_bad_requests_in_one_line(rig, capsys, extra, pattern):
    path, _ = rig
    code, _, err = run_cli(["psd", path, *extra], capsys)
    assert code == 2
    cli_error_line(err, pattern)


def test_stats_takes_the_new_statistics(rig, capsys):
    path, cols = rig
    code, text, err = run_cli(["stats", path, "--columns", "g1", "--stat", "pdev,mhdev,ldev,mhtotdev"], capsys)
    assert code == 0, err
    for stat in ("PDEV", "MHDEV", "LDEV", "MHTOTDEV"):
        assert f"g1 [?] {stat}" in text
    expected = sigmatau.mhdev(cols["g1"], rate=RATE, taus="octave")
    block = text.split("g1 [?] MHDEV")[1].split("\n\n")[0]
    sigma = [float(line.split()[5]) for line in block.splitlines()[2:] if line.strip()]
    np.testing.assert_allclose(sigma, expected.dev, rtol=5e-5)


def test_psd_with_a_carrier_writes_phase_noise(tmp_path, capsys):
    # Phase data in seconds of a 10 MHz oscillator: L(f) = 10·log10(S_φ/2), S_φ = (2πν0)²·S_x.
    x = np.random.default_rng(9).normal(0.0, 1e-12, 20_000)
    path = tmp_path / "osc-phase.dat"
    np.savetxt(path, x, fmt="%.17g")
    code, text, err = run_cli(["psd", path, "--rate", "1", "--data-type", "phase", "--carrier", "10e6",
                               "--csv", "-"], capsys)
    assert code == 0, err
    rows = list(csv.DictReader(io.StringIO(text)))
    r = psd(x, rate=1.0, data_type="phase", carrier=10e6, confidence=0.6827)
    np.testing.assert_allclose([float(row["l_dbc_hz"]) for row in rows], r.l_dbc, rtol=1e-12)
    # white PM: S_x = 2σ²/rate one-sided, so L is flat at 10·log10((2π·1e7)²·σ²); the top bins agree
    flat = 10 * np.log10((2 * np.pi * 1e7) ** 2 * 1e-24)
    top = [float(row["l_dbc_hz"]) for row in rows if float(row["f_hz"]) > 0.05]
    assert np.mean(top) == pytest.approx(flat, abs=0.3)
