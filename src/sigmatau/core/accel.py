"""Which implementation of an Allan-family kernel runs: numpy, or its fused compiled twin.

The compiled kernels (:mod:`sigmatau.core.fused`, numba; the optional extra ``fast``) give the
same sums in one pass over the record per τ, without the record-sized temporaries of the numpy
kernels. They are used when

* numba can be imported, and
* the record has at least :data:`FUSED_MIN_POINTS` points (below that, loading the compiled code
  costs more than it saves), and
* the environment variable ``SIGMATAU_NUMBA`` is not ``0``.

``SIGMATAU_NUMBA=0`` forces the numpy kernels; ``SIGMATAU_NUMBA=1`` uses the compiled ones at
every size (tests, debugging). The variable is read at every call, so it can be changed at run
time. numba is imported on the first call that chooses it, never by ``import sigmatau``; a numba
that cannot be imported (absent, or built for another numpy) leaves the numpy kernels in place.

The numpy kernels stay the reference: ``tests/test_fused_kernels.py`` holds every compiled kernel
to its numpy twin (1e-12 relative; each term is formed by the same floating-point operations,
only the summation order of the squares differs).
"""

from __future__ import annotations

import functools
import os
import threading
from types import ModuleType
from typing import Callable, Optional

__all__ = ["ENV", "FUSED_MIN_POINTS", "fused_for", "fused_module", "twin"]

#: Environment variable: ``0`` forces numpy, ``1`` the compiled kernels at every size.
ENV = "SIGMATAU_NUMBA"

#: Fewest points (phase points or samples) for which the compiled kernels are chosen by default.
#: Measured on the 2-core reference machine: loading them from numba's cache costs ~50 ms in a new
#: process (compiling them, the first time ever, ~16 s); OADEV, MDEV, OHDEV and TOTDEV of 10^5
#: points then take 9 ms instead of numpy's 20 ms (10^6: 66 vs 129 ms), so from here on they pay.
FUSED_MIN_POINTS = 100_000

_OFF = ("0", "false", "no", "off")
_ON = ("1", "true", "yes", "on")

_lock = threading.Lock()
_module: Optional[ModuleType] = None
_tried = False


def fused_module() -> Optional[ModuleType]:
    """:mod:`sigmatau.core.fused`, imported on first use, or None when numba cannot be imported."""
    global _module, _tried
    if not _tried:
        with _lock:
            if not _tried:
                try:
                    from . import fused
                except ImportError:
                    fused = None  # type: ignore[assignment]
                _module, _tried = fused, True
    return _module


def fused_for(n_points: int) -> Optional[ModuleType]:
    """The compiled kernels' module when they should run on a record of ``n_points``, else None."""
    setting = os.environ.get(ENV, "").strip().lower()
    if setting in _OFF:
        return None
    if setting not in _ON and n_points < FUSED_MIN_POINTS:
        return None
    return fused_module()


def twin(name: str) -> Callable[[Callable], Callable]:
    """Decorate a numpy kernel ``(series, ms, tau0) -> (var, n)`` with its compiled twin ``name``.

    The decorated kernel runs ``sigmatau.core.fused.<name>`` when :func:`fused_for` says so and
    the numpy code otherwise; ``kernel.numpy`` is the numpy code itself (the tests' oracle) and
    ``kernel.fused_name`` the twin's name (the driver calls a frequency twin with the mean to
    remove, so that no mean-removed copy of the record is made).
    """

    def wrap(kernel: Callable) -> Callable:
        @functools.wraps(kernel)
        def dispatch(series, ms, tau0):
            fast = fused_for(series.size)
            if fast is None:
                return kernel(series, ms, tau0)
            return getattr(fast, name)(series, ms, tau0)

        dispatch.numpy = kernel  # type: ignore[attr-defined]
        dispatch.fused_name = name  # type: ignore[attr-defined]
        return dispatch

    return wrap
