"""σ(τ) from a spectrum through each statistic's transfer function, and back.

Every statistic with a transfer function is a linear filter of the phase
samples ``x_k = x(kτ0)`` followed by a mean square, so its expectation is

.. math:: σ^2(τ) = \\int_0^{f_{max}} S_y(f)\\,|H(f, τ)|^2\\,df ,

with ``|H|² = Q(f)/f²`` and ``Q`` periodic in f with period ``1/τ0``
(``τ = nτ0``, n integer). The kernels below are those of the sampled
estimators (the ones the statistics compute), not their τ0 → 0 limits:
point sampling of x introduces no aliasing, so for a spectrum that holds up
to infinity the integral over [0, ∞) is the exact expectation of the
estimator. Power-law terms are integrated with the convention of
:func:`sigmatau.core.powerlaw.response` (SP1065 Table 9): over [0, f_h],
``f_h = rate/2``, when the integral needs the cut-off (α ≥ 1), over [0, ∞)
otherwise, which the periodicity of ``Q`` turns into one period weighted by a
Hurwitz zeta function, so no tail is truncated. Each half period of
``sin πτf`` gets its own Gauss–Legendre panel up to 4096 of them; beyond, the
middle of the band is integrated as a smooth envelope times the mean of the
oscillating factor plus end corrections (integration by parts), which agrees
with the panel-by-panel sum to ~1e-10 at a cost independent of τ/τ0.

Total and Theo statistics have no transfer function of this form (their
reflected or Theo-weighted records make the expectation depend on the record
length), and are refused with a :class:`~sigmatau.errors.ParameterError`.

References
----------
W. J. Riley, NIST SP 1065 (2008) §5.2 and Table 9; J. A. Barnes et al.,
"Characterization of frequency stability", IEEE Trans. IM-20 (1971);
F. Vernotte, M. Lenczner, P.-Y. Bourgeois, E. Rubiola, "The parabolic
variance (PVAR): a wavelet variance based on the least-square fit",
IEEE TUFFC 63(4), 2016.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Callable, Literal, Mapping, Optional

import numpy as np

from ..core.powerlaw import response
from ..errors import DataError, ParameterError, RangeWarning, caller_stacklevel
from .jitter import to_s_y

__all__ = [
    "KIND_OF_STAT", "NO_TRANSFER", "transfer_function", "spectrum_to_sigma",
    "SigmaFromSpectrum", "sigma_to_h", "sigma_to_powerlaw", "HFromSigma",
]

#: Statistic name → variance kind whose transfer function it has.
KIND_OF_STAT = {
    "avar": "avar", "adev": "avar", "oadev": "avar",
    "mvar": "mvar", "mdev": "mvar",
    "tvar": "tvar", "tdev": "tvar",
    "hvar": "hvar", "hdev": "hvar", "ohdev": "hvar",
    "mhvar": "mhvar", "mhdev": "mhvar",
    "lvar": "lvar", "ldev": "lvar",
    "pvar": "pvar", "pdev": "pvar",
}

#: Statistics without an exact transfer function (refused).
NO_TRANSFER = ("totdev", "mtotdev", "ttotdev", "htotdev", "mhtotdev", "theo1", "theobr", "theoh")

# Exponents α for which ∫ f^α |H|² df converges at f → 0 (α > low); every
# kernel decays as f^-2 at high f, so α < 1 converges on [0, ∞).
_LOW = {"avar": -3, "mvar": -3, "tvar": -3, "pvar": -3, "hvar": -5, "mhvar": -5, "lvar": -5}
_NODES = np.polynomial.legendre.leggauss(24)


def _kind(stat: object) -> str:
    if not isinstance(stat, str):
        raise ParameterError(f"stat={stat!r} must be a statistic name such as 'oadev'")
    key = stat.lower()
    if key in NO_TRANSFER:
        raise ParameterError(
            f"stat={stat!r} has no exact transfer function (total/Theo estimators depend on the "
            "record length); convert with its parent ('oadev', 'mdev', 'ohdev') instead")
    if key not in KIND_OF_STAT:
        raise ParameterError(f"stat={stat!r} is unknown; choose one of {sorted(KIND_OF_STAT)}")
    return KIND_OF_STAT[key]


def _pvar_q(u: np.ndarray, v: np.ndarray, n: int) -> np.ndarray:
    # Σ_k ((n-1)/2 - k) e^{-2iθk} has modulus |dD/dθ| with D = sin(nθ)/sin(θ), θ = πτ0 f.
    c = (n * np.cos(u) * np.sin(v) - np.sin(u) * np.cos(v)) / (2.0 * np.sin(v) ** 2)
    return 72.0 * np.sin(u) ** 2 * c**2 / float(n) ** 4


def _q(kind: str, f: np.ndarray, tau: float, tau0: float) -> np.ndarray:
    """``f²·|H(f, τ)|²``: periodic in f with period 1/τ0."""
    n = int(round(tau / tau0))
    u, v = math.pi * tau * f, math.pi * tau0 * f
    base = 1.0 / (math.pi * tau) ** 2
    if kind == "avar" or (kind == "pvar" and n == 1):
        return 2.0 * np.sin(u) ** 4 * base
    if kind == "hvar":
        return 8.0 / 3.0 * np.sin(u) ** 6 * base
    if kind in ("mvar", "tvar"):
        out = 2.0 * np.sin(u) ** 6 * base / (n * np.sin(v)) ** 2
        return out * tau**2 / 3.0 if kind == "tvar" else out
    if kind in ("mhvar", "lvar"):
        out = 8.0 / 3.0 * np.sin(u) ** 8 * base / (n * np.sin(v)) ** 2
        return out * tau**2 * 0.3 if kind == "lvar" else out
    return _pvar_q(u, v, n) * base


def transfer_function(stat: str, f: object, tau: float, *, rate: float) -> np.ndarray:
    """Squared transfer function ``|H(f, τ)|²`` of a statistic, on fractional frequency.

    Parameters
    ----------
    stat : str
        Statistic or variance name: ``"oadev"``/``"avar"``, ``"mdev"``,
        ``"tdev"``, ``"ohdev"``/``"hdev"``, ``"mhdev"``, ``"ldev"``, ``"pdev"``.
    f : array_like
        Fourier frequencies in Hz (> 0).
    tau : float
        Averaging time, an integer multiple ``n`` of ``τ0 = 1/rate``.
    rate : float
        Sample rate of the phase samples.

    Returns
    -------
    numpy.ndarray
        ``|H|²`` such that ``σ²(τ) = ∫ S_y(f)|H(f,τ)|² df``.

    Notes
    -----
    With ``u = πτf``, ``v = πτ0 f`` (SP1065 §5.2; Vernotte et al. 2016 for PVAR):

    * AVAR ``2 sin⁴u/(πτf)²``; HVAR ``(8/3) sin⁶u/(πτf)²``;
    * MVAR ``2 sin⁶u/((πτf)² n² sin²v)``, TVAR = τ²/3·MVAR;
    * MHVAR ``(8/3) sin⁸u/((πτf)² n² sin²v)``, LVAR = τ²·MHVAR/(10/3);
    * PVAR ``72 sin²u·C²/(n⁴(πτf)²)``, ``C = (n cos u sin v − sin u cos v)/(2 sin²v)``
      (the ramp weights ``(n−1)/2 − k``; at n = 1 PVAR is taken as AVAR).

    Examples
    --------
    >>> float(transfer_function("oadev", [0.25], 2.0, rate=1.0)[0])  # 2/(π/2)²
    0.8105694691387022
    """
    kind = _kind(stat)
    rate, tau = _check_rate(rate), float(tau)
    _check_tau_multiple(np.array([tau]), rate)
    freq = np.asarray(f, dtype=float)
    if np.any(~np.isfinite(freq)) or np.any(freq <= 0):
        raise DataError("f must hold finite frequencies > 0")
    return _q(kind, freq, tau, 1.0 / rate) / freq**2


def _check_rate(rate: object) -> float:
    try:
        value = float(rate)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"rate={rate!r} must be a positive number (Hz)") from None
    if not math.isfinite(value) or value <= 0:
        raise ParameterError(f"rate={rate!r} must be a positive number (Hz)")
    return value


def _check_taus(taus: object, rate: float) -> np.ndarray:
    arr = np.atleast_1d(np.asarray(taus, dtype=float))
    if arr.ndim != 1 or arr.size == 0 or np.any(~np.isfinite(arr)) or np.any(arr <= 0):
        raise ParameterError(f"taus={taus!r} must be finite averaging times > 0")
    _check_tau_multiple(arr, rate)
    return arr


def _check_tau_multiple(taus: np.ndarray, rate: float) -> None:
    m = taus * rate
    if np.any(np.abs(m - np.round(m)) > 1e-9 * np.maximum(m, 1.0)) or np.any(np.round(m) < 1):
        raise ParameterError(f"taus must be integer multiples of tau0 = 1/rate = {1.0 / rate!r} s")


def _nodes(lo: float, hi: float, width: float) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes on [lo, hi] in pieces of ``width`` (half a period of sin πτf)."""
    x, w = _NODES
    edges = lo + width * np.arange(max(int(math.ceil((hi - lo) / width - 1e-9)), 1))
    right = np.minimum(edges + width, hi)
    half = (right - edges) / 2.0
    f = (edges[:, None] + half[:, None] * (x[None, :] + 1.0)).ravel()
    return f, (half[:, None] * w[None, :]).ravel()


