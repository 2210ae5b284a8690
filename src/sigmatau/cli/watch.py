"""``sigmatau watch SOURCE``: σ–τ and the IMU noise terms while a log is being recorded, then the full analysis.

The run, as named steps:

1. **Inputs** — a growing file followed like ``tail -F`` (rotation and truncation survived: its new
   content is read from the start, its header skipped), standard input (``-``), a serial port
   (``serial:///dev/ttyUSB0?baud=115200`` or ``--serial PORT --baud N``; extra ``serial``) or a
   ROS 2 ``sensor_msgs/Imu`` topic (``ros2:/imu/data``, rclpy): :mod:`sigmatau.io.follow`.
2. **Lines** — parsed as ``sigmatau analyze`` parses the file (same header, column, unit and time
   recognition), timestamps checked as they come with the same policies (``--gaps``,
   ``--unsorted``, ``--duplicates``), every accepted line appended to the record, a copy kept in a
   marked folder beside ``--out``: :mod:`sigmatau.io.liveparse`.
3. **Live statistics** — in a thread, one :class:`sigmatau.stream.Stream` per channel
   (:func:`_live_engine`; memory bounded by the longest τ, ``--live-max-tau``), the IMU model and
   the recording advice (:func:`_advice`), every ``--refresh`` seconds (less often when the
   computation takes longer: at most half of the time is spent computing).
4. **Live view** — a table on a terminal (plain lines otherwise, none with ``--quiet``), one line
   per notice (rate-limited), and with ``--serve`` a page on 127.0.0.1: :mod:`sigmatau.report.live`.
5. **End** — Ctrl-C, SIGTERM, ``--duration``, end of input or ``--until-idle``: the record is read
   by the reader of :func:`sigmatau.io.read` and goes through the very job of ``sigmatau analyze``
   (:func:`~sigmatau.cli.common._run_analysis`), so the outputs are those of ``sigmatau analyze``
   on the finished file. A second Ctrl-C during that step abandons it (nothing written).
"""

from __future__ import annotations

import argparse
import math
import os
import queue
import shutil
import signal
import sys
import textwrap
import threading
import time
import warnings
from pathlib import Path
from typing import Any, Optional

import numpy as np

from .common import (
    _Console, _EPILOG_ERRORS, _Formatter, _UsageError, _add_analysis_options, _add_input_options, _add_output_options,
    _check_out, _check_replaceable, _datasheet, _dynamic_spec, _preparation, _read_options, _run_analysis, _say,
)

__all__ = ["add_cli"]

#: Statistics computed live (those of ``--stat`` among them; OADEV always, for the model).
LIVE_STATISTICS = ("oadev", "ohdev", "mdev", "tdev", "totdev")
#: The relative precision the recording advice aims at.
ADVICE_TARGET = 0.1
#: Seconds between polls of the source when nothing arrives.
POLL = 0.1
#: Plain status lines (not a terminal) every this many refresh periods.
PLAIN_EVERY = 5
#: Bytes of samples waiting for the live statistics beyond which reading pauses (a file read from
#: its start runs ahead of them; a pipe's writer then waits, a serial port's bytes are queued).
BACKLOG_BYTES = 32 << 20


# ------------------------------------------------------------------ the live statistics


def _live_engine(*, rate: float, data_type: str, statistics: tuple, confidence: float,
                 max_tau: Optional[float]) -> Any:
    """One channel's live statistics: a :class:`sigmatau.stream.Stream` (memory bounded by the longest
    τ, O(new samples) per update; its results equal the batch statistics of the samples given)."""
    from ..stream import Stream

    kw = {}
    if max_tau is not None:
        kw["max_m"] = max(16, 1 << max(int(math.floor(math.log2(max_tau * rate))), 0))
    return Stream(rate, statistics=statistics, taus="octave", data_type=data_type, confidence=confidence, **kw)


def _advice(model: Any, duration: float) -> tuple[str, str]:
    """The recording advice of a model (:func:`sigmatau.imu.advice.recording_advice`): its headline
    (one line) and its summary (one sentence per term)."""
    from ..errors import SigmaTauError
    from ..imu.advice import recording_advice

    try:
        advice = recording_advice(model, duration=duration, target=ADVICE_TARGET)
    except SigmaTauError as exc:  # the model is still shown
        return f"no advice: {exc}", ""
    return advice.headline(), advice.summary()


