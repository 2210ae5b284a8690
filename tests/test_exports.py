"""The estimators' parameter files, each read back the way its consumer reads it.

- VINS-Mono/VINS-Fusion and OpenVINS read their YAML with OpenCV's FileStorage
  (``parameters.cpp``; OpenVINS's ``YamlParser``): read here with ``cv2.FileStorage``;
- GTSAM's parameters are built by running the written module with the real ``gtsam``
  package and reading the covariances back from the ``PreintegrationCombinedParams``;
- MATLAB is not available here: the script is checked by a strict reader of the three
  statements it may hold (every other line a ``%`` comment) and for ASCII-only text;
- Kalibr's ``imu.yaml`` keeps its own tests (``test_output_safety.py``).

Expected values come from the channels' noise models and the conventions of each
project's code (cited in ``sigmatau.report.estimators``), never from the files.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import math
import re

import numpy as np
import pytest
from helpers import cli_error_line, run_cli, simulated_imu_log

HOSTILE = [
    "/imu: 0", "/it's \"quoted\"", '!!python/object/apply:os.system ["touch PWNED"]', "/ジャイロ/ü", "# not a comment",
    "&a *a", "- item", "{update_rate: 3}", "---", "%YAML 1.1", "back\\slash", "'; system('touch PWNED'); '",
    "\"\"\"; import os; os.system('touch PWNED') #",
]
CONTROL = ["/imu0\nupdate_rate: 1.0", "/tab\there", "/esc\x1b[2J", "/cr\rx", "/ls\u2028x", "/bidi\u202eevil"]


@pytest.fixture(scope="module")
def analysis():
    """A 6-axis simulated log (2 min at 50 Hz, seed 11) analysed with OADEV only."""
    from sigmatau.analysis import analyze_log

    log = simulated_imu_log()
    return analyze_log(log, statistics="oadev", workers=1, inflate=1.5)


def _renamed(analysis, name: str, rostopic: str = "/imu0"):
    """The same analysis with ``name`` as its file name and bag topic."""
    src = dataclasses.replace(analysis.log.source, path=name, topic=name)
    return dataclasses.replace(analysis, log=dataclasses.replace(analysis.log, source=src),
                               kalibr={**analysis.kalibr, "rostopic": rostopic})


def _axis(analysis, group: str, term: str) -> list[float]:
    """Each axis's SI value of ``term`` (its bound when unresolved) times the inflation, x, y, z."""
    out = []
    for c in analysis.channels:
        if c.group == group:
            p = getattr(c.model, term).si()
            out.append((p.value if p.resolved else p.high) * analysis.kalibr["inflation"])
    return out


def _largest(analysis, group: str, term: str) -> float:
    return max(_axis(analysis, group, term))  # the default axis rule: the largest


def _opencv(text: str, tmp_path):
    cv2 = pytest.importorskip("cv2")
    path = tmp_path / "f.yaml"
    path.write_text(text, encoding="utf-8")
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    assert fs.isOpened()
    return fs


# ----------------------------------------------------------------------------------- VINS


def test_vins_values_are_per_sample_standard_deviations(analysis, tmp_path):
    from sigmatau.outputs import export_text

    fs = _opencv(export_text(analysis, "vins"), tmp_path)
    sq = math.sqrt(50.0)
    expected = {"acc_n": _largest(analysis, "accel", "N") * sq, "gyr_n": _largest(analysis, "gyro", "N") * sq,
                "acc_w": _largest(analysis, "accel", "K") * sq, "gyr_w": _largest(analysis, "gyro", "K") * sq}
    for key, value in expected.items():
        assert fs.getNode(key).real() == pytest.approx(value, rel=1e-14), key
    assert analysis.kalibr["inflation"] == 1.5 and expected["gyr_n"] > 0


@pytest.mark.slow
def test_vins_matches_a_simulated_per_sample_noise():
    """VINS's acc_n is the standard deviation of each sample: a white noise of that σ per sample
    at f Hz has the density N = σ/√f that sigmatau measures, and the file gives σ back."""
    from sigmatau.analysis import analyze_log, log_from_arrays
    from sigmatau.outputs import export_text

    rng = np.random.default_rng(5)
    rate, sigma = 200.0, {"gyro": 0.003, "accel": 0.02}
    chans = {f"{g}_{a}": rng.normal(0.0, sigma[g], 200_000) for g in ("gyro", "accel") for a in "xyz"}
    units = {k: "rad/s" if k.startswith("gyro") else "m/s^2" for k in chans}
    analysis = analyze_log(log_from_arrays(chans, rate=rate, units=units, name="white"), statistics="oadev",
                           workers=1)
    text = export_text(analysis, "vins")
    values = dict(re.findall(r"^(\w+): ([0-9.e+-]+)", text, re.M))
    # one axis's N from 2e5 samples is good to about 0.5 %; the largest of three sits a little above
    assert float(values["gyr_n"]) == pytest.approx(sigma["gyro"], rel=0.02)
    assert float(values["acc_n"]) == pytest.approx(sigma["accel"], rel=0.02)


