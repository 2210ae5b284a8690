"""Built-in reference data (the NBS 1000-point and 9-point sets).

Public entry point, kept at this path for users; the implementation lives in
:mod:`sigmatau.noise.datasets`.
"""

from .noise.datasets import *  # noqa: F401,F403
from .noise.datasets import __all__  # noqa: F401
