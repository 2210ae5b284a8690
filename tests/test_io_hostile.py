"""sigmatau.io against careless and hostile input (issue 11): units it does not know, pipes,
huge lines, zip bombs and lying headers, thousands of columns, columns that would be lost
without a word, and messages that must make sense on the command line.

Each test here failed on the readers before issue 11 was fixed (the defect it pins is named
in its docstring). Every file is written under tmp_path; nothing here needs a network.
"""

from __future__ import annotations

import io as stdio
import json
import os
import re
import subprocess
import sys
import threading
import time
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest
from helpers import assert_one_line_error

from sigmatau import DataError, ParameterError, SigmaTauError, io
from sigmatau.cli import main
from sigmatau.io import FormatError, InputWarning

N = 3000
RATE = 100.0


def _check(exc_info, kind, *patterns):
    """One line, of the expected type, in sigmatau's hierarchy, matching every pattern."""
    exc = exc_info.value
    assert type(exc) is kind, (type(exc), exc)
    assert isinstance(exc, SigmaTauError)
    msg = str(exc)
    assert "\n" not in msg and "\r" not in msg, msg
    for pattern in patterns:
        assert re.search(pattern, msg), f"{pattern!r} not in {msg!r}"
    return msg


def _table(header: str, n: int = N, k: int = 3, seed: int = 1) -> tuple[str, np.ndarray]:
    """A CSV text: time column t at RATE, then k random columns under the header's names."""
    v = np.round(np.random.default_rng(seed).standard_normal((n, k)), 9)
    t = np.arange(n) / RATE
    rows = "\n".join(f"{ti:.2f}," + ",".join(repr(float(x)) for x in row) for ti, row in zip(t, v))
    return header + "\n" + rows + "\n", v


def _write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def _cli(argv, capsys):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _subprocess_cli(args, stdin_bytes: bytes | None = None, env_extra=None):
    env = dict(os.environ)
    env.update(env_extra or {})
    return subprocess.run([sys.executable, "-m", "sigmatau", *map(str, args)], input=stdin_bytes,
                          capture_output=True, env=env, timeout=300)


# ---------------------------------------------------------------------------------------------
# 1. Units the file states but sigmatau does not know
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("unit", ["rpm", "LSB", "counts"])
def test_unknown_gyro_unit_in_header_is_refused(tmp_path, unit):
    """Defect: ``gyro_x [rpm]`` was analysed as rad/s without a word."""
    text, _ = _table(f"t,gyro_x [{unit}],gyro_y [{unit}],gyro_z [{unit}]")
    p = _write(tmp_path / "g.csv", text)
    with pytest.raises(DataError) as e:
        io.read(p)
    _check(e, DataError, "g.csv", re.escape(f"'gyro_x [{unit}]'"), re.escape(f"'{unit}'"), "not a gyro unit",
           "rad/s, mrad/s, deg/s", re.escape("--gyro-unit deg/s (units={'gyro': 'deg/s'} in Python)"))


def test_unknown_accel_unit_and_a_unit_of_the_wrong_group(tmp_path):
    text, _ = _table("t,accel_x [counts],accel_y [counts],accel_z [counts]")
    with pytest.raises(DataError) as e:
        io.read(_write(tmp_path / "a.csv", text))
    _check(e, DataError, "'counts'", "not a accel unit|not an accel unit|accel unit",
           re.escape("--accel-unit g (units={'accel': 'g'} in Python)"))
    text, _ = _table("t,gyro_x [g],gyro_y [g],gyro_z [g]")  # g is an accelerometer unit
    with pytest.raises(DataError) as e:
        io.read(_write(tmp_path / "w.csv", text))
    _check(e, DataError, "'gyro_x \\[g\\]' is in 'g'", "--gyro-unit")


