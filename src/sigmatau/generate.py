"""Power-law noise generators (Kasdin–Walter, the design tip's constructions).

Public entry point, kept at this path for users; the implementation lives in
:mod:`sigmatau.noise.generate`.
"""

from .noise.generate import *  # noqa: F401,F403
from .noise.generate import __all__  # noqa: F401
