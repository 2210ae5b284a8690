"""
A fleet of IMUs on a Dask cluster
==================================

A production line tests many parts of one kind. :func:`sigmatau.batch.analyze_many` (what
``sigmatau batch`` runs) analyses every log as ``sigmatau analyze`` does, one task per log on a
Dask cluster, and summarises the fleet: every noise term with its interval, its distribution
across the parts, robust outliers and pass/fail against limits (here the LSM6DSL datasheet's
typical values × 1.5).

Here: five short simulated logs of an LSM6DSL-like IMU, one of them with a gyro twice as noisy,
on a local cluster of two single-threaded worker processes (``pip install "sigmatau[dask]"``).
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from distributed import Client, LocalCluster

import sigmatau.batch
from sigmatau import imu

rate = 104.0  # Hz, the LSM6DSL's output data rate of the design tip's example
duration = 200.0  # s: enough for the white-noise densities, the terms that pass or fail here
workdir = Path(tempfile.mkdtemp(prefix="sigmatau-fleet-"))

# %%
# Five logs of the same part
# --------------------------
# CSV files as ``sigmatau simulate`` writes them (time in seconds, then the six channels with
# their units in the header). Part 3's gyro has twice the datasheet's noise density.
rng = np.random.default_rng(6)
header = ("timestamp [s],gyro_x [rad/s],gyro_y [rad/s],gyro_z [rad/s],"
          "accel_x [m/s^2],accel_y [m/s^2],accel_z [m/s^2]")
(workdir / "line3").mkdir()
for part in range(5):
    scale = 2.0 if part == 3 else 1.0
    gyro = [scale * imu.simulate("lsm6dsl-gyro", duration=duration, rate=rate, rng=rng) for _ in range(3)]
    accel = [imu.simulate("lsm6dsl-accel", duration=duration, rate=rate, rng=rng) for _ in range(3)]
    t = np.arange(len(gyro[0])) / rate
    np.savetxt(workdir / "line3" / f"part{part}.csv", np.column_stack([t, *gyro, *accel]),
               delimiter=",", header=header, comments="", fmt="%.10g")

# %%
# A local cluster and the batch
# ------------------------------
# ``analyze_many`` starts its own local cluster of single-threaded worker processes when given
# no ``client`` (``workers=`` to size it), as ``sigmatau batch`` does; an existing cluster is used
# through ``client=`` (or ``scheduler="tcp://host:8786"``). Here a client of two workers in this
# process (threads: nothing to spawn; a script that starts worker *processes* itself must do so
# under ``if __name__ == "__main__":``). Figures and reports per log are left out to keep this
# fast; ``limits="lsm6dsl"`` checks each term against the datasheet's typical value ×
# ``limit_margin`` (default 1.5).
with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cluster, \
        Client(cluster) as client:
    fleet = sigmatau.batch.analyze_many(
        str(workdir / "line3" / "*.csv"), workdir / "line3-fleet", client=client,
        statistics=("oadev",), figures=None, report=False, limits="lsm6dsl", progress=False,
    )
print(fleet)
print(fleet.summary())

# %%
# What was written
# -----------------
# Each log's results land in ``logs/<name>-<sha256>/`` as soon as it finishes (``results.json``,
# CSV tables, ``imu.yaml``); the fleet files summarise them.
for path in sorted(p.relative_to(fleet.out) for p in fleet.out.iterdir()):
    print(path)

# %%
# The gyro noise density across the fleet
# ----------------------------------------
# ``fleet.rows`` holds one row per log × channel × term (the rows of ``fleet.csv``).
rows = [r for r in fleet.rows if r.get("group") == "gyro" and r.get("term") == "N"]
print(sorted(rows[0]))

# %%
fig, ax = plt.subplots(figsize=(7, 3.5))
logs = sorted({r["log"] for r in rows})
for i, log in enumerate(logs):
    for r in (r for r in rows if r["log"] == log):
        ax.errorbar(i, r["value"], yerr=[[r["value"] - r["low"]], [r["high"] - r["value"]]], fmt="o",
                    ms=4, color="#c0504d" if r.get("verdict") == "fail" else "#1f4e79")
ax.set_xticks(range(len(logs)), logs, rotation=20, fontsize=8)
ax.set_ylabel("gyro N [rad/s/√Hz]")
ax.set_title("angle random walk of each axis of each part (red: over the limit)")
fig.tight_layout()
