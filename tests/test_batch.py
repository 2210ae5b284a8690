"""``sigmatau.batch``: many logs on a local Dask cluster (loopback only), resume, a killed worker, the CLI.

The logs are 2-minute 6-axis LSM6DSL-like records at 50 Hz from :func:`sigmatau.imu.simulate`
(seeded); two of them have three times the gyro white noise, so they are fleet outliers and
fail the datasheet limit (4 mdps/√Hz × 1.5); one file is random bytes. Every number of the
batch must equal the one of :func:`sigmatau.analysis.analyze_log` run here on the same file:
the same code on the same bytes, so the tolerance is only JSON's round trip (exact for repr).
"""

from __future__ import annotations

import csv
import json
import math
import os
import signal
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from sigmatau import io
from sigmatau.analysis import Preparation, TERMS, analyze_log
from sigmatau.batch import analyze_many, expand_patterns, load_limits
from sigmatau.cli import main
from sigmatau.errors import ParameterError
from sigmatau.imu import PRESETS, simulate
from sigmatau.units import convert

distributed = pytest.importorskip("distributed")
pytest.importorskip("matplotlib")

N_LOGS = 20
NOISY = ("log05", "log13")
STATS = "oadev"  # the model is fitted on OADEV; the other statistics only cost time here


def _write_log(path: Path, seed: int, *, duration: float = 120.0, rate: float = 50.0, gyro_n: float = 1.0) -> None:
    streams = np.random.SeedSequence(seed).spawn(6)
    cols = []
    for i, group in enumerate(["gyro"] * 3 + ["accel"] * 3):
        kw = {"N": PRESETS["lsm6dsl-gyro"].N * gyro_n} if group == "gyro" else {}
        cols.append(simulate(f"lsm6dsl-{group}", duration=duration, rate=rate, rng=np.random.default_rng(streams[i]),
                             **kw))
    t = np.arange(cols[0].size) / rate
    header = ["timestamp [s]"] + [f"gyro_{a} [rad/s]" for a in "xyz"] + [f"accel_{a} [m/s^2]" for a in "xyz"]
    np.savetxt(path, np.column_stack([t, *cols]), delimiter=",", fmt="%.10g", header=",".join(header), comments="")


@pytest.fixture(scope="module")
def logs(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("fleet")
    for i in range(N_LOGS):
        name = f"log{i:02d}"
        _write_log(folder / f"{name}.csv", 100 + i, gyro_n=3.0 if name in NOISY else 1.0)
    (folder / "corrupt.csv").write_bytes(np.random.default_rng(0).bytes(4000))
    return folder


@pytest.fixture(scope="module")
def client():
    """Not the process default: a default client hid that batch needed one (issue 11 #1)."""
    with warnings.catch_warnings():  # the scheduler's HTTP port 8787 may be another test run's
        warnings.filterwarnings("ignore", message="Port .* is already in use")
        cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                           dashboard_address=None)
    with cluster, distributed.Client(cluster, set_as_default=False) as c:
        yield c


def _index(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / "index.jsonl").read_text().splitlines()]


def _csv_rows(path: Path) -> list[dict]:
    """The rows of a CSV file read as its consumer would (the file closed: ResourceWarning is an error)."""
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def _result_dirs(out: Path) -> list[Path]:
    return sorted((out / "logs").iterdir())


@pytest.fixture(scope="module")
def fleet(logs, client, tmp_path_factory):
    out = tmp_path_factory.mktemp("run") / "out"
    return analyze_many([str(logs / "*.csv")], out, client=client, statistics=STATS, figures=None,
                        limits="lsm6dsl", progress=False)


@pytest.mark.slow
def test_every_log_once_and_the_corrupt_one_reported(fleet, logs):
    out = fleet.out
    assert len(fleet.records) == N_LOGS and len(fleet.errors) == 1 and not fleet.ok
    assert fleet.computed == N_LOGS and fleet.reused == 0
    err = fleet.errors[0]
    assert Path(err["path"]).name == "corrupt.csv"
    assert err["error"]["type"] == "FormatError" and err["error"]["kind"] == "data"
    assert "binary" in err["error"]["message"] and "\n" not in err["error"]["message"]
    assert sorted(Path(r["path"]).stem for r in fleet.records) == [f"log{i:02d}" for i in range(N_LOGS)]
    assert [d.name for d in _result_dirs(out)] == sorted(r["name"] for r in fleet.records)
    for d in _result_dirs(out):
        assert {"results.json", "record.json", "report.html", "model.csv", "imu.yaml"} <= {p.name for p in d.iterdir()}
    entries = _index(out)
    assert sorted(e["path"] for e in entries) == sorted(str(p) for p in logs.glob("*.csv"))
    for name in ("fleet.csv", "fleet_logs.csv", "fleet.json", "fleet.html", "fleet_hist.png", "fleet_strip.png"):
        assert (out / name).is_file(), name


