"""Phase-noise units and rms time jitter from L(f).

The one-sided spectra of one oscillator at carrier ν0 are related by
(IEEE Std 1139-2008; NIST SP 1065 §3):

.. math:: \\mathcal{L}(f) = S_φ(f)/2, \\quad S_x(f) = \\frac{S_φ(f)}{(2πν_0)^2}, \\quad
          S_y(f) = (2πf)^2 S_x(f),

with ``L`` quoted in dBc/Hz (``10·log10``). The rms time jitter over a band is

.. math:: J = \\frac{\\sqrt{2\\int_{f_1}^{f_2} 10^{\\mathcal{L}(f)/10} df}}{2πν_0}.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..errors import DataError, ParameterError

__all__ = [
    "dbc_to_s_phi", "s_phi_to_dbc", "s_phi_to_s_x", "s_x_to_s_phi", "s_x_to_s_y", "s_y_to_s_x",
    "to_s_y", "rms_jitter", "JitterResult",
]


def _positive(value: object, name: str) -> float:
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={value!r} must be a positive number") from None
    if not math.isfinite(v) or v <= 0:
        raise ParameterError(f"{name}={value!r} must be a positive number")
    return v


def _finite(a: object, name: str) -> np.ndarray:
    arr = np.asarray(a, dtype=float)
    if np.any(~np.isfinite(arr)):
        raise DataError(f"{name} holds NaN or infinite values")
    return arr


def dbc_to_s_phi(l_dbc: object) -> np.ndarray:
    """``S_φ = 2·10^(L/10)`` (rad²/Hz) from ``L(f)`` in dBc/Hz.

    >>> float(dbc_to_s_phi(-100.0))
    2e-10
    """
    return 2.0 * 10.0 ** (_finite(l_dbc, "l_dbc") / 10.0)


def s_phi_to_dbc(s_phi: object) -> np.ndarray:
    """``L(f) = 10·log10(S_φ/2)`` in dBc/Hz (S_φ > 0)."""
    s = _finite(s_phi, "s_phi")
    if np.any(s <= 0):
        raise DataError("s_phi must be > 0 to be expressed in dBc/Hz")
    return 10.0 * np.log10(s / 2.0)


def s_phi_to_s_x(s_phi: object, *, carrier: float) -> np.ndarray:
    """``S_x = S_φ/(2πν0)²`` (s²/Hz)."""
    return _finite(s_phi, "s_phi") / (2.0 * math.pi * _positive(carrier, "carrier")) ** 2


def s_x_to_s_phi(s_x: object, *, carrier: float) -> np.ndarray:
    """``S_φ = (2πν0)² S_x`` (rad²/Hz)."""
    return _finite(s_x, "s_x") * (2.0 * math.pi * _positive(carrier, "carrier")) ** 2


def s_x_to_s_y(f: object, s_x: object) -> np.ndarray:
    """``S_y = (2πf)² S_x`` (1/Hz)."""
    return (2.0 * math.pi * _finite(f, "f")) ** 2 * _finite(s_x, "s_x")


def s_y_to_s_x(f: object, s_y: object) -> np.ndarray:
    """``S_x = S_y/(2πf)²`` (s²/Hz), f > 0."""
    freq = _finite(f, "f")
    if np.any(freq <= 0):
        raise DataError("f must be > 0 to convert S_y to S_x")
    return _finite(s_y, "s_y") / (2.0 * math.pi * freq) ** 2


def to_s_y(f: np.ndarray, values: np.ndarray, *, spectrum_type: str = "s_y",
           carrier: Optional[float] = None) -> np.ndarray:
    """``S_y`` from a table of ``spectrum_type`` ∈ {"s_y", "s_x", "s_phi", "L"}."""
    if spectrum_type == "s_y":
        return _finite(values, "values")
    if spectrum_type == "s_x":
        return s_x_to_s_y(f, values)
    if spectrum_type not in ("s_phi", "L"):
        raise ParameterError(f"spectrum_type={spectrum_type!r} must be 's_y', 's_x', 's_phi' or 'L'")
    if carrier is None:
        raise ParameterError(f"spectrum_type={spectrum_type!r} needs carrier (Hz)")
    s_phi = dbc_to_s_phi(values) if spectrum_type == "L" else _finite(values, "values")
    return s_x_to_s_y(f, s_phi_to_s_x(s_phi, carrier=carrier))


@dataclass(frozen=True)
class JitterResult:
    """rms time jitter ``jitter`` (s) and phase ``phase_rms`` (rad) over ``band`` (Hz)."""

    jitter: float
    phase_rms: float
    band: tuple[float, float]
    carrier: float

    def __repr__(self) -> str:
        return f"JitterResult(jitter={self.jitter:.4g} s, band={self.band})"


def _segment_integrals(f: np.ndarray, s: np.ndarray) -> np.ndarray:
    """∫ of the power law through each pair of points (exact for piecewise power laws)."""
    ratio = f[1:] / f[:-1]
    b = np.log(s[1:] / s[:-1]) / np.log(ratio)
    out = np.empty(b.size)
    near = np.abs(b + 1.0) < 1e-12
    out[near] = s[:-1][near] * f[:-1][near] * np.log(ratio[near])
    bb = b[~near] + 1.0
    out[~near] = s[:-1][~near] * f[:-1][~near] * np.expm1(bb * np.log(ratio[~near])) / bb
    return out


def rms_jitter(f: object, l_dbc: object, *, carrier: float, band: Optional[tuple[float, float]] = None
               ) -> JitterResult:
    """rms time jitter from a phase-noise table ``L(f)`` in dBc/Hz.

    Parameters
    ----------
    f : array_like
        Offset frequencies (Hz), increasing, > 0.
    l_dbc : array_like
        ``L(f)`` in dBc/Hz at ``f``; interpolated linearly in dB against log f
        (a power law between points).
    carrier : float
        Carrier frequency ν0 (Hz).
    band : (f1, f2), optional
        Integration band inside the table's range; the whole table by default.

    Returns
    -------
    JitterResult

    Notes
    -----
    ``J = sqrt(2∫_{f1}^{f2} 10^{L(f)/10} df)/(2πν0)``; each segment is
    integrated in closed form as a power law, so a piecewise-straight L(f) on a
    log axis is integrated exactly.

    Examples
    --------
    >>> r = rms_jitter([10.0, 1e6], [-150.0, -150.0], carrier=100e6)
    >>> round(r.jitter * 1e15, 6)  # fs
    71.175898
    """
    freq = _finite(f, "f")
    level = _finite(l_dbc, "l_dbc")
    if freq.ndim != 1 or freq.shape != level.shape or freq.size < 2:
        raise DataError(f"f and l_dbc must be 1-D of equal length >= 2, got {freq.shape} and {level.shape}")
    if np.any(freq <= 0) or np.any(np.diff(freq) <= 0):
        raise DataError("f must be > 0 and strictly increasing")
    nu0 = _positive(carrier, "carrier")
    lo, hi = (float(freq[0]), float(freq[-1])) if band is None else (float(band[0]), float(band[1]))
    if not (freq[0] <= lo < hi <= freq[-1]):
        raise ParameterError(f"band=({lo!r}, {hi!r}) must satisfy {freq[0]!r} <= f1 < f2 <= {freq[-1]!r}")
    # L is linear in log f: cut the table at the band edges before integrating.
    ll = np.interp(np.log([lo, hi]), np.log(freq), level)
    inside = (freq > lo) & (freq < hi)
    fb = np.concatenate(([lo], freq[inside], [hi]))
    lb = np.concatenate(([ll[0]], level[inside], [ll[1]]))
    integral = float(np.sum(_segment_integrals(fb, 10.0 ** (lb / 10.0))))
    phase = math.sqrt(2.0 * integral)
    return JitterResult(phase / (2.0 * math.pi * nu0), phase, (lo, hi), nu0)
