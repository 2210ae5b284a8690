"""The IMU noise model in the parameter files of the estimators people run.

Each writer takes a :class:`~sigmatau.analysis.LogAnalysis` with gyroscope and
accelerometer models and returns the text of one file, with the values in the
unit and the continuous/discrete convention that estimator's own code uses,
stated in a comment of the file:

========== ======================== ==========================================================
target     file                     convention (checked against the project's code)
========== ======================== ==========================================================
kalibr     ``imu.yaml``             continuous time: N [unit/√Hz], K [unit/s/√Hz]
vins       ``vins_imu.yaml``        VINS-Mono/VINS-Fusion: standard deviations per sample,
                                    ``acc_n = N·√f``, ``acc_w = K·√f`` (see :func:`vins_yaml`)
openvins   ``kalibr_imu_chain.yaml`` OpenVINS: continuous time, Kalibr's keys under ``imu0``
matlab     ``imu_params.m``         MATLAB ``gyroparams``/``accelparams``: NoiseDensity N,
                                    RandomWalk K, BiasInstability B, one value per axis
gtsam      ``gtsam_imu_params.py``  GTSAM ``PreintegrationCombinedParams``: continuous-time
                                    covariances N²·I, K²·I (per-axis diagonal)
========== ======================== ==========================================================

Formats that take one value for all three axes (Kalibr, VINS, OpenVINS) get the
analysis's Kalibr entry — the axes combined by its stated rule (largest by
default), inflation applied, an unresolved random walk entered as its upper
bound; formats that take one value per axis (MATLAB, GTSAM) get each axis's own
value, with the inflation. Every name that comes from the user's files (path,
topic, channel names) appears only in comments, with its control characters
escaped, or, for the ROS topic of the YAML files, as a double-quoted escaped
string; every number is written from a float, so no file can be made to hold
anything but its keys.
"""

from __future__ import annotations

import json
import math
from typing import Any, Callable, Optional, Sequence

from ..errors import ParameterError
from .formats import KALIBR_KEYS, kalibr_yaml, printable

__all__ = ["EXPORTS", "EXPORT_FILES", "export_text", "vins_yaml", "openvins_yaml", "matlab_script", "gtsam_script",
           "parse_exports"]

#: File written for each export target.
EXPORT_FILES = {"kalibr": "imu.yaml", "vins": "vins_imu.yaml", "openvins": "kalibr_imu_chain.yaml",
                "matlab": "imu_params.m", "gtsam": "gtsam_imu_params.py"}
#: The export targets, in the order of :data:`EXPORT_FILES`.
EXPORTS = tuple(EXPORT_FILES)


def parse_exports(value: object) -> tuple[str, ...]:
    """The export targets of a comma-separated list (or a sequence), checked, in the given order.

    ``"none"`` or an empty list gives none.

    Examples
    --------
    >>> parse_exports("kalibr,vins")
    ('kalibr', 'vins')
    >>> parse_exports("none")
    ()
    """
    items = value.split(",") if isinstance(value, str) else list(value)  # type: ignore[call-overload]
    out: list[str] = []
    for item in items:
        name = str(item).strip().lower()
        if name in ("", "none"):
            continue
        if name not in EXPORT_FILES:
            raise ParameterError(f"export {printable(item)!r} must be one of {', '.join(EXPORTS)} (or none)")
        if name not in out:
            out.append(name)
    return tuple(out)


def _entry(analysis: Any) -> dict[str, Any]:
    """The analysis's Kalibr entry, or a ParameterError saying why there is none."""
    k = analysis.kalibr
    if k is None:
        raise ParameterError(f"no IMU noise model for an estimator file: {analysis.kalibr_note or 'no IMU model'}")
    return k


def _ascii(text: str) -> str:
    """``text`` with control characters escaped and everything outside ASCII as ``\\uXXXX``
    (MATLAB reads scripts in the platform's encoding before R2020a)."""
    return printable(text).encode("ascii", "backslashreplace").decode("ascii")