# --- long τ: the middle of the band by its mean and end corrections -------------------------
#
# With n = τ/τ0 large, integrating every half period costs O(n) per τ. Away from f = 0 (and
# from f = 1/τ0) the integrand is a smooth envelope G(f) times a trigonometric polynomial in
# u = πτf, P(u) = P̄ + Σ_k a_k cos 2ku + b_k sin 2ku. Between half-period points A and B,
# by parts, ∫ G cos ωf df = [G1 cos ωf/ω² − G3 cos ωf/ω^4] and
# ∫ G sin ωf df = [−G cos ωf/ω + G2 cos ωf/ω³] (Gi the i-th derivative, ω = 2πkτ; the
# sin ωf terms vanish at those points), with a relative error ~ (_ENDS periods)^-5; the mean
# term ∫ G is smooth and takes few nodes.

_ENDS = 64           # periods of sin πτf integrated node by node at each end of the band
_DIRECT_MAX = 4096   # up to this many half periods every one gets its own panel

# Fourier series of the oscillating factors: (mean, {k: (a_k, b_k)}).
_SIN4 = (3 / 8, {1: (-1 / 2, 0.0), 2: (1 / 8, 0.0)})
_SIN6 = (5 / 16, {1: (-15 / 32, 0.0), 2: (3 / 16, 0.0), 3: (-1 / 32, 0.0)})
_SIN8 = (35 / 128, {1: (-7 / 16, 0.0), 2: (7 / 32, 0.0), 3: (-1 / 16, 0.0), 4: (1 / 128, 0.0)})
_SIN2COS2 = (1 / 8, {2: (-1 / 8, 0.0)})
_SIN3COS = (0.0, {1: (0.0, 1 / 4), 2: (0.0, -1 / 8)})

