"""Statistics streamed over records larger than memory.

Public entry point, kept at this path for users; the implementation lives in
:mod:`sigmatau.scale.chunked`.
"""

from .scale.chunked import *  # noqa: F401,F403
from .scale.chunked import __all__  # noqa: F401
