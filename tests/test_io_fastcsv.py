"""The pyarrow fast path for plain CSV files (issue 13) against the reference parser.

Every file is read twice through :func:`sigmatau.io._text.read_csv`: once with the fast path
switched off (``numpy.loadtxt`` in chunks, the reference) and once with it on; the tables must be
identical bit for bit (values, time tags, names, units, detail, digest) and errors identical word
for word. Ranges and pyarrow blocks are made tiny so that a few kB of text crosses many of them.
"""

from __future__ import annotations

import dataclasses
import hashlib
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pyarrow.csv")

from sigmatau import io  # noqa: E402
from sigmatau.io import _arrowcsv, _text  # noqa: E402
from sigmatau.io._progress import Progress  # noqa: E402
from sigmatau.io._registry import Options  # noqa: E402

EUROC_HEADER = ("#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
                "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]")


@pytest.fixture(autouse=True)
def small_ranges(monkeypatch):
    """Fast path for every size, in ranges of 4 kB parsed in blocks of 1 kB."""
    monkeypatch.setattr(_text, "_FAST_MIN_BYTES", 0)
    monkeypatch.setattr(_arrowcsv, "RANGE_BYTES", 4096)
    monkeypatch.setattr(_arrowcsv, "BLOCK_BYTES", 1024)


def _read(path: Path, fast: bool, progress: Progress | None = None, **options):
    """A Table from read_csv (or the error's type and message) with the fast path on or off."""
    saved = _text._FAST_CSV
    _text._FAST_CSV = fast
    _arrowcsv.last_outcome = ""
    try:
        return _text.read_csv(path, path.name, Options(**options),
                              progress or Progress(None, "test", enabled=False), auto=True)
    except Exception as exc:  # noqa: BLE001 - compared with the reference's
        return (type(exc), str(exc))
    finally:
        _text._FAST_CSV = saved


def _same(a, b) -> None:
    """Two read_csv results are identical: errors word for word, arrays bit for bit."""
    if isinstance(a, tuple) or isinstance(b, tuple):
        assert a == b
        return
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if f.name == "data":
            assert list(x) == list(y)
            for name in x:
                assert x[name].dtype == y[name].dtype == np.float64
                assert np.array_equal(x[name].view(np.int64), y[name].view(np.int64)), name
        elif f.name == "time":
            assert (x is None) == (y is None)
            if x is not None:
                assert x.dtype == y.dtype
                assert np.array_equal(x.view(np.int64), y.view(np.int64))
        else:
            assert x == y, f.name


def _compare(path: Path, expect_fast: bool | None = None, **options) -> str:
    """Read with and without the fast path, assert identical results; return the fast path's outcome."""
    ref = _read(path, False, **options)
    assert _arrowcsv.last_outcome == ""  # the switch does switch it off
    fast = _read(path, True, **options)
    outcome = _arrowcsv.last_outcome
    _same(ref, fast)
    if expect_fast is True:
        assert outcome == "fast", outcome
    elif expect_fast is False:
        assert outcome != "fast"
    return outcome


def _rows(n: int, seed: int = 0, fmt: str = "repr") -> np.ndarray:
    return np.random.default_rng(seed).standard_normal((n, 6)) * 10.0 ** np.random.default_rng(seed + 1).integers(
        -8, 8, size=(n, 6))


def _fmt(x: float, style: str) -> str:
    return {"repr": repr(float(x)), "g17": f"{x:.17g}", "e": f"{x:.9e}", "f": f"{x:.12f}", "E": f"{x:+.5E}"}[style]


def _write_csv(path: Path, header: str, t: list[str], values: np.ndarray, style: str = "repr",
               delimiter: str = ",", newline: str = "\n", tail: str = "") -> Path:
    lines = [header] if header else []
    lines += [delimiter.join([ti] + [_fmt(x, style) for x in row]) for ti, row in zip(t, values)]
    path.write_bytes((newline.join(lines) + newline + tail).encode("utf-8"))
    return path