Envelope = Callable[[np.ndarray], np.ndarray]


def _split(kind: str, tau: float, tau0: float) -> list[tuple[Envelope, tuple]]:
    """``Q(f) = Σ_j E_j(f)·P_j(πτf)``: envelopes and series (the same kernels as :func:`_q`)."""
    n = int(round(tau / tau0))
    base = 1.0 / (math.pi * tau) ** 2

    def sin_v(f: np.ndarray) -> np.ndarray:
        return np.sin(math.pi * tau0 * f)

    if kind == "avar" or (kind == "pvar" and n == 1):
        return [(lambda f: np.full_like(f, 2.0 * base), _SIN4)]
    if kind == "hvar":
        return [(lambda f: np.full_like(f, 8.0 / 3.0 * base), _SIN6)]
    if kind in ("mvar", "tvar"):
        c = 2.0 * base * (tau**2 / 3.0 if kind == "tvar" else 1.0) / n**2
        return [(lambda f: c / sin_v(f) ** 2, _SIN6)]
    if kind in ("mhvar", "lvar"):
        c = 8.0 / 3.0 * base * (0.3 * tau**2 if kind == "lvar" else 1.0) / n**2
        return [(lambda f: c / sin_v(f) ** 2, _SIN8)]
    c = 72.0 * base / float(n) ** 4
    return [(lambda f: c * n**2 / (4.0 * sin_v(f) ** 2), _SIN2COS2),
            (lambda f: -c * n * np.cos(math.pi * tau0 * f) / (2.0 * sin_v(f) ** 3), _SIN3COS),
            (lambda f: c * np.cos(math.pi * tau0 * f) ** 2 / (4.0 * sin_v(f) ** 4), _SIN4)]


