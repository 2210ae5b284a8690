"""Recovery and interval coverage of the IMU noise model over many seeds (slow).

The issue's validation: EuRoC-like gyro (N = 1.6968e-4 rad/s/√Hz, K = 1.9393e-5
rad/s²/√Hz) and accelerometer (N = 2.0e-3, K = 3.0e-3) channels and LSM6DSL-like
channels with flicker (datasheet N 4 mdps/√Hz and 80 µg/√Hz; B 5 °/h and 50 µg,
illustrative values: the datasheet gives none), at 200 Hz. Every seed runs the
public :func:`sigmatau.imu.analyze` (data checks off: they do not change the
figures of clean simulated data and cost time).

Checked for every seed: the fit recovers N within 2 % and K within 25 %, and
reports no Q or B where none was simulated (no K, Q either on the flicker
channels). Checked over the seeds: each reported 68.3 % interval covers the true
value at a rate consistent with 68.3 %. With S seeds the count is binomial, sd
≈ √(0.683·0.317/S) = 6.6 % for S = 50; the accepted band [0.50, 0.90] is −2.8 sd
to +3.3 sd (the upper side leaves room for the measured, slightly conservative
intervals; see the imu module docstring for the measured numbers).

Runtime: 50 seeds × 4 channels. At the full 3 h (2.16 M samples per channel)
one seed-channel costs 0.6 s (EuRoC: 0.1 s to simulate, 0.5 s to analyse) to
1.2 s (LSM6DSL: the exact flicker generator adds 0.7 s) on the 2-core machine
when it is quiet, twice that when it is shared: 3–6 min in all, over the
3-minute budget. So the EuRoC channels, which the issue specifies at 3 h, run at
full length, and the LSM6DSL channels at 1 h (720 000 samples; the longest τ is
660 s instead of 2600 s). The full-length 50-seed run of all four channels is
reported in the module docstring of :mod:`sigmatau.imu`.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from sigmatau.imu import ImuWarning, analyze, simulate

SEEDS = 50
RATE = 200.0
#: name: (preset, unit, extra terms, truth, duration in s)
CHANNELS = {
    "euroc-gyro": ("euroc-gyro", "rad/s", {}, {"N": 1.6968e-4, "K": 1.9393e-5}, 3 * 3600.0),
    "euroc-accel": ("euroc-accel", "m/s^2", {}, {"N": 2.0e-3, "K": 3.0e-3}, 3 * 3600.0),
    "lsm6dsl-gyro": ("lsm6dsl-gyro", "deg/s", {"B": 5.0 / 3600.0}, {"N": 4.0e-3, "B": 5.0 / 3600.0}, 3600.0),
    "lsm6dsl-accel": ("lsm6dsl-accel", "g", {"B": 50e-6}, {"N": 80e-6, "B": 50e-6}, 3600.0),
}


def _run(name: str, seed: int):
    preset, unit, extra, _, duration = CHANNELS[name]
    y = simulate(preset, duration=duration, rate=RATE, unit=unit, rng=seed, **extra)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ImuWarning)
        return analyze(y, rate=RATE, unit=unit, checks=False)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(CHANNELS))
def test_recovery_and_coverage(name):
    truth = CHANNELS[name][3]
    covered = {t: 0 for t in truth}
    errors = {t: [] for t in truth}
    spurious = []
    for seed in range(SEEDS):
        m = _run(name, 1000 + seed)
        for t, v in truth.items():
            p = getattr(m, t)
            assert p.resolved, (name, seed, t)
            errors[t].append(p.value / v - 1.0)
            covered[t] += p.low <= v <= p.high
        spurious += [(seed, t) for t in "QNBKR" if t not in truth and getattr(m, t).resolved]
    err_n = np.abs(errors["N"])
    assert err_n.max() < 0.02, (name, err_n.max())
    if "K" in errors:
        assert np.abs(errors["K"]).max() < 0.25, (name, np.abs(errors["K"]).max())
    bad = [(s, t) for s, t in spurious if t in ("Q", "B", "K")]
    assert bad == [], (name, bad)
    assert len(spurious) <= 2, (name, spurious)          # R from a flicker realisation's drift, rarely
    for t in truth:
        rate = covered[t] / SEEDS
        rms = math.sqrt(np.mean(np.square(errors[t])))
        worst = 100 * np.max(np.abs(errors[t]))
        print(f"{name} {t}: coverage {rate:.2f}, rms error {100 * rms:.2f} %, max {worst:.2f} %")
        assert 0.50 <= rate <= 0.90, (name, t, rate)


# ----------------------------------------------------------------- terms sharing the end

#: Truths on a 2 h record at 100 Hz (τ 0.01 s … ~1800 s), in rad/s units. The
#: crossings are placed inside the τ range: Q/N at 0.1 s, N/B at 30 s, B/K at
#: 300 s, N/K at 30 s and K/R at 300 s (K and R share the end of the record).
GRID_RATE = 100.0
GRID_DURATION = 2 * 3600.0
GRID = {
    "Q+N": {"Q": 1.8e-4, "N": 1e-3},
    "N+B": {"N": 1e-3, "B": 2.75e-4},
    "N+B+K": {"N": 1e-3, "B": 2.75e-4, "K": 1.8e-5},
    "N+K+R": {"N": 1e-3, "K": 5.8e-5, "R": 2.7e-6},
    "N+B+K+R": {"N": 1e-3, "B": 2.75e-4, "K": 1.8e-5, "R": 4.6e-7},
}


def _statements(config: str, seed: int, methods=("fit", "readoff"), kept: list | None = None):
    """(term, method, kind, holds) for every truth term: kind 'interval' for a
    resolved parameter (holds when low ≤ truth ≤ high), 'bound' for an
    unresolved one (holds when truth ≤ high). ``kept`` collects the fit's terms."""
    truth = GRID[config]
    y = simulate(duration=GRID_DURATION, rate=GRID_RATE, unit="rad/s", rng=seed, **truth)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ImuWarning)
        m = analyze(y, rate=GRID_RATE, unit="rad/s", checks=False)
    if kept is not None:
        kept.append(m.fit_terms)
    out = []
    for t, v in truth.items():
        for method in methods:
            p = getattr(m, t) if method == "fit" else m.readoff[t]
            if p.resolved:
                out.append((t, method, "interval", p.low <= v <= p.high))
            else:
                out.append((t, method, "bound", v <= p.high))
    return out


