"""Every ``sigmatau`` command the README prints runs, as printed, in a shell.

The commands are read from README.md itself (indented code lines and inline code spans that are
whole commands), so a command added to or changed in the README is exercised here or fails
``test_every_readme_command_is_exercised``. Each runs through ``bash -c`` exactly as printed, in
an empty temporary directory prepared with the input files the command names, with the
``sigmatau`` of this environment first on PATH and no Dask client in this process.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
BIN = Path(sys.executable).parent


def readme_commands() -> list[str]:
    """Whole ``sigmatau`` commands printed in the README (synopsis lines with ``[…]`` excluded)."""
    text = README.read_text(encoding="utf-8")
    text = re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)  # fenced blocks: synopsis, doctests
    found: list[str] = []
    for line in text.splitlines():
        if line.startswith("    ") and "sigmatau " in line:
            cmd = line.strip().split("  #")[0].strip()
            found.append(cmd)
    for span in re.findall(r"`(sigmatau [^`]+)`", text):
        if " --" in span and not re.search(r"[\[|…]|\.\.\.", span):
            found.append(span.strip())
    return list(dict.fromkeys(found))


def _shell(cmd: str, cwd: Path, timeout: float = 600) -> subprocess.CompletedProcess:
    env = dict(os.environ, PATH=f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}")
    env.pop("DASK_SCHEDULER_ADDRESS", None)
    return subprocess.run(["bash", "-c", cmd], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=timeout, stdin=subprocess.DEVNULL)


def _ok(cmd: str, cwd: Path, timeout: float = 600) -> subprocess.CompletedProcess:
    r = _shell(cmd, cwd, timeout)
    assert r.returncode == 0, f"{cmd!r} exited {r.returncode}:\n{r.stderr[-3000:]}"
    assert "Traceback" not in r.stderr
    return r


DEMO = 'python -m pip install -e ".[plot]" && sigmatau demo'
TOUR = [
    "sigmatau simulate imu.csv --preset lsm6dsl --duration 1800",
    "sigmatau analyze imu.csv --out imu-report --no-figures",
    "sigmatau stats imu.csv --stat oadev,mdev --columns gyro_x",
]
BATCH = "sigmatau batch 'line3/*.csv' --out line3-fleet --limits lsm6dsl"
BATCH_CLUSTER = ("sigmatau batch '/data/line3/*.csv' --out /data/line3-fleet "
                 "--scheduler tcp://10.0.0.5:8786")
CHUNKED = "sigmatau stats month.npy --chunked --rate 1000 --stat oadev,mdev,totdev"
OUT_OF_CORE = "sigmatau analyze day.npz --memory-limit 1GiB"
HELP = "sigmatau COMMAND --help"
EXPORT = "sigmatau analyze imu.csv --out imu-ekf --no-figures --export kalibr,vins,openvins,matlab,gtsam"
COMPARE_TOUR = [
    "sigmatau simulate rig.csv --preset lsm6dsl --sensors gyro --duration 600",
    "sigmatau compare rig.csv --out rig-hat",
    "sigmatau psd rig.csv --out rig-psd",
]
COMPARE_LOGS = "sigmatau compare a.csv b.csv c.csv --columns gyro_z"
STABLE32_OUT = "sigmatau simulate clock.dat --h 'h0=1e-22' --data-type phase --duration 10000"
WATCH = [
    "sigmatau simulate imu.csv --preset lsm6dsl --duration 600",
    "sigmatau watch imu.csv --serve --until-idle 2 --out imu-live --no-figures",
]
EXERCISED = {DEMO, *TOUR, EXPORT, BATCH, BATCH_CLUSTER, CHUNKED, OUT_OF_CORE, HELP, *COMPARE_TOUR, COMPARE_LOGS,
             STABLE32_OUT, *WATCH}


def test_every_readme_command_is_exercised():
    commands = readme_commands()
    assert set(commands) == EXERCISED, (
        f"README commands not exercised here: {sorted(set(commands) - EXERCISED)}; "
        f"exercised but no longer in the README: {sorted(EXERCISED - set(commands))}")


@pytest.mark.slow
def test_readme_demo(tmp_path):
    install, demo = (part.strip() for part in DEMO.split("&&"))
    assert install == 'python -m pip install -e ".[plot]"'  # this environment has it (and more)
    r = _ok(demo, tmp_path)
    out = tmp_path / "sigmatau-demo"
    for name in ("results.json", "statistics.csv", "model.csv", "report.html"):
        assert (out / name).is_file(), name
    assert "gyro" in r.stdout


@pytest.mark.slow
def test_readme_tour(tmp_path):
    for cmd in TOUR:
        r = _ok(cmd, tmp_path)
    results = json.loads((tmp_path / "imu-report" / "results.json").read_text(encoding="utf-8"))
    assert results["channels"]
    # the last command prints Stable32-style tables of gyro_x only
    assert "gyro_x" in r.stdout and "oadev" in r.stdout.lower() and "mdev" in r.stdout.lower()
    assert "gyro_y" not in r.stdout


@pytest.mark.slow
def test_readme_export(tmp_path):
    _ok("sigmatau simulate imu.csv --preset lsm6dsl --duration 300", tmp_path)
    _ok(EXPORT, tmp_path)
    written = {p.name for p in (tmp_path / "imu-ekf").iterdir()}
    assert {"imu.yaml", "vins_imu.yaml", "kalibr_imu_chain.yaml", "imu_params.m", "gtsam_imu_params.py"} <= written


def _line3(tmp_path: Path) -> None:
    (tmp_path / "line3").mkdir()
    for seed in range(3):
        _ok(f"sigmatau simulate line3/part{seed}.csv --preset lsm6dsl --duration 600 --seed {seed}",
            tmp_path)


@pytest.mark.slow
def test_readme_batch_default_cluster(tmp_path):
    _line3(tmp_path)
    _ok(BATCH, tmp_path)
    fleet = tmp_path / "line3-fleet"
    for name in ("fleet.html", "fleet.csv", "fleet_logs.csv", "fleet.json", "index.jsonl"):
        assert (fleet / name).is_file(), name
    assert len(list((fleet / "logs").iterdir())) == 3
    assert not list(fleet.rglob("*.partial*"))


@pytest.mark.slow
def test_readme_batch_existing_scheduler(tmp_path):
    """The README's cluster example with its paths and address replaced by real ones here."""
    distributed = pytest.importorskip("distributed")
    _line3(tmp_path)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=None, host="127.0.0.1") as cluster:
        cmd = (BATCH_CLUSTER.replace("/data/line3-fleet", str(tmp_path / "fleet"))
               .replace("/data/line3", str(tmp_path / "line3"))
               .replace("tcp://10.0.0.5:8786", cluster.scheduler_address))
        _ok(cmd, tmp_path)
    assert len(list((tmp_path / "fleet" / "logs").iterdir())) == 3