def test_unknown_unit_in_a_units_line(tmp_path):
    """A units line under the header with an unknown unit was skipped as preamble: rad/s again."""
    text, _ = _table("t,gx,gy,gz\ns,rpm,rpm,rpm")
    with pytest.raises(DataError) as e:
        io.read(_write(tmp_path / "u.csv", text))
    _check(e, DataError, "u.csv", "column 'gx' is in 'rpm'", "--gyro-unit")


def test_declared_unit_overrides_an_unknown_one_with_a_warning(tmp_path):
    text, v = _table("t,gyro_x [LSB],gyro_y [LSB],gyro_z [LSB]")
    p = _write(tmp_path / "g.csv", text)
    with pytest.warns(InputWarning, match="is in LSB according to the file; using the declared deg/s"):
        log = io.read(p, units={"gyro": "deg/s"})
    assert log.units == {"gyro_x": "deg/s", "gyro_y": "deg/s", "gyro_z": "deg/s"}
    np.testing.assert_array_equal(log.as_array(), v)


@pytest.mark.parametrize("spelled, unit", [("deg/s", "deg/s"), ("°/s", "deg/s"), ("dps", "deg/s"),
                                           ("rad s^-1", "rad/s"), ("mrad/s", "mrad/s"), ("deg/h", "deg/h")])
def test_known_gyro_units_still_accepted(tmp_path, spelled, unit):
    text, _ = _table(f"t,gyro_x [{spelled}],gyro_y [{spelled}],gyro_z [{spelled}]", n=50)
    with _no_warnings():
        log = io.read(_write(tmp_path / "k.csv", text))
    assert set(log.units.values()) == {unit} and set(log.unit_origin.values()) == {"file"}


@pytest.mark.parametrize("spelled, unit", [("m/s²", "m/s^2"), ("mg", "mg"), ("g", "g"), ("µg", "ug")])
def test_known_accel_units_still_accepted(tmp_path, spelled, unit):
    text, _ = _table(f"t,accel_x [{spelled}],accel_y [{spelled}],accel_z [{spelled}]", n=50)
    with _no_warnings():
        log = io.read(_write(tmp_path / "k.csv", text))
    assert set(log.units.values()) == {unit}


def test_unknown_unit_attribute_in_hdf5(tmp_path):
    h5py = pytest.importorskip("h5py")
    p = tmp_path / "g.h5"
    with h5py.File(p, "w") as f:
        f["t"] = np.arange(200) / RATE
        for a in "xyz":
            f[f"gyro_{a}"] = np.zeros(200)
            f[f"gyro_{a}"].attrs["units"] = "rpm"
    with pytest.raises(DataError) as e:
        io.read(p)
    _check(e, DataError, "g.h5", "'rpm'", "--gyro-unit")


def test_unknown_unit_on_the_command_line(tmp_path, capsys):
    text, _ = _table("t,gyro_x [rpm],gyro_y [rpm],gyro_z [rpm]")
    p = _write(tmp_path / "g.csv", text)
    code, out, err = _cli(["stats", p, "--stat", "oadev"], capsys)
    assert_one_line_error((code, err), code=1, match=r"g\.csv: column 'gyro_x \[rpm\]' is in 'rpm'.*--gyro-unit deg/s")
    assert out == ""


# ---------------------------------------------------------------------------------------------
# 2. Pipes, FIFOs and /dev/stdin are read once, completely
# ---------------------------------------------------------------------------------------------

class _no_warnings:
    def __enter__(self):
        self._ctx = warnings.catch_warnings()
        self._ctx.__enter__()
        warnings.simplefilter("error")

    def __exit__(self, *exc):
        self._ctx.__exit__(*exc)


def _feed_fifo(path: Path, data: bytes) -> threading.Thread:
    def write() -> None:
        try:
            with open(path, "wb") as fh:
                for i in range(0, len(data), 4096):  # in pieces, as a producer process would
                    fh.write(data[i:i + 4096])
        except BrokenPipeError:  # the reader refused the input and closed its end
            pass

    thread = threading.Thread(target=write, daemon=True)
    thread.start()
    return thread