def _nominal(kind: str, conf: float = 0.683) -> float:
    # A bound is the upper end of the two-sided interval: one-sided at (1 + p)/2.
    return conf if kind == "interval" else 0.5 * (1.0 + conf)


@pytest.mark.slow
def test_k_and_r_sharing_the_end_fast():
    """K and R sharing the end of the record (the issue's case): the printed
    statement for each (interval when resolved, upper bound when not) holds at
    its nominal rate, pooled over K and R and 30 seeds (60 statements).

    The count of statements that hold is a sum of Bernoulli variables with the
    nominal probabilities p_i (0.683 for an interval, 0.8415 for a bound): mean
    Σp_i, variance Σp_i(1 − p_i) (Poisson-binomial; K and R of one run are
    treated as independent). Accepted: not below 3.29 sd under the mean (one-sided;
    see the assertion). Before the fix: 65 of 120 held for 60 seeds (54 %, expected ≈ 74 %,
    −3.4 sd at 30 seeds), the kept term came out 1.07–1.29× the truth.
    """
    kept: list = []
    stmts = [s for seed in range(30) for s in _statements("N+K+R", 50_000 + seed, methods=("fit",), kept=kept)
             if s[0] in ("K", "R")]
    p = np.array([_nominal(kind) for _, _, kind, _ in stmts])
    held = sum(h for *_, h in stmts)
    mean, sd = p.sum(), math.sqrt(np.sum(p * (1 - p)))
    print(f"K, R statements held {held}/{len(stmts)} (expected {mean:.1f} ± {sd:.1f})")
    # One-sided since the selection-aware bounds (issue 11): a dropped R's bound over-covers in
    # N+K+R (117 of 122 in the grid, KNOWN_OPEN: the simulated ramp is deterministic) and so does
    # the kept K's interval there (146 of 198 in the grid, 73.7 %, with the selection-aware
    # intervals), so the pooled count sits above its nominal mean (55 of 60 held here, expected
    # 44.5 ± 3.3). What this test guards against is the under-coverage it was written for.
    assert held >= mean - 3.29 * sd, (held, mean, sd)
    both = sum("K" in k and "R" in k for k in kept)
    print(f"K and R both kept in {both}/30 runs")   # reported: the selection may keep one (see imu Notes)