def _header(analysis: Any, what: str) -> list[str]:
    """Comment lines common to every file: who wrote it, from which input, how axes were combined."""
    k = _entry(analysis)
    src = analysis.log.source
    topic = f", topic {src.topic}" if src.topic else ""
    lines = [f"{what}, written by sigmatau {analysis.version}",
             f"input: {src.path} ({src.format}{topic}), sha256 {src.sha256}",
             f"IMU rate {float(k['update_rate']):g} Hz; inflation factor {k['inflation']:g}"]
    if k.get("axes_note"):
        lines.append(f"fewer than three axes: {k['axes_note']}")
    if k["bounds_used"]:
        lines.append("upper bounds of unresolved terms used for: " + ", ".join(k["bounds_used"]))
    return lines


def _comments(lines: Sequence[str], mark: str = "#", ascii_only: bool = False) -> str:
    """Each line as one comment line, escaped so that no name can end the comment."""
    esc = _ascii if ascii_only else printable
    return "".join(f"{mark} {esc(line)}\n" if line else f"{mark}\n" for line in lines)


def _float(v: float) -> str:
    """A float literal that YAML (1.1 and OpenCV's), MATLAB and Python all read back exactly."""
    if not math.isfinite(v):
        raise ParameterError(f"a value to export is not finite ({v!r})")
    text = repr(float(v))
    mantissa, e, exponent = text.partition("e")
    # PyYAML (YAML 1.1) reads "1e-05" as a string: its floats need a point in the mantissa
    return (mantissa if "." in mantissa else mantissa + ".0") + (e + exponent if e else "")


def _quoted(text: str, what: str) -> str:
    """A double-quoted YAML string that OpenCV's reader gives back unchanged.

    JSON's escapes of ``"``, ``\\``, tab, CR and LF are YAML's and OpenCV's; OpenCV
    has no ``\\uXXXX`` escape, so other characters are written as they are (UTF-8)
    and a control character, which ROS names never hold, is refused.
    """
    text = str(text)
    if printable(text) != text:
        raise ParameterError(f"{what} '{printable(text)}' contains a control character; OpenCV's YAML reader"
                             " (OpenVINS, VINS) cannot hold it: give the name alone")
    return json.dumps(text, ensure_ascii=False)


# ---------------------------------------------------------------------------- VINS


def vins_yaml(analysis: Any) -> str:
    r"""The IMU block of a VINS-Mono / VINS-Fusion configuration file (OpenCV ``%YAML:1.0``).

    VINS reads ``acc_n``, ``gyr_n``, ``acc_w`` and ``gyr_w`` with OpenCV's
    FileStorage (``parameters.cpp``) and propagates its pre-integration
    covariance as ``P ← F·P·Fᵀ + V·Q·Vᵀ`` with ``Q = diag(acc_n², gyr_n², acc_n²,
    gyr_n², acc_w², gyr_w²)`` and a noise Jacobian ``V`` proportional to the
    sample interval δt (``integration_base.h``, ``midPointIntegration``): each
    IMU sample adds ``acc_n²·δt²`` to the velocity and ``acc_w²·δt²`` to the bias.
    A white noise of density N gives ``N²·δt`` per sample and a bias random walk
    K gives ``K²·δt``, so the values VINS's equations expect are the per-sample
    standard deviations

    .. math:: n = N\sqrt{f}, \qquad w = K\sqrt{f} \qquad (f = 1/δt\text{, the IMU rate}).

    The Kalibr (continuous-time) values are given in comments beside them, since
    many published VINS configurations use those directly, inflated by hand.

    Returns
    -------
    str
        ``%YAML:1.0`` then the four keys, to paste into the VINS configuration.
    """
    k = _entry(analysis)
    sq = math.sqrt(float(k["update_rate"]))
    head = _header(analysis, "IMU noise for VINS-Mono / VINS-Fusion (paste into the config file)")
    head += [
        "VINS propagates P <- F P F^T + V Q V^T with V proportional to dt (integration_base.h):",
        "acc_n, gyr_n, acc_w, gyr_w are standard deviations per IMU sample, n = N*sqrt(f), w = K*sqrt(f)",
        f"at f = {float(k['update_rate']):g} Hz, from the continuous-time (Kalibr) values N and K below",
    ]
    rows = []
    for key, sensor, unit, kind in (("acc_n", "accelerometer", "m/s^2", "noise_density"),
                                    ("gyr_n", "gyroscope", "rad/s", "noise_density"),
                                    ("acc_w", "accelerometer", "m/s^3", "random_walk"),
                                    ("gyr_w", "gyroscope", "rad/s^2", "random_walk")):
        cont = float(k[f"{sensor}_{kind}"])
        what = "measurement noise" if kind == "noise_density" else "bias random walk"
        rows.append(f"{key}: {_float(cont * sq)}  # [{unit}] {sensor} {what} per sample;"
                    f" continuous {cont:.6e} [{unit}/sqrt(Hz)]\n")
    return "%YAML:1.0\n" + _comments(head) + "".join(rows)


