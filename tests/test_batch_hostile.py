"""``sigmatau batch`` as a user (careless or hostile) runs it: real CLI in a subprocess, no default client.

Each test here failed on the code before issue 11 or covered behaviour nobody tested:

- the default local cluster (``--workers N`` or none) must work when no Dask client is the
  process default — the situation of every user; this module never makes a default client, and
  checks it (:func:`distributed.default_client` raises);
- ``--workers`` is capped by the usable cores and the number of logs, and says so;
- ``--scheduler`` with a malformed or unreachable address fails fast, in one line, creating nothing;
- ``batch.lock`` of a live run refuses; of a dead run, a reused PID or an earlier boot is taken over;
- ``index.jsonl`` holds one line per log, content hash and outcome however often it is rerun;
- no cell of ``fleet.csv``/``fleet_logs.csv`` starts a spreadsheet formula (OWASP CSV injection);
- ``--limit-margin`` and limits files (YAML, CSV, JSON), good and malformed;
- the README's batch command runs as printed.

The logs are written by ``sigmatau simulate`` (10 min at 50 Hz, LSM6DSL-like), as a user would.
"""

from __future__ import annotations

import csv
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

from sigmatau.batch import analyze_many, load_limits
from sigmatau.errors import ParameterError, SigmaTauWarning
from sigmatau.units import convert

distributed = pytest.importorskip("distributed")
pytest.importorskip("matplotlib")
pytest.importorskip("yaml")

BIN = Path(sys.executable).parent
SIGMATAU = str(BIN / "sigmatau")
LEAN = ["--stat", "oadev", "--no-figures", "--no-report", "--quiet"]  # the defects do not depend on the analysis
#: LSM6DSL gyro white noise, typical, from its datasheet (4 mdps/√Hz, as ST DT0064 quotes it).
LSM6DSL_GYRO_N = convert(4.0, "mdps/sqrt(Hz)", "rad/s/sqrt(Hz)")


def _env() -> dict[str, str]:
    env = dict(os.environ, PATH=f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}")
    env.pop("DASK_SCHEDULER_ADDRESS", None)  # a user's shell has none
    return env


def _run(args: list[str], cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([SIGMATAU, *args], cwd=cwd, env=_env(), capture_output=True, text=True,
                          timeout=timeout, stdin=subprocess.DEVNULL)


def _simulate(path: Path, seed: int, duration: int = 600) -> None:
    r = _run(["simulate", str(path), "--duration", str(duration), "--rate", "50", "--seed", str(seed), "--quiet"],
             path.parent)
    assert r.returncode == 0, r.stderr


def _one_error_line(r: subprocess.CompletedProcess) -> str:
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert re.match(r"sigmatau( batch)?: error: ", lines[0]) and "Traceback" not in r.stderr
    return lines[0]


def _no_default_client() -> None:
    with pytest.raises(ValueError, match="No clients found"):
        distributed.default_client()


@pytest.fixture(scope="module")
def fleet(tmp_path_factory) -> Path:
    """A folder ``fleet`` with two simulated logs."""
    root = tmp_path_factory.mktemp("user")
    (root / "fleet").mkdir()
    for seed in (1, 2):
        _simulate(root / "fleet" / f"unit{seed}.csv", seed)
    return root


@pytest.fixture(scope="module")
def done(fleet, tmp_path_factory) -> Path:
    """An output directory where both logs are done (a rerun needs no cluster: it reuses them)."""
    out = tmp_path_factory.mktemp("done") / "OUT"
    r = _run(["batch", "fleet/*.csv", "--out", str(out), "--workers", "1", *LEAN], fleet)
    assert r.returncode == 0, r.stderr
    return out


@pytest.fixture(scope="module")
def client():
    """A cluster of this module's own that is NOT the process default (as batch makes its own)."""
    with warnings.catch_warnings():  # the scheduler's HTTP port 8787 may be another test run's
        warnings.filterwarnings("ignore", message="Port .* is already in use")
        cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                                           dashboard_address=None)
    with cluster, distributed.Client(cluster, set_as_default=False) as c:
        _no_default_client()
        yield c


