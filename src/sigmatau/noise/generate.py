"""Power-law noise: the seven types of the design tip (expected variances in :mod:`.expected`).

Two generators produce a series whose one-sided spectrum is
``S_y(f) = h_α f^α`` for α ∈ {2, 1, 0, −1, −2, −3, −4}:

* ``method="kasdin"``: the Kasdin–Walter fractional-difference filter, exact
  in discrete time, so the expectation of every finite-difference statistic is
  known exactly (:func:`~sigmatau.generate.expected_variance_discrete`);
* ``method="tip"``: the constructions of ST DT0064 (randn, cumsum, diff and
  the octave-sum flicker generator, :func:`octave_flicker`), whose flicker
  types honour ``h_α`` only approximately.

:func:`~sigmatau.generate.expected_variance` gives the continuous-time formulas (numerics.md §6.3)
and :func:`~sigmatau.generate.expected_variance_discrete` the exact discrete-time expectations that
tests should use at small averaging factors (numerics.md §6.1).

Noise types may be given as α or by name (case-insensitive; ``-`` or a space
may replace ``_``):

=====  ====  =================================================
α      name  other accepted names (the design tip's vocabulary)
=====  ====  =================================================
+2     wpm   ``white_pm``
+1     fpm   ``flicker_pm``
0      wfm   ``white``
−1     ffm   ``flicker``
−2     rwfm  ``random_walk``
−3     fwfm  ``flicker_walk``
−4     rrfm  ``random_run``
=====  ====  =================================================

Series convention (numerics.md §0): a frequency series of ``n`` samples and a
phase series of ``n + 1`` points drawn with the same seed describe the same
realisation: ``x_0 = 0`` and ``x_{i+1} = x_i + y_i/rate``. WPM and FPM are
generated as phase and differenced; the other types are generated as
frequency and integrated.
"""

from __future__ import annotations

import math
import operator
from typing import Literal, Mapping, Optional, Union

import numpy as np
from scipy import fft as _fft

from ..core.validate import DataType, check_data_type, check_rate
from ..errors import ParameterError

__all__ = [
    "power_law_noise",
    "mixed_noise",
    "octave_flicker",
]

NoiseType = Union[int, str]
Method = Literal["kasdin", "tip"]
ExpectedStatistic = Literal["adev", "oadev", "mdev", "tdev", "hdev", "ohdev"]
RngLike = Union[None, int, np.random.SeedSequence, np.random.BitGenerator, np.random.Generator]

_ALPHA_BY_NAME: dict[str, int] = {
    "wpm": 2, "white_pm": 2,
    "fpm": 1, "flicker_pm": 1,
    "wfm": 0, "white": 0,
    "ffm": -1, "flicker": -1,
    "rwfm": -2, "random_walk": -2,
    "fwfm": -3, "flicker_walk": -3,
    "rrfm": -4, "random_run": -4,
}
_NAME: dict[int, str] = {2: "WPM", 1: "FPM", 0: "WFM", -1: "FFM", -2: "RWFM", -3: "FWFM", -4: "RRFM"}
_ALPHAS = tuple(_NAME)
_METHODS = ("kasdin", "tip")
_STATISTICS = ("adev", "oadev", "mdev", "tdev", "hdev", "ohdev")

#: Rows added to the design tip's ``⌊log2 n⌋ + 1`` when ``power_law_noise``
#: uses the octave generator: with a random counter start they keep the AVAR
#: plateau within 0.6 % from m ≈ 128 up to m = n/4, where the tip's bank alone
#: falls 4 % below it.
_TIP_EXTRA_ROWS = 4


# --- validation ----------------------------------------------------------------------


def _as_alpha(noise: object, name: str = "alpha") -> int:
    """Return the integer α of a noise type given as α or by name."""
    if isinstance(noise, str):
        key = noise.strip().lower().replace("-", "_").replace(" ", "_")
        if key in _ALPHA_BY_NAME:
            return _ALPHA_BY_NAME[key]
    elif not isinstance(noise, (bool, np.bool_)):
        try:
            value = float(noise)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            value = math.nan
        if value in _ALPHAS:
            return int(value)
    raise ParameterError(
        f"{name}={noise!r} must be one of {_ALPHAS} or a noise name ({', '.join(_ALPHA_BY_NAME)})"
    )