@pytest.mark.slow
def test_numbers_equal_single_machine_analysis(fleet):
    """Each log's model in the fleet (record and fleet.csv) is analyze_log's, in SI."""
    rows = _csv_rows(fleet.out / "fleet.csv")
    assert len(rows) == N_LOGS * 6 * len(TERMS)
    by_key = {(r["path"], r["channel"], r["term"]): r for r in rows}
    for rec in fleet.records:
        # what `sigmatau analyze` runs by default: the warm-up searched, temperature compensated
        here = analyze_log(io.read(rec["path"]), statistics=STATS, workers=1,
                           prep=Preparation(warmup="auto", temperature="auto"))
        assert rec["sha256"] == here.log.source.sha256
        assert rec["samples"] == len(here.log) and rec["rate"] == here.log.rate
        for ch, mine in zip(here.channels, rec["channels"]):
            assert mine["name"] == ch.name
            for t in TERMS:
                p, q = getattr(ch.model, t).si(), mine["terms"][t]
                assert q["resolved"] == p.resolved and q["unit"] == p.unit
                for key in ("low", "high") + (("value",) if p.resolved else ()):
                    want = getattr(p, key)
                    got = q[key] if q[key] is not None else math.inf
                    assert got == pytest.approx(want, rel=1e-12, abs=0), (rec["path"], ch.name, t, key)
                    cell = by_key[(rec["path"], ch.name, t)][key]
                    assert (float(cell) if cell else math.inf) == pytest.approx(want, rel=1e-12, abs=0)
        for key, value in here.kalibr.items():
            if key in rec["kalibr"] and key != "bounds_used":
                assert rec["kalibr"][key] == pytest.approx(value, rel=1e-12)


@pytest.mark.slow
def test_outliers_limits_and_report(fleet):
    limit = 1.5 * convert(4.0, "mdps/sqrt(Hz)", "rad/s/sqrt(Hz)")
    verdicts = {Path(r["path"]).stem: r["verdict"] for r in fleet.records}
    assert {k for k, v in verdicts.items() if v == "fail"} == set(NOISY)
    assert all(v == "pass" for k, v in verdicts.items() if k not in NOISY)
    gyro_n = [r for r in fleet.rows if r["group"] == "gyro" and r["term"] == "N"]
    assert all(r["limit"] == pytest.approx(limit) for r in gyro_n)
    flagged = {Path(r["path"]).stem for r in gyro_n if r["outlier"]}
    assert flagged == set(NOISY)
    d = next(x for x in fleet.distribution if x["group"] == "gyro" and x["term"] == "N")
    assert d["resolved"] == 3 * N_LOGS and d["fail"] == 6 and d["outliers"] == 6
    assert d["median"] == pytest.approx(PRESETS["lsm6dsl-gyro"].N, rel=0.05)
    page = (fleet.out / "fleet.html").read_text()
    assert "corrupt.csv" in page and "FormatError" in page and "data:image/png;base64," in page
    for rec in fleet.records:
        link = f'logs/{rec["name"]}/report.html'
        assert link in page and (fleet.out / link).is_file()
    data = json.loads((fleet.out / "fleet.json").read_text())
    assert data["analysed"] == N_LOGS and data["failed"] == 1 and len(data["records"]) == N_LOGS
    logs_csv = _csv_rows(fleet.out / "fleet_logs.csv")
    assert len(logs_csv) == N_LOGS + 1
    assert [r["error_type"] for r in logs_csv if r["status"] == "error"] == ["FormatError"]


@pytest.mark.slow
def test_rerun_skips_everything_done(fleet, logs, client):
    before = {d.name: (d / "record.json").stat().st_mtime_ns for d in _result_dirs(fleet.out)}
    again = analyze_many([str(logs / "*.csv")], fleet.out, client=client, statistics=STATS, figures=None,
                         limits="lsm6dsl", progress=False)
    assert again.computed == 0 and again.reused == N_LOGS and len(again.errors) == 1
    assert {d.name: (d / "record.json").stat().st_mtime_ns for d in _result_dirs(fleet.out)} == before
    assert [r["sha256"] for r in again.records] == [r["sha256"] for r in fleet.records]
    with pytest.raises(ParameterError, match="other settings"):
        analyze_many([str(logs / "*.csv")], fleet.out, client=client, statistics="oadev,mdev", figures=None)


