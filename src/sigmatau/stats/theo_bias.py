"""Theo1's bias against the Allan variance and its correction (``bias="published"``).

Theo1 equals AVAR on average for white FM only; for the other noise types the
ratio AVAR/Theo1 depends on the noise type and the averaging factor (Howe &
Tasset 2004, Table 1, as SP1065 and the Stable32 manual give it; numerics.md
§3). Used by :func:`sigmatau.stats.theo.theo1`.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Optional

import numpy as np

from ..errors import ParameterError
from ..core.result import StabilityResult

__all__: list[str] = []


#: ``AVAR/Theo1 = a + b/t^c`` at ``t = 0.75·m`` (τ/τ0), by noise exponent α: Howe & Tasset
#: 2004, Table 1 (as SP1065 and the Stable32 manual give it); numerics.md §3, checked there by
#: Monte Carlo at N = 513 (WPM/FPM within 2 %, WFM 1 %, FFM/RWFM ~7 %).
_THEO1_BIAS = {2: (0.09, 0.74, 0.40), 1: (0.14, 0.82, 0.30), 0: (1.0, 0.0, 0.0),
               -1: (1.87, -1.05, 0.79), -2: (2.70, -1.53, 0.85)}

_THEO_BIAS_MODES = ("none", "published", "auto")


def _check_theo1_bias(bias: object, alpha: Optional[int]) -> str:
    """Validate ``bias`` and a forced ``alpha`` against the table before computing."""
    if not isinstance(bias, str) or bias not in _THEO_BIAS_MODES:
        raise ParameterError(f"bias={bias!r} must be one of {_THEO_BIAS_MODES}")
    if bias != "none" and alpha is not None and alpha not in _THEO1_BIAS:
        raise ParameterError(
            f"theo1: no published bias factor for alpha={alpha}; allowed: 2, 1, 0, -1, -2"
        )
    return bias


def _theo1_avar_ratio(alphas: np.ndarray, ms: np.ndarray) -> np.ndarray:
    """``a + b/(0.75 m)^c`` per row; NaN where the row's α has no entry."""
    out = np.full(ms.size, np.nan)
    for k, (a_k, m_k) in enumerate(zip(alphas, ms)):
        if np.isfinite(a_k) and int(a_k) in _THEO1_BIAS:
            a, b, c = _THEO1_BIAS[int(a_k)]
            out[k] = a + b / (0.75 * float(m_k)) ** c
    return out


def _apply_theo1_bias(res: StabilityResult, bias: str, forced: Optional[int]) -> StabilityResult:
    """Multiply each row's variance by AVAR/Theo1 for its noise type (``res.alpha``)."""
    alphas = res.alpha if res.alpha is not None else np.full(res.m.size, np.nan)
    ratio = _theo1_avar_ratio(np.asarray(alphas, dtype=float), res.m)
    missing = ~np.isfinite(ratio)
    # bias_factor is the divisor applied to raw Theo1 (Theo1/AVAR), as for TheoBR (1/κ).
    factor = np.where(missing, 1.0, 1.0 / np.where(missing, 1.0, ratio))
    var = res.var / factor
    # A fixed divisor scales a χ² interval exactly as it scales the estimate.
    scaled = {f: getattr(res, f) / np.sqrt(factor) for f in ("ci_low", "ci_high") if getattr(res, f) is not None}
    desc = f"published alpha={forced}" if forced is not None else "published at the alpha identified per tau"
    if missing.any():
        desc += f" (uncorrected at {int(missing.sum())} tau whose alpha has no factor)"
    return replace(res, var=var, dev=np.sqrt(var), bias=desc, bias_factor=factor, **scaled)
