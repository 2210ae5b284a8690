"""Figures: σ–τ curves per group, the design tip's Figure 2, signals (extra ``plot``: matplotlib).

Public entry point, kept at this path for users; the implementation lives in
:mod:`sigmatau.report.plots`.
"""

from .report.plots import *  # noqa: F401,F403
from .report.plots import __all__  # noqa: F401
