"""Hostile names and interrupted runs: every output is read back the way its consumer reads it.

- CSV through the ``csv`` module (a spreadsheet would evaluate a cell starting with ``=+-@``);
- ``imu.yaml`` through PyYAML's ``safe_load`` and its unsafe ``Loader`` (what old Kalibr scripts use);
- terminal output scanned for control characters;
- ``--force`` and interrupted runs checked for what survives in the output directory.
"""

from __future__ import annotations

import csv
import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from helpers import cli_error_line, run_cli, simulated_imu_log


FORMULA_START = ("=", "+", "-", "@", "\t", "\r")


_run = run_cli
_one_line_error = cli_error_line


def _log(path: Path, names: list[str], rng: np.random.Generator, n: int = 2000) -> Path:
    """A CSV log at 100 Hz with a time column and one white-noise column per name."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["t", *names])
    for i, row in enumerate(rng.standard_normal((n, len(names)))):
        w.writerow([f"{i / 100:.2f}", *(repr(float(v)) for v in row)])
    path.write_text(buf.getvalue(), encoding="utf-8")
    return path


# --------------------------------------------------------------------------- CSV


@pytest.mark.parametrize("value, expected", [
    ("=1+2", "'=1+2"), ("+SUM(A1)", "'+SUM(A1)"), ("-2+3", "'-2+3"), ("@cmd", "'@cmd"),
    ("\tx", "'\tx"), ("\rx", "'\rx"), ("gyro_x", "gyro_x"), ("a=b", "a=b"), ("", ""),
    (-1.5, "-1.5"), (-3, "-3"), (np.float64(-2.5e-7), "-2.5e-07"), (np.int64(-4), "-4"),
    (float("nan"), ""), (None, ""), (True, "True"),
])
def test_csv_cell_owasp_rule(value, expected):
    from sigmatau.outputs import csv_cell

    assert csv_cell(value) == expected


HOSTILE_COLUMNS = ["=1+2", "+SUM(A1)", "-2+3", "@cmd"]


def test_csv_outputs_never_start_a_formula(tmp_path, capsys, rng):
    src = _log(tmp_path / "h.csv", HOSTILE_COLUMNS, rng)
    cols = ",".join(str(i) for i in range(1, len(HOSTILE_COLUMNS) + 1))
    code, _, err = _run(["analyze", src, "--out", tmp_path / "o", "--no-figures", "--stat", "oadev",
                         "--columns", cols, "--quiet"], capsys)
    assert code == 0, err
    code, stdout, err = _run(["stats", src, "--stat", "oadev", "--columns", cols, "--csv", "-"], capsys)
    assert code == 0, err
    for text in ((tmp_path / "o" / "statistics.csv").read_text(encoding="utf-8"), stdout):
        rows = list(csv.reader(io.StringIO(text)))
        assert {r[0] for r in rows[1:]} == {"'" + c for c in HOSTILE_COLUMNS}
        for r in rows:
            for cell in r:
                try:
                    float(cell)
                except ValueError:
                    assert not cell.startswith(FORMULA_START), cell


# ------------------------------------------------------------------------ imu.yaml

yaml = pytest.importorskip("yaml")

PWN = '!!python/object/apply:os.system ["touch PWNED"]'
HOSTILE_NAMES = [
    "/imu0\nupdate_rate: 1.0\ngyroscope_noise_density: 0",  # a newline adds or overrides keys
    "/imu: 0", "/it's \"quoted\"", "/tab\there", PWN, "/ジャイロ/ü", "/nel\x85gyroscope_random_walk: 0",
    "/ls\u2028rostopic: x", "/cr\rupdate_rate: 2", "/esc\x1b[2J", "# not a comment", "&a *a", "- item",
    "{update_rate: 3}", "---", "%YAML 1.1", "/bidi\u202eevil",
]
EXPECTED_KEYS = ["accelerometer_noise_density", "accelerometer_random_walk", "gyroscope_noise_density",
                 "gyroscope_random_walk", "rostopic", "update_rate"]


@pytest.fixture(scope="module")
def imu_analysis():
    """A 6-axis simulated log (2 min at 50 Hz, seed 11) analysed with OADEV only."""
    from sigmatau.analysis import analyze_log

    log = simulated_imu_log()
    return analyze_log(log, statistics="oadev", workers=1)


def _hostile(analysis, name: str):
    """The same analysis with ``name`` as its file name, bag topic and rostopic."""
    import dataclasses

    src = dataclasses.replace(analysis.log.source, path=name, topic=name)
    return dataclasses.replace(analysis, log=dataclasses.replace(analysis.log, source=src),
                               kalibr={**analysis.kalibr, "rostopic": name})


def _load_both(text: str) -> tuple[dict, dict]:
    return yaml.safe_load(text), yaml.load(text, Loader=yaml.Loader)  # noqa: S506 - the point of the test


@pytest.mark.parametrize("name", HOSTILE_NAMES)
def test_imu_yaml_round_trips_hostile_names(imu_analysis, name, tmp_path, monkeypatch):
    from sigmatau.outputs import kalibr_yaml

    monkeypatch.chdir(tmp_path)  # where an executed "touch PWNED" would leave its file
    text = kalibr_yaml(_hostile(imu_analysis, name))
    for doc in _load_both(text):
        assert list(doc) == EXPECTED_KEYS
        assert doc["rostopic"] == name
        assert doc["update_rate"] == 50.0
        for key in EXPECTED_KEYS[:4]:
            assert isinstance(doc[key], float) and doc[key] == pytest.approx(imu_analysis.kalibr[key], rel=1e-15)
    assert not (tmp_path / "PWNED").exists()
    for line in text.splitlines():  # every line is a comment or one of our keys
        assert line.startswith("#") or line.split(":")[0] in EXPECTED_KEYS, line
        assert "\x1b" not in line and "\u202e" not in line


@pytest.mark.slow
def test_imu_yaml_from_the_command_line_with_a_hostile_file_name(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    rng = np.random.default_rng(12)
    name = 'log\nupdate_rate: 1\n: "x" \t!!python ü.csv'
    src = _log(tmp_path / name, [f"{g}_{a}" for g in ("gyro", "accel") for a in "xyz"], rng, n=6000)
    code, _, err = _run(["analyze", src, "--out", tmp_path / "o", "--no-figures", "--no-report", "--stat", "oadev",
                         "--rostopic", PWN + " '\": ü", "--quiet"], capsys)
    assert code == 0, err
    text = (tmp_path / "o" / "imu.yaml").read_text(encoding="utf-8")
    for doc in _load_both(text):
        assert list(doc) == EXPECTED_KEYS
        assert doc["rostopic"] == PWN + " '\": ü" and doc["update_rate"] == 100.0
    assert not (tmp_path / "PWNED").exists()


@pytest.mark.parametrize("topic", ["/imu0\nupdate_rate: 1", "/imu\t0", "/imu\x1b[2J", "/imu\x85", "/a\rb"])
def test_rostopic_with_control_characters_is_refused(topic, tmp_path, capsys):
    src = _log(tmp_path / "l.csv", ["gyro_x", "gyro_y", "gyro_z"], np.random.default_rng(13), n=500)
    code, _, err = _run(["analyze", src, "--out", tmp_path / "o", "--no-figures", "--rostopic", topic], capsys)
    assert code == 2
    _one_line_error(err, "--rostopic", "control character")
    assert "\x1b" not in err and not (tmp_path / "o").exists()


@pytest.mark.slow
@pytest.mark.filterwarnings("default::sigmatau.errors.SigmaTauWarning")  # the CLI prints it
def test_without_pyyaml_imu_yaml_is_skipped_with_one_warning(tmp_path, capsys, monkeypatch):
    for name in [m for m in sys.modules if m == "yaml" or m.startswith("yaml.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "yaml", None)  # import yaml -> ImportError
    src = _log(tmp_path / "l.csv", [f"{g}_{a}" for g in ("gyro", "accel") for a in "xyz"],
               np.random.default_rng(14), n=6000)
    code, _, err = _run(["analyze", src, "--out", tmp_path / "o", "--no-figures", "--stat", "oadev", "--quiet"],
                        capsys)
    assert code == 0, err
    warns = [ln for ln in err.splitlines() if ln.strip()]
    assert len(warns) == 1 and "imu.yaml not written" in warns[0] and "sigmatau[yaml]" in warns[0], err
    assert not (tmp_path / "o" / "imu.yaml").exists() and (tmp_path / "o" / "model.csv").exists()


# ------------------------------------------------------------------ --force and leftovers


def _digests(folder: Path) -> dict[str, str]:
    import hashlib

    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def _leftovers(folder: Path) -> list[str]:
    return [p.name for p in folder.iterdir() if ".partial-" in p.name or ".old-" in p.name]


@pytest.fixture
def one_channel(tmp_path) -> Path:
    return _log(tmp_path / "one.csv", ["x"], np.random.default_rng(21), n=2000)


def _analyze(src: Path, out: Path, *extra) -> list[str]:
    return ["analyze", str(src), "--out", str(out), "--stat", "oadev", "--quiet", *map(str, extra)]


def test_force_refuses_a_directory_sigmatau_did_not_write(tmp_path, capsys, one_channel):
    proj = tmp_path / "proj"  # the reproducer
    proj.mkdir()
    (proj / "results.json").write_text("{}\n")
    (proj / "thesis.tex").write_text("x\n")
    before = _digests(proj)
    code, _, err = _run(_analyze(one_channel, proj, "--force", "--no-figures"), capsys)
    assert code == 2
    _one_line_error(err, "not a sigmatau output directory")
    assert _digests(proj) == before
    # a forged manifest naming a file outside the directory is no manifest
    (proj / "sigmatau-manifest.json").write_text(json.dumps({"format": "sigmatau output manifest 1",
        "files": [{"name": "../one.csv", "size": 1, "sha256": "0" * 64}]}))
    code, _, err = _run(_analyze(one_channel, proj, "--force", "--no-figures"), capsys)
    assert code == 2 and one_channel.exists()
    _one_line_error(err, "not a sigmatau output directory")
    assert not _leftovers(tmp_path)


def test_force_replaces_only_our_files(tmp_path, capsys, one_channel):
    from sigmatau.outputs import read_manifest

    res = tmp_path / "res"
    code, _, err = _run(_analyze(one_channel, res, "--figures", "png"), capsys)
    assert code == 0, err
    first = {e["name"] for e in read_manifest(res)}
    assert {"results.json", "statistics.csv", "report.html", "signal_x.png"} <= first
    (res / "thesis.tex").write_text("my thesis\n")  # the user's files, added later
    (res / "notes").mkdir()
    (res / "notes" / "a.txt").write_text("notes\n")
    code, _, err = _run(["analyze", one_channel, "--out", res, "--stat", "mdev", "--no-figures", "--quiet",
                         "--force"], capsys)
    assert code == 0, err
    assert (res / "thesis.tex").read_text() == "my thesis\n" and (res / "notes" / "a.txt").read_text() == "notes\n"
    assert not list(res.glob("*.png"))  # ours from the first run, not written by the second: removed
    assert json.loads((res / "results.json").read_text())["settings"]["statistics"] == ["mdev"]
    manifest = read_manifest(res)
    names = {e["name"] for e in manifest}
    assert names == {p.name for p in res.iterdir() if p.is_file()} - {"thesis.tex", "sigmatau-manifest.json"}
    assert all(e["size"] == (res / e["name"]).stat().st_size for e in manifest)
    assert not _leftovers(tmp_path)


def test_force_refuses_changed_or_foreign_files_of_our_names(tmp_path, capsys, one_channel):
    res = tmp_path / "res"
    assert _run(_analyze(one_channel, res, "--no-figures", "--no-report"), capsys)[0] == 0
    (res / "statistics.csv").write_text("my edits\n")
    code, _, err = _run(_analyze(one_channel, res, "--no-figures", "--force"), capsys)
    assert code == 2
    _one_line_error(err, "statistics.csv", "changed since sigmatau wrote it")
    assert (res / "statistics.csv").read_text() == "my edits\n"
    (res / "statistics.csv").unlink()
    (res / "report.html").write_text("<p>mine</p>\n")  # not written by the first run
    code, _, err = _run(_analyze(one_channel, res, "--no-figures", "--force"), capsys)
    assert code == 2
    _one_line_error(err, "report.html", "not a file sigmatau wrote")
    (res / "report.html").unlink()
    (res / "signal_x.png").write_text("mine\n")  # a figure name: found once the figures are planned
    before = _digests(res)
    code, _, err = _run(_analyze(one_channel, res, "--figures", "png", "--force"), capsys)
    assert code == 2
    _one_line_error(err, "signal_x.png", "not a file sigmatau wrote")
    assert _digests(res) == before
    assert not _leftovers(tmp_path)


def test_force_puts_the_previous_output_back_when_replacing_fails(tmp_path, capsys, one_channel, monkeypatch):
    res = tmp_path / "res"
    assert _run(_analyze(one_channel, res, "--figures", "png"), capsys)[0] == 0
    (res / "thesis.tex").write_text("my thesis\n")
    before = _digests(res)
    real_replace = os.replace

    def failing_replace(src, dst, *a, **k):
        if Path(dst) == res / "statistics.csv" and ".partial-" in str(src):
            raise OSError(28, "No space left on device", str(dst))
        return real_replace(src, dst, *a, **k)

    monkeypatch.setattr(os, "replace", failing_replace)
    code, _, err = _run(_analyze(one_channel, res, "--no-figures", "--force"), capsys)
    monkeypatch.undo()
    assert code == 1
    _one_line_error(err, "No space left on device")
    assert _digests(res) == before  # every previous file back, byte for byte, the user's file untouched
    assert not _leftovers(tmp_path)


def _marked(folder: Path, host: str, pid: int) -> Path:
    from sigmatau.outputs import PARTIAL_MARKER

    folder.mkdir()
    (folder / "results.json").write_text("{}\n")
    (folder / PARTIAL_MARKER).write_text(json.dumps({"host": host, "pid": pid}) + "\n")
    return folder


def test_a_later_run_removes_only_stale_partials_of_ours(tmp_path, capsys, one_channel):
    import socket

    done = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    dead = int(done.stdout)  # a process that has exited
    alive = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        here = socket.gethostname()
        stale = [_marked(tmp_path / ".res.partial-dead1", here, dead),
                 _marked(tmp_path / ".other.old-dead2", here, dead)]
        kept = [_marked(tmp_path / ".res.partial-alive", here, alive.pid),
                _marked(tmp_path / ".res.partial-remote", "another-host.example", dead),
                tmp_path / ".res.partial-nomarker", tmp_path / "res.partial-notours"]
        for d in kept[2:]:
            d.mkdir()
            (d / "x").write_text("user\n")
        code, _, err = _run(_analyze(one_channel, tmp_path / "res", "--no-figures"), capsys)
        assert code == 0, err
        assert not any(d.exists() for d in stale)
        assert all(d.exists() for d in kept)
    finally:
        alive.kill()
        alive.wait()


def test_sigterm_during_analyze_cleans_up_and_exits_143(tmp_path):
    src = _log(tmp_path / "six.csv", [f"c{i}" for i in range(6)], np.random.default_rng(22), n=20000)
    out = tmp_path / "o"
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    proc = subprocess.Popen([sys.executable, "-m", "sigmatau", "analyze", str(src), "--out", str(out), "--stat",
                             "oadev", "--figures", "png,svg,pdf", "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    deadline = time.monotonic() + 120
    while not list(tmp_path.glob(".o.partial-*")) and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    assert proc.poll() is None, "finished before it could be interrupted: make the log longer"
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err
    _one_line_error(err, "terminated")
    assert not out.exists() and not _leftovers(tmp_path)


# ------------------------------------------------------------------------ terminal

ESCAPES = ["x\x1b[31mred", "\x1b]0;title\x07", "y\x9b2J", "bidi\u202eevil"]


def _assert_inert(text: str, keep: str = "\n") -> None:
    """No character that drives a terminal: C0 but ``keep``, DEL, C1, bidirectional overrides."""
    bad = [hex(ord(c)) for c in text if (ord(c) < 0x20 and c not in keep) or 0x7f <= ord(c) <= 0x9f
           or 0x202a <= ord(c) <= 0x202e or 0x2066 <= ord(c) <= 0x2069]
    assert not bad, (bad, text[:2000])


def test_terminal_output_escapes_control_characters(tmp_path, capsys):
    src = _log(tmp_path / "l\x1b[2J.csv", ESCAPES, np.random.default_rng(23))
    cols = ",".join(str(i) for i in range(1, len(ESCAPES) + 1))
    runs = [
        ["analyze", src, "--out", tmp_path / "o", "--no-figures", "--stat", "oadev", "--columns", cols],
        ["stats", src, "--stat", "oadev", "--columns", cols],
        ["stats", src, "--stat", "oadev", "--columns", "nope\x1b[2J"],  # error naming the columns
        ["analyze", tmp_path / "missing\x1b[2J\n.csv", "--out", tmp_path / "o2"],  # error naming the file
        ["stats", src, "--stat", "oadev", "--bogus\x1b[2J"],  # argparse's message
    ]
    for argv in runs:
        code, out, err = _run(argv, capsys)
        _assert_inert(out)
        _assert_inert(err)
        if code != 0:
            line = _one_line_error(err)
            assert "\\x1b" in line, line  # shown escaped, not dropped
        else:
            assert "\\x1b[31mred" in out and "\\x1b]0;title\\x07" in out and "\\u202e" in out


def test_list_topics_escapes_control_characters(tmp_path, capsys):
    pytest.importorskip("rosbags")
    from test_io_ros import IMU, _imu, _store, write_bag

    ts = _store(False)
    topic = "/imu\x1b]0;pwned\x07\x1b[2J"
    msgs = [(10**9 + i * 10**7, _imu(ts, False, i, 10**9 + i * 10**7, [0.0, 0.0, 0.0], [0.0, 0.0, 9.8]))
            for i in range(10)]
    bag = write_bag(tmp_path / "bag", "mcap", {topic: msgs}, {topic: IMU})
    code, out, err = _run(["analyze", bag, "--list-topics"], capsys)
    assert code == 0, err
    _assert_inert(out, keep="\n\t")  # the tabs between the fields are ours
    assert "/imu\\x1b]0;pwned\\x07\\x1b[2J\tsensor_msgs/msg/Imu\t10 messages" in out


# ----------------------------------------------------------------------- resources


@pytest.mark.filterwarnings("default::sigmatau.errors.SigmaTauWarning")  # the CLI prints it
def test_figures_are_capped_and_the_cap_is_said_once(tmp_path, capsys, monkeypatch):
    from sigmatau.report import outputs

    monkeypatch.setattr(outputs, "MAX_SIGNAL_FIGURES", 2)
    monkeypatch.setattr(outputs, "MAX_SIGMA_TAU_FIGURES", 1)
    monkeypatch.setattr(outputs, "MAX_CURVES_PER_FIGURE", 2)
    src = _log(tmp_path / "wide.csv", ["a", "b", "c"], np.random.default_rng(24), n=1000)
    out = tmp_path / "o"
    code, _, err = _run(["analyze", src, "--out", out, "--stat", "oadev", "--figures", "png", "--no-model",
                         "--quiet"], capsys)
    assert code == 0, err
    warns = [ln for ln in err.splitlines() if ln.strip()]
    assert len(warns) == 1 and "figures limited" in warns[0] and "first 2 of 3 channels" in warns[0], err
    assert sorted(p.name for p in out.glob("*.png")) == ["sigma_tau_other.png", "signal_a.png", "signal_b.png"]
    data = json.loads((out / "results.json").read_text(encoding="utf-8"))
    assert "figures limited" in data["figures_note"] and len(data["channels"]) == 3
    assert "figures limited" in (out / "report.html").read_text(encoding="utf-8")
    with open(out / "statistics.csv", encoding="utf-8") as fh:
        assert len({r[0] for r in csv.reader(fh)}) == 4  # the header and every channel



# ------------------------------------------------------------------------ messages


def test_no_message_offers_an_option_that_would_be_refused(tmp_path, capsys, one_channel):
    folder = tmp_path / "x.csv"
    folder.mkdir()
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    cases = [(["simulate", folder, "--duration", "10"], "is a directory"),
             (["stats", one_channel, "--stat", "oadev", "--csv", folder], "is a directory"),
             (["stats", one_channel, "--stat", "oadev", "--csv", fifo], "not a regular file")]
    for argv, why in cases:
        for extra in ([], ["--force"]):
            code, _, err = _run([*argv, *extra], capsys)
            assert code == 2, (argv, extra, err)
            line = _one_line_error(err, why)
            assert "--force" not in line, line
    assert folder.is_dir() and not any(folder.iterdir()) and fifo.exists() and not fifo.is_file()
    # where --force is accepted, it is offered
    made = tmp_path / "made.csv"
    assert _run(["simulate", made, "--duration", "10"], capsys)[0] == 0
    code, _, err = _run(["simulate", made, "--duration", "10"], capsys)
    assert code == 2
    _one_line_error(err, "exists", "--force")
    assert _run(["simulate", made, "--duration", "10", "--force"], capsys)[0] == 0


# ------------------------------------------------------------- report.html's interactive charts

CHART_NAMES = ["</script><script>alert(1)</script>", "<!--", "\"quoted\" & 'single' \u2028 </SCRIPT >",
               "<img src=x onerror=alert(2)>"]


def _script_elements(page: str) -> list[tuple[dict, str]]:
    """Every ``<script>`` element of the page as the HTML parser sees it: (attributes, text)."""
    from html.parser import HTMLParser

    found: list[tuple[dict, str]] = []

    class Scripts(HTMLParser):
        def handle_starttag(self, tag, attrs):
            if tag == "script":
                found.append((dict(attrs), ""))

        def handle_data(self, data):
            if found and self.lasttag == "script" and self.cdata_elem == "script":
                found[-1] = (found[-1][0], found[-1][1] + data)

    Scripts(convert_charrefs=True).feed(page)
    return found


@pytest.mark.slow
def test_report_charts_keep_hostile_channel_names_as_data(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    pytest.importorskip("vl_convert")  # the interactive extra
    src = _log(tmp_path / "h.csv", CHART_NAMES, np.random.default_rng(25))
    cols = ",".join(str(i) for i in range(1, len(CHART_NAMES) + 1))
    code, _, err = _run(["analyze", src, "--out", tmp_path / "o", "--stat", "oadev,tdev", "--figures", "png",
                         "--columns", cols, "--quiet"], capsys)
    assert code == 0, err
    page = (tmp_path / "o" / "report.html").read_text(encoding="utf-8")
    scripts = _script_elements(page)
    # one spec (one σ–τ figure: the group of these channels), the library and the code that draws:
    # no element that a name could have opened
    assert [a.get("type") for a, _ in scripts] == ["application/json", None, None]
    assert page.lower().count("<script") == 3 and page.lower().count("</script>") == 3
    spec = json.loads(scripts[0][1])
    names = [c["name"] for c in json.loads((tmp_path / "o" / "results.json").read_text(encoding="utf-8"))["channels"]]
    assert names[:2] == CHART_NAMES[:2] and "</SCRIPT >" in names[2]  # (the CSV reader's own quoting aside)
    for data in ("left", "right"):
        assert [r["channel"] for r in spec["datasets"][data]] == names  # back exactly, as data
    for name in names:
        assert all(name not in text for _, text in scripts)  # escaped wherever it is
    assert "<script>alert" not in page and "<img src=x" not in page and "<!--" not in page.replace(
        "<!DOCTYPE", "")


def test_chart_json_cannot_end_its_script_element():
    from sigmatau.report.interactive import chart_html

    spec = {"title": {"text": "</script><!-- \u2028\u2029 & <b>"}}
    html_text = chart_html(spec, 0)
    body = html_text.split('data-target="ichart-0">', 1)[1].rsplit("</script>", 1)[0]  # the JSON in its element
    assert "<" not in body and ">" not in body and "&" not in body and "\u2028" not in body
    assert json.loads(body) == spec


def test_chart_library_cannot_end_its_script_element(monkeypatch):
    import types

    from sigmatau.report import interactive

    interactive._bundle.cache_clear()
    monkeypatch.setitem(sys.modules, "vl_convert",
                        types.SimpleNamespace(javascript_bundle=lambda: "var s = '</SCRIPT><script>x()';"))
    try:
        script = interactive.library_script()
    finally:
        monkeypatch.undo()
        interactive._bundle.cache_clear()
    assert "var s = '<\\/SCRIPT><script>x()';" in script and script.lower().count("</script") == 2
