"""Uncertainty of a statistic: noise identification, EDF and confidence intervals.

Holds the EDF models and χ² intervals (``confidence``), noise identification by
lag-1 autocorrelation, B1 and R(n), local slopes and power-law fits
(``noiseid``), and the step that attaches noise type, EDF and interval to a raw
result (``attach``). May import: :mod:`sigmatau.core` and :mod:`sigmatau.errors`.
"""
