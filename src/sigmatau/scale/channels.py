"""One statistic over several channels at once, on every core.

NumPy releases the GIL inside the array operations the kernels spend their time
in (differences, running sums, sums of squares, FFTs), so a thread per channel
runs the channels in parallel without copying the data to other processes.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from typing import Callable, Mapping, Optional, Union

import numpy as np

from ..core.validate import as_series
from ..errors import DataError, ParameterError
from ..core.result import StabilityResult

__all__ = ["compute_channels"]

Channels = Union[Mapping[str, object], np.ndarray]


def _split(data: Channels) -> dict[str, np.ndarray]:
    if isinstance(data, Mapping):
        if not data:
            raise DataError("no channels given")
        return {str(k): as_series(v, f"channel {k!r}") for k, v in data.items()}
    arr = np.asarray(data)
    if arr.ndim != 2:
        raise DataError(f"channels must be a mapping of 1-D arrays or a 2-D array (samples × channels), got shape {arr.shape}")
    return {str(i): as_series(arr[:, i], f"channel {i}") for i in range(arr.shape[1])}


def compute_channels(
    statistic: Callable[..., StabilityResult],
    data: Channels,
    *,
    workers: Optional[int] = None,
    **options: object,
) -> dict[str, StabilityResult]:
    """Apply one statistic to several channels in parallel threads.

    Parameters
    ----------
    statistic : callable
        A statistic function of sigmatau, e.g. :func:`sigmatau.oadev`.
    data : mapping or 2-D array
        ``{name: samples}``, or an array of shape (samples, channels) whose
        columns are named "0", "1", ….
    workers : int, optional
        Number of threads; default: the number of usable cores (at most one per
        channel). ``workers=1`` computes serially.
    **options
        Keyword arguments of ``statistic`` (``rate``, ``taus``, ``ci`` …).

    Returns
    -------
    dict of str to StabilityResult
        One result per channel, in the order given; identical to calling
        ``statistic`` on each channel in turn.

    Examples
    --------
    >>> import numpy as np, sigmatau
    >>> rng = np.random.default_rng(0)
    >>> imu = {"gyro_x": rng.standard_normal(10_000), "gyro_y": rng.standard_normal(10_000)}
    >>> out = sigmatau.compute_channels(sigmatau.oadev, imu, rate=100.0)
    >>> list(out), len(out["gyro_x"]) > 0
    (['gyro_x', 'gyro_y'], True)
    """
    if not callable(statistic):
        raise ParameterError(f"statistic={statistic!r} must be a statistic function such as sigmatau.oadev")
    channels = _split(data)
    if workers is None:
        usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
        workers = usable
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 1:
        raise ParameterError(f"workers={workers!r} must be a positive integer")
    workers = min(int(workers), len(channels))
    if workers == 1:
        return {name: statistic(values, **options) for name, values in channels.items()}
    with ThreadPoolExecutor(max_workers=workers, thread_name_prefix="sigmatau") as pool:
        futures = {name: pool.submit(statistic, values, **options) for name, values in channels.items()}
        return {name: future.result() for name, future in futures.items()}
