"""The IEEE 952 / IEEE 1293 noise model of gyroscopes and accelerometers.

What it holds: the model and its terms (``model``), units and conversions
(``units``), data checks (``checks``). What it may import: the statistics,
uncertainty, noise and core layers; never I/O, reports, the scale-out layer or
the CLI. The public API is re-exported here (``sigmatau.imu.*``).
"""

from .model import *  # noqa: F401,F403
from .model import __all__  # noqa: F401
