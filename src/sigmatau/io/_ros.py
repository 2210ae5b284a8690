"""ROS 1 bags and ROS 2 bags (sqlite3 and MCAP storage) with ``sensor_msgs/msg/Imu``, via ``rosbags``.

Channels: ``gyro_x/y/z`` from ``angular_velocity`` (rad/s) and ``accel_x/y/z``
from ``linear_acceleration`` (m/s^2), the units of the message definition.
Timestamps: ``header.stamp`` (default) or the bag's receive time
(``stamps="bag"``); header stamps that are all zero fall back to receive time
with a warning.

Messages are decoded in batches with NumPy when their layout is the plain
little-endian one (checked on the first message against the ``rosbags``
deserialiser); anything else goes through ``rosbags`` one message at a time.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError
from ._columns import select
from ._errors import FormatError, require_optional, option_hint
from ._model import TopicInfo
from ._progress import Progress
from ._registry import Options, Table, file_sha256, register

__all__ = ["read_bag", "topics", "IMU_TYPE", "CHANNELS"]

IMU_TYPE = "sensor_msgs/msg/Imu"
TEMPERATURE_TYPE = "sensor_msgs/msg/Temperature"
#: Share of the IMU samples a temperature topic must span to become the log's temperature channel.
TEMPERATURE_COVERAGE = 0.9
CHANNELS = ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
_BATCH = 8192
# Offsets (in float64 words) in the 37 doubles after the header: orientation (4),
# its covariance (9), angular_velocity (3), covariance (9), linear_acceleration (3), covariance (9).
_GYRO_WORD, _ACCEL_WORD, _WORDS = 13, 25, 37


def _rosbags(what: str) -> Any:
    require_optional("rosbags", extra="ros", package="rosbags", what=what)
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    return AnyReader, Stores, get_typestore


def _is_ros1(path: Path) -> bool:
    return path.is_file() and path.suffix.lower() == ".bag"


def _storage(path: Path) -> str:
    if _is_ros1(path):
        return "rosbag1"
    if path.is_dir():
        meta = (path / "metadata.yaml").read_text(errors="replace")
        return "mcap" if "storage_identifier: mcap" in meta else "sqlite3"
    return "mcap" if path.suffix.lower() == ".mcap" else "sqlite3"


class _Bag:
    """AnyReader opened with errors turned into one-line FormatErrors."""

    def __init__(self, path: Path, display: str) -> None:
        AnyReader, Stores, get_typestore = _rosbags("ROS bags")
        self.kind = "ROS 1 bag" if _is_ros1(path) else "ROS 2 bag"
        store = Stores.ROS1_NOETIC if _is_ros1(path) else Stores.ROS2_HUMBLE
        self.display = display
        try:
            self.reader = AnyReader([path], default_typestore=get_typestore(store))
            self.reader.open()
        except Exception as exc:  # rosbags raises many types on damaged files
            raise self.error(exc) from None

    def error(self, exc: BaseException) -> FormatError:
        text = " ".join(str(exc).split()) or type(exc).__name__
        return FormatError(f"{self.display}: cannot read as a {self.kind}: {text}")

    def close(self) -> None:
        try:
            self.reader.close()
        except Exception:  # closing a half-read damaged bag must not hide the first error
            pass


def topics(path: Path, display: str) -> list[TopicInfo]:
    bag = _Bag(path, display)
    try:
        return sorted(
            (TopicInfo(name, info.msgtype or "?", int(info.msgcount)) for name, info in bag.reader.topics.items()),
            key=lambda t: t.topic,
        )
    finally:
        bag.close()


def _choose_topic(bag: _Bag, wanted: str | None, display: str) -> tuple[str, Any]:
    infos = bag.reader.topics
    listing = ", ".join(f"{n} ({i.msgtype}, {i.msgcount})" for n, i in sorted(infos.items())) or "none"
    if wanted is not None:
        if wanted not in infos:
            raise ParameterError(f"{display}: no topic {wanted!r}; topics are: {listing}")
        if infos[wanted].msgtype != IMU_TYPE:
            raise ParameterError(
                f"{display}: topic {wanted!r} carries {infos[wanted].msgtype}, not {IMU_TYPE}; topics are: {listing}"
            )
        return wanted, infos[wanted]
    imu = sorted(n for n, i in infos.items() if i.msgtype == IMU_TYPE)
    if not imu:
        raise ParameterError(f"{display}: no {IMU_TYPE} topic; topics are: {listing}")
    if len(imu) > 1:
        raise ParameterError(f"{display}: {len(imu)} {IMU_TYPE} topics; choose one with"
                             f" {option_hint('--topic NAME', 'topic=')}: {', '.join(imu)}")
    return imu[0], infos[imu[0]]


def decode_batch(raws: list[bytes], ros1: bool) -> tuple[np.ndarray, np.ndarray] | None:
    """Header stamps (int64 ns) and the 6 channels (6, m) of serialised Imu messages.

    Returns None when the batch does not have one plain layout (different
    frame_id lengths, big-endian CDR …): the caller then deserialises it.
    """
    m = len(raws)
    size = len(raws[0])
    if any(len(r) != size for r in raws) or size < 16:
        return None
    buf = np.frombuffer(b"".join(raws), dtype=np.uint8).reshape(m, size)
    if ros1:
        head = 16  # seq, stamp.sec, stamp.nsec, frame_id length
        sec = buf[:, 4:8].copy().view("<u4").astype(np.int64).ravel()
    else:
        if not (np.all(buf[:, 0] == 0) and np.all(buf[:, 1] == 1)):  # CDR little-endian
            return None
        sec = buf[:, 4:8].copy().view("<i4").astype(np.int64).ravel()
        head = 16
    nsec = buf[:, 8:12].copy().view("<u4").astype(np.int64).ravel()
    flen = buf[:, 12:16].copy().view("<u4").ravel()
    if np.any(flen != flen[0]):
        return None
    body = head + int(flen[0])
    if not ros1:
        body = 4 + (((body - 4) + 7) & ~7)  # doubles are 8-aligned from the end of the CDR header
    if size != body + 8 * _WORDS:
        return None
    values = np.empty((6, m))
    for c, word in enumerate((_GYRO_WORD, _GYRO_WORD + 1, _GYRO_WORD + 2,
                              _ACCEL_WORD, _ACCEL_WORD + 1, _ACCEL_WORD + 2)):
        o = body + 8 * word
        values[c] = buf[:, o:o + 8].copy().view("<f8").ravel()
    return sec * 1_000_000_000 + nsec, values


def _slow(reader: Any, conn: Any, raw: bytes) -> tuple[int, tuple[float, ...]]:
    msg = reader.deserialize(raw, conn.msgtype)
    stamp = int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)
    w, a = msg.angular_velocity, msg.linear_acceleration
    return stamp, (w.x, w.y, w.z, a.x, a.y, a.z)


@register("rosbag1", extensions=(".bag",), description="ROS 1 bag with sensor_msgs/Imu (needs extra 'ros')",
          options=("topic", "stamps"))
def read_bag1(path: Path, display: str, opts: Options, progress: Progress) -> Table:
    return read_bag(path, display, opts, progress)


@register("rosbag2", extensions=(".db3", ".mcap"),
          description="ROS 2 bag (directory, .db3 or .mcap) with sensor_msgs/msg/Imu (needs extra 'ros')",
          options=("topic", "stamps"))
def read_bag2(path: Path, display: str, opts: Options, progress: Progress) -> Table:
    return read_bag(path, display, opts, progress)


def read_bag(path: Path, display: str, opts: Options, progress: Progress) -> Table:
    ros1 = _is_ros1(path)
    bag = _Bag(path, display)
    warnings: list[str] = []
    try:
        topic, info = _choose_topic(bag, opts.topic, display)
        total = int(info.msgcount)
        progress.set_total(total, unit="messages")
        stamps = np.empty(total, dtype=np.int64)
        received = np.empty(total, dtype=np.int64)
        values = np.empty((6, total))
        n = 0
        fast: bool | None = None
        batch: list[bytes] = []
        batch_conns: list[Any] = []
        batch_times: list[int] = []

        def flush() -> None:
            nonlocal n, fast, stamps, received, values
            m = len(batch)
            if n + m > stamps.shape[0]:  # the bag's index under-counted: grow
                grow = max(n + m, int(stamps.shape[0] * 1.5))
                stamps = np.concatenate([stamps[:n], np.empty(grow - n, dtype=np.int64)])
                received = np.concatenate([received[:n], np.empty(grow - n, dtype=np.int64)])
                values = np.concatenate([values[:, :n], np.empty((6, grow - n))], axis=1)
            decoded = decode_batch(batch, ros1) if fast is not False else None
            if decoded is not None and fast is None:
                s0, v0 = _slow(bag.reader, batch_conns[0], batch[0])
                fast = s0 == decoded[0][0] and np.array_equal(np.array(v0), decoded[1][:, 0], equal_nan=True)
                if not fast:
                    decoded = None
            if decoded is None:
                for k, (conn, raw) in enumerate(zip(batch_conns, batch)):
                    stamps[n + k], values[:, n + k] = _slow(bag.reader, conn, raw)
            else:
                stamps[n:n + m], values[:, n:n + m] = decoded
            received[n:n + m] = batch_times
            n += m
            batch.clear()
            batch_conns.clear()
            batch_times.clear()
            progress.update(n)

        try:
            for conn, t, raw in bag.reader.messages(connections=info.connections):
                batch.append(bytes(raw))
                batch_conns.append(conn)
                batch_times.append(t)
                if len(batch) >= _BATCH:
                    flush()
            if batch:
                flush()
        except FormatError:
            raise
        except Exception as exc:  # damaged chunk, bad serialisation …
            raise bag.error(exc) from None
        temperature = _temperature_messages(bag, opts) if opts.columns is None else None
    finally:
        bag.close()
    stamps, received, values = stamps[:n], received[:n], values[:, :n]
    source = "header.stamp"
    if opts.stamps == "bag":
        times, source = received, "bag receive time"
    elif n and not stamps.any():
        times, source = received, "bag receive time"
        warnings.append(f"{display}: every header.stamp on {topic} is zero; using the bag receive times")
    else:
        times = stamps
    names = list(CHANNELS)
    sel = select(names, [True] * 6, columns=opts.columns, time_column=False, path=display, what="channel")
    data = {names[j]: values[j] for j in sel.channels}
    units = {k: ("rad/s" if k.startswith("gyro") else "m/s^2") for k in data}
    detail_temp = ""
    if temperature is not None:
        name_t, t_ns, t_val = temperature
        column = _on_imu_times(times, t_ns, t_val)
        covered = float(np.mean(~np.isnan(column))) if column.size else 0.0
        if covered >= TEMPERATURE_COVERAGE:
            data["temperature"] = column
            units["temperature"] = "degC"
            names.append("temperature")
            detail_temp = f"; temperature from {name_t} ({TEMPERATURE_TYPE}, {t_ns.size} messages, interpolated)"
        else:
            warnings.append(f"{display}: temperature topic {name_t} spans {100 * covered:.3g} % of the IMU"
                            f" samples (at least {100 * TEMPERATURE_COVERAGE:g} % is needed); not used")
    digest, size = file_sha256(path)
    storage = _storage(path)
    return Table(
        format="rosbag1" if ros1 else "rosbag2",
        columns=tuple(names), data=data, rows=n, sha256=digest, size=size,
        time=times, time_name=source, time_unit="ns", time_unit_reason=f"{source} in ns",
        units=units, unit_origin="format",
        detail=f"topic {topic} ({IMU_TYPE}, {n} messages), storage {storage}; time from {source}{detail_temp}",
        topic=topic, warnings=warnings,
    )


def _temperature_messages(bag: _Bag, opts: Options) -> tuple[str, np.ndarray, np.ndarray] | None:
    """The one ``sensor_msgs/msg/Temperature`` topic of the bag as (name, times in ns, °C), sorted by
    time (header stamps, or the receive times when asked or when every stamp is zero); None when the
    bag has none or several (which one is the IMU's cannot be told)."""
    found = [(n, i) for n, i in bag.reader.topics.items() if i.msgtype == TEMPERATURE_TYPE]
    if len(found) != 1:
        return None
    name, info = found[0]
    stamps, received, values = [], [], []
    for conn, t, raw in bag.reader.messages(connections=info.connections):
        msg = bag.reader.deserialize(bytes(raw), conn.msgtype)
        stamps.append(int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec))
        received.append(int(t))
        values.append(float(msg.temperature))
    if len(values) < 2:
        return None
    times = np.array(received if opts.stamps == "bag" or not any(stamps) else stamps, dtype=np.int64)
    order = np.argsort(times, kind="stable")
    return name, times[order], np.array(values)[order]


def _on_imu_times(imu_ns: np.ndarray, t_ns: np.ndarray, values: np.ndarray) -> np.ndarray:
    """The temperature linearly interpolated at the IMU times; NaN outside the topic's time span."""
    if imu_ns.size == 0:
        return np.empty(0)
    origin = int(imu_ns[0])
    x = (imu_ns - origin).astype(np.float64)
    xp = (t_ns - origin).astype(np.float64)
    return np.interp(x, xp, values, left=np.nan, right=np.nan)