def _copy(out: Path, dest: Path) -> Path:
    shutil.copytree(out, dest)
    return dest


# ------------------------------------------------------------------ 1. the default local cluster


@pytest.mark.slow
@pytest.mark.parametrize("workers", [["--workers", "2"], ["--workers", "1"], []])
def test_default_local_cluster_from_the_cli(fleet, tmp_path, workers):
    """Issue 11 #1: exit 3 'No clients found' on every run with the default local cluster."""
    _no_default_client()
    out = tmp_path / "OUT"
    r = _run(["batch", "fleet/*.csv", "--out", str(out), *workers, *LEAN], fleet)
    assert r.returncode == 0, r.stderr
    assert "Traceback" not in r.stderr
    dirs = sorted(p.name for p in (out / "logs").iterdir())
    assert len(dirs) == 2 and not [d for d in dirs if d.startswith(".")]  # no .staging/.partial left
    assert not list(out.rglob("*.partial*")) and not list(out.rglob("*staging*"))
    index = [json.loads(line) for line in (out / "index.jsonl").read_text().splitlines()]
    assert sorted(Path(e["path"]).name for e in index) == ["unit1.csv", "unit2.csv"]
    assert all(e["status"] == "ok" for e in index)


@pytest.mark.slow
def test_api_local_cluster_is_not_made_the_default(fleet, tmp_path):
    _no_default_client()
    f = analyze_many(str(fleet / "fleet" / "*.csv"), tmp_path / "o", workers=1, statistics="oadev", figures=None,
                     report=False, fleet_figures=False, progress=False)
    assert f.ok and f.computed == 2
    _no_default_client()  # batch's client did not become the process default


@pytest.mark.slow
def test_api_with_a_client_that_is_not_the_default(fleet, client, tmp_path):
    f = analyze_many(str(fleet / "fleet" / "*.csv"), tmp_path / "o", client=client, statistics="oadev",
                     figures=None, report=False, fleet_figures=False, progress=False)
    assert f.ok and f.computed == 2
    assert client.status == "running"  # a client given is left open


# ------------------------------------------------------------------------------ 2. resources


@pytest.mark.slow
def test_workers_capped_by_cores_and_logs(fleet, tmp_path, monkeypatch):
    """Issue 11 #10: --workers 64 started 64 processes for two logs."""
    started = []
    real = distributed.LocalCluster

    def spy(*args, **kw):
        started.append(kw.get("n_workers"))
        return real(*args, **kw)

    monkeypatch.setattr(distributed, "LocalCluster", spy)
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    want = min(cores, 2)
    with warnings.catch_warnings(record=True) as caught:  # not pytest.warns: it re-raises Dask's own warnings
        warnings.simplefilter("always")
        f = analyze_many(str(fleet / "fleet" / "*.csv"), tmp_path / "o", workers=64, statistics="oadev",
                         figures=None, report=False, fleet_figures=False, progress=False)
    ours = [str(w.message) for w in caught if issubclass(w.category, SigmaTauWarning)]
    assert f.ok and started == [want]
    assert len(ours) == 1 and re.match(rf"workers=64 capped to {want}\b", ours[0]) and "\n" not in ours[0]


@pytest.mark.slow
def test_cli_says_once_that_workers_are_capped(fleet, tmp_path):
    r = _run(["batch", "fleet/*.csv", "--out", str(tmp_path / "o"), "--workers", "64", *LEAN], fleet)
    assert r.returncode == 0, r.stderr
    capped = [line for line in r.stderr.splitlines() if "capped" in line]
    assert len(capped) == 1 and capped[0].startswith("sigmatau: warning: ") and "2 log" in capped[0]


# ------------------------------------------------------------------- 3. scheduler, lock, index


@pytest.mark.slow
@pytest.mark.parametrize("address", ["not a url", "foo", "tcp://", "tcp://host:port", "tcp://h:99999",
                                     "http://127.0.0.1:8786", "tcp://a b:8786"])