# ----------------------------------------------------------------------------------- OpenVINS


def test_openvins_file_as_openvins_reads_it(analysis, tmp_path):
    from sigmatau.outputs import export_text

    fs = _opencv(export_text(analysis, "openvins"), tmp_path)
    imu = fs.getNode("imu0")
    for key, (group, term) in {"accelerometer_noise_density": ("accel", "N"),
                               "accelerometer_random_walk": ("accel", "K"),
                               "gyroscope_noise_density": ("gyro", "N"),
                               "gyroscope_random_walk": ("gyro", "K")}.items():
        assert imu.getNode(key).real() == pytest.approx(_largest(analysis, group, term), rel=1e-14), key
    assert imu.getNode("update_rate").real() == 50.0
    assert imu.getNode("rostopic").string() == "/imu0"
    assert imu.getNode("model").string() == "kalibr"
    assert imu.getNode("time_offset").real() == 0.0

    def matrix(name):
        node = imu.getNode(name)
        return np.array([[node.at(i).at(j).real() for j in range(node.at(i).size())] for i in range(node.size())])

    for name in ("Tw", "R_IMUtoGYRO", "Ta", "R_IMUtoACC"):
        np.testing.assert_array_equal(matrix(name), np.eye(3))
    np.testing.assert_array_equal(matrix("Tg"), np.zeros((3, 3)))
    np.testing.assert_array_equal(matrix("T_i_b"), np.eye(4))


@pytest.mark.parametrize("name", HOSTILE)
def test_openvins_and_vins_hold_hostile_names(analysis, name, tmp_path, monkeypatch):
    """A hostile file name stays in the comments and a hostile (printable) topic round-trips."""
    from sigmatau.outputs import export_text

    monkeypatch.chdir(tmp_path)
    hostile = _renamed(analysis, name, rostopic=name)
    fs = _opencv(export_text(hostile, "openvins"), tmp_path)
    assert fs.getNode("imu0").getNode("rostopic").string() == name
    assert fs.getNode("imu0").getNode("update_rate").real() == 50.0
    text = export_text(hostile, "vins")
    fs = _opencv(text, tmp_path)
    assert fs.getNode("gyr_n").real() == pytest.approx(_largest(analysis, "gyro", "N") * math.sqrt(50.0), rel=1e-14)
    body = [line for line in text.splitlines()[1:] if not line.startswith("#")]
    assert [line.split(":")[0] for line in body] == ["acc_n", "gyr_n", "acc_w", "gyr_w"]


@pytest.mark.parametrize("name", CONTROL)
def test_control_characters_stay_in_escaped_comments_or_are_refused(analysis, name, tmp_path):
    from sigmatau import ParameterError
    from sigmatau.outputs import export_text

    with pytest.raises(ParameterError, match="control character"):  # a topic OpenCV cannot hold
        export_text(_renamed(analysis, "x", rostopic=name), "openvins")
    for target in ("vins", "openvins", "matlab", "gtsam"):  # a file name: escaped in its comment
        text = export_text(_renamed(analysis, name), target)
        for line in text.splitlines():
            assert "\x1b" not in line and "\r" not in line and "\u2028" not in line and "\u202e" not in line


# ----------------------------------------------------------------------------------- GTSAM


