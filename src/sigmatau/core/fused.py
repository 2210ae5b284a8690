"""Fused compiled kernels of the main job's statistics: one pass over the record per τ, no record-sized temporary.

The numpy kernels (:mod:`sigmatau.core.kernels`, :mod:`sigmatau.stats.hadamard`,
:mod:`sigmatau.stats.total`, the lag-1 noise identification) make several passes over the record
at each τ — form a combination chunk by chunk, square and sum it, double the window sums — and
allocate record-sized arrays (a mean-removed copy, differenced series, |x|, x − mean); numpy
cannot fuse them, and on records of 10^7–10^8 points memory traffic and page faults, not
arithmetic, set their time. Here each kernel forms its terms and sums their squares in one loop
(:mod:`sigmatau.core.compiled`, numba). The functions have the numpy kernels' signatures, ``(series,
ms, tau0) -> (var, n)``, normalise the sums with the same expressions, and are chosen by
:mod:`sigmatau.core.accel`, which imports this module (and numba) on first need.

**Same terms.** Every term is formed by the floating-point operations of the numpy kernel, in
the same order (``(x[j+2m] + x[j+m]·(-2)) + x[j]`` for OAVAR, the window sums of
:class:`~sigmatau.core.numeric.WindowSums` through the same doublings and increments, the
sequential running sums of ``numpy.cumsum``, numpy's pairwise sums for block means and ``std``),
so each term is bit for bit the numpy one. Only the order in which the squares are added
differs: blocks of :data:`~sigmatau.core.compiled.BLOCK` terms from the first one, on four
accumulators, the blocks added with Neumaier's compensation (a few ε relative, against ~1e-15
for numpy's chunked einsum; the tests measure at most 2e-14 between the two).

**No record-sized temporary.** The frequency kernels remove the mean inside the loop (the driver
makes no mean-removed copy) and keep the window sums A_m "virtual" — computed from the samples
where they are read — while A_m is a sum of at most :data:`VIRTUAL_MAX` samples: A is stored
from the first doubling on, and MVAR on an octave grid never stores A at all (its double sums B
only; A's doublings are put off until A is read, and MVAR releases it first).

**Work shared by the statistics of a record.** Inside a
:func:`~sigmatau.core.shared.shared_record` scope OADEV's pass also forms OHDEV's sums (both read
A_m) and TOTDEV's pass TheoH's OAVAR of the phase (the same three points per term), and leaves
them to the scope; noise identification builds the block sums at 2m from those at m. What a
statistic takes from the scope is bit for bit what it would form itself.
"""

from __future__ import annotations

import numpy as np

from . import compiled as nb
from .compiled import BLOCK, MVAR as _MVAR, OAVAR as _OAVAR, OHVAR as _OHVAR
from .numeric import doublings_only
from .shared import memoized, shares, wants

__all__ = [
    "BLOCK", "VIRTUAL_MAX",
    "oavar_phase", "ohvar_phase", "mvar_phase", "totvar_phase",
    "oavar_freq", "ohvar_freq", "mvar_freq", "tvar_freq",
    "lag1_r1", "block_means", "phase_of_freq", "all_finite", "abs_peak", "std",
]

#: Largest window length kept virtual (each read of A_m costs m additions).
VIRTUAL_MAX = 4

#: WindowSums.MAX_INCREMENTS: unit increments tolerated before rebuilding (same steps as numpy).
_MAX_INCREMENTS = 8