class _LiveCompute(threading.Thread):
    """The live statistics of every channel, in a thread fed with the checked samples."""

    def __init__(self, layout: Any, args: argparse.Namespace) -> None:
        super().__init__(name="sigmatau-watch-compute", daemon=True)
        from ..pipeline.analysis import check_statistics

        log = layout.log
        wanted = check_statistics(args.stat)
        self.statistics = tuple(s for s in LIVE_STATISTICS if s in wanted or s == "oadev")
        self.channels = [(name, log.group_of(name), log.units.get(name, "")) for name in layout.channels]
        self.rate, self.data_type = float(log.rate), log.data_type
        self.engines = [_live_engine(rate=self.rate, data_type=log.data_type, statistics=self.statistics,
                                     confidence=args.confidence, max_tau=args.live_max_tau)
                        for _ in self.channels]
        self.skipped = 0  # missing samples (NaN) left out of the live statistics
        self.fed = self.drained = 0  # bytes of samples given and taken (each written by one thread)
        self.model_kw = {"confidence": args.confidence, "gauss_markov": args.gauss_markov}
        self.refresh = args.refresh
        self.inbox: queue.SimpleQueue = queue.SimpleQueue()
        self.views: list = []
        self.computed_at = 0
        self.error = ""
        self._halt = threading.Event()

    def feed(self, samples: np.ndarray) -> None:
        if not self.is_alive():  # it stopped on an error: nothing would take the samples
            return
        self.fed += samples.nbytes
        self.inbox.put(samples)

    @property
    def backlog(self) -> int:
        """Bytes of samples given but not yet taken by the streams."""
        return self.fed - self.drained

    def stop(self) -> None:
        self._halt.set()
        self.join(timeout=30.0)

    @property
    def nbytes(self) -> int:
        return sum(e.nbytes for e in self.engines)

    def run(self) -> None:
        due = 0.0
        try:
            while not self._halt.is_set():
                n = self._drain()
                if n > self.computed_at and time.monotonic() >= due:
                    t0 = time.monotonic()
                    self.views = self._compute(n)
                    self.computed_at = n
                    due = time.monotonic() + max(self.refresh, 2.0 * (time.monotonic() - t0))
                self._halt.wait(0.05)
        except Exception as exc:  # the live view stops; the final analysis is not affected
            self.error = f"live statistics stopped: {type(exc).__name__}: {exc}"

    def _drain(self) -> int:
        while True:
            try:
                chunk = self.inbox.get_nowait()
            except queue.Empty:
                break
            for k, e in enumerate(self.engines):
                y = chunk[:, k]
                gap = np.isnan(y)
                if gap.any():  # a stream takes no gaps: analysed across them live, marked in the final analysis
                    self.skipped += int(gap.sum())
                    y = y[~gap]
                e.update(y)
            self.drained += chunk.nbytes
        return max((e.n for e in self.engines), default=0)

    def _compute(self, n: int) -> list:
        from ..errors import DataError
        from ..report.live import LiveChannel

        views = []
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # warnings of a partial record: the final analysis words them
            for (name, group, unit), engine in zip(self.channels, self.engines):
                results = {}
                for stat in self.statistics:
                    try:
                        results[stat] = engine.result(stat)
                    except DataError:  # too few samples for it yet
                        continue
                model, note = self._model(engine, group, unit, results)
                advice, detail = _advice(model, n / self.rate) if model is not None else ("", "")
                views.append(LiveChannel(name, group, unit, results, model, advice, note, detail))
        return views

    def _model(self, engine: Any, group: str, unit: str, results: dict) -> tuple[Any, str]:
        from ..errors import DataError, SigmaTauError
        from ..imu.units import sensor_unit

        if group not in ("gyro", "accel"):
            return None, ""
        if "oadev" not in results:
            return None, "too few samples yet"
        try:
            su = sensor_unit(unit)
        except SigmaTauError:
            su = None
        if su is None or su.kind != group or self.data_type != "freq":
            return None, f"no IMU model for unit {unit!r}"
        try:
            return engine.imu_model(unit=su.name, **self.model_kw), ""
        except DataError as exc:
            return None, str(exc)
        except (ArithmeticError, np.linalg.LinAlgError) as exc:
            return None, f"model not fitted: {type(exc).__name__}"