def _read_fifo(fifo: Path, seconds: float = 60.0, **kw):
    """``io.read(fifo)`` in a thread: its result, or its exception raised here; a read that
    blocks (a second open of the FIFO waits for a writer that has gone) fails the test."""
    box: dict = {}

    def run() -> None:
        try:
            with warnings.catch_warnings(record=True) as rec:
                warnings.simplefilter("always")
                box["log"] = io.read(fifo, **kw)
            box["warnings"] = [str(w.message) for w in rec]
        except BaseException as exc:  # handed to the test thread
            box["exc"] = exc

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(seconds)
    if thread.is_alive():
        fd = os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)  # give the blocked open its EOF
        os.close(fd)
        thread.join(10)
        pytest.fail(f"reading {fifo.name} blocked: the FIFO was opened a second time")
    if "exc" in box:
        raise box["exc"]
    return box["log"], box["warnings"]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs os.mkfifo")
def test_fifo_is_read_once_and_completely(tmp_path):
    """Defect: the FIFO was opened twice (detection, then reading): ~160 rows vanished, exit 0."""
    text, v = _table("t,gyro_x,gyro_y,gyro_z")
    fifo = tmp_path / "log.fifo"
    os.mkfifo(fifo)
    writer = _feed_fifo(fifo, text.encode())
    log, warned = _read_fifo(fifo)
    writer.join(10)
    assert warned == []
    assert len(log) == N and log.names == ("gyro_x", "gyro_y", "gyro_z")
    np.testing.assert_array_equal(log.as_array(), v)
    assert log.source.size == len(text.encode())
    assert log.rate == pytest.approx(RATE)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs os.mkfifo")
def test_fifo_gzip_and_binary_and_empty(tmp_path):
    import gzip

    text, v = _table("t,gyro_x,gyro_y,gyro_z")
    fifo = tmp_path / "z.fifo"
    os.mkfifo(fifo)
    writer = _feed_fifo(fifo, gzip.compress(text.encode()))
    log, _ = _read_fifo(fifo)
    writer.join(10)
    np.testing.assert_array_equal(log.as_array(), v)
    assert "gzip" in log.source.detail

    buf = stdio.BytesIO()
    np.save(buf, v)
    writer = _feed_fifo(fifo, buf.getvalue())
    with pytest.raises(FormatError) as e:
        _read_fifo(fifo)
    writer.join(10)
    _check(e, FormatError, "z.fifo", "pipe or device", "npy", "regular file")

    writer = _feed_fifo(fifo, b"")
    with pytest.raises(DataError) as e:
        _read_fifo(fifo)
    writer.join(10)
    _check(e, DataError, "z.fifo", "empty")


@pytest.mark.slow
@pytest.mark.parametrize("command", ["stats", "analyze"])
def test_dev_stdin_through_a_pipe_keeps_every_sample(tmp_path, command):
    """``cat log.csv | sigmatau stats /dev/stdin``: every one of the 3,000 samples is there."""
    if not Path("/dev/stdin").exists():
        pytest.skip("no /dev/stdin")
    text, _ = _table("t,gyro_x,gyro_y,gyro_z")
    out = tmp_path / "out"
    args = [command, "/dev/stdin", "--stat", "oadev"]
    args += ["--out", out, "--no-figures", "--no-model"] if command == "analyze" else []
    res = _subprocess_cli(args, stdin_bytes=text.encode())
    assert res.returncode == 0, res.stderr.decode()
    if command == "stats":
        assert "3,000 samples" in res.stdout.decode(), res.stdout.decode()[:300]
    else:
        doc = json.loads((out / "results.json").read_text())
        assert doc["log"]["n_samples"] == N


# ---------------------------------------------------------------------------------------------
# 3. Long lines
# ---------------------------------------------------------------------------------------------

