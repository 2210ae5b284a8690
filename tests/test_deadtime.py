"""Barnes' bias functions and the dead-time correction (sigmatau.spectral.deadtime).

Expected values come from
* B1 per noise type, Howe et al., PTTI 2000, Table 3;
* the closed forms of NIST SP 1065 §5.15 / Barnes, NBS TN 375 (1969):
  B1(N, μ) = N(1 − N^μ)/(2(N − 1)(1 − 2^μ)) and its μ = 0 limit N ln N/(2(N − 1) ln 2);
* the identities B1(2, μ) = 1, B2(1, μ) = 1, B3(2, M, 1, μ) = B3(2, 1, r, μ) = 1, B2 = 1 for white
  FM and B2 = (3r − 1)/2 for random-walk FM;
* a plain oracle written here: the exact variance of gate averages of discrete processes from
  their covariance matrices (white FM, random-walk FM, white PM), with no structure function.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sigmatau.errors import DataError, ParameterError
from sigmatau.spectral import b1, b2, b3, deadtime_correction, mu_from_alpha

MUS = [-2.0, -1.5, -1.0, -0.5, 0.0, 0.5, 1.0, 1.5, 1.9]


def _b1_closed(n: int, mu: float) -> float:
    if mu == 0.0:
        return n * math.log(n) / (2.0 * (n - 1) * math.log(2.0))
    return n * (1.0 - n**mu) / (2.0 * (n - 1) * (1.0 - 2.0**mu))


@pytest.mark.parametrize("mu", MUS)
def test_b1_identities_and_closed_form(mu):
    assert b1(2, mu) == 1.0
    for n in (3, 4, 8, 32, 100):
        assert b1(n, mu) == pytest.approx(_b1_closed(n, mu), rel=1e-10)


def test_b1_per_noise_type():
    # B1 per noise type as tabulated by Howe, Beard, Greenhall, Vernotte, Riley (PTTI 2000,
    # Table 3): μ = 1: N/2; μ = 0: N ln N/(2(N−1) ln 2); μ = −1: 1; μ = −2: (N²−1)/(1.5N(N−1)).
    for n in (3, 4, 10, 128):
        assert b1(n, 1.0) == pytest.approx(n / 2.0, rel=1e-12)
        assert b1(n, 0.0) == pytest.approx(n * math.log(n) / (2.0 * (n - 1) * math.log(2.0)), rel=1e-12)
        assert b1(n, -1.0) == pytest.approx(1.0, rel=1e-12)
        assert b1(n, -2.0) == pytest.approx((n * n - 1.0) / (1.5 * n * (n - 1.0)), rel=1e-12)


def test_b1_white_pm_and_fm_oracles():
    # White PM (x iid, σ_x = 1): E[N-sample] = (2N − 2/N)/(N − 1), Allan = 3 → B1 = 2(N + 1)/(3N).
    # White FM: the N-sample variance is the Allan variance, B1 = 1.
    for n in (3, 5, 16):
        assert b1(n, -2.0) == pytest.approx(2.0 * (n + 1) / (3.0 * n), rel=1e-12)
        assert b1(n, -1.0) == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize("mu", MUS)
def test_b2_b3_identities(mu):
    assert b2(1.0, mu) == 1.0
    assert b3(2, 1, 3.0, mu) == 1.0
    assert b3(2, 8, 1.0, mu) == 1.0


@pytest.mark.parametrize("r", [1.25, 2.0, 5.0, 10.0])
def test_b2_published_cases(r):
    assert b2(r, -1.0) == pytest.approx(1.0, rel=1e-12)               # white FM
    assert b2(r, 1.0) == pytest.approx((3.0 * r - 1.0) / 2.0, rel=1e-12)  # random-walk FM
    assert b2(r, -2.0) == pytest.approx(2.0 / 3.0, rel=1e-12)          # white PM, r > 1


@pytest.mark.parametrize("mu", [-1.5, -0.5, 0.0, 0.5, 1.5])
@pytest.mark.parametrize("r", [1.5, 3.0])
def test_b2_closed_form(mu, r):
    p = mu + 2.0
    if mu == 0.0:
        g = lambda s: s * s * math.log(s)  # noqa: E731
        want = (g(r + 1) + g(r - 1) - 2 * g(r)) / (4 * math.log(2))
    else:
        want = (2 + 2 * r**p - (r + 1) ** p - (r - 1) ** p) / (4 - 2**p)
    assert b2(r, mu) == pytest.approx(want, rel=1e-10)


# --- plain oracle: covariance of discrete processes ------------------------------------------------

GATE = 40  # fine steps per gate


def _cov(kind: str, size: int) -> np.ndarray:
    if kind == "rwfm":  # y_k = e_0 + … + e_k
        i = np.arange(size)
        return np.minimum.outer(i, i) + 1.0
    return np.eye(size)  # white FM: y iid; white PM: x iid


def _gate_rows(kind: str, starts: list[int], length: int, size: int) -> np.ndarray:
    """Row vectors giving each gate's mean frequency as a linear form of the process samples."""
    rows = np.zeros((len(starts), size))
    for g, s in enumerate(starts):
        if kind == "wpm":  # x samples at fine points: y = (x_end − x_start)/length
            rows[g, s + length] += 1.0 / length
            rows[g, s] -= 1.0 / length
        else:
            rows[g, s:s + length] = 1.0 / length
    return rows


