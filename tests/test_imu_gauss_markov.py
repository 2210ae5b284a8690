"""The Gauss–Markov term of the IMU model (``sigmatau.imu.gaussmarkov``, ``analyze(gauss_markov=)``).

Known truth from :func:`sigmatau.imu.simulate` (``gauss_markov=(sigma, tau_c)``, the exact AR(1)):
the AVAR formula against its plain definition and a Monte Carlo of the generator; recovery of σ_GM
and T_c with the GM term chosen; coverage of their intervals over many seeds against a binomial
bound; the false-alarm rate on the presets (no GM); and the five-term results of records without
GM compared with ``gauss_markov="never"`` computed here (the code path of the model before the
option). The slow tests are those of the figures in ``docs/gauss-markov.md``.
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest
from scipy.stats import binom

import sigmatau
from sigmatau import imu
from sigmatau.errors import ParameterError
from sigmatau.imu.gaussmarkov import BIC_MARGIN, gauss_markov_avar

RATE = 100.0
N_WHITE = 1e-3
#: (σ_GM, T_c): humps of a few times the white level at their peak (≈ 0.62σ at τ ≈ 1.89 T).
CASES = [(2e-3, 1.0), (1e-3, 10.0), (5e-4, 100.0)]


def _analyze(y, **kw):
    """``imu.analyze`` with its expected warnings (K and the like are not resolved) silenced."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", imu.ImuWarning)
        return imu.analyze(y, **kw)


def _gm_record(sigma, tau_c, seed, duration=9000.0):
    return imu.simulate(duration=duration, rate=RATE, N=N_WHITE, gauss_markov=(sigma, tau_c), rng=seed)


# ------------------------------------------------------------------ the AVAR of the process


def _avar_plain(m: int, sigma: float, phi: float, tau0: float) -> float:
    """AVAR of a sampled AR(1) by its definition: half the variance of the difference of two adjacent
    m-sample means, ``wᵀΓw/2`` with ``w = (−1/m …, +1/m …)`` and ``Γ_ij = σ²φ^|i−j|``."""
    w = np.concatenate([-np.ones(m), np.ones(m)]) / m
    lag = np.abs(np.subtract.outer(np.arange(2 * m), np.arange(2 * m)))
    return float(w @ (sigma**2 * phi**lag) @ w / 2.0)


@pytest.mark.parametrize("tau_c", [0.013, 0.1, 3.0])
def test_avar_equals_its_definition_for_the_sampled_process(tau_c):
    tau0 = 1.0 / RATE
    ms = np.array([1, 2, 3, 7, 16, 50, 200])
    got = gauss_markov_avar(ms * tau0, sigma=2.0, tau_c=tau_c, rate=RATE)
    want = [_avar_plain(int(m), 2.0, math.exp(-tau0 / tau_c), tau0) for m in ms]
    np.testing.assert_allclose(got, want, rtol=1e-9)


def test_avar_continuous_form_and_limits():
    t = np.array([1e-4, 1e-3, 1e3, 1e4])
    v = gauss_markov_avar(t, sigma=1.0, tau_c=1.0)
    # τ ≪ T: a rate random walk K² = 2σ²/T (σ²_A = K²τ/3); τ ≫ T: white, N² = 2σ²T.
    np.testing.assert_allclose(v[:2], 2 * t[:2] / 3, rtol=1e-3)
    np.testing.assert_allclose(v[2:], 2 / t[2:] * (1 - 1.5 / t[2:]), rtol=1e-6)
    # The peak of the ADEV: τ ≈ 1.89 T, σ ≈ 0.618 σ_GM.
    tt = np.geomspace(1.0, 4.0, 4001)
    a = np.sqrt(gauss_markov_avar(tt, sigma=1.0, tau_c=1.0))
    assert tt[np.argmax(a)] == pytest.approx(1.8926, rel=1e-3) and a.max() == pytest.approx(0.61736, rel=1e-4)
    # Sampled and continuous forms meet away from the first few samples.
    x = np.geomspace(0.5, 500, 9)
    np.testing.assert_allclose(gauss_markov_avar(x, sigma=1.0, tau_c=5.0, rate=RATE),
                               gauss_markov_avar(x, sigma=1.0, tau_c=5.0), rtol=2e-3)


def test_avar_against_monte_carlo_of_the_generator():
    """Mean OAVAR of 24 simulated records against the formula, within 4 standard errors of the mean
    (relative standard error √(2/ΣEDF) at each τ, from the χ² EDF of each record)."""
    runs, edf = [], []
    for seed in range(24):
        y = imu.simulate(duration=300.0, rate=RATE, N=0.0, gauss_markov=(1.0, 0.5), rng=seed)
        r = sigmatau.oadev(y, rate=RATE, taus="octave")
        runs.append(r.var)
        edf.append(r.edf)
    taus = r.taus
    keep = taus <= 20.0
    mean = np.mean(runs, axis=0)[keep]
    se = np.sqrt(2.0 / np.sum(edf, axis=0)[keep])
    ratio = mean / gauss_markov_avar(taus[keep], sigma=1.0, tau_c=0.5, rate=RATE)
    assert np.all(np.abs(ratio - 1.0) < 4.0 * se), (ratio, se)