# ---------------------------------------------------------------------------- OpenVINS


def _matrix(name: str, rows: Sequence[Sequence[float]]) -> str:
    """A YAML block sequence of rows, as OpenVINS's own files write matrices."""
    return f"  {name}:\n" + "".join("    - [" + ", ".join(_float(v) for v in row) + "]\n" for row in rows)


def openvins_yaml(analysis: Any) -> str:
    """OpenVINS's ``kalibr_imu_chain.yaml`` (OpenCV ``%YAML:1.0``, the keys under ``imu0``).

    OpenVINS reads Kalibr's four keys as continuous-time densities and
    discretises them itself (``Propagator.cpp``: ``σ_w²/δt`` for the white noise,
    ``σ_wb²·δt`` for the bias random walk), so the values are Kalibr's, in SI.
    The intrinsics OpenVINS also reads from this file (``Tw``, ``R_IMUtoGYRO``,
    ``Ta``, ``R_IMUtoACC``, ``Tg``) and ``T_i_b`` are written as identities
    (``Tg`` zero, ``model: "kalibr"``): sigmatau does not estimate scale factors,
    misalignments or g-sensitivity, and a comment says so.
    """
    k = _entry(analysis)
    head = _header(analysis, "OpenVINS IMU file (kalibr_imu_chain.yaml)")
    head += ["noise values: continuous time (densities), SI; OpenVINS discretises them (Propagator.cpp)",
             "intrinsics below are identities: sigmatau does not estimate scale, misalignment or g-sensitivity"]
    eye3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    eye4 = [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]
    body = ["imu0:\n", _matrix("T_i_b", eye4)]
    body += [f"  {key}: {_float(float(k[key]))}  # [{k['units'][key]}]\n" for key in KALIBR_KEYS]
    body += [f"  rostopic: {_quoted(k['rostopic'], 'rostopic')}\n", "  time_offset: 0.0\n",
             f"  update_rate: {_float(float(k['update_rate']))}\n", '  model: "kalibr"\n']
    body += [_matrix(name, eye3) for name in ("Tw", "R_IMUtoGYRO", "Ta", "R_IMUtoACC")]
    body.append(_matrix("Tg", [[0.0] * 3] * 3))
    return "%YAML:1.0\n" + _comments(head) + "".join(body)


# ---------------------------------------------------------------------------- per axis