# ---------------------------------------------------------------------------------------------
# Plain files: the fast path is taken and gives the same table
# ---------------------------------------------------------------------------------------------

def test_euroc_layout_takes_the_fast_path_with_exact_int64_nanoseconds(tmp_path):
    n = 3000
    t = [str(1_403_636_579_758_555_392 + 5_000_003 * i) for i in range(n)]  # beyond 2**53: int64
    p = _write_csv(tmp_path / "data.csv", EUROC_HEADER, t, _rows(n), "g17")
    _compare(p, expect_fast=True)
    table = _read(p, True)
    assert table.time.dtype == np.int64 and table.time[-1] == int(t[-1])
    assert table.sha256 == hashlib.sha256(p.read_bytes()).hexdigest() and table.size == p.stat().st_size
    assert "EuRoC" in table.detail


def test_plain_t_gyro_file_takes_the_fast_path(tmp_path):
    n = 2500
    t = [f"{i / 1000:.3f}" for i in range(n)]
    p = _write_csv(tmp_path / "imu.csv", "t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z", t, _rows(n, 3))
    _compare(p, expect_fast=True)
    ref, fast = _read(p, False), _read(p, True)
    assert fast.time.dtype == np.float64 and fast.rows == ref.rows == n


def test_read_of_a_plain_file_gives_the_same_sensor_log(tmp_path, monkeypatch):
    n = 2000
    p = _write_csv(tmp_path / "imu.csv", "t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z",
                   [f"{i / 100:.2f}" for i in range(n)], _rows(n, 5))
    monkeypatch.setattr(_text, "_FAST_CSV", False)
    ref = io.read(p)
    monkeypatch.setattr(_text, "_FAST_CSV", True)
    fast = io.read(p)
    assert _arrowcsv.last_outcome == "fast"
    assert np.array_equal(ref.as_array().view(np.int64), fast.as_array().view(np.int64))
    assert np.array_equal(ref.timestamps, fast.timestamps)
    assert ref.source == fast.source and ref.units == fast.units


@pytest.mark.parametrize("style", ["repr", "g17", "e", "f", "E"])
@pytest.mark.parametrize("delimiter", [",", ";", "\t", "|"])
def test_number_styles_and_delimiters(tmp_path, style, delimiter):
    n = 700
    t = [repr(i * 0.001) for i in range(n)]
    header = delimiter.join(["time", "gx", "gy", "gz", "ax", "ay", "az"])
    p = _write_csv(tmp_path / "s.csv", header, t, _rows(n, 7), style, delimiter)
    _compare(p, expect_fast=True)


TRICKY = [
    "0.1", "0.2", "0.30000000000000004", "1e23", "8.98846567431158e307", "1.7976931348623157e308",
    "2.2250738585072011e-308", "2.2250738585072014e-308", "4.9e-324", "2.4703282292062327e-324",
    "2.4703282292062328e-324", "1e-400", "-0", "-0.0", "+1.5", "000.5", ".5", "5.", "1E5", "1e+05",
    "9007199254740993", "9007199254740992.5", "123456789012345678901234567890", " 1.25", "2.5 ", "\t3.5",
    "0.1000000000000000055511151231257827021181583404541015625",
    "1." + "0" * 300 + "1", "7.038531e-26", "1.00000000000000011102230246251565404236316680908203125",
    "1.000000000000000111022302462515654042363166809082031251", "3.4028235677973366e38",
]


def test_tricky_decimal_strings_round_like_numpy(tmp_path):
    values = TRICKY * 40
    lines = ["t,gyro_x,gyro_y"] + [f"{i},{v},{values[-1 - i]}" for i, v in enumerate(values)]
    p = tmp_path / "tricky.csv"
    p.write_text("\n".join(lines) + "\n")
    _compare(p, expect_fast=True, time_column=False, rate=1)


