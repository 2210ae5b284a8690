"""Warm-up: detect the settling of the bias after power-on, estimate it, and cut it off.

:func:`warmup` fits ``b(t) = b∞ + A·exp(−t/T)`` to block means of a rate record (block
lengths growing geometrically from the start, so that a fast transient is resolved and a
slow one is not drowned in noise), under a noise model of white block means plus a
random-walk bias (Kalman-whitened, its ratio by REML), tests the exponential against a
constant with a test that accounts for T being undefined under the constant (Davies'
bound), and, when the transient is significant, returns the record from the end of the
warm-up.
:func:`drop_warmup` cuts a duration given by the caller (the CLI's ``--warmup SECONDS``).

The fit is separable (linear in b∞ and A for a fixed T): the residual sum of squares is
profiled over a logarithmic grid of T and polished by a bounded scalar search (variable
projection); every block mean of ``exp(−t/T)`` is summed exactly, as geometric series over
the gap-free runs of each block.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.special import fdtrc

from ..errors import DataError, ParameterError, caller_stacklevel
from ..core.validate import as_series
from ._common import count_valid, rate_of, series
from ._edit import part
from ._result import Estimate, PrepResult, PrepWarning

__all__ = ["warmup", "drop_warmup"]

#: Fewest blocks (with at least one valid sample) the test and the fit are made on.
_MIN_BLOCKS = 30
#: The block length at the end of the record is 1/_TAIL_BLOCKS of it; the first is 1/100 of that.
_TAIL_BLOCKS = 200
_GROWTH = 1.1
_GRID = 160
#: The slowest time constant considered, as a share of the record: a slower transient does not
#: settle within the record and cannot be told from a drift.
_T_MAX_SHARE = 1.0 / 3.0

END_RULE = ("end of warm-up: t_end = T·ln(|A|/σ_b), where the transient |A|·exp(−t/T) falls to the"
            " standard error σ_b of the settled bias b∞ (0 when |A| ≤ σ_b)")


@dataclass(frozen=True)
class _Design:
    """The blocks of a record and the gap-free pieces of each (for exact block means)."""

    starts: np.ndarray   # first index of each gap-free piece of a block
    lengths: np.ndarray  # its length (samples)
    block: np.ndarray    # the block it belongs to, renumbered over the blocks kept
    counts: np.ndarray   # valid samples per kept block
    edges: np.ndarray    # block edges (sample indices), all blocks
    used: np.ndarray     # the blocks kept (with a valid sample)
    tau0: float


def _block_edges(n: int) -> np.ndarray:
    """Edges ``0 = e_0 < e_1 < … = n``: lengths grow by 10 % from ``m_max/100`` up to ``m_max = n/200``."""
    m_max = max(1, n // _TAIL_BLOCKS)
    size = max(1.0, m_max / 100.0)
    edges = [0]
    while edges[-1] < n:
        edges.append(min(n, edges[-1] + min(m_max, int(round(size)))))
        size *= _GROWTH
    return np.asarray(edges, dtype=np.int64)


def _design(valid: np.ndarray, tau0: float) -> _Design:
    edges = _block_edges(valid.size)
    change = np.flatnonzero(np.diff(valid.astype(np.int8))) + 1
    cuts = np.union1d(edges, change)
    starts, lengths = cuts[:-1], np.diff(cuts)
    keep = valid[starts]
    starts, lengths = starts[keep], lengths[keep]
    block = np.searchsorted(edges, starts, side="right") - 1
    counts_all = np.bincount(block, weights=lengths, minlength=edges.size - 1)
    used = np.flatnonzero(counts_all > 0)
    renumber = np.full(edges.size - 1, -1)
    renumber[used] = np.arange(used.size)
    return _Design(starts, lengths, renumber[block], counts_all[used], edges, used, tau0)


def _block_means_of(d: _Design, v: np.ndarray, ref: float) -> np.ndarray:
    """Block means of ``v − ref`` over the design's segments (runs of valid samples, so no gap
    inside one): one pass of ``numpy.add.reduceat`` over the samples, no record-sized temporary."""
    ends = d.starts + d.lengths
    idx = np.empty(2 * d.starts.size, dtype=np.int64)
    idx[0::2], idx[1::2] = d.starts, ends
    if idx[-1] == v.size:  # reduceat takes the last run to the end by itself
        idx = idx[:-1]
    seg = np.add.reduceat(v, idx)[0::2] - ref * d.lengths
    return np.bincount(d.block, weights=seg, minlength=d.counts.size) / d.counts


def _exp_means(d: _Design, taus: np.ndarray) -> np.ndarray:
    """``g_k(T) = mean over block k's valid samples of exp(−t_i/T)``, one row per T (exact sums)."""
    taus = np.atleast_1d(taus)[:, None]
    r = d.tau0 / taus
    # Σ_{j<L} e^{−(s+j)τ0/T} = e^{−sτ0/T}·(1 − e^{−Lτ0/T})/(1 − e^{−τ0/T})
    seg = np.exp(-d.starts * r) * np.expm1(-d.lengths * r) / np.expm1(-r)
    out = np.empty((taus.shape[0], d.counts.size))
    for j in range(taus.shape[0]):
        out[j] = np.bincount(d.block, weights=seg[j], minlength=d.counts.size)
    return out / d.counts