def _axis_values(analysis: Any, group: str, term: str) -> tuple[list[float], list[str], list[str]]:
    """Each axis's value of ``term`` in SI (its upper bound when unresolved), times the inflation;
    the axes' names; the axes given as bounds (``"name (no bound: 0)"`` when the record gives not
    even a bound, which the files' comments then say)."""
    k = _entry(analysis)
    chans = [c for c in analysis.channels if c.group == group and c.model is not None]
    vals, names, bounds = [], [], []
    for c in chans:
        p = getattr(c.model, term).si()
        v = p.value if p.resolved else p.high
        names.append(c.name)
        if v is None or not math.isfinite(v):
            v = 0.0
            bounds.append(f"{c.name} (no bound: 0)")
        elif not p.resolved:
            bounds.append(c.name)
        vals.append(float(v) * float(k["inflation"]))
    return vals, names, bounds


def _three(vals: list[float]) -> list[float]:
    """Three per-axis values: the axes' own when there are three, else the largest on every axis."""
    if len(vals) == 3:
        return vals
    return [max(vals)] * 3 if vals else [0.0] * 3


# ---------------------------------------------------------------------------- MATLAB


def _matlab_vector(vals: Sequence[float]) -> str:
    return "[" + " ".join(_float(v) for v in vals) + "]"


def matlab_script(analysis: Any) -> str:
    """A MATLAB script making ``gyroparams`` and ``accelparams`` objects (Sensor Fusion / Navigation Toolbox).

    The properties and their units are MATLAB's (``gyroparams`` reference page):
    ``NoiseDensity`` N in (rad/s)/√Hz, ``RandomWalk`` K in (rad/s)·√Hz (the rate
    random walk; the same unit as rad/s²/√Hz) and ``BiasInstability`` B in rad/s
    — the coefficient, σ_min/0.664, as MathWorks' "Inertial Sensor Noise Analysis
    Using Allan Variance" example defines it; ``accelparams`` the same in m/s².
    Each is a 1×3 row vector of the x, y, z axes' own values (the largest on
    every axis when the log has fewer than three); unresolved terms enter as
    their upper bounds and a comment names them. Run it, then pass ``gyro`` and
    ``accel`` to ``imuSensor``.
    """
    head = _header(analysis, "MATLAB IMU noise parameters (gyroparams / accelparams)")
    head += ["units as MATLAB's: NoiseDensity (unit)/sqrt(Hz), RandomWalk (unit)*sqrt(Hz),"
             " BiasInstability (unit) = sigma_min/0.664",
             "each property is [x y z], one value per axis"]
    lines = []
    for group, func, unit in (("gyro", "gyroparams", "rad/s"), ("accel", "accelparams", "m/s^2")):
        args = []
        for term, prop in (("N", "NoiseDensity"), ("K", "RandomWalk"), ("B", "BiasInstability")):
            vals, names, bounds = _axis_values(analysis, group, term)
            head.append(f"{func}.{prop} from {', '.join(names) or 'no axis'}"
                        + (f"; upper bound on {', '.join(bounds)}" if bounds else ""))
            args.append(f"'{prop}', {_matlab_vector(_three(vals))}")
        lines.append(f"{group} = {func}( ...\n    " + ", ...\n    ".join(args) + f");  % {unit}\n")
    k = _entry(analysis)
    lines.append(f"sampleRate = {_float(float(k['update_rate']))};  % Hz, for imuSensor('SampleRate', sampleRate)\n")
    return _comments(head, "%", ascii_only=True) + "".join(lines)


# ---------------------------------------------------------------------------- GTSAM


