"""Expected variances of the power-law noise model (numerics.md §6.3).

One table shared by noise generation (:mod:`sigmatau.generate`) and the
power-law fit (:mod:`sigmatau.noiseid`): the variance each statistic family
gives for one-sided ``S_y(f) = f^α`` (unit ``h_α``), continuous model with a
sharp cut-off ``f_h = rate/2`` (constants re-derived by exact integration;
W. J. Riley, NIST SP 1065 (2008) §5.2, Table 9).
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

__all__ = ["EULER_GAMMA", "KINDS", "response"]

EULER_GAMMA = 0.57721566490153286

#: Variance kinds: AVAR (adev, oadev), MVAR (mdev), TVAR (tdev), HVAR (hdev, ohdev).
KINDS = ("avar", "mvar", "tvar", "hvar")


def _table(kind: str, rate: float, sampled: bool) -> dict[int, Callable[[np.ndarray], np.ndarray]]:
    pi2 = math.pi**2
    f_h = rate / 2.0
    tau0 = 1.0 / rate
    g, ln2, ln3 = EULER_GAMMA, math.log(2.0), math.log(3.0)
    if kind == "avar":
        return {
            2: lambda t: 3.0 * f_h / (4.0 * pi2 * t**2),
            1: lambda t: (3.0 * g - ln2 + 3.0 * np.log(2.0 * math.pi * f_h * t)) / (4.0 * pi2 * t**2),
            0: lambda t: 1.0 / (2.0 * t),
            -1: lambda t: np.full_like(t, 2.0 * ln2),
            -2: lambda t: 2.0 * pi2 / 3.0 * t,
        }
    if kind in ("mvar", "tvar"):
        return {
            # exact for discrete white PM: 3σ_x²/(nτ²), σ_x² = h2 f_h/(4π²)
            2: lambda t: 3.0 * f_h * tau0 / (4.0 * pi2 * t**3),
            1: lambda t: 3.0 * math.log(256.0 / 27.0) / (8.0 * pi2 * t**2),
            # sampled: exact for τ0-averaged white FM, h0/(4τ)·(1 + 1/m²) (→ AVAR at m = 1);
            # otherwise the published large-m limit h0/(4τ)
            0: (lambda t: (1.0 + (tau0 / t) ** 2) / (4.0 * t)) if sampled else (lambda t: 1.0 / (4.0 * t)),
            -1: lambda t: np.full_like(t, 27.0 / 8.0 * ln3 - 4.0 * ln2),
            -2: lambda t: 11.0 * pi2 / 20.0 * t,
        }
    return {
        2: lambda t: 5.0 * f_h / (6.0 * pi2 * t**2),
        1: lambda t: (10.0 * g - 6.0 * ln2 + ln3 + 10.0 * np.log(2.0 * math.pi * f_h * t)) / (12.0 * pi2 * t**2),
        0: lambda t: 1.0 / (2.0 * t),
        -1: lambda t: np.full_like(t, 4.0 * ln2 - 1.5 * ln3),
        -2: lambda t: pi2 / 3.0 * t,
        -3: lambda t: pi2 / 6.0 * (27.0 * ln3 - 32.0 * ln2) * t**2,
        -4: lambda t: 11.0 * pi2**2 / 15.0 * t**3,
    }


def response(kind: str, alpha: int, tau: np.ndarray, rate: float, *, sampled: bool = False) -> np.ndarray:
    """Variance of kind ``kind`` for ``S_y = f^α`` at averaging times ``tau``.

    Raises ``KeyError`` for an α the kind does not converge for (callers check
    and raise their own ParameterError). TVAR is MVAR·τ²/3.
    """
    out = _table(kind, rate, sampled)[alpha](tau)
    return out * tau**2 / 3.0 if kind == "tvar" else out