def test_avar_input_errors():
    with pytest.raises(ParameterError, match="tau_c"):
        gauss_markov_avar([1.0], sigma=1.0, tau_c=0.0)
    with pytest.raises(ParameterError, match="sigma"):
        gauss_markov_avar([1.0], sigma=-1.0, tau_c=1.0)
    with pytest.raises(ParameterError, match="taus"):
        gauss_markov_avar([0.0, 1.0], sigma=1.0, tau_c=1.0)


# ------------------------------------------------------------------ recovery in analyze


@pytest.fixture(scope="module")
def gm_model():
    """A 2.5 h, 100 Hz gyro: white noise plus a GM of σ = 1e-3 rad/s, T_c = 10 s (99.7 % intervals)."""
    y = _gm_record(1e-3, 10.0, seed=7)
    return _analyze(y, rate=RATE, unit="rad/s", confidence=0.997)


def test_gm_term_recovered_within_its_intervals(gm_model):
    gm = gm_model.gauss_markov
    assert gm is not None and gm.resolved
    assert gm.delta_bic > BIC_MARGIN and gm.criterion == "BIC"
    assert gm.sigma.low <= 1e-3 <= gm.sigma.high, gm
    assert gm.tau_c.low <= 10.0 <= gm.tau_c.high, gm
    assert gm.sigma.unit == "rad/s" and gm.tau_c.unit == "s"
    assert gm_model.N.low <= N_WHITE <= gm_model.N.high
    assert "GM" in gm_model.fit_terms


def test_gm_model_curve_flags_and_outputs(gm_model):
    m = gm_model
    taus = np.asarray(m.result.taus)
    # The model's curve holds the GM term: its total is the five terms plus the GM column.
    five = sum(m.term_deviation(t, taus) ** 2 for t in imu.TERMS)
    np.testing.assert_allclose(m.variance(taus), five + m.term_deviation("GM", taus) ** 2, rtol=1e-12)
    gm_part = gauss_markov_avar(taus, sigma=m.gauss_markov.sigma.value, tau_c=m.gauss_markov.tau_c.value,
                                rate=RATE)
    np.testing.assert_allclose(m.term_deviation("GM", taus) ** 2, gm_part, rtol=1e-9)
    # The GM term explains the curve: no model-discrepancy flag.
    assert not any(f.code == "model" for f in m.flags)
    d = json.loads(json.dumps(m.to_dict()))
    assert d["gauss_markov"]["sigma"]["value"] == pytest.approx(m.gauss_markov.sigma.value)
    assert d["gauss_markov"]["tau_c"]["unit"] == "s" and d["gauss_markov_test"]["chosen"] is True
    assert "Gauss–Markov term: σ =" in m.to_table()
    k = m.kalibr()
    assert "Gauss–Markov" in k["gauss_markov"] and "gyroscope_noise_density" in k


def test_without_gm_option_the_discrepancy_flag_fires():
    """The same record under ``gauss_markov="never"``: the five-term model cannot describe the hump."""
    y = _gm_record(1e-3, 10.0, seed=7)
    m = _analyze(y, rate=RATE, unit="rad/s", gauss_markov="never")
    assert m.gauss_markov is None and m.gauss_markov_test["mode"] == "never"
    assert any(f.code == "model" and "Gauss–Markov hump" in f.message for f in m.flags)


def test_figure_draws_the_gm_term(gm_model):
    pytest.importorskip("matplotlib")
    from sigmatau import plots

    r = gm_model.result
    fig = plots.sigma_tau_figure([plots.ChannelCurves("gyro x", "rad/s", {"oadev": r}, gm_model)])
    line = next(ln for ax in fig.axes for ln in ax.lines if ln.get_gid() == "term-GM-gyro x")
    assert "T_c" in line.get_label() and "Gauss–Markov" in line.get_label()
    x, yv = line.get_data()
    np.testing.assert_allclose(yv, gm_model.term_deviation("GM", x), rtol=1e-12)
    import matplotlib.pyplot as plt

    plt.close(fig)


def test_report_model_section_lists_the_gm_term(gm_model):
    from types import SimpleNamespace

    from sigmatau.report import html

    ch = SimpleNamespace(name="gyro x", model=gm_model, model_note=None, datasheet=None)
    text = html._model_section(SimpleNamespace(channels=[ch]))
    assert "GM σ" in text and "GM T<sub>c</sub>" in text and "ΔBIC" in text


def test_options_are_checked():
    y = imu.simulate("euroc-gyro", duration=60.0, rng=1)
    with pytest.raises(ParameterError, match="gauss_markov"):
        imu.analyze(y, rate=200.0, unit="rad/s", gauss_markov="sometimes")


