"""Units of IMU noise parameters: the identities of the reference page, parsing, Kalibr.

Reference: /work/shared/reference/imu-noise-model.md ("Unit identities", the table of
the five terms, "Kalibr / VIO conventions", "Worked reference: ADIS16448") and
/work/shared/reference/dt0064.md ("Parts named": LSM6DSL/LSM6DSM noise densities).
"""

from __future__ import annotations

import math

import pytest

from sigmatau.errors import ParameterError
from sigmatau.units import (
    CUSTOMARY, STANDARD_GRAVITY, TERMS, convert, density_to_discrete, discrete_to_density,
    discrete_to_random_walk, parse_unit, random_walk_to_discrete, sensor_unit, term_unit,
)


@pytest.mark.parametrize("value, src, dst, expected, rel", [
    # "1 °/s/√Hz = 60 °/√h" (exact)
    (1.0, "deg/s/sqrt(Hz)", "deg/sqrt(h)", 60.0, 1e-12),
    # "1 °/√h = 2.909×10⁻⁴ rad/√s" (4 digits printed)
    (1.0, "°/√h", "rad/√s", 2.909e-4, 5e-4),
    # "1 µg/√Hz = 9.80665×10⁻⁶ m/s²/√Hz" (exact with standard gravity)
    (1.0, "µg/√Hz", "m/s^2/sqrt(Hz)", 9.80665e-6, 1e-12),
    # "1 °/h = 4.848×10⁻⁶ rad/s"
    (1.0, "deg/h", "rad/s", 4.848e-6, 5e-4),
    # ADIS16448 gyro: 0.0135 °/s/√Hz = 2.36×10⁻⁴ rad/s/√Hz; accel 0.23 mg/√Hz = 2.26×10⁻³ m/s²/√Hz
    (0.0135, "deg/s/sqrt(Hz)", "rad/s/sqrt(Hz)", 2.36e-4, 2e-3),
    (0.23, "mg/sqrt(Hz)", "m/s^2/sqrt(Hz)", 2.26e-3, 2e-3),
    # velocity random walk: m/s²/√Hz → m/s/√h is ×60, like the gyro identity
    (1.0, "m/s^2/sqrt(Hz)", "m/s/sqrt(h)", 60.0, 1e-12),
    # the design tip: LSM6DSL gyro 4 mdps/√Hz, accel 80 µg/√Hz
    (4.0, "mdps/sqrt(Hz)", "deg/s/sqrt(Hz)", 0.004, 1e-12),
    (80.0, "ug/sqrt(Hz)", "mg/sqrt(Hz)", 0.08, 1e-12),
    # random-walk units: rad/s²/√Hz = rad/s/√s; °/h/√h = (π/180)/3600^1.5 rad/s/√s
    (1.0, "rad/s^2/sqrt(Hz)", "rad/s/sqrt(s)", 1.0, 1e-12),
    (1.0, "deg/h/sqrt(h)", "rad/s^2/sqrt(Hz)", math.pi / 180 / 3600**1.5, 1e-12),
    # rate ramp °/h² and angle units
    (1.0, "deg/h^2", "rad/s^2", math.pi / 180 / 3600**2, 1e-12),
    (1.0, "arcsec", "urad", math.pi / 180 / 3600 * 1e6, 1e-12),
])
def test_reference_identities(value, src, dst, expected, rel):
    assert convert(value, src, dst) == pytest.approx(expected, rel=rel)


def test_spellings_agree():
    f, d = parse_unit("rad/s^2/sqrt(Hz)")
    for spelling in ("rad/s²/√Hz", "rad s^-2 Hz^-0.5", "rad/(s^2*sqrt(Hz))", "rad/s/s/√Hz", "rad/s^(3/2)"):
        g, e = parse_unit(spelling)
        assert g == pytest.approx(f) and e == d, spelling
    assert parse_unit("dps") == parse_unit("deg/s")
    assert parse_unit("dph") == parse_unit("deg/h")
    assert parse_unit("m/s2") == parse_unit("m/s^2")
    assert parse_unit("g")[0] == STANDARD_GRAVITY


def test_dimension_mismatch_and_bad_units_raise():
    with pytest.raises(ParameterError, match="cannot convert"):
        convert(1.0, "rad/s", "m/s^2")
    with pytest.raises(ParameterError, match="cannot convert"):
        convert(1.0, "rad/s/sqrt(Hz)", "rad/s")   # a density is not a discrete σ
    with pytest.raises(ParameterError, match="unknown symbol"):
        parse_unit("furlong/fortnight")
    with pytest.raises(ParameterError):
        parse_unit("")
    with pytest.raises(ParameterError):
        parse_unit("rad/(s")
    with pytest.raises(ParameterError):
        parse_unit(3)  # type: ignore[arg-type]


def test_sensor_units_and_term_units():
    gyro = sensor_unit("deg/s")
    assert gyro.kind == "gyro" and gyro.si == "rad/s"
    assert gyro.to_si == pytest.approx(math.pi / 180)
    accel = sensor_unit("g")
    assert accel.kind == "accel" and accel.term_si("K") == "m/s^3/sqrt(Hz)"
    assert [term_unit("rad/s", t) for t in TERMS] == [
        "rad", "rad/s/sqrt(Hz)", "rad/s", "rad/s^2/sqrt(Hz)", "rad/s^2"]
    assert [term_unit("m/s^2", t) for t in TERMS] == [
        "m/s", "m/s^2/sqrt(Hz)", "m/s^2", "m/s^3/sqrt(Hz)", "m/s^3"]
    # every term unit of every accepted input converts to its SI unit with the input's factor
    for unit in ("rad/s", "deg/s", "deg/h", "mdps", "m/s^2", "g", "mg", "m s^-2"):
        su = sensor_unit(unit)
        for t in TERMS:
            assert su.term_to_si(t) == pytest.approx(su.to_si, rel=1e-12), (unit, t)
    for bad in ("m/s", "rad", "Hz", "deg/s^2"):
        with pytest.raises(ParameterError, match="angular rate"):
            sensor_unit(bad)
    with pytest.raises(ParameterError):
        term_unit("rad/s", "X")


def test_customary_units_have_the_right_dimension():
    for kind, base in (("gyro", "rad/s"), ("accel", "m/s^2")):
        for term, units in CUSTOMARY[kind].items():
            for u in units:
                convert(1.0, u, term_unit(base, term))  # raises on a wrong dimension


def test_kalibr_discrete_equivalents():
    # EuRoC: σ_d = N·√200, σ_bd = K/√200
    assert density_to_discrete(1.6968e-4, rate=200.0) == pytest.approx(1.6968e-4 * math.sqrt(200.0))
    assert random_walk_to_discrete(1.9393e-5, rate=200.0) == pytest.approx(1.9393e-5 / math.sqrt(200.0))
    assert discrete_to_density(density_to_discrete(2e-3, rate=100.0), rate=100.0) == pytest.approx(2e-3)
    assert discrete_to_random_walk(random_walk_to_discrete(3e-3, rate=100.0), rate=100.0) == pytest.approx(3e-3)
    with pytest.raises(ParameterError):
        density_to_discrete(1.0, rate=0.0)
