"""The main job on a sensor log (what ``sigmatau analyze`` runs).

Public entry point, kept at this path for users; the implementation lives in
:mod:`sigmatau.pipeline.analysis`.
"""

from .pipeline.analysis import *  # noqa: F401,F403
from .pipeline.analysis import __all__  # noqa: F401
from .pipeline.analysis import Reference  # noqa: F401  (public before the split, outside __all__)
from .pipeline.results import IMU_GROUPS, TERMS  # noqa: F401
