"""Live inputs for ``sigmatau watch``: a growing file followed like ``tail -F``, a pipe, a serial port, a ROS 2 topic.

Every source hands out whole lines (``bytes`` ending in ``\\n``) through :meth:`LiveSource.poll`; a
line is handed out only once its newline has arrived, and the unfinished rest of the input only by
:meth:`LiveSource.rest`, at the end of input. A line longer than :data:`MAX_LINE_CHARS` bytes is
never held whole: it is dropped as it arrives, with a notice (the batch reader refuses such a file).

A followed file (:class:`FollowedFile`) is read from its first byte and only read:

* **rotation** — the path now names another file (``logrotate`` with ``create``, a logger that
  renames its file and starts a new one): the rest of the old file is read, then the new file from
  its start, with a notice and a :data:`NEW_CONTENT` event, so that its header is not taken for data;
* **truncation** — the file became shorter than what was read, or the bytes just before the read
  position changed (truncated and rewritten past it between two polls, ``copytruncate``): a notice,
  and its new content is read from the start, as after a rotation. The record goes on: what was
  read before stays in it (``copytruncate`` copies it away before truncating).

Standard input and other pipes (:class:`PipeSource`) are read once and never seeked; a serial port
(:class:`SerialSource`, pyserial: extra ``serial``) and a ROS 2 ``sensor_msgs/Imu`` topic
(:class:`Ros2Source`, rclpy from a ROS 2 installation) are read in a thread into a bounded queue,
so the port's buffer is emptied while the caller computes.

Layer: :mod:`sigmatau.io` (imports :mod:`sigmatau.core` and :mod:`sigmatau.errors` only).
"""

from __future__ import annotations

import os
import queue
import stat
import threading
import time
import urllib.parse
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional

from ..errors import DataError, MissingDependencyError, ParameterError
from ._errors import FormatError, InputNotFoundError, require_optional
from ._limits import MAX_LINE_CHARS

__all__ = [
    "NEW_CONTENT", "Poll", "LineSplitter", "LiveSource", "FollowedFile", "PipeSource", "SerialSource", "Ros2Source",
    "open_source", "source_kind",
]

#: Marker in :attr:`Poll.lines`: the lines after it are new content (a rotated or truncated file)
#: whose header and preamble must be skipped, not the continuation of the record.
NEW_CONTENT = b""

#: Bytes read from a followed file per poll at most (the rest at the next poll, without waiting).
READ_BLOCK = 4 << 20
#: Bytes compared just before the read position to notice a file truncated and rewritten past it.
TAIL_CHECK = 64
#: Bytes a threaded source may queue before its reader waits (a pipe's writer then waits too).
QUEUE_BYTES = 64 << 20


@dataclass
class Poll:
    """What one :meth:`LiveSource.poll` brought.

    Attributes
    ----------
    lines : list of bytes
        Whole lines, each ending in ``\\n``, in order; :data:`NEW_CONTENT` between them where a
        rotated or truncated file starts again.
    notices : list of (kind, text)
        Events to tell the user about: ``"rotation"``, ``"truncation"``, ``"long-line"``, ``"source"``.
    eof : bool
        The input ended (a pipe closed, a port or topic gone); a followed file never ends by itself.
    grew : bool
        Bytes arrived (for ``--until-idle``).
    """

    lines: list = field(default_factory=list)
    notices: list = field(default_factory=list)
    eof: bool = False
    grew: bool = False


class LineSplitter:
    """Bytes in, whole lines out; the unfinished last line is kept (at most MAX_LINE_CHARS bytes)."""

    def __init__(self) -> None:
        self._pending = bytearray()
        self._dropping = False
        self.dropped = 0

    def feed(self, data: bytes, poll: Poll) -> None:
        """Split ``data`` after what was pending; whole lines go to ``poll.lines``."""
        start = 0
        while True:
            k = data.find(b"\n", start)
            if k < 0:
                break
            if self._dropping:
                self._dropping = False
            else:
                self._pending += data[start:k + 1]
                poll.lines.append(bytes(self._pending))
            self._pending.clear()
            start = k + 1
        if not self._dropping:
            self._pending += data[start:]
            if len(self._pending) >= MAX_LINE_CHARS:
                self._pending.clear()
                self._dropping = True
                self.dropped += 1
                poll.notices.append(("long-line", f"a line longer than {MAX_LINE_CHARS:,} bytes was dropped"
                                                  " (not a table of numbers)"))

    def rest(self) -> bytes:
        """The unfinished last line (empty when there is none), and forget it."""
        out = b"" if self._dropping else bytes(self._pending)
        self._pending.clear()
        self._dropping = False
        return out

    def reset(self) -> bytes:
        """Forget the unfinished line (new content starts); return what was dropped."""
        return self.rest()