class _Noise:
    """White block means plus a random-walk bias (a local-level model), whitened by a Kalman filter.

    ``ȳ_k = c + x_k + ε_k``, ``Var ε_k ∝ 1/m_k + ρ·(L_k² − 1)/(12 L_k)`` (white noise, and the
    random walk's spread within the block), ``x_k = x_{k−1} + η_k``, ``Var η_k ∝ ρ·Δ_k`` with Δ_k the
    spacing of the block centres in samples (``x`` starts at 0 at power-on; its level is the
    constant c). :meth:`white` returns the standardised innovations, ``Cov = σ²·I`` under the model.
    """

    def __init__(self, d: _Design, rho: float):
        self.rho = rho
        a = d.edges[d.used].astype(np.float64)
        length = (d.edges[d.used + 1] - d.edges[d.used]).astype(np.float64)
        centre = a + 0.5 * (length - 1.0)
        scale = float(np.min(d.counts))  # white variance of the longest block mean is 1/scale·…
        obs = scale / d.counts + rho * (length ** 2 - 1.0) / (12.0 * length) / centre[-1]
        step = rho * np.diff(np.concatenate(([0.0], centre))) / centre[-1]
        k = d.counts.size
        self.f = np.empty(k)
        self.gain = np.empty(k)
        p = 0.0
        for i in range(k):
            p += step[i]
            self.f[i] = p + obs[i]
            self.gain[i] = p / self.f[i]
            p *= 1.0 - self.gain[i]
        self.sqrt_f = np.sqrt(self.f)
        self.log_det = float(np.sum(np.log(self.f)))

    def white(self, x: np.ndarray) -> np.ndarray:
        z = np.asarray(x, dtype=np.float64)
        out = np.empty_like(z)
        state = np.zeros(z.shape[1:])
        for i in range(z.shape[0]):
            innov = z[i] - state
            out[i] = innov / self.sqrt_f[i]
            state = state + self.gain[i] * innov
        return out


def _reml(x: np.ndarray, ybar: np.ndarray, d: _Design) -> float:
    """The ratio ρ maximising the restricted (REML) likelihood, on a logarithmic grid with 0."""
    best, best_val = 0.0, math.inf
    k, p = x.shape
    for rho in np.concatenate(([0.0], np.geomspace(1e-6, 1e6, 37))):
        nz = _Noise(d, float(rho))
        q, r = np.linalg.qr(nz.white(x))
        yw = nz.white(ybar)
        res = yw - q @ (q.T @ yw)
        s2 = float(res @ res) / (k - p)
        if s2 <= 0:
            return 0.0
        val = (k - p) * math.log(s2) + nz.log_det + 2.0 * float(np.sum(np.log(np.abs(np.diag(r)))))
        if val < best_val:
            best, best_val = float(rho), val
    return best