def test_malformed_scheduler_address_fails_fast_creating_nothing(fleet, tmp_path, address):
    """Issue 11 #11: 'not a url' took 41 s, printed a traceback and left OUT."""
    out = tmp_path / "OUT"
    t0 = time.monotonic()
    r = _run(["batch", "fleet/*.csv", "--out", str(out), "--scheduler", address], fleet, timeout=60)
    assert time.monotonic() - t0 < 15  # the interpreter's start-up included
    assert r.returncode == 2
    line = _one_error_line(r)
    assert "--scheduler" in line and "tcp://host:8786" in line
    assert not out.exists()


def _closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_unreachable_scheduler_fails_fast_creating_nothing(fleet, tmp_path):
    out = tmp_path / "OUT"
    address = f"tcp://127.0.0.1:{_closed_port()}"
    t0 = time.monotonic()
    r = _run(["batch", "fleet/*.csv", "--out", str(out), "--scheduler", address, "--quiet"], fleet, timeout=120)
    assert time.monotonic() - t0 < 15
    assert r.returncode == 1
    line = _one_error_line(r)
    assert address in line and "cannot reach" in line and " s" in line  # the timeout is stated
    assert not out.exists()


def _start_ticks(pid: int) -> int:
    """Field 22 of /proc/<pid>/stat (proc(5)): the process start time in clock ticks after boot."""
    text = Path(f"/proc/{pid}/stat").read_text()
    return int(text[text.rindex(")") + 2:].split()[19])


def _boot_id() -> str:
    return Path("/proc/sys/kernel/random/boot_id").read_text().strip()


linux_only = pytest.mark.skipif(not Path("/proc/self/stat").is_file(), reason="needs /proc (Linux)")


@pytest.fixture
def sleeper():
    p = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)"])
    yield p
    p.kill()
    p.wait()


def _lock(out: Path, **fields) -> Path:
    """``batch.lock`` as the module documents it: a JSON object host, pid, start, boot_id."""
    base = {"host": socket.gethostname(), "pid": os.getpid(), "start": None, "boot_id": None}
    path = out / "batch.lock"
    path.write_text(json.dumps({**base, **fields}))
    return path


@pytest.mark.slow
@linux_only
def test_live_lock_refuses_in_one_line(done, fleet, tmp_path, sleeper):
    out = _copy(done, tmp_path / "OUT")
    lock = _lock(out, pid=sleeper.pid, start=_start_ticks(sleeper.pid), boot_id=_boot_id())
    before = lock.read_bytes()
    r = _run(["batch", "fleet/*.csv", "--out", str(out), *LEAN], fleet)
    assert r.returncode == 2
    line = _one_error_line(r)
    assert f"process {sleeper.pid}" in line and "batch.lock" in line
    assert lock.read_bytes() == before
    with pytest.raises(ParameterError, match="another sigmatau batch"):
        analyze_many(str(fleet / "fleet" / "*.csv"), out, workers=1, statistics="oadev", figures=None, report=False,
                     progress=False)


def _dead_pid() -> tuple[int, int]:
    p = subprocess.Popen([sys.executable, "-c", "import sys; sys.stdin.read()"], stdin=subprocess.PIPE)
    ticks = _start_ticks(p.pid)
    p.communicate(b"")
    return p.pid, ticks


@pytest.mark.slow
@linux_only
@pytest.mark.parametrize("case", ["dead pid", "pid reused", "other boot", "old format, pid reused"])
def test_stale_lock_is_taken_over(done, fleet, tmp_path, sleeper, case):
    out = _copy(done, tmp_path / "OUT")
    if case == "dead pid":
        pid, ticks = _dead_pid()
        lock = _lock(out, pid=pid, start=ticks, boot_id=_boot_id())
    elif case == "pid reused":  # the PID is alive, but it is another process than the one that locked
        lock = _lock(out, pid=sleeper.pid, start=_start_ticks(sleeper.pid) - 100, boot_id=_boot_id())
    elif case == "other boot":
        lock = _lock(out, pid=sleeper.pid, start=_start_ticks(sleeper.pid), boot_id="0" * 8 + "-dead-beef")
    else:  # "host pid", written by sigmatau before the start time was recorded; the lock is an hour old
        lock = out / "batch.lock"
        lock.write_text(f"{socket.gethostname()} {sleeper.pid}")
        os.utime(lock, (time.time() - 3600, time.time() - 3600))
    r = _run(["batch", "fleet/*.csv", "--out", str(out), *LEAN], fleet, timeout=120)
    assert r.returncode == 0, r.stderr
    assert not lock.exists()  # taken over, then released
    assert json.loads((out / "fleet.json").read_text())["reused"] == 2


