"""Statistics streamed over records larger than memory.

Public entry point, kept at this path for users; the implementation lives in
:mod:`sigmatau.scale.chunked`.
"""

from .scale.chunked import *  # noqa: F401,F403
from .scale.chunked import __all__  # noqa: F401
from .scale.chunked.sources import PathLike  # noqa: F401  (public before the split, outside __all__)
from .scale.chunked.streams import VFun  # noqa: F401
