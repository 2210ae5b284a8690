"""sigmatau.io on ROS 1 bags and ROS 2 bags (sqlite3 and MCAP), written here with rosbags itself."""

from __future__ import annotations

import hashlib
import re
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

from sigmatau import DataError, ParameterError, SigmaTauError, io
from sigmatau.io import FormatError, TimingWarning, TopicInfo

rosbags = pytest.importorskip("rosbags")
from rosbags.rosbag1 import Writer as Writer1  # noqa: E402
from rosbags.rosbag2 import StoragePlugin, Writer as Writer2  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

from sigmatau.io._ros import decode_batch  # noqa: E402

IMU = "sensor_msgs/msg/Imu"
TEMPERATURE = "sensor_msgs/msg/Temperature"
N = 600
T0 = 1_700_000_000_123_456_789  # ns
STEP = 5_000_000  # 200 Hz
KINDS = ["ros1", "sqlite3", "mcap"]


def _check(exc_info, kind, *patterns):
    exc = exc_info.value
    assert type(exc) is kind, (type(exc), exc)
    assert isinstance(exc, SigmaTauError)
    msg = str(exc)
    assert "\n" not in msg, msg
    for pattern in patterns:
        assert re.search(pattern, msg, flags=re.IGNORECASE), f"{pattern!r} not in {msg!r}"


def _store(ros1: bool):
    return get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)