@pytest.mark.slow
@linux_only
def test_old_format_lock_of_a_live_process_still_holds(done, fleet, tmp_path, sleeper):
    out = _copy(done, tmp_path / "OUT")
    (out / "batch.lock").write_text(f"{socket.gethostname()} {sleeper.pid}")
    r = _run(["batch", "fleet/*.csv", "--out", str(out), *LEAN], fleet)
    assert r.returncode == 2 and f"process {sleeper.pid}" in _one_error_line(r)


@pytest.mark.slow
def test_lock_written_by_a_run_names_the_process(fleet, client, tmp_path):
    """While a run holds it, the lock says who (PID, start time where the system has one, boot id)."""
    seen = []

    def look(rec, done, total):
        seen.append(json.loads((tmp_path / "o" / "batch.lock").read_text()))

    analyze_many(str(fleet / "fleet" / "*.csv"), tmp_path / "o", client=client, statistics="oadev", figures=None,
                 report=False, fleet_figures=False, progress=look)
    assert seen and seen[0]["pid"] == os.getpid() and seen[0]["host"] == socket.gethostname()
    if Path("/proc/self/stat").is_file():
        assert seen[0]["start"] == _start_ticks(os.getpid()) and seen[0]["boot_id"] == _boot_id()
    assert not (tmp_path / "o" / "batch.lock").exists()


@pytest.mark.slow
def test_index_has_one_line_per_log_and_content(fleet, client, tmp_path):
    """Issue 11 #11: every rerun appended another error line for the same unreadable log."""
    src = tmp_path / "in"
    src.mkdir()
    shutil.copy(fleet / "fleet" / "unit1.csv", src / "good.csv")
    (src / "bad.csv").write_bytes(np.random.default_rng(11).bytes(3000))
    kw = dict(client=client, statistics="oadev", figures=None, report=False, fleet_figures=False, progress=False)
    for _ in range(3):
        f = analyze_many(str(src / "*.csv"), tmp_path / "o", **kw)
        assert len(f.errors) == 1 and len(f.records) == 1
    lines = [json.loads(x) for x in (tmp_path / "o" / "index.jsonl").read_text().splitlines()]
    assert sorted((Path(e["path"]).name, e["status"]) for e in lines) == [("bad.csv", "error"), ("good.csv", "ok")]
    (src / "bad.csv").write_bytes(np.random.default_rng(12).bytes(3000))  # new content: a new line, once
    for _ in range(2):
        analyze_many(str(src / "*.csv"), tmp_path / "o", **kw)
    lines = [json.loads(x) for x in (tmp_path / "o" / "index.jsonl").read_text().splitlines()]
    assert len(lines) == 3 and len({e["sha256"] for e in lines if e["path"].endswith("bad.csv")}) == 2


# ------------------------------------------------------------------------- 4. CSV injection


FORMULA = ("=", "+", "-", "@", "\t", "\r")


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


