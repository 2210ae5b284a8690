"""``compute``: a chunked statistic by name, on a series, a dask array or a path it opens itself."""

from __future__ import annotations

import os
from typing import Optional

from ...core.result import StabilityResult
from ...errors import ParameterError
from ...uncertainty.confidence import ONE_SIGMA
from .sources import STATISTICS, ChunkedSeries, as_chunked


def compute(
    statistic: str,
    source: object,
    *,
    rate: float = 1.0,
    data_type: str = "freq",
    taus: object = "octave",
    m: object = None,
    points_per_decade: int = 10,
    alpha: Optional[int] = None,
    confidence: float = ONE_SIGMA,
    ci: Optional[str] = "chi2",
    chunk_size: Optional[int] = None,
    dtype: object = None,
    offset: int = 0,
    dataset: Optional[str] = None,
    **options: object,
) -> StabilityResult:
    """Compute ``statistic`` on a record read chunk by chunk.

    Parameters
    ----------
    statistic : str
        One of :data:`STATISTICS`.
    source : ChunkedSeries, dask array, path or array_like
        A path is opened by :func:`~sigmatau.chunked.open_series` (``.npy``; HDF5 with
        ``dataset``; raw binary with ``dtype`` and ``offset``).
    rate, data_type, taus, m, points_per_decade, alpha, confidence, ci
        As for the statistic's own function.
    chunk_size : int, optional
        Samples per read (default :data:`~sigmatau.chunked.DEFAULT_CHUNK`, or the series' own).
    dtype, offset, dataset
        How to read a path (see :func:`~sigmatau.chunked.open_series`).
    **options
        Further keywords of the statistic (``bias`` for ``totdev``).

    Returns
    -------
    StabilityResult
        The result of ``sigmatau.<statistic>(data_in_memory, ...)``, variance
        within 1e-12 relative.

    Examples
    --------
    >>> import numpy as np, sigmatau
    >>> from sigmatau import chunked
    >>> y = np.random.default_rng(0).standard_normal(5000)
    >>> r = chunked.compute("oadev", y, chunk_size=999, m=[1, 10, 100])
    >>> bool(np.allclose(r.dev, sigmatau.oadev(y, m=[1, 10, 100]).dev, rtol=1e-12))
    True
    """
    if statistic not in STATISTICS:
        raise ParameterError(f"statistic={statistic!r} must be one of {STATISTICS}")
    opened = not isinstance(source, ChunkedSeries) and isinstance(source, (str, os.PathLike))
    src = as_chunked(source, chunk_size=chunk_size, dtype=dtype, offset=offset, dataset=dataset)
    from ...stats import allan, hadamard, total

    func = {"adev": allan.adev, "oadev": allan.oadev, "mdev": allan.mdev, "tdev": allan.tdev,
            "hdev": hadamard.hdev, "ohdev": hadamard.ohdev, "totdev": total.totdev}[statistic]
    try:
        return func(src, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
                    alpha=alpha, confidence=confidence, ci=ci, **options)
    finally:
        if opened:
            src.close()