def _check_n(n: object, least: int = 2) -> int:
    if isinstance(n, (bool, np.bool_)):
        raise ParameterError(f"n={n!r} must be an integer >= {least}")
    try:
        value = operator.index(n)  # type: ignore[arg-type]
    except TypeError:
        raise ParameterError(f"n={n!r} must be an integer >= {least}") from None
    if value < least:
        raise ParameterError(f"n={n!r} must be an integer >= {least}")
    return value


def _check_level(h: object, name: str = "h") -> float:
    try:
        value = float(h)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={h!r} must be a finite number >= 0") from None
    if not math.isfinite(value) or value < 0.0:
        raise ParameterError(f"{name}={h!r} must be a finite number >= 0")
    return value


def _check_method(method: object) -> str:
    if method not in _METHODS:
        raise ParameterError(f"method={method!r} must be one of {_METHODS}")
    return method  # type: ignore[return-value]


def _as_rng(rng: object) -> np.random.Generator:
    try:
        return np.random.default_rng(rng)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(
            f"rng={rng!r} must be None, an int seed, a SeedSequence, a BitGenerator or a Generator"
        ) from None


def _power_law_iv(n, alpha, h, rate, data_type, method):
    return (
        _check_n(n), _as_alpha(alpha), _check_level(h), check_rate(rate),
        check_data_type(data_type), _check_method(method),
    )


# --- generators ----------------------------------------------------------------------


def _kasdin_coefficients(beta: float, n: int) -> np.ndarray:
    """First n taps of ``(1 − z⁻¹)^{β/2}``: h_0 = 1, h_k = h_{k−1}(k − 1 − β/2)/k."""
    k = np.arange(1, n, dtype=np.float64)
    taps = np.empty(n)
    taps[0] = 1.0
    taps[1:] = (k - 1.0 - beta / 2.0) / k
    return np.cumprod(taps)


def _causal_fft_convolve(w: np.ndarray, taps: np.ndarray) -> np.ndarray:
    """``Σ_{k≤i} taps_k w_{i−k}`` for i < len(w): linear (zero-padded) FFT convolution."""
    n = w.size
    nfft = _fft.next_fast_len(2 * n - 1, real=True)
    spec = _fft.rfft(w, nfft)
    spec *= _fft.rfft(taps, nfft)
    return _fft.irfft(spec, nfft)[:n].copy()  # a copy frees the padding


def _kasdin_filter(w: np.ndarray, beta: int) -> np.ndarray:
    """Apply the Kasdin–Walter filter ``(1 − z⁻¹)^{β/2}`` (start at rest) for β ≤ 0.

    The filter factors as ``(1 − z⁻¹)^{−1/2}`` (odd β only) times ``⌊−β/2⌋``
    integrations. The fractional factor goes through the FFT; the integrations
    are cumulative sums, which equal the convolution with the growing taps
    h_k = 1, k + 1 … exactly while losing fewer digits.
    """
    sums, odd = divmod(-beta, 2)
    z = w
    if odd:
        z = _causal_fft_convolve(z, _kasdin_coefficients(-1.0, z.size))
    for _ in range(sums):
        z = np.cumsum(z)
    return z


def _octave_sum(n: int, rows: int, start: int, sigma: float, gen: np.random.Generator) -> np.ndarray:
    """Extra white term plus the bank sum, for the counters ``start … start + n − 1``.

    Random numbers are drawn in a fixed order: the n white values, then for
    each row r = 0 … K−1 its value current at the first sample followed by one
    value per redraw. Row r is redrawn at the counters c ≡ 2^r (mod 2^{r+1}), so
    its value is indexed by ``b_r(c) = ((c >> r) + 1) >> 1`` and every row
    r' ≥ r is constant on the blocks ``c >> r``. The sum is therefore built from
    the slowest row down, doubling the resolution at each level: O(n) work in
    all, with no loop over samples. A counter divisible by 2^K redraws no row.
    """
    out = sigma * gen.standard_normal(n)
    last = start + n - 1
    draws = []
    for r in range(rows):
        first, final = ((start >> r) + 1) >> 1, ((last >> r) + 1) >> 1
        draws.append(sigma * gen.standard_normal(final - first + 1))
    level = np.zeros((last >> rows) - (start >> rows) + 1)
    for r in range(rows - 1, -1, -1):
        k_lo, size = start >> r, (last >> r) - (start >> r) + 1
        parent = k_lo - 2 * (start >> (r + 1))  # 0 or 1: offset of block k_lo in the parent level
        own = (k_lo + 1) & 1
        level = np.repeat(level, 2)[parent : parent + size] + np.repeat(draws[r], 2)[own : own + size]
    out += level
    return out