def _load_module(path):
    spec = importlib.util.spec_from_file_location(f"gtsam_params_{abs(hash(str(path)))}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("name", ["sim", *HOSTILE])
def test_gtsam_module_builds_gtsams_params(analysis, name, tmp_path, monkeypatch):
    gtsam = pytest.importorskip("gtsam")
    from sigmatau.outputs import export_text

    monkeypatch.chdir(tmp_path)  # where an executed "touch PWNED" would leave its file
    path = tmp_path / "gtsam_imu_params.py"
    path.write_text(export_text(_renamed(analysis, name), "gtsam"), encoding="utf-8")
    module = _load_module(path)
    params = module.make_params()
    assert isinstance(params, gtsam.PreintegrationCombinedParams)
    for getter, group, term in (("getAccelerometerCovariance", "accel", "N"),
                                ("getGyroscopeCovariance", "gyro", "N"),
                                ("getBiasAccCovariance", "accel", "K"),
                                ("getBiasOmegaCovariance", "gyro", "K")):
        np.testing.assert_allclose(getattr(params, getter)(), np.diag(np.square(_axis(analysis, group, term))),
                                   rtol=1e-14, atol=0, err_msg=getter)
    np.testing.assert_allclose(params.getIntegrationCovariance(), 1e-14 * np.eye(3), rtol=1e-14)
    assert params.n_gravity[2] == pytest.approx(-9.81)
    assert not (tmp_path / "PWNED").exists()


# ----------------------------------------------------------------------------------- MATLAB

_STATEMENT = re.compile(r"(\w+) = (gyroparams|accelparams)\( \.\.\.\n((?:    '\w+', \[[^\]]*\](?:, \.\.\.)?\n?)+)\);"
                        r"  % [\w/^]+\n")


def _matlab(text: str) -> dict:
    """The objects a MATLAB run of the script makes: {var: (class, {property: [x, y, z]})}, strictly."""
    assert text.isascii()
    rest = "".join(line + "\n" for line in text.splitlines() if not line.startswith("%"))
    out = {}
    for var, cls, args in _STATEMENT.findall(rest):
        props = dict(re.findall(r"'(\w+)', \[([^\]]*)\]", args))
        out[var] = (cls, {k: [float(v) for v in vals.split()] for k, vals in props.items()})
    rate = re.search(r"^sampleRate = ([0-9.e+-]+);  % Hz[^\n]*$", rest, re.M)
    leftover = _STATEMENT.sub("", rest).replace(rate.group(0), "").strip()
    assert leftover == "", leftover  # nothing but the three statements
    return out, float(rate.group(1))


@pytest.mark.parametrize("name", ["sim", *HOSTILE, *CONTROL])
def test_matlab_script(analysis, name):
    from sigmatau.outputs import export_text

    objects, rate = _matlab(export_text(_renamed(analysis, name), "matlab"))
    assert rate == 50.0
    assert set(objects) == {"gyro", "accel"}
    for var, cls, group in (("gyro", "gyroparams", "gyro"), ("accel", "accelparams", "accel")):
        assert objects[var][0] == cls
        props = objects[var][1]
        assert set(props) == {"NoiseDensity", "RandomWalk", "BiasInstability"}
        for prop, term in (("NoiseDensity", "N"), ("RandomWalk", "K"), ("BiasInstability", "B")):
            np.testing.assert_allclose(props[prop], _axis(analysis, group, term), rtol=1e-15, err_msg=prop)


# ----------------------------------------------------------------------------------- errors and CLI


def test_unknown_target_and_no_model(analysis):
    from sigmatau import ParameterError
    from sigmatau.outputs import export_text, parse_exports

    with pytest.raises(ParameterError, match="must be one of kalibr, vins, openvins, matlab, gtsam"):
        parse_exports("kalibr,ros")
    with pytest.raises(ParameterError, match="must be one of"):
        export_text(analysis, "ros")
    assert parse_exports(["VINS", " gtsam", "vins"]) == ("vins", "gtsam")
    bare = dataclasses.replace(analysis, kalibr=None, kalibr_note="Kalibr needs both sensors; no gyroscope model")
    with pytest.raises(ParameterError, match="no gyroscope model"):
        export_text(bare, "gtsam")


@pytest.mark.slow
def test_cli_writes_the_files_asked_for(tmp_path, capsys):
    code, _, err = run_cli(["simulate", tmp_path / "imu.csv", "--preset", "lsm6dsl", "--duration", "120"], capsys)
    assert code == 0, err
    out = tmp_path / "o"
    code, stdout, err = run_cli(["analyze", tmp_path / "imu.csv", "--out", out, "--no-figures", "--stat", "oadev",
                                 "--export", "vins,gtsam,matlab,openvins", "--quiet"], capsys)
    assert code == 0, err
    names = {p.name for p in out.iterdir()}
    assert {"vins_imu.yaml", "gtsam_imu_params.py", "imu_params.m", "kalibr_imu_chain.yaml"} <= names
    assert "imu.yaml" not in names
    code, _, err = run_cli(["analyze", tmp_path / "imu.csv", "--out", tmp_path / "n", "--no-figures", "--stat",
                            "oadev", "--export", "none", "--quiet"], capsys)
    assert code == 0, err
    assert not {"imu.yaml", "vins_imu.yaml"} & {p.name for p in (tmp_path / "n").iterdir()}


def test_cli_refuses_an_unknown_target_before_reading(tmp_path, capsys):
    code, _, err = run_cli(["analyze", tmp_path / "missing.csv", "--out", tmp_path / "o", "--export", "kalibr,ros"],
                           capsys)
    assert code == 2
    assert "--export" in cli_error_line(err) and "ros" in err
    assert not (tmp_path / "o").exists()


def test_a_term_without_even_a_bound_is_zero_and_said(analysis):
    from sigmatau.outputs import export_text

    ch = analysis.channels[0]
    unknown = dataclasses.replace(ch.model.B, value=float("nan"), high=float("inf"), resolved=False)
    channels = (dataclasses.replace(ch, model=dataclasses.replace(ch.model, B=unknown)), *analysis.channels[1:])
    text = export_text(dataclasses.replace(analysis, channels=channels), "matlab")
    objects, _ = _matlab(text)
    assert objects["gyro"][1]["BiasInstability"][0] == 0.0
    assert f"upper bound on {ch.name} (no bound: 0)" in text