# ------------------------------------------------------------------------------------------ view


class _View:
    """The live table on a terminal (redrawn in place), plain status lines otherwise, notices always."""

    def __init__(self, console: _Console, refresh: float) -> None:
        self.quiet, self.tty = console.quiet, console.tty
        self.refresh = refresh
        self.drawn = 0
        self.last_plain = time.monotonic()

    def _erase(self) -> None:
        if self.drawn:
            sys.stderr.write(f"\x1b[{self.drawn}F\x1b[J")
            self.drawn = 0

    def notices(self, lines: list) -> None:
        if not lines:
            return
        self._erase()
        for line in lines:
            _say(f"sigmatau: {line}", err=True)
        sys.stderr.flush()

    def show(self, snap: dict) -> None:
        from ..report.live import status_line, terminal_lines

        if self.quiet:
            return
        if self.tty:
            size = shutil.get_terminal_size((100, 24))
            lines = terminal_lines(snap, size.columns or 100)[:max((size.lines or 24) - 2, 3)]
            self._erase()
            sys.stderr.write("\n".join(lines) + "\n")
            sys.stderr.flush()
            self.drawn = len(lines)
        elif time.monotonic() - self.last_plain >= PLAIN_EVERY * self.refresh:
            self.last_plain = time.monotonic()
            _say(f"sigmatau: watch: {status_line(snap)}", err=True, flush=True)

    def close(self) -> None:
        self._erase()


# ------------------------------------------------------------------------------------------- run


class _Run:
    """One watch: the source, the record, the live computation and view, and how it ended."""

    def __init__(self, args: argparse.Namespace, console: _Console, source: Any, folder: Path,
                 read_kw: dict) -> None:
        from ..io.liveparse import LiveReader
        from ..report.live import LiveState, NoticeLimiter

        self.args, self.console, self.source, self.folder, self.read_kw = args, console, source, folder, read_kw
        self.record = folder / source.name
        self.record_fh = open(self.record, "wb")
        self.reader = LiveReader(source, read_kw, self.record)
        self.limiter = NoticeLimiter()
        self.view = _View(console, args.refresh)
        self.state = LiveState()
        self.live: Optional[_LiveCompute] = None
        self.server: Any = None
        self.started = time.monotonic()
        self.stop_why = ""
        self.status = "waiting for data"
        self._skip_said = False

    def serve(self, port: int) -> None:
        from ..report.live import LiveServer

        self.publish()
        try:
            self.server = LiveServer(self.state, port)
        except OSError as exc:
            raise _UsageError(f"--serve {port}: cannot listen on 127.0.0.1:{port}: {exc.strerror or exc}; choose"
                              " another port, or 0 for any free port") from None
        _say(f"sigmatau: live view at {self.server.url}", err=True, flush=True)

    def publish(self) -> dict:
        from ..report.live import snapshot

        layout = self.reader.layout
        live = self.live
        snap = snapshot(live.views if live else [], source=self.source.display, status=self.status,
                        samples=self.reader.samples, rate=None if layout is None else float(layout.log.rate),
                        timing=self.reader.timing.summary() if self.reader.timing else None,
                        notices=self.limiter.latest(), elapsed=time.monotonic() - self.started,
                        computed_at=live.computed_at if live else 0, live_bytes=live.nbytes if live else 0)
        self.state.publish(snap)
        return snap

    def _on_signal(self, signum: int, frame: Any) -> None:
        self.stop_why = "interrupted (Ctrl-C)" if signum == signal.SIGINT else "terminated (SIGTERM)"

    def follow(self) -> bool:
        """Read until the run ends; True when the input itself ended (its unfinished last line counts)."""
        args = self.args
        handlers = {}
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                handlers[sig] = signal.signal(sig, self._on_signal)
        last_growth = shown = time.monotonic()
        self.status = "running"
        try:
            while True:
                step = self.reader.step(POLL)
                self._take(step)
                now = time.monotonic()
                if step.grew:
                    last_growth = now
                if step.eof or self.reader.ended:
                    why, end = "end of input", True
                elif args.until_idle is not None and now - last_growth >= args.until_idle:
                    why, end = f"no new data for {args.until_idle:g} s", True
                elif args.duration is not None and now - self.started >= args.duration:
                    why, end = f"--duration {args.duration:g} s reached", False
                elif self.stop_why:
                    why, end = self.stop_why, False
                else:
                    if now - shown >= args.refresh:
                        shown = now
                        self._tick()
                    continue
                break
        finally:
            for sig, old in handlers.items():
                signal.signal(sig, old)
        self._take(self.reader.finish(end_of_input=end))
        self.record_fh.close()
        self.stop_why = why
        return end

    def _take(self, step: Any) -> None:
        if step.record:
            self.record_fh.write(step.record)
        lines: list = []
        for kind, text in step.notices:
            lines += self.limiter.add(kind, text)
        lines += self.limiter.flush()
        self.view.notices(lines)
        if self.live is None and self.reader.layout is not None:
            self.live = _LiveCompute(self.reader.layout, self.args)
            self.live.start()
        if step.samples is not None and self.live is not None:
            self.live.feed(step.samples)
            while self.live.backlog > BACKLOG_BYTES and self.live.is_alive() and not self.stop_why:
                time.sleep(0.05)

    def _tick(self) -> None:
        live = self.live
        if live is not None and live.error:
            self.view.notices([live.error])
            live.error = ""
        if live is not None and live.skipped and not self._skip_said:
            self._skip_said = True
            self.view.notices(self.limiter.add("gap", "the live statistics leave the missing samples out (analysed"
                                                      " across the gaps); the final analysis applies --gaps"))
        self.view.show(self.publish())

    def close(self) -> None:
        self.view.close()
        if self.live is not None:
            self.live.stop()
        if self.server is not None:
            self.server.close()
        self.source.close()
        if not self.record_fh.closed:
            self.record_fh.close()