def _derivatives(g: Envelope, f0: float, h: float) -> tuple[float, float, float, float]:
    """G and its first three derivatives at f0 by central differences (steps ±h, ±2h)."""
    v = g(f0 + h * np.array([-2.0, -1.0, 0.0, 1.0, 2.0]))
    d1 = (v[0] - 8 * v[1] + 8 * v[3] - v[4]) / (12 * h)
    d2 = (-v[0] + 16 * v[1] - 30 * v[2] + 16 * v[3] - v[4]) / (12 * h * h)
    d3 = (-v[0] + 2 * v[1] - 2 * v[3] + v[4]) / (2 * h**3)
    return float(v[2]), float(d1), float(d2), float(d3)


def _panels(lo: float, hi: float, breaks: np.ndarray, pole: float) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes on [lo, hi] in panels growing by 1.25 away from lo and, when
    ``pole`` (> hi) is finite, away from it too; extra edges at ``breaks`` (table kinks)."""
    mid = hi if not math.isfinite(pole) else 0.5 * (lo + hi)
    edges = [lo * 1.25 ** np.arange(int(math.log(mid / lo) / math.log(1.25)) + 1)]
    if math.isfinite(pole):
        count = int(math.log((pole - mid) / (pole - hi)) / math.log(1.25)) + 1
        edges.append(pole - (pole - hi) * 1.25 ** np.arange(count))
    edges.append(np.array([lo, mid, hi]))
    edges.append(breaks[(breaks > lo) & (breaks < hi)])
    grid = np.unique(np.concatenate(edges))
    x, w = np.polynomial.legendre.leggauss(16)
    half = np.diff(grid) / 2.0
    f = (grid[:-1, None] + half[:, None] * (x[None, :] + 1.0)).ravel()
    return f, (half[:, None] * w[None, :]).ravel()


def _middle(kind: str, tau: float, tau0: float, weight: Envelope, j_lo: int, j_hi: int,
            pole: float, breaks: np.ndarray) -> float:
    """∫ Q·weight between the half-period points j_lo/(2τ) and j_hi/(2τ), n large."""
    lo, hi = j_lo / (2.0 * tau), j_hi / (2.0 * tau)
    f, w = _panels(lo, hi, breaks, pole)
    step = 0.05 * _ENDS / tau
    total = 0.0
    for envelope, (mean, series) in _split(kind, tau, tau0):
        def g(x: np.ndarray, e: Envelope = envelope) -> np.ndarray:
            return e(x) * weight(x)

        total += mean * float(np.sum(w * g(f)))
        ends = [(_derivatives(g, lo, step), j_lo, -1.0), (_derivatives(g, hi, step), j_hi, 1.0)]
        for k, (a, b) in series.items():
            om = 2.0 * math.pi * k * tau
            for (g0, g1, g2, g3), j, sign in ends:
                c = sign * (-1.0) ** (k * j % 2)  # ± cos ωf at f = j/(2τ)
                total += c * (a * (g1 / om**2 - g3 / om**4) + b * (-g0 / om + g2 / om**3))
    return total


def _integral(kind: str, tau: float, tau0: float, weight: Envelope, j_top: int, *,
              periodic: bool = False, breaks: Optional[np.ndarray] = None) -> float:
    """``∫_0^{j_top/(2τ)} Q(f)·weight(f) df``. ``periodic``: the band is one period [0, 1/τ0]
    of Q, whose end at 1/τ0 (where sin πτ0f vanishes) is integrated node by node too."""
    width = 1.0 / (2.0 * tau)
    if j_top <= _DIRECT_MAX:
        f, w = _nodes(0.0, j_top * width, width)
        return float(np.sum(w * _q(kind, f, tau, tau0) * weight(f)))
    ends = 2 * _ENDS
    f, w = _nodes(0.0, ends * width, width)
    total = float(np.sum(w * _q(kind, f, tau, tau0) * weight(f)))
    j_hi, pole = j_top, math.inf
    if periodic:
        j_hi, pole = j_top - ends, j_top * width
        f, w = _nodes(j_hi * width, j_top * width, width)
        total += float(np.sum(w * _q(kind, f, tau, tau0) * weight(f)))
    kinks = np.empty(0) if breaks is None else breaks
    return total + _middle(kind, tau, tau0, weight, ends, j_hi, pole, kinks)


def _power_term(kind: str, alpha: float, tau: float, tau0: float) -> float:
    """``∫ f^α |H|² df`` with the cut-off convention of ``powerlaw.response``."""
    n = int(round(tau / tau0))
    if alpha >= 1:
        return _integral(kind, tau, tau0, lambda f: f ** (alpha - 2.0), n)
    from scipy.special import zeta

    # Σ_k (f + k/τ0)^(α-2) = τ0^(2-α) ζ(2-α, fτ0): the whole [0, ∞) in one period of Q.
    return _integral(kind, tau, tau0, lambda f: tau0 ** (2.0 - alpha) * zeta(2.0 - alpha, f * tau0),
                     2 * n, periodic=True)


def _check_alpha(kind: str, alpha: object) -> float:
    try:
        a = float(alpha)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"alpha={alpha!r} must be a number") from None
    if not (_LOW[kind] < a <= 2):
        raise ParameterError(f"alpha={alpha!r}: {kind} converges only for {_LOW[kind]} < alpha <= 2")
    return a


@dataclass(frozen=True)
class SigmaFromSpectrum:
    """σ(τ) computed from a spectrum: ``stat``, ``taus`` (s), ``var`` and ``dev``."""

    stat: str
    taus: np.ndarray
    var: np.ndarray

    @property
    def dev(self) -> np.ndarray:
        """Deviation ``sqrt(var)``."""
        return np.sqrt(self.var)

    def to_dict(self) -> dict:
        """Plain lists, for tables."""
        return {"stat": self.stat, "tau": self.taus.tolist(), "var": self.var.tolist(),
                "dev": self.dev.tolist()}

    def __repr__(self) -> str:
        return f"SigmaFromSpectrum(stat={self.stat!r}, {self.taus.size} taus)"


SpectrumType = Literal["s_y", "s_x", "s_phi", "L"]
_TYPES = ("s_y", "s_x", "s_phi", "L")


def _as_table(spectrum: object, spectrum_type: str,
              carrier: Optional[float]) -> tuple[np.ndarray, np.ndarray]:
    """(f, S_y) from a PsdResult, or from (f, values) of the given type."""
    if hasattr(spectrum, "f") and hasattr(spectrum, "s_y"):
        f, s = np.asarray(spectrum.f, float), np.asarray(spectrum.s_y, float)  # type: ignore[attr-defined]
        spectrum_type = "s_y"
    else:
        try:
            f, s = (np.asarray(a, dtype=float) for a in spectrum)  # type: ignore[union-attr]
        except (TypeError, ValueError):
            raise DataError("spectrum must be a PsdResult, {alpha: h_alpha} or a pair (f, values)") from None
    if f.ndim != 1 or f.shape != s.shape or f.size < 2:
        raise DataError(f"spectrum f and values must be 1-D of equal length >= 2, "
                        f"got {f.shape} and {s.shape}")
    if np.any(~np.isfinite(f)) or np.any(~np.isfinite(s)) or np.any(f <= 0) or np.any(np.diff(f) <= 0):
        raise DataError("spectrum f must be finite, > 0 and increasing, with finite values")
    s_y = to_s_y(f, s, spectrum_type=spectrum_type, carrier=carrier)
    if np.any(s_y < 0):
        raise DataError("spectrum values must be >= 0")
    return f, s_y


def _loglog(f_new: np.ndarray, f: np.ndarray, s: np.ndarray) -> np.ndarray:
    """S at f_new: log-log interpolation (linear where S has zeros), flat outside [f[0], f[-1]]."""
    if np.all(s > 0):
        out = np.exp(np.interp(np.log(f_new), np.log(f), np.log(s)))
    else:
        out = np.interp(f_new, f, s)
    return np.where(f_new < f[0], s[0], out)


#: τ·f_min above which over ~1 % of a white-FM AVAR comes from below the table (≈ 4π²(τf)³/3).
_LOW_END = 0.1


def _warn_low_end(taus: np.ndarray, f_min: float, modelled: bool) -> None:
    worst = float(np.max(taus)) * f_min
    if worst > _LOW_END:
        how = "its fitted power law" if modelled else "its lowest value held flat"
        warnings.warn(f"tau up to {float(np.max(taus)):.4g} s needs the spectrum below its lowest frequency "
                      f"{f_min:.4g} Hz (tau*f_min = {worst:.3g} > {_LOW_END}); it is continued by {how}",
                      RangeWarning, stacklevel=caller_stacklevel())


def _fitted_model(spectrum: object) -> Optional[Callable[[np.ndarray], np.ndarray]]:
    """A PsdResult's fitted power law, used below its lowest bin (None if it has no fit)."""
    h = getattr(spectrum, "h", None)
    if not h or not any(v > 0 for v in h.values()):
        return None
    return spectrum.model  # type: ignore[attr-defined]