def test_200_kB_line_in_the_data_is_refused_with_its_line_number(tmp_path, capsys):
    """Defect: exit 3 ``field larger than field limit (131072)``."""
    text, _ = _table("t,gyro_x,gyro_y,gyro_z", n=500)
    lines = text.splitlines()
    lines.insert(300, '0.1,"' + "x" * 200_000 + '",1,2')  # file line 301
    p = _write(tmp_path / "long.csv", "\n".join(lines) + "\n")
    with pytest.raises(DataError) as e:
        io.read(p)
    msg = _check(e, DataError, "long.csv", "line 301")
    assert len(msg) < 400, msg  # the 200 kB field is not repeated in the message
    code, _, err = _cli(["stats", p, "--stat", "oadev"], capsys)
    assert_one_line_error((code, err), code=1, match="line 301")


@pytest.mark.parametrize("sep", [",", ";", "\t", " "])
def test_a_data_line_with_more_fields_than_the_header_is_refused(tmp_path, capsys, sep):
    """Defect: numpy's loadtxt reads only the columns asked for, so a line with an extra
    value (a field split in two, a lost line break) was kept, its values most likely shifted."""
    text, _ = _table("t,gyro_x,gyro_y,gyro_z", n=500)
    lines = [ln.replace(",", sep) for ln in text.splitlines()]
    lines[300] += f"{sep}7"  # file line 301
    p = _write(tmp_path / "extra.csv", "\n".join(lines) + "\n")
    with pytest.raises(DataError) as e:
        io.read(p)
    _check(e, DataError, "extra.csv", "line 301 has 5 fields, expected 4")
    code, _, err = _cli(["stats", p, "--stat", "oadev"], capsys)
    assert_one_line_error((code, err), code=1, match="line 301 has 5 fields")


def test_empty_trailing_fields_are_not_extra_values(tmp_path):
    text, v = _table("t,gyro_x,gyro_y,gyro_z", n=500)
    lines = text.splitlines()
    lines[300] += ","
    lines[301] += ",,"
    log = io.read(_write(tmp_path / "trailing.csv", "\n".join(lines) + "\n"))
    np.testing.assert_array_equal(log.as_array(), v)


@pytest.mark.slow
def test_an_extra_field_is_refused_on_the_fast_csv_path_too(tmp_path):
    """Files over 16 MiB go through pyarrow's reader first, which gives way to the reference."""
    rng = np.random.default_rng(3)
    n = 400_000
    a = rng.normal(size=(n, 2))
    rows = [f"{0.01 * i:.2f},{a[i, 0]:.17f},{a[i, 1]:.17f}" for i in range(n)]
    rows[300_000] += ",5"
    p = _write(tmp_path / "big.csv", "t,gyro_x,gyro_y\n" + "\n".join(rows) + "\n")
    assert p.stat().st_size > 16 << 20
    with pytest.raises(DataError, match="line 300002 has 4 fields, expected 3"):
        io.read(p)


def test_200_kB_quoted_header_field_is_read(tmp_path):
    """A header whose quoted name is longer than the csv module's field limit: read, and the
    column named in the warning of unused columns (cut short)."""
    text, v = _table('t,gyro_x,gyro_y,"' + "n" * 200_000 + '"', n=200)
    p = _write(tmp_path / "h.csv", text)
    with pytest.warns(InputWarning, match=r"1 column not used: 'n{60}'… \(200,000 characters\)") as rec:
        log = io.read(p)
    assert log.names == ("gyro_x", "gyro_y")
    np.testing.assert_array_equal(log.as_array(), v[:, :2])
    assert all(len(str(w.message)) < 400 for w in rec)


@pytest.mark.parametrize("where", [2, 5000])
def test_line_over_a_mebibyte_is_refused_before_it_is_held(tmp_path, where):
    text, _ = _table("t,gyro_x,gyro_y,gyro_z", n=6000)
    lines = text.splitlines()
    lines.insert(where - 1, "1" * ((1 << 20) + 10))  # io.MAX_LINE_CHARS is 1 MiB
    p = _write(tmp_path / "huge.csv", "\n".join(lines) + "\n")
    with pytest.raises(DataError) as e:
        io.read(p)
    _check(e, DataError, "huge.csv", f"line {where} is longer than 1,048,576 characters")


