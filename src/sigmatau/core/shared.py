"""Work shared by the statistics of one record: validated samples, phase, noise identification.

The main job computes six statistics and the IMU model on every channel. Each
public statistic validates its input, scales it, integrates it to phase and
identifies the noise type at every τ on its own — for a 86-million-sample
channel that is the same few seconds of work five times over. Inside

>>> import numpy as np
>>> from sigmatau.core.shared import shared_record
>>> import sigmatau
>>> y = np.random.default_rng(1).standard_normal(10_000)
>>> with shared_record(y):
...     a = sigmatau.oadev(y, taus="octave")
...     h = sigmatau.ohdev(y, taus="octave")
>>> bool(np.array_equal(a.dev, sigmatau.oadev(y, taus="octave").dev))
True

every statistic called on that very object ``y`` takes its validated, scaled
samples (and their phase) from the scope, and noise identification reuses the
lag-1 autocorrelations already computed at each averaging factor. Each shared
value is computed by the same code as without the scope, so every result is
bit-for-bit the same; only repeated work is skipped.

The scope lives in a :class:`contextvars.ContextVar`: it belongs to the thread
(or task) that opened it, so channels analysed in parallel threads each have
their own. The caller promises not to modify ``y`` inside the block; the arrays
the scope hands out are read-only, so an accidental in-place change fails
loudly instead of corrupting the next statistic.
"""

from __future__ import annotations

from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any, Callable, Hashable, Iterable, Iterator, Optional, TypeVar

import numpy as np

__all__ = ["shared_record", "derived", "memoized", "shares", "wants"]

T = TypeVar("T")


class _Record:
    """One record's shared values: forms of the source (arrays) and memoized results."""

    def __init__(self, source: object, statistics: Optional[frozenset[str]] = None) -> None:
        self.source = source
        self.statistics = statistics  # what the scope will compute; None: unknown (anything)
        # form key -> array; the arrays are kept alive here, so their id()s stay unique.
        self.forms: dict[Hashable, np.ndarray] = {}
        self.form_ids: dict[int, Hashable] = {}
        self.memo: dict[tuple[Hashable, Hashable], Any] = {}
        self.source_array: Optional[np.ndarray] = None  # np.asarray(source), when first needed

    def may_alias(self, arr: np.ndarray) -> bool:
        """Whether ``arr`` may share memory with the caller's data.

        The source may be an array-like whose ``__array__`` hands out its own buffer
        (a pandas Series): ``numpy.asarray`` of it is then the caller's memory, and
        validation returns that very array for data it need not change (all zeros,
        float64 already). Unknown means yes.
        """
        try:
            if self.source_array is None:
                self.source_array = np.asarray(self.source)
            return bool(np.may_share_memory(arr, self.source_array))
        except Exception:  # an array-like numpy cannot read: it is not locked
            return True

    def form_key(self, obj: object) -> Optional[Hashable]:
        """The key under which ``obj`` was handed out (the source itself is ``()``), or None."""
        if obj is self.source:
            return ()
        key = self.form_ids.get(id(obj))
        if key is not None and self.forms[key] is obj:
            return key
        return None


_CURRENT: ContextVar[Optional[_Record]] = ContextVar("sigmatau_shared_record", default=None)


@contextmanager
def shared_record(source: object, *, statistics: Optional[Iterable[str]] = None) -> Iterator[None]:
    """Share validation, phase and noise identification among the statistics of ``source``.

    Parameters
    ----------
    source : array_like
        The record (one channel). Only calls given this very object (``is``)
        share; anything else is computed as usual. It must not be modified
        inside the block.
    statistics : iterable of str, optional
        The statistics the block will compute (``"oadev"``, ``"ohdev"`` …), when
        known. A kernel that could form another statistic's sums in its own pass
        (OADEV's pass forming OHDEV's) does so only for a statistic named here
        (:func:`wants`); default: any statistic may follow, so it always does.

    Notes
    -----
    The scope holds the validated samples and, once a statistic needs it, their
    phase (about two copies of the record) until the block ends; each statistic
    would otherwise make and free its own. Nested scopes are allowed: the inner
    one is used until it closes.
    """
    wanted = None if statistics is None else frozenset(str(s).lower() for s in statistics)
    token = _CURRENT.set(_Record(source, wanted))
    try:
        yield
    finally:
        _CURRENT.reset(token)


def derived(data: object, key: Hashable, make: Callable[[], T]) -> T:
    """``make()`` — once per scope when ``data`` is the shared record or one of its forms.

    Use for values derived from the whole record that several statistics need
    (the validated samples, their phase). A numpy array returned by ``make`` is
    registered as a form of the record, so :func:`derived` and :func:`memoized`
    recognise it when it is passed on, and is made read-only unless it is the
    caller's own object. A tuple is handled element by element.

    Parameters
    ----------
    data : object
        What the statistic was given.
    key : hashable
        Names the derived value and every parameter it depends on.
    make : callable
        Computes the value from ``data``.
    """
    rec = _CURRENT.get()
    base = rec.form_key(data) if rec is not None else None
    if rec is None or base is None:
        return make()
    full = (base, key)
    if full not in rec.memo:
        value = make()
        for item in value if isinstance(value, tuple) else (value,):
            if isinstance(item, np.ndarray) and item is not rec.source and rec.form_key(item) is None:
                if item.flags.owndata and not rec.may_alias(item):  # never lock the caller's memory
                    item.flags.writeable = False
                form = (full, len(rec.forms))
                rec.forms[form] = item
                rec.form_ids[id(item)] = form
        rec.memo[full] = value
    return rec.memo[full]  # type: ignore[no-any-return]


def memoized(data: object, key: Hashable, make: Callable[[], T]) -> T:
    """``make()`` — once per scope for the same ``data`` form and ``key``.

    For results computed from a form of the record that other statistics ask for
    again (the lag-1 autocorrelation at an averaging factor). Outside a scope,
    or for data the scope does not know, ``make()`` is called every time.
    """
    return derived(data, ("memo", key), make)


def shares(data: object) -> bool:
    """Whether ``data`` is the record of the current scope or one of its forms: what is
    :func:`memoized` for it is then kept for the other statistics of the record."""
    rec = _CURRENT.get()
    return rec is not None and rec.form_key(data) is not None


def wants(data: object, *statistics: str) -> bool:
    """Whether ``data`` :func:`shares` the current scope and the scope will compute one of
    ``statistics`` (or did not say what it computes): a kernel forms sums for another
    statistic in its own pass only then, since forming them costs time (about 30 % more for
    OADEV's pass with OHDEV's sums) that only that statistic repays."""
    rec = _CURRENT.get()
    if rec is None or rec.form_key(data) is None:
        return False
    return rec.statistics is None or any(s in rec.statistics for s in statistics)