def _imu(ts, ros1: bool, seq: int, stamp: int, gyro, accel, frame_id="imu_link"):
    T = ts.types
    header = {"stamp": T["builtin_interfaces/msg/Time"](sec=stamp // 10**9, nanosec=stamp % 10**9),
              "frame_id": frame_id}
    if ros1:
        header["seq"] = seq
    V = T["geometry_msgs/msg/Vector3"]
    return T[IMU](
        header=T["std_msgs/msg/Header"](**header),
        orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
        orientation_covariance=np.full(9, -1.0),
        angular_velocity=V(x=gyro[0], y=gyro[1], z=gyro[2]),
        angular_velocity_covariance=np.arange(9.0),
        linear_acceleration=V(x=accel[0], y=accel[1], z=accel[2]),
        linear_acceleration_covariance=np.arange(9.0) * 2,
    )


def _temperature(ts, ros1: bool, stamp: int, value: float):
    T = ts.types
    header = {"stamp": T["builtin_interfaces/msg/Time"](sec=stamp // 10**9, nanosec=stamp % 10**9), "frame_id": "t"}
    if ros1:
        header["seq"] = 0
    return T[TEMPERATURE](header=T["std_msgs/msg/Header"](**header), temperature=value, variance=0.0)


def write_bag(path: Path, kind: str, topics: dict[str, list[tuple[int, object]]], types: dict[str, str]) -> Path:
    """Write {topic: [(receive time ns, message)]} with rosbags' writers."""
    ros1 = kind == "ros1"
    ts = _store(ros1)
    if ros1:
        writer = Writer1(path)
        serialize = ts.serialize_ros1
    else:
        plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
        writer = Writer2(path, version=9, storage_plugin=plugin)
        serialize = ts.serialize_cdr
    with writer:
        conns = {name: writer.add_connection(name, types[name], typestore=ts) for name in topics}
        for name, msgs in topics.items():
            for t, msg in msgs:
                writer.write(conns[name], t, serialize(msg, types[name]))
    return path


def _suffix(kind):
    return "bag.bag" if kind == "ros1" else f"bag_{kind}"


def _data():
    rng = np.random.default_rng(42)
    gyro = rng.standard_normal((N, 3)) * 1e-3
    accel = rng.standard_normal((N, 3)) * 1e-2 + [0, 0, 9.81]
    stamps = T0 + STEP * np.arange(N, dtype=np.int64)
    received = stamps + 1_000_000 + rng.integers(0, 200_000, N)
    return gyro, accel, stamps, received


@pytest.fixture(scope="module")
def bags(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bags")
    gyro, accel, stamps, received = _data()
    out = {}
    for kind in KINDS:
        ros1 = kind == "ros1"
        ts = _store(ros1)
        imu = [(int(received[i]), _imu(ts, ros1, i, int(stamps[i]), gyro[i], accel[i])) for i in range(N)]
        # a temperature message every 50 IMU samples over the whole record: 20 °C rising 1 °C per message
        temp = [(int(stamps[i]), _temperature(ts, ros1, int(stamps[i]), 20.0 + i / 50)) for i in range(0, N, 50)]
        temp.append((int(stamps[-1]), _temperature(ts, ros1, int(stamps[-1]), 20.0 + (N - 1) / 50)))
        out[kind] = write_bag(folder / _suffix(kind), kind, {"/imu": imu, "/temperature": temp},
                              {"/imu": IMU, "/temperature": TEMPERATURE})
    return out


def _digest(path: Path) -> str:
    files = [path] if path.is_file() else sorted(p for p in path.rglob("*") if p.is_file())
    h = hashlib.sha256()
    for p in files:
        h.update(p.name.encode() + p.read_bytes())
    return h.hexdigest()


@pytest.mark.parametrize("kind", KINDS)
def test_list_topics(bags, kind):
    assert io.list_topics(bags[kind]) == [TopicInfo("/imu", IMU, N), TopicInfo("/temperature", TEMPERATURE, N // 50 + 1)]


@pytest.mark.parametrize("kind", KINDS)
def test_read_back_exactly(bags, kind):
    gyro, accel, stamps, _ = _data()
    before = _digest(bags[kind])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        log = io.read(bags[kind])
    assert _digest(bags[kind]) == before  # the bag is only read
    assert log.source.format == ("rosbag1" if kind == "ros1" else "rosbag2")
    assert log.source.topic == "/imu" and f"storage {'rosbag1' if kind == 'ros1' else kind}" in log.source.detail
    assert log.names == ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z", "temperature")
    np.testing.assert_array_equal(log.as_array()[:, :3], gyro)
    np.testing.assert_array_equal(log.as_array()[:, 3:6], accel)
    # the sensor_msgs/Temperature topic beside the IMU topic, interpolated at the IMU stamps
    np.testing.assert_allclose(log["temperature"], 20.0 + np.arange(N) / 50, rtol=0, atol=1e-9)
    assert "temperature from /temperature" in log.source.detail
    assert log.units == {**{f"gyro_{a}": "rad/s" for a in "xyz"}, **{f"accel_{a}": "m/s^2" for a in "xyz"},
                         "temperature": "degC"}
    assert set(log.unit_origin.values()) == {"format"}
    np.testing.assert_array_equal(log.timestamps, (stamps - stamps[0]) / 1e9)
    assert log.time_origin == pytest.approx(T0 / 1e9, abs=1e-6)
    assert log.rate == 200.0 and log.timing.jitter_rms == 0 and log.timing.time_column == "header.stamp"
    assert len(log.source.sha256) == 64 and log.source.size > 0


@pytest.mark.parametrize("kind", ["sqlite3", "mcap"])
def test_read_storage_file_directly(bags, kind):
    inner = next(bags[kind].glob("*.db3" if kind == "sqlite3" else "*.mcap"))
    assert io.detect_format(inner) == "rosbag2"
    log = io.read(inner, topic="/imu", columns=["accel_z", "gyro_x"])
    gyro, accel, _, _ = _data()
    assert log.names == ("accel_z", "gyro_x")
    np.testing.assert_array_equal(log["accel_z"], accel[:, 2])


@pytest.mark.parametrize("kind", KINDS)
def test_bag_receive_time(bags, kind):
    _, _, _, received = _data()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        log = io.read(bags[kind], stamps="bag")
    assert log.timing.time_column == "bag receive time"
    np.testing.assert_array_equal(log.timestamps, (received - received[0]) / 1e9)
    assert log.timing.jitter_rms > 0 and log.timing.measured_rate == pytest.approx(200, rel=0.05)


@pytest.mark.parametrize("kind", KINDS)
def test_topic_errors(bags, kind):
    with pytest.raises(ParameterError) as e:
        io.read(bags[kind], topic="/imu0")
    _check(e, ParameterError, "no topic '/imu0'", rf"/imu \({IMU}, {N}\)", rf"/temperature \({TEMPERATURE}, {N // 50 + 1}\)")
    with pytest.raises(ParameterError) as e:
        io.read(bags[kind], topic="/temperature")
    _check(e, ParameterError, f"carries {TEMPERATURE}, not {IMU}", "topics are")
    with pytest.raises(ParameterError) as e:
        io.read(bags[kind], columns="gyro_w")
    _check(e, ParameterError, "no channel 'gyro_w'", "'gyro_x'.*'accel_z'")
    with pytest.raises(ParameterError) as e:
        io.read(bags[kind], time_column="stamp")
    _check(e, ParameterError, "time_column= does not apply to ROS bags")


@pytest.mark.parametrize("kind", KINDS)
def test_no_imu_topic_and_two_imu_topics(tmp_path, kind):
    ros1 = kind == "ros1"
    ts = _store(ros1)
    temp = [(T0 + i, _temperature(ts, ros1, T0 + i, 1.0)) for i in range(3)]
    p = write_bag(tmp_path / _suffix(kind), kind, {"/t": temp}, {"/t": TEMPERATURE})
    with pytest.raises(ParameterError) as e:
        io.read(p)
    _check(e, ParameterError, f"no {IMU} topic", rf"/t \({TEMPERATURE}, 3\)")
    imu = [(T0 + i * STEP, _imu(ts, ros1, i, T0 + i * STEP, (1, 2, 3), (4, 5, 6))) for i in range(5)]
    two = write_bag(tmp_path / ("two.bag" if ros1 else "two"), kind, {"/a": imu, "/b": imu}, {"/a": IMU, "/b": IMU})
    with pytest.raises(ParameterError) as e:
        io.read(two)
    _check(e, ParameterError, f"2 {IMU} topics", "topic=", "/a, /b")
    assert len(io.read(two, topic="/b")) == 5


@pytest.mark.parametrize("kind", KINDS)
def test_zero_header_stamps_fall_back_to_receive_time(tmp_path, kind):
    ros1 = kind == "ros1"
    ts = _store(ros1)
    msgs = [(T0 + i * STEP, _imu(ts, ros1, i, 0, (i, 0, 0), (0, 0, 1))) for i in range(50)]
    p = write_bag(tmp_path / _suffix(kind), kind, {"/imu": msgs}, {"/imu": IMU})
    with pytest.warns(io.InputWarning, match="every header.stamp on /imu is zero"):
        log = io.read(p)
    assert log.timing.time_column == "bag receive time" and log.rate == 200.0


@pytest.mark.parametrize("kind", KINDS)
def test_mixed_frame_ids_and_disordered_stamps(tmp_path, kind):
    """Different message sizes take the rosbags path; header stamps going back are sorted."""
    ros1 = kind == "ros1"
    ts = _store(ros1)
    stamps = T0 + STEP * np.arange(40)
    stamps[[10, 11]] = stamps[[11, 10]]
    msgs = [(T0 + i * STEP, _imu(ts, ros1, i, int(stamps[i]), (i, -i, 0.5), (0, 0, i), frame_id="f" * (i % 4)))
            for i in range(40)]
    p = write_bag(tmp_path / _suffix(kind), kind, {"/imu": msgs}, {"/imu": IMU})
    with pytest.warns(TimingWarning, match=r"1 timestamp\(s\) go backwards"):
        log = io.read(p)
    expected = np.arange(40.0)
    expected[[10, 11]] = expected[[11, 10]]
    np.testing.assert_array_equal(log["gyro_x"], expected)
    assert log.timing.out_of_order == 1 and log.timing.gaps == ()


@pytest.mark.parametrize("ros1", [True, False])
def test_fast_decoder_matches_rosbags(ros1):
    ts = _store(ros1)
    rng = np.random.default_rng(7)
    for length in range(10):
        msgs = [_imu(ts, ros1, i, int(T0 + rng.integers(0, 10**12)), rng.standard_normal(3), rng.standard_normal(3),
                     frame_id="x" * length) for i in range(5)]
        raws = [bytes(ts.serialize_ros1(m, IMU) if ros1 else ts.serialize_cdr(m, IMU)) for m in msgs]
        stamps, values = decode_batch(raws, ros1)
        for k in range(len(msgs)):
            back = ts.deserialize_ros1(raws[k], IMU) if ros1 else ts.deserialize_cdr(raws[k], IMU)
            assert stamps[k] == back.header.stamp.sec * 10**9 + back.header.stamp.nanosec
            w, a = back.angular_velocity, back.linear_acceleration
            assert values[:, k].tolist() == [w.x, w.y, w.z, a.x, a.y, a.z]
    if not ros1:
        big = bytes(ts.serialize_cdr(msgs[0], IMU, little_endian=False))
        assert decode_batch([big], ros1) is None  # big-endian CDR goes to rosbags
        # same size, different frame_id lengths (the CDR padding makes up the difference)
        mixed = [bytes(ts.serialize_cdr(_imu(ts, False, 0, T0, (1, 2, 3), (4, 5, 6), frame_id=f), IMU))
                 for f in ("a", "abc")]
        assert len(mixed[0]) == len(mixed[1]) and decode_batch(mixed, False) is None


@pytest.mark.parametrize("kind", KINDS)
def test_gap_in_bag_refused_with_position(tmp_path, kind):
    ros1 = kind == "ros1"
    ts = _store(ros1)
    stamps = T0 + STEP * np.r_[np.arange(100), np.arange(150, 250)]
    msgs = [(int(s), _imu(ts, ros1, i, int(s), (0, 0, 0), (0, 0, 9.8))) for i, s in enumerate(stamps)]
    p = write_bag(tmp_path / _suffix(kind), kind, {"/imu": msgs}, {"/imu": IMU})
    with pytest.raises(DataError) as e:
        io.read(p)
    _check(e, DataError, r"1 gap\(s\)", r"0\.255 s after 0\.495 s", "before sample 100", "50 samples missing")
    assert [len(s) for s in io.read(p, gaps="split").segments()] == [100, 100]


def test_corrupt_and_truncated_bags(bags, tmp_path):
    garbage = tmp_path / "garbage.bag"
    garbage.write_bytes(b"#ROSBAG V2.0\n" + bytes(range(256)) * 8)
    with pytest.raises(FormatError) as e:
        io.read(garbage)
    _check(e, FormatError, "garbage.bag", "cannot read as a ROS 1 bag")
    with pytest.raises(FormatError):
        io.list_topics(garbage)

    mcap = next(bags["mcap"].glob("*.mcap"))
    cut = tmp_path / "cut.mcap"
    data = mcap.read_bytes()
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(FormatError) as e:
        io.read(cut)
    _check(e, FormatError, "cut.mcap", "cannot read as a ROS 2 bag")

    db3 = tmp_path / "not.db3"
    db3.write_bytes(b"SQLite format 3\x00" + b"\x00" * 200)
    with pytest.raises(FormatError) as e:
        io.read(db3)
    _check(e, FormatError, "not.db3", "cannot read as a ROS 2 bag")

    broken = tmp_path / "broken_dir"
    shutil.copytree(bags["sqlite3"], broken)
    (broken / "metadata.yaml").write_text("rosbag2_bagfile_information: [unclosed\n")
    with pytest.raises(FormatError) as e:
        io.read(broken)
    _check(e, FormatError, "broken_dir", "cannot read as a ROS 2 bag")


@pytest.mark.parametrize("kind", ["ros1", "mcap"])
def test_temperature_topic_used_only_when_it_spans_the_record(tmp_path, kind):
    ros1 = kind == "ros1"
    ts = _store(ros1)
    gyro, accel, stamps, received = _data()
    imu = [(int(received[i]), _imu(ts, ros1, i, int(stamps[i]), gyro[i], accel[i])) for i in range(N)]
    short = [(int(stamps[i]), _temperature(ts, ros1, int(stamps[i]), 25.0)) for i in range(0, N // 4, 10)]
    p = write_bag(tmp_path / _suffix(kind), kind, {"/imu": imu, "/t": short}, {"/imu": IMU, "/t": TEMPERATURE})
    with pytest.warns(io.InputWarning, match=r"temperature topic /t spans 2[0-9.]* % of the IMU samples .*not used"):
        log = io.read(p)
    assert "temperature" not in log.names
    # choosing columns leaves the temperature topic alone
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert io.read(p, columns=["gyro_x"]).names == ("gyro_x",)