def octave_flicker(
    n: int, *, sigma: float = 1.0, rows: Optional[int] = None, start: Optional[int] = None,
    rng: RngLike = None,
) -> np.ndarray:
    """Flicker (1/f) noise from the design tip's octave-sum generator.

    Parameters
    ----------
    n : int
        Number of samples (≥ 1).
    sigma : float
        Standard deviation σ of every generator of the bank and of the extra
        white term.
    rows : int, optional
        Number of generators K in the bank; default ``⌊log2 n⌋ + 1`` as in the
        tip. Rows that never change within the record only add a constant.
    start : int, optional
        Counter of the first sample. The tip's listing starts at 1 (use
        ``start=1`` to reproduce its schedule); the default draws it uniformly
        from ``[0, 2^K)``, which gives every row a random phase, makes the
        process stationary and lets rows slower than the record contribute
        their low-frequency power.
    rng : None, int, SeedSequence or numpy.random.Generator
        Source of randomness, normalised by :func:`numpy.random.default_rng`.

    Returns
    -------
    numpy.ndarray
        ``n`` samples ``y_i = e_i + Σ_{r=0}^{K−1} g_r(i)``.

    Notes
    -----
    A bank of K Gaussian generators ``g_r`` is summed; at sample i (counter
    ``c = start + i``) the generator whose index is the number of trailing
    zeros of c is redrawn, so row r holds each value for ``2^{r+1}`` samples;
    ``e_i ~ N(0, σ²)`` is redrawn every sample (McCartney's extra row, the
    missing one-sample octave). The listing in the tip adds ``rand(1)*sd``
    instead, a uniform term of mean σ/2 and variance σ²/12; a Gaussian one keeps
    the mean at zero and the octave ladder complete. The sum is built level
    by level from the slowest row (O(n), no Python loop over samples).

    With a random start the autocovariance is

    .. math:: C(k) = σ^2 \\Big[δ_{k0} + \\sum_{r=0}^{K-1}
              \\max\\big(0, 1 - |k|/2^{r+1}\\big)\\Big],

    and the expected Allan variance computed from it is 2σ² at m = 1,
    1.875σ² at m = 2 and 4, 1.949σ² at m = 16, 1.985σ² at m = 64 and within
    0.6 % of 2σ² from m ≈ 128 up to ``m = 2^{K−6}``, falling beyond
    (−2 % at ``2^{K−4}``, −8 % at ``2^{K−2}``). Equating the plateau 2σ² to the
    flicker-FM value ``2 ln 2 · h_{−1}`` gives the level scaling
    ``h_{−1} ≈ σ²/ln 2`` (numerics.md §6.2). The spectrum keeps the octave
    ripple of the construction (1–2 dB in published analyses of the
    Voss–McCartney generator), so the scaling is approximate in the spectral
    domain and at m ≲ 16.

    References
    ----------
    ST DT0064 ("Noise models and generators"); R. F. Voss & J. Clarke, J. Acoust.
    Soc. Am. 63 (1978) 258 (octave sums); numerics.md §6.2.

    Examples
    --------
    >>> from sigmatau.generate import octave_flicker
    >>> y = octave_flicker(1000, sigma=0.5, rng=7)
    >>> y.shape
    (1000,)
    """
    n = _check_n(n, least=1)
    sigma = _check_level(sigma, "sigma")
    if rows is None:
        rows = int(n).bit_length()
    else:
        rows_in = rows
        try:
            rows = operator.index(rows)
        except TypeError:
            raise ParameterError(f"rows={rows_in!r} must be an integer in [1, 60]") from None
        if not 1 <= rows <= 60 or isinstance(rows_in, bool):
            raise ParameterError(f"rows={rows_in!r} must be an integer in [1, 60]")
    gen = _as_rng(rng)
    if start is None:
        start = int(gen.integers(0, 1 << rows))
    else:
        start_in = start
        try:
            start = operator.index(start)
        except TypeError:
            raise ParameterError(f"start={start_in!r} must be an integer >= 0") from None
        if start < 0 or isinstance(start_in, bool) or start > (1 << 62) - n:
            raise ParameterError(f"start={start_in!r} must be an integer in [0, 2**62 - n]")
    return _octave_sum(n, rows, start, sigma, gen)


