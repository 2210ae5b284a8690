"""Temperature: fit the bias of a rate record against the sensor's temperature, and compensate it.

:func:`temperature_fit` fits a polynomial in temperature to block means (order chosen by
BIC), reports the coefficients and the temperature coefficient (tempco) at the mean
temperature with standard errors, and returns the record with the temperature-dependent
part of the bias removed.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..errors import DataError, ParameterError, caller_stacklevel
from ._bias_noise import MIN_DOF_COLOURED, BlockLayout, NoisePosterior, allan_levels, noise_posterior
from ._common import rate_of, series
from ._result import Estimate, PrepResult, PrepWarning

__all__ = ["temperature_fit"]

#: Blocks the record is cut into (uniform length ``n // _BLOCKS`` samples, at least 1).
_BLOCKS = 200
_MIN_BLOCKS = 5
#: The order under which the noise model for the order criterion is estimated. Measured on ramps:
#: under the cubic it loses the wander the extra terms absorb and the criterion over-fits (order 1
#: found on 82 of 100 random-walk ramps); under the linear model a real curvature is taken for noise
#: (a quadratic with all three noises found on 10 of 60); under the quadratic 54 and 48 of those 60.
_NOISE_ORDER = 2


def _check_order(max_order: object) -> int:
    if isinstance(max_order, (bool, np.bool_)) or not isinstance(max_order, (int, np.integer)):
        raise ParameterError(f"max_order={max_order!r} must be a whole number from 0 to 6")
    if not 0 <= int(max_order) <= 6:
        raise ParameterError(f"max_order={max_order!r} must lie from 0 to 6")
    return int(max_order)


def _block_means(v: np.ndarray, u: np.ndarray, ok: np.ndarray, order: int
                 ) -> tuple[np.ndarray, np.ndarray, BlockLayout]:
    """Block means of the data and of ``u^k`` (k = 0 … order) over the jointly valid samples,
    and where each block mean sits (for the noise model's covariance)."""
    n = v.size
    m = max(1, n // _BLOCKS)
    nb = -(-n // m)
    idx = np.arange(n) // m
    counts = np.bincount(idx[ok], minlength=nb).astype(np.float64)
    used = counts > 0
    ybar = np.bincount(idx[ok], weights=v[ok], minlength=nb)[used] / counts[used]
    powers = np.column_stack([np.bincount(idx[ok], weights=u[ok] ** k, minlength=nb)[used] / counts[used]
                              for k in range(order + 1)])
    return ybar, powers, _layout(ok, np.flatnonzero(used), counts[used], m)


def _layout(ok: np.ndarray, blocks: np.ndarray, counts: np.ndarray, m: int) -> BlockLayout:
    """The interval of each block mean, in block lengths: the block itself, or for a block with gaps
    an interval as long as its valid samples centred on their mean time (sample i spans [i, i+1))."""
    n = ok.size
    start = blocks * m
    stop = np.minimum(start + m, n)
    centre = 0.5 * (start + stop).astype(np.float64)
    length = (stop - start).astype(np.float64)
    for j in np.flatnonzero(counts < length):  # only blocks with gaps: O(m) each, O(n) at most
        centre[j] = start[j] + float(np.mean(np.flatnonzero(ok[start[j]:stop[j]]))) + 0.5
        length[j] = counts[j]
    return BlockLayout(start=(centre - 0.5 * length) / m, stop=(centre + 0.5 * length) / m,
                       counts=counts, m=m, span=n / m)


def _gls(xw: np.ndarray, yw: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Least squares on whitened values: coefficients, their unscaled covariance ``(X̃ᵀX̃)⁻¹`` and the RSS."""
    q, r = np.linalg.qr(xw)
    beta = np.linalg.solve(r, q.T @ yw)
    res = yw - xw @ beta
    rinv = np.linalg.inv(r)
    return beta, rinv @ rinv.T, float(res @ res)


def temperature_fit(data: object, temperature: object, *, rate: float, unit: str | None = None,
                    max_order: int = 3) -> PrepResult:
    r"""Fit the bias against temperature and remove its temperature-dependent part.

    Parameters
    ----------
    data : array_like
        Rate samples (gyro, accelerometer); NaN marks a gap. Not modified.
    temperature : array_like
        The sensor's temperature at each sample (°C or K: only differences matter), as many
        values as ``data``; NaN where it is missing (those samples become gaps).
    rate : float
        Sample rate in Hz.
    unit : str, optional
        The data's unit (``"deg/s"``, ``"m/s^2"`` …), used to label the results: the tempco is
        in ``unit/K``. Convert with :func:`sigmatau.imu.units.convert`, e.g. to °/h/°C with
        ``convert(tc, unit, "deg/h")`` or mg/°C with ``convert(tc, unit, "mg")`` (a kelvin and a
        degree Celsius are the same step).
    max_order : int
        Highest polynomial order tried (0 … 6; default 3).

    Returns
    -------
    PrepResult
        ``data``: the compensated series ``y_i − Σ_{k≥1} c_k (T_i − T̄)^k`` (the bias at the mean
        temperature ``c_0`` stays; gaps where the data or the temperature are missing);
        ``estimates``: ``tempco`` (``dbias/dT`` at T̄, ``c_1``), ``bias_at_reference`` (``c_0``)
        and ``c1`` … ``cP`` of the order chosen, each ± standard error; ``details``: the order,
        the BIC of every order tried, the reference temperature T̄, the temperature range,
        the blocks, the noise model behind the errors (``noise_model``, ``noise_levels``,
        ``noise_probability``, ``errors``); ``indices``: samples made gaps for a missing temperature.

    Raises
    ------
    ParameterError
        A bad rate or max_order.
    DataError
        Data or temperature not numeric, not 1-D, of different lengths, or all NaN; a
        temperature that does not vary; too few blocks with both data and temperature.

    Notes
    -----
    **Model** (IEEE Std 952-1997: the temperature-sensitive drift-rate term of its model
    equation, measured by its drift-rate temperature-sensitivity test):
    ``y_i = Σ_{k=0}^{P} c_k (T_i − T̄)^k + n_i`` with ``T̄`` the mean temperature of the valid
    samples. The record is cut into about 200 blocks of equal length, and the block means
    ``ȳ_b = Σ_k c_k ⟨(T − T̄)^k⟩_b`` are fitted by generalised least squares under the noise
    model below. Using the block means of the powers, not powers of the mean
    temperature, keeps the fit exact however much the temperature moves within a block;
    fitting block means rather than samples keeps the white noise from dominating the order
    selection (a million samples would make every tiny curvature "significant").

    **Noise model of the block means** (what the standard errors and the order rest on). The
    bias noise is white + flicker (bias instability, ``S_y = h₋₁/f``) + random walk
    (``S_y = h₋₂/f²``), the three terms of an Allan-variance model; its block means are
    correlated unless the white term dominates at every length. Their covariance is
    ``Σ = s²·V``, ``V = D + ρ_f·F̃ + ρ_w·W̃``: ``D = diag(m/n_b)`` (white, n_b valid samples in
    block b of nominal length m), and ``F̃``, ``W̃`` the exact covariances of block averages of
    flicker and random-walk noise, from their generalised covariances ``−h₋₁ ln|τ|`` and
    ``−π² h₋₂ |τ|`` integrated over each pair of blocks in closed form, each scaled to an Allan
    variance of 1 at the block length (so ``ρ_f``, ``ρ_w`` are the Allan-variance ratios to the
    white term there; :mod:`sigmatau.prep._bias_noise`). The levels are estimated from the block
    means themselves, by restricted maximum likelihood (REML: the likelihood of the residual
    contrasts, free of the coefficients, ``s²`` concentrated out). A 30-minute record pins the
    white level well but the flicker and random-walk levels poorly, and the two can stand in
    for each other over the scales it holds while implying slope errors several times apart
    (most on a ramp); so rather than plugging in the best levels, every estimate is
    **averaged over their REML posterior** (Harville 1974): a grid of ``(ρ_f, ρ_w)``, each
    absent with prior probability ½ or else log-uniform over ``e^−10 … e^8`` (grid steps 1/4
    in ``ln ρ_f``, 1 in ``ln ρ_w``), weighted by prior × REML likelihood. For each grid point
    g the GLS fit gives ``β_g`` and ``s²_g(XᵀV_g⁻¹X)⁻¹`` (``s²_g = RSS̃_g/(K − P − 1)``, RSS̃
    whitened); the reported coefficients are ``β̄ = Σ w_g β_g`` with covariance
    ``Σ w_g s²_g(XᵀV_g⁻¹X)⁻¹ + Σ w_g (β_g − β̄)(β_g − β̄)ᵀ`` (law of total variance). At
    ``ρ_f = ρ_w = 0`` this is the former ``s²(XᵀWX)⁻¹``; on white data the posterior keeps
    some weight on coloured levels a short record cannot rule out, and the errors come out
    larger by 17 % (cycle) and 56 % (ramp) on average. ``details`` gives the model, the
    posterior-mean levels ``N`` (unit/√Hz), ``B`` (unit, ``h₋₁ = B²/π``) and ``K`` (unit/√s,
    ``h₋₂ = K²/2π²``), and the posterior probability that flicker and random walk are present. The error of ``c_0`` also counts the
    wander over one record length (the cut-off of the generalised covariances); the other
    coefficients do not depend on it (Rao 1967). With fewer than 20 residual degrees of
    freedom the block means are taken as white.

    **Order** by the Bayesian information criterion over K blocks,
    ``BIC_P = K·ln(RSS̃_P/K) + (P + 1)·ln K``, P = 0 … max_order, every order whitened by the
    same covariance: ``V`` at the posterior-mean levels of the order-2 model (of max_order if
    lower). BIC is consistent and charges ln K ≈ 5 per term rather than AIC's 2. Whitening
    keeps slow bias wander that happens to follow the temperature from being fitted as
    curvature: with white-block-mean residuals (the former criterion) flicker bias chose
    order 2 or 3 in 72 % of ramps. The noise for the criterion is estimated under the
    quadratic: under the cubic, on a ramp, it loses the wander the extra terms absorb and
    over-fits again; under the linear model a real curvature is taken for noise.

    A single temperature ramp cannot tell a temperature effect from a drift in time: under
    random-walk or flicker bias its tempco error is several times that of a cycle over the same
    range, which the standard error says. The tempco is ``dbias/dT`` at T̄, i.e. ``c_1``, even
    when a higher order is chosen; when BIC chooses order 0 the tempco of the order-1 fit is
    still reported (marked not significant in ``details``) and nothing is removed.

    **Checked** on 200 simulated 30-minute, 100 Hz records per case, ramp and cycle
    (docs/warmup-temperature.md): ±2 standard errors cover the true tempco in 0.925–0.995 of
    the records for white, white + flicker and white + flicker + random walk bias, linear or
    quadratic (formerly 0.18–0.37 with flicker or random walk), conservatively on a ramp
    (white: 0.995); random walk without flicker is short (0.83 ramp, 0.89 cycle). The true
    order is found in 0.88–1.0 (formerly 0.17–0.68 under coloured noise), except a quadratic
    on a ramp with all three noises: 0.75.

    References
    ----------
    IEEE Std 952-1997, *IEEE Standard Specification Format Guide and Test Procedure for
    Single-Axis Interferometric Fiber Optic Gyros*, Annex (model equation: the
    temperature-sensitive drift rate) and the drift-rate temperature-sensitivity test.
    G. Schwarz, "Estimating the dimension of a model", Ann. Statist. 6 (1978) 461–464 (BIC).
    D. A. Harville, "Maximum likelihood approaches to variance component estimation and to
    related problems", J. Amer. Statist. Assoc. 72 (1977) 320–338 (REML); "Bayesian inference
    for variance components using only error contrasts", Biometrika 61 (1974) 383–385.
    S. D. P. Williams, "The effect of coloured noise on the uncertainties of rates estimated
    from geodetic time series", J. Geodesy 76 (2003) 483–494 (white + flicker + random-walk
    covariance of a trend's error). M. S. Keshner, "1/f noise", Proc. IEEE 70 (1982) 212–218.
    J. A. Hoeting et al., "Bayesian model averaging: a tutorial", Statist. Sci. 14 (1999)
    382–417. C. R. Rao, "Least squares theory using an estimated dispersion matrix and its
    application to measurement of signals", Proc. Fifth Berkeley Symp. 1 (1967) 355–372.

    Examples
    --------
    >>> import numpy as np
    >>> from sigmatau.prep import temperature_fit
    >>> temp = np.linspace(20.0, 40.0, 36000)
    >>> y = 0.002 * (temp - 30.0) + np.random.default_rng(1).normal(0.0, 0.05, temp.size)
    >>> r = temperature_fit(y, temp, rate=100.0, unit="deg/s")
    >>> r.details["order"], r.estimates["tempco"].unit
    (1, 'deg/s/K')
    >>> abs(r.estimates["tempco"].value - 0.002) < 3 * r.estimates["tempco"].stderr
    True
    """
    v = series(data)
    temp = series(temperature, "temperature")
    rate_f = rate_of(rate)
    order_max = _check_order(max_order)
    if unit is not None and not isinstance(unit, str):
        raise ParameterError(f"unit={unit!r} must be a unit name such as 'deg/s', or None")
    if temp.size != v.size:
        raise DataError(f"temperature has {temp.size} samples but data has {v.size}; they must match")
    ok = ~np.isnan(v) & ~np.isnan(temp)
    if not ok.any():
        raise DataError("no sample has both a value and a temperature")
    tv = temp[ok]
    if float(np.max(tv)) == float(np.min(tv)):
        raise DataError("the temperature does not vary: no temperature dependence can be fitted")
    made_gaps = np.flatnonzero(~np.isnan(v) & np.isnan(temp))
    if made_gaps.size:
        warnings.warn(f"temperature_fit: {made_gaps.size} sample(s) without a temperature become gaps",
                      PrepWarning, stacklevel=caller_stacklevel())
    t_ref = float(np.mean(tv))
    half = 0.5 * float(np.max(tv) - np.min(tv))
    u = (temp - t_ref) / half
    ybar, powers, lay = _block_means(v, u, ok, order_max)
    # the fits run on the block means scaled by an exact power of two into [0.5, 1), so that no
    # square overflows or underflows at 1e±200; _result scales the coefficients back
    peak = float(np.max(np.abs(ybar))) if ybar.size else 0.0
    shift = math.frexp(peak)[1] if peak > 0 and math.isfinite(peak) else 0
    ybar = np.ldexp(ybar, -shift)
    k = ybar.size
    if k < _MIN_BLOCKS:
        raise DataError(f"temperature_fit: too few blocks with data and temperature ({k}; at least"
                        f" {_MIN_BLOCKS} are needed)")
    distinct = np.unique(np.round(powers[:, 1], 12)).size if order_max else 1
    top = min(order_max, k - 2, distinct - 1)
    post = noise_posterior(powers[:, : top + 1], ybar, lay)
    bic = _bic(post, powers[:, : top + 1], ybar)
    order = int(np.argmin(bic))
    fits = [post.average(p) for p in range(top + 1)]
    return _result(v, temp, ok, fits, order, bic, t_ref, half, unit, rate_f, order_max, made_gaps, post, shift)


def _bic(post: NoisePosterior, x: np.ndarray, y: np.ndarray) -> list[float]:
    """``BIC_P = K·ln(RSS̃_P/K) + (P + 1)·ln K`` of every order, all whitened by one noise covariance:
    that at the posterior-mean levels of the order-:data:`_NOISE_ORDER` model (see the Notes of
    :func:`temperature_fit`)."""
    from scipy.linalg import solve_triangular  # on first use: import sigmatau stays light

    k, top = x.shape
    chol = post.mean_model(min(_NOISE_ORDER, top - 1))
    z = solve_triangular(chol, np.column_stack([x, y]), lower=True, check_finite=False)
    bic = []
    for p in range(top):
        rss = _gls(z[:, : p + 1], z[:, top])[2]
        bic.append(k * math.log(max(rss, 1e-300) / k) + (p + 1) * math.log(k))
    return bic


def _result(v: np.ndarray, temp: np.ndarray, ok: np.ndarray, fits: list, order: int, bic: list[float],
            t_ref: float, half: float, unit: str | None, rate: float, order_max: int, made_gaps: np.ndarray,
            post: NoisePosterior, shift: int = 0) -> PrepResult:
    """Coefficients in powers of ``T − T̄``, the tempco, the compensated series and the record."""
    du = unit or "data"
    k, m = post.layout.counts.size, post.layout.m

    def coefficients(p: int) -> tuple[np.ndarray, np.ndarray]:
        """The coefficients in the data's unit and their standard errors (from the scaled fit)."""
        beta, cov = fits[p]
        scale = half ** -np.arange(p + 1)  # c_k = β_k / h^k
        se = np.sqrt(np.maximum(np.diag(cov), 0.0)) * np.abs(scale)
        return np.ldexp(beta * scale, shift), np.ldexp(se, shift)

    c, se = coefficients(order)
    estimates: dict[str, Estimate] = {}
    significant = order >= 1
    if significant:
        estimates["tempco"] = Estimate(float(c[1]), float(se[1]), f"{du}/K")
    elif len(fits) > 1:
        c1, se1 = coefficients(1)
        estimates["tempco"] = Estimate(float(c1[1]), float(se1[1]), f"{du}/K")
    estimates["bias_at_reference"] = Estimate(float(c[0]), float(se[0]), du)
    for j in range(1, order + 1):
        estimates[f"c{j}"] = Estimate(float(c[j]), float(se[j]), f"{du}/K^{j}" if j > 1 else f"{du}/K")
    dt = temp - t_ref
    correction = sum(c[j] * dt ** j for j in range(1, order + 1)) if order else np.zeros_like(v)
    out = np.where(ok, v - correction, np.nan)
    out.flags.writeable = False
    tc = estimates.get("tempco")
    notes = [f"bias versus temperature: order {order} chosen by BIC (of 0 … {len(fits) - 1}) on {k} block means",
             _noise_note(post, order, rate, shift, du)]
    if significant and tc is not None:
        notes.append(f"tempco {tc.value:.4g} ± {tc.stderr:.2g} {tc.unit} at {t_ref:.4g}°; the temperature-"
                     f"dependent bias is removed (the bias at {t_ref:.4g}° stays)")
    else:
        notes.append("no temperature dependence is significant (BIC chose order 0): nothing removed")
    if made_gaps.size:
        notes.append(f"{made_gaps.size} sample(s) without a temperature became gaps")
    details = {"order": order, "criterion": "BIC", "bic": bic, "significant": significant,
               "reference_temperature": t_ref,
               "temperature_range": [float(np.min(temp[ok])), float(np.max(temp[ok]))],
               "blocks": k, "block_samples": m, "gaps_from_temperature": int(made_gaps.size),
               "unit": unit, "coefficients_in": "powers of (T − reference_temperature)",
               **_noise_details(post, order, rate, shift)}
    return PrepResult(step="temperature", data=out, data_type="freq",
                      parameters={"rate": rate, "unit": unit, "max_order": order_max},
                      estimates=estimates, indices=made_gaps.astype(np.int64), details=details,
                      notes=tuple(notes))


def _noise_levels(post: NoisePosterior, p: int, rate: float, shift: int) -> dict[str, float]:
    """Posterior-mean N, B, K of the order-p fit in the data's unit."""
    levels = allan_levels(*post.mean_levels(p), rate, post.layout.m)
    return {name: math.ldexp(level, shift) for name, level in levels.items()}


def _noise_details(post: NoisePosterior, p: int, rate: float, shift: int) -> dict:
    """What the standard errors and the order rest on: the noise model of the block means and its levels."""
    flicker, walk = post.present(p)
    model = ("white + flicker + random walk, levels averaged over their REML posterior" if post.coloured
             else f"white (fewer than {MIN_DOF_COLOURED} residual degrees of freedom)")
    return {"noise_model": model,
            "noise_levels": _noise_levels(post, p, rate, shift),
            "noise_probability": {"flicker": flicker, "random_walk": walk},
            "errors": "GLS averaged over the noise posterior (within- plus between-model variance)"}


def _noise_note(post: NoisePosterior, p: int, rate: float, shift: int, du: str) -> str:
    """One sentence on the noise model behind the standard errors."""
    if not post.coloured:
        return (f"standard errors for white block means (fewer than {MIN_DOF_COLOURED} residual degrees of"
                " freedom: no coloured noise fitted)")
    lv = _noise_levels(post, p, rate, shift)
    flicker, walk = post.present(p)
    return (f"standard errors and order under white + flicker + random-walk bias noise fitted to the block"
            f" means (REML posterior means: N {lv['N']:.2g} {du}/√Hz, B {lv['B']:.2g} {du}"
            f" (P = {flicker:.2f}), K {lv['K']:.2g} {du}/√s (P = {walk:.2f}))")