class LiveSource:
    """A live input: :meth:`poll` for new whole lines, :meth:`rest` at the end, :meth:`close`."""

    #: How the source is named in messages and the record (``Source.path`` of the final analysis).
    display: str = ""
    #: File name of the record's copy (its extension chooses the reader, as for the file itself).
    name: str = "record"
    #: Whether the input is a regular file that stays where it is (no copy of the record needed).
    is_file: bool = False

    def poll(self, timeout: float) -> Poll:  # pragma: no cover - interface
        raise NotImplementedError

    def rest(self) -> bytes:  # pragma: no cover - interface
        raise NotImplementedError

    def close(self) -> None:
        pass


class FollowedFile(LiveSource):
    """A regular file read from its start and followed as it grows, across rotation and truncation."""

    is_file = True

    def __init__(self, path: str) -> None:
        self.display = path
        self.path = Path(path)
        self.name = self.path.name or "record"
        if not self.path.exists():
            raise InputNotFoundError(f"{path}: no such file or directory")
        if self.path.is_dir():
            raise FormatError(f"{path}: is a directory; sigmatau watch follows a text log")
        self._fh = open(self.path, "rb")  # only ever read
        st = os.fstat(self._fh.fileno())
        self._id = (st.st_dev, st.st_ino)
        self._offset = 0
        self._tail = b""
        self._split = LineSplitter()
        self._gone_said = False

    def _changed_under_us(self) -> Optional[str]:
        """Why the content already read is no longer there (truncated, rewritten), or None."""
        size = os.fstat(self._fh.fileno()).st_size
        if size < self._offset:
            return f"shrank from {self._offset:,} to {size:,} bytes (truncated)"
        if self._tail and size > self._offset:
            self._fh.seek(self._offset - len(self._tail))
            if self._fh.read(len(self._tail)) != self._tail:
                return "was truncated and rewritten (its bytes before the read position changed)"
        return None

    def _restart(self, poll: Poll, kind: str, text: str) -> None:
        dropped = self._split.reset()
        extra = f"; its unfinished last line ({len(dropped):,} bytes) was left out" if dropped else ""
        poll.notices.append((kind, f"{self.display} {text}: reading its new content from the start{extra}"))
        poll.lines.append(NEW_CONTENT)
        self._offset = 0
        self._tail = b""

    def poll(self, timeout: float) -> Poll:
        poll = Poll()
        why = self._changed_under_us()
        if why is not None:
            self._restart(poll, "truncation", why)
        self._fh.seek(self._offset)
        data = self._fh.read(READ_BLOCK)
        if data:
            self._consume(data, poll)
            return poll
        if self._rotated(poll):
            return poll
        time.sleep(timeout)
        return poll

    def _consume(self, data: bytes, poll: Poll) -> None:
        self._offset += len(data)
        self._tail = (self._tail + data)[-TAIL_CHECK:]
        self._split.feed(data, poll)
        poll.grew = True

    def _rotated(self, poll: Poll) -> bool:
        """Switch to the file the path names now, once the old one is read to its end."""
        try:
            st = os.stat(self.path)
        except FileNotFoundError:
            if not self._gone_said:
                self._gone_said = True
                poll.notices.append(("rotation", f"{self.display} was moved or deleted; waiting for a new file"
                                                 " of that name"))
            return False
        except OSError:
            return False
        if (st.st_dev, st.st_ino) == self._id:
            return False
        try:
            fh = open(self.path, "rb")
        except OSError:
            return False
        self._fh.close()
        self._fh = fh
        st = os.fstat(fh.fileno())
        self._id = (st.st_dev, st.st_ino)
        self._gone_said = False
        self._restart(poll, "rotation", "was replaced by a new file (rotation)")
        return True

    def rest(self) -> bytes:
        return self._split.rest()

    def close(self) -> None:
        self._fh.close()


