"""Equivalent degrees of freedom and confidence intervals.

Public entry point, kept at this path for users; the implementation lives in
:mod:`sigmatau.uncertainty.confidence`.
"""

from .uncertainty.confidence import *  # noqa: F401,F403
from .uncertainty.confidence import __all__  # noqa: F401
from .uncertainty.confidence import Sided  # noqa: F401  (public before the split, outside __all__)
from .uncertainty.edfchecks import Version  # noqa: F401
