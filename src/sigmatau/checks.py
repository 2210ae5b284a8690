"""Data checks that change the answer (quantisation, saturation, decimation).

Public entry point, kept at this path for users; the implementation lives in
:mod:`sigmatau.imu.checks`.
"""

from .imu.checks import *  # noqa: F401,F403
from .imu.checks import __all__  # noqa: F401
