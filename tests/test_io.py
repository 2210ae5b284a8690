"""sigmatau.io: text, Stable32, NumPy, HDF5 and Parquet readers, timing policies, every error path.

Files are written in tmp_path; the real files read are the repository's Stable32
PHASE.DAT (tests/data/allantools) and, when ../shared is present, the ADIS16405
recording (CC BY-NC-SA: read in place, never copied).
"""

from __future__ import annotations

import bz2
import gzip
import hashlib
import io as stdio
import lzma
import os
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from sigmatau import DataError, ParameterError, SigmaTauError, io
from sigmatau.io import FormatError, InputNotFoundError, MissingDependencyError, TimingWarning

REFDATA_IMU = Path(__file__).resolve().parents[2] / "shared" / "refdata" / "imu"
ADIS = REFDATA_IMU / "smac_imudata_adis16405" / "adis_16405_imu1.csv.gz"
IMU_UTILS = REFDATA_IMU / "imu_utils_adev"
PHASE_DAT = Path(__file__).parent / "data" / "allantools" / "phasedat" / "PHASE.DAT"

EUROC_HEADER = ("#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
                "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]")


def _check(exc_info, kind, *patterns):
    """One line, of the expected type, in sigmatau's hierarchy, matching every pattern."""
    exc = exc_info.value
    assert type(exc) is kind, (type(exc), exc)
    assert isinstance(exc, SigmaTauError)
    msg = str(exc)
    assert "\n" not in msg and "\r" not in msg, msg
    for pattern in patterns:
        assert re.search(pattern, msg, flags=re.IGNORECASE), f"{pattern!r} not in {msg!r}"


def _write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def _s(x) -> str:
    return repr(float(x))


def _values(n=50, k=3, seed=0):
    return np.round(np.random.default_rng(seed).standard_normal((n, k)), 6)


