"""``sigmatau watch``: a log followed while it is written, its live view, and the final outputs.

A writer subprocess appends a simulated 1 kHz IMU log (``sigmatau simulate`` output) in chunks cut
anywhere — so the watcher sees a partial last line most of the time — while ``sigmatau watch``
follows it; the final ``results.json`` is compared with ``sigmatau analyze`` on the finished file.
The default tests use a few seconds of a 3-axis gyro; the long run with the live page, figures and
memory is marked slow.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from helpers import assert_one_line_error, headless_chromium, run_cli

from sigmatau.cli import main

WRITER = r'''
import os, sys, time
src, dst, mode, seconds = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
data = open(src, "rb").read()
cut = data.index(b"\n") + 1
header, body = data[:cut], data[cut:]
fh = open(dst, "ab", buffering=0)
if fh.tell() == 0:  # else the test wrote the header and started the watcher first
    fh.write(header)
step = 0.05
chunk = max(1, int(len(body) / (seconds / step)))
pos, switched = 0, False
while pos < len(body):
    if not switched and pos >= len(body) // 2 and mode != "plain":
        switched = True
        end = body.index(b"\n", pos) + 1  # a logger rotates or truncates between lines
        fh.write(body[pos:end])
        pos = end
        if mode == "truncate":
            fh.truncate(0); fh.seek(0); fh.write(header)
        elif mode == "rotate":
            fh.close(); os.replace(dst, dst + ".1"); fh = open(dst, "wb", buffering=0); fh.write(header)
        elif mode.startswith("stall"):
            time.sleep(float(mode[5:]))
    fh.write(body[pos:pos + chunk])  # cut anywhere: a partial last line most of the time
    pos += chunk
    time.sleep(step)
fh.close()
'''


def _sigmatau(*args: object) -> list[str]:
    return [sys.executable, "-m", "sigmatau", *map(str, args)]


@pytest.fixture(scope="module")
def gyro(tmp_path_factory) -> Path:
    """4 s of a 3-axis gyro at 1 kHz (4,000 rows), as ``sigmatau simulate`` writes it."""
    folder = tmp_path_factory.mktemp("watch-src")
    path = folder / "gyro.csv"
    assert main(["simulate", str(path), "--preset", "lsm6dsl", "--sensors", "gyro", "--rate", "1000",
                 "--duration", "4", "--seed", "7"]) == 0
    (folder / "writer.py").write_text(WRITER)
    return path


def _start_writer(src: Path, dst: Path, mode: str = "plain", seconds: float = 2.0) -> subprocess.Popen:
    p = subprocess.Popen([sys.executable, str(src.parent / "writer.py"), str(src), str(dst), mode, str(seconds)])
    for _ in range(200):
        if dst.exists():
            break
        time.sleep(0.02)
    return p


def _watch_then_write(tmp_path: Path, src: Path, mode: str, seconds: float, *args: object
                      ) -> tuple[subprocess.Popen, Path, Path]:
    """The watcher started on a file holding the header, then — once it serves its page, so it has
    the file open — the writer appending the rest; returns the watcher, its stderr and the file."""
    live = tmp_path / "live.csv"
    live.write_bytes(src.read_bytes().split(b"\n", 1)[0] + b"\n")
    p, _, err = _watch(tmp_path, live, "--serve", 0, *args)
    _url(err)
    writer = _start_writer(src, live, mode, seconds)
    writer.wait(timeout=120)
    return p, err, live


def _watch(cwd: Path, *args: object, stdin=None) -> tuple[subprocess.Popen, Path, Path]:
    out, err = cwd / f"watch-{time.monotonic_ns()}.out", cwd / f"watch-{time.monotonic_ns()}.err"
    with open(out, "wb") as fo, open(err, "wb") as fe:
        p = subprocess.Popen(_sigmatau("watch", *args), cwd=cwd, stdout=fo, stderr=fe,
                             stdin=stdin if stdin is not None else subprocess.DEVNULL)
    return p, out, err


def _done(p: subprocess.Popen, err: Path, timeout: float = 120) -> str:
    assert p.wait(timeout=timeout) == 0, err.read_text(errors="replace")
    text = err.read_text(encoding="utf-8")
    assert "Traceback" not in text
    return text


def _analyze(log: Path, out: Path, *extra: str) -> dict:
    r = subprocess.run(_sigmatau("analyze", log, "--out", out, "--quiet", *extra), capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    return json.loads((out / "results.json").read_text(encoding="utf-8"))


def _manifest_names(out: Path) -> set:
    return {f["name"] for f in json.loads((out / "sigmatau-manifest.json").read_text())["files"]}


def _results(out: Path) -> dict:
    return json.loads((out / "results.json").read_text(encoding="utf-8"))


def assert_same_statistics(a: dict, b: dict, rtol: float = 1e-12) -> float:
    """Every statistic (τ, n, α, var, dev, EDF, interval) and model term of two results.json agree to
    ``rtol``; returns the largest relative difference seen."""
    worst = 0.0
    assert [c["name"] for c in a["channels"]] == [c["name"] for c in b["channels"]]
    assert a["log"]["n_samples"] == b["log"]["n_samples"]
    for ca, cb in zip(a["channels"], b["channels"]):
        assert ca["statistics"].keys() == cb["statistics"].keys()
        pairs = []
        for stat, rb in cb["statistics"].items():
            ra = ca["statistics"][stat]
            for key in ("taus", "m", "n", "alpha", "var", "dev", "edf", "ci_low", "ci_high"):
                pairs.append((ra.get(key), rb.get(key)))
        if cb["model"] is not None:
            for term in "QNBKR":
                for key in ("value", "low", "high"):
                    pairs.append(([ca["model"]["parameters"][term][key]], [cb["model"]["parameters"][term][key]]))
        for xa, xb in pairs:
            assert (xa is None) == (xb is None)
            if xa is None:
                continue
            fa = np.array([np.nan if v is None else v for v in xa], dtype=float)
            fb = np.array([np.nan if v is None else v for v in xb], dtype=float)
            np.testing.assert_array_equal(np.isnan(fa), np.isnan(fb))
            ok = ~np.isnan(fb)
            rel = np.abs(fa[ok] - fb[ok]) / np.maximum(np.abs(fb[ok]), 1e-300)
            worst = max(worst, float(rel.max(initial=0.0)))
    assert worst <= rtol, worst
    return worst


# ------------------------------------------------------------------------------------- following


@pytest.mark.slow
def test_followed_file_equals_analyze_of_the_finished_file(gyro, tmp_path):
    """Chunks cut mid-line: no line is parsed before its newline; the record is the file, byte for byte."""
    p, err, live = _watch_then_write(tmp_path, gyro, "plain", 2.0, "--until-idle", 1.5, "--out", "out",
                                     "--no-figures", "--no-report")
    text = _done(p, err)
    assert "no new data for 1.5 s" in text and "left out" not in text
    a, b = _results(tmp_path / "out"), _analyze(live, tmp_path / "ref", "--no-figures", "--no-report")
    assert a["input"]["sha256"] == b["input"]["sha256"]  # the record is the file
    assert a["input"]["path"] == b["input"]["path"] == str(live)
    assert_same_statistics(a, b)
    assert live.read_bytes() == gyro.read_bytes()  # only read


@pytest.mark.slow
def test_a_last_line_without_newline(gyro, tmp_path, capsys):
    """At the end of input an unfinished last line is parsed (as analyze does); when the run is
    stopped (--duration) it is left out, saying so."""
    cut = tmp_path / "cut.csv"
    cut.write_bytes(gyro.read_bytes().rstrip(b"\n"))
    code, _, err = run_cli(["watch", cut, "--until-idle", "0.5", "--out", tmp_path / "a", "--no-figures",
                            "--no-report", "--quiet"], capsys)
    assert code == 0, err
    assert _results(tmp_path / "a")["log"]["n_samples"] == 4000
    code, _, err = run_cli(["watch", cut, "--duration", "0.8", "--out", tmp_path / "b", "--no-figures",
                            "--no-report", "--quiet"], capsys)
    assert code == 0, err
    assert "unfinished last line" in err and "--duration 0.8 s reached" in err
    assert _results(tmp_path / "b")["log"]["n_samples"] == 3999


@pytest.mark.slow
def test_truncated_file_is_read_again_from_its_start(gyro, tmp_path):
    p, err, _ = _watch_then_write(tmp_path, gyro, "truncate", 2.0, "--until-idle", 1.5, "--out", "out",
                                  "--no-figures", "--no-report")
    text = _done(p, err)
    assert re.search(r"live\.csv shrank from [\d,]+ to [\d,]+ bytes \(truncated\): reading its new content from"
                     r" the start", text), text
    n = _results(tmp_path / "out")["log"]["n_samples"]
    # what was written between the last read and the truncation is lost (a gap says so)
    assert 3000 < n <= 4000
    assert n == 4000 or "gap of" in text


@pytest.mark.slow
def test_rotated_file_is_followed_without_losing_a_line(gyro, tmp_path):
    p, err, _ = _watch_then_write(tmp_path, gyro, "rotate", 2.0, "--until-idle", 1.5, "--out", "out",
                                  "--no-figures", "--no-report")
    text = _done(p, err)
    assert "was replaced by a new file (rotation)" in text
    a = _results(tmp_path / "out")
    b = _analyze(gyro, tmp_path / "ref", "--no-figures", "--no-report")
    # the old file's rest, then the new file without its header: the record is the simulated log
    assert a["input"]["sha256"] == b["input"]["sha256"]
    assert_same_statistics(a, b)


@pytest.mark.slow
def test_a_stalled_writer_is_waited_for(gyro, tmp_path):
    p, err, live = _watch_then_write(tmp_path, gyro, "stall1.5", 2.0, "--until-idle", 2.5, "--out", "out",
                                     "--no-figures", "--no-report")
    _done(p, err)
    assert_same_statistics(_results(tmp_path / "out"),
                           _analyze(live, tmp_path / "ref", "--no-figures", "--no-report"))


@pytest.mark.slow
def test_standard_input_through_a_pipe(gyro, tmp_path):
    cat = subprocess.Popen(["cat", str(gyro)], stdout=subprocess.PIPE)
    p, _, err = _watch(tmp_path, "-", "--out", "out", "--no-figures", "--no-report", stdin=cat.stdout)
    cat.stdout.close()
    text = _done(p, err)
    assert cat.wait(timeout=10) == 0
    assert "end of input" in text
    a, b = _results(tmp_path / "out"), _analyze(gyro, tmp_path / "ref", "--no-figures", "--no-report")
    assert a["input"]["path"] == "<stdin>" and a["input"]["sha256"] == b["input"]["sha256"]
    assert_same_statistics(a, b)


def test_a_refused_stream_keeps_what_it_received(tmp_path):
    """Standard input cannot be read again: when a policy refuses it, the lines received are kept
    beside the output directory and the one-line error says where."""
    t = np.arange(400) / 100.0
    log = _timed(tmp_path / "back.csv", np.concatenate([t[:300], t[250:251], t[300:]]))
    with open(log, "rb") as stdin:
        r = subprocess.run(_sigmatau("watch", "-", "--unsorted", "refuse", "--out", "out"), cwd=tmp_path,
                           stdin=stdin, capture_output=True, text=True, timeout=60)
    line = assert_one_line_error(r, code=1, match=r"goes backwards at sample 300 .*the record received is kept in")
    kept = Path(line.rsplit(" kept in ", 1)[1])
    assert kept == tmp_path / "out-record.txt" and kept.read_bytes() == log.read_bytes()
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
def test_a_fifo_is_read_once(gyro, tmp_path):
    fifo = tmp_path / "imu.fifo"
    os.mkfifo(fifo)
    p, _, err = _watch(tmp_path, fifo, "--out", "out", "--no-figures", "--no-report")
    with open(fifo, "wb") as fh:
        fh.write(gyro.read_bytes())
    _done(p, err)
    assert_same_statistics(_results(tmp_path / "out"), _analyze(gyro, tmp_path / "ref", "--no-figures", "--no-report"))


@pytest.mark.slow
def test_sigint_mid_run_writes_complete_outputs(gyro, tmp_path):
    live = tmp_path / "live.csv"
    writer = _start_writer(gyro, live, "plain", 5.0)
    p, _, err = _watch(tmp_path, live, "--out", "out")
    time.sleep(2.5)
    p.send_signal(signal.SIGINT)
    text = _done(p, err)
    writer.wait(timeout=60)
    assert "interrupted (Ctrl-C)" in text
    out = tmp_path / "out"
    manifest = json.loads((out / "sigmatau-manifest.json").read_text())
    assert {f["name"] for f in manifest["files"]} >= {"results.json", "statistics.csv", "model.csv", "report.html",
                                                       "sigma_tau_gyro.png", "signal_gyro_x.svg"}
    assert 500 < _results(out)["log"]["n_samples"] < 4000
    assert not [q for q in tmp_path.iterdir() if ".partial-" in q.name]  # the record's folder is gone
    assert live.read_bytes() == gyro.read_bytes()  # the watched file was only read


# ------------------------------------------------------------------------------ serial and ROS 2


def test_missing_serial_extra_is_one_line(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "serial", None)  # import serial → ImportError
    code, _, err = run_cli(["watch", "serial:///dev/ttyUSB0?baud=115200", "--out", "never"], capsys)
    line = assert_one_line_error((code, err), code=1, match=r"pip install 'sigmatau\[serial\]'")
    assert "pyserial" in line


def test_bad_serial_port_is_one_line(capsys, tmp_path):
    pytest.importorskip("serial")
    code, _, err = run_cli(["watch", "--serial", tmp_path / "no-such-port", "--out", tmp_path / "o"], capsys)
    assert_one_line_error((code, err), code=1, match="cannot open serial port")
    code, _, err = run_cli(["watch", "serial:///dev/ttyS0?baud=fast", "--out", tmp_path / "o"], capsys)
    assert_one_line_error((code, err), code=2, match="baud='fast' must be an integer")
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
@pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs a pseudo-terminal")
def test_serial_port_through_a_pty(gyro, tmp_path):
    pytest.importorskip("serial")
    import tty

    master, slave = os.openpty()
    tty.setraw(slave)
    port = os.ttyname(slave)
    p, _, err = _watch(tmp_path, f"serial://{port}?baud=115200", "--until-idle", 1.5, "--out", "out",
                       "--no-figures", "--no-report", "--save", "received.csv")
    time.sleep(1.5)
    data = gyro.read_bytes()
    for i in range(0, len(data), 8192):
        os.write(master, data[i:i + 8192])
        time.sleep(0.005)
    text = _done(p, err)
    os.close(master)
    os.close(slave)
    assert "4,000 samples received" in text
    assert (tmp_path / "received.csv").read_bytes() == data
    assert_same_statistics(_results(tmp_path / "out"), _analyze(gyro, tmp_path / "ref", "--no-figures", "--no-report"))


def test_ros2_without_rclpy_is_one_line(capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "rclpy", None)
    code, _, err = run_cli(["watch", "ros2:/imu/data", "--out", "never"], capsys)
    assert_one_line_error((code, err), code=1, match="needs rclpy .* ROS 2 installation")


# ---------------------------------------------------------------------------------- timing policies


def _timed(path: Path, t: np.ndarray) -> Path:
    rng = np.random.default_rng(3)
    rows = "".join(f"{ti!r},{v!r}\n" for ti, v in zip(t.tolist(), rng.standard_normal(t.size).tolist()))
    path.write_text("time,gyro_x\n" + rows)
    return path


@pytest.mark.slow
def test_policies_are_those_of_analyze(tmp_path, capsys):
    t = np.arange(3000) / 100.0
    back = _timed(tmp_path / "back.csv", np.concatenate([t[:2000], t[1990:1991], t[2000:]]))
    code, _, err = run_cli(["watch", back, "--until-idle", "0.3", "--unsorted", "refuse", "--out", tmp_path / "o"],
                           capsys)
    assert_one_line_error((code, err), code=1, match=r"timestamp goes backwards at sample 2000 .*--unsorted sort")
    assert not (tmp_path / "o").exists()
    gaps = _timed(tmp_path / "gaps.csv", np.concatenate([t[:1000], t[1003:]]))
    code, _, err = run_cli(["watch", gaps, "--until-idle", "0.3", "--out", tmp_path / "g", "--no-figures",
                            "--no-report"], capsys)
    assert code == 0, err
    assert re.search(r"gap of 0\.04 s before sample 1000 .*3 samples missing", err), err
    ref = _analyze(gaps, tmp_path / "gref", "--no-figures", "--no-report")
    assert_same_statistics(_results(tmp_path / "g"), ref)


def test_live_timing_marks_holds_and_counts():
    from sigmatau.io.liveparse import LiveTiming

    timing = LiveTiming(unit="s", measured_rate=10.0, gaps="auto", gap_threshold=1.5, unsorted="sort",
                        duplicates="drop", display="x")
    raw = np.array([0.0, 0.1, 0.2, 0.5, 0.6, 0.6, 0.55, 1.4, 1.5])
    values = np.arange(raw.size, dtype=float)[:, None]
    out, notices = timing.feed(raw[:5], values[:5])
    np.testing.assert_array_equal(out[:, 0], [0, 1, 2, 2, 2, 3, 4])  # a 2-sample gap holds the sample before
    out, notices = timing.feed(raw[5:], values[5:])
    assert np.isnan(out[:7, 0]).all() and out[7:, 0].tolist() == [7.0, 8.0]  # a 7-sample gap: NaN
    kinds = {k for k, _ in notices}
    assert kinds == {"backwards", "duplicate", "gap"}
    s = timing.summary()
    assert (s["out_of_order"], s["duplicates"], s["gaps"], s["missing"], s["held"]) == (1, 1, 2, 9, 2)


def test_line_splitter_holds_an_unfinished_line():
    from sigmatau.io.follow import LineSplitter, Poll

    split, poll = LineSplitter(), Poll()
    split.feed(b"a,b\n1,2\n3,", poll)
    split.feed(b"4", poll)
    assert poll.lines == [b"a,b\n", b"1,2\n"]
    split.feed(b"\n5", poll)
    assert poll.lines[-1] == b"3,4\n" and split.rest() == b"5"


# ------------------------------------------------------------------------------ hostile input, page

HOSTILE = ["time", "\x1b]0;owned\x07\x1b[2Jesc", "<img src=x onerror=alert(1)>", "=cmd|' /C calc'!A0",
           "\u202eevil"]


def _hostile_log(path: Path, rows: int = 3000) -> None:
    rng = np.random.default_rng(11)
    with open(path, "w", encoding="utf-8", newline="") as fh:
        fh.write(",".join(HOSTILE) + "\n")
        for i in range(rows):
            fh.write(",".join([repr(i / 100.0)] + [repr(v) for v in rng.standard_normal(4).tolist()]) + "\n")


def _get(url: str, host: str | None = None) -> tuple[int, dict, bytes, float]:
    req = urllib.request.Request(url, headers={"Host": host} if host else {})
    t0 = time.perf_counter()
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            return r.status, dict(r.headers), r.read(), time.perf_counter() - t0
    except urllib.error.HTTPError as exc:
        return exc.code, dict(exc.headers), exc.read(), time.perf_counter() - t0


def _url(err: Path, timeout: float = 30) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        m = re.search(r"live view at (http://127\.0\.0\.1:\d+/)", err.read_text(errors="replace"))
        if m:
            return m.group(1)
        time.sleep(0.05)
    raise AssertionError(err.read_text(errors="replace"))


@pytest.mark.slow
@pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs a pseudo-terminal")
def test_hostile_column_names_are_escaped_everywhere(tmp_path):
    """Names with terminal escapes, markup, a formula and a bidi override: escaped on the terminal
    (a pty, so the live table is drawn), only text on the page, and in the files as analyze writes them."""
    log = tmp_path / "hostile.csv"
    _hostile_log(log)
    master, slave = os.openpty()
    p = subprocess.Popen(_sigmatau("watch", log, "--until-idle", 3, "--refresh", 0.3, "--serve", 0, "--out", "out",
                                   "--no-figures"), cwd=tmp_path, stdin=subprocess.DEVNULL,
                         stdout=subprocess.DEVNULL, stderr=slave)
    os.close(slave)
    seen = b""
    url = None
    deadline = time.monotonic() + 60
    data = None
    while time.monotonic() < deadline:
        try:
            block = os.read(master, 65536)
        except OSError:  # the watcher closed the terminal
            break
        if not block:
            break
        seen += block
        m = re.search(rb"live view at (http://127\.0\.0\.1:\d+/)", seen)
        if m and url is None:
            url = m.group(1).decode()
        if url and data is None:
            code, _, body, _ = _get(url + "data.json")
            snap = json.loads(body)
            if snap["channels"]:
                data = snap
                page = _get(url)[2].decode()
    assert p.wait(timeout=60) == 0
    os.close(master)
    text = seen.decode("utf-8", errors="replace")
    ours = re.sub(r"\x1b\[\d+F\x1b\[J", "", text)  # the table's own redraw
    ours = re.sub(r"\x1b\[[0-9;?]*[A-Za-z]|\r", "", ours)  # tqdm's bar of the final analysis
    assert not re.search(r"[\x00-\x08\x0b-\x1f\x7f\u202a-\u202e\u2066-\u2069]", ours), repr(ours[:2000])
    assert "\\x1b]0;owned\\x07" in text and "\\u202eevil" in text
    assert data is not None, text
    assert [c["name"] for c in data["channels"]] == HOSTILE[1:]
    assert "owned" not in page and "onerror" not in page  # the page holds no data, only its script
    out = tmp_path / "out"
    stats = (out / "statistics.csv").read_text(encoding="utf-8")
    assert "'=cmd|" in stats and "\n=cmd" not in stats and ",=cmd" not in stats
    report = (out / "report.html").read_text(encoding="utf-8")
    assert "<img src=x" not in report and "&lt;img src=x onerror=alert(1)&gt;" in report
    assert [c["name"] for c in _results(out)["channels"]] == HOSTILE[1:]


def test_server_is_local_self_contained_and_checks_the_host():
    from sigmatau.report.live import LiveServer, LiveState, PAGE, snapshot

    state = LiveState()
    state.publish(snapshot([], source="<b>x</b>", status="running", samples=0, rate=None))
    server = LiveServer(state, 0)
    try:
        assert server.url.startswith("http://127.0.0.1:") and server.httpd.server_address[0] == "127.0.0.1"
        code, headers, body, _ = _get(server.url)
        assert code == 200 and body == PAGE
        csp = headers["Content-Security-Policy"]
        assert "default-src 'none'" in csp and "connect-src 'self'" in csp and "unsafe-inline" not in csp
        assert headers["X-Content-Type-Options"] == "nosniff"
        # no external URL: the only one is SVG's namespace name, which is never fetched
        assert set(re.findall(rb"https?://[^\s\"'<>]+", body)) == {b"http://www.w3.org/2000/svg"}
        assert b"innerHTML" not in body and b"eval(" not in body
        code, headers, body, _ = _get(server.url + "data.json")
        assert code == 200 and headers["Content-Type"] == "application/json"
        assert json.loads(body)["source"] == "<b>x</b>"
        assert _get(server.url + "data.json", host="evil.example:80")[0] == 403  # DNS rebinding
        assert _get(server.url + "../etc/passwd")[0] == 404
    finally:
        server.close()


def test_usage_errors_are_one_line(tmp_path, capsys, gyro):
    for argv, match in (
        (["watch", "--out", tmp_path / "o"], "give a SOURCE"),
        (["watch", gyro, "--format", "npy"], "reads csv or stable32"),
        (["watch", gyro, "--topic", "/imu"], "ros2:/TOPIC"),
        (["watch", gyro, "--until-idle", "0"], "--until-idle 0.0 must be a positive"),
        (["watch", gyro, "--serve", "70000"], "--serve 70000 must be a port number"),
        (["watch", gyro, "--serve", "x"], "not a port number"),
        (["watch", gyro, "--save", gyro], "is the watched file"),
    ):
        code, _, err = run_cli(argv, capsys)
        assert_one_line_error((code, err), code=2, match=match)
    code, _, err = run_cli(["watch", tmp_path / "missing.csv"], capsys)
    assert_one_line_error((code, err), code=1, match="no such file")


# -------------------------------------------------------------------------------- the long run


def _vm(pid: int, key: str) -> int:
    """A memory figure of a running process in KiB (/proc/PID/status), 0 once it is gone."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith(key + ":"):
                return int(line.split()[1])
    except OSError:
        pass
    return 0


