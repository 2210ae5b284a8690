"""Power-law noise generators (Kasdin–Walter, the design tip's constructions) and expected variances.

Public entry point, kept at this path for users; the implementation lives in
:mod:`sigmatau.noise.generate` and :mod:`sigmatau.noise.expected`.
"""

from .noise import expected as _expected
from .noise import generate as _generate
from .noise.expected import *  # noqa: F401,F403
from .noise.generate import *  # noqa: F401,F403

__all__ = [*_generate.__all__, *_expected.__all__]
from .noise.generate import ExpectedStatistic, Method, NoiseType, RngLike  # noqa: F401  (public before the split)