# ---------------------------------------------------------------------------------------------
# 4. Resources: declared sizes checked before allocating; channels capped
# ---------------------------------------------------------------------------------------------

def _npy_member(shape, dtype="<f8") -> bytes:
    buf = stdio.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": dtype, "fortran_order": False, "shape": shape})
    return buf.getvalue()


def test_npz_header_declaring_more_than_it_holds(tmp_path):
    """Defect: a member whose header declares 10^11 samples made numpy allocate 745 GiB (MemoryError)."""
    p = tmp_path / "lie.npz"
    with zipfile.ZipFile(p, "w") as z:
        z.writestr("gyro_x.npy", _npy_member((10**11,)))
    with pytest.raises(FormatError) as e:
        io.read(p, rate=1)
    _check(e, FormatError, "lie.npz", "array 'gyro_x'", r"declares shape \(100000000000,\)",
           "800,000,000,000 bytes", "holds 0")


def test_npz_zip_bomb_refused_under_a_memory_limit(tmp_path):
    """Defect: an honest zip bomb (zeros, 200 MB in ~0.9 MB) under ``ulimit -v``: exit 3 MemoryError.

    Run in a child whose address space is limited to what it uses plus 100 MiB, so the
    check must use the declared size (the zip directory and the member header) to refuse.
    """
    resource = pytest.importorskip("resource")
    n = 25_000_000
    p = tmp_path / "bomb.npz"
    zero = bytes(1 << 22)
    with zipfile.ZipFile(p, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=1) as z:
        with z.open("gyro_x.npy", "w", force_zip64=True) as m:
            m.write(_npy_member((n,)))
            left = 8 * n
            while left:
                m.write(zero[:min(left, len(zero))])
                left -= min(left, len(zero))
    assert p.stat().st_size < 2_000_000
    code = f"""
import resource, sys
from sigmatau import io, SigmaTauError
used = int(next(l for l in open('/proc/self/status') if l.startswith('VmSize:')).split()[1]) * 1024
resource.setrlimit(resource.RLIMIT_AS, (used + (100 << 20), resource.getrlimit(resource.RLIMIT_AS)[1]))
try:
    io.read({str(p)!r}, rate=1)
except SigmaTauError as exc:
    print(type(exc).__name__, exc)
    sys.exit(1)
except MemoryError as exc:
    print('MemoryError', exc)
    sys.exit(3)
"""
    if not Path("/proc/self/status").exists():
        pytest.skip("needs /proc")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert res.returncode == 1, (res.returncode, res.stdout, res.stderr)
    assert re.search(r"DataError .*bomb\.npz: loading its 1 array\(s\) needs 190\.7 MiB of memory, more than"
                     r" the .* available; refused before allocating", res.stdout), res.stdout


def test_hdf5_declared_rows_beyond_memory(tmp_path, monkeypatch):
    """A chunked HDF5 dataset of 10^11 rows takes a few kB on disk; reading it allocated 745 GiB."""
    h5py = pytest.importorskip("h5py")
    p = tmp_path / "big.h5"
    with h5py.File(p, "w") as f:
        f.create_dataset("gyro_x", shape=(10**11,), dtype="f8", chunks=(1 << 16,), compression="gzip")
    assert p.stat().st_size < 100_000
    with pytest.raises(DataError) as e:
        io.read(p, rate=1)
    _check(e, DataError, "big.h5", "1 column\\(s\\) of 100,000,000,000 rows needs", "refused before allocating")


