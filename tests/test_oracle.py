"""Every fast estimator against two plain definitions.

1. The design tip's filter chain (:mod:`sigmatau.filterchain`), on frequency data.
2. The SP 1065 sums over phase, written below straight from numerics.md §1.1–1.7
   with every index range spelled out (vectorised over the outer index only).

The three are algebraically identical, so they must agree to round-off;
``rtol = 1e-10`` catches any wrong index, term count or normalisation (those
change the value by at least about 1/N). Observed agreement: ≤ 3e-12 for the
Allan kinds, except OSTDVAR with two averages (ill-conditioned, 2.6e-11), and
≤ 6e-11 for the Hadamard kinds, except the known case marked below.

Data: seeded series of the tip's seven noise types (tests/_noise.py), many
record lengths (tiny, odd, prime, ~10^4) and averaging factors up to the
largest each estimator allows, as frequency and as phase input, at unit and
non-unit sample rates.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np
import pytest

import sigmatau
from sigmatau import filterchain as fc
from sigmatau.errors import DataError, ParameterError, RangeWarning

from _noise import NOISES

RTOL = 1e-10


# --- SP 1065 sums over phase x_0 … x_{N-1} (numerics.md §0, §1.1–1.7) ------------


def sp_stdvar(x: np.ndarray, m: int, tau0: float) -> float:
    """§1.1 non-overlapped: K = ⌊(N-1)/m⌋ averages ȳ_k = (x_{(k+1)m} − x_{km})/τ, ddof 1."""
    tau = m * tau0
    K = (x.size - 1) // m
    k = np.arange(K)
    ybar = (x[(k + 1) * m] - x[k * m]) / tau
    return float(np.sum((ybar - ybar.mean()) ** 2) / (K - 1))


def sp_ostdvar(x: np.ndarray, m: int, tau0: float) -> float:
    """§1.1 overlapped: M − m + 1 averages ā_j = (x_{j+m} − x_j)/τ, ddof 1."""
    tau = m * tau0
    M = x.size - 1
    j = np.arange(M - m + 1)
    abar = (x[j + m] - x[j]) / tau
    return float(np.sum((abar - abar.mean()) ** 2) / (M - m))


def sp_avar(x: np.ndarray, m: int, tau0: float) -> float:
    """§1.2: 1/(2τ²(K−1)) Σ_{k=0}^{K−2} (x_{(k+2)m} − 2x_{(k+1)m} + x_{km})²."""
    tau = m * tau0
    K = (x.size - 1) // m
    k = np.arange(K - 1)
    d2 = x[(k + 2) * m] - 2 * x[(k + 1) * m] + x[k * m]
    return float(np.sum(d2**2) / (2 * tau**2 * (K - 1)))


def sp_oavar(x: np.ndarray, m: int, tau0: float) -> float:
    """§1.3: 1/(2τ²(N−2m)) Σ_{i=0}^{N−2m−1} (x_{i+2m} − 2x_{i+m} + x_i)²."""
    tau = m * tau0
    N = x.size
    i = np.arange(N - 2 * m)
    d2 = x[i + 2 * m] - 2 * x[i + m] + x[i]
    return float(np.sum(d2**2) / (2 * tau**2 * (N - 2 * m)))


def sp_mvar(x: np.ndarray, m: int, tau0: float) -> float:
    """§1.4: 1/(2m²τ²(N−3m+1)) Σ_{j=0}^{N−3m} [Σ_{i=j}^{j+m−1} (x_{i+2m} − 2x_{i+m} + x_i)]²."""
    tau = m * tau0
    N = x.size
    i = np.arange(N - 2 * m)
    d2 = x[i + 2 * m] - 2 * x[i + m] + x[i]
    # Row j of the window view holds d2_j … d2_{j+m-1}, for j = 0 … N-3m.
    inner = np.lib.stride_tricks.sliding_window_view(d2, m).sum(axis=1)
    assert inner.size == N - 3 * m + 1
    return float(np.sum(inner**2) / (2 * m**2 * tau**2 * (N - 3 * m + 1)))


def sp_tvar(x: np.ndarray, m: int, tau0: float) -> float:
    """§1.5: TVAR = τ²/3 · MVAR."""
    return (m * tau0) ** 2 / 3 * sp_mvar(x, m, tau0)


def sp_hvar(x: np.ndarray, m: int, tau0: float) -> float:
    """§1.6: 1/(6τ²(K−2)) Σ_{k=0}^{K−3} (x_{(k+3)m} − 3x_{(k+2)m} + 3x_{(k+1)m} − x_{km})²."""
    tau = m * tau0
    K = (x.size - 1) // m
    k = np.arange(K - 2)
    d3 = x[(k + 3) * m] - 3 * x[(k + 2) * m] + 3 * x[(k + 1) * m] - x[k * m]
    return float(np.sum(d3**2) / (6 * tau**2 * (K - 2)))


def sp_ohvar(x: np.ndarray, m: int, tau0: float) -> float:
    """§1.7: 1/(6τ²(N−3m)) Σ_{i=0}^{N−3m−1} (x_{i+3m} − 3x_{i+2m} + 3x_{i+m} − x_i)²."""
    tau = m * tau0
    N = x.size
    i = np.arange(N - 3 * m)
    d3 = x[i + 3 * m] - 3 * x[i + 2 * m] + 3 * x[i + m] - x[i]
    return float(np.sum(d3**2) / (6 * tau**2 * (N - 3 * m)))


# --- the statistics under test ------------------------------------------------------


@dataclass(frozen=True)
class Spec:
    fast: Callable[..., sigmatau.StabilityResult]
    chain: Callable[..., float]
    sp1065: Callable[[np.ndarray, int, float], float]
    max_m: Callable[[int], int]  # largest m for N phase points (numerics.md §1)
    min_points: int  # fewest phase points
    stop: int  # Stable32 stop ratio: keyword grids end at ⌊N/stop⌋


SPECS = {
    "stdev": Spec(sigmatau.stdev, fc.stdvar, sp_stdvar, lambda n: (n - 1) // 2, 3, 5),
    "ostdev": Spec(sigmatau.ostdev, fc.ostdvar, sp_ostdvar, lambda n: n - 2, 3, 4),
    "adev": Spec(sigmatau.adev, fc.avar, sp_avar, lambda n: (n - 1) // 2, 3, 5),
    "oadev": Spec(sigmatau.oadev, fc.oavar, sp_oavar, lambda n: (n - 1) // 2, 3, 4),
    "mdev": Spec(sigmatau.mdev, fc.mvar, sp_mvar, lambda n: n // 3, 3, 4),
    "tdev": Spec(sigmatau.tdev, fc.tvar, sp_tvar, lambda n: n // 3, 3, 4),
    "hdev": Spec(sigmatau.hdev, fc.hvar, sp_hvar, lambda n: (n - 1) // 3, 4, 5),
    "ohdev": Spec(sigmatau.ohdev, fc.ohvar, sp_ohvar, lambda n: (n - 1) // 3, 4, 4),
}


def factors(spec: Spec, n_points: int) -> list[int]:
    """Averaging factors to test: all of them for short records, else a spread
    that includes primes, both sides of the default grid limit and the largest."""
    top = spec.max_m(n_points)
    if top <= 40:
        return list(range(1, top + 1))
    default = max(1, n_points // spec.stop)
    picks = {1, 2, 3, 4, 5, 7, 10, 13, 16, 31, 64, 97, top // 7, default, default + 1, top - 1, top}
    return sorted(m for m in picks if 1 <= m <= top)


def run_fast(name: str, data: np.ndarray, ms: list[int], *, n_points: int, **kwargs) -> np.ndarray:
    """Variances from the fast path; a RangeWarning must come exactly when some
    m is beyond the default grid limit, and no other warning at all."""
    spec = SPECS[name]
    beyond = [m for m in ms if m > max(1, n_points // spec.stop)]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = spec.fast(data, m=ms, **kwargs)
    categories = [w.category for w in caught]
    assert categories == ([RangeWarning] if beyond else []), [str(w.message) for w in caught]
    np.testing.assert_array_equal(result.m, ms)
    assert result.n_points == n_points
    return result.var


def series(noise: str, size: int, tag: int) -> np.ndarray:
    rng = np.random.default_rng([list(NOISES).index(noise), size, tag])
    return NOISES[noise](size, rng)


# Frequency-sample counts M (17, 101 prime); the tiny ones are added per statistic.
FREQ_SIZES = (4, 5, 16, 17, 100, 101)
# The long record: prime, ~10^4 samples.
LONG_SIZE = 10007
# Phase-point counts N for phase input (97 and 1009 prime, 18 even).
PHASE_SIZES = (5, 18, 97, 1009)

# The SP 1065 sums take differences of phase values that can be far larger than
# the differences (random-run FM at N = 10^4: phase ~4e8, third differences ~1),
# which costs float64 up to ~1e-9. They run in extended precision so that they
# stay a reference; where long double is plain double their tolerance is wider.
PHASE_DTYPE = np.longdouble
SUMS_RTOL = RTOL if np.finfo(PHASE_DTYPE).eps < 1e-18 else 1e-8



def tiny_sizes(spec: Spec) -> tuple[int, int]:
    """The two smallest frequency-sample counts the statistic accepts."""
    return spec.min_points - 1, spec.min_points


def to_phase_extended(y: np.ndarray, rate: float) -> np.ndarray:
    """x_0 = 0, x_{i+1} = x_i + τ0·y_i, accumulated in extended precision."""
    x = np.zeros(y.size + 1, dtype=PHASE_DTYPE)
    x[1:] = np.cumsum(y.astype(PHASE_DTYPE)) / PHASE_DTYPE(rate)
    return x


def check_all(name: str, var: np.ndarray, y: np.ndarray, x: np.ndarray, ms: list[int], rate: float) -> None:
    """``var`` (fast) against the chain on frequency ``y`` and the sums on phase ``x``."""
    spec = SPECS[name]
    chain = np.array([spec.chain(y, m, rate=rate) for m in ms])
    tau0 = 1 / PHASE_DTYPE(rate)
    sums = np.array([float(spec.sp1065(x.astype(PHASE_DTYPE), m, tau0)) for m in ms])
    np.testing.assert_allclose(var, chain, rtol=RTOL, atol=0, err_msg=f"{name} vs filter chain, m={ms}")
    np.testing.assert_allclose(var, sums, rtol=SUMS_RTOL, atol=0, err_msg=f"{name} vs SP1065 sums, m={ms}")


def cases(long: bool = False) -> list:
    return [pytest.param(name, noise, id=f"{name}-{noise}") for name in SPECS for noise in NOISES]


@pytest.mark.parametrize("rate", [1.0, 104.0])
@pytest.mark.parametrize(("name", "noise"), cases())
def test_frequency_input(name: str, noise: str, rate: float) -> None:
    spec = SPECS[name]
    for size in tiny_sizes(spec) + FREQ_SIZES:
        y = series(noise, size, 1)
        n_points = size + 1
        ms = factors(spec, n_points)
        var = run_fast(name, y, ms, n_points=n_points, rate=rate)
        check_all(name, var, y, to_phase_extended(y, rate), ms, rate)


@pytest.mark.parametrize(("name", "noise"), cases(long=True))
def test_frequency_input_long(name: str, noise: str) -> None:
    spec = SPECS[name]
    y = series(noise, LONG_SIZE, 1)
    ms = factors(spec, LONG_SIZE + 1)
    var = run_fast(name, y, ms, n_points=LONG_SIZE + 1, rate=1.0)
    check_all(name, var, y, to_phase_extended(y, 1.0), ms, 1.0)


@pytest.mark.parametrize("rate", [1.0, 0.25])
@pytest.mark.parametrize(("name", "noise"), cases())
def test_phase_input(name: str, noise: str, rate: float) -> None:
    spec = SPECS[name]
    for n_points in (spec.min_points, spec.min_points + 1) + PHASE_SIZES:
        # A phase record with an offset, as a time-interval counter gives it.
        x = 3.0 + sigmatau.frequency_to_phase(series(noise, n_points - 1, 2), rate=rate)
        ms = factors(spec, n_points)
        var = run_fast(name, x, ms, n_points=n_points, rate=rate, data_type="phase")
        # The chain sees the differences of the phase as given (rounded once).
        y = sigmatau.phase_to_frequency(x, rate=rate)
        check_all(name, var, y, x, ms, rate)


def check_offset(name: str, noise: str, size: int) -> None:
    """A gyro bias of 1e6 on unit noise leaves the fast path as exact as the data.

    The oracle runs on ``(1e6 + y) − 1e6``: that subtraction is exact (Sterbenz),
    so it is the offset-free content of the data as stored, already rounded to
    the 1.2e-10 spacing of floats near 1e6. Any further loss is the estimator's.
    """
    spec = SPECS[name]
    y_biased = 1e6 + series(noise, size, 3)
    y_clean = y_biased - 1e6
    ms = factors(spec, size + 1)
    var = run_fast(name, y_biased, ms, n_points=size + 1, rate=50.0)
    chain = np.array([spec.chain(y_clean, m, rate=50.0) for m in ms])
    np.testing.assert_allclose(var, chain, rtol=RTOL, atol=0)


@pytest.mark.parametrize(("name", "noise"), cases())
def test_large_offset_keeps_precision(name: str, noise: str) -> None:
    for size in (17, 101):
        check_offset(name, noise, size)


@pytest.mark.parametrize(("name", "noise"), cases(long=True))
def test_large_offset_keeps_precision_long(name: str, noise: str) -> None:
    check_offset(name, noise, LONG_SIZE)


@pytest.mark.parametrize("name", SPECS)
def test_same_limits(name: str) -> None:
    """Fast path and filter chain accept and refuse the same records and factors."""
    spec = SPECS[name]
    rng = np.random.default_rng(7)
    y_short = rng.standard_normal(spec.min_points - 2)
    with pytest.raises(DataError):
        spec.fast(y_short, m=1)
    with pytest.raises(DataError):
        spec.chain(y_short, 1)
    for size in (spec.min_points - 1, 30, 31, 32):
        y = rng.standard_normal(size)
        top = spec.max_m(size + 1)
        with pytest.raises(ParameterError):
            spec.fast(y, m=top + 1)
        with pytest.raises(DataError):
            spec.chain(y, top + 1)
        spec.chain(y, top)


def test_filter_chain_rejects_bad_factor() -> None:
    for bad in (0, -1, 1.5, True):
        with pytest.raises(ParameterError):
            fc.oavar([1.0, 2.0, 3.0], bad)


# --- the carried window sums behind the frequency kernels ------------------------------


def test_window_sums_follow_their_definition() -> None:
    """WindowSums reaches every w through doublings, unit steps and restarts; every
    route gives the plain sums A_w[j] = Σ y_j…y_{j+w-1} and B_w[j] = Σ A_w[j…j+w-1]."""
    from sigmatau.core.numeric import WindowSums

    rng = np.random.default_rng(11)
    y = rng.standard_normal(97)
    routes = [
        [1, 2, 4, 8, 16, 32],  # octave: one doubling each
        [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15],  # dense: unit steps, then restarts
        [10, 20, 40, 5, 3, 48, 47, 1],  # prefix extensions, decreasing, restarts
        [31, 32, 33, 30],
    ]
    for chunk in (None, 1, 4, 7):
        for route in routes:
            ws = WindowSums(y, double=True, chunk=chunk)
            for w in route:
                ws.advance(w)
                a = np.lib.stride_tricks.sliding_window_view(y, w).sum(axis=1)
                b = np.lib.stride_tricks.sliding_window_view(a, w).sum(axis=1)
                np.testing.assert_allclose(ws.a, a, rtol=1e-13, atol=1e-13, err_msg=f"A, {route=} {w=} {chunk=}")
                np.testing.assert_allclose(ws.b, b, rtol=1e-13, atol=1e-12, err_msg=f"B, {route=} {w=} {chunk=}")


GRIDS = {
    "octave": "octave",
    "decade": "decade",
    "all": "all",
    "log": "log",
}


@pytest.mark.parametrize("grid", GRIDS)
@pytest.mark.parametrize(("name", "noise"), cases())
def test_chunked_kernels_on_every_grid(name: str, noise: str, grid: str, monkeypatch) -> None:
    """Chunk boundaries everywhere (chunks of 5 samples) and every route through the
    carried sums (the grids of the τ keywords): still the filter chain to RTOL."""
    import sigmatau.core.numeric as numeric

    monkeypatch.setattr(numeric, "CHUNK", 5)
    spec = SPECS[name]
    y = series(noise, 257, 4)
    result = spec.fast(y, taus=GRIDS[grid], ci=None)
    chain = np.array([spec.chain(y, int(m)) for m in result.m])
    np.testing.assert_allclose(result.var, chain, rtol=RTOL, atol=0, err_msg=f"{name} {grid}")
    x = to_phase_extended(y, 1.0)
    sums = np.array([float(spec.sp1065(x, int(m), PHASE_DTYPE(1))) for m in result.m])
    np.testing.assert_allclose(result.var, sums, rtol=SUMS_RTOL, atol=0)
    # The phase kernels chunk their differences the same way.
    xp = 3.0 + sigmatau.frequency_to_phase(y)
    rp = spec.fast(xp, data_type="phase", taus=GRIDS[grid], ci=None)
    chain = np.array([spec.chain(sigmatau.phase_to_frequency(xp), int(m)) for m in rp.m])
    np.testing.assert_allclose(rp.var, chain, rtol=RTOL, atol=0, err_msg=f"{name} {grid} phase")
