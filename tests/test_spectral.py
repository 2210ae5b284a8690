"""sigmatau.spectral: conversions σ(τ) ↔ spectrum, PSD with log-frequency averaging, jitter.

Sources of expected values:
* SP1065 Table 9 as re-derived in ``sigmatau.core.powerlaw.response`` (power-law expectations);
* plain oracles written here from the estimators' definitions (weights on the phase samples,
  exact variances for white phase and for Brownian phase);
* F. Vernotte et al., IEEE TUFFC 63(4) 2016, PVAR responses for white FM 3h0/(5τ), flicker FM
  2(7 − ln 16)h₋₁/5, random-walk FM 26π²h₋₂τ/35 and white PM 3h2/(2π²τ³) (continuous limits);
* closed forms (jitter of a flat and of an f⁻² L(f)).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import sigmatau
from sigmatau.core.powerlaw import response
from sigmatau.errors import DataError, ParameterError
from sigmatau.spectral import (dbc_to_s_phi, psd, rms_jitter, s_phi_to_dbc, s_phi_to_s_x, s_x_to_s_phi,
                               s_x_to_s_y, s_y_to_s_x, sigma_to_h, spectrum_to_sigma, transfer_function)
from sigmatau.stats.modhadamard import mhdev

# --- power-law expectations -----------------------------------------------------------------

# (kind, α, sampled): entries of powerlaw.response that are exact integrals at every m.
EXACT = ([("avar", a, False) for a in (2, 0, -1, -2)]
         + [("hvar", a, False) for a in (2, 0, -1, -2, -3, -4)]
         + [("mvar", 2, False), ("tvar", 2, False), ("mvar", 0, True), ("tvar", 0, True)])
# Entries that are the large-m limits (SP1065 asymptotic forms).
LIMITS = ([("avar", 1), ("hvar", 1)] + [(k, a) for k in ("mvar", "tvar") for a in (1, 0, -1, -2)])


@pytest.mark.parametrize("kind,alpha,sampled", EXACT)
@pytest.mark.parametrize("m", [1, 2, 3, 10, 64])
@pytest.mark.parametrize("rate", [1.0, 250.0])
def test_powerlaw_exact_entries(kind, alpha, sampled, m, rate):
    tau = np.array([m / rate])
    got = spectrum_to_sigma({alpha: 1.0}, tau, stat=kind, rate=rate).var
    want = response(kind, alpha, tau, rate, sampled=sampled)
    np.testing.assert_allclose(got, want, rtol=1e-9)


@pytest.mark.parametrize("kind,alpha", LIMITS)
def test_powerlaw_limit_entries(kind, alpha):
    # The table holds the m → ∞ form; the sampled integral reaches it as 1/m².
    rel = []
    for m in (1024, 4096):
        tau = np.array([float(m)])
        got = spectrum_to_sigma({alpha: 1.0}, tau, stat=kind, rate=1.0).var[0]
        rel.append(abs(got / response(kind, alpha, tau, 1.0)[0] - 1.0))
    assert rel[1] < 1e-6
    assert rel[0] / rel[1] > 8.0  # ≈ 16 for a 1/m² approach


def test_mixture_is_sum_of_terms():
    taus = np.array([1.0, 8.0, 32.0])
    h = {2: 3e-22, 0: 2e-20, -2: 1e-26}
    got = spectrum_to_sigma(h, taus, stat="oadev", rate=1.0).var
    want = sum(v * response("avar", a, taus, 1.0) for a, v in h.items())
    np.testing.assert_allclose(got, want, rtol=1e-9)


def test_pvar_vernotte_limits():
    tau = 4096.0
    cases = {0: 3.0 / (5.0 * tau), -1: 2.0 * (7.0 - math.log(16.0)) / 5.0,
             -2: 26.0 * math.pi**2 / 35.0 * tau, 2: 3.0 / (2.0 * math.pi**2 * tau**3)}
    for alpha, want in cases.items():
        got = spectrum_to_sigma({alpha: 1.0}, [tau], stat="pdev", rate=1.0).var[0]
        assert got == pytest.approx(want, rel=1e-6)


# --- plain oracles: the estimators' weights on the phase samples ------------------------------


def _weights(kind: str, n: int, tau0: float = 1.0) -> tuple[np.ndarray, float]:
    """Weights w on x_0 … x_K and normaliser: variance = E[(Σ w_k x_k)²]/norm (one term)."""
    tau = n * tau0
    if kind in ("avar", "hvar"):
        coef = [1, -2, 1] if kind == "avar" else [-1, 3, -3, 1]
        w = np.zeros(n * (len(coef) - 1) + 1)
        for j, c in enumerate(coef):
            w[j * n] += c
        return w, (2.0 if kind == "avar" else 6.0) * tau**2
    if kind in ("mvar", "tvar", "mhvar", "lvar"):
        coef = [1, -2, 1] if kind in ("mvar", "tvar") else [-1, 3, -3, 1]
        w = np.zeros(n * (len(coef) - 1) + n)
        for i in range(n):
            for j, c in enumerate(coef):
                w[i + j * n] += c / n
        norm = (2.0 if kind in ("mvar", "tvar") else 6.0) * tau**2
        scale = {"tvar": tau**2 / 3.0, "lvar": tau**2 * 3.0 / 10.0}.get(kind, 1.0)
        return w, norm / scale
    # PVAR (Vernotte et al. 2016): Σ_k ((n−1)/2 − k)(x_{i+k} − x_{i+n+k}), 72/(n⁴τ²); AVAR at n = 1
    if n == 1:
        return _weights("avar", 1, tau0)
    w = np.zeros(2 * n)
    for k in range(n):
        c = (n - 1) / 2.0 - k
        w[k] += c
        w[n + k] -= c
    return w, n**4 * tau**2 / 72.0


KINDS_ALL = ["avar", "hvar", "mvar", "tvar", "mhvar", "lvar", "pvar"]


@pytest.mark.parametrize("kind", KINDS_ALL)
@pytest.mark.parametrize("n", [1, 2, 3, 7])
def test_white_pm_oracle(kind, n):
    # White phase with a sharp cut-off at f_h = 1/(2τ0): samples iid, σ_x² = h2 f_h/(4π²).
    h2 = 1.0
    w, norm = _weights(kind, n)
    want = h2 * 0.5 / (4.0 * math.pi**2) * np.sum(w**2) / norm
    got = spectrum_to_sigma({2: h2}, [float(n)], stat=kind, rate=1.0).var[0]
    assert got == pytest.approx(want, rel=1e-10)


@pytest.mark.parametrize("kind", KINDS_ALL)
@pytest.mark.parametrize("n", [1, 2, 3, 7])
def test_white_fm_oracle(kind, n):
    # Brownian phase (S_y = h0 to infinity) sampled at points: increments iid, variance h0τ0/2.
    h0 = 1.0
    w, norm = _weights(kind, n)
    tail = np.array([np.sum(w[j + 1:]) for j in range(w.size - 1)])
    want = h0 * 0.5 * np.sum(tail**2) / norm
    got = spectrum_to_sigma({0: h0}, [float(n)], stat=kind, rate=1.0).var[0]
    assert got == pytest.approx(want, rel=1e-10)


@pytest.mark.parametrize("kind", KINDS_ALL)
def test_transfer_function_is_weights_dft(kind):
    n, rate = 5, 2.0
    w, norm = _weights(kind, n, 1.0 / rate)
    f = np.array([0.013, 0.21, 0.377, 0.6, 0.999, 1.37])
    k = np.arange(w.size)
    dft = np.array([abs(np.sum(w * np.exp(-2j * math.pi * fi * k / rate))) ** 2 for fi in f])
    want = dft / norm / (2.0 * math.pi * f) ** 2
    np.testing.assert_allclose(transfer_function(kind, f, n / rate, rate=rate), want, rtol=1e-9)


@pytest.mark.slow
@pytest.mark.parametrize("kind", KINDS_ALL)
def test_long_tau_method_matches_node_by_node(kind, monkeypatch):
    # Beyond _DIRECT_MAX half periods the middle of the band is integrated by its mean and end
    # corrections; against every half period integrated on its own (n = 5000, 12345).
    import sigmatau.spectral.convert as convert

    f = np.geomspace(1e-6, 0.7, 50)
    table = (f, 1e-20 * (f**-1.0 + 30.0 * f**2))
    for tau in (5000.0, 12345.0):
        fast = [spectrum_to_sigma({a: 1.0}, [tau], stat=kind, rate=1.0).var[0] for a in (2, 1, 0, -1, -2)]
        fast.append(spectrum_to_sigma(table, [tau], stat=kind, rate=1.0).var[0])
        fast.append(spectrum_to_sigma(table, [tau], stat=kind, rate=1.0, samples=True).var[0])
        monkeypatch.setattr(convert, "_DIRECT_MAX", 10**9)
        slow = [spectrum_to_sigma({a: 1.0}, [tau], stat=kind, rate=1.0).var[0] for a in (2, 1, 0, -1, -2)]
        slow.append(spectrum_to_sigma(table, [tau], stat=kind, rate=1.0).var[0])
        slow.append(spectrum_to_sigma(table, [tau], stat=kind, rate=1.0, samples=True).var[0])
        monkeypatch.undo()
        np.testing.assert_allclose(fast, slow, rtol=1e-9)


# --- tables, phase noise, refusals ------------------------------------------------------------


def test_table_matches_power_law():
    f = np.geomspace(1e-6, 0.5, 400)
    taus = [1.0, 4.0, 16.0]
    got = spectrum_to_sigma((f, 2e-22 * f**2), taus, stat="mdev", rate=1.0).var
    want = spectrum_to_sigma({2: 2e-22}, taus, stat="mdev", rate=1.0).var
    np.testing.assert_allclose(got, want, rtol=1e-6)


def test_table_errors():
    with pytest.raises(DataError, match=">= 0"):
        spectrum_to_sigma(([0.1, 0.2], [1.0, -1.0]), [1.0], stat="oadev", rate=1.0)
    with pytest.raises(DataError, match="increasing"):
        spectrum_to_sigma(([0.2, 0.1], [1.0, 1.0]), [1.0], stat="oadev", rate=1.0)
    with pytest.raises(ParameterError, match="carrier"):
        spectrum_to_sigma(([0.1, 0.2], [-100.0, -110.0]), [1.0], stat="oadev", rate=1.0, spectrum_type="L")


def test_phase_noise_input_equals_s_y():
    f = np.geomspace(1.0, 1e5, 60)
    nu0 = 10e6
    l_dbc = -120.0 - 10.0 * np.log10(f)
    s_y = (f / nu0) ** 2 * 2.0 * 10.0 ** (l_dbc / 10.0)
    a = spectrum_to_sigma((f, l_dbc), [1e-4, 1e-3], stat="oadev", rate=2e5, spectrum_type="L", carrier=nu0)
    b = spectrum_to_sigma((f, s_y), [1e-4, 1e-3], stat="oadev", rate=2e5)
    np.testing.assert_allclose(a.var, b.var, rtol=1e-12)


@pytest.mark.parametrize("stat", ["totdev", "mtotdev", "htotdev", "theo1", "theobr"])
def test_no_transfer_function_refused(stat):
    with pytest.raises(ParameterError, match="no exact transfer function"):
        spectrum_to_sigma({0: 1.0}, [1.0], stat=stat, rate=1.0)


@pytest.mark.parametrize("kwargs,match", [
    ({"stat": "nope"}, "unknown"),
    ({"taus": [1.5]}, "integer multiples"),
    ({"spectrum": {3: 1.0}}, "converges only"),
    ({"spectrum": {0: -1.0}}, ">= 0"),
    ({"rate": None}, "rate is required"),
])
def test_conversion_errors(kwargs, match):
    args = {"spectrum": {0: 1.0}, "taus": [1.0], "stat": "oadev", "rate": 1.0} | kwargs
    with pytest.raises(ParameterError, match=match):
        spectrum_to_sigma(args.pop("spectrum"), args.pop("taus"), **args)


def test_sigma_to_h_inverts_table9():
    taus = np.array([2.0, 8.0, 32.0])
    for stat, kind in (("oadev", "avar"), ("mdev", "mvar"), ("ohdev", "hvar")):
        for alpha in (2, 1, 0, -1, -2):
            dev = np.sqrt(3e-21 * response(kind, alpha, taus, 1.0))
            est = sigma_to_h(taus, dev, alpha=alpha, stat=stat, rate=1.0)
            assert est.h == pytest.approx(3e-21, rel=1e-12)


# --- psd --------------------------------------------------------------------------------------

# Kasdin–Walter series have S(f) = h_α (sin(πfτ0)/(πτ0))^α: within 1 % of h_α f^α below 0.05/τ0.
FIT_RANGE = (0.0, 0.05)


@pytest.mark.parametrize("alpha", [2, 1, 0, -1, -2])
def test_psd_recovers_h(alpha, rng):
    h = 10.0 ** (-20 - alpha)
    y = sigmatau.power_law_noise(2**16, alpha, h=h, rate=1.0, rng=rng)
    r = psd(y, rate=1.0, fit_range=FIT_RANGE, confidence=0.9973)  # 3σ: a single draw
    assert r.h_lo[alpha] <= h <= r.h_hi[alpha]
    assert all(d[2] == alpha for d in r.dominant)


def test_psd_h_interval_coverage():
    # 200 series at 68.27 %: binomial 3σ = 3·sqrt(p(1-p)/200) = 0.099.
    gen = np.random.default_rng(151)
    hits = []
    for _ in range(200):
        y = sigmatau.power_law_noise(2**14, 0, h=1.0, rate=1.0, rng=gen)
        r = psd(y, rate=1.0, alphas=(0,), fit_range=FIT_RANGE)
        hits.append(r.h_lo[0] <= 1.0 <= r.h_hi[0])
    p = 0.682689
    assert abs(np.mean(hits) - p) < 3.0 * math.sqrt(p * (1 - p) / 200)


def test_psd_bin_interval_coverage():
    # White FM (flat spectrum, where the EDF's flat-in-bin assumption is exact).
    gen = np.random.default_rng(152)
    hits = n = 0
    for _ in range(100):
        y = sigmatau.power_law_noise(2**14, 0, h=1.0, rate=1.0, rng=gen)
        r = psd(y, rate=1.0, alphas=(0,))
        hits += int(np.sum((r.lo <= 1.0) & (1.0 <= r.hi)))
        n += r.f.size
    p = 0.682689
    assert abs(hits / n - p) < 3.0 * math.sqrt(p * (1 - p) / n)


@pytest.mark.parametrize("alpha", [2, -1, -2])
def test_psd_bin_interval_coverage_coloured(alpha):
    # Against the Kasdin series' exact discrete spectrum averaged over each bin's frequencies;
    # 60 series × 26 bins, binomial 3σ.
    from sigmatau.spectral.psd import _log_bins

    gen = np.random.default_rng(153 + alpha)
    hits = n = 0
    for _ in range(60):
        y = sigmatau.power_law_noise(2**14, alpha, h=1.0, rate=1.0, rng=gen)
        r = psd(y, rate=1.0, alphas=(alpha,))
        exact = (np.sin(np.pi * r.raw_f) / np.pi) ** alpha
        truth = np.array([exact[b].mean() for b in _log_bins(r.raw_f, 10)])
        hits += int(np.sum((r.lo <= truth) & (truth <= r.hi)))
        n += truth.size
    p = 0.682689
    assert abs(hits / n - p) < 3.0 * math.sqrt(p * (1 - p) / n)


def test_psd_parseval(rng):
    y = sigmatau.power_law_noise(2**15, 0, h=2.0, rate=10.0, rng=rng)
    r = psd(y, rate=10.0, alphas=(0,))
    df = r.raw_f[1] - r.raw_f[0]
    # The kept band lacks DC, two bins and Nyquist (1.5e-3 of it); Welch's EDF ≈ 2·N → sd ≈ 1 %.
    assert np.sum(r.raw_s_y) * df == pytest.approx(np.var(y), rel=0.04)


def test_psd_phase_input_and_units(rng):
    x = sigmatau.power_law_noise(2**13, 2, h=1e-20, rate=1.0, data_type="phase", rng=rng)
    r = psd(x, rate=1.0, data_type="phase", carrier=5e6)
    ry = psd(np.diff(x), rate=1.0)
    np.testing.assert_allclose(r.s_y, ry.s_y, rtol=1e-12)
    # the samples are phase differences: S_y = |2·rate·sin(πf/rate)|²·S_x exactly
    np.testing.assert_allclose(r.s_x, r.s_y / (2 * np.sin(math.pi * r.f)) ** 2, rtol=1e-12)
    # white PM of h2 = 1e-20: S_x = h2/(2π)² flat; within the bins' χ² intervals up to Nyquist
    # (the continuous (2πf)² would put the top bin 3.9 dB low)
    truth = 1e-20 / (2 * math.pi) ** 2
    inside = (r.lo / (2 * np.sin(math.pi * r.f)) ** 2 <= truth) & (truth <= r.hi / (2 * np.sin(math.pi * r.f)) ** 2)
    assert inside[r.f > 0.1].mean() > 0.5 and inside[-3:].any()
    np.testing.assert_allclose(r.s_phi, (2 * math.pi * 5e6) ** 2 * r.s_x, rtol=1e-12)
    np.testing.assert_allclose(r.l_dbc, 10 * np.log10(r.s_phi / 2), rtol=1e-12)
    with pytest.raises(ParameterError, match="carrier"):
        _ = ry.s_phi


def test_psd_dominant_per_decade(rng):
    y = (sigmatau.power_law_noise(2**16, 2, h=1.0, rate=1.0, rng=rng)
         + sigmatau.power_law_noise(2**16, -2, h=1e-8, rate=1.0, rng=rng))
    r = psd(y, rate=1.0)
    assert r.dominant[0][2] == -2 and r.dominant[-1][2] == 2


@pytest.mark.parametrize("data,kwargs,error,match", [
    ([1.0, np.nan] * 100, {}, DataError, "NaN|finite"),
    (np.ones(500), {}, DataError, "constant"),
    (np.arange(40.0), {}, DataError, "need >= 16"),
    (np.arange(400.0) % 7, {"window": "nowindow"}, ParameterError, "window"),
    (np.arange(400.0) % 7, {"segments": 0}, ParameterError, "segments"),
    (np.arange(400.0) % 7, {"fit_range": (0.3, 0.1)}, ParameterError, "f_low < f_high"),
    (np.arange(400.0) % 7, {"alphas": ()}, ParameterError, "alphas"),
    (np.arange(400.0) % 7, {"carrier": -1.0}, ParameterError, "carrier"),
])
def test_psd_errors(data, kwargs, error, match):
    with pytest.raises(error, match=match):
        psd(np.asarray(data), rate=1.0, **kwargs)


# --- round trip: series → psd → σ(τ) against oadev on the same series ----------------------------


# pdev joins this list once its EDF is attached (its kernel is held to the definition above).
ROUND_TRIP_STATS = {"oadev": sigmatau.oadev, "mdev": sigmatau.mdev, "tdev": sigmatau.tdev,
                    "ohdev": sigmatau.ohdev, "mhdev": mhdev, "pdev": sigmatau.pdev}


@pytest.mark.parametrize("alpha", [2, 1, 0, -1, -2])
def test_round_trip_psd_to_sigma(alpha, rng):
    # The converted spectrum must fall inside each statistic's own 95 % interval, same series.
    y = sigmatau.power_law_noise(2**15, alpha, h=1.0, rate=1.0, rng=rng)
    spectrum = psd(y, rate=1.0)
    for stat, func in ROUND_TRIP_STATS.items():
        o = func(y, rate=1.0, m=[1, 4, 16, 64], alpha=alpha, confidence=0.95)
        c = spectrum_to_sigma(spectrum, o.taus, stat=stat)
        assert np.all((o.ci_low <= c.dev) & (c.dev <= o.ci_high)), stat


# --- jitter and units ---------------------------------------------------------------------------


def test_jitter_flat():
    r = rms_jitter([10.0, 1e6], [-150.0, -150.0], carrier=100e6)
    want = math.sqrt(2.0 * 1e-15 * (1e6 - 10.0)) / (2.0 * math.pi * 100e6)
    assert r.jitter == pytest.approx(want, rel=1e-12)


def test_jitter_sloped_and_band():
    # L = −100 − 20 log10(f/10): S = 1e-10 (f/10)^-2, ∫_{f1}^{f2} = 1e-8 (1/f1 − 1/f2).
    f = np.array([10.0, 100.0, 1e3, 1e4])
    l_dbc = -100.0 - 20.0 * np.log10(f / 10.0)
    r = rms_jitter(f, l_dbc, carrier=1e9, band=(30.0, 5e3))
    want = math.sqrt(2.0 * 1e-8 * (1 / 30.0 - 1 / 5e3)) / (2.0 * math.pi * 1e9)
    assert r.jitter == pytest.approx(want, rel=1e-12)
    with pytest.raises(ParameterError, match="band"):
        rms_jitter(f, l_dbc, carrier=1e9, band=(1.0, 5e3))


def test_unit_round_trips():
    f = np.array([1.0, 10.0, 1e3])
    l_dbc = np.array([-90.0, -120.0, -150.0])
    s_phi = dbc_to_s_phi(l_dbc)
    np.testing.assert_allclose(s_phi_to_dbc(s_phi), l_dbc, rtol=1e-13)
    s_x = s_phi_to_s_x(s_phi, carrier=1e7)
    np.testing.assert_allclose(s_x_to_s_phi(s_x, carrier=1e7), s_phi, rtol=1e-13)
    s_y = s_x_to_s_y(f, s_x)
    np.testing.assert_allclose(s_y, (f / 1e7) ** 2 * s_phi, rtol=1e-13)
    np.testing.assert_allclose(s_y_to_s_x(f, s_y), s_x, rtol=1e-13)


def test_low_end_warning(rng):
    y = sigmatau.power_law_noise(2**12, 0, h=1.0, rate=1.0, rng=rng)
    r = psd(y, rate=1.0, alphas=(0,))
    with pytest.warns(sigmatau.errors.RangeWarning, match="fitted power law"):
        spectrum_to_sigma(r, [256.0], stat="oadev")
    with pytest.warns(sigmatau.errors.RangeWarning, match="held flat"):
        spectrum_to_sigma((r.f, r.s_y), [256.0], stat="oadev", rate=1.0)


def test_sigma_to_powerlaw_round_trip(rng):
    # σ(τ) → power-law fit → σ(τ) of another statistic: MDEV predicted from an OADEV curve.
    from sigmatau.spectral import sigma_to_powerlaw

    y = (sigmatau.power_law_noise(2**15, 0, h=2e-20, rate=1.0, rng=rng)
         + sigmatau.power_law_noise(2**15, -2, h=1e-26, rate=1.0, rng=rng))
    fit = sigma_to_powerlaw(sigmatau.oadev(y, rate=1.0), alphas=(0, -2))
    m = sigmatau.mdev(y, rate=1.0, m=[1, 8, 64, 512], confidence=0.95)
    pred = spectrum_to_sigma(fit, m.taus, stat="mdev", rate=1.0)
    assert np.all((m.ci_low <= pred.dev) & (pred.dev <= m.ci_high))