@pytest.mark.slow
def test_results_of_other_settings_are_never_reused(logs, client, tmp_path):
    """A forced rerun of some logs with new settings must not make a later run reuse the others'
    old-settings results (they are recomputed)."""
    out = tmp_path / "o"
    two = [str(logs / "log00.csv"), str(logs / "log01.csv")]
    analyze_many(two, out, client=client, statistics="oadev", figures=None, progress=False)
    analyze_many(two[:1], out, client=client, statistics="mdev", figures=None, force=True, progress=False)
    again = analyze_many(two, out, client=client, statistics="mdev", figures=None, progress=False)
    assert again.computed == 1 and again.reused == 1
    for d in _result_dirs(out):
        assert json.loads((d / "results.json").read_text())["settings"]["statistics"] == ["mdev"]


@pytest.mark.slow
def test_estimator_files_per_log(logs, client, tmp_path):
    """--export reaches every log's folder: the files asked for, and Kalibr's only when asked."""
    out = tmp_path / "o"
    two = [str(logs / "log00.csv"), str(logs / "log01.csv")]
    fleet = analyze_many(two, out, client=client, statistics="oadev", figures=None, report=False,
                         exports="vins,gtsam", progress=False)
    assert fleet.computed == 2
    for d in _result_dirs(out):
        names = {p.name for p in d.iterdir()}
        assert {"vins_imu.yaml", "gtsam_imu_params.py"} <= names and "imu.yaml" not in names
    with pytest.raises(ParameterError, match="must be one of"):
        analyze_many(two, tmp_path / "bad", client=client, statistics="oadev", exports="ros", progress=False)
    assert not (tmp_path / "bad").exists()


@pytest.mark.slow
def test_a_foreign_directory_is_not_used_as_out(logs, client, tmp_path):
    out = tmp_path / "proj"
    (out / "logs" / ".keepme").mkdir(parents=True)
    (out / "logs" / ".keepme" / "notes.txt").write_text("important")
    with pytest.raises(ParameterError, match="not a sigmatau batch directory"):
        analyze_many([str(logs / "log00.csv")], out, client=client, statistics="oadev", figures=None)
    assert (out / "logs" / ".keepme" / "notes.txt").read_text() == "important"


@pytest.mark.slow
def test_interrupted_run_resumes_without_duplicates(logs, client, tmp_path):
    out = tmp_path / "out"
    seen: list[str] = []

    def stop_after_five(rec, done, total):
        seen.append(rec["path"])
        if done == 5:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        analyze_many([str(logs / "log*.csv")], out, client=client, statistics=STATS, figures=None, report=False,
                     progress=stop_after_five)
    first = _index(out)
    assert len(first) == 5 and not (out / "fleet.json").exists()
    assert not (out / "batch.lock").exists()
    done_before = {e["name"]: (out / "logs" / e["name"] / "record.json").stat().st_mtime_ns
                   for e in first if e["status"] == "ok"}
    assert len(done_before) == 5
    resumed = analyze_many([str(logs / "log*.csv")], out, client=client, statistics=STATS, figures=None,
                           report=False, progress=False)
    assert len(resumed.records) == N_LOGS and resumed.ok
    assert resumed.computed + resumed.reused == N_LOGS and resumed.reused >= 5
    for name, mtime in done_before.items():  # not recomputed
        assert (out / "logs" / name / "record.json").stat().st_mtime_ns == mtime
    dirs = _result_dirs(out)
    assert len(dirs) == N_LOGS and not [d for d in dirs if d.name.startswith(".")]
    # The journal has one line per finished task; read by path, every log is there once.
    assert {e["path"] for e in _index(out)} == {str(p) for p in logs.glob("log*.csv")}
    assert sorted(r["path"] for r in resumed.records) == sorted({r["path"] for r in resumed.records})


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:Port .* is already in use")  # the HTTP port of the fixture's scheduler
def test_a_worker_killed_mid_run(logs, tmp_path):
    """One of two workers dies while it analyses a log; Dask reruns its task; every log once."""
    out = tmp_path / "out"
    killed: list[str] = []
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster, set_as_default=False) as c:
        before = set(c.scheduler_info()["workers"])

        def kill_one(rec, done, total):
            if done == 3 and not killed:
                busy = [w for w, keys in c.processing().items() if keys]
                killed.append(busy[0])
                pid = c.run(os.getpid, workers=[busy[0]])[busy[0]]
                os.kill(pid, getattr(signal, "SIGKILL", signal.SIGTERM))

        fleet = analyze_many([str(logs / "*.csv")], out, client=c, statistics=STATS, figures=None, report=False,
                             progress=kill_one)
        after = set(c.scheduler_info()["workers"])
    assert killed and killed[0] not in after and before != after
    assert len(fleet.records) == N_LOGS and len(fleet.errors) == 1
    entries = _index(out)
    assert len(entries) == N_LOGS + 1 and len({e["path"] for e in entries}) == N_LOGS + 1
    dirs = _result_dirs(out)
    assert len(dirs) == N_LOGS and not [d for d in dirs if d.name.startswith(".")]