class _WindowSums:
    """:class:`~sigmatau.core.numeric.WindowSums` for the compiled kernels: the same steps, so the
    same values, with A virtual while it is a sum of at most :data:`VIRTUAL_MAX` samples and the
    last doubling before a statistic's terms fused with them (:meth:`sums_a`, :meth:`sums_b`).

    :meth:`advance` is WindowSums.advance step for step (the tests hold the two bit-identical on
    octave, dense and arbitrary grids).
    """

    def __init__(self, y: np.ndarray, mean: float, *, double: bool) -> None:
        self.y, self.mean, self.M = y, float(mean), y.size
        self.a = np.empty(0)  # storage of A once it is no longer virtual
        self.a_state = "virtual"  # "virtual", "stored" or "released"
        self.b = np.empty(y.size) if double else np.empty(0)
        self.has_b = double
        self.w = 0
        self.steps = 0
        self.pending = 0  # w of a doubling not yet carried out (0: none)
        self.a_owed: list = []  # w of A's doublings put off until A is read

    # -- the steps of WindowSums.advance --
    def advance(self, w: int) -> None:
        if not 1 <= w <= self.M:
            raise ValueError(f"window length {w} outside 1 … {self.M}")
        if w == self.w:
            return
        bits = bin(w)[2:]
        here = bin(self.w)[2:] if self.w else ""
        chain = len(bits) - 1 + bits.count("1") - 1
        extend = len(bits) - len(here) + bits[len(here):].count("1")
        released = self.a_state == "released"
        if released and not (here and bits.startswith(here) and bits[len(here):].count("1") == 0):
            raise ValueError(f"window length {w} from {self.w} needs A_w, which was released")
        if 0 < self.w < w and w - self.w <= min(chain, _MAX_INCREMENTS - self.steps):
            for _ in range(w - self.w):
                self._increment()
            self.steps += w - self.w
            return
        if not (here and bits.startswith(here) and extend <= chain):
            self._restart()
            here = "1"
        for bit in bits[len(here):]:
            self._double()
            if bit == "1":
                self._increment()
        self.steps = 0

    def release_a(self) -> None:
        """Only B is read from here on and every later step doubles (WindowSums.release_a)."""
        self.a_state = "released"
        self.a = np.empty(0)
        self.a_owed = []

    def _restart(self) -> None:
        self.pending = 0
        self.a_owed = []
        if self.a_state != "released":
            self.a_state = "virtual"  # its storage, if any, is kept for the next doubling
        if self.has_b:
            nb.fill_b(self.b, self.y, self.mean)
        self.w = 1

    def _store_a(self) -> None:
        if self.a.size < self.M:
            self.a = np.empty(self.M)

    def _settle_a(self) -> None:
        """Carry out the doublings of A put off so far (A is about to be read)."""
        owed, self.a_owed = self.a_owed, []
        for w in owed:
            virtual = self.a_state == "virtual"
            self._store_a()
            nb.double_a(self.a, self.y, self.mean, w, virtual)
            self.a_state = "stored"

    def _increment(self) -> None:
        self._flush()
        self._settle_a()
        if self.a_state == "virtual" and self.w + 1 > VIRTUAL_MAX:
            self._store_a()
            nb.fill_a(self.a, self.y, self.mean, self.w)
            self.a_state = "stored"
        nb.increment(self.a, self.b, self.y, self.mean, self.w, self.a_state == "virtual", self.has_b)
        self.w += 1

    def _double(self) -> None:
        self._flush()
        self.pending = self.w
        self.w *= 2

    def _flush(self) -> None:
        """Carry out a pending doubling without forming any term; A's is put off until A is read
        (MVAR releases A before it reads it again: its doublings are then never done)."""
        w, self.pending = self.pending, 0
        if w:
            if self.a_state != "released":
                self.a_owed.append(w)
            if self.has_b:
                nb.double_b(self.b, w, self.M)

    # -- the terms of the statistics at the current w --
    def sums_a(self, k1: int, k2: int) -> tuple[float, float]:
        """Σ of the squares of the first k1 OAVAR and k2 OHVAR terms at m = w (0: not formed)."""
        k1, k2 = max(k1, 0), max(k2, 0)
        w, m = self.pending, self.w
        if not (k1 or k2):
            self._flush()
            return 0.0, 0.0
        self._settle_a()
        if w:
            self.pending = 0
            virtual = self.a_state == "virtual"
            self._store_a()
            self.a_state = "stored"
            if self.has_b:
                nb.double_b(self.b, w, self.M)
            s1, s2 = nb.a_double_terms(self.a, self.y, self.mean, w, virtual, k1, k2)
        else:
            s1, s2 = nb.a_terms(self.a, self.y, self.mean, m, k1, k2, self.a_state == "virtual")
        return float(s1), float(s2)

    def sums_b(self, k: int) -> float:
        """Σ of the squares of the first k MVAR terms at m = w."""
        w, m = self.pending, self.w
        if k <= 0:
            self._flush()
            return 0.0
        if w:
            self.pending = 0
            if self.a_state != "released":
                self.a_owed.append(w)
            return float(nb.b_double_terms(self.b, w, self.M, k))
        return float(nb.b_terms(self.b, m, k))


# --- the kernels: (series, ms, tau0) -> (var, n), normalised as their numpy twins ----


def _f64(a: np.ndarray) -> np.ndarray:
    return a if a.dtype == np.float64 else a.astype(np.float64)


def oavar_phase(x: np.ndarray, ms: np.ndarray, tau0: float):
    """:func:`sigmatau.core.kernels.oavar_kernel` (the sums TOTVAR's pass left in the scope, if any)."""
    x = _f64(x)
    store = _phase_store(x)
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        k = x.size - 2 * m
        total = (store[int(m)] if int(m) in store else nb.oavar_phase_sum(x, int(m))) if k > 0 else 0.0
        var[i] = total / (2.0 * (m * tau0) ** 2 * k)
        n[i] = k
    return var, n