def test_always_fits_a_term_on_a_record_without_one():
    y = imu.simulate("euroc-gyro", duration=1800.0, rng=3)
    m = _analyze(y, rate=200.0, unit="rad/s", gauss_markov="always")
    t = m.gauss_markov_test
    assert t["mode"] == "always" and t["tau_c_best"] is not None
    if m.gauss_markov is not None:
        assert m.gauss_markov.note.startswith("gauss_markov='always'")
    json.dumps(m.to_dict())


def test_filtered_white_noise_keeps_n_with_auto():
    """White noise through a first-order low-pass filter is a GM process of short T_c (here 5 samples):
    "auto" keeps the five-term model with N (the GM term would replace it), "always" fits the GM."""
    y = imu.simulate(duration=1800.0, rate=RATE, N=0.0, gauss_markov=(1e-2, 0.05), rng=5)
    auto = _analyze(y, rate=RATE, unit="rad/s")
    assert auto.gauss_markov is None and auto.N.resolved
    assert "replaces the white noise" in auto.gauss_markov_test["reason"]
    always = _analyze(y, rate=RATE, unit="rad/s", gauss_markov="always", confidence=0.997)
    assert always.gauss_markov is not None and always.gauss_markov.resolved
    assert always.gauss_markov.tau_c.low <= 0.05 <= always.gauss_markov.tau_c.high


# ------------------------------------------------------------------ records without GM


def _same_parameter(a, b):
    return (a.resolved == b.resolved and a.note == b.note
            and all((x == y) or (math.isnan(x) and math.isnan(y)) for x, y in
                    ((a.value, b.value), (a.low, b.low), (a.high, b.high))))


@pytest.mark.parametrize("preset,seed", [("euroc-gyro", 11), ("euroc-accel", 12), ("lsm6dsl-gyro", 13)])
def test_records_without_gm_keep_the_five_term_results(preset, seed):
    p = imu.PRESETS[preset]
    y = imu.simulate(preset, duration=1800.0, rng=seed)
    auto = _analyze(y, rate=p.rate, unit=p.unit)
    never = _analyze(y, rate=p.rate, unit=p.unit, gauss_markov="never")
    assert auto.gauss_markov is None and auto.gauss_markov_test["chosen"] is False
    for t in imu.TERMS:
        assert _same_parameter(getattr(auto, t), getattr(never, t)), t
        assert _same_parameter(auto.readoff[t], never.readoff[t]), t
    assert auto.fit_terms == never.fit_terms and auto.flags == never.flags
    np.testing.assert_array_equal(auto.covariance, never.covariance)
    assert auto.discrepancy == never.discrepancy and auto.fit_chi2 == never.fit_chi2


# ------------------------------------------------------------------ slow: coverage and false alarms


def _binomial_floor(n: int, p: float) -> int:
    """Fewest successes out of n that a true rate p gives with probability ≥ 0.999."""
    return int(binom.ppf(0.001, n, p))


@pytest.mark.slow
@pytest.mark.parametrize("sigma,tau_c", CASES)
def test_gm_choice_and_coverage_over_seeds(sigma, tau_c):
    """60 records per case: the GM term is chosen in ≥ 95 % (binomial floor), and the 68.3 % intervals
    of σ_GM, T_c and N cover the truth no less often than the nominal rate allows (binomial floor at
    10⁻³, given the number of records where the term was chosen)."""
    n = 60
    chosen = cov_s = cov_t = cov_n = 0
    for seed in range(n):
        m = _analyze(_gm_record(sigma, tau_c, seed=500 + seed), rate=RATE, unit="rad/s")
        gm = m.gauss_markov
        if gm is None or not gm.resolved:
            continue
        chosen += 1
        cov_s += gm.sigma.low <= sigma <= gm.sigma.high
        cov_t += gm.tau_c.low <= tau_c <= gm.tau_c.high
        cov_n += m.N.low <= N_WHITE <= m.N.high
    assert chosen >= _binomial_floor(n, 0.95)
    floor = _binomial_floor(chosen, 0.683)
    assert cov_s >= floor and cov_t >= floor and cov_n >= floor, (chosen, cov_s, cov_t, cov_n)


@pytest.mark.slow
@pytest.mark.parametrize("preset", ["euroc-gyro", "euroc-accel", "lsm6dsl-gyro", "adis16448-accel"])
def test_false_alarm_rate_on_presets(preset):
    """No GM in the presets: over 60 records a GM term is kept no more often than a 2 % rate allows
    (binomial ceiling at 10⁻³)."""
    p = imu.PRESETS[preset]
    n = 60
    alarms = sum(_analyze(imu.simulate(preset, duration=1800.0, rng=900 + s), rate=p.rate,
                          unit=p.unit).gauss_markov is not None for s in range(n))
    assert alarms <= int(binom.ppf(0.999, n, 0.02)), alarms