class _QueuedSource(LiveSource):
    """A source read by a thread into a bounded queue of byte blocks (``None`` ends it)."""

    def __init__(self) -> None:
        self._queue: queue.Queue = queue.Queue(maxsize=max(1, QUEUE_BYTES // 65536))
        self._split = LineSplitter()
        self._ended = False
        self._stop = threading.Event()
        self._notices: list = []
        self._thread: Optional[threading.Thread] = None

    def _start(self, name: str) -> None:
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def _run(self) -> None:  # pragma: no cover - interface
        raise NotImplementedError

    def _put(self, block: Optional[bytes]) -> None:
        while not self._stop.is_set():
            try:
                self._queue.put(block, timeout=0.2)
                return
            except queue.Full:
                continue

    def poll(self, timeout: float) -> Poll:
        poll = Poll(notices=self._notices)
        self._notices = []
        if self._ended:
            poll.eof = True
            return poll
        deadline = time.monotonic() + timeout
        while True:
            try:
                block = self._queue.get(timeout=max(deadline - time.monotonic(), 0.0))
            except queue.Empty:
                break
            if block is None:
                self._ended = poll.eof = True
                break
            if isinstance(block, str):  # a notice from the reader thread
                poll.notices.append(("source", block))
                continue
            poll.grew = True
            self._split.feed(block, poll)
            if len(poll.lines) >= 65536 or self._queue.empty():
                break
        return poll

    def rest(self) -> bytes:
        return self._split.rest()

    def close(self) -> None:
        self._stop.set()


class PipeSource(_QueuedSource):
    """Standard input, a FIFO or a character device, read once and never seeked."""

    def __init__(self, fd: int = 0, display: str = "<stdin>", name: str = "stdin") -> None:
        super().__init__()
        self.display, self.name = display, name
        self._fd = fd
        self._start("sigmatau-watch-pipe")

    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                block = os.read(self._fd, 65536)
                if not block:
                    break
                self._put(block)
        except OSError as exc:
            self._put(f"{self.display}: cannot read: {exc.strerror or exc}")
        self._put(None)


def parse_serial(spec: str, baud: Optional[int]) -> tuple[str, int]:
    """The pyserial port (or URL) and baud rate of ``serial:///dev/ttyUSB0?baud=115200``,
    ``serial://COM3?baud=9600`` or a plain port name.

    >>> parse_serial("serial:///dev/ttyUSB0?baud=115200", None)
    ('/dev/ttyUSB0', 115200)
    >>> parse_serial("loop://", 9600)
    ('loop://', 9600)
    """
    port, rate = spec, baud
    if spec.startswith("serial:"):
        parts = urllib.parse.urlsplit(spec)
        port = urllib.parse.unquote(parts.netloc + parts.path)
        query = urllib.parse.parse_qs(parts.query)
        unknown = sorted(set(query) - {"baud"})
        if unknown:
            raise ParameterError(f"{spec!r}: unknown serial option(s) {', '.join(map(repr, unknown))}; the form is"
                                 " serial:///dev/ttyUSB0?baud=115200")
        if "baud" in query:
            try:
                from_url = int(query["baud"][-1])
            except ValueError:
                raise ParameterError(f"{spec!r}: baud={query['baud'][-1]!r} must be an integer") from None
            if baud is not None and baud != from_url:
                raise ParameterError(f"{spec!r} says baud={from_url} but --baud {baud} was given; give one")
            rate = from_url
    if not port:
        raise ParameterError(f"{spec!r} names no serial port; the form is serial:///dev/ttyUSB0?baud=115200")
    rate = 115200 if rate is None else rate
    if not 50 <= rate <= 20_000_000:
        raise ParameterError(f"baud rate {rate} must be between 50 and 20,000,000")
    return port, rate


class SerialSource(_QueuedSource):
    """A serial port through pyserial (``serial_for_url``: device names and pyserial URLs such as
    ``loop://``, ``socket://host:port``, ``rfc2217://``)."""

    name = "serial"

    def __init__(self, port: str, baud: int) -> None:
        super().__init__()
        serial = require_optional("serial", extra="serial", package="pyserial", what="a serial port")
        self.display = f"serial:{port}"
        try:
            self._port = serial.serial_for_url(port, baudrate=baud, timeout=0.2)
        except (serial.SerialException, ValueError, OSError) as exc:
            raise DataError(f"cannot open serial port {port!r}: {' '.join(str(exc).split())}") from None
        self._serial = serial
        self._start("sigmatau-watch-serial")

    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                block = self._port.read(max(1, min(self._port.in_waiting, 65536)))
                if block:
                    self._put(block)
        except (self._serial.SerialException, OSError) as exc:
            self._put(f"{self.display}: the port closed: {' '.join(str(exc).split())}")
        self._put(None)

    def close(self) -> None:
        super().close()
        if self._thread is not None:
            self._thread.join(timeout=1.0)
        try:
            self._port.close()
        except Exception:  # closing a port that vanished: nothing left to release
            pass


#: The columns of a ROS 2 ``sensor_msgs/Imu`` message as text: header.stamp in ns, then the six
#: channels in the units of ROS REP 103, as the bag reader names them.
ROS2_HEADER = (b"timestamp [ns],gyro_x [rad/s],gyro_y [rad/s],gyro_z [rad/s],accel_x [m/s^2],accel_y [m/s^2],"
               b"accel_z [m/s^2]\n")


class Ros2Source(_QueuedSource):
    """A ``sensor_msgs/msg/Imu`` topic of a running ROS 2 system (rclpy, which a ROS 2 installation
    provides; it is not on PyPI). Each message becomes a line of :data:`ROS2_HEADER`'s columns, with
    ``repr`` of each value, so the record holds the very float64 values received."""

    def __init__(self, topic: str) -> None:
        super().__init__()
        if not topic.startswith("/") or any(c.isspace() for c in topic):
            raise ParameterError(f"ROS 2 topic {topic!r} must be an absolute name such as /imu/data")
        try:
            import rclpy
            from rclpy.qos import qos_profile_sensor_data
            from sensor_msgs.msg import Imu
        except ImportError:
            raise MissingDependencyError(
                f"ros2:{topic} needs rclpy and sensor_msgs, which come with a ROS 2 installation (not PyPI):"
                " source its setup script (/opt/ros/<distro>/setup.bash) and run sigmatau with that Python"
            ) from None
        self.display = f"ros2:{topic}"
        self.name = "ros2"
        self._rclpy = rclpy
        rclpy.init(args=None)
        self._node = rclpy.create_node("sigmatau_watch")
        self._node.create_subscription(Imu, topic, self._message, qos_profile_sensor_data)
        self._put(ROS2_HEADER)
        self._start("sigmatau-watch-ros2")

    def _message(self, msg: Any) -> None:
        stamp = int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)
        if stamp == 0:  # no header stamp: the receive time
            stamp = int(self._node.get_clock().now().nanoseconds)
        w, a = msg.angular_velocity, msg.linear_acceleration
        values = ",".join(repr(float(v)) for v in (w.x, w.y, w.z, a.x, a.y, a.z))
        self._put(f"{stamp},{values}\n".encode("ascii"))

    def _run(self) -> None:
        try:
            while not self._stop.is_set() and self._rclpy.ok():
                self._rclpy.spin_once(self._node, timeout_sec=0.2)
        finally:
            self._put(None)

    def close(self) -> None:
        super().close()
        if self._thread is not None:
            self._thread.join(timeout=1.0)
        try:
            self._node.destroy_node()
            self._rclpy.shutdown()
        except Exception:  # already shut down by the ROS 2 runtime
            pass


def source_kind(spec: str) -> str:
    """``"stdin"``, ``"serial"``, ``"ros2"`` or ``"file"`` for a SOURCE argument."""
    if spec == "-":
        return "stdin"
    if spec.startswith("serial:"):
        return "serial"
    if spec.startswith("ros2:"):
        return "ros2"
    return "file"


def open_source(spec: str, *, serial: Optional[str] = None, baud: Optional[int] = None) -> LiveSource:
    """The live source a SOURCE argument names.

    Parameters
    ----------
    spec : str
        A file path (followed), ``-`` (standard input), ``serial:///dev/ttyUSB0?baud=115200`` or
        ``ros2:/imu/data``; ignored when ``serial`` is given. A path that is a FIFO or a device
        is read once, as standard input.
    serial : str, optional
        A serial port or pyserial URL (``--serial``).
    baud : int, optional
        Its baud rate (default 115200).

    Raises
    ------
    InputNotFoundError
        The file does not exist.
    MissingDependencyError
        pyserial (extra ``serial``) or rclpy is not installed.
    DataError
        The port cannot be opened.
    """
    if serial is not None:
        return SerialSource(*parse_serial(serial, baud))
    kind = source_kind(spec)
    if kind != "serial" and baud is not None:
        raise ParameterError("--baud applies to a serial port (serial:///dev/ttyUSB0 or --serial PORT)")
    if kind == "stdin":
        return PipeSource(0)
    if kind == "serial":
        return SerialSource(*parse_serial(spec, baud))
    if kind == "ros2":
        return Ros2Source(spec[len("ros2:"):])
    path = Path(spec)
    if path.exists() and not path.is_dir() and not stat.S_ISREG(path.stat().st_mode):
        try:  # a FIFO or a device: read once, as standard input (a FIFO waits for its writer here)
            fd = os.open(path, os.O_RDONLY)
        except OSError as exc:
            raise DataError(f"{spec}: cannot read: {exc.strerror or exc}") from None
        return PipeSource(fd, display=spec, name=path.name or "record")
    return FollowedFile(spec)