def ohvar_phase(x: np.ndarray, ms: np.ndarray, tau0: float):
    """:func:`sigmatau.stats.hadamard._ohvar_kernel`."""
    x = _f64(x)
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        k = x.size - 3 * m
        total = nb.ohvar_phase_sum(x, int(m)) if k > 0 else 0.0
        var[i] = total / (6.0 * (m * tau0) ** 2 * k)
        n[i] = k
    return var, n


def mvar_phase(x: np.ndarray, ms: np.ndarray, tau0: float):
    """:func:`sigmatau.core.kernels._mvar_kernel`."""
    x = _f64(x)
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        size = x.size - 3 * int(m) + 1
        total = nb.mvar_phase_sum(x, int(m)) if size > 0 else 0.0
        var[i] = total / (2.0 * m**2 * (m * tau0) ** 2 * size)
        n[i] = size
    return var, n


def totvar_phase(x: np.ndarray, ms: np.ndarray, tau0: float):
    """:func:`sigmatau.stats.total._totvar_kernel`.

    Inside a :func:`~sigmatau.core.shared.shared_record` scope its pass also forms OAVAR of the
    phase at each m (the same three points per term) and leaves the sums to the scope, where
    :func:`oavar_phase` takes them (TheoH's short-τ rows): bit for bit the sums it forms itself.
    """
    x = _f64(x)
    n_pts = x.size
    var = np.empty(ms.size)
    keep = wants(x, "oadev", "theoh")  # OADEV of phase data and TheoH's short-τ rows read them
    store = _phase_store(x)
    for i, m in enumerate(ms):
        mi = int(m)
        with_oavar = keep and n_pts - 2 * mi > 0 and mi not in store
        total, oavar = nb.totvar_sums(x, mi, with_oavar)
        if with_oavar:
            store[mi] = float(oavar)
        var[i] = total / (2.0 * (m * tau0) ** 2 * (n_pts - 2))
    return var, np.full(ms.size, n_pts - 2, dtype=np.int64)


def _phase_store(x: np.ndarray) -> dict:
    """OAVAR sums of the phase ``x`` by m, kept for the scope (a new, empty dict outside one)."""
    return memoized(x, ("fused-oavar-phase-sums",), dict)


def _freq_kernel(y: np.ndarray, ms: np.ndarray, mean: float, kind: int):
    """Sums and term counts of ``kind`` at each factor, through the window sums in increasing m.

    OAVAR and OHVAR read the same window sums A_m. Inside a
    :func:`~sigmatau.core.shared.shared_record` scope the OAVAR pass forms the OHVAR sums too and
    leaves them to the scope, and the OHVAR kernel takes them from there when every factor it
    needs was reached along the same steps (the same factors below it): one doubling pass over
    the record per octave for both statistics. The sums are those OHVAR forms on its own, bit for
    bit (:func:`sigmatau.core.compiled.a_terms`).
    """
    y = _f64(y)
    M = y.size
    order = np.argsort(ms, kind="stable")
    sums = np.empty(ms.size)
    terms = np.empty(ms.size, dtype=np.int64)
    path = [int(ms[i]) for i in order]  # the factors in the order the window sums reach them
    store = memoized(y, ("fused-ohvar-sums", float(mean)), dict)  # by the path up to m
    if kind == _OHVAR and all(tuple(path[:pos + 1]) in store for pos in range(len(path))):
        for pos, i in enumerate(order):
            sums[i] = store[tuple(path[:pos + 1])]
            terms[i] = M - 3 * path[pos] + 1
        return sums, terms
    double = kind == _MVAR
    ws = _WindowSums(y, mean, double=double)
    for pos, i in enumerate(order):
        m = path[pos]
        ws.advance(m)
        if double:
            if m >= 4 and doublings_only(m, ms[order[pos + 1:]]):
                ws.release_a()
            k = M - 3 * m + 2
            sums[i] = ws.sums_b(k)
        elif kind == _OAVAR:
            k = M - 2 * m + 1
            k2 = M - 3 * m + 1 if wants(y, "ohdev") else 0
            sums[i], s2 = ws.sums_a(k, k2)
            if k2 > 0:
                store[tuple(path[:pos + 1])] = s2
        else:
            k = M - 3 * m + 1
            _, sums[i] = ws.sums_a(0, k)
        terms[i] = k
    return sums, terms


def oavar_freq(y: np.ndarray, ms: np.ndarray, tau0: float, mean: float = 0.0):
    """:func:`sigmatau.core.kernels._oavar_freq` of ``y - mean`` (no centred copy is made)."""
    sums, k = _freq_kernel(y, ms, mean, _OAVAR)
    var = np.empty(ms.size)
    for i, m in enumerate(ms.tolist()):
        var[i] = sums[i] / (2.0 * float(m) ** 2 * int(k[i]))
    return var, k