def _copula_curves(truth: dict, rng: np.random.Generator, draws: int):
    """OADEV curves of the 2 h, 100 Hz grid record drawn from a model of the points themselves:
    AVAR_i = model_i·X_i with ln X jointly normal (mean −s_i²/2, variance s_i² = ln(1 + 2/ν_i), so
    that E X = 1 and var X ≈ 2/ν, right-skewed as a χ²), ν_i the Greenhall EDF of the dominant term
    and the correlation across τ of :func:`sigmatau.imu.fitting._correlation`. No time series: a
    draw costs nothing, and the fit's own model of its points holds by construction."""
    from sigmatau.imu import from_curve
    from sigmatau.imu.fitting import _correlation
    from sigmatau.imu.terms import _ALPHA, _design
    from sigmatau.uncertainty.confidence import edf_array

    n = int(GRID_DURATION * GRID_RATE)
    taus = 2.0 ** np.arange(18) / GRID_RATE
    c = np.array([truth.get(t, 0.0) ** 2 for t in "QNBKR"])
    parts = _design(taus, GRID_RATE) * c
    alpha = np.array([_ALPHA["QNBKR"[k]] for k in np.argmax(parts, axis=1)])
    nu = np.asarray(edf_array("oadev", alpha, np.round(taus * GRID_RATE).astype(np.int64), n + 1), float)
    s = np.sqrt(np.log1p(2.0 / nu))
    chol = np.linalg.cholesky(_correlation(taus, alpha))
    for _ in range(draws):
        x = np.exp(s * (chol @ rng.standard_normal(taus.size)) - 0.5 * s * s)
        yield from_curve(taus, np.sqrt(parts.sum(axis=1) * x), rate=GRID_RATE, n_samples=n)


@pytest.mark.slow
def test_dropped_k_bound_holds_given_the_drop_fast(rng):
    """The upper bound printed for a K that the term selection dropped holds at its nominal rate
    (84.1 %, the upper end of the 68.3 % interval) among the runs that drop it: N+B+K+R, whose K
    sits at the detection limit (dropped in about half the runs), on 100 curves drawn from the
    points' own model (``_copula_curves``). The count of bounds that hold is binomial; accepted:
    within 3.29 sd (two-sided 0.1 %) of 84.1 %.

    Before the selection-aware bound: 26 of 46 held (56.5 %; after: 41 of 46): K is dropped
    exactly when it came out low, and a bound built from its estimate as if it had not been
    selected is too low in those runs."""
    truth = GRID["N+B+K+R"]
    held = []
    for curve in _copula_curves(truth, rng, 100):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ImuWarning)
            k = analyze(curve, unit="rad/s").K
        if not k.resolved:
            held.append(truth["K"] <= k.high)
    p0, n = _nominal("bound"), len(held)
    sd = math.sqrt(p0 * (1 - p0) / n)
    print(f"dropped K's bound held in {sum(held)}/{n} runs ({100 * sum(held) / n:.1f} %, nominal {100 * p0:.1f} %)")
    assert n >= 30, n
    assert abs(sum(held) / n - p0) <= 3.29 * sd, (sum(held), n)


@pytest.mark.slow
def test_kept_k_interval_covers_given_the_keep(rng):
    """The interval printed for a K that the term selection kept covers at its nominal rate (68.3 %)
    among the runs that keep it, and its value is not biased up by the selection: N+B+K+R, K at the
    detection limit (kept in about half the runs), on 300 curves drawn from the points' own model
    (``_copula_curves``). The count is binomial; accepted within 3.29 sd (two-sided 0.1 %) of
    68.3 %, and the median of value/truth within 0.9–1.1.

    Measured on these draws: 120 of 175 kept runs covered (68.6 %), value/truth 0.961 at the
    median (120 of 173 and 1.025 with the dominant noise's EDF at every τ, before the white
    mixture EDF moved the draws' N-dominated points). Before the selection-aware intervals
    (ĉ ± zσ_c of the unconstrained fit, widened to hold the selected model's value): 137 of
    173 (79.2 %), and the value (the selected model's) 1.277× the truth at the median, which
    fails the test: K is kept exactly when it came out high."""
    truth = GRID["N+B+K+R"]
    held, ratio = [], []
    for curve in _copula_curves(truth, rng, 300):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ImuWarning)
            k = analyze(curve, unit="rad/s").K
        if k.resolved:
            held.append(k.low <= truth["K"] <= k.high)
            ratio.append(k.value / truth["K"])
    p0, n = _nominal("interval"), len(held)
    sd = math.sqrt(p0 * (1 - p0) / n)
    print(f"kept K's interval covered in {sum(held)}/{n} runs ({100 * sum(held) / n:.1f} %, nominal"
          f" {100 * p0:.1f} %); value/truth median {np.median(ratio):.3f}")
    assert n >= 60, n
    assert abs(sum(held) / n - p0) <= 3.29 * sd, (sum(held), n)
    assert 0.9 <= np.median(ratio) <= 1.1, np.median(ratio)