def test_float_grammar_accepted_by_pyarrow_is_numpys(tmp_path):
    """Any field pyarrow's float64 or int64 conversion accepts parses to the same bits in numpy.loadtxt.

    The field is the second of its line: at the very start of its input pyarrow skips a byte-order
    mark, which the fast path handles by giving up (``bom mid-file`` below).
    """
    import pyarrow as pa
    import pyarrow.csv as pcsv

    rng = np.random.default_rng(11)
    alphabet = list("0123456789") * 3 + list(".eE+-_ \tnaifNAIFdDbo") + ["\u00a0", "\ufeff", "inf", "nan"]
    # no 'x': pyarrow reads 0x1F as an integer, numpy does not; the fast path gives up on '0x' instead
    samples = ["".join(rng.choice(alphabet, size=rng.integers(1, 9))) for _ in range(3000)] + TRICKY
    for typ, dtype in ((pa.float64(), np.float64), (pa.int64(), np.int64)):
        reader = _arrowcsv.FastReader(tmp_path, "", ",", 2, [1, 0], typ == pa.int64())
        read, parse, convert = reader._options()
        for s in samples:
            try:
                got = pcsv.read_csv(pa.py_buffer(f"0,{s}\n".encode()), read_options=read, parse_options=parse,
                                    convert_options=convert).column("c1").to_numpy()
            except pa.ArrowInvalid:
                continue
            try:
                ref = np.loadtxt([f"0,{s}"], delimiter=",", usecols=[1], dtype=dtype, ndmin=1)
            except ValueError:
                pytest.fail(f"pyarrow accepts {s!r} as {typ}, numpy.loadtxt does not")
            if dtype is np.float64 and not np.isfinite(got).all():
                continue  # the fast path gives up on non-finite values
            assert got.view(np.int64)[0] == ref.view(np.int64)[0], s


def test_file_without_final_newline_and_extra_unused_columns(tmp_path):
    n = 500
    lines = ["t,gyro_x,gyro_y,gyro_z,status,note"] + [
        f"{i * 0.01:.2f},{i},{-i * 0.5},{i * 1e-3},OK,x{i}" for i in range(n)]
    p = tmp_path / "u.csv"
    p.write_text("\n".join(lines))
    _compare(p, expect_fast=True)


def test_crlf_file_is_read_exactly(tmp_path):
    n = 800
    p = _write_csv(tmp_path / "crlf.csv", "t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z",
                   [f"{i / 100:.2f}" for i in range(n)], _rows(n, 9), newline="\r\n")
    _compare(p)


# ---------------------------------------------------------------------------------------------
# Irregular files: the same error, or the reference's answer after the fast path gives up
# ---------------------------------------------------------------------------------------------

def _base(n: int = 1200) -> list[str]:
    return ["t,gyro_x,gyro_y,gyro_z"] + [f"{i / 100:.2f},{i * 0.25},{-i * 1e-3},{i % 7}" for i in range(n)]


