"""Unit parsing and SI / customary / Kalibr conversions.

Public entry point, kept at this path for users; the implementation lives in
:mod:`sigmatau.imu.units`.
"""

from .imu.units import *  # noqa: F401,F403
from .imu.units import __all__  # noqa: F401
from .imu.units import Kind, Term, pretty  # noqa: F401  (public before the split, outside __all__)
