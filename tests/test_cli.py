"""The ``sigmatau`` command: every subcommand in-process, outputs, error paths and exit codes."""

from __future__ import annotations

import csv
import hashlib
import json
import math
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import assert_one_line_error, cli_error_line, run_cli

import sigmatau
from sigmatau import __version__
from sigmatau.cli import main
from sigmatau.units import convert

matplotlib = pytest.importorskip("matplotlib")
yaml = pytest.importorskip("yaml")


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


_run = run_cli
_one_line_error = cli_error_line


def _no_partial(folder: Path) -> None:
    assert not [p.name for p in folder.iterdir() if ".partial" in p.name or ".old-" in p.name]


@pytest.fixture(scope="module")
def imu_csv(tmp_path_factory) -> Path:
    """A 10-minute 6-axis log at 100 Hz written by ``sigmatau simulate`` (known truth)."""
    folder = tmp_path_factory.mktemp("log")
    path = folder / "imu.csv"
    assert main(["simulate", str(path), "--preset", "lsm6dsl", "--duration", "600", "--rate", "100",
                 "--seed", "3", "--gyro-unit", "deg/s", "--accel-unit", "g"]) == 0
    return path


@pytest.fixture(scope="module")
def analyzed(imu_csv, tmp_path_factory):
    """``sigmatau analyze`` with the default statistics on the simulated log."""
    out = tmp_path_factory.mktemp("res") / "out"
    before = _digest(imu_csv)
    code = main(["analyze", str(imu_csv), "--out", str(out), "--datasheet", "lsm6dsl", "--figures", "png,svg,pdf"])
    assert code == 0
    assert _digest(imu_csv) == before  # the input is only read
    return out


# --------------------------------------------------------------------------- help


def test_version_and_help(capsys):
    code, out, _ = _run(["--version"], capsys)
    assert code == 0 and out.strip() == f"sigmatau {__version__}"
    for cmd in ("demo", "analyze", "stats", "simulate"):
        code, out, _ = _run([cmd, "--help"], capsys)
        assert code == 0
        assert "examples:" in out and "exit codes" in out
    code, out, _ = _run(["analyze", "--help"], capsys)
    assert "gyro rad/s and accel m/s^2" in out  # the unit defaults are stated


def test_no_command_is_usage_error(capsys):
    code, _, err = _run([], capsys)
    assert code == 2
    assert "usage" in err


def test_unknown_command_and_option(capsys):
    code, _, err = _run(["frobnicate"], capsys)
    assert code == 2
    _one_line_error(err, "invalid choice")
    code, _, err = _run(["stats", "x.csv", "--bogus"], capsys)
    assert code == 2
    _one_line_error(err, "--bogus")


# --------------------------------------------------------------------- simulate


def test_simulate_csv_header_units_and_truth(imu_csv):
    with open(imu_csv) as fh:
        header = next(csv.reader(fh))
    assert header == ["timestamp [s]", "gyro_x [deg/s]", "gyro_y [deg/s]", "gyro_z [deg/s]",
                      "accel_x [g]", "accel_y [g]", "accel_z [g]"]
    data = np.loadtxt(imu_csv, delimiter=",", skiprows=1)
    assert data.shape == (60000, 7)
    # white noise density of the LSM6DSL preset (4 mdps/√Hz): sample std = N·√rate
    std = data[:, 1:4].std(axis=0)
    expected = convert(4.0, "mdps/sqrt(Hz)", "deg/s/sqrt(Hz)") * math.sqrt(100.0)
    assert np.all(np.abs(std / expected - 1) < 0.02)


def test_simulate_npz_npy_explicit_terms_and_power_law(tmp_path, capsys):
    from sigmatau import io

    npz = tmp_path / "g.npz"
    code, _, err = _run(["simulate", npz, "--preset", "none", "--sensors", "gyro", "--rate", "200",
                         "--duration", "60", "--gyro-N", "0.2 deg/sqrt(h)", "--gyro-B", "3 deg/h"], capsys)
    assert code == 0, err
    log = io.read(npz)
    assert log.names == ("gyro_x", "gyro_y", "gyro_z") and log.rate == pytest.approx(200.0)
    expected = convert(0.2, "deg/sqrt(h)", "rad/s/sqrt(Hz)") * math.sqrt(200.0)
    assert np.std(log["gyro_x"]) == pytest.approx(expected, rel=0.05)
    npy = tmp_path / "clock.npy"
    code, _, err = _run(["simulate", npy, "--h", "h0=1e-22", "--duration", "1000", "--rate", "1"], capsys)
    assert code == 0, err
    y = np.load(npy)
    assert y.shape == (1000,)
    # white FM: AVAR(1 s) = h0/2 → sample variance ≈ h0/2 (one-sided PSD h0 up to 0.5 Hz)
    assert np.var(y) == pytest.approx(0.5e-22, rel=0.15)
    code, _, err = _run(["simulate", npy, "--h", "h0=1e-22"], capsys)
    assert code == 2
    _one_line_error(err, "exists", "--force")