def _table_variance(kind: str, f: np.ndarray, s: np.ndarray, tau: float, tau0: float, samples: bool,
                    below: Optional[Callable[[np.ndarray], np.ndarray]] = None) -> float:
    def spectrum(nodes: np.ndarray) -> np.ndarray:
        out = _loglog(nodes, f, s)
        if below is not None:
            low = nodes < f[0]
            out[low] = below(nodes[low])
        return out

    if samples:
        # Spectrum of the τ0-averaged frequency samples: S_ȳ = S_y·sinc²(πτ0f) on [0, f_h],
        # so the kernel on it is |H|²/sinc², exact in discrete time (no aliasing term).
        def sample_weight(x: np.ndarray) -> np.ndarray:
            return spectrum(x) * (math.pi * tau0 / np.sin(math.pi * tau0 * x)) ** 2

        return _integral(kind, tau, tau0, sample_weight, int(round(tau / tau0)), breaks=f)

    def weight(x: np.ndarray) -> np.ndarray:
        return spectrum(x) / x**2

    j_top = int(math.floor(2.0 * tau * float(f[-1]) + 1e-9))
    total = _integral(kind, tau, tau0, weight, j_top, breaks=f) if j_top > 0 else 0.0
    nodes, w = _nodes(j_top / (2.0 * tau), float(f[-1]), 1.0 / (2.0 * tau))
    return total + float(np.sum(w * _q(kind, nodes, tau, tau0) * weight(nodes)))