HOSTILE = {
    "short line": lambda L: L[:900] + ["9.00,1"] + L[900:],
    "long line": lambda L: L[:900] + ["9.00,1,2,3,4"] + L[900:],
    "non-numeric": lambda L: L[:1100] + ["11.00,oops,2,3"] + L[1100:],
    "empty field": lambda L: L[:700] + ["7.00,,2,3"] + L[700:],
    "NA field": lambda L: L[:700] + ["7.00,NA,2,3"] + L[700:],
    "quoted field": lambda L: L[:700] + ['7.00,"1",2,3'] + L[700:],
    "quoted comma": lambda L: L[:700] + ['7.00,1,2,"3,4"'] + L[700:],
    "nan": lambda L: L[:600] + ["6.00,nan,2,3"] + L[600:],
    "NaN": lambda L: L[:600] + ["6.00,NaN,2,3"] + L[600:],
    "-nan": lambda L: L[:600] + ["6.00,-nan,2,3"] + L[600:],
    "inf": lambda L: L[:600] + ["6.00,inf,-Infinity,3"] + L[600:],
    "overflow": lambda L: L[:600] + ["6.00,1e400,2,3"] + L[600:],
    "empty line": lambda L: L[:500] + [""] + L[500:],
    "blank line with spaces": lambda L: L[:500] + ["   "] + L[500:],
    "empty lines at the end": lambda L: L + ["", ""],
    "comment line": lambda L: L[:800] + ["# a comment"] + L[800:],
    "inline comment": lambda L: L[:800] + ["8.00,1,2,3 # note"] + L[800:],
    "percent comment": lambda L: L[:800] + ["% a comment"] + L[800:],
    "slash comment": lambda L: L[:800] + ["// a comment"] + L[800:],
    "trailing delimiter": lambda L: [s + "," for s in L],
    "trailing delimiter once": lambda L: L[:300] + [L[300] + ","] + L[301:],
    "units line": lambda L: L[:1] + ["s,rad/s,rad/s,rad/s"] + L[1:],
    "header in a comment": lambda L: ["# " + L[0]] + L[1:],
    "comment in the head": lambda L: L[:5] + ["# pause"] + L[5:],
    "bom": lambda L: ["\ufeff" + L[0]] + L[1:],
    "bom without header": lambda L: ["\ufeff" + L[1]] + L[2:],
    "bom mid-file": lambda L: L[:600] + ["\ufeff" + L[600]] + L[601:],
    "nul byte": lambda L: L[:600] + ["6.00,1\x00,2,3"] + L[600:],
    "lone cr": lambda L: ["\r".join(L[:400])] + L[400:],
    "mixed cr": lambda L: L[:400] + [L[400] + "\r" + L[401]] + L[402:],
    "plus signs": lambda L: L[:400] + ["+4.00,+1,+2,+3"] + L[400:],
    "spaces around": lambda L: L[:400] + [" 4.00 , 1 ,\t2\t, 3 "] + L[400:],
    "underscore": lambda L: L[:400] + ["4.00,1_000,2,3"] + L[400:],
    "hex": lambda L: L[:400] + ["4.00,0x10,2,3"] + L[400:],
    "fortran exponent": lambda L: L[:400] + ["4.00,1d5,2,3"] + L[400:],
    "nbsp": lambda L: L[:400] + ["4.00,\u00a01,2,3"] + L[400:],
    "arabic digits": lambda L: L[:400] + ["4.00,\u0661,2,3"] + L[400:],
    "decimal comma": lambda L: L[:400] + ["4.00,1;5,2,3"] + L[400:],
    "whitespace delimited": lambda L: [s.replace(",", " ") for s in L],
    "no data rows after head": lambda L: L[:3],
}


@pytest.mark.parametrize("case", sorted(HOSTILE))
def test_hostile_text_gives_the_reference_answer(tmp_path, case):
    p = tmp_path / "h.csv"
    p.write_bytes("\n".join(HOSTILE[case](_base())).encode("utf-8") + b"\n")
    _compare(p)


def test_invalid_utf8_in_an_unused_column_and_in_a_value(tmp_path):
    base = "\n".join(_base()).encode()
    lines = base.split(b"\n")
    unused = b"\n".join([lines[0] + b",note"] + [s + b",ok" for s in lines[1:600]] + [lines[600] + b",\xff\xfe"]
                        + [s + b",ok" for s in lines[601:]]) + b"\n"
    p = tmp_path / "u.csv"
    p.write_bytes(unused)
    _compare(p, expect_fast=True)
    bad = b"\n".join(lines[:600] + [b"6.00,1\xff,2,3"] + lines[600:]) + b"\n"
    q = tmp_path / "b.csv"
    q.write_bytes(bad)
    _compare(q, expect_fast=False)


def test_line_over_the_limit_in_the_data_is_refused_the_same_way(tmp_path):
    lines = _base()
    lines.insert(900, "9.00," + " " * (1 << 20) + "1,2,3")  # a padded but valid value, over 1 MiB
    p = tmp_path / "long.csv"
    p.write_text("\n".join(lines) + "\n")
    assert _compare(p, expect_fast=False)
    assert "longer than" in _read(p, True)[1]