#: Statements known not to hold at their nominal rate within the band of ``test_grid_coverage``
#: (seeds 60 000 … 60 199), per configuration: (term, method, kind) → measured (held, of). All
#: are read-off bounds, and all over-cover: the bound rule bounds the whole curve, and the term is
#: only a share of it at every τ (K and R sharing the end, B under N and K), so the bound holds in
#: nearly every run. Made a bound on the term itself, it would be the fit's bound again. And the
#: fit's bound of a dropped R in N+K+R over-covers (96 %): the simulated R is a deterministic ramp,
#: whose share of the long-τ points does not scatter, while the fit's error model (and the spread
#: of the selection-aware bound) treats every share as noise.
KNOWN_OPEN = {
    "N+B+K": {("K", "readoff", "bound"): (198, 200)},
    "N+K+R": {("R", "readoff", "bound"): (200, 200), ("R", "fit", "bound"): (117, 122)},
    "N+B+K+R": {("B", "readoff", "bound"): (106, 106), ("K", "readoff", "bound"): (192, 192),
                ("R", "readoff", "bound"): (200, 200)},
}


@pytest.mark.slow
@pytest.mark.parametrize("config", list(GRID))
def test_grid_coverage(config):
    """Every printed statement, of the fit and of the read-offs, per term, over 200
    seeds: intervals cover, and bounds hold, at their nominal rates within ±5 points
    plus three binomial standard errors of the count (a class with fewer than 30
    members is reported, not tested).

    Measured at commit time (seeds 60 000 … 60 199): every fit statement is in the
    band; the bound of a K the selection dropped holds in 89 of 101 runs in N+B+K+R
    (88.1 %; 69 of 101 before the selection-aware bound) and 115 of 134 in N+B+K
    (85.8 %; 97 of 135 before), a dropped R's in 132 of 146 (90.4 %; 136 of 147 before).
    The interval of a kept K covers in 48 of 66 (N+B+K, 72.7 %), 76 of 99 (N+B+K+R,
    76.8 %) and 146 of 198 runs (N+K+R, 73.7 %), a kept R's in 50 of 78 (N+K+R, 64.1 %)
    and 33 of 54 (N+B+K+R, 61.1 %), with the selection-aware intervals; 76.9/84.8/82.3 %
    and 85.9/73.6 % before them (ĉ ± zσ_c widened to hold the selected model's value). On
    200 other seeds (61 000 … 61 199): kept K 73.0/69.8/78.2 %, kept R 67.2/70.5 %
    (82.3/83.2/87.8 % and 79.0/80.3 % before). N's intervals cover in 75.5, 74.5, 75.5,
    73.0 and 74.5 % (Q+N, N+B, N+B+K, N+K+R, N+B+K+R; 67.5, 69.0, 70.0, 67.0 and 68.5 % on
    the other seeds) with the exact EDF of the white PM + white FM mixture where Q and N
    hold the variance (``extraction._white_edf``); 82.5, 75.5, 77.0, 76.0 and 76.5 % with
    the dominant noise's EDF. Six classes stay more than 5 points off (``KNOWN_OPEN``, all
    over-covering); the test asserts that no other statement fails and that each known one
    is still more than 5 points off its nominal rate, so a new failure, or a known one
    fixed, both fail it. Also more than 5 points off but inside the band: the B read-off
    with K and R (55 of 94, 58.5 %; 75.3 % on the other seeds), the K read-off in N+K+R
    (151 of 193, 78.2 %; 87.2 % on the other seeds, outside the band there), the kept K in
    N+B+K+R and N+K+R, the kept R in N+B+K+R, and N except in N+K+R (74.5–75.5 %). Their
    causes, measured on these seeds with the fit re-run on cached curves (stops 24–26): the
    B read-off's flat region is found when B came out high (read over 41–164 s in all of
    600 runs: 65.0 %; 59.8 % where a region is found, 69.2 % where none is); N's σ was
    6–8 % above the sd of its 200 estimates here (before the mixture EDF; that sd is
    known to 5 %), and the widening to the selected model's value adds about 2 points;
    the kept K of N+K+R over-covers with the simulated ramp, which is
    deterministic (on curves drawn from the fit's own model of its points it covers in
    69 %). The model of the points' correlation across τ is not the cause: the measured
    correlation matrix moves every class by at most 1.5 points."""
    runs = 200
    table: dict = {}
    for seed in range(runs):
        for t, method, kind, holds in _statements(config, 60_000 + seed):
            n, k = table.get((t, method, kind), (0, 0))
            table[(t, method, kind)] = (n + 1, k + holds)
    failures = []
    for (t, method, kind), (n, k) in sorted(table.items()):
        p0 = _nominal(kind)
        rate = k / n
        print(f"{config} {t} {method} {kind}: {k}/{n} = {100 * rate:.1f} % (nominal {100 * p0:.1f} %)")
        if n >= 30:
            se = math.sqrt(p0 * (1 - p0) / n)
            if abs(rate - p0) > 0.05 + 3 * se:
                failures.append((t, method, kind))
    known = KNOWN_OPEN.get(config, {})
    assert set(failures) <= set(known), (failures, known)
    for key, measured in known.items():
        # Still open: more than the ±5-point target off nominal. Once within, this entry goes.
        n, k = table[key]
        assert abs(k / n - _nominal(key[2])) > 0.05, (key, k, n, measured)