@pytest.mark.slow
def test_cli_on_an_existing_scheduler(logs, client, tmp_path, capsys):
    out = tmp_path / "cli"
    argv = ["batch", str(logs / "log0*.csv"), str(logs / "corrupt.csv"), "--out", str(out),
            "--scheduler", client.scheduler.address, "--stat", STATS, "--no-figures", "--limits", "lsm6dsl", "--quiet"]
    assert main(argv) == 1  # the corrupt file fails; the summary is still written
    text = capsys.readouterr().out
    assert "10 analysed" in text and "1 failed" in text and "FAIL" in text and "log05" in text
    assert "corrupt.csv: FormatError" in text
    rows = _csv_rows(out / "fleet_logs.csv")
    assert len(rows) == 11
    assert main(["batch", str(logs / "log0*.csv"), "--out", str(out), "--scheduler", client.scheduler.address,
                 "--stat", STATS, "--no-figures", "--quiet"]) == 0
    assert "0 now, 10 done before" in capsys.readouterr().out


@pytest.mark.parametrize("argv, message", [
    (["--limits", "nosuchpart"], "unknown datasheet"),
    (["--workers", "0"], "--workers"),
    (["--stat", "bogus"], "unknown statistic"),
    (["--gaps", "split", "--time-unit", "ms", "--columns", "gyro_x", "--rate", "-1"], "rate"),
    (["--scheduler", "foo"], "not a scheduler address"),
])
def test_cli_usage_errors(logs, tmp_path, capsys, argv, message):
    assert main(["batch", str(logs / "log00.csv"), "--out", str(tmp_path / "o"), *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_patterns(logs, tmp_path):
    assert len(expand_patterns([str(logs / "log*.csv"), str(logs / "log00.csv")])) == N_LOGS
    with pytest.raises(ParameterError, match="matches no log"):
        expand_patterns([str(logs / "*.nope")])
    with pytest.raises(ParameterError, match="is a directory"):
        expand_patterns([str(logs)])
    bag = tmp_path / "rosbag2_x"
    bag.mkdir()
    (bag / "metadata.yaml").write_text("x")
    assert expand_patterns([str(tmp_path / "*")]) == [str(bag)]


def test_limits_from_preset_and_files(tmp_path):
    pre = load_limits("lsm6dsl", margin=2.0)
    assert pre["gyro"]["N"]["max"] == pytest.approx(2 * PRESETS["lsm6dsl-gyro"].N)
    assert pre["accel"]["N"]["unit"] == "m/s^2/sqrt(Hz)"
    f = tmp_path / "lim.csv"
    f.write_text("group,term,max,unit\ngyro,N,6,mdps/sqrt(Hz)\naccel,B,50,ug\n")
    lim = load_limits(f)
    assert lim["gyro"]["N"]["max"] == pytest.approx(convert(6.0, "mdps/sqrt(Hz)", "rad/s/sqrt(Hz)"))
    assert lim["accel"]["B"]["max"] == pytest.approx(50e-6 * 9.80665)
    j = tmp_path / "lim.json"
    j.write_text(json.dumps({"gyro": {"B": [10, "deg/h"], "K": 1e-5}}))
    lim = load_limits(j)
    assert lim["gyro"]["B"]["max"] == pytest.approx(convert(10.0, "deg/h", "rad/s")) and lim["gyro"]["K"]["max"] == 1e-5
    for bad, msg in (({"gyro": {"X": 1}}, "term"), ({"mag": {"N": 1}}, "group"), ({"gyro": {"N": "4 furlongs"}}, "unit")):
        with pytest.raises(ParameterError, match=msg):
            load_limits(bad)


@pytest.mark.slow
def test_import_sigmatau_loads_no_dask_and_missing_dask_is_named(monkeypatch):
    code = "import sys, sigmatau, sigmatau.batch, sigmatau.cli.app; sigmatau.cli.app._parser(); " \
           "print([m for m in sys.modules if m.split('.')[0] in ('dask', 'distributed')])"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True).stdout.strip() == "[]"
    from sigmatau.scale import batch
    from sigmatau.io import MissingDependencyError

    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(MissingDependencyError, match=r'sigmatau\[dask\]'):
        batch._distributed()
