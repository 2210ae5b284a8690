"""Compatibility layers that let code written for other libraries run on sigmatau.

* :mod:`sigmatau.compat.allantools` — the statistics of allantools with its
  names, arguments, τ grids and ``(taus, devs, errs, ns)`` returns::

      import sigmatau.compat.allantools as allantools

Nothing here is imported by ``import sigmatau``. Layer: beside
:mod:`sigmatau.scale`; it may import the statistics (:mod:`sigmatau.stats`) and
the layers below them, and needs none of the libraries it imitates.
"""

from __future__ import annotations

__all__: list[str] = []
