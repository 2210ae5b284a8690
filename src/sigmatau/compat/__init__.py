"""Compatibility layers that let code written for other libraries run on sigmatau.

* :mod:`sigmatau.compat.allantools` — the statistics of allantools with its
  names, arguments, τ grids and ``(taus, devs, errs, ns)`` returns::

      import sigmatau.compat.allantools as allantools

Nothing here is imported by ``import sigmatau``; the layers depend only on the
public statistics and need none of the libraries they imitate.
"""

from __future__ import annotations

__all__: list[str] = []