@pytest.mark.parametrize("argv, pattern", [
    (["simulate", "x.txt"], "must end in .csv"),
    (["simulate", "x.csv", "--duration", "-1"], "--duration"),
    (["simulate", "x.csv", "--preset", "nosuch"], "choose from"),
    (["simulate", "x.csv", "--sensors", "magnet"], "magnet"),
    (["simulate", "x.csv", "--gyro-N", "abc"], "value [unit]"),
    (["simulate", "x.csv", "--gyro-N", "1 m/s"], "--gyro-N"),
    (["simulate", "x.csv", "--h", "h7=1"], "ALPHA"),
])
def test_simulate_usage_errors(tmp_path, capsys, monkeypatch, argv, pattern):
    monkeypatch.chdir(tmp_path)
    code, _, err = _run(argv, capsys)
    assert code == 2
    _one_line_error(err, pattern)
    assert not list(tmp_path.iterdir())


# ----------------------------------------------------------------------- analyze


@pytest.mark.slow
def test_analyze_writes_every_output(analyzed):
    names = {p.name for p in analyzed.iterdir()}
    assert {"results.json", "statistics.csv", "model.csv", "imu.yaml", "report.html"} <= names
    for group in ("gyro", "accel"):
        for ext in ("png", "svg", "pdf"):
            assert f"sigma_tau_{group}.{ext}" in names
    for ch in ("gyro_x", "accel_z"):
        assert f"signal_{ch}.png" in names
    _no_partial(analyzed.parent)
    assert (analyzed / f"sigma_tau_gyro.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (analyzed / f"sigma_tau_gyro.pdf").read_bytes()[:5] == b"%PDF-"


@pytest.mark.slow
def test_results_json_records_everything(analyzed, imu_csv):
    data = json.loads((analyzed / "results.json").read_text())
    assert data["tool"] == {"name": "sigmatau", "version": __version__}
    assert data["input"]["sha256"] == _digest(imu_csv)
    assert data["input"]["format"] == "csv"
    s = data["settings"]
    assert s["statistics"] == ["oadev", "mdev", "tdev", "ohdev", "totdev", "theoh"]
    assert s["confidence"] == pytest.approx(0.6827) and s["axis_rule"] == "max"
    assert s["theoh"] == "fast"  # the main job's default (docs/theoh-fast.md)
    assert data["log"]["timing"]["gaps"] == [] and data["log"]["rate"] == pytest.approx(100.0)
    chans = {c["name"]: c for c in data["channels"]}
    assert list(chans) == ["gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"]
    gx = chans["gyro_x"]
    assert set(gx["statistics"]) == set(s["statistics"])
    oadev = gx["statistics"]["oadev"]
    assert len(oadev["taus"]) == len(oadev["dev"]) == len(oadev["edf"]) == len(oadev["alpha"])
    assert all(lo < d < hi for lo, d, hi in zip(oadev["ci_low"], oadev["dev"], oadev["ci_high"]) if lo and hi)
    # the model is in deg/s (the samples' unit) with SI and customary conversions
    model = gx["model"]
    assert model["unit"] == "deg/s"
    n_si = model["si"]["N"]
    truth = convert(4.0, "mdps/sqrt(Hz)", "rad/s/sqrt(Hz)")
    assert n_si["low"] < truth * 1.01 and n_si["high"] > truth * 0.99
    assert gx["datasheet"][0]["term"] == "N"
    assert data["figures"] and all(f["files"] for f in data["figures"])


@pytest.mark.slow
def test_statistics_and_model_csv(analyzed):
    with open(analyzed / "statistics.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert {r["statistic"] for r in rows} == {"oadev", "mdev", "tdev", "ohdev", "totdev", "theoh"}
    first = next(r for r in rows if r["channel"] == "gyro_x" and r["statistic"] == "oadev")
    assert first["m"] == "1" and float(first["tau_s"]) == pytest.approx(0.01)
    assert float(first["dev_low"]) < float(first["dev"]) < float(first["dev_high"])
    with open(analyzed / "model.csv") as fh:
        model = list(csv.DictReader(fh))
    n_si = [r for r in model if r["channel"] == "gyro_x" and r["term"] == "N" and r["unit_kind"] == "si"]
    assert n_si[0]["unit"] == "rad/s/sqrt(Hz)" and n_si[0]["resolved"] == "True"
    assert any(r["unit"] == "deg/sqrt(h)" for r in model)


@pytest.mark.slow
def test_kalibr_yaml_is_valid_and_states_the_rule(analyzed):
    text = (analyzed / "imu.yaml").read_text()
    doc = yaml.safe_load(text)
    for key in ("accelerometer_noise_density", "accelerometer_random_walk", "gyroscope_noise_density",
                "gyroscope_random_walk", "update_rate"):
        assert isinstance(doc[key], float), key  # PyYAML (Kalibr) must read floats, not strings
    assert doc["rostopic"] == "/imu0" and doc["update_rate"] == 100.0
    assert "axes combined: largest of the axes" in text
    assert "gyroscope_sigma_d" in text and "discrete-time" in text
    data = json.loads((analyzed / "results.json").read_text())
    per_axis = [c["model"]["si"]["N"]["value"] for c in data["channels"] if c["group"] == "gyro"]
    assert doc["gyroscope_noise_density"] == pytest.approx(max(per_axis), rel=1e-6)


@pytest.mark.slow
def test_report_html_is_self_contained(analyzed):
    html = (analyzed / "report.html").read_text()
    assert html.startswith("<!DOCTYPE html>")
    assert html.count('src="data:image/png;base64,') == 8  # 2 σ–τ + 6 signal figures
    # Nothing is fetched: no src/href to another host. The only scripts are the inlined chart library,
    # its start-up code and the two charts' specs (JSON data, not code); the only URLs inside the
    # library's text are its own (the SVG namespace, links of an actions menu that is switched off).
    assert not re.search(r'(?:src|href)\s*=\s*["\']?(?:https?:)?//', html, re.I)
    assert html.count("<script") == 4 and html.count('<script type="application/json" class="ichart-spec"') == 2
    outside = re.sub(r"<script[^>]*>.*?</script>", "", html, flags=re.S)
    assert "http://" not in outside and "https://" not in outside
    assert "gyroscope_noise_density" in html  # the YAML
    assert "Data checks" in html and "Noise model" in html and "AF" in html


@pytest.mark.slow
def test_analyze_summary_on_stdout(imu_csv, tmp_path, capsys):
    code, out, err = _run(["analyze", imu_csv, "--out", tmp_path / "o", "--stat", "oadev", "--no-figures",
                           "--axis-rule", "rms", "--quiet"], capsys)
    assert code == 0, err
    assert "angle random walk" in out and "°/√h" in out and "rad/s/√Hz" in out
    assert "[not-resolved" in out  # flags
    assert "root mean square of the axes" in out
    assert not list((tmp_path / "o").glob("*.png"))
    assert err == ""  # quiet, and no warnings on stderr (flags are in the summary)


@pytest.mark.slow
def test_output_directory_policy(imu_csv, tmp_path, capsys, monkeypatch):
    out = tmp_path / "o"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    base = ["analyze", imu_csv, "--stat", "oadev", "--no-figures"]
    # a directory sigmatau did not write is refused with or without --force, and the message
    # does not send the user to --force
    for extra in ([], ["--force"]):
        code, _, err = _run([*base, "--out", out, *extra], capsys)
        assert code == 2
        line = _one_line_error(err, "not a sigmatau output directory")
        assert "--force" not in line
    assert (out / "keep.txt").read_text() == "mine"
    # nor the current directory, its parents (/ included) or the home directory: the first message
    # says so, without sending the user to --force first
    monkeypatch.chdir(out)
    for target in (".", "..", "/", str(Path.home())):
        for extra in ([], ["--force"]):
            code, _, err = _run([*base, "--out", target, *extra], capsys)
            assert code == 2, target
            line = _one_line_error(err, "current directory")
            assert "--force" not in line
    assert (out / "keep.txt").read_text() == "mine"
    monkeypatch.chdir(tmp_path)
    # a previous output: without --force the message offers it, and with it the run succeeds
    res = tmp_path / "res"
    assert _run([*base, "--out", res], capsys)[0] == 0
    code, _, err = _run([*base, "--out", res], capsys)
    assert code == 2
    _one_line_error(err, "exists", "--force")
    code, _, err = _run([*base, "--out", res, "--force"], capsys)
    assert code == 0, err
    assert (res / "results.json").exists()
    _no_partial(tmp_path)


def test_channel_names_cannot_escape_the_output_directory(tmp_path, capsys):
    rng = np.random.default_rng(2)
    rows = "".join(f"{i / 100},{float(rng.standard_normal())!r},{float(rng.standard_normal())!r}\n"
                   for i in range(3000))
    src = _write(tmp_path / "esc.csv", "t,a/../../../escaped,rate a/b\n" + rows)
    work = tmp_path / "w" / "x"
    work.mkdir(parents=True)
    code, out, err = _run(["analyze", src, "--out", work / "o", "--stat", "oadev", "--figures", "png"], capsys)
    assert code == 0, err
    assert all((work / "o") in p.parents for p in tmp_path.rglob("*.png"))  # nothing written outside --out
    pngs = sorted(p.name for p in (work / "o").glob("*.png"))
    assert len(pngs) == 3 and all("/" not in p for p in pngs)  # σ–τ of the group + two signal figures
    assert not [p for p in (work / "o").iterdir() if p.is_dir()]


def test_stats_csv_never_overwrites_the_input(imu_csv, tmp_path, capsys):
    import shutil as _sh

    src = tmp_path / "in.csv"
    _sh.copy(imu_csv, src)
    before = _digest(src)
    code, _, err = _run(["stats", src, "--csv", src, "--force"], capsys)
    assert code == 2
    _one_line_error(err, "is the input")
    assert _digest(src) == before


def test_force_never_deletes_the_input(tmp_path, imu_csv, capsys):
    folder = tmp_path / "d"
    folder.mkdir()
    log = folder / "imu.csv"
    shutil.copy(imu_csv, log)
    (folder / "results.json").write_text("{}")  # looks like a previous output that holds the input
    code, _, err = _run(["analyze", log, "--out", folder, "--force", "--stat", "oadev", "--no-figures"], capsys)
    assert code == 2
    _one_line_error(err, "contains the input")
    assert _digest(log) == _digest(imu_csv)


@pytest.mark.slow
def test_failure_while_writing_leaves_nothing(imu_csv, tmp_path, capsys, monkeypatch):
    from sigmatau.report import plots

    def boom(*a, **k):
        raise RuntimeError("disk on fire")

    monkeypatch.setattr(plots, "save_figure", boom)
    out = tmp_path / "o"
    code, _, err = _run(["analyze", imu_csv, "--out", out, "--stat", "oadev"], capsys)
    assert code == 3
    _one_line_error(err, "internal error", "disk on fire", "--debug")
    assert not out.exists()
    _no_partial(tmp_path)
    with pytest.raises(RuntimeError, match="disk on fire"):
        main(["analyze", str(imu_csv), "--out", str(out), "--stat", "oadev", "--debug"])
    assert not out.exists()
    _no_partial(tmp_path)


# ------------------------------------------------------------------ input errors


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def _write_bytes(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


@pytest.mark.parametrize("make, extra, code, patterns", [
    (lambda d: d / "missing.csv", [], 1, ["missing.csv", "no such file"]),
    (lambda d: _write(d / "words.csv", "a,b\nx,y\nz,w\n"), [], 1, ["words.csv", "numeric"]),
    (lambda d: _write(d / "short.csv", "t,gyro_x\n0,1\n0.01,2\n"), [], 1, ["short.csv"]),
    (lambda d: _write(d / "short.csv", "t,gyro_x\n0,1\n0.01,2\n0.02,3\n"), ["--stat", "theobr"], 1,
     ["too few samples for any statistic"]),
    (lambda d: _write_bytes(d / "bad.npy", b"\x93NUMPY garbage"), [], 1, ["bad.npy"]),
    (lambda d: _write(d / "nan.csv", "t,gyro_x\n" + "".join(f"{i / 100},{'nan' if i == 50 else i % 7}\n"
                                                         for i in range(200))), ["--gaps", "refuse"], 1, ["NaN"]),
    (lambda d: _write(d / "inf.csv", "t,gyro_x\n" + "".join(f"{i / 100},{'inf' if i == 50 else i % 7}\n"
                                                         for i in range(200))), [], 1, ["infinite"]),
    (lambda d: _write(d / "gap.csv", "t,gyro_x\n" + "".join(f"{i / 100 if i < 100 else i / 100 + 1},{i % 7}\n"
                                                          for i in range(300))), [], 1, ["gap"]),
    (lambda d: _write(d / "c.csv", "t,gyro_x\n" + "".join(f"{i / 100},{i % 7}\n" for i in range(300))),
     ["--columns", "gyro_q"], 2, ["gyro_q", "gyro_x"]),
    (lambda d: _write(d / "c.csv", "t,gyro_x\n" + "".join(f"{i / 100},{i % 7}\n" for i in range(300))),
     ["--stat", "adev,zdev"], 2, ["zdev", "choose from"]),
    (lambda d: _write(d / "c.csv", "t,gyro_x\n" + "".join(f"{i / 100},{i % 7}\n" for i in range(300))),
     ["--confidence", "1.5"], 2, ["--confidence"]),
    (lambda d: _write(d / "c.csv", "t,gyro_x\n" + "".join(f"{i / 100},{i % 7}\n" for i in range(300))),
     ["--figures", "gif"], 2, ["gif"]),
    (lambda d: _write(d / "c.csv", "t,gyro_x\n" + "".join(f"{i / 100},{i % 7}\n" for i in range(300))),
     ["--gyro-unit", "furlongs"], 2, ["furlongs"]),
    (lambda d: _write(d / "c.csv", "t,gyro_x\n" + "".join(f"{i / 100},{i % 7}\n" for i in range(300))),
     ["--taus", "weekly"], 2, ["weekly"]),
    (lambda d: _write(d / "c.csv", "t,gyro_x\n" + "".join(f"{i / 100},{i % 7}\n" for i in range(300))),
     ["--datasheet", "nosuchpart"], 2, ["nosuchpart", "lsm6dsl"]),
    (lambda d: _write(d / "c.csv", "t,gyro_x\n" + "".join(f"{i / 100},{i % 7}\n" for i in range(300))),
     ["--gaps", "maybe"], 2, ["maybe"]),
])
def test_analyze_errors_one_line_with_exit_code(tmp_path, capsys, make, extra, code, patterns):
    src = make(tmp_path)
    before = _digest(src) if src.exists() else None
    out = tmp_path / "out"
    got, stdout, err = _run(["analyze", src, "--out", out, "--no-figures", *extra], capsys)
    assert got == code, err
    _one_line_error(err, *patterns)
    assert not out.exists()
    _no_partial(tmp_path)
    if before is not None:
        assert _digest(src) == before


def test_debug_shows_the_traceback(tmp_path):
    with pytest.raises(Exception, match="no such file"):
        main(["analyze", str(tmp_path / "nothing.csv"), "--debug"])


def test_gap_split_analyses_the_longest_segment(tmp_path, capsys):
    rng = np.random.default_rng(5)
    t = np.concatenate([np.arange(3000), np.arange(3005, 4005)]) / 100.0
    g = rng.standard_normal(t.size) * 1e-3
    lines = "t,gyro_x\n" + "".join(f"{a:.2f},{float(b)!r}\n" for a, b in zip(t, g))
    src = _write(tmp_path / "gappy.csv", lines)
    code, out, err = _run(["analyze", src, "--out", tmp_path / "o", "--gaps", "split", "--stat", "oadev",
                           "--no-figures"], capsys)
    assert code == 0, err
    data = json.loads((tmp_path / "o" / "results.json").read_text())
    assert data["channels"][0]["n_samples"] == 3000
    assert "longest" in data["notes"][0] and "3000 of 4000" in data["notes"][0]


# ------------------------------------------------------------------------ stats


def test_stats_table_matches_the_library(tmp_path, capsys):
    import sigmatau
    from sigmatau.datasets import nbs1000

    y = nbs1000()
    src = _write(tmp_path / "nbs.txt", "".join(f"{float(v)!r}\n" for v in y))
    code, out, err = _run(["stats", src, "--data-type", "freq", "--rate", "1", "--stat", "adev,oadev"], capsys)
    assert code == 0, err
    assert "AF" in out and "Min Sigma" in out and "Max Sigma" in out
    # NBS 1000 OADEV at tau = 1 s (NIST SP 1065 Table 31): 2.922319e-01 → printed to 5 digits
    assert "2.9223e-01" in out
    ref = sigmatau.oadev(y, taus="octave")
    assert f"{ref.ci_high[2]:.4e}" in out
    csv_path = tmp_path / "s.csv"
    code, _, err = _run(["stats", src, "--data-type", "freq", "--rate", "1", "--stat", "mdev", "--csv", csv_path],
                        capsys)
    assert code == 0, err
    with open(csv_path, encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert rows[0]["statistic"] == "mdev" and float(rows[0]["dev"]) == pytest.approx(
        sigmatau.mdev(y).dev[0], rel=1e-15)
    code, _, err = _run(["stats", src, "--data-type", "freq", "--rate", "1", "--csv", csv_path], capsys)
    assert code == 2
    _one_line_error(err, "exists")
    code, out, _ = _run(["stats", src, "--data-type", "freq", "--rate", "1", "--csv", "-"], capsys)
    assert code == 0 and out.startswith("channel,group,unit,statistic")


def test_stats_too_short_for_a_statistic_is_reported(tmp_path, capsys):
    src = _write(tmp_path / "y.txt", "".join(f"{v}\n" for v in np.random.default_rng(1).standard_normal(40)))
    code, out, err = _run(["stats", src, "--data-type", "freq", "--rate", "1", "--stat", "oadev,theobr"], capsys)
    assert code == 0, err
    assert "THEOBR: not computed" in out


def test_stats_stable32_phase_file(tmp_path, capsys):
    from refdata import dataset

    src = tmp_path / "phase.dat"
    np.savetxt(src, dataset("phasedat")[0])
    code, out, err = _run(["stats", src, "--data-type", "phase", "--rate", "1", "--stat", "adev"], capsys)
    assert code == 0, err
    assert "ADEV" in out


# ------------------------------------------------------------------------- demo


@pytest.mark.slow
def test_demo_runs_the_full_analysis(tmp_path, capsys):
    out = tmp_path / "demo"
    code, stdout, err = _run(["demo", "--out", out, "--duration", "600", "--rate", "52", "--quiet"], capsys)
    assert code == 0, err
    assert "demo: simulating a 6-axis LSM6DSL-like IMU" in err
    names = {p.name for p in out.iterdir()}
    assert {"report.html", "imu.yaml", "results.json", "sigma_tau_gyro.png", "sigma_tau_accel.svg"} <= names
    data = json.loads((out / "results.json").read_text())
    assert data["settings"]["datasheet"]["gyro"]["N"][1] == "rad/s/sqrt(Hz)"
    assert "datasheet N" in stdout


def test_installed_entry_point(tmp_path):
    exe = shutil.which("sigmatau")
    if exe is None:
        pytest.skip("the console script is not on PATH (package not installed)")
    out = subprocess.run([exe, "--version"], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.strip() == f"sigmatau {__version__}"
    out = subprocess.run([exe, "analyze", str(tmp_path / "none.csv")], capture_output=True, text=True)
    assert out.returncode == 1
    _one_line_error(out.stderr, "no such file")
    mod = subprocess.run([sys.executable, "-m", "sigmatau", "--version"], capture_output=True, text=True)
    assert mod.returncode == 0 and mod.stdout.strip() == f"sigmatau {__version__}"


ADIS = Path(__file__).resolve().parents[2] / "shared" / "refdata" / "imu" / "smac_imudata_adis16405" / \
    "adis_16405_imu1.csv.gz"


@pytest.mark.slow
@pytest.mark.skipif(not ADIS.exists(), reason=f"{ADIS} not available (CC BY-NC-SA data, read in place only)")
def test_analyze_real_adis16405_log(tmp_path, capsys):
    """A real 1e6-row gzip CSV (no time column, units in the names): read in place, never copied."""
    before = _digest(ADIS)
    code, out, err = _run(["analyze", ADIS, "--out", tmp_path / "adis"], capsys)
    assert code == 2
    _one_line_error(err, "no time column and no rate", "--rate")
    code, out, err = _run(["analyze", ADIS, "--rate", "100", "--gyro-unit", "deg/s", "--accel-unit", "g",
                           "--stat", "oadev", "--no-figures", "--out", tmp_path / "adis"], capsys)
    assert code == 0, err
    assert _digest(ADIS) == before
    # the bias of this unit settles after power-on: detected and left out by default, saying so, and
    # the count of samples analysed is the record's less those
    found = re.search(r"warm-up: detected on [a-z_, ]+; every channel analysed from ([0-9.]+) s \((\d+) samples", out)
    assert found, out
    cut = int(found.group(2))
    assert 10 <= float(found.group(1)) <= 600 and cut == round(100 * float(found.group(1)))
    assert f"{1_000_000 - cut} samples at 100 Hz" in out
    assert "[quantized N]" in out  # the ADIS16405 accelerometers are quantised (std ≈ 1 LSB)
    doc = yaml.safe_load((tmp_path / "adis" / "imu.yaml").read_text())
    # ARW of the three gyros ≈ 2.4–2.6 °/√h (the largest is written): between 2 and 3 °/√h in rad/s/√Hz
    arw = convert(doc["gyroscope_noise_density"], "rad/s/sqrt(Hz)", "deg/sqrt(h)")
    assert 2.0 < arw < 3.0


EUROC_HEADER = ("#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
                "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]")


def test_same_numbers_from_every_format(tmp_path, capsys):
    """One 6-axis record written as EuRoC CSV, whitespace text, .npz, .npy, HDF5 and Parquet:
    ``sigmatau stats --csv -`` gives identical tables."""
    n, rate = 4000, 200.0
    rng = np.random.default_rng(11)
    v = rng.standard_normal((n, 6)) * 1e-3
    t_ns = 1_403_636_579_758_555_392 + 5_000_000 * np.arange(n, dtype=np.int64)
    files = {}
    rows = "\n".join(f"{ti}," + ",".join(repr(float(x)) for x in r) for ti, r in zip(t_ns, v))
    files["euroc"] = _write(tmp_path / "data.csv", EUROC_HEADER + "\n" + rows + "\n"), []
    text = "\n".join(" ".join(repr(float(x)) for x in r) for r in v)
    files["whitespace"] = _write(tmp_path / "plain.txt", "# gyro_x gyro_y gyro_z accel_x accel_y accel_z\n"
                                 + text + "\n"), ["--rate", "200"]
    names = ["gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"]
    np.savez(tmp_path / "log.npz", rate=rate, **{k: v[:, j] for j, k in enumerate(names)})
    files["npz"] = tmp_path / "log.npz", []
    np.save(tmp_path / "log.npy", v)
    files["npy"] = tmp_path / "log.npy", ["--rate", "200", "--columns", "0,1,2,3,4,5"]
    try:
        import h5py

        with h5py.File(tmp_path / "log.h5", "w") as f:
            g = f.create_group("imu")
            g["gyro"] = v[:, :3]
            g["accel"] = v[:, 3:]
            g.attrs["rate"] = rate
        files["hdf5"] = tmp_path / "log.h5", ["--dataset", "imu"]
    except ImportError:
        pass
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq

        pq.write_table(pa.table({"t": (t_ns - t_ns[0]) / 1e9, **{k: v[:, j] for j, k in enumerate(names)}}),
                       tmp_path / "log.parquet")
        files["parquet"] = tmp_path / "log.parquet", []
    except ImportError:
        pass
    tables = {}
    for kind, (path, extra) in files.items():
        code, out, err = _run(["stats", path, "--stat", "oadev,mdev", "--csv", "-", *extra], capsys)
        assert code == 0, (kind, err)
        rows = list(csv.DictReader(out.splitlines()))
        tables[kind] = {(r["statistic"], int(r["m"]), r["channel"] if not r["channel"].startswith("col")
                         else names[int(r["channel"][3:])]): float(r["dev"]) for r in rows}
    ref = tables.pop("euroc")
    assert len(ref) > 50
    for kind, table in tables.items():
        assert set(table) == set(ref), kind
        for key, dev in table.items():
            assert dev == pytest.approx(ref[key], rel=1e-12), (kind, key)


@pytest.mark.slow
def test_datasheet_numbers_and_units(imu_csv, tmp_path, capsys):
    code, out, err = _run(["analyze", imu_csv, "--out", tmp_path / "o", "--stat", "oadev", "--no-figures",
                           "--datasheet", "gyro.N=0.24 deg/sqrt(h)", "--datasheet", "accel.N=80 ug/sqrt(Hz)"],
                          capsys)
    assert code == 0, err
    assert "datasheet N = 0.24 deg/sqrt(h)" in out and "datasheet N = 80 ug/sqrt(Hz)" in out
    code, _, err = _run(["analyze", imu_csv, "--out", tmp_path / "p", "--datasheet", "gyro.N=fast"], capsys)
    assert code == 2
    _one_line_error(err, "gyro.N")


@pytest.mark.slow
@pytest.mark.filterwarnings("default::sigmatau.errors.SigmaTauWarning")  # the CLI prints it
def test_without_matplotlib_everything_but_the_figures_is_written(imu_csv, tmp_path, capsys, monkeypatch):
    """`pip install sigmatau` without the plot extra: a warning names the extra, the rest is written."""
    for name in [m for m in sys.modules if m == "matplotlib" or m.startswith("matplotlib.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib -> ImportError
    out = tmp_path / "o"
    code, stdout, err = _run(["analyze", imu_csv, "--out", out, "--stat", "oadev"], capsys)
    assert code == 0, err
    assert "sigmatau[plot]" in err and "warning" in err
    names = {p.name for p in out.iterdir()}
    assert {"results.json", "statistics.csv", "model.csv", "imu.yaml", "report.html", "sigmatau-manifest.json"} == names
    html = (out / "report.html").read_text()
    assert "Figures not made" in html and "sigmatau[plot]" in html


def test_stats_chunked_equals_in_memory(tmp_path, capsys):
    """`stats --chunked` reads one series piecewise (.npy and raw binary with a header) and gives the
    in-memory numbers; wrong use is a one-line usage error."""
    import sigmatau

    y = np.random.default_rng(21).standard_normal(50_001)
    np.save(tmp_path / "y.npy", y)
    (tmp_path / "y.bin").write_bytes(b"H" * 64 + y.astype("<f4").tobytes())
    code, out, err = _run(["stats", tmp_path / "y.npy", "--chunked", "--rate", "10", "--stat", "oadev,totdev",
                           "--chunk-size", "4099", "--csv", "-"], capsys)
    assert code == 0, err
    rows = list(csv.DictReader(out.splitlines()))
    for stat in ("oadev", "totdev"):
        ref = getattr(sigmatau, stat)(y, rate=10.0)
        got = [float(r["dev"]) for r in rows if r["statistic"] == stat]
        np.testing.assert_allclose(got, ref.dev, rtol=1e-12, atol=0)
        assert [int(r["alpha"]) for r in rows if r["statistic"] == stat] == ref.alpha.astype(int).tolist()
    code, out, err = _run(["stats", tmp_path / "y.bin", "--chunked", "--dtype", "<f4", "--offset", "64",
                           "--rate", "10", "--stat", "mdev"], capsys)
    assert code == 0, err
    ref = sigmatau.mdev(y.astype("<f4"), rate=10.0)
    assert "read in chunks" in out and f"{ref.dev[0]:.4e}" in out
    for argv, pattern in ((["--stat", "oadev"], "--rate"), (["--rate", "1", "--stat", "theo1"], "not theo1")):
        code, _, err = _run(["stats", tmp_path / "y.npy", "--chunked", *argv], capsys)
        assert code == 2
        _one_line_error(err, pattern)
    code, _, err = _run(["stats", tmp_path / "y.bin", "--chunked", "--rate", "1"], capsys)
    assert code == 2
    _one_line_error(err, "--dtype")


# ------------------------------------------------------------- options tested end to end


@pytest.mark.slow
def test_axis_rule_mean(imu_csv, tmp_path, capsys):
    out = tmp_path / "o"
    code, _, err = _run(["analyze", imu_csv, "--out", out, "--stat", "oadev", "--no-figures", "--no-report",
                         "--axis-rule", "mean", "--quiet"], capsys)
    assert code == 0, err
    text = (out / "imu.yaml").read_text()
    doc = yaml.safe_load(text)
    assert "axes combined: mean of the axes" in text
    data = json.loads((out / "results.json").read_text())
    for group, key in (("gyro", "gyroscope_noise_density"), ("accel", "accelerometer_noise_density")):
        per_axis = [c["model"]["si"]["N"]["value"] for c in data["channels"] if c["group"] == group]
        assert len(per_axis) == 3 and all(v is not None for v in per_axis)
        assert doc[key] == pytest.approx(sum(per_axis) / 3, rel=1e-12), key
        assert doc[key] < max(per_axis)  # not the default rule (largest)


def _timed_csv(path: Path, t, y) -> Path:
    return _write(path, "t,gyro_x\n" + "".join(f"{a:.2f},{float(b)!r}\n" for a, b in zip(t, y)))


def _table(out: str) -> str:
    return out.split("\n", 1)[1]  # without the header line naming the file


@pytest.mark.filterwarnings("default::sigmatau.errors.SigmaTauWarning")  # the CLI prints it
@pytest.mark.parametrize("policy", ["unsorted", "duplicates"])
def test_unsorted_and_duplicates_policies(policy, tmp_path, capsys):
    rng = np.random.default_rng(31)
    t, y = np.arange(3000) / 100.0, rng.standard_normal(3000)
    ref = _timed_csv(tmp_path / "ok.csv", t, y)
    if policy == "unsorted":  # two samples swapped: sorting by time restores the log
        order = np.arange(3000)
        order[[100, 101]] = [101, 100]
        bad = _timed_csv(tmp_path / "bad.csv", t[order], y[order])
        refuse, keep, warned = ["--unsorted", "refuse"], "--unsorted sort", "go backwards"
    else:  # a repeated timestamp after the original with another value: keeping the first restores it
        bad = _timed_csv(tmp_path / "bad.csv", np.insert(t, 201, t[200]), np.insert(y, 201, y[200] + 1.0))
        refuse, keep, warned = ["--duplicates", "refuse"], "--duplicates drop", "repeat the timestamp"
    base = ["stats", "--stat", "oadev,mdev"]
    code, expected, err = _run([base[0], ref, *base[1:]], capsys)
    assert code == 0 and err == "", err
    code, got, err = _run([base[0], bad, *base[1:]], capsys)  # the default policy: repair with a warning
    assert code == 0, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("sigmatau: warning:") and warned in lines[0], err
    assert _table(got) == _table(expected)
    code, _, err = _run([base[0], bad, *base[1:], *refuse], capsys)
    assert code == 1
    _one_line_error(err, "bad.csv", warned, keep)


@pytest.mark.slow
def test_kalibr_from_fewer_than_three_axes_says_so(imu_csv, tmp_path, capsys):
    # Kalibr's values stand for all three axes; a log with two gyro axes must say so (the reader
    # already warns about the column it left out).
    rows = Path(imu_csv).read_text().splitlines()
    header = rows[0].split(",")
    keep = [i for i, name in enumerate(header) if not name.startswith("gyro_z")]
    two = _write(tmp_path / "two_gyros.csv", "".join(",".join(r.split(",")[i] for i in keep) + "\n" for r in rows))
    out = tmp_path / "o"
    code, stdout, err = _run(["analyze", two, "--out", out, "--stat", "oadev", "--no-figures", "--no-report",
                              "--quiet"], capsys)
    assert code == 0, err
    assert "fewer than three axes: gyroscope from 2 of 3 axes (gyro_x, gyro_y)" in stdout
    text = (out / "imu.yaml").read_text()
    assert "fewer than three axes: gyroscope from 2 of 3 axes (gyro_x, gyro_y)" in text
    assert "accelerometer from" not in text


def test_stats_theo1_bias_published_is_the_api_correction(tmp_path, capsys):
    """``--theo1-bias published`` gives sigmatau.theo1(..., bias="published"): Theo1 divided by
    Howe & Tasset's AVAR/Theo1 ratio of the type identified at each τ (raw by default)."""
    x = sigmatau.power_law_noise(4000, 2, data_type="phase", rng=np.random.default_rng(7)) * 1e-9
    path = tmp_path / "wpm.txt"
    np.savetxt(path, x)
    rows = {}
    for bias in ("none", "published"):
        code, out, _ = run_cli(["stats", path, "--data-type", "phase", "--rate", "1", "--stat", "theo1",
                                "--theo1-bias", bias], capsys)
        assert code == 0
        rows[bias] = [ln.split() for ln in out.splitlines() if ln.strip()[:1].isdigit()]
        assert ("corrected for its bias" in out) == (bias == "published")
    for bias, table in rows.items():
        want = sigmatau.theo1(x, rate=1.0, data_type="phase", bias=bias)
        assert [int(r[0]) for r in table] == want.m.tolist()
        np.testing.assert_allclose([float(r[5]) for r in table], want.dev, rtol=5e-5)  # 5 printed digits
    assert float(rows["published"][0][5]) < 0.9 * float(rows["none"][0][5])  # white PM: AVAR < Theo1
    code, _, err = run_cli(["stats", path, "--data-type", "phase", "--rate", "1", "--stat", "theo1",
                            "--theo1-bias", "auto"], capsys)
    assert_one_line_error((code, err), code=2, match="--theo1-bias")


@pytest.mark.parametrize("chunked", [False, True])
def test_stats_header_counts_the_missing_samples(tmp_path, capsys, chunked):
    y = np.random.default_rng(11).normal(size=20_000)
    y[5000:5100] = np.nan
    np.save(tmp_path / "gap.npy", y)
    argv = ["stats", tmp_path / "gap.npy", "--rate", "100", "--stat", "oadev"] + (["--chunked"] if chunked else [])
    code, out, _ = run_cli(argv, capsys)
    assert code == 0
    assert out.splitlines()[0].startswith(f"{tmp_path / 'gap.npy'}: 20,000 samples (100 missing, NaN: gaps) at 100 Hz")
    np.save(tmp_path / "full.npy", np.nan_to_num(y))
    code, out, _ = run_cli(["stats", tmp_path / "full.npy", "--rate", "100", "--stat", "oadev"], capsys)
    assert "missing" not in out.splitlines()[0]
