"""Writing an analysis: results.json, CSV, imu.yaml, figures, report.html.

Public entry point, kept at this path for users; the implementation lives in
:mod:`sigmatau.report.outputs`.
"""

from .report.outputs import *  # noqa: F401,F403
from .report.outputs import __all__  # noqa: F401
from .report.directory import umask  # noqa: F401  (public before the split, outside __all__)
from .report.formats import FORMULA_TRIGGERS  # noqa: F401
