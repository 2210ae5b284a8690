"""
From a ROS 2 bag to a Kalibr ``imu.yaml``
==========================================

The usual way to calibrate a visual-inertial rig starts with a few hours of an IMU lying still,
recorded as a ROS bag, and ends with the four noise values Kalibr (and most VIO estimators)
read from ``imu.yaml``. This example does the whole trip on a small bag it writes itself:

1. simulate a EuRoC-like IMU (:func:`sigmatau.imu.simulate`) and write it as ``sensor_msgs/Imu``
   messages into a ROS 2 bag with the ``rosbags`` package (``pip install "sigmatau[ros]"``);
2. list the bag's topics and read one (:func:`sigmatau.io.list_topics`, :func:`sigmatau.io.read`):
   the rate comes from the header stamps, with a timing report;
3. analyse it as ``sigmatau analyze`` does (:func:`sigmatau.analysis.analyze_log`): statistics
   with noise types and intervals, and the IEEE 952 model of every axis;
4. print the Kalibr text (:func:`sigmatau.outputs.kalibr_yaml`).

A real record is hours long; 20 minutes at 100 Hz keep this example fast, and the long-τ terms
(bias instability, rate random walk) are then only upper bounds — which the output says.
"""

import tempfile
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

import sigmatau.analysis
import sigmatau.io
import sigmatau.outputs
from sigmatau import imu

rate = 100.0  # Hz
duration = 1200.0  # s
rng = np.random.default_rng(952)

# %%
# A still IMU, simulated
# -----------------------
# The ``euroc-gyro`` and ``euroc-accel`` presets carry the noise of the EuRoC data set's
# ADIS16448 (rad/s and m/s², as ROS's REP 103 wants); gravity sits on the accelerometer's z axis.
gyro = np.column_stack([imu.simulate("euroc-gyro", duration=duration, rate=rate, rng=rng)
                        for _ in range(3)])
accel = np.column_stack([imu.simulate("euroc-accel", duration=duration, rate=rate, rng=rng)
                         for _ in range(3)]) + [0.0, 0.0, 9.81]
n = len(gyro)
stamps = 1_700_000_000_000_000_000 + np.arange(n, dtype=np.int64) * int(1e9 / rate)  # ns

# %%
# Written into a ROS 2 bag
# -------------------------
# ``rosbags`` writes the bag (here the SQLite 3 storage; MCAP works the same) with the message
# definitions of ROS 2 Humble. Each message's header stamp is the sample time.
workdir = Path(tempfile.mkdtemp(prefix="sigmatau-ros2-"))
bag = workdir / "still_imu"
store = get_typestore(Stores.ROS2_HUMBLE)
T = store.types
Imu = "sensor_msgs/msg/Imu"
with Writer(bag, version=9, storage_plugin=StoragePlugin.SQLITE3) as writer:
    connection = writer.add_connection("/imu0", Imu, typestore=store)
    for t, w, a in zip(stamps.tolist(), gyro.tolist(), accel.tolist()):
        header = T["std_msgs/msg/Header"](
            stamp=T["builtin_interfaces/msg/Time"](sec=t // 10**9, nanosec=t % 10**9), frame_id="imu")
        msg = T[Imu](
            header=header,
            orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
            orientation_covariance=np.full(9, -1.0),
            angular_velocity=T["geometry_msgs/msg/Vector3"](x=w[0], y=w[1], z=w[2]),
            angular_velocity_covariance=np.zeros(9),
            linear_acceleration=T["geometry_msgs/msg/Vector3"](x=a[0], y=a[1], z=a[2]),
            linear_acceleration_covariance=np.zeros(9),
        )
        writer.write(connection, t, store.serialize_cdr(msg, Imu))

# %%
# Read back
# ----------
# ``list_topics`` says what the bag holds; ``read`` takes the ``sensor_msgs/Imu`` topic into a
# :class:`~sigmatau.io.SensorLog` (six channels, the rate from the stamps, a timing report of
# jitter, gaps and duplicates). The bag itself is only read.
for topic in sigmatau.io.list_topics(bag):
    print(topic)
log = sigmatau.io.read(bag, topic="/imu0")
print(log)

# %%
# The main job
# -------------
# :func:`~sigmatau.analysis.analyze_log` is what ``sigmatau analyze`` runs: here OADEV and MDEV
# only, to stay quick (the command's default adds TDEV, OHDEV, TOTDEV and TheoH).
analysis = sigmatau.analysis.analyze_log(log, statistics=("oadev", "mdev"), rostopic="/imu0")
print(analysis.summary())

# %%
# The σ–τ curves of the three gyro axes with the fitted model:
ax = analysis.plot(group="gyro")

# %%
# The Kalibr file
# ----------------
# Kalibr reads continuous-time values: the white-noise densities N (``*_noise_density``) and
# the random walks K (``*_random_walk``), the largest of the three axes by default. The comments
# give each axis, the discrete-time equivalents at the bag's rate, and flag what the record was
# too short to resolve. ``sigmatau.outputs.write_outputs(analysis, folder)`` writes it as
# ``imu.yaml`` with the rest of the results (``results.json``, CSV tables, figures, report).
print(sigmatau.outputs.kalibr_yaml(analysis))

# %%
# The same from the command line:
#
# .. code-block:: console
#
#    $ sigmatau analyze still_imu --topic /imu0 --out still-imu-report
