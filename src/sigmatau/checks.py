"""Data checks that change the answer (quantisation, saturation, decimation, stuck values, timestamps).

Public entry point, kept at this path for users; the implementation lives in
:mod:`sigmatau.imu.checks` and :mod:`sigmatau.imu.timestamps`.
"""

from .imu import checks as _checks
from .imu import timestamps as _timestamps
from .imu.checks import *  # noqa: F401,F403
from .imu.timestamps import *  # noqa: F401,F403

__all__ = [*_checks.__all__, *_timestamps.__all__]