@pytest.mark.slow
def test_b_readoff_unbiased_between_n_and_k_fast():
    """The B read-off (flat region, σ/0.6643) between N and K is unbiased once the
    fitted neighbouring terms' share is subtracted from each point of its region.

    Before: the flat region's σ includes N²/τ and K²τ/3 and the read-off came out
    1.31× the truth (median of 60 runs; 4.7 % of its intervals covered). Tested:
    the median of ln(B̂/B) over the runs where a flat region exists is within three
    standard errors of 0, the standard error of a median being 1.2533·sd/√n.
    """
    truth = GRID["N+B+K"]
    logs = []
    for seed in range(20):
        y = simulate(duration=GRID_DURATION, rate=GRID_RATE, unit="rad/s", rng=70_000 + seed, **truth)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ImuWarning)
            m = analyze(y, rate=GRID_RATE, unit="rad/s", checks=False)
        if m.readoff["B"].resolved:
            logs.append(math.log(m.readoff["B"].value / truth["B"]))
    assert len(logs) >= 5, len(logs)
    logs = np.array(logs)
    se = 1.2533 * logs.std(ddof=1) / math.sqrt(logs.size)
    print(f"B read-off: {logs.size} runs, median ratio {math.exp(np.median(logs)):.3f}, se of ln {se:.3f}")
    assert abs(np.median(logs)) <= 3 * se, (np.median(logs), se)


@pytest.mark.slow
def test_n_interval_matches_its_scatter_beside_q():
    """Beside quantisation (the grid's Q+N), N's interval is as wide as N's scatter: over 200 seeds
    (62 000 … 62 199, not the grid's) the mean half-width of the printed 68.3 % interval, divided by
    the standard deviation of the printed value, lies within [0.85, 1.15] (the sd of 200 values is
    known to 5 %: the band is 3 of its standard errors), and the intervals cover within ±5 points plus
    three binomial standard errors of 68.3 %.

    Before the white-mixture EDF (``extraction._white_edf``) the ratio was 1.35 and the coverage
    82.5 % on the grid's seeds: the EDF of the dominant noise at each τ understated the scatter of
    points where Q and N share the variance."""
    truth = GRID["Q+N"]
    values, halves, held = [], [], 0
    for seed in range(62_000, 62_200):
        y = simulate(duration=GRID_DURATION, rate=GRID_RATE, unit="rad/s", rng=seed, **truth)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ImuWarning)
            n = analyze(y, rate=GRID_RATE, unit="rad/s", checks=False).N
        values.append(n.value)
        halves.append(0.5 * (n.high - n.low))
        held += n.low <= truth["N"] <= n.high
    ratio = float(np.mean(halves) / np.std(values, ddof=1))
    rate = held / len(values)
    print(f"N beside Q: half-width / scatter {ratio:.3f}; coverage {held}/{len(values)} = {100 * rate:.1f} %")
    assert 0.85 <= ratio <= 1.15, ratio
    assert abs(rate - 0.683) <= 0.05 + 3 * math.sqrt(0.683 * 0.317 / len(values)), rate