def test_a_line_just_under_the_window_is_read_fast(tmp_path, monkeypatch):
    monkeypatch.setattr(_arrowcsv, "BLOCK_BYTES", 4 * _arrowcsv._WINDOW)  # as in use: above any line let through
    lines = ["t,gyro_x,gyro_y,gyro_z,note"] + [f"{i / 100:.2f},{i},2,3,x" for i in range(1000)]
    lines[500] = lines[500][:-1] + "y" * 100_000
    p = tmp_path / "wide.csv"
    p.write_text("\n".join(lines) + "\n")
    _compare(p, expect_fast=True)


def test_integer_time_tags_that_break_the_int64_grammar(tmp_path):
    t = [str(1_700_000_000_000_000_000 + 1_000_000 * i) for i in range(1000)]
    v = _rows(1000, 2)
    for i, bad in ((700, "1.7e18"), (699, "0x179a8f0000000000"), (698, " 0X17"), (701, "+1700000000701000000"), (702, "9223372036854775808"),
                   (703, "1700000000703000000.0")):
        t2 = list(t)
        t2[i] = bad
        p = _write_csv(tmp_path / f"t{i}.csv", "timestamp [ns],gx,gy,gz,ax,ay,az", t2, v)
        _compare(p, expect_fast=False)
    p = _write_csv(tmp_path / "ok.csv", "timestamp [ns],gx,gy,gz,ax,ay,az", t, v)
    _compare(p, expect_fast=True)


def test_options_columns_time_column_and_delimiter(tmp_path):
    n = 900
    p = _write_csv(tmp_path / "o.csv", "time,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z",
                   [f"{i / 100:.2f}" for i in range(n)], _rows(n, 4))
    _compare(p, expect_fast=True, columns=["accel_z", "gyro_x"])
    _compare(p, expect_fast=True, time_column=False, rate=100)
    _compare(p, expect_fast=True, delimiter=",")
    _compare(p, delimiter=";")
    _compare(p, columns=["nope"])


def test_compressed_and_small_files_use_the_reference(tmp_path, monkeypatch):
    import gzip

    n = 500
    text = "\n".join(_base(n)) + "\n"
    z = tmp_path / "z.csv.gz"
    z.write_bytes(gzip.compress(text.encode()))
    _compare(z, expect_fast=False)
    assert _arrowcsv.last_outcome == ""  # not even tried
    monkeypatch.setattr(_text, "_FAST_MIN_BYTES", 1 << 20)
    p = tmp_path / "small.csv"
    p.write_text(text)
    _compare(p)
    assert _arrowcsv.last_outcome == ""


def test_without_pyarrow_the_reference_reads(tmp_path, monkeypatch):
    monkeypatch.setattr(_arrowcsv, "usable", lambda: False)
    p = tmp_path / "p.csv"
    p.write_text("\n".join(_base()) + "\n")
    _compare(p)
    assert _arrowcsv.last_outcome == ""


def test_buffer_growth_when_the_size_estimate_is_short(tmp_path):
    """The first lines are long, the rest short: the buffers grow during the fast read."""
    lines = ["t,gyro_x"] + [f"{i / 100:.2f},{0.1 * i:.17e}" for i in range(300)] + [
        f"{i / 100:.2f},{i % 10}" for i in range(300, 20_000)]
    p = tmp_path / "grow.csv"
    p.write_text("\n".join(lines) + "\n")
    _compare(p, expect_fast=True)


class _Recording(Progress):
    def __init__(self) -> None:
        super().__init__(None, "rec", enabled=False)
        self.seen: list[float] = []

    def update(self, done: float) -> None:
        self.seen.append(done)


def test_progress_reports_bytes_up_to_the_file_size(tmp_path):
    p = tmp_path / "p.csv"
    p.write_text("\n".join(_base(3000)) + "\n")
    rec = _Recording()
    table = _read(p, True, rec)
    assert _arrowcsv.last_outcome == "fast"
    assert rec.total == p.stat().st_size
    assert len(rec.seen) > 3 and rec.seen == sorted(rec.seen) and rec.seen[-1] == table.size == p.stat().st_size