def _reap(p: subprocess.Popen, block: bool) -> int | None:
    """The peak resident memory (KiB, from wait4's rusage) of a finished child, None while it runs."""
    pid, status, usage = os.wait4(p.pid, 0 if block else os.WNOHANG)
    if pid == 0:
        return None
    p.returncode = os.waitstatus_to_exitcode(status)
    return usage.ru_maxrss


#: The watcher's peak resident memory may exceed that of `sigmatau analyze` on the finished file by
#: this much: the streams are released before the final analysis (the peak), what remains is the
#: page's server and the live models (measured 2026-11-28: 28–58 MiB here, 33 MiB on a 10-minute log).
EXTRA_MIB = 96
#: Growth of the watcher's resident memory allowed over the second half of the writer's run, its
#: streams full (the record goes to disk): the live phase holds nothing that grows with the record
#: (measured 2026-11-28: 0–3 MiB; on a 600,000-row log read from its start, flat at 150 MiB).
GROWTH_MIB = 16


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/status").exists() or not hasattr(os, "wait4"), reason="Linux /proc, wait4")
def test_live_page_during_a_run_and_the_same_outputs_as_analyze(tmp_path):
    src = tmp_path / "imu.csv"
    assert main(["simulate", str(src), "--preset", "lsm6dsl", "--rate", "1000", "--duration", "15",
                 "--seed", "3"]) == 0
    (tmp_path / "writer.py").write_text(WRITER)
    live = tmp_path / "live.csv"
    writer = _start_writer(src, live, "plain", 12.0)
    # --live-max-tau 4: the streams (4,096 samples: every τ of this 15 s log) fill within seconds,
    # so the resident memory of the live phase shows whether anything grows with the record
    p, _, err = _watch(tmp_path, live, "--serve", 0, "--until-idle", 2, "--out", "out", "--live-max-tau", 4)
    url = _url(err)
    samples, latencies, rss, snaps, snap, peak = [], [], [], [], None, None
    while peak is None:
        if writer.poll() is None:
            code, _, body, seconds = _get(url + "data.json")
            assert code == 200
            latencies.append(seconds)
            snap = json.loads(body)
            snaps.append(snap)
            samples.append(snap["samples"])
            if snap["channels"] and snap["channels"][0]["model"]:
                rss.append(_vm(p.pid, "VmRSS"))
        time.sleep(0.5)
        peak = _reap(p, block=False)
    assert p.returncode == 0, err.read_text()
    assert samples[-1] > samples[0] and snap["channels"][0]["model"]  # the page followed the record
    assert "oadev" in snap["channels"][0]["statistics"] and snap["channels"][0]["advice"]
    assert max(latencies) < 1.0, latencies
    ref = subprocess.Popen(_sigmatau("analyze", live, "--out", tmp_path / "ref", "--quiet"), stdout=subprocess.DEVNULL)
    ref_peak = _reap(ref, block=True)
    assert ref.returncode == 0
    a, b = _results(tmp_path / "out"), _results(tmp_path / "ref")
    assert a["input"]["sha256"] == b["input"]["sha256"]
    worst = assert_same_statistics(a, b)
    assert _manifest_names(tmp_path / "out") == _manifest_names(tmp_path / "ref")
    live_mib = max(s["live_bytes"] for s in snaps) / 2**20
    assert peak / 1024 <= ref_peak / 1024 + EXTRA_MIB, (peak, ref_peak, live_mib)
    half = rss[len(rss) // 2:]
    assert (max(half) - half[0]) / 1024 < GROWTH_MIB, rss
    print(f"\nlive page latency: median {1e3 * np.median(latencies):.1f} ms, max {1e3 * max(latencies):.1f} ms"
          f" over {len(latencies)} requests; peak memory: watcher {peak / 1024:.0f} MiB (live statistics"
          f" {live_mib:.0f} MiB), analyze {ref_peak / 1024:.0f} MiB; watcher RSS from the first live model to the"
          f" end of the writer {rss[0] / 1024:.0f} -> {rss[-1] / 1024:.0f} MiB (second half"
          f" {half[0] / 1024:.0f} -> {max(half) / 1024:.0f}); largest relative difference of the statistics"
          f" {worst:.1e}")


def _browser():
    return headless_chromium()


def test_live_page_draws_hostile_data_as_text_in_a_browser():
    """The page in headless Chromium: curves and table drawn from data.json, every name shown as
    text (no element, no script from it), no error, no request but to the server itself."""
    import sigmatau
    from sigmatau.imu import analyze, simulate
    from sigmatau.report.live import LiveChannel, LiveServer, LiveState, snapshot

    y = simulate("euroc-gyro", duration=300.0, rng=5)
    oadev = sigmatau.oadev(y, rate=200.0)
    with pytest.warns(sigmatau.imu.ImuWarning):
        model = analyze(oadev, unit="rad/s")
    names = ["<img src=x onerror=alert(1)>", "</script><script>alert(2)</script>", "\u202egyro"]
    chans = [LiveChannel(n, "gyro", "rad/s", {"oadev": oadev}, model, "N known to ±1 % <b>bold</b>") for n in names]
    state = LiveState()
    state.publish(snapshot(chans, source="<i>src</i>", status="running", samples=len(y), rate=200.0,
                           notices=[{"kind": "gap", "text": "<svg onload=alert(3)>", "time": 0.0}]))
    server = LiveServer(state, 0, refresh=0.5)
    driver = _browser()
    try:
        driver.get(server.url)
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline and not driver.find_elements("css selector", "svg polyline"):
            time.sleep(0.1)
        body = driver.find_element("css selector", "body").text
        assert all(n in body for n in names) and "<i>src</i>" in body and "<svg onload=alert(3)>" in body
        assert driver.execute_script("return document.querySelectorAll('img, script, i, b').length") == 1  # ours
        assert len(driver.find_elements("css selector", "svg polyline")) == 2 * len(names)  # curve and model
        assert len(driver.find_elements("css selector", "svg polygon")) == len(names)  # interval bands
        problems = [e for e in driver.get_log("browser") if e.get("level") in ("SEVERE", "WARNING")]
        assert problems == []
        urls = {json.loads(e["message"])["message"]["params"]["request"]["url"]
                for e in driver.get_log("performance")
                if json.loads(e["message"])["message"].get("method") == "Network.requestWillBeSent"}
        assert urls and all(u.startswith(server.url) for u in urls), urls
    finally:
        driver.quit()
        server.close()