def spectrum_to_sigma(
    spectrum: object, taus: object, *, stat: str = "oadev", rate: Optional[float] = None,
    spectrum_type: SpectrumType = "s_y", carrier: Optional[float] = None,
    samples: Optional[bool] = None,
) -> SigmaFromSpectrum:
    """Expected σ(τ) of a statistic for a given one-sided spectrum.

    Parameters
    ----------
    spectrum : PsdResult, mapping, PowerLawFit or pair of arrays
        ``{α: h_α}`` power-law coefficients of ``S_y(f) = Σ h_α f^α`` (or a
        :func:`sigma_to_powerlaw` fit holding them); a
        :class:`~sigmatau.spectral.PsdResult`; or ``(f, values)`` with values of
        ``spectrum_type``.
    taus : array_like
        Averaging times in s, integer multiples of ``1/rate``.
    stat : str
        Statistic (see :data:`KIND_OF_STAT`); total and Theo families are refused.
    rate : float, optional
        Sample rate (Hz) of the estimator: sets τ0 and, for power laws,
        ``f_h = rate/2``. Required for power laws; for a table it defaults to
        twice its highest frequency (or the PsdResult's rate).
    spectrum_type : {"s_y", "s_x", "s_phi", "L"}
        What a table holds: ``S_y`` (1/Hz), ``S_x`` (s²/Hz), ``S_φ`` (rad²/Hz) or
        ``L(f)`` (dBc/Hz); the last two need ``carrier``.
    carrier : float, optional
        Carrier frequency ν0 (Hz) for ``S_φ`` and ``L(f)``.
    samples : bool, optional
        Whether a table is the spectrum of the record's frequency *samples*
        (τ0 averages, as :func:`~sigmatau.spectral.psd` measures: True by
        default for a PsdResult) or of the continuous process (False by default
        for arrays, e.g. an oscillator's L(f)).

    Returns
    -------
    SigmaFromSpectrum

    Notes
    -----
    ``σ²(τ) = ∫ S_y(f)|H(f,τ)|² df`` (:func:`transfer_function`). A power-law
    term ``h_α f^α`` is integrated over [0, f_h] for α ≥ 1 and over [0, ∞)
    otherwise, which reproduces :func:`sigmatau.core.powerlaw.response` to
    rounding wherever that table is exact (AVAR, HVAR at α ≠ 1; MVAR/TVAR at
    α = 2 and at α = 0 with ``sampled=True``); where the table gives the
    large-τ limit (α = 1, and MVAR/TVAR at α ≤ 0) the difference falls as
    1/n². A table is integrated over [0, f_max] after log-log interpolation,
    taken flat beyond its ends: a process spectrum over [0, f_max] of the
    table with ``|H|²``; a spectrum of frequency samples over [0, rate/2] with
    ``|H|²/sinc²(πτ0f)``, because averaging over τ0 multiplied the process
    spectrum by ``sinc²(πτ0f)``.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2, Table 9.

    Examples
    --------
    >>> r = spectrum_to_sigma({0: 2e-20}, [1.0, 10.0], stat="oadev", rate=1.0)
    >>> [round(float(v) / 1e-20, 12) for v in r.var]  # h0/(2τ)
    [1.0, 0.1]
    """
    kind = _kind(stat)
    if not hasattr(spectrum, "s_y") and isinstance(getattr(spectrum, "h", None), Mapping):
        spectrum = dict(spectrum.h)  # type: ignore[attr-defined]  # a PowerLawFit
    if isinstance(spectrum, Mapping):
        if rate is None:
            raise ParameterError("rate is required with power-law coefficients (f_h = rate/2)")
        rate_v = _check_rate(rate)
        t = _check_taus(taus, rate_v)
        terms = {_check_alpha(kind, a): _check_h(h, a) for a, h in spectrum.items()}
        if not terms:
            raise DataError("spectrum holds no power-law term")
        var = np.array([sum(h * _power_term(kind, a, tau, 1.0 / rate_v) for a, h in terms.items())
                        for tau in t])
        return SigmaFromSpectrum(stat, t, var)
    if spectrum_type not in _TYPES:
        raise ParameterError(f"spectrum_type={spectrum_type!r} must be one of {_TYPES}")
    f, s = _as_table(spectrum, spectrum_type, carrier)
    if samples is None:
        samples = hasattr(spectrum, "s_y")
    if rate is None:
        rate = getattr(spectrum, "rate", None) or 2.0 * float(f[-1])
    rate_v = _check_rate(rate)
    t = _check_taus(taus, rate_v)
    below = _fitted_model(spectrum)
    _warn_low_end(t, float(f[0]), below is not None)
    var = np.array([_table_variance(kind, f, s, tau, 1.0 / rate_v, bool(samples), below) for tau in t])
    return SigmaFromSpectrum(stat, t, var)


