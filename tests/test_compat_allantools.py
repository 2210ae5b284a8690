"""sigmatau.compat.allantools against allantools itself.

Source of the expected values: the installed allantools package (checked with
2024.6), run in the same test on the same seeded data.
Every function is compared for phase and frequency data, the seven noise types
of tests/_noise.py and several ``taus`` arguments.

Tolerances: τ and ns must be identical (the same integer averaging factors);
devs and errs agree to 1e-10 relative. The two libraries evaluate the same sums
in a different order (sigmatau removes the mean frequency or linear phase trend
first and differences frequency samples directly), so they differ by round-off
only. The data carry a frequency offset 3e-9, 300 times their noise level: the
phase ramp is then up to 1e5 times the phase noise and float64 itself resolves
the noise only to about 1e-11 relative. The largest difference seen here is
2.5e-11 (hdev of white PM phase, where an 80-bit evaluation of the same sum
differs from both libraries by as much); without the offset, random-run FM
phase (dominated by its own quadratic wander) reaches 4e-11 for hdev and mdev,
and everything else stays below 3e-12.

allantools' theo1, mtotdev, ttotdev and htotdev loop in Python over O(N·m)
terms per τ, so they get the shorter records (N ≈ 200).
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from _noise import NOISES

allantools = pytest.importorskip("allantools")

import sigmatau  # noqa: E402
import sigmatau.compat.allantools as compat  # noqa: E402
from sigmatau.errors import DataError, ParameterError  # noqa: E402

FAST = ["adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "totdev", "mtie", "tierms"]
SLOW = ["mtotdev", "ttotdev", "htotdev", "theo1", "pdev"]  # allantools' pdev loops in Python too
RTOL = 1e-10
RATE = 2.0
OFFSET = 3e-9
# Keyword grids, None, and τ in seconds including some that round, repeat,
# are odd for Theo1 or do not fit the record at all.
TAUS = [None, "octave", "decade", "log10", np.array([0.2, 0.5, 1.0, 1.4, 3.0, 3.2, 10.0, 1e9])]


def _data(noise: str, data_type: str, n: int) -> np.ndarray:
    """Seeded series with a realistic scale and a frequency offset."""
    rng = np.random.default_rng(sorted(NOISES).index(noise) * 2 + (data_type == "phase"))
    y = 1e-11 * NOISES[noise](n, rng) + OFFSET
    if data_type == "freq":
        return y
    return np.concatenate(([0.0], np.cumsum(y))) / RATE


def _assert_same(expected, got, where: str) -> None:
    taus_e, devs_e, errs_e, ns_e = expected
    taus_g, devs_g, errs_g, ns_g = got
    np.testing.assert_array_equal(taus_g, taus_e, err_msg=f"taus, {where}")
    np.testing.assert_array_equal(ns_g, ns_e, err_msg=f"ns, {where}")
    np.testing.assert_allclose(devs_g, devs_e, rtol=RTOL, atol=0, err_msg=f"devs, {where}")
    np.testing.assert_allclose(errs_g, errs_e, rtol=RTOL, atol=0, err_msg=f"errs, {where}")
    for arr in got:
        assert arr.dtype == np.float64


def _compare(name: str, data: np.ndarray, **kwargs) -> None:
    expected = getattr(allantools, name)(data, **kwargs)
    got = getattr(compat, name)(data, **kwargs)
    _assert_same(expected, got, f"{name}({kwargs})")


@pytest.mark.parametrize("noise", sorted(NOISES))
@pytest.mark.parametrize("data_type", ["phase", "freq"])
@pytest.mark.parametrize("name", FAST)
def test_fast_statistics_match(name, data_type, noise):
    data = _data(noise, data_type, 500)
    for taus in TAUS + ["all"]:
        _compare(name, data, rate=RATE, data_type=data_type, taus=taus)


@pytest.mark.slow
@pytest.mark.parametrize("noise", ["WPM", "FFM", "RWFM", "RRFM"])
@pytest.mark.parametrize("data_type", ["phase", "freq"])
@pytest.mark.parametrize("name", SLOW)
def test_slow_statistics_match(name, data_type, noise):
    data = _data(noise, data_type, 200)
    for taus in TAUS[1:]:  # None is "octave" (test_defaults_are_phase_data_and_octave)
        _compare(name, data, rate=RATE, data_type=data_type, taus=taus)


@pytest.mark.parametrize("name", FAST + SLOW)
def test_all_grid_on_a_short_record(name):
    # Every factor allantools accepts, up to the estimator's last usable one.
    for data_type in ("phase", "freq"):
        _compare(name, _data("FFM", data_type, 40), rate=RATE, data_type=data_type, taus="all")


@pytest.mark.parametrize("name", FAST + SLOW)
def test_defaults_are_phase_data_and_octave(name):
    x = _data("WFM", "phase", 120)
    _assert_same(getattr(allantools, name)(x), getattr(compat, name)(x), name)
    _assert_same(getattr(allantools, name)(x, taus=[]), getattr(compat, name)(list(x), taus=[]), name)


@pytest.mark.parametrize("name", ["oadev", "mtie", "htotdev", "theo1"])
def test_scalar_and_integer_taus(name):
    x = _data("RWFM", "phase", 150)
    _compare(name, x, rate=1, taus=8)
    _compare(name, x, rate=4.0, taus=[2, 4, 6])


def test_theo1_reports_m_tau0_while_sigmatau_reports_three_quarters():
    x = _data("FFM", "phase", 200)
    taus, devs, _, ns = compat.theo1(x, rate=RATE, taus=[5.0, 10.0, 20.0])
    res = sigmatau.theo1(x, rate=RATE, data_type="phase", m=[10, 20, 40], ci=None)
    np.testing.assert_array_equal(taus, res.m / RATE)
    np.testing.assert_array_equal(0.75 * taus, res.taus)
    np.testing.assert_allclose(devs, res.dev, rtol=1e-14)
    np.testing.assert_array_equal(ns, res.n)


@pytest.mark.parametrize("name", ["adev", "mtie", "htotdev", "tierms"])
def test_frequency_data_lose_nan_at_the_ends(name):
    y = _data("WFM", "freq", 300)
    padded = np.concatenate(([np.nan, np.nan], y, [np.nan]))
    if name != "htotdev":  # allantools' htotdev keeps them (module docstring, item 3)
        _compare(name, padded, rate=RATE, data_type="freq")
    _assert_same(getattr(compat, name)(y, rate=RATE, data_type="freq"),
                 getattr(compat, name)(padded, rate=RATE, data_type="freq"), name)


def test_interior_nan_is_a_data_error():
    y = _data("WFM", "freq", 100)
    y[50] = np.nan
    with pytest.raises(DataError, match="non-finite"):
        compat.oadev(y, data_type="freq")
    with pytest.raises(DataError):
        compat.oadev(np.concatenate(([np.nan], _data("WFM", "phase", 50))))


def test_no_usable_tau_is_a_data_error():
    x = _data("WFM", "phase", 100)
    with pytest.raises(UserWarning):  # allantools prints and raises UserWarning
        allantools.oadev(x, taus=[1000.0])
    with pytest.raises(DataError, match="no averaging time"):
        compat.oadev(x, taus=[1000.0])
    with pytest.raises(DataError, match="no averaging time"):
        compat.mdev(x, taus=np.array([]))
    with pytest.raises(DataError):
        compat.adev([1.0, 2.0])


def test_bad_arguments_are_parameter_errors():
    x = _data("WFM", "phase", 100)
    with pytest.raises(ParameterError, match="data_type"):
        compat.adev(x, data_type="frequency")
    with pytest.raises(ParameterError, match="rate"):
        compat.adev(x, rate=0)
    with pytest.raises(ParameterError, match="taus"):
        compat.adev(x, taus="octaves")
    with pytest.raises(ParameterError, match="taus"):
        compat.adev(x, taus=["octave"])
    with pytest.raises(ValueError):  # both errors are ValueErrors
        compat.adev(x, rate=-1.0)


def test_nothing_printed_and_outputs_are_fresh_arrays(capsys):
    x = _data("WFM", "phase", 100)
    out = compat.adev(x, taus=[1.0, 500.0])
    assert capsys.readouterr().out == ""
    for arr in out:
        arr[...] = 0.0  # writable, owned


def test_same_names_and_signatures_as_allantools():
    import inspect

    for name in compat.__all__:
        theirs = inspect.signature(getattr(allantools, name)).parameters
        ours = inspect.signature(getattr(compat, name)).parameters
        assert list(ours) == list(theirs), name
        assert [p.default for p in ours.values()] == [p.default for p in theirs.values()], name


@pytest.mark.parametrize("data_type", ["phase", "freq"])
def test_gcodev_matches_allantools_unsigned(data_type):
    # three clocks of different noise and level; B is the loudest and enters AB and BC with opposite signs
    clocks = [_data(noise, data_type, 400) * scale for noise, scale in (("WFM", 1), ("WPM", 30), ("FFM", 2))]
    ab, bc = clocks[0] - clocks[1], clocks[1] - clocks[2]
    for taus in TAUS[1:] + ["all"]:
        expected = allantools.gcodev(ab, bc, rate=RATE, data_type=data_type, taus=taus)
        got = compat.gcodev(ab, bc, rate=RATE, data_type=data_type, taus=taus)
        _assert_same(expected, got, f"gcodev({data_type}, {taus})")
    # allantools drops the sign that sigmatau.gcodev keeps
    signed = sigmatau.gcodev(ab, bc, rate=RATE, data_type=data_type, m=[1, 2, 4])
    assert np.all(signed.cov < 0)


def test_module_does_not_need_allantools():
    code = ("import sys, sigmatau.compat.allantools as a; a.oadev([0.0, 1.0, 3.0, 2.0, 5.0]);"
            " assert 'allantools' not in sys.modules, 'allantools was imported'")
    subprocess.run([sys.executable, "-c", code], check=True)
