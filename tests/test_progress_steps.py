"""The main job's step events and the terminal display built on them (sigmatau analyze on a TTY)."""

import io
import threading

import numpy as np
import pytest

from sigmatau.analysis import STEP_COST, StepEvent, analyze_log, log_from_arrays


def _log(names=("gyro_x", "gyro_y", "temp")):
    rng = np.random.default_rng(8)
    chans = {n: rng.standard_normal(4000) * 1e-3 for n in names}
    return log_from_arrays(chans, rate=100.0, units={n: ("rad/s" if n.startswith("gyro") else "") for n in names},
                           groups={"gyro": [n for n in names if n.startswith("gyro")],
                                   "other": [n for n in names if not n.startswith("gyro")]})


@pytest.mark.parametrize("workers", [1, 2])
def test_every_step_starts_and_ends_and_the_weights_add_up(workers):
    events, lock = [], threading.Lock()

    def on_step(ev):
        with lock:
            events.append(ev)

    analyze_log(_log(), workers=workers, on_step=on_step)
    assert all(isinstance(e, StepEvent) for e in events)
    starts = [(e.channel, e.step) for e in events if not e.done]
    ends = [(e.channel, e.step) for e in events if e.done]
    assert sorted(starts) == sorted(ends) and len(set(ends)) == len(ends)
    # gyro channels: the model then six statistics; the other channel: six statistics, no model
    assert {s for c, s in ends if c == "gyro_x"} == {"model", "oadev", "mdev", "tdev", "ohdev", "totdev", "theoh"}
    assert {s for c, s in ends if c == "temp"} == {"oadev", "mdev", "tdev", "ohdev", "totdev", "theoh"}
    total = events[0].total
    assert all(e.total == total for e in events)
    assert sum(e.weight for e in events if e.done) == pytest.approx(total)
    # OADEV of a gyro comes with its model and TDEV from MDEV: nearly free; the rest cost what was measured
    w = {(e.channel, e.step): e.weight for e in events}
    assert w[("gyro_x", "oadev")] < 0.1 and w[("temp", "oadev")] == STEP_COST["oadev"]
    assert w[("gyro_x", "tdev")] < 0.1 and w[("gyro_x", "model")] == STEP_COST["model"]


class _Tty(io.StringIO):
    def isatty(self):
        return True


def test_the_terminal_display_shows_the_steps_and_the_time_left(monkeypatch):
    pytest.importorskip("tqdm")
    from sigmatau.cli import common

    err = _Tty()
    monkeypatch.setattr(common.sys, "stderr", err)
    monkeypatch.setattr(common._StepDisplay, "MININTERVAL", 0.0)  # draw at every step of this short job
    console = common._Console(quiet=False)
    assert console.tty
    display = common._StepDisplay(console)
    hostile = "gyro_\x1b[2Jx"
    log = log_from_arrays({hostile: np.random.default_rng(1).standard_normal(3000)}, rate=50.0,
                          units={hostile: "rad/s"}, groups={"gyro": [hostile]})
    analyze_log(log, workers=1, on_step=display.event, progress=display.line)
    display.close()
    text = err.getvalue()
    assert "analysing" in text and "left" in text and "100%" in text
    assert "\x1b[2J" not in text and "gyro_\\x1b[2Jx" in text  # the name escaped, never sent to the terminal
    assert "IMU model" in text


def test_no_display_when_quiet_or_not_a_terminal(monkeypatch):
    from sigmatau.cli import common

    err = _Tty()
    monkeypatch.setattr(common.sys, "stderr", err)
    assert not common._StepDisplay(common._Console(quiet=True)).enabled
    monkeypatch.setattr(common.sys, "stderr", io.StringIO())
    quiet = common._StepDisplay(common._Console(quiet=False))
    assert not quiet.enabled
    quiet.event(StepEvent("a", "oadev", False, 1.0, 2.0))  # nothing drawn, nothing raised
    assert common.sys.stderr.getvalue() == ""


def test_default_workers_fit_in_the_memory_available(monkeypatch):
    from sigmatau.errors import SigmaTauWarning
    from sigmatau.pipeline import analysis

    monkeypatch.setattr(analysis.os, "sched_getaffinity", lambda pid: {0, 1, 2, 3}, raising=False)
    gib = 2**30
    monkeypatch.setattr(analysis, "available_memory", lambda: 100.0 * gib)
    assert analysis._worker_count(None, 6, gib) == 4  # plenty: the cores
    monkeypatch.setattr(analysis, "available_memory", lambda: 10.0 * gib)
    assert analysis._worker_count(None, 6, gib) == 2  # 4.5 GiB per worker
    assert analysis._worker_count(3, 6, gib) == 3  # an explicit request stands
    monkeypatch.setattr(analysis, "available_memory", lambda: 1.0 * gib)
    with pytest.warns(SigmaTauWarning, match=r"needs about 4\.5 GiB .* 1\.0 GiB are available.*--memory chunked"):
        assert analysis._worker_count(None, 6, gib) == 1
    monkeypatch.setattr(analysis, "available_memory", lambda: None)  # unknown: the cores
    assert analysis._worker_count(None, 6, gib) == 4
    # the main job itself: the log's channels sized, the setting recorded
    monkeypatch.setattr(analysis, "available_memory", lambda: 4.6 * 8 * 4000.0)
    a = analyze_log(_log(), statistics=("oadev",), model=False)
    assert a.settings["workers"] == 1


def test_available_memory_reads_meminfo():
    from sigmatau.pipeline.analysis import available_memory

    avail = available_memory()
    assert avail is None or avail > 2**20


@pytest.mark.slow
def test_sigmatau_analyze_draws_the_bar_on_a_real_pseudo_terminal(tmp_path):
    # A fresh pty reports a size of 0 × 0, as under `script` and some CI runners: tqdm left to
    # itself draws nothing there. stderr on the pty, stdout on a pipe, as a user's `> out.txt`.
    pytest.importorskip("tqdm")
    import os
    import pty
    import subprocess
    import sys

    rng = np.random.default_rng(4)
    log = tmp_path / "log.npz"
    np.savez(log, gyro_x=rng.standard_normal(200_000) * 1e-3, gyro_y=rng.standard_normal(200_000) * 1e-3,
             rate=np.array(200.0))
    master, slave = pty.openpty()
    proc = subprocess.Popen([sys.executable, "-m", "sigmatau", "analyze", str(log), "--out", str(tmp_path / "o"),
                             "--no-figures", "--gyro-unit", "rad/s"], stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=slave, cwd=tmp_path)
    os.close(slave)
    chunks = []
    while True:
        try:
            data = os.read(master, 65536)
        except OSError:  # EIO: the child closed its end
            break
        if not data:
            break
        chunks.append(data)
    proc.stdout.read()
    proc.stdout.close()
    assert proc.wait(timeout=300) == 0
    os.close(master)
    text = b"".join(chunks).decode("utf-8", "replace")
    assert "analysing" in text and "left" in text and "gyro_x" in text
