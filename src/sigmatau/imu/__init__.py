"""The IEEE 952 / IEEE 1293 noise model of gyroscopes and accelerometers.

What it holds: the public face of the model (``model``, re-exported here as
``sigmatau.imu.*``) and its parts — the terms and their constants (``terms``),
the result types (``results``, ``noisemodel``), part presets (``presets``),
simulation (``simulation``), read-offs (``readoffs``), the weighted fit and its
intervals (``fitting``), the first-order Gauss–Markov term chosen against the five
terms by BIC (``gaussmarkov``), ``analyze`` itself (``extraction``), the design tip's
answers (``answers``), Kalibr values (``kalibr``), how long a record must still run
(``advice``, with its forecast of the fit on a longer record in ``forecast``); units and conversions
(``units``); data checks of samples (``checks``) and timestamps
(``timestamps``). What it may import: the statistics, uncertainty, noise and
core layers; never I/O, reports, the scale-out layer or the CLI.
"""

from .model import *  # noqa: F401,F403
from .model import __all__  # noqa: F401
from .model import DEVIATION_RANGE  # noqa: F401  (public before the split, outside __all__)
# Names the single module imu.py had in its namespace before the split (issue 12); kept so
# that code written against them (``sigmatau.imu.convert``, ``sigmatau.imu.check_samples``) runs.
from ..core.result import StabilityResult  # noqa: E402,F401
from ..noise.generate import octave_flicker, power_law_noise  # noqa: E402,F401
from ..stats.allan import oadev  # noqa: E402,F401
from ..uncertainty.confidence import ONE_SIGMA, deviation_interval, edf_array  # noqa: E402,F401
from .checks import DataChecks, check_samples  # noqa: E402,F401
from .units import CUSTOMARY, TERMS, SensorUnit, convert, pretty, sensor_unit, term_unit  # noqa: E402,F401
