"""``sigmatau analyze`` out of core: a log that would not fit in memory is read in chunks, automatically.

The whole analysis out of core (``sigmatau.chunked.analyze_file(memory="chunked")``, ``sigmatau
analyze --memory chunked`` or ``--memory-limit``) is held to the in-memory run on the same log:
every statistic's deviation to 1e-12 relative with the same τ, noise types, EDF and ``ci_reason``,
the IMU model's values and the Kalibr entry, for .npz, .npy, HDF5 and text logs, with timestamps,
duplicates, gaps and NaN cells. The decision never depends on this machine's memory: the tests set
the budget (``memory_limit``) or force the mode. Temporary files of text logs are removed after
success, after an error and after SIGTERM.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest

from sigmatau import io
from sigmatau.chunked import analyze_file, memory_plan
from sigmatau.cli import main
from sigmatau.errors import DataError
from sigmatau.imu import simulate

RATE = 200.0
CHUNK = 1000  # a small chunk, so that every pass crosses many chunk boundaries
TERMS = ("Q", "N", "B", "K", "R")


def _imu(seconds: float = 120.0, seed: int = 0, axes: str = "xyz") -> dict[str, np.ndarray]:
    out = {f"gyro_{a}": simulate("euroc-gyro", duration=seconds, rng=seed + i) for i, a in enumerate(axes)}
    out |= {f"accel_{a}": simulate("euroc-accel", duration=seconds, rng=seed + 10 + i) for i, a in enumerate(axes)}
    return out


def _pair(path: Path, **read: object):
    """The analysis of ``path`` in memory and out of core (prep none: the statistics of the samples)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        inside = analyze_file(path, memory="in", read_options=read)
        outside = analyze_file(path, memory="chunked", chunk_size=CHUNK, read_options=read, workdir=path.parent)
    return inside, outside


def _same_result(a, b, what: str) -> None:
    np.testing.assert_array_equal(a.taus, b.taus, err_msg=what)
    np.testing.assert_array_equal(a.m, b.m, err_msg=what)
    np.testing.assert_array_equal(a.n, b.n, err_msg=what)
    np.testing.assert_allclose(b.dev, a.dev, rtol=1e-12, atol=0, err_msg=what)
    np.testing.assert_array_equal(a.alpha, b.alpha, err_msg=what)
    np.testing.assert_allclose(b.edf, a.edf, rtol=1e-12, atol=0, err_msg=what)
    np.testing.assert_allclose(b.ci_low, a.ci_low, rtol=1e-12, atol=0, err_msg=what)
    np.testing.assert_allclose(b.ci_high, a.ci_high, rtol=1e-12, atol=0, err_msg=what)
    assert list(a.ci_reason) == list(b.ci_reason), what
    assert (a.n_missing, a.n_points) == (b.n_missing, b.n_points), what


def _same_analysis(inside, outside) -> None:
    assert [c.name for c in inside.channels] == [c.name for c in outside.channels]
    assert len(inside.log) == len(outside.log) and inside.log.rate == outside.log.rate
    assert outside.notes[0].startswith("analysed out of core")
    assert outside.settings["memory"]["mode"] == "chunked"
    for ci, co in zip(inside.channels, outside.channels):
        assert set(co.results) == set(ci.results) - {"theoh"}, ci.name
        assert "no chunked kernel" in co.skipped["theoh"]
        for stat, r in co.results.items():
            _same_result(ci.results[stat], r, f"{ci.name} {stat}")
        assert (ci.model is None) == (co.model is None), ci.name
        if ci.model is not None:
            for t in TERMS:
                p, q = getattr(ci.model, t), getattr(co.model, t)
                assert p.resolved == q.resolved, (ci.name, t)
                np.testing.assert_allclose([q.value, q.low, q.high], [p.value, p.low, p.high], rtol=1e-9,
                                           err_msg=f"{ci.name} {t}")
            assert ci.model.fit_terms == co.model.fit_terms
    _close(inside.kalibr, outside.kalibr, "kalibr")


