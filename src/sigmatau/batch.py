"""Many logs on a Dask cluster (what ``sigmatau batch`` runs).

Public entry point, kept at this path for users; the implementation lives in
:mod:`sigmatau.scale.batch`.
"""

from .scale.batch import *  # noqa: F401,F403
from .scale.batch import __all__  # noqa: F401
from .cli.batch import add_cli  # noqa: F401  (public before the split, outside __all__)
from .scale.batch.common import PathLike  # noqa: F401