def _finish(run: _Run, out: Path) -> int:
    """The record through the job of ``sigmatau analyze``; outputs written atomically into ``out``."""
    from ..errors import SigmaTauError
    from ..io.liveparse import read_record

    args = run.args
    run.view.notices(run.limiter.flush(force=True))
    run.view.close()
    if run.live is not None:
        run.live.stop()
        run.live.engines = []  # the streams' memory goes back before the analysis needs its own
        _return_memory()
    run.status = f"finishing: {run.stop_why}"
    run.publish()
    if run.reader.samples:  # else the read's error says what is wrong, in one line
        _say(f"sigmatau: watch: {run.stop_why}; analysing the {run.reader.samples:,} samples received", err=True,
             flush=True)
    if args.save:
        _keep_record(run.record, Path(args.save))
    try:
        log = read_record(run.record, run.source.display, run.read_kw)
        code = _run_analysis(log, args, run.console, out)
    except SigmaTauError as exc:
        raise _kept(run, out, exc) from None
    except KeyboardInterrupt:  # a second Ctrl-C: the analysis is abandoned, not what was received
        if _keeps(run):
            _say(f"sigmatau: the record received is kept in {_salvage(run.record, out)}", err=True)
        raise
    run.status = f"finished: {run.stop_why}; outputs in {out}"
    run.publish()
    if args.save:
        _say(f"sigmatau: the record received is in {args.save}", err=True)
    return code


def _keeps(run: _Run) -> bool:
    """Whether the record must outlive the run: a stream that cannot be read again, not saved."""
    if not run.record_fh.closed:
        run.record_fh.write(run.reader.undelivered)
        run.record_fh.close()
    return not (run.source.is_file or run.args.save) and run.record.stat().st_size > 0


def _kept(run: _Run, out: Path, exc: Exception) -> Exception:
    """``exc``, its message saying where the record was kept when it must outlive the run."""
    if not _keeps(run):
        return exc
    return type(exc)(f"{exc}; the record received is kept in {_salvage(run.record, out)}")


def _return_memory() -> None:
    """Hand freed memory back to the system before the final analysis. The streams were filled by
    the live thread, whose glibc arena keeps what they freed (140 MiB for six channels at the
    default τ) unless trimmed; elsewhere (no glibc) nothing is done."""
    import ctypes
    import ctypes.util
    import gc

    gc.collect()
    name = ctypes.util.find_library("c") if sys.platform.startswith("linux") else None
    if name is None:
        return
    try:
        trim = ctypes.CDLL(name).malloc_trim
    except (OSError, AttributeError):  # not glibc (musl): it has no malloc_trim
        return
    trim(0)