@pytest.mark.slow
def test_ten_thousand_columns_capped_with_a_way_out(tmp_path, capsys):
    """Defect: a 10,000-column CSV planned 20,000 figures and ran for minutes."""
    k = 10_000
    v = np.round(np.random.default_rng(3).standard_normal((20, k)), 3)
    header = ",".join(f"c{j}" for j in range(k))
    p = _write(tmp_path / "wide.csv", header + "\n" + "\n".join(",".join(map(str, row)) for row in v) + "\n")
    start = time.monotonic()
    with pytest.raises(DataError) as e:
        io.read(p, rate=1)
    assert time.monotonic() - start < 60
    _check(e, DataError, "wide.csv", "10000 numeric columns", "at most 256 channels",
           re.escape("--columns a,b,c (columns=[...] in Python)"))
    log = io.read(p, rate=1, columns=["c7", "c9999"])
    np.testing.assert_array_equal(log.as_array(), v[:, [7, 9999]])
    with pytest.raises(ParameterError) as e:
        io.read(p, rate=1, columns=list(range(300)))
    _check(e, ParameterError, "300 columns selected", "at most 256")
    code, _, err = _cli(["stats", p, "--rate", "1"], capsys)
    assert_one_line_error((code, err), code=1, match="at most 256 channels.*--columns")


def test_npy_with_thousands_of_columns_capped(tmp_path):
    np.save(tmp_path / "wide.npy", np.zeros((10, 300)))
    with pytest.raises(DataError) as e:
        io.read(tmp_path / "wide.npy", rate=1)
    _check(e, DataError, "wide.npy", "300 numeric columns", "at most 256")


# ---------------------------------------------------------------------------------------------
# 5. Strict column names; every column left out is reported
# ---------------------------------------------------------------------------------------------

def test_third_gyro_like_column_is_reported_not_silently_dropped(tmp_path, capsys):
    """Defect: gyro_x, gyro_y and an unrecognised third column: 2 axes analysed without a word."""
    text, v = _table("t,gyro_x,gyro_y,gyro_third")
    p = _write(tmp_path / "two.csv", text)
    with pytest.warns(InputWarning) as rec:
        log = io.read(p)
    assert log.names == ("gyro_x", "gyro_y")
    assert log.source.unused_columns == ("gyro_third (not a recognised channel name)",)
    (w,) = [w for w in rec if "not used" in str(w.message)]
    assert re.search(r"two\.csv: 1 column not used: 'gyro_third' \(not a recognised channel name\);"
                     r" choose columns with --columns \(columns= in Python\)", str(w.message))
    with warnings.catch_warnings():
        warnings.simplefilter("always")  # as on the command line: shown, not turned into errors
        code, _, err = _cli(["stats", p, "--stat", "oadev"], capsys)
    assert code == 0 and re.search(r"sigmatau: warning: .*two\.csv: 1 column not used: 'gyro_third'", err), err
    log = io.read(p, columns=["gyro_x", "gyro_y", "gyro_third"])  # chosen columns: nothing to report
    assert log.names == ("gyro_x", "gyro_y", "gyro_third") and log.source.unused_columns == ()


@pytest.mark.parametrize("name", ["a/../../x", "a//x", "gyro..x", "w_/_y", "acc--z", "g/x"])
def test_loose_names_are_not_channels(tmp_path, name):
    """Defect: ``a/../../x`` passed for accel_x (separators collapsed and '/' accepted)."""
    assert io.read.__module__  # the public reader is what is exercised
    text, _ = _table(f"t,{name},gyro_y,gyro_z", n=50)
    with pytest.warns(InputWarning, match=re.escape(f"'{name}' (not a recognised channel name)")):
        log = io.read(_write(tmp_path / "n.csv", text))
    assert log.names == ("gyro_y", "gyro_z")


@pytest.mark.parametrize("name, channel", [("gyro_x", "gyro_x"), ("Gyro X [deg/s]", "gyro_x"),
                                           ("acc.z", "accel_z"), ("w_RS_S_y [rad s^-1]", "gyro_y"),
                                           ("field.angular_velocity.x", "gyro_x"), ("gx", "gyro_x"),
                                           ("accel-y", "accel_y")])
def test_strict_names_still_recognised(tmp_path, name, channel):
    text, _ = _table(f"t,{name}", n=50, k=1)
    with _no_warnings():
        log = io.read(_write(tmp_path / "s.csv", text))
    assert log.names == (channel,)


