"""Power spectral density of fractional frequency with log-frequency averaging and a power-law fit.

Welch's averaged periodogram (``scipy.signal.welch``) gives ``S_y`` on a linear
frequency grid; averaging it in bins equally spaced in log f gives estimates
whose equivalent degrees of freedom (EDF) grow with frequency, each with a χ²
interval; a weighted fit of ``S_y(f) = Σ h_α f^α`` over those bins gives the
power-law coefficients of NIST SP 1065 Table 9 with intervals, and the noise
type that dominates each decade.

References
----------
P. D. Welch, "The use of fast Fourier transform for the estimation of power
spectra", IEEE Trans. AU-15 (1967) 70–73; W. J. Riley, NIST SP 1065 (2008)
§3 and §6.2 (power-law spectra, h_α); D. B. Percival & A. T. Walden,
*Spectral Analysis for Physical Applications* (1993) §6.17 (EDF of Welch's
estimate as a quadratic form).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from ..core.validate import DataType, as_series, check_data_type, check_rate
from ..errors import DataError, ParameterError
from ..uncertainty.confidence import ONE_SIGMA, chi2_interval

__all__ = ["psd", "PsdResult"]

_ALPHAS = (2, 1, 0, -1, -2)
#: First Welch bin kept (k·rate/nperseg): k = 1, 2 lie in the Hann main lobe around DC.
_FIRST_BIN = 3


@dataclass(frozen=True)
class PsdResult:
    """One-sided PSD of fractional frequency, log-frequency averaged, with its power-law fit.

    Attributes
    ----------
    f : numpy.ndarray
        Geometric-mean frequency of each log bin (Hz).
    s_y : numpy.ndarray
        Mean of the Welch estimates in the bin (1/Hz).
    lo, hi : numpy.ndarray
        χ² interval of ``s_y`` at ``confidence``.
    n_avg : numpy.ndarray
        Number of Welch frequency estimates averaged in the bin.
    edf : numpy.ndarray
        Equivalent degrees of freedom of ``s_y`` (segments, overlap, window and
        bin width all counted).
    h, h_lo, h_hi : dict
        Fitted ``h_α`` per α and its interval (``h_lo`` ≥ 0).
    dominant : tuple
        ``(f_low, f_high, α)`` per decade of the fitted frequencies: the term
        ``h_α f^α`` that is largest at the decade's centre.
    raw_f, raw_s_y : numpy.ndarray
        Welch's estimate on its linear grid (DC and Nyquist dropped).
    """

    f: np.ndarray
    s_y: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    n_avg: np.ndarray
    edf: np.ndarray
    rate: float
    confidence: float
    h: dict = field(default_factory=dict)
    h_lo: dict = field(default_factory=dict)
    h_hi: dict = field(default_factory=dict)
    dominant: tuple = ()
    raw_f: np.ndarray = field(default_factory=lambda: np.empty(0))
    raw_s_y: np.ndarray = field(default_factory=lambda: np.empty(0))
    carrier: Optional[float] = None

    @property
    def s_x(self) -> np.ndarray:
        """Phase (time) PSD in s²/Hz: ``S_x = S_y/(2·rate·sin(πf/rate))²``.

        The frequency samples are phase differences, ``y_k = (x_{k+1} − x_k)·rate``, so
        the exact relation of their spectra is the difference filter's response
        ``|2·rate·sin(πf/rate)|²``, not ``(2πf)²``: the two agree far below Nyquist, but
        ``(2πf)²`` would put S_x 0.9 dB low at rate/4 and 3.9 dB low at Nyquist.
        """
        return self.s_y / (2.0 * self.rate * np.sin(math.pi * self.f / self.rate)) ** 2

    @property
    def s_phi(self) -> np.ndarray:
        """Phase PSD ``S_φ = (2πν0)² S_x`` in rad²/Hz (needs ``carrier``)."""
        if self.carrier is None:
            raise ParameterError("s_phi needs the carrier frequency: psd(..., carrier=nu0)")
        return (2.0 * math.pi * self.carrier) ** 2 * self.s_x

    @property
    def l_dbc(self) -> np.ndarray:
        """``L(f) = 10·log10(S_φ/2)`` in dBc/Hz (needs ``carrier``)."""
        return 10.0 * np.log10(self.s_phi / 2.0)

    def model(self, f: object) -> np.ndarray:
        """The fitted ``Σ h_α f^α`` at ``f``."""
        freq = np.asarray(f, dtype=float)
        return sum((h * freq**a for a, h in self.h.items()), np.zeros_like(freq))

    def to_dict(self) -> dict:
        """Plain lists and numbers, for tables."""
        return {"f": self.f.tolist(), "s_y": self.s_y.tolist(), "lo": self.lo.tolist(),
                "hi": self.hi.tolist(), "n_avg": self.n_avg.tolist(), "edf": self.edf.tolist(),
                "h": dict(self.h), "h_lo": dict(self.h_lo), "h_hi": dict(self.h_hi),
                "dominant": [list(d) for d in self.dominant]}

    def __repr__(self) -> str:
        terms = ", ".join(f"h{a}={v:.3g}" for a, v in self.h.items() if v > 0)
        return f"PsdResult({self.f.size} bins, {self.f[0]:.3g}–{self.f[-1]:.3g} Hz, {terms})"


def _psd_iv(data, rate, data_type, segments, bins_per_decade, fit_range, alphas, carrier):
    rate = check_rate(rate)
    data_type = check_data_type(data_type)
    x = as_series(data)
    y = np.diff(x) * rate if data_type == "phase" else x
    if isinstance(segments, bool) or not isinstance(segments, (int, np.integer)) or segments < 1:
        raise ParameterError(f"segments={segments!r} must be an integer >= 1")
    nperseg = y.size // int(segments)
    if nperseg < 16:
        raise DataError(f"{y.size} frequency samples give {nperseg=} with {segments=}; "
                        "need >= 16 per segment")
    if np.ptp(y) == 0:
        raise DataError("data are constant: the spectrum is zero")
    if isinstance(bins_per_decade, bool) or not isinstance(bins_per_decade, (int, float)) \
            or not bins_per_decade > 0:
        raise ParameterError(f"bins_per_decade={bins_per_decade!r} must be a positive number")
    if fit_range is not None:
        try:
            lo, hi = (float(v) for v in fit_range)
        except (TypeError, ValueError):
            raise ParameterError(f"fit_range={fit_range!r} must be a pair (f_low, f_high) in Hz") from None
        if not lo < hi:
            raise ParameterError(f"fit_range={fit_range!r} must have f_low < f_high")
    if len(alphas) == 0 or any(isinstance(a, bool) or not isinstance(a, (int, np.integer)) for a in alphas):
        raise ParameterError(f"alphas={alphas!r} must be a non-empty sequence of integer exponents")
    if carrier is not None and not (isinstance(carrier, (int, float)) and math.isfinite(carrier)
                                    and carrier > 0):
        raise ParameterError(f"carrier={carrier!r} must be a positive frequency in Hz")
    return rate, y, nperseg


def _overlap_sums(win: np.ndarray, step: int, count: int) -> list[tuple[int, np.ndarray]]:
    """``(weight, |G_j(Δ)|²)`` per segment lag j: G_j is the normalised spectrum of w_n w_{n+jD}."""
    length = win.size
    norm = float(np.sum(win**2))
    out = []
    for j in range(count):
        if j * step >= length:
            break
        prod = win[j * step:] * win[: length - j * step]
        g = np.abs(np.fft.fft(prod, n=length)) ** 2 / norm**2
        out.append((count - j if j == 0 else 2 * (count - j), g))
    return out


def _bin_edf(sizes: np.ndarray, overlaps: list[tuple[int, np.ndarray]], count: int) -> np.ndarray:
    """EDF ``2(tr A)²/tr(A²)`` of a mean of ``size`` adjacent bins over ``count`` segments.

    Assumes the spectrum is flat within the bin (white locally); the
    pseudo-covariance terms at k + k' are neglected (they matter only next to DC).
    """
    tr2 = np.zeros(sizes.size)
    for weight, g in overlaps:
        c1 = np.concatenate(([0.0], np.cumsum(g[1:])))
        c2 = np.concatenate(([0.0], np.cumsum(np.arange(1, g.size) * g[1:])))
        lb = sizes.astype(int)
        s = lb * g[0] + 2.0 * (lb * c1[lb - 1] - c2[lb - 1])
        tr2 += weight * s
    return 2.0 * (count * sizes) ** 2 / tr2


def _log_bins(f: np.ndarray, per_decade: float) -> list[np.ndarray]:
    """Indices of f in bins equally spaced in log f, empty bins dropped."""
    edges = np.log10(f[0]) + np.arange(0, np.log10(f[-1] / f[0]) * per_decade + 2) / per_decade
    which = np.searchsorted(edges, np.log10(f) + 1e-12, side="right") - 1
    return [np.flatnonzero(which == b) for b in np.unique(which)]


def _adjacent_cov(sizes: np.ndarray, overlaps: list[tuple[int, np.ndarray]], count: int) -> np.ndarray:
    """Correlation ``tr(A_b A_{b+1})/(tr A_b tr A_{b+1})`` of neighbouring bins (shared window leakage)."""
    out = np.zeros(max(sizes.size - 1, 0))
    for b in range(sizes.size - 1):
        la, lb = int(sizes[b]), int(sizes[b + 1])
        lag = np.arange(1, min(la + lb, 64))
        pairs = np.minimum.reduce([lag, np.full_like(lag, la), np.full_like(lag, lb), la + lb - lag])
        out[b] = sum(w * np.sum(pairs * g[lag]) for w, g in overlaps) / (count * la * count * lb)
    return out


def _fit(X, s, edf, adjacent, alphas, confidence):
    """Weighted non-negative least squares of the bin means on Σ h_α·⟨f^α⟩, iterated weights.

    The interval uses the sandwich variance with the covariance of neighbouring
    bins (their edge frequencies are correlated through the window).
    """
    from scipy.optimize import nnls
    from scipy.stats import norm

    scale = np.max(np.abs(X), axis=0)
    Xs = X / scale
    expected = s.copy()
    coef = np.zeros(len(alphas))
    for _ in range(8):
        sd = expected * np.sqrt(2.0 / edf)
        coef, _ = nnls(Xs / sd[:, None], s / sd)
        expected = np.maximum(Xs @ coef, 1e-300 * np.max(s))
    free = coef > 0
    se = np.zeros(len(alphas))
    if np.any(free):
        var = 2.0 * expected**2 / edf
        cov = np.diag(var)
        off = adjacent * expected[:-1] * expected[1:]
        cov += np.diag(off, 1) + np.diag(off, -1)
        A = Xs[:, free] / var[:, None]
        bread = np.linalg.pinv(Xs[:, free].T @ A)
        se[free] = np.sqrt(np.diag(bread @ (A.T @ cov @ A) @ bread))
    z = float(norm.ppf(0.5 + confidence / 2.0))
    h = coef / scale
    half = z * se / scale
    return ({a: float(v) for a, v in zip(alphas, h)},
            {a: float(max(v - d, 0.0)) for a, v, d in zip(alphas, h, half)},
            {a: float(v + d) for a, v, d in zip(alphas, h, half)})


def _dominant(h: dict, f_low: float, f_high: float) -> tuple:
    out = []
    for k in range(math.floor(math.log10(f_low)), math.ceil(math.log10(f_high))):
        lo, hi = max(10.0**k, f_low), min(10.0 ** (k + 1), f_high)
        if lo >= hi:
            continue
        centre = math.sqrt(lo * hi)
        terms = {a: v * centre**a for a, v in h.items() if v > 0}
        if terms:  # a fit with every h at zero names no noise type
            out.append((lo, hi, max(terms, key=terms.get)))
    return tuple(out)


def psd(
    data: object, *, rate: float = 1.0, data_type: DataType = "freq", window: str = "hann",
    segments: int = 8, bins_per_decade: float = 10, confidence: float = ONE_SIGMA,
    alphas: tuple = _ALPHAS, fit_range: Optional[tuple[float, float]] = None,
    carrier: Optional[float] = None,
) -> PsdResult:
    """One-sided PSD ``S_y(f)`` averaged in log-frequency bins, with a power-law fit.

    Parameters
    ----------
    data : array_like
        Fractional frequency (``data_type="freq"``) or phase in s (``"phase"``).
    rate : float
        Sample rate in Hz.
    data_type : {"freq", "phase"}
        Phase is differenced to frequency first.
    window : str
        Welch window (any :func:`scipy.signal.get_window` name; "hann" by default).
    segments : int
        The record is cut in segments of ``N // segments`` samples with 50 %
        overlap (``2·segments − 1`` of them).
    bins_per_decade : float
        Log-frequency bins per decade.
    confidence : float
        Coverage of the χ² intervals of the bins and of the ``h_α`` intervals.
    alphas : tuple of int
        Power laws in the fit (default 2, 1, 0, −1, −2).
    fit_range : (f_low, f_high), optional
        Frequencies of the bins used in the fit; all bins by default.
    carrier : float, optional
        Carrier ν0 (Hz) for ``s_phi`` and ``l_dbc``.

    Returns
    -------
    PsdResult

    Notes
    -----
    A bin mean ``Ŝ = (1/L)Σ_k Ŝ_W(f_k)`` of the Welch estimate is a quadratic
    form ``yᵀAy``; with the spectrum flat inside the bin its EDF is
    ``ν = 2(tr A)²/tr(A²)``, computed from the window's overlap spectra, and the
    interval is ``[νŜ/χ²_ν(1−q), νŜ/χ²_ν(q)]``, ``q = (1 − p)/2``. The fit
    minimises ``Σ_b ν_b(Ŝ_b − Σ_α h_α⟨f^α⟩_b)²/(2E_b²)`` over ``h_α ≥ 0`` with E_b
    the fitted value (iterated), ``⟨f^α⟩_b`` the mean over the bin's
    frequencies; the ``h_α`` intervals are ±z standard errors of that fit
    (sandwich covariance, with the correlation of neighbouring bins).

    Welch bins k = 1, 2 (``k·rate/nperseg``) lie in the Hann main lobe around DC
    and are dropped; the window still smooths a curved spectrum over about
    ±1 bin, a relative bias of about ``α(α − 1)/(6k²)`` at bin k (6 % at k = 4
    for random-walk FM), so ``fit_range`` can leave out the lowest bins. A series
    of τ0-averaged frequency samples has the process spectrum times
    ``sinc²(πfτ0)``; :func:`~sigmatau.spectral.spectrum_to_sigma` accounts for it.

    Examples
    --------
    >>> import sigmatau
    >>> y = sigmatau.power_law_noise(2**14, "wfm", h=2e-20, rate=1.0, rng=3)
    >>> r = psd(y, rate=1.0, alphas=(0,))
    >>> 1.9e-20 < r.h[0] < 2.1e-20
    True
    """
    from scipy.signal import get_window, welch

    alphas = tuple(alphas)
    rate, y, nperseg = _psd_iv(data, rate, data_type, segments, bins_per_decade, fit_range, alphas, carrier)
    step = nperseg - nperseg // 2
    count = (y.size - nperseg) // step + 1
    try:
        win = get_window(window, nperseg)
    except ValueError as exc:
        raise ParameterError(f"window={window!r}: {exc}") from None
    f, s = welch(y, fs=rate, window=win, nperseg=nperseg, noverlap=nperseg - step, detrend="constant")
    # Drop DC, the Nyquist bin (χ²₁) and the bins inside the window's main lobe
    # around DC, whose mean removal and leakage bias them (×18 at k = 1 for white PM).
    keep = slice(_FIRST_BIN, (nperseg - 1) // 2 + 1)
    raw_f, raw_s = f[keep], s[keep]
    bins = _log_bins(raw_f, bins_per_decade)
    sizes = np.array([b.size for b in bins], dtype=float)
    mean = np.array([raw_s[b].mean() for b in bins])
    overlaps = _overlap_sums(win, step, count)
    edf = _bin_edf(sizes, overlaps, count)
    ci = chi2_interval(mean, edf, confidence)
    fb = np.array([math.exp(np.mean(np.log(raw_f[b]))) for b in bins])
    use = np.ones(fb.size, bool) if fit_range is None else (fb >= fit_range[0]) & (fb <= fit_range[1])
    if np.count_nonzero(use) < len(alphas):
        raise ParameterError(f"fit_range={fit_range!r} keeps {np.count_nonzero(use)} bins, fewer than the "
                             f"{len(alphas)} power laws fitted")
    X = np.array([[np.mean(raw_f[b] ** a) for a in alphas] for b, u in zip(bins, use) if u])
    adjacent = _adjacent_cov(sizes[use], overlaps, count)
    h, h_lo, h_hi = _fit(X, mean[use], edf[use], adjacent, tuple(alphas), confidence)
    return PsdResult(fb, mean, np.asarray(ci.low), np.asarray(ci.high), sizes.astype(int), edf, rate,
                     confidence, h, h_lo, h_hi, _dominant(h, float(fb[use][0]), float(fb[use][-1])),
                     raw_f, raw_s, carrier)