def _quiet_read(*args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return io.read(*args, **kw)


# ---------------------------------------------------------------------------------------------
# Delimited text
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("delim", [",", ";", "\t", " ", "   ", "|", ", "])
@pytest.mark.parametrize("header", [True, False])
def test_csv_delimiters_and_header(tmp_path, delim, header):
    v = _values()
    lines = ([delim.join(["gyro_x", "gyro_y", "gyro_z"])] if header else [])
    lines += [delim.join(_s(x) for x in row) for row in v]
    p = _write(tmp_path / "d.txt", "\n".join(lines) + "\n")
    log = _quiet_read(p, rate=100)
    names = ("gyro_x", "gyro_y", "gyro_z") if header else ("col0", "col1", "col2")
    assert log.names == names
    np.testing.assert_array_equal(log.as_array(), v)
    assert log.rate == 100 and log.timing.rate_source == "given" and log.timestamps is None
    assert log.data_type == "freq"


def test_delimiter_given_and_microseconds(tmp_path):
    p = _write(tmp_path / "d.txt", "time_us;gx\n0;1,5\n1000;2\n2000;3\n")  # a comma inside a field
    with pytest.raises(DataError):
        io.read(p)  # detected as ';' then '1,5' is not a number
    p = _write(tmp_path / "e.txt", "time_us:gx\n0:1\n1000:2\n2000:3\n")
    log = _quiet_read(p, delimiter=":")
    assert log.timing.time_unit == "us" and log.rate == pytest.approx(1000)
    assert _quiet_read(p, delimiter=":", time_unit="µs").timing.time_unit_reason == "given"


def test_comments_blank_lines_crlf_and_inline_comments(tmp_path):
    v = _values(20)
    body = ["# logged by rig 3", "% matlab style", "// c style", "", "ax,ay,az"]
    for i, row in enumerate(v):
        line = ",".join(map(_s, row))
        body.append(line + ("  # note" if i == 3 else ""))
        if i == 10:
            body += ["# a comment inside the data", "", "% another"]
    p = tmp_path / "c.csv"
    p.write_bytes(("\r\n".join(body) + "\r\n").encode())
    log = _quiet_read(p, rate=10)
    assert log.names == ("accel_x", "accel_y", "accel_z")
    assert log.groups == {"accel": ("accel_x", "accel_y", "accel_z")}
    np.testing.assert_array_equal(log.as_array(), v)
    assert "header on line 5" in log.source.detail


def test_header_in_comment_line_and_quoted_fields(tmp_path):
    p = _write(tmp_path / "q.csv", '# "t","gx","gy"\n"0.0","1.5","2.5"\n"0.01","1.25","-3"\n"0.02","0","1e-3"\n')
    log = _quiet_read(p)
    assert log.names == ("gyro_x", "gyro_y")
    np.testing.assert_array_equal(log["gyro_y"], [2.5, -3, 1e-3])
    assert log.timing.time_column == "t" and log.timing.time_unit == "s"


def test_euroc_layout(tmp_path):
    n = 1000
    t = 1_403_636_579_758_555_392 + 5_000_000 * np.arange(n, dtype=np.int64)
    v = _values(n, 6)
    rows = [f"{ti}," + ",".join(map(_s, r)) for ti, r in zip(t, v)]
    p = _write(tmp_path / "data.csv", EUROC_HEADER + "\n" + "\n".join(rows) + "\n")
    log = _quiet_read(p)
    assert log.names == ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
    assert log.original_names["gyro_x"] == "w_RS_S_x [rad s^-1]"
    assert dict(log.units) == {**{f"gyro_{a}": "rad/s" for a in "xyz"}, **{f"accel_{a}": "m/s^2" for a in "xyz"}}
    assert set(log.unit_origin.values()) == {"file"}
    assert log.rate == 200.0 and log.timing.rate_source == "timestamps"
    assert log.timing.time_unit == "ns" and "column name" in log.timing.time_unit_reason
    # int64 parsing keeps the nanoseconds: the steps are exact
    np.testing.assert_array_equal(log.timestamps, (t - t[0]) / 1e9)
    assert log.time_origin == pytest.approx(1_403_636_579.758555392, abs=1e-6)
    assert log.timing.jitter_rms == 0.0 and log.timing.gaps == ()
    np.testing.assert_array_equal(log.as_array(), v)
    assert "EuRoC" in log.source.detail


def test_rostopic_echo_csv_picks_header_stamp_and_imu_fields(tmp_path):
    cols = (["%time", "field.header.seq", "field.header.stamp", "field.header.frame_id"]
            + [f"field.orientation.{a}" for a in "xyzw"]
            + [f"field.angular_velocity.{a}" for a in "xyz"]
            + [f"field.linear_acceleration.{a}" for a in "xyz"])
    n = 30
    stamp = 1_600_000_000_000_000_000 + 10_000_000 * np.arange(n)
    rows = []
    for i in range(n):
        vals = [stamp[i] + 777, i, stamp[i], "imu_link", 0, 0, 0, 1, 0.1 * i, 0.2, 0.3, 1.0, 2.0, 9.8]
        rows.append(",".join(map(str, vals)))
    p = _write(tmp_path / "imu.csv", ",".join(cols) + "\n" + "\n".join(rows) + "\n")
    # every column left out is named, with why
    with pytest.warns(io.InputWarning, match=r"imu.csv: 7 columns not used: 'time' \(another time column\),"
                      r" 'field.header.seq' \(not a recognised channel name\), 'field.header.frame_id'"
                      r" \(not numeric\), 'field.orientation.x' .*'field.orientation.w'"):
        log = io.read(p)
    assert log.timing.time_column == "field.header.stamp" and log.timing.time_unit == "ns"
    assert log.names == ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
    assert "left out" in log.source.detail and "field.orientation.w" in log.source.detail
    np.testing.assert_allclose(log["gyro_x"], 0.1 * np.arange(n))
    assert log.rate == 100.0


def test_units_line_under_header_and_adis_style_suffixes(tmp_path):
    p = _write(tmp_path / "u.csv", "time,gx,gy,az\ns,deg/s,deg/s,mg\n0,1,2,3\n0.5,1,2,3\n1.0,1,2,3\n")
    log = _quiet_read(p)
    assert log.units == {"gyro_x": "deg/s", "gyro_y": "deg/s", "accel_z": "mg"}
    assert log.timing.time_unit == "s"
    p2 = _write(tmp_path / "adis.csv", "gyro_x_dps,acc_z_g\n0.05,-1.01\n0.1,-1.02\n0,-1\n")
    log2 = _quiet_read(p2, rate=100)
    assert log2.units == {"gyro_x": "deg/s", "accel_z": "g"}


@pytest.mark.parametrize("opener", [gzip.open, bz2.open, lzma.open])
def test_compressed_text(tmp_path, opener):
    v = _values(100)
    p = tmp_path / "z.csv.gz"
    with opener(p, "wt") as fh:
        fh.write("gyro_x,gyro_y,gyro_z\n" + "\n".join(",".join(map(_s, r)) for r in v) + "\n")
    log = _quiet_read(p, rate=50)
    np.testing.assert_array_equal(log.as_array(), v)
    assert "compressed" in log.source.detail
    assert log.source.sha256 == hashlib.sha256(p.read_bytes()).hexdigest()


def test_chunked_reading_matches_whole(tmp_path, monkeypatch):
    n = 1000
    t = np.arange(n) / 100.0
    v = _values(n, 2)
    text = "t,gyro_x,gyro_y\n" + "\n".join(f"{_s(a)},{_s(b)},{_s(c)}" for a, (b, c) in zip(t, v)) + "\n"
    plain = _write(tmp_path / "p.csv", text)
    packed = tmp_path / "p.csv.gz"
    packed.write_bytes(gzip.compress(text.encode()))
    monkeypatch.setattr("sigmatau.io._text.CHUNK_ROWS", 7)
    for p in (plain, packed):  # the .gz file starts with a small buffer and grows
        log = _quiet_read(p)
        np.testing.assert_array_equal(log.as_array(), v)
        np.testing.assert_allclose(log.timestamps, t - t[0], atol=1e-12)


def test_columns_by_name_index_and_canonical_name(tmp_path):
    p = _write(tmp_path / "s.csv", EUROC_HEADER + "\n" + "\n".join(
        f"{1_000_000_000_000_000_000 + i * 5_000_000},1,2,3,4,5,{i}" for i in range(20)) + "\n")
    assert _quiet_read(p, columns="w_RS_S_y [rad s^-1]").names == ("gyro_y",)
    assert _quiet_read(p, columns=["accel_z", 1]).names == ("accel_z", "gyro_x")
    assert _quiet_read(p, columns="A_RS_S_Z").names == ("accel_z",)
    assert _quiet_read(p, columns=-1).names == ("accel_z",)
    log = _quiet_read(p, columns=[0, 6], time_column=False, rate=200)
    assert log.names == ("timestamp [ns]", "accel_z") and log.timestamps is None


def test_time_unit_inference(tmp_path):
    def make(name, times):
        text = "t,gyro_x\n" + "\n".join(f"{x},{i}" for i, x in enumerate(times)) + "\n"
        return _write(tmp_path / f"{name}.csv", text)

    log = _quiet_read(make("s", [f"{0.005 * i:.3f}" for i in range(50)]))
    assert log.timing.time_unit == "s" and log.rate == pytest.approx(200)
    assert "only if in s" in log.timing.time_unit_reason
    log = _quiet_read(make("ms_epoch", [1_700_000_000_000 + 10 * i for i in range(50)]))
    assert log.timing.time_unit == "ms" and "Unix time" in log.timing.time_unit_reason
    assert log.rate == pytest.approx(100)
    ambiguous = make("amb", [10 * i for i in range(50)])
    with pytest.raises(DataError) as e:
        io.read(ambiguous)
    _check(e, DataError, r"cannot tell the unit of time column 't'", r"0\.1 Hz if s", r"100 Hz if ms", "time_unit=")
    assert _quiet_read(ambiguous, time_unit="ms").rate == pytest.approx(100)


def test_mjd_time_tags_stable32(tmp_path):
    mjd = 59000 + np.arange(100) / 86400.0
    v = np.random.default_rng(1).standard_normal(100) * 1e-9
    p = _write(tmp_path / "clock_phase.dat", "Stable32 phase data\n" + "\n".join(
        f"{_s(a)} {_s(b)}" for a, b in zip(mjd, v)) + "\n")
    log = _quiet_read(p)
    assert log.source.format == "stable32" and log.data_type == "phase" and log.names == ("phase",)
    assert log.units == {"phase": "s"} and log.rate == pytest.approx(1.0, rel=1e-6)
    assert log.timing.time_unit == "d" and "MJD" in log.timing.time_unit_reason
    np.testing.assert_array_equal(log["phase"], v)


@pytest.mark.parametrize("relpath, data_type, oracle", [
    ("gps/gps_1pps_phase_data.txt.gz", "phase", "gps_phase"),
    ("ocxo/ocxo_frequency.txt", "freq", None),
    ("Keysight53230A_ti_noise_floor/tic_phase.txt", "phase", "tic_phase"),
    ("pink_frequency/pink_frequency.txt", "freq", "pink_frequency"),
])
def test_real_clock_data_files(relpath, data_type, oracle):
    """Real clock data in the repository: data type from the header or name, values as the helpers read them."""
    import refdata

    log = _quiet_read(PHASE_DAT.parents[1] / relpath, rate=1.0)
    assert log.source.format == "stable32" and log.data_type == data_type and log.names == (data_type,)
    expected = getattr(refdata, oracle)() if oracle else refdata.ocxo_frequency() * 1e7 + 1e7
    values = log[data_type][: expected.size]
    if oracle:
        np.testing.assert_array_equal(values, expected)
    else:  # the helper normalises to fractional frequency
        np.testing.assert_allclose(values, expected, rtol=1e-15)


def test_stable32_phase_dat_real_file():
    log = _quiet_read(PHASE_DAT, rate=1.0)
    assert log.source.format == "stable32" and log.data_type == "phase"
    assert len(log) == 1001 and log.names == ("phase",) and log.groups == {"phase": ("phase",)}
    assert log["phase"][1] == pytest.approx(8.511601033439709e-02, rel=0, abs=0)
    # same numbers as the test helper that reads it line by line
    from refdata import phase_dat
    np.testing.assert_array_equal(log["phase"], phase_dat())


def test_stable32_data_type_from_header_or_argument(tmp_path):
    freq = _write(tmp_path / "a.txt", "# fractional frequency data\n" + "\n".join(["1e-12", "2e-12", "3e-12"]) + "\n")
    assert _quiet_read(freq, rate=1).data_type == "freq"
    plain = _write(tmp_path / "b.txt", "1\n2\n3\n4\n")
    with pytest.raises(ParameterError) as e:
        io.read(plain, rate=1)
    _check(e, ParameterError, "b.txt", "phase or frequency", "data_type=")
    log = _quiet_read(plain, rate=1, data_type="phase")
    assert log.data_type == "phase" and log.names == ("phase",)
    # forcing the csv reader keeps the generic name and "freq"
    assert _quiet_read(plain, rate=1, format="csv").names == ("col0",)


# ---------------------------------------------------------------------------------------------
# NumPy, HDF5, Parquet
# ---------------------------------------------------------------------------------------------

def test_npy_1d_2d_and_structured(tmp_path):
    v = _values(40, 3)
    np.save(tmp_path / "one.npy", v[:, 0])
    np.save(tmp_path / "two.npy", v.astype(np.float32))
    log = _quiet_read(tmp_path / "one.npy", rate=10)
    assert log.names == ("col0",) and log.source.format == "npy"
    np.testing.assert_array_equal(log["col0"], v[:, 0])
    log = _quiet_read(tmp_path / "two.npy", rate=10, columns=[2, 0])
    np.testing.assert_array_equal(log.as_array(), v[:, [2, 0]].astype(np.float32).astype(np.float64))
    rec = np.zeros(40, dtype=[("time", "f8"), ("gyro_z", "f4"), ("accel_x", "f8")])
    rec["time"] = np.arange(40) * 0.002
    rec["gyro_z"], rec["accel_x"] = v[:, 0], v[:, 1]
    np.save(tmp_path / "rec.npy", rec)
    log = _quiet_read(tmp_path / "rec.npy")
    assert log.names == ("gyro_z", "accel_x") and log.rate == pytest.approx(500)


def test_npz_with_rate_time_and_2d_member(tmp_path):
    v = _values(60, 3)
    np.savez(tmp_path / "a.npz", gyro=v, temp=np.full(60, 25.0), rate=np.float64(200.0), other=np.arange(3))
    with pytest.warns(io.InputWarning, match=r"1 column not used: 'other \(3,\)' \(not of the common length 60\)"):
        log = io.read(tmp_path / "a.npz")
    assert log.names == ("gyro_x", "gyro_y", "gyro_z", "temperature")
    assert log.rate == 200.0 and log.timing.rate_source == "file"
    assert "other (3,)" in log.source.detail
    np.testing.assert_array_equal(log.as_array(["gyro_x", "gyro_y", "gyro_z"]), v)
    np.savez_compressed(tmp_path / "b.npz", t=np.arange(60) * 0.01, accel_z=v[:, 2])
    log = _quiet_read(tmp_path / "b.npz")
    assert log.names == ("accel_z",) and log.rate == pytest.approx(100)


def test_npy_refuses_pickles_and_corruption(tmp_path):
    np.save(tmp_path / "obj.npy", np.array([{"a": 1}, None], dtype=object), allow_pickle=True)
    with pytest.raises(FormatError) as e:
        io.read(tmp_path / "obj.npy", rate=1)
    _check(e, FormatError, "obj.npy", "Python objects")
    bad = tmp_path / "bad.npy"
    bad.write_bytes(b"\x93NUMPY\x01\x00garbage")
    with pytest.raises(FormatError) as e:
        io.read(bad, rate=1)
    _check(e, FormatError, "bad.npy", "not a valid .npy")
    (tmp_path / "bad.npz").write_bytes(b"PK\x03\x04 not really a zip")
    with pytest.raises(FormatError) as e:
        io.read(tmp_path / "bad.npz", rate=1)
    _check(e, FormatError, "bad.npz", "not a valid .npz")


def test_hdf5_dataset_and_group(tmp_path):
    h5py = pytest.importorskip("h5py")
    v = _values(80, 6)
    p = tmp_path / "log.h5"
    with h5py.File(p, "w") as f:
        ds = f.create_dataset("raw/table", data=v)
        ds.attrs["columns"] = ["gx", "gy", "gz", "ax", "ay", "az"]
        ds.attrs["units"] = ["deg/s"] * 3 + ["g"] * 3
        g = f.create_group("imu")
        g["time"] = 1_700_000_000 + np.arange(80) * 0.01
        g["gyro"] = v[:, :3]
        g["gyro"].attrs["units"] = "rad/s"
        g["accel_z"] = v[:, 5]
        g.attrs["rate"] = 100.0
    log = _quiet_read(p, dataset="raw/table", rate=50)
    assert log.names == ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
    assert log.units["gyro_x"] == "deg/s" and log.units["accel_z"] == "g"
    np.testing.assert_array_equal(log.as_array(), v)
    log = _quiet_read(p, dataset="/imu")
    assert log.names == ("accel_z", "gyro_x", "gyro_y", "gyro_z")  # HDF5 lists members by name
    assert log.timing.time_unit == "s" and log.rate == 100.0 and log.timing.rate_source == "file"
    assert log.source.detail == "group /imu, 80 rows"  # named while the file is open (was "group None")
    with pytest.raises(ParameterError) as e:
        io.read(p, dataset="nope")
    _check(e, ParameterError, "no dataset or group 'nope'", r"/imu/gyro \(80, 3\)", r"/raw/table")
    with pytest.raises(FormatError) as e:
        io.read(p)
    _check(e, FormatError, "cannot tell which dataset", "dataset=")


def test_parquet(tmp_path):
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    n = 500
    t = (1_700_000_000_000_000_000 + 4_000_000 * np.arange(n)).astype("datetime64[ns]")
    v = _values(n, 2)
    table = pa.table({"stamp": pa.array(t), "gyro_z": v[:, 0], "accel_z": v[:, 1], "label": ["x"] * n})
    table = table.replace_schema_metadata({"rate": "250"})
    p = tmp_path / "log.parquet"
    pq.write_table(table, p, row_group_size=128)
    with pytest.warns(io.InputWarning, match=r"1 column not used: 'label' \(not numeric\)"):
        log = io.read(p)
    assert log.names == ("gyro_z", "accel_z") and log.rate == 250.0
    assert log.timing.time_unit == "ns" and log.timing.measured_rate == pytest.approx(250)
    np.testing.assert_array_equal(log.as_array(), v)
    with pytest.raises(DataError) as e:
        io.read(p, columns="label")
    _check(e, DataError, "column 'label' is not numeric")
    with pytest.raises(ParameterError) as e:
        io.read(p, columns="gyro_q")
    _check(e, ParameterError, "no column 'gyro_q'", "'stamp', 'gyro_z', 'accel_z', 'label'")
    bad = tmp_path / "bad.parquet"
    bad.write_bytes(b"PAR1" + b"\x00" * 64)
    with pytest.raises(FormatError) as e:
        io.read(bad)
    _check(e, FormatError, "bad.parquet", "not a readable Parquet")


@pytest.mark.parametrize("module, extra, suffix", [("h5py", "hdf5", ".h5"), ("pyarrow", "parquet", ".parquet"),
                                                    ("rosbags", "ros", ".bag")])
def test_missing_optional_dependency_names_the_extra(tmp_path, monkeypatch, module, extra, suffix):
    p = tmp_path / f"x{suffix}"
    p.write_bytes(b"whatever content")
    monkeypatch.setitem(sys.modules, module, None)  # import now fails
    with pytest.raises(MissingDependencyError) as e:
        io.read(p)
    _check(e, MissingDependencyError, module, rf"pip install 'sigmatau\[{extra}\]'")
    assert isinstance(e.value, ImportError)


# ---------------------------------------------------------------------------------------------
# Timing: jitter, gaps, duplicates, disorder and the policies
# ---------------------------------------------------------------------------------------------

def _timed(tmp_path, t, name="t.csv", values=None):
    values = np.arange(len(t), dtype=float) if values is None else values
    return _write(tmp_path / name, "time_s,gyro_x\n" + "\n".join(f"{_s(a)},{_s(b)}" for a, b in zip(t, values)) + "\n")


def test_jitter_is_measured(tmp_path):
    rng = np.random.default_rng(3)
    t = 1000 + np.arange(5000) * 0.01 + rng.normal(0, 1e-4, 5000)
    log = _quiet_read(_timed(tmp_path, t))
    assert log.timing.measured_rate == pytest.approx(100, rel=1e-3)
    # steps are differences of independent errors: their rms is sqrt(2) × 1e-4
    assert log.timing.jitter_rms == pytest.approx(np.sqrt(2) * 1e-4, rel=0.05)
    assert log.timing.jitter_max < 1e-3 and not log.timing.gaps
    assert "jitter: rms" in log.timing.summary()


def test_gap_marked_by_default_and_refused_on_request(tmp_path):
    t = np.concatenate([np.arange(300) * 0.01, 3.5 + np.arange(200) * 0.01])
    p = _timed(tmp_path, t)
    # 50 of 550 samples missing (9.1 %): placed on the grid as NaN gaps
    log = io.read(p)
    assert len(log) == 550 and log.timing.gaps_policy == "mark"
    x = log["gyro_x"]
    assert np.isnan(x[300:350]).all() and not np.isnan(x[:300]).any() and not np.isnan(x[350:]).any()
    np.testing.assert_array_equal(x[350:], np.arange(300, 500))
    np.testing.assert_allclose(np.diff(log.timestamps), 0.01, atol=1e-9)
    g = log.timing.gaps[0]
    assert (g.index, g.missing) == (350, 50)
    assert "50 samples missing (9.09 % of the 550)" in log.timing.summary()
    assert [len(s) for s in log.segments()] == [300, 200]
    with pytest.raises(DataError) as e:
        io.read(p, gaps="refuse")
    _check(e, DataError, "t.csv", r"1 gap\(s\)", r"0\.51 s after 2\.99 s", "before sample 300",
           "50 samples missing", r"--gaps mark \(gaps='mark' in Python\)", r"--gaps split \(gaps='split' in Python\)",
           r"--gaps ignore \(gaps='ignore' in Python\)")


def test_gaps_beyond_the_share_are_refused_and_short_ones_held(tmp_path):
    t = np.concatenate([np.arange(300) * 0.01, 5.0 + np.arange(200) * 0.01])
    with pytest.raises(DataError) as e:
        io.read(_timed(tmp_path, t))
    _check(e, DataError, "200 samples missing", r"28\.6 % of the samples", "up to 10 %",
           r"--gaps mark \(gaps='mark' in Python\)")
    assert len(_quiet_read(_timed(tmp_path, t), gaps="mark")) == 700
    # gaps of at most AUTO_HOLD_SAMPLES samples hold the sample before them; longer ones are NaN
    t = np.delete(np.arange(400) * 0.01, [10, 11, 100, 101, 102, 103, 104, 105])
    log = io.read(_timed(tmp_path, t, values=np.arange(t.size, dtype=float)))
    x = log["gyro_x"]
    assert len(log) == 400 and x[10] == x[11] == x[9] == 9.0 and np.isnan(x[100:106]).all()
    assert [(g.index, g.missing) for g in log.timing.gaps] == [(106, 6)]
    assert any("held the sample before each of 1 gap(s)" in a for a in log.timing.actions)
    marked = _quiet_read(_timed(tmp_path, t, values=np.arange(t.size, dtype=float)), gaps="mark")
    assert np.isnan(marked["gyro_x"][10:12]).all() and len(marked.timing.gaps) == 2


def test_gap_split_and_ignore(tmp_path):
    t = np.concatenate([np.arange(300) * 0.01, 3.5 + np.arange(200) * 0.01, 6 + np.arange(1) * 0.01])
    p = _timed(tmp_path, t)
    log = _quiet_read(p, gaps="split")
    assert len(log) == 501 and len(log.timing.gaps) == 2 and log.timing.gaps_policy == "split"
    g = log.timing.gaps[0]
    assert (g.index, g.missing) == (300, 50) and g.duration == pytest.approx(0.51)
    segs = log.segments()
    assert [len(s) for s in segs] == [300, 200]  # the 1-sample run is dropped
    np.testing.assert_array_equal(segs[1]["gyro_x"], np.arange(300, 500))
    assert segs[1].timestamps[0] == 0 and segs[1].time_origin == pytest.approx(3.5)
    assert segs[1].timing.gaps == () and segs[1].timing.samples == 200
    assert [len(s) for s in log.segments(min_samples=1)] == [300, 200, 1]
    ignored = _quiet_read(p, gaps="ignore")
    assert len(ignored) == 501 and ignored.timing.gaps_policy == "ignore"
    assert any("ignored 2 gap" in a for a in ignored.timing.actions)
    # a wider threshold tolerates the steps
    assert _quiet_read(p, gap_threshold=100).timing.gaps == ()


def test_out_of_order_sorted_with_warning_or_refused(tmp_path):
    t = np.arange(100) * 0.01
    t[[40, 41]] = t[[41, 40]]
    v = np.arange(100.0)
    v[[40, 41]] = v[[41, 40]]
    p = _timed(tmp_path, t, values=v)
    with pytest.warns(TimingWarning, match=r"1 timestamp\(s\) go backwards .*sample 41.*sorted"):
        log = io.read(p)
    np.testing.assert_array_equal(log["gyro_x"], np.arange(100.0))
    assert log.timing.out_of_order == 1 and log.timing.unsorted_policy == "sort"
    with pytest.raises(DataError) as e:
        io.read(p, unsorted="refuse")
    _check(e, DataError, r"go backwards \(first at sample 41", "unsorted='sort'")


def test_duplicates_dropped_with_warning_or_refused(tmp_path):
    t = np.arange(100) * 0.01
    t = np.insert(t, [10, 10, 50], [t[9], t[9], t[49]])  # two repeats of t[9], one of t[49]
    v = np.arange(t.size, dtype=float)
    v[10] = v[9]  # a true duplicate; the other two carry other values
    p = _timed(tmp_path, t, values=v)
    with pytest.warns(TimingWarning, match=r"3 sample\(s\) repeat .*2 with different values"):
        log = io.read(p)
    assert len(log) == 100 and log.timing.duplicates == 3 and log.timing.duplicates_differing == 2
    assert log["gyro_x"][9] == 9 and log.timing.rows == 103
    with pytest.raises(DataError) as e:
        io.read(p, duplicates="refuse")
    _check(e, DataError, r"3 sample\(s\) repeat", "duplicates='drop'")


def test_given_rate_disagreeing_with_timestamps_warns(tmp_path):
    p = _timed(tmp_path, np.arange(100) * 0.01)
    with pytest.warns(TimingWarning, match=r"given rate 200 Hz differs from the 100 Hz measured"):
        log = io.read(p, rate=200)
    assert log.rate == 200 and log.timing.rate_source == "given" and log.timing.measured_rate == pytest.approx(100)
    assert _quiet_read(p, rate=100.2).rate == 100.2  # within 1 %: silent


# ---------------------------------------------------------------------------------------------
# Units
# ---------------------------------------------------------------------------------------------

def test_declared_default_and_conflicting_units(tmp_path):
    p = _write(tmp_path / "u.csv", "gx,gy,ax,temp\n" + "1,2,1,25\n" * 5)
    log = _quiet_read(p, rate=10)
    assert log.units == {"gyro_x": "rad/s", "gyro_y": "rad/s", "accel_x": "m/s^2", "temperature": ""}
    assert log.unit_origin["gyro_x"] == "default"
    log = _quiet_read(p, rate=10, units={"gyro": "°/s", "accel": "mg", "gyro_y": "deg/h", "temperature": "degC"})
    assert log.units == {"gyro_x": "deg/s", "gyro_y": "deg/h", "accel_x": "mg", "temperature": "degC"}
    assert set(log.unit_origin.values()) == {"declared"}
    si = log.to_si()
    assert si["gyro_x"][0] == pytest.approx(np.pi / 180) and si["accel_x"][0] == pytest.approx(9.80665e-3)
    assert si.units["gyro_y"] == "rad/s" and si["temperature"][0] == 25
    euroc = _write(tmp_path / "e.csv", "w_RS_S_x [rad s^-1]\n1\n2\n3\n")
    with pytest.warns(io.InputWarning, match=r"in rad/s according to the file; using the declared deg/s"):
        io.read(euroc, rate=1, units={"gyro": "deg/s"})
    with pytest.raises(ParameterError) as e:
        io.read(p, rate=10, units={"gyro": "furlongs"})
    _check(e, ParameterError, r"units\['gyro'\]='furlongs' \(--gyro-unit furlongs\) is not a gyro unit",
           "rad/s, mrad/s, deg/s")
    with pytest.raises(ParameterError) as e:
        io.read(p, rate=10, units={"mag": "uT"})
    _check(e, ParameterError, "units key 'mag'", "gyro, accel, temperature", "gyro_x")


# ---------------------------------------------------------------------------------------------
# SensorLog, progress, input untouched, registry
# ---------------------------------------------------------------------------------------------

def test_sensorlog_api(tmp_path):
    p = _write(tmp_path / "a.csv", "t,gx,gy,gz,ax\n" + "".join(f"{i * 0.01},{i},1,2,3\n" for i in range(10)))
    log = _quiet_read(p)
    assert "SensorLog(csv" in repr(log) and "gyro[rad/s]: gyro_x, gyro_y, gyro_z" in repr(log)
    assert len(log) == 10 and "gyro_x" in log and log.group_of("accel_x") == "accel"
    with pytest.raises(ValueError):
        log["gyro_x"][0] = 5.0  # read-only
    with pytest.raises(ParameterError) as e:
        log["nope"]
    _check(e, ParameterError, "no channel 'nope'", "gyro_x, gyro_y")
    sub = log.select(["accel_x", "gyro_y"])
    assert sub.names == ("accel_x", "gyro_y") and sub.groups == {"gyro": ("gyro_y",), "accel": ("accel_x",)}
    d = log.to_dict()
    assert d["timing"]["rate"] == pytest.approx(100) and d["source"]["format"] == "csv"
    assert d["n_samples"] == 10 and d["units"]["gyro_x"] == "rad/s"
    import json

    assert json.loads(json.dumps(d))["timing"]["time_column"] == "t"


def test_progress_bar_only_when_asked_or_on_a_terminal(tmp_path, monkeypatch):
    p = _write(tmp_path / "big.csv", "gyro_x\n" + "1.0\n" * 3000)
    monkeypatch.setattr("sigmatau.io._text.CHUNK_ROWS", 100)
    monkeypatch.setattr(io._progress.Progress, "DELAY", 0.0)
    ticks = iter(np.arange(1e6) * 10.0)  # every update is 10 s after the previous one
    monkeypatch.setattr(io._progress.Progress, "clock", staticmethod(lambda: float(next(ticks))))
    err = stdio.StringIO()
    monkeypatch.setattr(sys, "stderr", err)
    io.read(p, rate=1)  # StringIO is not a terminal: quiet
    assert err.getvalue() == ""
    io.read(p, rate=1, progress=False)
    assert err.getvalue() == ""
    io.read(p, rate=1, progress=True)
    out = err.getvalue()
    assert "sigmatau: reading big.csv [" in out and "%" in out and out.endswith("\r")


def test_input_file_is_never_modified(tmp_path):
    p = _write(tmp_path / "keep.csv", "t,gyro_x\n" + "".join(f"{i * 0.01},{i}\n" for i in range(50)))
    os.chmod(p, 0o444)
    before = (p.read_bytes(), p.stat().st_mtime_ns)
    log = _quiet_read(p)
    assert (p.read_bytes(), p.stat().st_mtime_ns) == before
    assert log.source.sha256 == hashlib.sha256(before[0]).hexdigest() and log.source.size == len(before[0])
    assert sorted(x.name for x in tmp_path.iterdir()) == ["keep.csv"]


def test_formats_and_detection(tmp_path):
    assert set(io.formats()) == {"csv", "stable32", "npy", "npz", "rosbag1", "rosbag2", "hdf5", "parquet"}
    np.save(tmp_path / "noext", np.zeros(3))
    assert io.detect_format(tmp_path / "noext.npy") == "npy"
    (tmp_path / "x").write_bytes((tmp_path / "noext.npy").read_bytes())
    assert io.detect_format(tmp_path / "x") == "npy"  # by content
    assert io.detect_format(_write(tmp_path / "y.weird", "1\n2\n")) == "csv"


def test_importing_io_loads_no_optional_backend():
    code = ("import sys, sigmatau.io; "
            "print(','.join(m for m in ('rosbags', 'h5py', 'pyarrow', 'pandas') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


# ---------------------------------------------------------------------------------------------
# Every error path: one line naming the file and the problem
# ---------------------------------------------------------------------------------------------

def test_missing_file(tmp_path):
    with pytest.raises(InputNotFoundError) as e:
        io.read(tmp_path / "nope.csv")
    _check(e, InputNotFoundError, "nope.csv", "no such file")
    assert isinstance(e.value, FileNotFoundError) and isinstance(e.value, DataError)


def test_empty_and_comment_only_and_header_only_files(tmp_path):
    (tmp_path / "empty.csv").write_bytes(b"")
    with pytest.raises(DataError) as e:
        io.read(tmp_path / "empty.csv")
    _check(e, DataError, "empty.csv", "the file is empty")
    with pytest.raises(DataError) as e:
        io.read(_write(tmp_path / "c.csv", "# only\n# comments\n\n"))
    _check(e, DataError, "c.csv", "no numeric data", "only comments")
    with pytest.raises(DataError) as e:
        io.read(_write(tmp_path / "h.csv", "time,gyro_x,gyro_y\n"))
    _check(e, DataError, "h.csv", "no numeric data")
    with pytest.raises(DataError) as e:
        io.read(_write(tmp_path / "words.csv", "a,b\nx,y\nz,w\n"))
    _check(e, DataError, "words.csv", "no numeric data")


def test_binary_garbage(tmp_path):
    junk = np.random.default_rng(0).integers(0, 256, 4096, dtype=np.uint8).tobytes()
    (tmp_path / "junk.bin").write_bytes(junk)
    with pytest.raises(FormatError) as e:
        io.read(tmp_path / "junk.bin")
    _check(e, FormatError, "junk.bin", "unrecognised format", "binary", "csv, stable32")
    (tmp_path / "junk.csv").write_bytes(junk)
    with pytest.raises(FormatError) as e:
        io.read(tmp_path / "junk.csv")
    _check(e, FormatError, "junk.csv", "not a text file")
    (tmp_path / "junk.csv.gz").write_bytes(b"\x1f\x8b" + junk)
    with pytest.raises(FormatError) as e:
        io.read(tmp_path / "junk.csv.gz")
    _check(e, FormatError, "junk.csv.gz", "cannot read the gzip data")


def test_wrong_column_lists_the_columns(tmp_path):
    p = _write(tmp_path / "a.csv", "time,gx,gy,status\n0,1,2,OK\n0.1,1,2,OK\n0.2,1,2,OK\n")
    with pytest.raises(ParameterError) as e:
        io.read(p, columns="gyro_q")
    _check(e, ParameterError, "a.csv", "no column 'gyro_q'", "'time', 'gx', 'gy', 'status'")
    with pytest.raises(ParameterError) as e:
        io.read(p, columns=7)
    _check(e, ParameterError, "index 7 is out of range", "4 columns")
    with pytest.raises(ParameterError) as e:
        io.read(p, time_column="clock")
    _check(e, ParameterError, "no column 'clock'", "'time'")
    with pytest.raises(ParameterError) as e:
        io.read(p, columns=["time"])
    _check(e, ParameterError, "'time' is the time column")
    with pytest.raises(ParameterError) as e:
        io.read(p, columns=["gx", 1])
    _check(e, ParameterError, "'gx' is selected twice")


def test_non_numeric_column_and_values(tmp_path):
    p = _write(tmp_path / "a.csv", "time,gx,status\n0,1,OK\n0.1,1,OK\n0.2,1,OK\n")
    with pytest.raises(DataError) as e:
        io.read(p, columns="status")
    _check(e, DataError, "column 'status' is not numeric", "'OK'")
    mid = _write(tmp_path / "b.csv", "t,gx\n" + "".join(f"{i * 0.01},1\n" for i in range(10)) + "0.1,oops\n0.11,1\n")
    with pytest.raises(DataError) as e:
        io.read(mid)
    _check(e, DataError, "b.csv", "line 12", "'oops' in column 'gx' is not a number")
    first = _write(tmp_path / "g.csv", "t,gx,gy\n0,oops,1\n" + "".join(f"{i * 0.01},1,2\n" for i in range(1, 10)))
    with pytest.raises(DataError) as e:
        io.read(first)
    _check(e, DataError, "g.csv", "line 2: 'oops' in column 'gx' is not a number")
    fields = _write(tmp_path / "c.txt", "1 2 3\n" * 30 + "1 2\n" + "1 2 3\n" * 3)
    with pytest.raises(DataError) as e:
        io.read(fields, rate=1)
    _check(e, DataError, "c.txt", "line 31 has 2 fields, expected 3")
    empty_field = _write(tmp_path / "d.csv", "gx,gy\n1,2\n3,\n5,6\n" + "1,2\n" * 20)
    with pytest.raises(DataError) as e:
        io.read(empty_field, rate=1)
    _check(e, DataError, "line 3: an empty field in column 'gy'")
    comma = _write(tmp_path / "e.csv", "1,5;2,5\n" * 10)
    with pytest.raises(FormatError) as e:
        io.read(comma, rate=1)
    _check(e, FormatError, "decimal commas", "'1,5'")
    ragged = _write(tmp_path / "f.txt", "a: 1\nb: 2 3\nc: 4 5 6\n")
    with pytest.raises(FormatError) as e:
        io.read(ragged, rate=1)
    _check(e, FormatError, "f.txt", "not a table of numbers")


def test_nan_values(tmp_path):
    # NaN cells are missing samples (gaps): kept by default up to 10 % of a column, refused beyond
    # and under gaps='refuse'; inf is always refused (unless allow_nan)
    p = _write(tmp_path / "n.csv", "gx,gy\n" + "1,2\n" * 10 + "nan,2\n" + "3,4\n" * 9)
    log = io.read(p, rate=1)
    assert np.isnan(log["gyro_x"][10]) and np.isnan(log["gyro_x"]).sum() == 1
    assert any("kept 1 NaN value(s)" in a for a in log.timing.actions)
    with pytest.raises(DataError) as e:
        io.read(p, rate=1, gaps="refuse")
    _check(e, DataError, "column 'gx' \\(gyro_x\\) holds 1 NaN", "sample 10", "gaps='refuse'",
           r"--gaps mark \(gaps='mark' in Python\)")
    many = _write(tmp_path / "m.csv", "gx,gy\n1,2\nnan,2\n3,4\n")
    with pytest.raises(DataError) as e:
        io.read(many, rate=1)
    _check(e, DataError, "holds 1 NaN", "33.3 % of the column")
    assert np.isnan(io.read(many, rate=1, gaps="mark")["gyro_x"][1])
    inf = _write(tmp_path / "i.csv", "gx,gy\n1,2\ninf,2\n3,4\n")
    with pytest.raises(DataError) as e:
        io.read(inf, rate=1, gaps="mark")
    _check(e, DataError, "holds 1 infinite value", "sample 1")
    assert np.isinf(_quiet_read(inf, rate=1, allow_nan=True)["gyro_x"][1])
    t = _write(tmp_path / "t.csv", "t,gx\n0,1\nnan,1\n0.2,1\n")
    with pytest.raises(DataError) as e:
        io.read(t)
    _check(e, DataError, "time column 't' holds 1 non-finite")


def test_too_few_samples_and_equal_timestamps(tmp_path):
    with pytest.raises(DataError) as e:
        io.read(_write(tmp_path / "two.csv", "gx\n1\n2\n"), rate=10)
    _check(e, DataError, "two.csv", "only 2 sample", "at least 3")
    with pytest.raises(DataError) as e:
        io.read(_write(tmp_path / "eq.csv", "t,gx\n5,1\n5,2\n5,3\n"))
    _check(e, DataError, "eq.csv", "all 3 timestamps in 't' are equal")


@pytest.mark.parametrize("rate", [0, -100, float("nan"), float("inf"), "100", True])
def test_bad_rate(tmp_path, rate):
    p = _write(tmp_path / "a.csv", "gx\n1\n2\n3\n")
    with pytest.raises(ParameterError) as e:
        io.read(p, rate=rate)
    _check(e, ParameterError, "rate=", "positive")


def test_no_time_column_and_no_rate(tmp_path):
    p = _write(tmp_path / "a.csv", "gx,gy\n1,2\n3,4\n5,6\n")
    with pytest.raises(ParameterError) as e:
        io.read(p)
    _check(e, ParameterError, "a.csv", "no time column and no rate", r"--rate HZ \(rate= in Python\)",
           "--time-column NAME", "'gx', 'gy'")
    with pytest.raises(ParameterError) as e:
        io.read(p, rate=1, time_unit="ms")
    _check(e, ParameterError, "a.csv", r"time_unit='ms' \(--time-unit\) given but", "no time column")


@pytest.mark.parametrize("kw, pattern", [
    ({"format": "xls"}, r"format='xls' is not a known format; formats are: csv"),
    ({"gaps": "fill"}, r"gaps='fill' must be one of \('auto', 'mark', 'refuse', 'split', 'ignore'\)"),
    ({"unsorted": "keep"}, r"unsorted='keep' must be one of"),
    ({"duplicates": "mean"}, r"duplicates='mean' must be one of"),
    ({"stamps": "sensor"}, r"stamps='sensor' must be one of"),
    ({"time_unit": "fortnight"}, r"time_unit='fortnight' must be one of"),
    ({"data_type": "rate"}, r"data_type='rate' must be one of"),
    ({"gap_threshold": 1}, r"gap_threshold=1 must be a number > 1"),
    ({"delimiter": "ab"}, r"delimiter='ab' \(--delimiter\) must be one character"),
    ({"units": ["deg/s"]}, r"units=\['deg/s'\] must map"),
    ({"topic": "/imu"}, r"topic= \(--topic\) applies to rosbag1 and rosbag2 files only; .* is read as csv"),
    ({"dataset": "/x"}, r"dataset= \(--dataset\) applies to hdf5 files only"),
    ({"time_column": True}, r"time_column=True is not a column"),
    ({"progress": "yes"}, r"progress='yes' must be"),
    ({"allow_nan": 1}, r"allow_nan=1 must be True or False"),
])
def test_bad_arguments(tmp_path, kw, pattern):
    p = _write(tmp_path / "a.csv", "gx\n1\n2\n3\n")
    with pytest.raises(ParameterError) as e:
        io.read(p, **{"rate": 1, **kw})
    _check(e, ParameterError, pattern)


def test_list_topics_refuses_non_bags(tmp_path):
    p = _write(tmp_path / "a.csv", "gx\n1\n2\n3\n")
    with pytest.raises(ParameterError) as e:
        io.list_topics(p)
    _check(e, ParameterError, "a.csv", "not a ROS bag")
    with pytest.raises(InputNotFoundError):
        io.list_topics(tmp_path / "none.bag")
    (tmp_path / "dir").mkdir()
    with pytest.raises(FormatError) as e:
        io.read(tmp_path / "dir")
    _check(e, FormatError, "is a directory, not a ROS 2 bag")


# ---------------------------------------------------------------------------------------------
# Real recordings from ../shared/refdata/imu (read in place; skipped when absent)
# ---------------------------------------------------------------------------------------------

@pytest.mark.slow
@pytest.mark.skipif(not ADIS.exists(), reason="shared/refdata/imu not present")
def test_real_adis16405_recording():
    log = _quiet_read(ADIS, rate=100)
    assert len(log) == 1_000_000 and log.source.format == "csv" and "gzip" in log.source.detail
    assert log.names == ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
    # units from the column suffixes _dps and _g (README: inferred from the LSB grids)
    assert log.units["gyro_x"] == "deg/s" and log.units["accel_z"] == "g"
    assert log.source.sha256 == "8d8c7e055a111f4190a8b67087f3d68b3ed3474a6992a1b5f9c8a406aa233ecc"
    # first row as written in the file, and the statistics the README quotes
    np.testing.assert_array_equal(log.as_array()[0], [-0.05, -0.3, 0.7, -0.00666, 0, -1.01565])
    assert all(0.345 <= np.std(log[f"gyro_{a}"]) <= 0.435 for a in "xyz")  # README: 0.35–0.43
    assert np.mean(log["accel_z"]) == pytest.approx(-1.016, abs=1e-3)
    assert log.timing.span == pytest.approx(9999.99)


@pytest.mark.skipif(not IMU_UTILS.exists(), reason="shared/refdata/imu not present")
def test_real_imu_utils_one_value_per_line():
    log = _quiet_read(IMU_UTILS / "data_16448_gyr_t.txt", rate=1, data_type="freq")
    assert log.source.format == "stable32" and len(log) > 90
    assert np.all(np.diff(log["freq"]) > 0)  # the τ values, increasing


def test_memory_grows_like_the_samples_not_the_text(tmp_path, monkeypatch):
    """Peak memory per extra row stays within 3× the row as float64 (the text is parsed in chunks).

    Measured on 10⁶ EuRoC-like rows (141 MB of text, 6 channels and int64 ns time):
    traced peak 99 MB = 2.1× the samples as float64.
    """
    import tracemalloc

    monkeypatch.setattr("sigmatau.io._text.CHUNK_ROWS", 4096)
    rng = np.random.default_rng(0)
    peaks = []
    sizes = (30_000, 90_000)
    for n in sizes:
        t = 1_403_636_579_758_555_392 + 5_000_000 * np.arange(n, dtype=np.int64)
        p = tmp_path / f"m{n}.csv"
        with p.open("w") as fh:
            fh.write(EUROC_HEADER + "\n")
            np.savetxt(fh, np.column_stack([t.astype(object), rng.standard_normal((n, 6))]),
                       fmt=["%d"] + ["%.17g"] * 6, delimiter=",")
        tracemalloc.start()
        try:
            log = io.read(p)
            peaks.append(tracemalloc.get_traced_memory()[1])
        finally:
            tracemalloc.stop()
        assert len(log) == n
    row = 8 * 7  # six channels and the time column as 8-byte numbers
    per_row = (peaks[1] - peaks[0]) / (sizes[1] - sizes[0])
    assert per_row < 3 * row, (per_row, peaks)