def test_non_numeric_and_spare_time_columns_reported(tmp_path):
    n = 50
    rows = "\n".join(f"{i / 100:.2f},{i * 10},{0.1 * i!r},ok" for i in range(n))
    p = _write(tmp_path / "m.csv", "t,time_ms,gyro_z,status\n" + rows + "\n")
    with pytest.warns(InputWarning, match=r"2 columns not used: 'time_ms' \(another time column\),"
                                          r" 'status' \(not numeric\)"):
        log = io.read(p)
    assert log.names == ("gyro_z",)


# ---------------------------------------------------------------------------------------------
# 6. Messages: right words, both spellings of an option, never numpy's pickle advice
# ---------------------------------------------------------------------------------------------

def test_random_bytes_npy_is_not_called_pickled(tmp_path):
    """Defect: random bytes in a .npy were 'holds Python objects (pickled)'."""
    p = tmp_path / "noise.npy"
    p.write_bytes(np.random.default_rng(5).bytes(300))
    with pytest.raises(FormatError) as e:
        io.read(p, rate=1)
    msg = _check(e, FormatError, "noise.npy", "not a valid .npy file")
    assert "pickle" not in msg.lower()
    damaged = tmp_path / "damaged.npy"
    damaged.write_bytes(b"\x93NUMPY\x01\x00" + np.random.default_rng(6).bytes(300))
    with pytest.raises(FormatError) as e:
        io.read(damaged, rate=1)
    assert "pickle" not in _check(e, FormatError, "damaged.npy", "not a valid .npy file").lower()


def test_object_arrays_named_as_such_without_allow_pickle_advice(tmp_path):
    np.save(tmp_path / "obj.npy", np.array([{"a": 1}, None], dtype=object), allow_pickle=True)
    with pytest.raises(FormatError) as e:
        io.read(tmp_path / "obj.npy", rate=1)
    msg = _check(e, FormatError, "obj.npy", "holds Python objects", "never loaded")
    assert "allow_pickle" not in msg
    np.savez(tmp_path / "obj.npz", x=np.array([{"a": 1}, None], dtype=object), y=np.zeros(2))
    with pytest.raises(FormatError) as e:
        io.read(tmp_path / "obj.npz", rate=1)
    msg = _check(e, FormatError, "obj.npz", "array 'x' holds Python objects", "never loaded")
    assert "allow_pickle" not in msg


def test_npy_header_larger_than_the_file(tmp_path):
    p = tmp_path / "short.npy"
    p.write_bytes(_npy_member((10**9,)) + b"\x00" * 80)
    with pytest.raises(FormatError) as e:
        io.read(p, rate=1)
    _check(e, FormatError, "short.npy", "8,000,000,000 bytes", "holds 80")


def _timed_csv(tmp_path: Path, t: np.ndarray, name: str = "t.csv") -> Path:
    rows = "\n".join(f"{float(x)!r},{0.001 * i}" for i, x in enumerate(t))
    return _write(tmp_path / name, "t,gyro_x\n" + rows + "\n")


@pytest.mark.parametrize("kind, kw, hint", [
    ("gap", {}, r"--gaps split \(gaps='split' in Python\).*--gaps ignore \(gaps='ignore' in Python\)"),
    ("backwards", {"unsorted": "refuse"}, r"--unsorted sort \(unsorted='sort' in Python\)"),
    ("duplicate", {"duplicates": "refuse"}, r"--duplicates drop \(duplicates='drop' in Python\)"),
])
def test_timing_hints_name_the_option_and_the_keyword(tmp_path, kind, kw, hint):
    """Defect: hints in Python syntax only (``gaps='split'``) printed to command-line users."""
    t = np.arange(200) * 0.01
    if kind == "gap":
        t[100:] += 0.5
    elif kind == "backwards":
        t[[50, 51]] = t[[51, 50]]
    else:
        t[60] = t[59]
    p = _timed_csv(tmp_path, t)
    with pytest.raises(DataError) as e:
        io.read(p, **kw)
    _check(e, DataError, "t.csv", hint)


