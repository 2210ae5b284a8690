"""The design tip's filter-chain definitions: the plain, slow oracle.

Public entry point, kept at this path for users; the implementation lives in
:mod:`sigmatau.stats.filterchain`.
"""

from .stats.filterchain import *  # noqa: F401,F403
from .stats.filterchain import __all__  # noqa: F401