def _profile(gw: np.ndarray, yw: np.ndarray, onew: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Whitened regression of ``ȳ`` on ``[1, g(T)]`` per column of ``gw``: RSS(T), unit regressors, RSS₀."""
    u = onew / np.linalg.norm(onew)
    yc = yw - u * (u @ yw)
    z = gw - np.outer(u, u @ gw)
    sxx = np.einsum("ij,ij->j", z, z)
    sxy = yc @ z
    rss0 = float(yc @ yc)
    with np.errstate(divide="ignore", invalid="ignore"):
        gain = np.where(sxx > 0, sxy ** 2 / sxx, 0.0)
        e = np.where(sxx > 0, z / np.sqrt(sxx), 0.0)
    return rss0 - gain, e.T, rss0


def _fit(d: _Design, nz: _Noise, ybar: np.ndarray, grid: np.ndarray
         ) -> tuple[float, int, np.ndarray, float, float, np.ndarray]:
    """Profile over the grid and polish T; return T, its grid index, (b∞, A), RSS, RSS₀, unit regressors."""
    yw, onew = nz.white(ybar), nz.white(np.ones_like(ybar))
    rss_grid, e, rss0 = _profile(nz.white(_exp_means(d, grid).T), yw, onew)
    j = int(np.argmin(rss_grid))
    lo, hi = math.log(grid[max(j - 1, 0)]), math.log(grid[min(j + 1, grid.size - 1)])

    def rss_at(s: float) -> float:
        return float(_profile(nz.white(_exp_means(d, np.array([math.exp(s)])).T), yw, onew)[0][0])

    from scipy.optimize import minimize_scalar  # on first use: import sigmatau stays light

    sol = minimize_scalar(rss_at, bounds=(lo, hi), method="bounded", options={"xatol": 1e-6})
    tau = math.exp(sol.x) if sol.fun <= rss_grid[j] else float(grid[j])
    gw = nz.white(_exp_means(d, np.array([tau]))[0])
    coef, *_ = np.linalg.lstsq(np.column_stack([onew, gw]), yw, rcond=None)
    r = yw - coef[0] * onew - coef[1] * gw
    return tau, j, coef, float(r @ r), rss0, e


def _p_value(u: float, nu: int, arc: float) -> float:
    """Davies' upper bound on P(sup_T F(T) > u) for the F (squared t) process with ν d.o.f."""
    if not math.isfinite(u):
        return 0.0
    tail = float(fdtrc(1, nu, u))  # the F(1, ν) survival function
    crossings = arc / math.pi * (1.0 + u / nu) ** (-(nu - 1) / 2.0)
    return min(1.0, tail + crossings)


def _check_alpha(alpha: object) -> float:
    if isinstance(alpha, (bool, np.bool_)) or not isinstance(alpha, (int, float, np.integer, np.floating)):
        raise ParameterError(f"alpha={alpha!r} must be a number in (0, 1)")
    a = float(alpha)
    if not 0.0 < a < 1.0:
        raise ParameterError(f"alpha={alpha!r} must lie in (0, 1)")
    return a


def warmup(data: object, *, rate: float, alpha: float = 0.01) -> PrepResult:
    r"""Detect the warm-up transient of a rate record, estimate it, and cut it off.

    Parameters
    ----------
    data : array_like
        Rate samples (gyro °/s, accelerometer m/s², or fractional frequency) from power-on:
        sample i at ``t_i = i/rate``. NaN marks a gap. Not modified.
    rate : float
        Sample rate in Hz.
    alpha : float
        False-alarm probability of the test for a transient (default 1 %).

    Returns
    -------
    PrepResult
        ``data``: the record from the end of the warm-up (the whole record when none is
        detected or it does not settle within the record); ``indices``: the samples left out;
        ``estimates``: ``time_constant`` T (s), ``amplitude`` A and ``settled_bias`` b∞ (data
        unit), ``end`` (s), each ± standard error (the best fit is reported even when it is
        not significant); ``details``: ``detected``, ``p_value``, ``statistic``,
        ``end_index``, ``end_time``, ``settled``, the block design and the T range searched.

    Raises
    ------
    ParameterError
        A bad rate or alpha.
    DataError
        Not numeric or 1-D, all NaN, or fewer than 30 blocks with a valid sample (too short).

    Notes
    -----
    **Model.** ``y_i = b∞ + A·exp(−t_i/T) + n_i``. Block means ``ȳ_k`` over blocks of ``m_k``
    valid samples are fitted by generalised least squares with the model's own block means
    ``b∞ + A·g_k(T)``, ``g_k(T) = ⟨exp(−t_i/T)⟩_k`` summed exactly, so blocks need not be short
    against T. Block lengths grow by 10 % from ``n/20000`` samples up to ``n/200`` (then stay
    there), so a transient from about one first-block length to a third of the record is
    resolved with a few hundred blocks. T is searched on ``[τ_first block, duration/3]``.

    **Noise.** The block means are white (variance ∝ ``1/m_k``) plus a random-walk bias
    (a local-level model: ``ȳ_k = b∞ + A·g_k + x_k + ε_k``, ``x_k`` a random walk with
    variance ∝ ρ·elapsed time), whitened by its Kalman filter. The ratio ρ is estimated by
    restricted maximum likelihood (REML, on a logarithmic grid that includes 0) with a
    first, white-noise fit of the transient regressed out, so that a real warm-up is not
    taken for bias wander. ρ = 0 for white noise; flicker and random-walk bias get ρ > 0,
    which keeps their slow wander from being reported as a warm-up. Standard errors are
    ``s²(J̃ᵀJ̃)⁻¹`` with J̃ the whitened Jacobian at the optimum and ``s² = RSS/(K − 3)``
    over K blocks (Wald, linearised).

    **Test.** For a fixed T the exponential adds one regressor, and
    ``F(T) = (RSS₀ − RSS(T))/(RSS(T)/ν)``, ``ν = K − 2`` (whitened), is F(1, ν) under a
    constant bias. T is not defined under the constant, so the statistic is
    ``F̂ = sup_T F(T)`` and its p-value is Davies' bound
    ``P(F̂ > u) ≤ P(F(1, ν) > u) + (V/π)(1 + u/ν)^{−(ν−1)/2}``, where V is the arc length, over
    the T range, of the unit vector of the whitened regressor ``g(T)`` with the constant
    projected out (the expected number of up-crossings of the t-process). The bound makes
    the false-alarm rate at most ``alpha`` under the noise model, and close to it.

    **End of the warm-up.** ``t_end = T·ln(|A|/σ_b)``: the time at which the transient
    ``|A|·exp(−t/T)`` has fallen to the standard error σ_b of the settled bias b∞ (0 when
    ``|A| ≤ σ_b``); what is left after it is below what the record can resolve. Its
    standard error follows by the delta method from those of A and T. The first sample kept
    is ``⌈t_end·rate⌉``. ``details["five_T"]`` gives the 5T rule of thumb for comparison.
    Nothing is cut (and a :class:`PrepWarning` says why) when the transient is not
    significant, when T reaches the slow end of the range (a drift cannot be told from a
    warm-up that slow), or when ``t_end`` lies beyond the record.

    References
    ----------
    R. B. Davies, "Hypothesis testing when a nuisance parameter is present only under the
    alternative", Biometrika 74 (1987) 33–43 (the bound; the t-process form is its ν-d.o.f.
    version); K. J. Worsley, "Local maxima and the expected Euler characteristic of excursion
    sets of χ², F and t fields", Adv. Appl. Probab. 26 (1994) 13–42 (the t-process crossing
    density). G. H. Golub and V. Pereyra, "The differentiation of pseudo-inverses and
    nonlinear least squares problems whose variables separate", SIAM J. Numer. Anal. 10
    (1973) 413–432 (variable projection). D. M. Bates and D. G. Watts, *Nonlinear
    Regression Analysis and Its Applications*, Wiley (1988), ch. 2 (linearised standard
    errors). H. D. Patterson and R. Thompson, "Recovery of inter-block information when block
    sizes are unequal", Biometrika 58 (1971) 545–554 (REML). A. C. Harvey, *Forecasting,
    Structural Time Series Models and the Kalman Filter*, CUP (1989) (the local-level model).

    Examples
    --------
    >>> import numpy as np
    >>> from sigmatau.prep import warmup
    >>> t = np.arange(60000) / 100.0
    >>> y = 0.2 * np.exp(-t / 30.0) + np.random.default_rng(1).normal(0.0, 0.05, t.size)
    >>> r = warmup(y, rate=100.0)
    >>> r.details["detected"], round(r.estimates["time_constant"].value)
    (True, 30)
    """
    v = as_series(data, "data", gaps=True)  # read only: the part kept is copied by _result
    rate_f = rate_of(rate)
    alpha_f = _check_alpha(alpha)
    tau0 = 1.0 / rate_f
    valid = ~np.isnan(v)
    d = _design(valid, tau0)
    if d.counts.size < _MIN_BLOCKS:
        raise DataError(f"warmup: the record is too short ({count_valid(v)} valid samples give"
                        f" {d.counts.size} blocks; at least {_MIN_BLOCKS} are needed)")
    # any central value conditions the sums; the median of at most ~10^5 evenly spread samples
    ref = float(np.nanmedian(v[:: max(1, v.size // 100_000)]))
    ybar = _block_means_of(d, v, ref)
    # The fit runs on the block means scaled by an exact power of two into [0.5, 1) (their
    # squares and the whitened products cannot overflow or underflow at 1e±200): A, b∞, the RSS
    # and the covariance are scaled back below; T, the test and the noise ratio are scale free.
    peak = float(np.max(np.abs(ybar))) if ybar.size else 0.0
    shift = math.frexp(peak)[1] if peak > 0 and math.isfinite(peak) else 0
    ybar = np.ldexp(ybar, -shift)
    t_lo = float(d.edges[1]) * tau0
    t_hi = max(v.size * tau0 * _T_MAX_SHARE, 2.0 * t_lo)
    grid = np.geomspace(t_lo, t_hi, _GRID)
    # Pass 1 (white) gives a first T; the noise model is estimated with that transient regressed
    # out, so that a real warm-up is not taken for bias wander; pass 2 fits and tests under it.
    tau, *_ = _fit(d, _Noise(d, 0.0), ybar, grid)
    x = np.column_stack([np.ones_like(ybar), _exp_means(d, np.array([tau]))[0]])
    nz = _Noise(d, _reml(x, ybar, d))
    tau, j, (b_inf, amp), rss, rss0, e = _fit(d, nz, ybar, grid)
    arc = float(np.sum(np.linalg.norm(np.diff(e, axis=0), axis=1)))
    k = d.counts.size
    if rss0 <= 0.0:  # a constant record: nothing to detect
        u, p = 0.0, 1.0
    else:
        u = (rss0 - rss) / (rss / (k - 2)) if rss > 0 else math.inf
        p = _p_value(u, k - 2, arc)
    cov = _covariance(d, nz, tau, amp, rss, k)
    extra = {"noise_model": "white + random-walk bias (REML)", "random_walk_ratio": nz.rho}
    return _result(v, rate_f, alpha_f, d, tau, amp, b_inf, cov, u, p, (t_lo, t_hi), j, arc, extra,
                   shift=shift, ref=ref)


def _covariance(d: _Design, nz: _Noise, tau: float, amp: float, rss: float, k: int) -> np.ndarray:
    """``s²(J̃ᵀJ̃)⁻¹`` of (b∞, A, T) with J̃ the whitened Jacobian, ``s² = RSS/(K − 3)``."""
    h = 1e-4
    g, g_up, g_dn = _exp_means(d, np.array([tau, tau * (1 + h), tau * (1 - h)]))
    jac = nz.white(np.column_stack([np.ones_like(g), g, amp * (g_up - g_dn) / (2.0 * h * tau)]))
    s2 = rss / max(k - 3, 1)
    try:
        return s2 * np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        return np.full((3, 3), np.inf)


def _se(cov: np.ndarray, i: int) -> float:
    c = cov[i, i]
    return float(math.sqrt(c)) if np.isfinite(c) and c >= 0 else math.inf


def _result(v: np.ndarray, rate: float, alpha: float, d: _Design, tau: float, amp: float, b_inf: float,
            cov: np.ndarray, u: float, p: float, t_range: tuple[float, float], j: int, arc: float,
            extra: dict[str, object], *, shift: int = 0, ref: float = 0.0) -> PrepResult:
    """Decide, place the end, cut, and write the record.

    ``amp``, ``b_inf`` and ``cov`` are those of the fit on the block means less ``ref`` scaled by
    2**-shift: the decision is scale free; the estimates are reported in the data's unit.
    """
    n = v.size
    duration = n / rate
    detected = p < alpha
    se_b, se_a, se_t = _se(cov, 0), _se(cov, 1), _se(cov, 2)
    floor = max(se_b, 1e-12 * max(abs(amp), abs(b_inf), 1e-300))
    if detected and abs(amp) > floor:
        ratio = math.log(abs(amp) / floor)
        t_end = tau * ratio
        grad = np.array([0.0, tau / amp, ratio])
        se_end = float(math.sqrt(max(grad @ cov @ grad, 0.0))) if np.isfinite(cov).all() else math.inf
    else:
        t_end, se_end = 0.0, 0.0
    end_index = int(math.ceil(t_end * rate - 1e-9)) if t_end > 0 else 0
    at_bound = "slowest" if j == _GRID - 1 else "fastest" if j == 0 else None
    # A transient at the slow end of the range is not resolved from a drift: nothing is cut.
    settled = end_index < n and at_bound != "slowest"
    notes = []
    if not detected:
        notes.append(f"no warm-up detected (p = {p:.3g} ≥ alpha = {alpha:g}); the record is kept whole")
    elif at_bound == "slowest":
        what = "as slow as the record allows: it may be a drift rather than a warm-up; nothing is cut"
        notes.append(f"the fitted transient (T = {tau:.4g} s) is {what}")
        warnings.warn(f"warmup: the fitted transient (T = {tau:.4g} s) is {what}", PrepWarning,
                      stacklevel=caller_stacklevel())
    elif not settled:
        notes.append(f"warm-up detected (T = {tau:.4g} s) but it does not settle within the record"
                     f" (end {t_end:.4g} s > {duration:.4g} s); the record is kept whole")
        warnings.warn(f"warmup: the transient (T = {tau:.4g} s) does not settle within the record"
                      f" ({t_end:.4g} s needed, {duration:.4g} s recorded); nothing is cut",
                      PrepWarning, stacklevel=caller_stacklevel())
    else:
        notes.append(f"warm-up detected (p = {p:.2g}): T = {tau:.4g} ± {se_t:.2g} s, A = {math.ldexp(amp, shift):.4g}"
                     f" ± {math.ldexp(se_a, shift):.2g}; the record is analysed from {end_index / rate:.6g} s"
                     f" (sample {end_index}, {end_index} of {n} samples left out)")
        if at_bound == "fastest":
            notes.append("the time constant is faster than the first block: T is not resolved")
            warnings.warn("warmup: the fitted transient is faster than the first block: T is not resolved",
                          PrepWarning, stacklevel=caller_stacklevel())
    cut = end_index if (detected and settled) else 0
    out = v[cut:].copy()
    if np.isnan(out).all():
        raise DataError("warmup: no valid sample is left after the end of the warm-up")
    out.flags.writeable = False
    def unscaled(value: float) -> float:
        return math.ldexp(value, shift) if math.isfinite(value) else value

    estimates = {"time_constant": Estimate(tau, se_t, "s"),
                 "amplitude": Estimate(unscaled(amp), unscaled(se_a), "data"),
                 "settled_bias": Estimate(unscaled(b_inf) + ref, unscaled(se_b), "data"),
                 "end": Estimate(t_end, se_end, "s")}
    details = {"detected": bool(detected), "p_value": p, "statistic": u, "settled": bool(settled),
               "end_index": cut if detected and settled else (None if detected else 0),
               "end_time": cut / rate if detected and settled else (None if detected else 0.0),
               "end_rule": END_RULE, "five_T": 5.0 * tau, "blocks": int(d.counts.size),
               "block_samples": [int(np.diff(d.edges).min()), int(np.diff(d.edges).max())],
               "time_constant_range": list(t_range), "time_constant_at_bound": at_bound,
               "arc_length": arc, "test": "sup-F over T with Davies' bound", "mode": "auto", **extra}
    return PrepResult(step="warmup", data=out, data_type="freq", parameters={"rate": rate, "alpha": alpha},
                      estimates=estimates, indices=np.arange(cut, dtype=np.int64), details=details,
                      notes=tuple(notes))


def drop_warmup(data: object, *, rate: float, seconds: float) -> PrepResult:
    """Cut a given warm-up duration from the start of a record (the CLI's ``--warmup SECONDS``).

    Parameters
    ----------
    data : array_like
        Samples from power-on, sample i at ``t_i = i/rate``; NaN marks a gap. Not modified.
    rate : float
        Sample rate in Hz.
    seconds : float
        The duration to cut, ≥ 0 and shorter than the record.

    Returns
    -------
    PrepResult
        Step ``"warmup"`` with ``details["mode"] == "given"``: ``data`` from the first sample
        at or after ``seconds`` (:func:`sigmatau.prep.part`'s rule, ``⌈seconds·rate⌉``),
        ``indices`` the samples left out.

    Raises
    ------
    ParameterError
        A bad rate, or ``seconds`` negative, not finite or not shorter than the record.
    DataError
        All NaN, or nothing valid left.

    Examples
    --------
    >>> from sigmatau.prep import drop_warmup
    >>> drop_warmup([5.0, 3.0, 1.0, 1.1, 0.9], rate=2.0, seconds=1.0).data.tolist()
    [1.0, 1.1, 0.9]
    """
    v = series(data)
    rate_f = rate_of(rate)
    if isinstance(seconds, (bool, np.bool_)) or not isinstance(seconds, (int, float, np.integer, np.floating)):
        raise ParameterError(f"seconds={seconds!r} must be a number of seconds")
    s = float(seconds)
    duration = v.size / rate_f
    if not (math.isfinite(s) and 0.0 <= s < duration):
        raise ParameterError(f"seconds={seconds!r} must be ≥ 0 and shorter than the record ({duration:g} s)")
    kept = part(v, start=s, rate=rate_f, unit="seconds")
    a = int(kept.details["range"][0])
    return PrepResult(step="warmup", data=kept.data, data_type="freq",
                      parameters={"rate": rate_f, "seconds": s},
                      indices=np.arange(a, dtype=np.int64),
                      details={"mode": "given", "end_index": a, "end_time": a / rate_f, "detected": None},
                      notes=(f"the first {s:g} s (samples 0 … {a - 1}) cut as warm-up, as given",)
                      if a else ("warm-up of 0 s given: nothing cut",))