def test_other_hints_name_the_option_and_the_keyword(tmp_path):
    p = _write(tmp_path / "n.csv", "gx,gy\n1,2\nnan,2\n3,4\n")
    with pytest.raises(DataError) as e:
        io.read(p, rate=1)
    # the hint names the command-line option and the keyword alike
    _check(e, DataError, "n.csv", re.escape("--gaps mark (gaps='mark' in Python)"))
    s32 = _write(tmp_path / "s32.txt", "\n".join(repr(float(x)) for x in np.arange(20) * 1e-9) + "\n")
    with pytest.raises(ParameterError) as e:
        io.read(s32, rate=1)
    _check(e, ParameterError, "s32.txt", re.escape("--data-type phase|freq (data_type='phase' or 'freq' in Python)"))
    ragged = _write(tmp_path / "r.csv", "\n".join(",".join(["1"] * (1 + i % 4)) for i in range(40)) + "\n")
    with pytest.raises(FormatError) as e:
        io.read(ragged, rate=1)
    _check(e, FormatError, "r.csv", re.escape("--delimiter (delimiter= in Python)"))
    amb = _write(tmp_path / "a.csv", "stamp,gx\n" + "\n".join(f"{i * 1000},{i}" for i in range(50)) + "\n")
    with pytest.raises(DataError) as e:
        io.read(amb)
    _check(e, DataError, "a.csv", re.escape("--time-unit s|ms|us|ns (time_unit= in Python)"))


def test_no_python_only_hint_left_in_the_readers():
    """Every 'pass x=' hint in sigmatau/io names the command-line option too."""
    folder = Path(io.__file__).parent
    offenders = []
    for path in sorted(folder.glob("*.py")):
        for no, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if re.search(r"\bpass [a-z_]+=", line) and "--" not in line:
                offenders.append(f"{path.name}:{no}: {line.strip()}")
    assert not offenders, offenders


def test_hdf5_member_of_another_length_is_reported(tmp_path):
    h5py = pytest.importorskip("h5py")
    p = tmp_path / "m.h5"
    with h5py.File(p, "w") as f:
        f["gyro_x"] = np.zeros(100)
        f["gyro_y"] = np.zeros(100)
        f["gyro_z"] = np.zeros(99)  # lost without a word before
    with pytest.warns(InputWarning, match=r"1 column not used: 'gyro_z \(99,\)' \(not of the common length 100\)"):
        log = io.read(p, rate=10)
    assert log.names == ("gyro_x", "gyro_y")


def test_terminal_escapes_in_a_unit_or_column_name_are_not_printed_raw(tmp_path):
    esc = "\x1b[2J\x1b[31m"
    text, _ = _table(f"t,gyro_x [{esc}],gyro_y,odd{esc}", n=50)
    p = _write(tmp_path / "e.csv", text)
    with pytest.warns(InputWarning) as rec:
        io.read(p, units={"gyro": "deg/s"})
    assert rec and all("\x1b" not in str(w.message) for w in rec), [str(w.message) for w in rec]
    with pytest.raises(DataError) as e:
        io.read(p)
    assert "\x1b" not in str(e.value)


def test_cgroup_budget_does_not_count_the_page_cache(tmp_path):
    """A container that has just read a large file is not out of memory: its page cache is
    reclaimable (memory.current counts it; memory.stat 'file' says how much it is)."""
    from sigmatau.io import _limits

    (tmp_path / "memory.max").write_text("4294967296\n")
    (tmp_path / "memory.current").write_text("4194304000\n")  # 3.9 GiB, of which 3.5 GiB cache
    (tmp_path / "memory.stat").write_text("anon 419430400\nfile 3774873600\nkernel 1000\n")
    assert _limits.cgroup_available(tmp_path) == 4294967296 - 419430400
    (tmp_path / "memory.max").write_text("max\n")
    assert _limits.cgroup_available(tmp_path) is None
