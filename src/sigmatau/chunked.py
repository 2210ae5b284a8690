"""Statistics streamed over records larger than memory, and the main job on such a log.

Public entry point, kept at this path for users; the implementation lives in
:mod:`sigmatau.scale.chunked` (the statistics) and :mod:`sigmatau.scale.outofcore`
(:func:`analyze_file`: the analysis of a log in memory or, when it would not fit, out of core).
"""

from .scale.chunked import *  # noqa: F401,F403
from .scale.chunked import __all__ as _chunked_all
from .scale.outofcore import MEMORY_MODES, MemoryPlan, analyze_disk_log, analyze_file, memory_plan, parse_size

# The main job out of core (a log larger than memory) beside the statistics it streams.
__all__ = [*_chunked_all, "analyze_file", "analyze_disk_log", "memory_plan", "MemoryPlan", "MEMORY_MODES",
           "parse_size"]
from .scale.chunked.sources import PathLike  # noqa: F401  (public before the split, outside __all__)
from .scale.chunked.streams import VFun  # noqa: F401