def _allan(kind: str, m: int, period: int, length: int) -> float:
    """½E[(ȳ_B − ȳ_A)²], ȳ the mean of m gates of ``length`` every ``period`` fine steps."""
    size = 2 * m * period + length + 1
    a = _gate_rows(kind, [i * period for i in range(m)], length, size).mean(axis=0)
    b = _gate_rows(kind, [(m + i) * period for i in range(m)], length, size).mean(axis=0)
    c = b - a
    return 0.5 * float(c @ _cov(kind, size) @ c)


KINDS = {"wpm": -2.0, "wfm": -1.0, "rwfm": 1.0}


@pytest.mark.parametrize("kind", list(KINDS))
@pytest.mark.parametrize("r_steps", [60, 120])  # r = 1.5, 3
def test_b2_oracle(kind, r_steps):
    want = _allan(kind, 1, r_steps, GATE) / _allan(kind, 1, GATE, GATE)
    # Discrete random-walk FM approaches the continuous value as 1/GATE²: 1e-3 is ample.
    assert b2(r_steps / GATE, KINDS[kind]) == pytest.approx(want, rel=1e-3)


@pytest.mark.parametrize("kind", list(KINDS))
@pytest.mark.parametrize("m", [2, 3])
@pytest.mark.parametrize("r_steps", [60, 120])
def test_b3_oracle(kind, m, r_steps):
    want = _allan(kind, m, r_steps, GATE) / _allan(kind, 1, m * r_steps, m * GATE)
    assert b3(2, m, r_steps / GATE, KINDS[kind]) == pytest.approx(want, rel=1e-3)


# --- the correction -------------------------------------------------------------------------------


def test_correction_undoes_the_bias():
    r, mu = 2.5, mu_from_alpha(-2)
    ms = [1, 2, 4]
    true = np.array([1e-12, 2e-12, 3e-12])
    measured = true * np.sqrt([b2(r, mu) * b3(2, m, r, mu) for m in ms])
    c = deadtime_correction(measured, ms, gate=2.0, dead=3.0, alpha=-2)
    np.testing.assert_allclose(c.dev, true, rtol=1e-12)
    np.testing.assert_allclose(c.taus, [2.0, 4.0, 8.0])
    assert c.r == 2.5


def test_no_dead_time_no_change():
    c = deadtime_correction([1e-11, 5e-12], [1, 10], gate=1.0, dead=0.0, alpha=-1)
    np.testing.assert_array_equal(c.dev, [1e-11, 5e-12])


def test_mu_from_alpha():
    assert [mu_from_alpha(a) for a in (2, 1, 0, -1, -2)] == [-2.0, -2.0, -1.0, 0.0, 1.0]


@pytest.mark.parametrize("call,error,match", [
    (lambda: b1(1, 0.0), ParameterError, "n=1"),
    (lambda: b2(0.5, 0.0), ParameterError, "r=0.5"),
    (lambda: b2(2.0, 2.0), ParameterError, r"\[-2, 2\)"),
    (lambda: b3(3, 2, 2.0, 0.0), ParameterError, "only B3"),
    (lambda: b3(2, 2.5, 2.0, 0.0), ParameterError, "m=2.5"),
    (lambda: mu_from_alpha(-3), ParameterError, "alpha=-3"),
    (lambda: deadtime_correction([1.0, 2.0], [1], gate=1.0, dead=1.0, alpha=0), DataError, "equal length"),
    (lambda: deadtime_correction([np.nan], [1], gate=1.0, dead=1.0, alpha=0), DataError, "finite"),
    (lambda: deadtime_correction([1.0], [1], gate=0.0, dead=1.0, alpha=0), ParameterError, "gate"),
])
def test_errors(call, error, match):
    with pytest.raises(error, match=match):
        call()