@pytest.mark.slow
def test_fleet_csvs_never_start_a_formula(fleet, client, tmp_path):
    """Issue 11 #13 (OWASP CSV injection): log names and messages start cells with - = + @."""
    src = tmp_path / "in"
    src.mkdir()
    shutil.copy(fleet / "fleet" / "unit1.csv", src / "-2+3.csv")
    shutil.copy(fleet / "fleet" / "unit2.csv", src / "@SUM(A1).csv")
    for name in ("=HYPERLINK(x).csv", "+1.csv", "-cmd.csv"):
        (src / name).write_bytes(np.random.default_rng(len(name)).bytes(2000))
    f = analyze_many(str(src / "*.csv"), tmp_path / "o", client=client, statistics="oadev", figures=None,
                     report=False, fleet_figures=False, limits="lsm6dsl", progress=False)
    assert len(f.records) == 2 and len(f.errors) == 3
    for name in ("fleet.csv", "fleet_logs.csv"):
        with open(tmp_path / "o" / name, newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
        assert len(rows) > 1
        for row in rows:
            for cell in row:
                assert not (cell.startswith(FORMULA) and not _is_number(cell)), (name, cell)
    with open(tmp_path / "o" / "fleet_logs.csv", newline="", encoding="utf-8") as fh:
        logs = list(csv.DictReader(fh))
    assert sorted(r["log"] for r in logs if r["log"])[0].startswith("'-2_3-")  # shown as text, nothing lost


# ------------------------------------------------------------------- 5. limits and their margin


def _limit_cell(out: Path, group: str, term: str) -> float:
    with open(out / "fleet.csv", newline="", encoding="utf-8") as fh:
        cells = {r["limit"] for r in csv.DictReader(fh) if r["group"] == group and r["term"] == term}
    assert len(cells) == 1
    return float(cells.pop())


@pytest.mark.slow
@pytest.mark.parametrize("margin", ["1.5", "2", "0.5"])
def test_limit_margin(done, fleet, tmp_path, margin):
    out = _copy(done, tmp_path / "OUT")
    args = ["--limits", "lsm6dsl"] + ([] if margin == "1.5" else ["--limit-margin", margin])
    r = _run(["batch", "fleet/*.csv", "--out", str(out), *args, *LEAN], fleet)
    assert r.returncode == 0, r.stderr
    assert _limit_cell(out, "gyro", "N") == pytest.approx(float(margin) * LSM6DSL_GYRO_N, rel=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("margin", ["0", "-1", "nan", "inf", "x"])
def test_bad_limit_margin(fleet, tmp_path, margin):
    out = tmp_path / "OUT"
    r = _run(["batch", "fleet/*.csv", "--out", str(out), "--limits", "lsm6dsl", "--limit-margin", margin, *LEAN],
             fleet)
    assert r.returncode == 2
    assert "--limit-margin" in _one_error_line(r) or "margin" in r.stderr
    assert not out.exists()


GOOD_LIMITS = {
    "lim.yaml": "gyro:\n  N: 6 mdps/sqrt(Hz)\n  B: [10, deg/h]\naccel:\n  N: 1e-3\n",
    "lim.yml": "gyro: {N: '6 mdps/sqrt(Hz)', B: [10, deg/h]}\naccel: {N: 0.001}\n",
    "lim.json": '{"gyro": {"N": "6 mdps/sqrt(Hz)", "B": [10, "deg/h"]}, "accel": {"N": 1e-3}}',
    "lim.csv": "group,term,max,unit\ngyro,N,6,mdps/sqrt(Hz)\ngyro,B,10,deg/h\naccel,N,1e-3,\n",
    "excel.csv": "\ufeffgroup,term,max,unit\r\ngyro,N,6,mdps/sqrt(Hz)\r\ngyro,B,10,deg/h\r\naccel,N,0.001,m/s^2/sqrt(Hz)\r\n",
}


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(GOOD_LIMITS))
def test_limits_files(done, fleet, tmp_path, name):
    (tmp_path / name).write_text(GOOD_LIMITS[name], encoding="utf-8", newline="")
    out = _copy(done, tmp_path / "OUT")
    r = _run(["batch", "fleet/*.csv", "--out", str(out), "--limits", str(tmp_path / name), *LEAN], fleet)
    assert r.returncode == 0, r.stderr
    assert _limit_cell(out, "gyro", "N") == pytest.approx(1.5 * LSM6DSL_GYRO_N, rel=1e-12)  # 6 = 1.5 × 4
    assert _limit_cell(out, "gyro", "B") == pytest.approx(10 * np.pi / 180 / 3600, rel=1e-12)
    assert _limit_cell(out, "accel", "N") == pytest.approx(1e-3, rel=1e-12)


BAD_LIMITS = {
    "syntax.yaml": ("gyro: [1, 2\n", "YAML"),
    "tab.yaml": ("gyro:\n\tN: 1\n", "YAML"),
    "list.yaml": ("- gyro\n- N\n", "map groups"),
    "scalar.yaml": ("gyro: 5\n", "map terms"),
    "empty.yaml": ("", "map groups"),
    "term.yaml": ("gyro:\n  X: 1\n", "term"),
    "group.json": ('{"mag": {"N": 1}}', "group"),
    "syntax.json": ('{"gyro": {"N": 1}', "JSON"),
    "negative.json": ('{"gyro": {"N": -1}}', "positive"),
    "nan.json": ('{"gyro": {"N": NaN}}', "positive"),
    "unit.json": ('{"gyro": {"N": "4 furlongs"}}', "unit"),
    "columns.csv": ("g,t,m\ngyro,N,1\n", "columns"),
    "short.csv": ("group,term,max,unit\ngyro\n", "row 2"),
    "number.csv": ("group,term,max,unit\ngyro,N,lots,\n", "not a number"),
    "twice.csv": ("group,term,max,unit\ngyro,N,1,\ngyro,N,2,\n", "twice"),
    "binary.csv": (None, "UTF-8"),
}


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(BAD_LIMITS))
def test_malformed_limits_files(fleet, tmp_path, name):
    text, message = BAD_LIMITS[name]
    f = tmp_path / name
    if text is None:
        f.write_bytes(b"group,term,max\n\xff\xfe\x00gyro,N,1\n")
    else:
        f.write_text(text, encoding="utf-8")
    before = f.read_bytes()
    out = tmp_path / "OUT"
    r = _run(["batch", "fleet/*.csv", "--out", str(out), "--limits", str(f), *LEAN], fleet)
    assert r.returncode == 2, r.stderr
    line = _one_error_line(r)
    assert message in line and name in line
    assert not out.exists() and f.read_bytes() == before
    with pytest.raises(ParameterError, match=message):
        load_limits(f)


