"""Noise identification of a chunked record, streamed: lag-1 autocorrelation, B1 and R(n).

Follows the decision rules of :func:`sigmatau.noiseid.identify` (in
:mod:`sigmatau.uncertainty.noiseid`) on the decimated or averaged series,
streamed twice per factor; :func:`_attach` hands the identified noise to
:func:`sigmatau.uncertainty.attach.attach`. With missing samples the rules are
the in-memory gap rules: a decimated point or block mean that reads a gap is
missing (NaN), the lag-1 autocorrelation uses the points present and the pairs
of neighbours both present (:func:`_lag1_gaps`), B1 the block means present
(:func:`_b1_streamed` when they are too many to hold).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Callable, Iterator, Optional

import numpy as np

from ...core.result import StabilityResult
from ...core.taus import long_factors_expected
from ...errors import DataError
from ...uncertainty.attach import attach
from ...uncertainty.confidence import EDF_STATISTICS
from ...uncertainty.lag1 import difference_until_white, lag1_alpha
from .streams import _block_means, _Diff, _Raw, _Series, _strided, _with_history


def _differences(batches: Callable[[], Iterator[np.ndarray]], dmax: int) -> Iterator[tuple[int, np.ndarray]]:
    """``(d, z)``: the d-th differences (d = 0 … dmax) each batch adds, in stream order (empty ones skipped)."""
    had = 0
    for ext in _with_history(batches(), dmax):
        for d in range(dmax + 1):
            z = _new_values(ext, had, d)
            if z.size:
                yield d, z
        had = min(dmax, ext.size)


def _lag1_streamed(batches: Callable[[], Iterator[np.ndarray]], n: int, dmax: int) -> tuple[list[float], list[float]]:
    """Lag-1 sums of the d-th differences of a streamed series, d = 0 … dmax.

    Returns ``(den_d, num_d)`` with ``den = Σ (z - z̄)²`` and
    ``num = Σ (z_k - z̄)(z_{k+1} - z̄)`` (z̄ the mean of that difference series),
    from two passes: means first, then the centred sums (:func:`_centred_sums`).
    """
    sums: list[list[float]] = [[] for _ in range(dmax + 1)]
    for d, z in _differences(batches, dmax):
        sums[d].append(float(np.add.reduce(z)))
    means = [math.fsum(sums[d]) / (n - d) for d in range(dmax + 1)]
    return _centred_sums(batches, dmax, means)


def _present_sums(batches: Callable[[], Iterator[np.ndarray]], dmax: int) -> list[tuple[int, int, float]]:
    """First pass of the lag-1 sums with gaps: per difference order d = 0 … dmax, the points
    present (not NaN), the pairs of neighbours both present, and the sum of the points present."""
    sums: list[list[float]] = [[] for _ in range(dmax + 1)]
    present = [0] * (dmax + 1)
    pairs = [0] * (dmax + 1)
    last_ok = [False] * (dmax + 1)
    for d, z in _differences(batches, dmax):
        ok = ~np.isnan(z)
        sums[d].append(float(np.add.reduce(z[ok])))
        present[d] += int(np.count_nonzero(ok))
        pairs[d] += int(np.count_nonzero(ok[:-1] & ok[1:])) + int(last_ok[d] and ok[0])
        last_ok[d] = bool(ok[-1])
    return [(present[d], pairs[d], math.fsum(sums[d])) for d in range(dmax + 1)]


def _centred_sums(batches: Callable[[], Iterator[np.ndarray]], dmax: int,
                  means: list[float]) -> tuple[list[float], list[float]]:
    """Second pass: ``Σ zc²`` and ``Σ zc_k·zc_{k+1}`` of the d-th differences centred on ``means``,
    a missing point (NaN) taken as 0, so a pair with one adds nothing; the pair across two
    batches joins the last value of one to the first of the next."""
    den: list[list[float]] = [[] for _ in range(dmax + 1)]
    num: list[list[float]] = [[] for _ in range(dmax + 1)]
    last = [0.0] * (dmax + 1)
    for d, z in _differences(batches, dmax):
        zc = np.where(np.isnan(z), 0.0, z - means[d])
        den[d].append(float(np.einsum("i,i->", zc, zc)))
        num[d].append(float(np.einsum("i,i->", zc[:-1], zc[1:])))
        num[d].append(last[d] * float(zc[0]))
        last[d] = float(zc[-1])
    return [math.fsum(v) for v in den], [math.fsum(v) for v in num]


def _lag1_gaps(batches: Callable[[], Iterator[np.ndarray]], m: int, dtype: str, dmax: int):
    """α and α̂ of a streamed series holding NaN (missing points), by the in-memory gap rules:
    the mean and ``Σ zc²`` over the n points present, ``Σ zc_k·zc_{k+1}`` over the pairs both
    present, ``r1 = num/den·(n-1)/pairs`` (:func:`sigmatau.noiseid.lag1_acf_noise_id`)."""
    from ...uncertainty import noiseid

    first = _present_sums(batches, dmax)
    if first[0][0] < noiseid.LAG1_MIN_POINTS:
        raise noiseid.InsufficientDataError(
            f"lag-1 noise identification needs at least {noiseid.LAG1_MIN_POINTS} points at m={m},"
            f" got {first[0][0]} outside the gaps")
    means = [total / n if n else 0.0 for n, _, total in first]
    den, num = _centred_sums(batches, dmax, means)

    def r1_at(d: int) -> float:
        n, pairs = first[d][0], first[d][1]
        if n < 2 or den[d] == 0.0:
            raise DataError("the series is constant at this averaging factor; its autocorrelation is undefined")
        if pairs == 0:
            raise noiseid.InsufficientDataError("no two neighbouring points are both present at this averaging factor")
        return num[d] / den[d] * (n - 1) / pairs

    return _lag1_decision(r1_at, m, dtype, dmax)


def _lag1_decision(r1_at: Callable[[int], float], m: int, dtype: str, dmax: int) -> tuple[int, float]:
    """α and α̂ from the lag-1 autocorrelation ``r1_at(d)`` of the d-th differences, by the
    in-memory rule itself (:func:`sigmatau.uncertainty.lag1.difference_until_white`)."""
    d, delta, _ = difference_until_white(r1_at, m, 0, dmax)
    return lag1_alpha(d, delta, dtype)


def _new_values(ext: np.ndarray, had: int, d: int) -> np.ndarray:
    """The d-th differences of a batch preceded by ``had`` values of history, less those already seen."""
    diff = np.diff(ext, d) if d else ext
    return diff[max(0, had - d) :]


def _lag1(raw: _Raw, m: int, dtype: str, dmax: int, L: int, gaps: bool = False):
    """α and α̂ by :func:`sigmatau.noiseid.lag1_acf_noise_id` on the decimated or averaged series."""
    from ...uncertainty import noiseid

    nz = len(range(0, raw.n, m)) if dtype == "phase" else raw.n // m

    def batches() -> Iterator[np.ndarray]:
        return _strided(raw, m, nz, L) if dtype == "phase" else _block_means(raw, m, nz, L)

    if nz < noiseid.LAG1_MIN_POINTS:
        raise noiseid.InsufficientDataError(f"lag-1 noise identification needs at least 30 points at m={m}, got {nz}")
    if nz <= L:  # small enough: the in-memory routine itself
        z = np.concatenate(list(batches()))
        if gaps and np.count_nonzero(~np.isnan(z)) < noiseid.LAG1_MIN_POINTS:
            # (checked here: the routine would first refuse a series with no point present at all)
            raise noiseid.InsufficientDataError(f"lag-1 noise identification needs at least 30 points at m={m}")
        r = noiseid.lag1_acf_noise_id(z, 1, data_type=dtype, dmax=dmax)
        return r.alpha, r.alpha_estimate
    if gaps:
        return _lag1_gaps(batches, m, dtype, dmax)
    den, num = _lag1_streamed(batches, nz, dmax)

    def r1_at(d: int) -> float:
        if den[d] == 0.0:
            raise DataError("the series is constant at this averaging factor; its autocorrelation is undefined")
        return num[d] / den[d]

    return _lag1_decision(r1_at, m, dtype, dmax)


def _b1_streamed(batches: Callable[[], Iterator[np.ndarray]], m: int) -> tuple[float, int]:
    """The observed B1 ratio and Nb from block means streamed twice (some missing: NaN), as
    :func:`sigmatau.noiseid.b1_observed`: the variance of the means present over the Allan
    variance of the neighbouring pairs present."""
    from ...uncertainty.noiseid import InsufficientDataError

    sums: list[float] = []
    sq_diff: list[float] = []
    nb = n_diff = 0
    for ext in _with_history(batches(), 1):
        dif = np.diff(ext)
        dif = dif[~np.isnan(dif)]
        sq_diff.append(float(np.einsum("i,i->", dif, dif)))
        n_diff += dif.size
        new = ext if len(sums) == 0 else ext[1:]  # the history value was counted with its own batch
        new = new[~np.isnan(new)]
        sums.append(float(np.add.reduce(new)))
        nb += new.size
    if nb < 2 or n_diff == 0:
        raise InsufficientDataError(f"the B1 ratio needs at least 2 averages (and a pair of neighbours) at m={m},"
                                    f" got {nb} outside the gaps")
    mean = math.fsum(sums) / nb
    squares: list[float] = []
    for b in batches():
        c = b[~np.isnan(b)] - mean
        squares.append(float(np.einsum("i,i->", c, c)))
    avar = math.fsum(sq_diff) / (2.0 * n_diff)
    if avar == 0.0:
        raise DataError(f"the Allan variance is zero at m={m}; the B1 ratio is undefined")
    return math.fsum(squares) / (nb - 1) / avar, nb


def _b1(freq: object, m: int, hadamard: bool, L: int, n_expected: Optional[int] = None, gaps: bool = False):
    """:func:`sigmatau.noiseid.b1_noise_id` from streamed block means of the frequency series."""
    from ...uncertainty.noiseid import InsufficientDataError, b1_classify, b1_observed

    def obs(series: object) -> tuple[float, int]:
        count = series.n // m  # type: ignore[attr-defined]
        if gaps and count > L:  # many blocks, most of them missing: streamed, not held
            return _b1_streamed(lambda: _block_means(series, m, count, L), m)
        means = np.concatenate([np.empty(0)] + list(_block_means(series, m, count, L)))
        if means.size < 2:
            raise InsufficientDataError(f"the B1 ratio needs at least 2 averages at m={m}, got {means.size}")
        return b1_observed(means, 1)

    ratio, nb = obs(freq)
    if nb < 3:
        raise InsufficientDataError(f"B1 noise identification needs at least 3 averages at m={m}, got {nb}")
    mu, mu_hat = b1_classify(ratio, nb, n_expected)
    if hadamard and mu >= 1:
        try:
            ratio2, nb2 = obs(_Diff(freq))
        except DataError:
            nb2 = 0
        if nb2 >= 3:
            mu2, mu2_hat = b1_classify(ratio2, nb2, n_expected)
            mu = min(max(mu2 + 2, 1), 3)
            mu_hat = min(max(mu2_hat + 2.0, 1.0), 3.0)
    alpha = 1 if mu == -2 else -mu - 1
    return alpha, -mu_hat - 1.0, mu == -2


def _rn(src: _Series, m: int, dtype: str) -> float:
    """R(n) = MVAR/OAVAR at factor m, computed streamed on ``src``."""
    from ...stats.allan import MVAR, OAVAR
    from ...uncertainty.noiseid import InsufficientDataError

    npts = src.n if dtype == "phase" else src.n + 1
    if npts < 3 * m:
        raise InsufficientDataError(f"R(n) needs at least {3 * m} phase points at m={m}, got {npts}")
    with long_factors_expected():  # long-τ factors are the point here
        # Through the series' StreamedSeries protocol, i.e. sources._run(stat, src, …): that module
        # imports this one, so it is not imported back.
        mv = src.__sigmatau_statistic__(MVAR, rate=1.0, data_type=dtype, taus="octave", m=[m], ci=None).var[0]
        av = src.__sigmatau_statistic__(OAVAR, rate=1.0, data_type=dtype, taus="octave", m=[m], ci=None).var[0]
    if av == 0.0:
        raise DataError(f"the Allan variance is zero at m={m}; R(n) is undefined")
    return float(mv / av)


def _identify(src: _Series, ms: np.ndarray, dtype: str, family: str,
              n_terms: Optional[np.ndarray] = None, gaps: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """``(alpha, alpha_estimate)`` per factor, following :func:`sigmatau.noiseid.identify`."""
    from ...uncertainty import noiseid

    fam = noiseid.FAMILY_ALIASES[family]
    dmax, lo, hi = noiseid.FAMILY_RULES[fam]
    raw = _Raw(src)
    freq = _Diff(raw) if dtype == "phase" else raw
    L = src.chunk_size
    m_list = [int(v) for v in ms]
    alpha = np.zeros(len(m_list), dtype=np.int64)
    est = np.full(len(m_list), np.nan)
    method: list[str] = []
    n_freq = src.n - 1 if dtype == "phase" else src.n
    min_averages = noiseid.b1_min_averages(family)
    memo = getattr(src, "_memo", None)

    def remembered(key: tuple, make: Callable[[], object]) -> object:
        """``make()`` once per record and key (each statistic of a channel would repeat its passes)."""
        if memo is None:
            return make()
        if key not in memo:
            memo[key] = make()
        return memo[key]

    for i, m in enumerate(m_list):
        if src.n // m >= noiseid.LAG1_MIN_POINTS:
            try:
                alpha[i], est[i] = remembered(("lag1", m, dtype, dmax, L, gaps),
                                              lambda: _lag1(raw, m, dtype, dmax, L, gaps))
            except noiseid.InsufficientDataError:
                pass
            else:
                method.append("lag1")
                continue
        if n_freq // m < min_averages:
            method.append("carried")
            continue
        try:
            n_exp = None if n_terms is None else int(n_terms[i])
            a, e, ambiguous = remembered(("b1", m, dtype, fam == "hadamard", n_exp, L, gaps),
                                         lambda: _b1(freq, m, fam == "hadamard", L, n_exp, gaps))
        except DataError:
            method.append("carried")
            continue
        alpha[i], est[i] = a, e
        if ambiguous:
            try:
                rn = remembered(("rn", m, dtype, L), lambda: _rn(src, m, dtype))
            except DataError:
                pass
            else:
                wpm, fpm = float(noiseid.rn_expected(m, 2)), float(noiseid.rn_expected(m, 1))
                alpha[i] = 2 if rn < math.sqrt(wpm * fpm) else 1
                t = (math.log(rn) - math.log(wpm)) / (math.log(fpm) - math.log(wpm)) if fpm != wpm else 0.0
                est[i] = 2.0 - t
        method.append("done")
    done = [i for i, tag in enumerate(method) if tag != "carried"]
    for i, tag in enumerate(method):
        if tag == "carried":
            if not done:
                raise noiseid.InsufficientDataError(
                    f"no averaging factor in ms leaves enough data ({src.n} points) for any method"
                )
            below = [j for j in done if m_list[j] < m_list[i]]
            if below:
                source = max(below, key=lambda j: m_list[j])
            else:
                source = min(done, key=lambda j: (abs(math.log(m_list[j] / m_list[i])), -m_list[j]))
            alpha[i] = alpha[source]
    return np.clip(alpha, lo, hi).astype(float), est


def _attach(result: StabilityResult, src: _Series, data_type: str, *, alpha: Optional[int],
            confidence: float, ci: Optional[str], id_factors: Optional[np.ndarray] = None,
            identified: Optional[tuple[np.ndarray, np.ndarray]] = None, gaps: bool = False) -> StabilityResult:
    """:func:`sigmatau.uncertainty.attach.attach` with the noise identified chunk-wise
    (``gaps``: the record holds missing samples, NaN, and the in-memory gap rules apply)."""
    if ci is None or len(result) == 0 or alpha is not None or identified is not None:
        # The data are not looked at on these paths.
        return attach(result, np.empty(0), data_type, alpha=alpha, confidence=confidence, ci=ci,
                      id_factors=id_factors, identified=identified)
    factors = result.m if id_factors is None else id_factors
    try:
        same = np.array_equal(factors, result.m)
        ident = _identify(src, factors, data_type, result.statistic, n_terms=result.n if same else None,
                          gaps=gaps)
    except DataError as exc:
        nan = np.full(len(result), np.nan)
        out = attach(result, np.empty(0), data_type, alpha=None, confidence=confidence, ci=ci, identified=(nan, nan))
        if ci == "chi2" and result.statistic in EDF_STATISTICS:
            reason = f"noise type not identified ({exc}); give alpha= for an interval"
            out = replace(out, ci_reason=(reason,) * len(result))
        return out
    return attach(result, np.empty(0), data_type, alpha=None, confidence=confidence, ci=ci, identified=ident)