def ohvar_freq(y: np.ndarray, ms: np.ndarray, tau0: float, mean: float = 0.0):
    """:func:`sigmatau.stats.hadamard._ohvar_freq` of ``y - mean``."""
    sums, k = _freq_kernel(y, ms, mean, _OHVAR)
    var = np.empty(ms.size)
    for i, m in enumerate(ms.tolist()):
        var[i] = sums[i] / (6.0 * float(m) ** 2 * int(k[i]))
    return var, k


def mvar_freq(y: np.ndarray, ms: np.ndarray, tau0: float, mean: float = 0.0):
    """:func:`sigmatau.core.kernels._mvar_freq` of ``y - mean``."""
    sums, k = _freq_kernel(y, ms, mean, _MVAR)
    var = np.empty(ms.size)
    for i, m in enumerate(ms.tolist()):
        var[i] = sums[i] / (2.0 * float(m) ** 4 * int(k[i]))
    return var, k


def tvar_freq(y: np.ndarray, ms: np.ndarray, tau0: float, mean: float = 0.0):
    """:func:`sigmatau.core.kernels._tvar_freq` of ``y - mean``."""
    var, n = mvar_freq(y, ms, tau0, mean)
    return var * (ms * tau0) ** 2 / 3.0, n


def lag1_r1(z: np.ndarray, d: int, acf: str = "standard") -> float:
    """Lag-1 autocorrelation r1 of ``z`` differenced d ≤ 3 times, NaN when that series is constant.

    :func:`sigmatau.uncertainty.lag1._lag1_r1`, without its centred and differenced copies.
    """
    z = _f64(z)
    if not 0 <= d <= min(3, z.size - 2):
        return float("nan")
    _, den, num = nb.lag1_sums(z, int(d))
    if den == 0.0:
        return float("nan")
    r1 = num / den
    size = z.size - d
    return r1 * (size - 1) / size if acf == "stable32" else r1


def block_means(y: np.ndarray, m: int) -> np.ndarray:
    """:func:`sigmatau.core.numeric.block_means` (the means of the ⌊M/m⌋ blocks of m samples), bit for bit.

    numpy's pairwise summation splits a block of m = 2^p ≥ 256 samples into its two halves, so
    inside a :func:`~sigmatau.core.shared.shared_record` scope the block sums at m are the
    pairwise sums of those at m/2 when the scope holds them (noise identification visits the
    octaves in increasing m): O(M/m) instead of a pass over the record. Otherwise one pass.
    """
    y = _f64(y)
    m = int(m)
    keep = shares(y)
    store = memoized(y, ("fused-block-sums",), dict) if keep else {}
    half = store.get(m // 2) if m >= 256 and m & (m - 1) == 0 else None
    sums = np.empty(y.size // m)
    if half is not None:
        nb.pair_sums(half, sums)
    else:
        nb.block_sums(y, m, sums)
    if keep and m >= 128 and m & (m - 1) == 0:
        store[m] = sums.copy()  # at most 1/128 of the record
    sums += 0.0  # the sum numpy's reduction starts from 0.0 (a -0.0 sum becomes 0.0)
    sums /= m  # in place: numpy's mean divides its sums the same way, without a second copy
    return sums


def all_finite(v: np.ndarray) -> bool:
    """Whether every value of the float64 array ``v`` is finite (numpy.isfinite(v).all(), no temporary)."""
    if v.dtype != np.float64 or not v.flags.c_contiguous:
        return bool(np.isfinite(v).all())
    return nb.non_finite(v.view(np.int64)) == 0


def std(v: np.ndarray, ddof: int = 0) -> float:
    """``numpy.std(v, ddof=ddof)`` of a contiguous float64 array, bit for bit, without its temporary
    ``v - mean`` of the record's size (numpy's pairwise sums, the same operations)."""
    v = np.ascontiguousarray(_f64(v))
    mean = (0.0 + nb.pairwise(v, 0, v.size, nb.SUM_PLAIN, 0.0, 0)) / v.size
    return float(np.sqrt((0.0 + nb.pairwise(v, 0, v.size, nb.SUM_SQUARED_DEVIATIONS, mean, 0)) / max(v.size - ddof, 0)))


def abs_peak(v: np.ndarray) -> float:
    """numpy.nanmax(numpy.abs(v)) of a float64 array with at least one value that is not NaN."""
    return float(nb.nan_abs_peak(v))


def phase_of_freq(y: np.ndarray, mean: float, rate: float) -> np.ndarray:
    """:func:`sigmatau.core.validate.to_phase` of ``y - mean`` (frequency data), without the centred copy."""
    x = np.empty(y.size + 1)
    nb.phase_of_freq(_f64(y), float(mean), 1.0 / rate, x)
    return x