@pytest.mark.slow
def test_readme_compare_and_psd(tmp_path):
    for cmd in COMPARE_TOUR:
        r = _ok(cmd, tmp_path)
    for name in ("compare.csv", "compare.json", "compare.png", "report.html"):
        assert (tmp_path / "rig-hat" / name).is_file(), name
    for name in ("psd.csv", "psd.json", "psd.png", "report.html"):
        assert (tmp_path / "rig-psd" / name).is_file(), name
    assert "gyro_z" in r.stdout and "dominates" in r.stdout
    for seed, name in enumerate("abc"):
        _ok(f"sigmatau simulate {name}.csv --preset lsm6dsl --sensors gyro --duration 300 --seed {seed}", tmp_path)
    r = _ok(COMPARE_LOGS, tmp_path)
    # one table per log, each named after its file
    assert [line.split()[0] for line in r.stdout.splitlines() if line.endswith("OADEV [rad/s]")] == ["a", "b", "c"]


def test_readme_stable32_output(tmp_path):
    _ok(STABLE32_OUT, tmp_path)
    values = (tmp_path / "clock.dat").read_text().split()
    assert len(values) == 10_000


@pytest.mark.slow
def test_readme_watch(tmp_path):
    """The README's watch example: a finished log, followed until 2 s without growth, the live page
    served on 127.0.0.1, then the same outputs as ``sigmatau analyze``."""
    for cmd in WATCH:
        r = _ok(cmd, tmp_path)
    assert "live view at http://127.0.0.1:" in r.stderr
    out = tmp_path / "imu-live"
    assert {"results.json", "statistics.csv", "model.csv", "imu.yaml", "report.html"} <= {p.name for p in out.iterdir()}
    _ok("sigmatau analyze imu.csv --out imu-ref --no-figures", tmp_path)
    live = json.loads((out / "results.json").read_text())["channels"]
    ref = json.loads((tmp_path / "imu-ref" / "results.json").read_text())["channels"]
    assert [c["name"] for c in live] == [c["name"] for c in ref]
    for a, b in zip(live, ref):
        assert a["statistics"].keys() == b["statistics"].keys()
        for stat, r in a["statistics"].items():
            np.testing.assert_allclose(r["dev"], b["statistics"][stat]["dev"], rtol=1e-12, atol=0)
            assert r["alpha"] == b["statistics"][stat]["alpha"]


@pytest.mark.slow
@pytest.mark.parametrize("command", ["demo", "analyze", "stats", "compare", "psd", "simulate", "batch", "watch"])
def test_readme_help(tmp_path, command):
    r = _ok(HELP.replace("COMMAND", command), tmp_path, timeout=120)
    assert "examples:" in r.stdout and "exit codes" in r.stdout


@pytest.mark.slow
def test_readme_chunked_stats(tmp_path):
    rng = np.random.default_rng(20261124)
    np.save(tmp_path / "month.npy", rng.standard_normal(200_000))
    r = _ok(CHUNKED, tmp_path)
    low = r.stdout.lower()
    assert "oadev" in low and "mdev" in low and "totdev" in low


@pytest.mark.slow
def test_readme_out_of_core(tmp_path):
    rng = np.random.default_rng(20261207)
    np.savez(tmp_path / "day.npz", gyro_x=rng.standard_normal(50_000) * 1e-3,
             accel_x=rng.standard_normal(50_000) * 1e-2, rate=np.array(100.0))
    # as printed: a day that fits in 1 GiB is analysed in memory …
    r = _ok(OUT_OF_CORE, tmp_path)
    assert "out of core" not in r.stdout and (tmp_path / "day-sigmatau" / "results.json").is_file()
    # … and with a smaller budget the same command reads it in chunks and says so
    r = _ok(OUT_OF_CORE.replace("1GiB", "1MiB") + " --out small --no-figures", tmp_path)
    assert "note: analysed out of core, read in chunks of 65,536 samples" in r.stdout
    memory = json.loads((tmp_path / "small" / "results.json").read_text())["settings"]["memory"]
    assert memory["mode"] == "chunked" and memory["budget"] == 1 << 20