def _keep_record(record: Path, dest: Path) -> None:
    """The record copied to ``dest`` through a temporary file renamed into place."""
    import tempfile

    parent = dest.resolve().parent
    fd, tmp = tempfile.mkstemp(prefix=f".{dest.name}.", suffix=".partial", dir=parent)
    try:
        with os.fdopen(fd, "wb") as fh, open(record, "rb") as src:
            shutil.copyfileobj(src, fh, 1 << 20)
        from ..report.outputs import umask

        os.chmod(tmp, 0o666 & ~umask())
        os.replace(tmp, dest)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _salvage(record: Path, out: Path) -> Path:
    """The record kept beside ``out`` under a name not taken (a stream cannot be read again): a hard
    link, since the record's folder, a sibling of ``out``, is removed at the end (a copy where links
    are not supported)."""
    parent = out.resolve().parent
    suffix = Path(record.name).suffix or ".txt"
    for k in range(1, 1000):
        dest = parent / f"{out.name}-record{'' if k == 1 else f'-{k}'}{suffix}"
        try:
            os.link(record, dest)  # fails rather than replace a file that appeared meanwhile
        except FileExistsError:
            continue
        except OSError:  # no hard links here: copy
            if os.path.lexists(dest):
                continue
            _keep_record(record, dest)
        return dest
    raise OSError("no free name for the record")  # pragma: no cover


def _default_out(source: str, serial: Optional[str]) -> Path:
    from ..io.follow import source_kind

    kind = "serial" if serial else source_kind(source)
    stem = Path(source).name.split(".")[0] if kind == "file" else kind
    return Path(f"{stem or 'watch'}-sigmatau")