def _close(a: object, b: object, where: str) -> None:
    """Equal structures, floats to 1e-9 relative (the fit's round-off of curves equal to ~1e-16)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), where
        for k in a:
            _close(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), where  # type: ignore[arg-type]
        for i, (x, y) in enumerate(zip(a, b)):  # type: ignore[call-overload]
            _close(x, y, f"{where}[{i}]")
    elif isinstance(a, float):
        assert b == pytest.approx(a, rel=1e-9, abs=0), where
    else:
        assert a == b, where


def _left_over(folder: Path) -> list[Path]:
    return sorted(folder.glob(".sigmatau-outofcore-*"))


# ------------------------------------------------------------------- equality, format by format


@pytest.mark.slow
def test_npz_whole_analysis_equals_in_memory(tmp_path):
    f = tmp_path / "imu.npz"
    np.savez(f, rate=np.array(RATE), **_imu(60.0))
    inside, outside = _pair(f)
    _same_analysis(inside, outside)
    assert outside.kalibr is not None
    assert any("data checks of the samples" in n for n in outside.notes)


@pytest.mark.slow
def test_npy_two_dimensional_and_structured(tmp_path):
    chans = _imu(30.0, seed=3)
    f = tmp_path / "block.npy"
    np.save(f, np.column_stack([chans["gyro_x"], chans["gyro_y"]]))
    _same_analysis(*_pair(f, rate=RATE))
    g = tmp_path / "fields.npy"
    rec = np.zeros(chans["gyro_x"].size, dtype=[("t", "<f8"), ("gyro_x", "<f4"), ("accel_z", "<f8")])
    rec["t"] = np.arange(rec.size) / RATE
    rec["gyro_x"], rec["accel_z"] = chans["gyro_x"], chans["accel_z"]
    np.save(g, rec)
    _same_analysis(*_pair(g))
    h = tmp_path / "fortran.npy"
    np.save(h, np.asfortranarray(np.column_stack([chans["accel_x"], chans["accel_y"]])))
    _same_analysis(*_pair(h, rate=RATE))


@pytest.mark.slow
def test_hdf5_group(tmp_path):
    h5py = pytest.importorskip("h5py")
    f = tmp_path / "imu.h5"
    with h5py.File(f, "w") as h:
        g = h.create_group("imu")
        for k, v in _imu(30.0, seed=5, axes="xz").items():
            g.create_dataset(k, data=v, chunks=True)
        g.attrs["rate"] = RATE
    _same_analysis(*_pair(f, dataset="imu"))


def _write_csv(path: Path, t: np.ndarray, cols: dict[str, np.ndarray]) -> None:
    with open(path, "w") as fh:
        fh.write("#timestamp [ns]," + ",".join(cols) + "\n")
        rows = np.column_stack(list(cols.values()))
        for ti, row in zip(t.tolist(), rows.tolist()):
            fh.write(f"{ti}," + ",".join(repr(v) for v in row) + "\n")


@pytest.mark.slow
def test_csv_with_timestamps_duplicates_and_gaps(tmp_path):
    chans = _imu(40.0, seed=7, axes="xy")
    n = chans["gyro_x"].size
    t = 1_403_636_579_758_555_392 + 5_000_000 * np.arange(n)
    keep = np.ones(n, dtype=bool)
    keep[[1000, 1001, 1002]] = False           # a gap of 3: held (gaps="auto")
    keep[5000:5020] = False                    # a gap of 20: NaN
    keep[7001] = False                         # one missing
    t = t[keep]
    cols = {k: v[keep] for k, v in chans.items()}
    dup = 2000
    t = np.insert(t, dup, t[dup - 1])          # a repeated timestamp with other values
    cols = {k: np.insert(v, dup, v[dup] + 1.0) for k, v in cols.items()}
    f = tmp_path / "imu.csv"
    _write_csv(f, t, cols)
    for gaps in ("auto", "mark", "ignore"):
        inside, outside = _pair(f, gaps=gaps)
        _same_analysis(inside, outside)
        a, b = inside.log.timing, outside.log.timing
        assert (a.samples, a.gaps, a.actions, a.duplicates, a.duplicates_differing, a.rate, a.measured_rate) == \
               (b.samples, b.gaps, b.actions, b.duplicates, b.duplicates_differing, b.rate, b.measured_rate)
        assert b.jitter_rms == pytest.approx(a.jitter_rms, rel=1e-12, abs=1e-18)
    assert _left_over(tmp_path) == []


@pytest.mark.slow
def test_csv_with_nan_cells_and_jittery_float_times(tmp_path):
    chans = _imu(30.0, seed=9, axes="xy")
    n = chans["gyro_x"].size
    rng = np.random.default_rng(4)
    t = np.arange(n) / RATE + rng.uniform(-1e-5, 1e-5, n)  # many distinct steps: the radix median
    chans["gyro_y"][[17, 4000, 4001]] = np.nan
    f = tmp_path / "jitter.csv"
    with open(f, "w") as fh:
        fh.write("time," + ",".join(chans) + "\n")
        for i in range(n):
            fh.write(f"{float(t[i])!r}," + ",".join(repr(float(v[i])) for v in chans.values()) + "\n")
    inside, outside = _pair(f)
    _same_analysis(inside, outside)
    assert outside.log.timing.measured_rate == inside.log.timing.measured_rate
    assert outside.channel("gyro_y").results["oadev"].n_missing == 3


def test_stable32_phase_file(tmp_path):
    x = np.cumsum(np.random.default_rng(2).standard_normal(20_000)) * 1e-9
    f = tmp_path / "clock-phase.dat"
    f.write_text("Stable32 phase data\n" + "\n".join(repr(float(v)) for v in x) + "\n")
    _same_analysis(*_pair(f, rate=1.0))


# ------------------------------------------------------------------- the decision and the CLI


def test_decision_follows_the_limit_not_the_machine(tmp_path):
    f = tmp_path / "imu.npz"
    np.savez(f, rate=np.array(RATE), **_imu(30.0))
    small, large = memory_plan(f, memory_limit="64KiB"), memory_plan(f, memory_limit="1TiB")
    assert (small.mode, large.mode) == ("chunked", "in")
    assert small.rows == 6000 and small.columns == 6 and small.needed > 6000 * 6 * 8
    assert "more than the limit" in small.describe()
    assert memory_plan(f, memory="in", memory_limit="1KiB").mode == "in"
    assert memory_plan(f, memory="chunked").mode == "chunked"


@pytest.mark.slow
def test_cli_out_of_core_writes_every_output_and_says_so(tmp_path, capsys):
    f = tmp_path / "imu.npz"
    np.savez(f, rate=np.array(RATE), **_imu(40.0, axes="xy"))
    out = tmp_path / "ooc"
    code = main(["analyze", str(f), "--memory-limit", "100KiB", "--chunk-size", "4096", "--out", str(out),
                 "--figures", "png", "--export", "kalibr,vins"])
    printed = capsys.readouterr()
    assert code == 0, printed.err
    assert "analysed out of core, read in chunks of 4,096 samples" in printed.out
    assert "warm-up: not looked for out of core" in printed.out
    names = {p.name for p in out.iterdir()}
    assert {"results.json", "statistics.csv", "model.csv", "imu.yaml", "vins_imu.yaml", "report.html",
            "sigma_tau_gyro.png", "sigmatau-manifest.json"} <= names
    assert not any(n.startswith("signal_") for n in names)
    data = json.loads((out / "results.json").read_text())
    assert data["settings"]["memory"]["mode"] == "chunked" and data["settings"]["memory"]["limited"]
    assert "signal figures" in data["figures_note"]
    assert "analysed out of core" in (out / "report.html").read_text()
    # the same log in memory: the same Kalibr file (its values printed with every digit agree to 1e-9)
    yaml = pytest.importorskip("yaml")
    inside = tmp_path / "in"
    assert main(["analyze", str(f), "--warmup", "keep", "--memory", "in", "--out", str(inside),
                 "--no-figures", "--no-report"]) == 0
    _close(yaml.safe_load((inside / "imu.yaml").read_text()), yaml.safe_load((out / "imu.yaml").read_text()),
           "imu.yaml")
    assert not any(p.name.startswith(".") for p in tmp_path.iterdir())  # no staging or temporary directory left


@pytest.mark.slow
def test_cli_in_memory_path_is_unchanged(tmp_path, capsys):
    f = tmp_path / "imu.npz"
    np.savez(f, rate=np.array(RATE), **_imu(30.0))
    assert main(["analyze", str(f), "--out", str(tmp_path / "o"), "--no-figures", "--no-report",
                 "--memory-limit", "1TiB"]) == 0
    data = json.loads((tmp_path / "o" / "results.json").read_text())
    assert "memory" not in data["settings"] and not any("out of core" in n for n in data["notes"])
    assert "theoh" in data["channels"][0]["statistics"]


@pytest.mark.parametrize("case, expected", [
    ("compressed", "is compressed (numpy.savez_compressed)"),
    ("split", "out of core the log is not split"),
    ("unsorted", "out of core the samples are not sorted"),
    ("parquet", "parquet logs are not read out of core"),
])
def test_what_is_not_done_out_of_core_is_one_line(tmp_path, capsys, case, expected):
    if case == "compressed":
        f = tmp_path / "z.npz"
        np.savez_compressed(f, gyro_x=np.zeros(1000), rate=np.array(RATE))
    elif case == "parquet":
        pa = pytest.importorskip("pyarrow")
        import pyarrow.parquet as pq

        f = tmp_path / "p.parquet"
        pq.write_table(pa.table({"gyro_x": np.zeros(1000)}), f)
    else:
        t = np.arange(1000) * 5_000_000
        t = np.delete(t, np.arange(300, 320)) if case == "split" else t
        if case == "unsorted":
            t[[500, 501]] = t[[501, 500]]
        f = tmp_path / "t.csv"
        _write_csv(f, t, {"gyro_x": np.zeros(t.size) + np.arange(t.size) % 7})
    extra = ["--gaps", "split"] if case == "split" else []
    code = main(["analyze", str(f), "--memory", "chunked", "--out", str(tmp_path / "o"), "--rate", "200", *extra]
                if case in ("compressed", "parquet") else
                ["analyze", str(f), "--memory", "chunked", "--out", str(tmp_path / "o"), *extra])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1
    # the error is one line (after, when the file was opened, the line announcing the mode)
    assert len(err) <= 2 and all(e.startswith("sigmatau: analysed out of core") for e in err[:-1])
    assert err[-1].startswith("sigmatau: error:") and expected in err[-1]
    assert "--memory in" in err[-1]
    assert not (tmp_path / "o").exists() and _left_over(tmp_path) == []


def test_bad_memory_options_are_usage_errors(tmp_path, capsys):
    f = tmp_path / "imu.npz"
    np.savez(f, gyro_x=np.zeros(100), rate=np.array(RATE))
    assert main(["analyze", str(f), "--memory-limit", "lots"]) == 2
    assert "--memory-limit 'lots'" in capsys.readouterr().err
    assert main(["analyze", str(f), "--memory", "chunked", "--chunk-size", "4"]) == 2
    assert main(["analyze", str(f), "--memory", "sometimes"]) == 2


# ------------------------------------------------------------------- temporary files


def test_temporary_files_removed_after_success_and_error(tmp_path):
    chans = _imu(20.0)
    t = 5_000_000 * np.arange(chans["gyro_x"].size)
    good = tmp_path / "good.csv"
    _write_csv(good, t, chans)
    with io.open_log(good, workdir=tmp_path) as log:
        folder = Path(log.workdir)
        assert folder.parent == tmp_path and folder.is_dir() and oct(folder.stat().st_mode)[-3:] == "700"
        assert log["gyro_x"].read(0, 5).size == 5
    assert not folder.exists()
    with pytest.raises(DataError, match="closed"):
        log["gyro_x"].read(0, 5)
    bad = tmp_path / "bad.csv"
    text = good.read_text().splitlines()
    text[3000] = text[3000].replace(",", ",oops,", 1)
    bad.write_text("\n".join(text) + "\n")
    with pytest.raises(DataError, match="line 3001"):
        io.open_log(bad, workdir=tmp_path)
    assert _left_over(tmp_path) == []


@pytest.mark.slow
@pytest.mark.skipif(sys.platform == "win32", reason="SIGTERM")
def test_temporary_files_removed_after_sigterm(tmp_path):
    n = 400_000
    rng = np.random.default_rng(1)
    f = tmp_path / "long.csv"
    with open(f, "w") as fh:
        fh.write("t,gyro_x,gyro_y\n")
        block = np.column_stack([np.arange(n) * 0.005, rng.standard_normal((n, 2))])
        np.savetxt(fh, block, delimiter=",", fmt="%.9g")
    cmd = [sys.executable, "-m", "sigmatau", "analyze", str(f), "--memory", "chunked", "--chunk-size", "256",
           "--out", str(tmp_path / "o"), "--no-figures", "--quiet"]
    proc = subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not _left_over(tmp_path) and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    assert _left_over(tmp_path), "the temporary directory never appeared"
    time.sleep(0.5)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert "terminated" in err and "Traceback" not in err
    assert _left_over(tmp_path) == []
    assert not (tmp_path / "o").exists()


def test_npz_is_read_in_place(tmp_path):
    f = tmp_path / "big.npz"
    np.savez(f, gyro_x=np.arange(10_000, dtype=np.float32), accel_x=np.arange(10_000.0), rate=np.array(RATE))
    with zipfile.ZipFile(f) as z:
        assert all(i.compress_type == zipfile.ZIP_STORED for i in z.infolist())
    with io.open_log(f) as log:
        assert log.workdir is None  # no copy: the channels are read from the archive's bytes
        np.testing.assert_array_equal(log["gyro_x"].read(9_990, 10_000), np.arange(9_990, 10_000.0))
    size = io.log_size(f)
    assert (size.rows, size.channels, size.time, size.exact) == (10_000, 2, False, True)