def _primary_kasdin(size: int, alpha: int, h: float, tau0: float, phase: bool,
                    gen: np.random.Generator) -> np.ndarray:
    beta = alpha - 2 if phase else alpha
    qd = h / (2.0 * (2.0 * math.pi) ** alpha * tau0 ** ((alpha - 1) if phase else (alpha + 1)))
    return _kasdin_filter(math.sqrt(qd) * gen.standard_normal(size), beta)


def _primary_tip(size: int, alpha: int, h: float, tau0: float, phase: bool,
                 gen: np.random.Generator) -> np.ndarray:
    if alpha in (2, 0, -2, -4):
        # randn, cumsum(white) and cumsum(cumsum(white)) are the Kasdin filter
        # for β = 0, −2, −4; WPM = diff(white FM) is white phase.
        return _primary_kasdin(size, alpha, h, tau0, phase, gen)
    rows = int(size).bit_length() + _TIP_EXTRA_ROWS
    if alpha == -1:
        return octave_flicker(size, sigma=math.sqrt(h * math.log(2.0)), rows=rows, rng=gen)
    if alpha == 1:  # phase x = flicker with S_x = h1/(4π² f)
        sigma = math.sqrt(h * math.log(2.0)) / (2.0 * math.pi)
        return octave_flicker(size, sigma=sigma, rows=rows, rng=gen)
    # α = −3: y = cumsum(flicker FM); a sum divides S by (2π f τ0)².
    sigma = 2.0 * math.pi * tau0 * math.sqrt(h * math.log(2.0))
    return np.cumsum(octave_flicker(size, sigma=sigma, rows=rows, rng=gen))


def _generate(n: int, alpha: int, h: float, rate: float, data_type: str, method: str,
              gen: np.random.Generator) -> np.ndarray:
    tau0 = 1.0 / rate
    phase_primary = alpha >= 1
    want_phase = data_type == "phase"
    if phase_primary:
        size = n if want_phase else n + 1
    else:
        size = n - 1 if want_phase else n
    make = _primary_kasdin if method == "kasdin" else _primary_tip
    z = make(size, alpha, h, tau0, phase_primary, gen)
    if phase_primary == want_phase:
        return z
    if phase_primary:
        return np.diff(z) * rate
    x = np.empty(n)
    x[0] = 0.0
    np.cumsum(z, out=x[1:])
    x[1:] *= tau0
    return x


