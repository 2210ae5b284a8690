"""sigmatau: noise analysis of sensors with the Allan family of variances.

The public API is re-exported here explicitly; see ``__all__``.
"""

from __future__ import annotations

from ._input import frequency_to_phase, phase_to_frequency
from ._version import __version__
from .allan import adev, mdev, oadev, ostdev, stdev, tdev
from .errors import DataError, ParameterError, RangeWarning, SigmaTauError, SigmaTauWarning
from .hadamard import hdev, ohdev
from .result import StabilityResult

__all__ = [
    "__version__",
    # statistics
    "stdev", "ostdev", "adev", "oadev", "mdev", "tdev", "hdev", "ohdev",
    # types and errors
    "StabilityResult", "SigmaTauError", "ParameterError", "DataError",
    "SigmaTauWarning", "RangeWarning",
    # conversions
    "frequency_to_phase", "phase_to_frequency",
]
