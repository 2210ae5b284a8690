"""Streaming statistics: σ(τ) of a record while it is being recorded.

Holds :class:`Stream` (``stream``), which takes chunks of any length and gives, at any
moment, the batch result of ADEV, OADEV, MDEV, TDEV, HDEV, OHDEV and TOTDEV on every
sample seen — τ rows, term counts, noise types, EDF and intervals — from a state bounded
by the longest averaging factor, not by the record: the window-sum chain and its running
sums (``chain``), ring buffers and compensated sums (``buffers``), the streamed noise
identification (``noiseid``), the state and its blocks (``state``), the results
(``results``) and the checks of options and chunks (``checks``). May import:
:mod:`sigmatau.imu`, :mod:`sigmatau.stats`, :mod:`sigmatau.uncertainty`,
:mod:`sigmatau.core` and :mod:`sigmatau.errors` (it sits beside ``scale`` and ``compat``).
"""

from __future__ import annotations

from .checks import NOT_STREAMABLE, STREAMABLE
from .stream import DEFAULT_STATISTICS, Stream

__all__ = ["Stream", "STREAMABLE", "NOT_STREAMABLE", "DEFAULT_STATISTICS"]
