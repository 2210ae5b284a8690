"""Noise identification: lag-1 autocorrelation, B1, R(n), slopes, power-law fit.

Public entry point, kept at this path for users; the implementation lives in
:mod:`sigmatau.uncertainty.noiseid`.
"""

from .uncertainty.noiseid import *  # noqa: F401,F403
from .uncertainty.noiseid import __all__  # noqa: F401
from .uncertainty.lag1 import LAG1_MIN_POINTS  # noqa: F401  (public before the split, outside __all__)
from .uncertainty.noisebase import Family  # noqa: F401