def _check_args(args: argparse.Namespace) -> None:
    from ..pipeline.analysis import check_statistics

    if args.log is None and args.serial is None:
        raise _UsageError("sigmatau watch: error: give a SOURCE (a file, -, serial://PORT, ros2:/TOPIC) or --serial")
    if args.log is not None and args.serial is not None:
        raise _UsageError(f"sigmatau watch: error: give SOURCE {args.log!r} or --serial {args.serial!r}, not both")
    for flag, dest in (("--topic", "topic"), ("--list-topics", "list_topics"), ("--dataset", "dataset"),
                       ("--stamps", "stamps")):
        if getattr(args, dest):
            raise _UsageError(f"{flag} applies to files of sigmatau analyze; watch a ROS 2 topic as ros2:/TOPIC")
    if args.format is not None and args.format not in ("csv", "stable32"):
        raise _UsageError(f"--format {args.format!r}: sigmatau watch reads csv or stable32 text")
    for flag, value in (("--refresh", args.refresh), ("--duration", args.duration), ("--until-idle", args.until_idle),
                        ("--live-max-tau", args.live_max_tau)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise _UsageError(f"{flag} {value!r} must be a positive number of seconds")
    if args.serve is not None and not 0 <= args.serve <= 65535:
        raise _UsageError(f"--serve {args.serve!r} must be a port number, 0–65535 (0: any free port)")
    if args.baud is not None and args.baud <= 0:
        raise _UsageError(f"--baud {args.baud!r} must be a positive integer")
    if args.taus not in ("octave", "decade", "all", "log"):
        raise _UsageError(f"--taus {args.taus!r} must be octave, decade, all or log")
    # What the final analysis would refuse is refused now, not after hours of recording.
    check_statistics(args.stat)
    _preparation(args)
    _dynamic_spec(args)
    _datasheet(args.datasheet)


def _cmd_watch(args: argparse.Namespace, console: _Console) -> int:
    from ..errors import ParameterError, SigmaTauError
    from ..io import check_read_options
    from ..io.follow import open_source, source_kind
    from ..report.live import staging_folder

    _check_args(args)
    read_kw = _read_options(args)
    try:
        check_read_options(**read_kw)
    except ParameterError as exc:
        raise _UsageError(str(exc)) from None
    spec = args.log if args.log is not None else args.serial
    is_file = args.serial is None and source_kind(spec) == "file"
    out = _check_out(args, _default_out(spec, args.serial), protect=[spec] if is_file else [])
    if args.save:
        if is_file and Path(args.save).resolve() == Path(spec).resolve():
            raise _UsageError(f"--save {args.save!r} is the watched file; choose another file")
        _check_replaceable(Path(args.save), "--save", args.force)
    source = open_source(spec if args.serial is None else "", serial=args.serial, baud=args.baud)
    folder: Optional[Path] = None
    run: Optional[_Run] = None
    try:
        folder = staging_folder(out)
        run = _Run(args, console, source, folder, read_kw)
        if args.serve is not None:
            run.serve(args.serve)
        try:
            run.follow()
        except SigmaTauError as exc:  # a policy refused the input, or it could not be read
            raise _kept(run, out, exc) from None
        return _finish(run, out)
    finally:
        if run is not None:
            run.close()
        else:
            source.close()
        if folder is not None:
            shutil.rmtree(folder, ignore_errors=True)


def _port(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a port number (put SOURCE before --serve)") from None


def _adapt_input_options(p: argparse.ArgumentParser) -> None:
    """The input options of ``analyze`` for a live source: SOURCE instead of LOG, the bag and HDF5
    options hidden (refused when given)."""
    for action in p._actions:
        if action.dest == "log":
            action.metavar, action.nargs, action.default, action.required = "SOURCE", "?", None, False
            action.help = ("a text log to follow (CSV/TSV/text, Stable32 data), - for standard input,"
                           " serial:///dev/ttyUSB0?baud=115200, or ros2:/imu/data (sensor_msgs/Imu, needs rclpy)")
        elif action.dest in ("topic", "list_topics", "dataset", "stamps"):
            action.help = argparse.SUPPRESS
        elif action.dest == "format":
            action.help = "csv or stable32, when detection is not wanted"


def add_cli(sub: Any) -> None:
    """Register ``sigmatau watch`` on the command's subparsers."""
    watch = sub.add_parser(
        "watch", help="σ–τ and the IMU noise terms live while a log is recorded, then the full analysis",
        formatter_class=_Formatter,
        description="Follow a growing log (or standard input, a serial port, a ROS 2 topic), show σ–τ, the IMU"
                    " noise terms with intervals and how much longer to record, on the terminal and with --serve"
                    " on a local web page; at the end (Ctrl-C, SIGTERM, --duration, end of input, --until-idle)"
                    " write what sigmatau analyze writes for the finished log into --out.",
        epilog=textwrap.dedent("""
            examples:
              sigmatau watch imu.csv --serve                 follow a log being written; the page's URL is printed
              sigmatau watch imu.csv --until-idle 10 --out run   stop 10 s after the file stops growing
              logger | sigmatau watch - --rate 200 --out run     standard input, no timestamps
              sigmatau watch 'serial:///dev/ttyUSB0?baud=921600' --duration 7200 --save run.csv
              sigmatau watch ros2:/imu/data --serve 8000     a ROS 2 topic (rclpy from a ROS 2 installation)
            """) + _EPILOG_ERRORS)
    _add_input_options(watch)
    _adapt_input_options(watch)
    w = watch.add_argument_group("live")
    w.add_argument("--serial", metavar="PORT",
                   help="a serial port or pyserial URL (loop://, socket://host:port) instead of SOURCE (extra serial:"
                        " pip install 'sigmatau[serial]')")
    w.add_argument("--baud", type=int, help="baud rate of the serial port (default 115200)")
    w.add_argument("--serve", nargs="?", const=0, type=_port, metavar="PORT",
                   help="serve the live page on http://127.0.0.1:PORT/ (this machine only); no PORT or 0: any free"
                        " port; the URL is printed")
    w.add_argument("--refresh", type=float, default=2.0, help="seconds between live updates (default 2)")
    w.add_argument("--duration", type=float, metavar="SECONDS", help="stop after this many seconds")
    w.add_argument("--until-idle", type=float, metavar="SECONDS",
                   help="stop when no data arrived for this many seconds (default: follow a file for ever)")
    w.add_argument("--save", metavar="FILE", help="also write the record received (the accepted lines) to FILE")
    w.add_argument("--live-max-tau", type=float, metavar="SECONDS",
                   help="longest τ of the live statistics (default 2**18 samples: 262 s at 1 kHz); memory grows"
                        " with it, about 90 bytes × rate × SECONDS per channel; the final analysis has every τ")
    _add_analysis_options(watch, "oadev,mdev,tdev,ohdev,totdev,theoh")
    _add_output_options(watch)
    watch.set_defaults(func=_cmd_watch)