def _check_h(h: object, alpha: object) -> float:
    try:
        value = float(h)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"h for alpha={alpha!r} must be a number, got {h!r}") from None
    if not math.isfinite(value) or value < 0:
        raise ParameterError(f"h for alpha={alpha!r} must be finite and >= 0, got {h!r}")
    return value


@dataclass(frozen=True)
class HFromSigma:
    """``h_α`` of ``S_y = h_α f^α`` fitted to σ(τ) in one power-law region."""

    alpha: int
    h: float
    per_tau: np.ndarray

    def __repr__(self) -> str:
        return f"HFromSigma(alpha={self.alpha}, h={self.h:.4g}, {self.per_tau.size} taus)"


#: Kinds with SP1065 Table 9 expectations in ``powerlaw.response``.
_RESPONSE_KINDS = ("avar", "mvar", "tvar", "hvar")


def sigma_to_h(
    taus: object, devs: object, *, alpha: int, stat: str = "oadev", rate: float = 1.0,
    sampled: bool = False,
) -> HFromSigma:
    """Power-law coefficient ``h_α`` from deviations measured in one noise region.

    Parameters
    ----------
    taus, devs : array_like
        Averaging times (s) and deviations of ``stat`` where one noise type α dominates.
    alpha : int
        The noise type of that region, α ∈ {2, 1, 0, −1, −2} (−3, −4 for Hadamard).
    stat : str
        ``"oadev"``/``"adev"``, ``"mdev"``, ``"tdev"`` or ``"ohdev"``/``"hdev"``.
    rate : float
        Sample rate (Hz), for the f_h of α = 2, 1.
    sampled : bool
        Passed to :func:`sigmatau.core.powerlaw.response` (MVAR at α = 0).

    Returns
    -------
    HFromSigma
        ``h`` is the geometric mean of ``h_i = σ_i²/R_α(τ_i)``, R the unit-h
        response; ``per_tau`` holds the ``h_i``.

    Notes
    -----
    This inverts SP1065 Table 9 (``σ² = h_α·R_α(τ)``) region by region; the
    spectrum it gives is a power-law model, not a measured spectrum.

    Examples
    --------
    >>> round(sigma_to_h([1.0, 4.0], [1e-10, 5e-11], alpha=0).h, 30)  # h0 = 2τσ²
    2e-20
    """
    kind = _kind(stat)
    if kind not in _RESPONSE_KINDS:
        raise ParameterError(f"stat={stat!r}: sigma_to_h supports adev/oadev, mdev, tdev, hdev/ohdev")
    rate_v = _check_rate(rate)
    t = np.atleast_1d(np.asarray(taus, dtype=float))
    d = np.atleast_1d(np.asarray(devs, dtype=float))
    if t.shape != d.shape or t.ndim != 1 or t.size == 0:
        raise DataError(f"taus and devs must be 1-D of equal length, got {t.shape} and {d.shape}")
    if np.any(~np.isfinite(d)) or np.any(d <= 0) or np.any(~np.isfinite(t)) or np.any(t <= 0):
        raise DataError("taus and devs must be finite and > 0")
    try:
        unit = response(kind, int(alpha), t, rate_v, sampled=sampled)
    except KeyError:
        raise ParameterError(f"alpha={alpha!r} is not a power law {stat} converges for") from None
    per = d**2 / unit
    return HFromSigma(int(alpha), float(np.exp(np.mean(np.log(per)))), per)



def sigma_to_powerlaw(result: object, **fit_options: object) -> object:
    """Power-law spectrum ``S_y = Σ h_α f^α`` fitted to a whole σ(τ) curve.

    Parameters
    ----------
    result : StabilityResult
        An ``adev``, ``oadev``, ``mdev``, ``tdev``, ``hdev`` or ``ohdev`` result.
    **fit_options
        Passed to :func:`sigmatau.fit_power_law` (``alphas``, ``edf``,
        ``min_significance``, ``tau_correlation``).

    Returns
    -------
    PowerLawFit
        Its ``h`` (``{α: h_α}``) is the spectrum; :func:`spectrum_to_sigma`
        accepts the fit itself.

    Notes
    -----
    SP1065 Table 9 inverted over all τ at once (non-negative least squares of
    ``σ² = Σ h_α R_α(τ)``, :func:`sigmatau.fit_power_law`), so each noise
    region sets its own ``h_α`` while the overlaps of regions are shared. The
    spectrum is a model made of the terms the curve shows, not a measured one.
    """
    from ..uncertainty.noiseid import fit_power_law

    return fit_power_law(result, **fit_options)  # type: ignore[arg-type]