def gtsam_script(analysis: Any) -> str:
    """A Python module building GTSAM's ``PreintegrationCombinedParams`` from the model.

    GTSAM's covariances are continuous-time (``PreintegrationParams.h``: "Continuous-time
    'Covariance' of accelerometer"; ``CombinedImuFactor.cpp`` divides the measurement
    covariances by δt and multiplies the bias ones by δt), so the file sets
    ``accelerometerCovariance = diag(N_a²)`` [(m/s²)²/Hz], ``gyroscopeCovariance =
    diag(N_g²)`` [(rad/s)²/Hz], ``biasAccCovariance = diag(K_a²)`` [(m/s³)²/Hz] and
    ``biasOmegaCovariance = diag(K_g²)`` [(rad/s²)²/Hz], one diagonal entry per
    axis. ``integrationCovariance`` is not a sensor property: it is set to
    ``(1e-7)²·I``, the value of GTSAM's own Python examples, and a comment says
    so; gravity is an argument (9.81 m/s² by default, GTSAM's ``MakeSharedU``).
    ``make_params()`` needs ``gtsam`` and ``numpy``; importing the module does not.
    """
    head = _header(analysis, "GTSAM IMU preintegration parameters (CombinedImuFactor)")
    head += ["covariances are continuous time (GTSAM divides measurement covariances by dt and multiplies",
             "bias covariances by dt, CombinedImuFactor.cpp): diag(N^2) and diag(K^2), one entry per axis x, y, z"]
    consts = []
    for group, prefix, unit_n, unit_k in (("accel", "ACCEL", "m/s^2/sqrt(Hz)", "m/s^3/sqrt(Hz)"),
                                          ("gyro", "GYRO", "rad/s/sqrt(Hz)", "rad/s^2/sqrt(Hz)")):
        for term, name, unit in (("N", "NOISE_DENSITY", unit_n), ("K", "RANDOM_WALK", unit_k)):
            vals, names, bounds = _axis_values(analysis, group, term)
            head.append(f"{prefix}_{name} from {', '.join(names) or 'no axis'}"
                        + (f"; upper bound on {', '.join(bounds)}" if bounds else ""))
            consts.append(f"{prefix}_{name} = ({', '.join(_float(v) for v in _three(vals))})  # [{unit}] x, y, z\n")
    k = _entry(analysis)
    consts.append(f"RATE_HZ = {_float(float(k['update_rate']))}  # the IMU rate the model was measured at\n")
    consts.append("# Not a sensor property: the integration uncertainty of GTSAM's own Python examples.\n"
                  "INTEGRATION_SIGMA = 1e-07\n")
    body = (
        "\n\ndef make_params(gravity=9.81):\n"
        '    """gtsam.PreintegrationCombinedParams with these noise values (navigation frame Z up)."""\n'
        "    import gtsam\n"
        "    import numpy as np\n\n"
        "    params = gtsam.PreintegrationCombinedParams.MakeSharedU(gravity)\n"
        "    params.setAccelerometerCovariance(np.diag(np.square(ACCEL_NOISE_DENSITY)))\n"
        "    params.setGyroscopeCovariance(np.diag(np.square(GYRO_NOISE_DENSITY)))\n"
        "    params.setBiasAccCovariance(np.diag(np.square(ACCEL_RANDOM_WALK)))\n"
        "    params.setBiasOmegaCovariance(np.diag(np.square(GYRO_RANDOM_WALK)))\n"
        "    params.setIntegrationCovariance(INTEGRATION_SIGMA ** 2 * np.eye(3))\n"
        "    return params\n"
    )
    return _comments(head) + "\n" + "".join(consts) + body


#: The text writer of each target.
_WRITERS: dict[str, Callable[[Any], str]] = {"kalibr": kalibr_yaml, "vins": vins_yaml, "openvins": openvins_yaml,
                                             "matlab": matlab_script, "gtsam": gtsam_script}


def export_text(analysis: Any, target: str) -> str:
    """The text of the ``target`` file (one of :data:`EXPORTS`) for an analysis with gyro and accel models.

    Raises
    ------
    ParameterError
        An unknown target, or an analysis without both gyroscope and accelerometer models.
    MissingDependencyError
        ``kalibr`` without PyYAML (extra ``yaml``).
    """
    writer: Optional[Callable[[Any], str]] = _WRITERS.get(target)
    if writer is None:
        raise ParameterError(f"export {printable(target)!r} must be one of {', '.join(EXPORTS)}")
    return writer(analysis)