def test_margin_with_a_limits_file_is_said_to_be_unused(tmp_path):
    f = tmp_path / "lim.json"
    f.write_text('{"gyro": {"N": 1e-4}}')
    with pytest.warns(SigmaTauWarning, match="margin"):
        lim = load_limits(f, margin=2.0)
    assert lim["gyro"]["N"]["max"] == 1e-4  # as given
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load_limits(f)  # the default margin is no request: nothing to say


# ----------------------------------------------------------------------------- 6. the README


README_BATCH = "sigmatau batch 'line3/*.csv' --out line3-fleet --limits lsm6dsl"


@pytest.mark.slow
def test_readme_batch_command_as_printed(tmp_path):
    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")
    assert f"    {README_BATCH}\n" in readme
    (tmp_path / "line3").mkdir()
    for seed in (1, 2):
        _simulate(tmp_path / "line3" / f"part{seed}.csv", seed)
    _no_default_client()
    r = subprocess.run(["bash", "-c", README_BATCH], cwd=tmp_path, env=_env(), capture_output=True, text=True,
                       timeout=600, stdin=subprocess.DEVNULL)
    assert r.returncode == 0, r.stderr
    assert "Traceback" not in r.stderr
    fleet_dir = tmp_path / "line3-fleet"
    for name in ("fleet.html", "fleet.csv", "fleet_logs.csv", "fleet.json", "fleet_hist.png", "fleet_strip.png"):
        assert (fleet_dir / name).is_file(), name
    logs = sorted((fleet_dir / "logs").iterdir())
    assert len(logs) == 2 and all((d / "report.html").is_file() and (d / "imu.yaml").is_file() for d in logs)
    assert _limit_cell(fleet_dir, "gyro", "N") == pytest.approx(1.5 * LSM6DSL_GYRO_N, rel=1e-12)
    assert "limits:" in r.stdout and "2 analysed" in r.stdout