def power_law_noise(
    n: int, alpha: NoiseType, *, h: float = 1.0, rate: float = 1.0,
    data_type: DataType = "freq", rng: RngLike = None, method: Method = "kasdin",
) -> np.ndarray:
    """Simulated power-law noise with one-sided spectrum ``S_y(f) = h_α f^α``.

    Parameters
    ----------
    n : int
        Number of samples returned (≥ 2), frequency or phase as ``data_type``.
    alpha : int or str
        Noise type: α ∈ {2, 1, 0, −1, −2, −3, −4} or a name (see the module
        docstring: ``"wpm"``, ``"fpm"``, ``"wfm"``, ``"ffm"``, ``"rwfm"``,
        ``"fwfm"``, ``"rrfm"`` or the tip's ``"white"``, ``"flicker"``,
        ``"random_walk"``, ``"flicker_walk"``, ``"random_run"``).
    h : float
        Level ``h_α`` of the one-sided fractional-frequency (or rate) spectrum,
        in (data unit)²·Hz^{−α−1}; for white FM ``h_0 = 2·(noise density)²``.
    rate : float
        Sample rate in Hz (τ0 = 1/rate).
    data_type : {"freq", "phase"}
        Return frequency samples ``y`` or phase (integrated) samples ``x``.
    rng : None, int, SeedSequence or numpy.random.Generator
        Source of randomness, normalised by :func:`numpy.random.default_rng`.
    method : {"kasdin", "tip"}
        Kasdin–Walter filter (exact in discrete time) or the design tip's
        constructions (approximate level for the three flicker types).

    Returns
    -------
    numpy.ndarray
        ``n`` float64 samples. For the same seed, the phase series of ``n``
        points is ``frequency_to_phase`` of the frequency series of ``n − 1``
        samples (exactly for α ≤ 0; up to the constant ``x_0`` and rounding for
        WPM/FPM, which are generated as phase).

    Notes
    -----
    **Kasdin–Walter.** White ``w_k ~ N(0, Q_d)`` is filtered by
    ``(1 − z^{−1})^{β/2}`` with taps ``h_0 = 1``,
    ``h_k = h_{k−1}(k − 1 − β/2)/k``, starting at rest; the discrete spectrum is
    ``S(f) = 2 Q_d τ0 |2 sin(π f τ0)|^β``. Frequency is generated with β = α
    for α ≤ 0 and phase with β = α − 2 for WPM and FPM, with

    .. math:: Q_d = \\frac{h_α}{2 (2π)^α τ_0^{α+1}} \\;(\\text{frequency}), \\qquad
              Q_d = \\frac{h_α}{2 (2π)^α τ_0^{α-1}} \\;(\\text{phase}).

    The fractional part of the filter, ``(1 − z^{−1})^{−1/2}``, is applied by a
    zero-padded FFT convolution (O(N log N)); whole powers are cumulative sums.
    The start at rest leaves a transient whose effect on OAVAR of a
    2^14-sample record of FFM is below 2·10⁻⁴ at m ≤ 64.

    **Design tip.** WFM = randn, RWFM = cumsum(white), RRFM = cumsum(RWFM),
    WPM = diff(white) — the same series as the Kasdin filter for these four —
    and flicker FM from :func:`octave_flicker` with ``σ² = h_{−1} ln 2`` per
    row, FWFM = cumsum(flicker FM) with ``σ² = 4π² τ0² ln 2 · h_{−3}``, FPM =
    diff(flicker) with the flicker as phase and ``σ² = h_1 ln 2/(4π²)``. The bank
    has four rows more than the tip's ``⌊log2 n⌋ + 1`` and a random counter
    start, so the AVAR of flicker FM stays within 0.6 % of ``2 ln 2 · h_{−1}``
    from m ≈ 128 to m = n/4, but is 2.5 % low at m = 16 and 6 % low at m = 2–4
    (the ripple of the octave construction); the FPM and FWFM levels carry the
    same approximation.

    References
    ----------
    N. J. Kasdin & T. Walter, "Discrete simulation of power law noise", Proc.
    1992 IEEE Frequency Control Symp., 274–283; N. J. Kasdin, Proc. IEEE 83(5)
    (1995) 802–827; ST DT0064 ("Noise models and generators"); numerics.md §6.1–6.2.

    Examples
    --------
    >>> import sigmatau
    >>> from sigmatau.generate import power_law_noise
    >>> y = power_law_noise(2**14, "wfm", h=2e-4, rate=100.0, rng=1)
    >>> r = sigmatau.oadev(y, rate=100.0, m=[1])
    >>> round(float(r.var[0]) / 1e-2, 2)        # expected h0/(2τ) = 1e-2
    1.0
    """
    n, a, h, rate, data_type, method = _power_law_iv(n, alpha, h, rate, data_type, method)
    return _generate(n, a, h, rate, data_type, method, _as_rng(rng))


def mixed_noise(
    n: int, h: Mapping[NoiseType, float], *, rate: float = 1.0, data_type: DataType = "freq",
    rng: RngLike = None, method: Method = "kasdin",
) -> np.ndarray:
    """Sum of independent power-law components, ``S_y(f) = Σ_α h_α f^α``.

    Parameters
    ----------
    n : int
        Number of samples (≥ 2).
    h : mapping
        Noise type (α or name, as in :func:`power_law_noise`) → level ``h_α``.
    rate, data_type, rng, method
        As in :func:`power_law_noise`.

    Returns
    -------
    numpy.ndarray
        ``n`` samples.

    Notes
    -----
    The components are drawn one after the other from the same generator, in
    decreasing α whatever the order of ``h``, so they are independent and the
    result is reproducible for a seed; the spectra, and every variance of the
    Allan family, add.

    Examples
    --------
    >>> from sigmatau.generate import mixed_noise
    >>> y = mixed_noise(1000, {"wfm": 1e-4, "rwfm": 1e-8}, rate=100.0, rng=3)
    >>> y.size
    1000
    """
    n = _check_n(n)
    rate = check_rate(rate)
    data_type = check_data_type(data_type)
    method = _check_method(method)
    if not isinstance(h, Mapping) or len(h) == 0:
        raise ParameterError(f"h={h!r} must be a non-empty mapping of noise type to level")
    levels: dict[int, float] = {}
    for key, value in h.items():
        a = _as_alpha(key, "noise type")
        if a in levels:
            raise ParameterError(f"noise type {key!r} (alpha={a}) is given twice in h")
        levels[a] = _check_level(value, f"h[{key!r}]")
    gen = _as_rng(rng)
    out = np.zeros(n)
    for a in sorted(levels, reverse=True):
        out += _generate(n, a, levels[a], rate, data_type, method, gen)
    return out
