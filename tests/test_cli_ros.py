"""``sigmatau analyze`` on ROS 1 and ROS 2 (sqlite3 and MCAP) bags written here with ``rosbags`` itself."""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

import numpy as np
import pytest

from sigmatau.cli import main

pytest.importorskip("rosbags")
pytest.importorskip("matplotlib")

from test_io_ros import IMU, _imu, _store, write_bag  # noqa: E402

RATE = 200.0
N = 24_000  # 2 min at 200 Hz
T0 = 1_700_000_000_000_000_000
KINDS = ["ros1", "sqlite3", "mcap"]
GYRO_N = 1.7e-4  # rad/s/√Hz (EuRoC ADIS16448 class)
ACCEL_N = 2.0e-3  # m/s²/√Hz


def _digest(path: Path) -> str:
    files = sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]
    h = hashlib.sha256()
    for f in files:
        h.update(f.read_bytes())
    return h.hexdigest()


@pytest.fixture(scope="module")
def bags(tmp_path_factory):
    rng = np.random.default_rng(7)
    gyro = rng.standard_normal((N, 3)) * GYRO_N * math.sqrt(RATE)
    accel = rng.standard_normal((N, 3)) * ACCEL_N * math.sqrt(RATE) + [0.0, 0.0, 9.81]
    stamps = T0 + (np.arange(N, dtype=np.int64) * int(1e9 / RATE))
    folder = tmp_path_factory.mktemp("bags")
    out = {}
    for kind in KINDS:
        ros1 = kind == "ros1"
        ts = _store(ros1)
        msgs = [(int(stamps[i]) + 300_000, _imu(ts, ros1, i, int(stamps[i]), gyro[i], accel[i])) for i in range(N)]
        other = msgs[:50]
        name = "run.bag" if ros1 else f"run_{kind}"
        out[kind] = write_bag(folder / name, kind, {"/imu/data": msgs, "/imu/other": other}, {"/imu/data": IMU,
                                                                                              "/imu/other": IMU})
    return out, gyro, accel


@pytest.mark.slow
@pytest.mark.parametrize("kind", KINDS)
def test_analyze_bag_end_to_end(bags, kind, tmp_path, capsys):
    paths, gyro, _ = bags
    bag = paths[kind]
    before = _digest(bag)
    assert main(["analyze", str(bag), "--list-topics"]) == 0
    listing = capsys.readouterr().out
    assert "/imu/data\tsensor_msgs/msg/Imu\t24000 messages" in listing
    assert "/imu/other" in listing
    # two IMU topics: the topic must be chosen, and the error lists them
    code = main(["analyze", str(bag), "--out", str(tmp_path / "x"), "--no-figures"])
    err = capsys.readouterr().err
    assert code == 2 and "/imu/data" in err and "/imu/other" in err and len(err.strip().splitlines()) == 1
    code = main(["analyze", str(bag), "--topic", "/imu/nothing", "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err
    assert code == 2 and "/imu/nothing" in err and "/imu/data" in err
    out = tmp_path / "res"
    code = main(["analyze", str(bag), "--topic", "/imu/data", "--out", str(out), "--stat", "oadev,mdev",
                 "--rostopic", "/imu/data", "--quiet"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert _digest(bag) == before
    data = json.loads((out / "results.json").read_text())
    assert data["input"]["topic"] == "/imu/data"
    assert data["log"]["rate"] == pytest.approx(RATE, rel=1e-9)
    chans = {c["name"]: c for c in data["channels"]}
    assert list(chans) == ["gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"]
    # the statistic equals the library's on the samples written into the bag
    import sigmatau

    ref = sigmatau.oadev(gyro[:, 1], rate=RATE)
    assert np.allclose(chans["gyro_y"]["statistics"]["oadev"]["dev"], ref.dev, rtol=1e-12, atol=0)
    n = chans["gyro_x"]["model"]["si"]["N"]
    assert n["low"] < GYRO_N * 1.03 and n["high"] > GYRO_N * 0.97
    import yaml

    doc = yaml.safe_load((out / "imu.yaml").read_text())
    assert doc["rostopic"] == "/imu/data" and doc["update_rate"] == pytest.approx(RATE)
    assert doc["accelerometer_noise_density"] == pytest.approx(ACCEL_N, rel=0.05)
    assert (out / "report.html").is_file() and (out / "sigma_tau_gyro.png").is_file()


def test_corrupt_bag_is_a_data_error(bags, tmp_path, capsys):
    paths, _, _ = bags
    bad = tmp_path / "broken.bag"
    bad.write_bytes(paths["ros1"].read_bytes()[:5000])
    code = main(["analyze", str(bad), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 1 and "broken.bag" in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not (tmp_path / "o").exists()
