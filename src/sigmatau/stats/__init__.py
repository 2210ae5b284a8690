"""The statistics of the design tip, one module per family, and their oracle.

Holds the Allan family (``allan``: STDEV, ADEV, OADEV, MDEV, TDEV), the Hadamard
family (``hadamard``), the modified Hadamard family (``modhadamard``: MHDEV, LDEV,
MHTOTDEV), the parabolic deviation (``parabolic``: PDEV), the total variances (``total``), the Theo family
(``theo``), the time-error statistics (``tie``), the plain filter-chain
definitions every fast kernel is tested against (``filterchain``) and the path
every public statistic takes (``engine``: compute, then attach the uncertainty).
May import: :mod:`sigmatau.uncertainty`, :mod:`sigmatau.core`, :mod:`sigmatau.errors`.
``FUNCTIONS`` maps each statistic's name to its public function.
"""

from __future__ import annotations

from typing import Callable

from .allan import adev, mdev, oadev, ostdev, stdev, tdev
from .hadamard import hdev, ohdev
from .modhadamard import ldev, mhdev, mhtotdev
from .parabolic import pdev
from .theo import theo1, theobr, theoh
from .tie import mtie, tierms
from .total import htotdev, mtotdev, totdev, ttotdev

#: Every statistic by its name, in the design tip's order.
FUNCTIONS: dict[str, Callable[..., object]] = {
    f.__name__: f for f in (stdev, ostdev, adev, oadev, mdev, tdev, hdev, ohdev, mhdev, ldev, pdev, totdev, mtotdev,
                            ttotdev, htotdev, mhtotdev, theo1, theobr, theoh, mtie, tierms)
}

__all__ = ["FUNCTIONS"]
