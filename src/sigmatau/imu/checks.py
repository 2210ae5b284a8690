"""Checks of an IMU log that change the noise figures read from it.

:func:`check_samples` looks for four problems and reports them in a
:class:`DataChecks`; each one that affects the answer is also issued as a
:class:`DataCheckWarning` subclass through :func:`warnings.warn`:

* **quantisation** — the quantisation step (LSB) is estimated from the sample
  values. Rate-sample quantisation adds white noise of density
  ``LSB/√(12 f)`` to N; below about 3 LSB of standard deviation the additive
  model fails and the white-noise figures mean little
  (:class:`QuantizationWarning`).
* **decimation without averaging** — a log taken by keeping every k-th sample
  of a faster stream has no anti-alias roll-off below f/2 and a white-noise
  density √k too large (:class:`AliasingWarning`, when the sensor's own rate
  is given; the limits of the test are in :func:`check_samples`).
* **saturation** — samples piled up at the extreme values (or beyond a given
  full scale) (:class:`SaturationWarning`).
* **stuck values** — runs of identical consecutive samples longer than chance
  allows, and logs that repeat (hold) samples because they are recorded faster
  than the sensor updates (:class:`StuckValueWarning`).

:func:`~sigmatau.imu.timestamps.check_timestamps` (in ``timestamps``) reports
out-of-order, duplicated and missing time stamps and the sample rate they imply.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import asdict, dataclass
from typing import Any, Optional

import numpy as np

from ..core.accel import fused_for
from ..core.validate import as_series, check_rate
from ..core.gaps import present_runs
from ..errors import ParameterError, SigmaTauWarning

__all__ = [
    "DataCheckWarning",
    "QuantizationWarning",
    "AliasingWarning",
    "SaturationWarning",
    "StuckValueWarning",
    "DataChecks",
    "estimate_lsb",
    "check_samples",
    "FEW_LSB",
]

#: Samples looked at to decide whether a channel is continuous (not on a grid).
_HEAD = 65536

#: Standard deviation, in LSB, below which a quantised channel is warned about.
FEW_LSB = 3.0

# Spectral bands (fractions of the sample rate) for the roll-off test.
_MID_BAND = (0.10, 0.25)
_TOP_BAND = (0.40, 0.48)
_ROLLS_OFF_BELOW = 0.8
_RISES_ABOVE = 1.4


class DataCheckWarning(SigmaTauWarning):
    """A property of the data changes the noise figures read from it."""


class QuantizationWarning(DataCheckWarning):
    """The samples span only a few quantisation steps."""


class AliasingWarning(DataCheckWarning):
    """The log looks decimated without averaging (white noise aliased into the band)."""


class SaturationWarning(DataCheckWarning):
    """Samples sit at the sensor's full scale."""


class StuckValueWarning(DataCheckWarning):
    """Runs of repeated values longer than chance allows."""


@dataclass(frozen=True)
class DataChecks:
    """Findings of :func:`check_samples` on one channel.

    Attributes
    ----------
    n_samples : int
    std : float
        Standard deviation of the samples (their unit).
    levels : int or None
        Number of distinct values; None when the samples are continuous (most
        of the first 65 536 samples differ), which is not counted.
    lsb : float or None
        Estimated quantisation step; None when the samples are not on a grid.
    std_lsb : float or None
        ``std / lsb``.
    quantization_density : float or None
        White-noise density ``lsb/√(12·rate)`` that an (additive, uniform)
        quantiser adds to N, in the unit per √Hz.
    spectrum_ratio : float or None
        Mean power spectral density in 0.40–0.48·f over that in 0.10–0.25·f
        (Welch, Hann window); None for fewer than 256 samples.
    rolloff : {"rolls off", "flat", "rises", "unknown"}
        ``< 0.8``: the log is low-passed below f/2 (anti-alias filtered); 0.8–1.4: flat up
        to f/2; ``> 1.4``: rising (angle quantisation or white phase noise, or a
        folded filter skirt).
    decimation_factor : float or None
        ``odr / rate`` when the sensor's output data rate was given.
    saturated : int
        Samples at a piled-up extreme value or beyond ``full_scale``.
    stuck_runs, stuck_samples, longest_run : int
        Runs of identical consecutive samples at least ``run_threshold`` long,
        the samples in them, and the longest run of any length.
    run_threshold : int
        Shortest run counted as stuck: fewer than 0.01 such runs are expected
        by chance in the record from the distribution of the values.
    repeated_fraction : float
        Fraction of consecutive samples that are equal.
    findings : tuple of str
        One sentence per finding, in the order above.
    warned : tuple of (str, str)
        ``(warning class name, message)`` of each problem that changes the
        figures (issued as warnings when ``warn=True``).
    """

    n_samples: int
    std: float
    levels: Optional[int]
    lsb: Optional[float]
    std_lsb: Optional[float]
    quantization_density: Optional[float]
    spectrum_ratio: Optional[float]
    rolloff: str
    decimation_factor: Optional[float]
    saturated: int
    stuck_runs: int
    stuck_samples: int
    longest_run: int
    run_threshold: int
    repeated_fraction: float
    findings: tuple[str, ...] = ()
    warned: tuple[tuple[str, str], ...] = ()

    @property
    def quantized(self) -> bool:
        """True when the samples lie on a grid of step ``lsb``."""
        return self.lsb is not None

    @property
    def coarse(self) -> bool:
        """True when the standard deviation is below :data:`FEW_LSB` LSB."""
        return self.std_lsb is not None and self.std_lsb < FEW_LSB

    def to_dict(self) -> dict[str, Any]:
        """Plain dictionary (JSON-ready)."""
        out = asdict(self)
        out["findings"] = list(self.findings)
        out["warned"] = [list(w) for w in self.warned]
        return out


def estimate_lsb(samples: object, *, max_levels_fraction: float = 0.25) -> Optional[float]:
    """Quantisation step of samples that lie on a regular grid, or None.

    Parameters
    ----------
    samples : array_like
        1-D samples.
    max_levels_fraction : float
        Samples with more distinct values than this fraction of their number
        are taken as unquantised (continuous) without further test.

    Returns
    -------
    float or None

    Notes
    -----
    The distinct values are sorted; the smallest gap between neighbours is the
    candidate step, accepted when at least 99 % of all gaps are whole multiples
    of it within 5 % (values printed with a few significant digits, such as
    ``%.6g``, pass). The step is then refined as the span divided by the whole
    number of steps in it.

    Examples
    --------
    >>> import numpy as np
    >>> from sigmatau.checks import estimate_lsb
    >>> x = 0.05 * np.round(np.random.default_rng(0).normal(0, 8, 5000))
    >>> round(estimate_lsb(x), 6)
    0.05
    >>> estimate_lsb(np.random.default_rng(0).normal(size=5000)) is None
    True
    """
    x = as_series(samples, "samples", gaps=True)
    x = x[~np.isnan(x)]  # missing samples (gaps) hold no level
    u = np.unique(x)
    if u.size > max(16, max_levels_fraction * x.size):
        return None
    return _lsb_from_levels(u, x.size)


def _lsb_from_levels(u: np.ndarray, n: int) -> Optional[float]:
    """Grid step of the sorted distinct values ``u`` (see :func:`estimate_lsb`)."""
    if u.size < 2 or u.size > max(16, 0.25 * n):
        return None
    gaps = np.diff(u)
    span = float(u[-1] - u[0])
    gaps = gaps[gaps > 1e-12 * max(span, abs(float(u[-1])), 1e-300)]
    if gaps.size == 0:
        return None
    step = float(gaps.min())
    ratio = gaps / step
    good = np.abs(ratio - np.round(ratio)) < 0.05
    if good.mean() < 0.99:
        return None
    count = round(span / step)
    return span / count if count > 0 else step


def _spectrum_ratio(x: np.ndarray, rate: float) -> Optional[float]:
    if x.size < 256:
        return None
    nper = int(min(4096, 2 ** int(math.log2(x.size // 8))))
    f, p = welch_density(x, rate, nper)
    mid = (f >= _MID_BAND[0] * rate) & (f <= _MID_BAND[1] * rate)
    top = (f >= _TOP_BAND[0] * rate) & (f <= _TOP_BAND[1] * rate)
    if not mid.any() or not top.any() or p[mid].mean() <= 0:
        return None
    return float(p[top].mean() / p[mid].mean())


#: Samples per batch of Welch segments (32 MB of float64): bounds the memory of :func:`welch_density`.
_WELCH_BATCH = 1 << 22


def welch_density(x: np.ndarray, rate: float, nperseg: int, *, remove_mean: bool = True,
                  max_segments: Optional[int] = None, single: bool = False,
                  workers: Optional[int] = None) -> tuple[np.ndarray, np.ndarray]:
    """One-sided power spectral density by Welch's method, as ``scipy.signal.welch`` with its defaults.

    Periodic Hann window of ``nperseg`` points, half-overlapped segments (the
    trailing samples that fill no segment are left out), the mean of each
    segment removed, density scaling:

    .. math:: P(f_k) = \\frac{c_k}{f_s \\sum_j w_j^2}\\,\\frac{1}{L}\\sum_{l=0}^{L-1}
              \\Bigl|\\sum_j w_j (x_{lS+j} - \\bar x_l) e^{-2πi jk/n}\\Bigr|^2,

    S = n − ⌊n/2⌋, c_k = 2 except at 0 and at the Nyquist frequency (P. D. Welch,
    IEEE Trans. Audio Electroacoust. 15(2), 1967). Equal to scipy's to rounding;
    the segments are taken from a strided view of ``x`` in batches, so the cost
    is one pass of FFTs with at most :data:`_WELCH_BATCH` samples of scratch
    memory (scipy's implementation detrends segment by segment in Python and
    took 5.6 s on a 21.6-million-sample channel; this takes under 1 s).

    Parameters
    ----------
    x : numpy.ndarray
        The samples.
    rate : float
        Sample rate in Hz.
    nperseg : int
        Segment length.
    remove_mean : bool
        Subtract the record's mean before each segment's (so that the segment
        means are small; the data checks do, the signal figure does not).
    max_segments : int, optional
        Average at most this many segments, spread evenly over the record (L is
        then their number); default all.
    single : bool
        Window and transform in single precision (a figure: about 1e-6 relative,
        half the cost of the transforms); the sums stay in double precision.
    workers : int, optional
        Threads of the FFT (``scipy.fft.rfft``; -1 for all cores).

    Returns
    -------
    f, p : numpy.ndarray
        Frequencies (Hz) and density (unit²/Hz).
    """
    from scipy.fft import rfft, rfftfreq
    from scipy.signal import get_window

    step = nperseg - nperseg // 2  # scipy's default overlap is ⌊n/2⌋ points
    n_seg = (x.size - nperseg) // step + 1
    if nperseg < 2 or n_seg < 1:
        raise ParameterError(f"Welch needs 2 ≤ nperseg ≤ {x.size} samples, got nperseg={nperseg}")
    segments = np.lib.stride_tricks.sliding_window_view(x, nperseg)[::step][:n_seg]
    # Segments picked batch by batch: indexing them all at once would copy them (0.27 GB for a figure).
    pick = None if max_segments is None or n_seg <= max_segments else \
        np.linspace(0, n_seg - 1, max_segments).round().astype(np.int64)
    used = n_seg if pick is None else pick.size
    dtype = np.float32 if single else np.float64
    win = get_window("hann", nperseg).astype(dtype)
    mean = float(np.mean(x)) if remove_mean else None
    per_batch = max(1, _WELCH_BATCH // nperseg)
    buf = np.empty((min(per_batch, used), nperseg), dtype=dtype)
    acc = np.zeros(nperseg // 2 + 1)
    for lo in range(0, used, per_batch):
        chunk = segments[lo:lo + per_batch] if pick is None else segments[pick[lo:lo + per_batch]]
        if mean is not None:
            chunk = chunk - mean
        seg = buf[: chunk.shape[0]]
        np.subtract(chunk, chunk.mean(axis=1, keepdims=True), out=seg, casting="same_kind")
        seg *= win
        spec = rfft(seg, axis=1, workers=workers)
        acc += np.einsum("ij,ij->j", spec.real, spec.real, dtype=np.float64)
        acc += np.einsum("ij,ij->j", spec.imag, spec.imag, dtype=np.float64)
    w64 = win.astype(np.float64)
    p = acc / (used * rate * float(np.sum(w64 * w64)))
    p[1:(None if nperseg % 2 else -1)] *= 2.0
    return rfftfreq(nperseg, 1.0 / rate), p


def _repeat_runs(same: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start index and length of each run of two or more equal consecutive values.

    ``same[i]`` says ``x[i+1] == x[i]``. Runs of one sample are left out: on
    continuous data they are every sample, and listing them cost two
    record-sized integer arrays for nothing (stuck runs are three or more).
    """
    idx = np.flatnonzero(same)
    if idx.size == 0:
        return idx, idx
    breaks = np.flatnonzero(np.diff(idx) != 1) + 1
    first = idx[np.concatenate(([0], breaks))]
    last = idx[np.concatenate((breaks - 1, [idx.size - 1]))]
    return first, last - first + 2


def _pile_up(x: np.ndarray, value: float, neighbour_count: int, quantized: bool) -> int:
    count = int(np.count_nonzero(x == value))
    if count < 3:
        return 0
    if quantized and count <= 2 * neighbour_count + 2:
        return 0
    return count


def check_samples(
    samples: object,
    *,
    rate: float,
    unit: Optional[str] = None,
    lsb: Optional[float] = None,
    odr: Optional[float] = None,
    full_scale: Optional[float] = None,
    warn: bool = True,
) -> DataChecks:
    """Check one channel of an IMU log for problems that change its noise figures.

    Parameters
    ----------
    samples : array_like
        1-D samples (rate or specific force).
    rate : float
        Sample rate of the log in Hz.
    unit : str, optional
        Unit of the samples, used in the messages only.
    lsb : float, optional
        Known quantisation step; estimated by :func:`estimate_lsb` if omitted.
    odr : float, optional
        Output data rate of the sensor itself, in Hz, if known. When it exceeds
        ``rate`` the log was decimated, and the spectrum says whether it was
        averaged.
    full_scale : float, optional
        Full-scale range (±) of the sensor in the unit of the samples.
    warn : bool
        Issue the :class:`DataCheckWarning` subclasses (default True).

    Returns
    -------
    DataChecks

    Notes
    -----
    *Quantisation.* Uniform quantisation of the rate samples with step Δ adds
    white noise of variance Δ²/12 per sample, i.e. a density ``Δ/√(12 f)`` that
    adds in quadrature to N (it does not produce the −1 slope "Q" term, which
    comes from quantising the integrated angle or velocity). The additive model
    needs a few LSB of noise; below :data:`FEW_LSB` a warning is issued.

    *Decimation.* A log decimated through a proper anti-alias filter shows a
    PSD that rolls off towards f/2; keeping every k-th sample of a faster
    stream folds the whole band in and leaves the PSD flat (or rising, when the
    folded skirt of the original filter shows). The ratio of the PSD near f/2 to
    the mid band measures that roll-off with a statistical error below 3 % for
    10⁴ samples or more (tests/test_checks.py). What it cannot do is tell
    picking from block averaging on white noise: the means of disjoint blocks
    of white noise are white too, with the same density N, whereas picked
    samples keep the per-sample σ and show a density √k too large. Nor does a
    flat spectrum alone prove decimation (a sensor whose bandwidth reaches f/2
    looks the same). So :class:`AliasingWarning` is issued only when ``odr``
    shows the log was decimated and the spectrum has no anti-alias roll-off;
    it states both readings. Comparing N with the datasheet density (a ratio
    near √k) settles it (:meth:`sigmatau.imu.NoiseModel.compare`).

    *Saturation.* The largest (smallest) value is a pile-up when at least 3
    samples sit on it and, for quantised data, more than twice as many as on the
    next occupied level; or any sample at ±``full_scale``.

    *Stuck values.* With p the larger of ``Σ p_k²`` (the chance that two
    independent samples are equal, ``p_k`` the frequencies of the distinct
    values) and the observed fraction of equal consecutive samples, a run of L
    equal samples starts at a given sample with probability about ``p^(L−1)``;
    runs at least ``L* = 1 + ⌈ln(0.01/n)/ln p⌉`` long are reported as stuck.
    Serially correlated signals make long runs likelier than this, so the
    threshold is a screen, not a test; a warning is issued only when the stuck
    samples reach 0.1 % of the record or a run lasts 1 s. A fraction of equal
    consecutive samples much larger than ``Σ p_k²`` (over 3·Σ p_k² + 5 %) means
    samples are held: the log runs faster than the sensor updates.

    Examples
    --------
    >>> import numpy as np
    >>> from sigmatau.checks import check_samples
    >>> x = 0.05 * np.round(np.random.default_rng(1).normal(0, 8, 20000))
    >>> c = check_samples(x, rate=100.0, unit="deg/s")
    >>> round(c.lsb, 3), c.coarse
    (0.05, False)
    """
    x = as_series(samples, "samples", gaps=True)
    rate_f = check_rate(rate)
    u = f" {unit}" if unit else ""
    found = _Findings()
    # Missing samples (NaN gaps): the checks of values read the samples present, the
    # spectrum the longest gap-free run.
    missing = np.isnan(x)
    present = x[~missing] if missing.any() else x  # no copy of a record without gaps
    del missing
    contiguous = x if present.size == x.size else _longest_run(x)
    n = present.size
    fast = fused_for(n) if n > 1 else None  # numpy's std bit for bit, without its temporary
    std = (fast.std(present, 1) if fast is not None else float(present.std(ddof=1))) if n > 1 else 0.0
    q = _check_quantisation(present, rate_f, lsb, std, u, found)
    ratio, rolloff = _check_spectrum(contiguous, rate_f, q.n_levels, found)
    dec = _check_decimation(odr, rate_f, rolloff, found)
    saturated = _check_saturation(present, q, full_scale, u, found)
    runs = _check_runs(present, q, rate_f, found)
    if warn:
        for cls, msg in found.issued:
            warnings.warn(msg, cls, stacklevel=2)
    return DataChecks(
        n_samples=int(n), std=std, levels=q.n_levels, lsb=q.step, std_lsb=q.std_lsb,
        quantization_density=q.qdens, spectrum_ratio=ratio, rolloff=rolloff, decimation_factor=dec,
        saturated=int(saturated), stuck_runs=runs.stuck_runs, stuck_samples=runs.stuck_samples,
        longest_run=runs.longest, run_threshold=int(runs.threshold),
        repeated_fraction=runs.repeated, findings=tuple(found.findings),
        warned=tuple((cls.__name__, msg) for cls, msg in found.issued),
    )


def _longest_run(x: np.ndarray) -> np.ndarray:
    """The longest stretch of ``x`` without a missing sample (NaN)."""
    starts, stops = present_runs(np.isnan(x))
    i = int(np.argmax(stops - starts))
    return x[starts[i]:stops[i]]


class _Findings:
    """What the checks found: every finding as text, and those that warrant a warning."""

    def __init__(self) -> None:
        self.findings: list[str] = []
        self.issued: list[tuple[type, str]] = []

    def note(self, msg: str) -> None:
        self.findings.append(msg)

    def warn(self, cls: type, msg: str) -> None:
        self.findings.append(msg)
        self.issued.append((cls, msg))


@dataclass(frozen=True)
class _Levels:
    """The quantisation of a channel: its step and, for a quantised one, its distinct values."""

    step: Optional[float]
    values: Optional[np.ndarray]
    counts: Optional[np.ndarray]
    std_lsb: Optional[float]
    qdens: Optional[float]

    @property
    def n_levels(self) -> Optional[int]:
        return None if self.values is None else int(self.values.size)


def _check_quantisation(x: np.ndarray, rate_f: float, lsb: Optional[float], std: float, u: str,
                        found: _Findings) -> _Levels:
    """The LSB (given or estimated from the levels), its white-noise floor, and a warning below FEW_LSB."""
    if lsb is not None:
        if isinstance(lsb, bool) or not (isinstance(lsb, (int, float, np.floating, np.integer)) and lsb > 0
                                         and math.isfinite(lsb)):
            raise ParameterError(f"lsb={lsb!r} must be a positive number")
    head = x[:_HEAD]
    continuous = np.unique(head).size > 0.5 * head.size and head.size >= 64
    if continuous:
        values = counts = None
        step: Optional[float] = float(lsb) if lsb is not None else None
    else:
        values, counts = np.unique(x, return_counts=True)
        step = float(lsb) if lsb is not None else _lsb_from_levels(values, x.size)
    std_lsb = std / step if step else None
    qdens = step / math.sqrt(12.0 * rate_f) if step else None
    if step is not None:
        levels_text = f", {values.size} levels" if values is not None else ""
        found.note(
            f"quantised: LSB {step:.6g}{u}{levels_text}, std {std_lsb:.3g} LSB;"
            f" the quantiser adds a white-noise density of about {qdens:.3g}{u}/√Hz to N"
        )
        if std_lsb is not None and std_lsb < FEW_LSB:
            found.warn(QuantizationWarning,
                       f"std is only {std_lsb:.2g} LSB (LSB {step:.6g}{u}): quantisation dominates the short-τ"
                       f" noise and the white-noise figure (N) is unreliable; its quantisation floor is"
                       f" {qdens:.3g}{u}/√Hz")
    levels = _Levels(step, values, counts, std_lsb, qdens)
    if levels.n_levels == 1:
        found.warn(StuckValueWarning, "all samples are equal: nothing to analyse")
    return levels


def _check_spectrum(x: np.ndarray, rate_f: float, n_levels: Optional[int],
                    found: _Findings) -> tuple[Optional[float], str]:
    """The PSD ratio near Nyquist and what it says: ``rolls off``, ``flat``, ``rises`` or ``unknown``."""
    ratio = _spectrum_ratio(x, rate_f) if n_levels != 1 else None
    if ratio is None:
        return None, "unknown"
    if ratio < _ROLLS_OFF_BELOW:
        rolloff = "rolls off"
    elif ratio > _RISES_ABOVE:
        rolloff = "rises"
    else:
        rolloff = "flat"
    text = {
        "rolls off": "the spectrum rolls off below f/2 (the samples are averaged or low-passed)",
        "flat": "the spectrum is flat up to f/2 (sensor bandwidth ≥ f/2, or decimation without averaging)",
        "rises": "the spectrum rises towards f/2 (angle/velocity quantisation, or a folded filter skirt)",
    }[rolloff]
    found.note(f"{text}: PSD(0.40–0.48 f)/PSD(0.10–0.25 f) = {ratio:.2f}")
    return ratio, rolloff


def _check_decimation(odr: Optional[float], rate_f: float, rolloff: str, found: _Findings) -> Optional[float]:
    """The decimation factor from the sensor's own rate, and a warning when it aliased white noise."""
    if odr is None:
        return None
    odr_f = check_rate(odr)
    dec = odr_f / rate_f
    if dec > 1.01:
        if rolloff in ("flat", "rises"):
            found.warn(AliasingWarning,
                       f"the sensor runs at {odr_f:g} Hz and the log at {rate_f:g} Hz with no anti-alias roll-off:"
                       f" if every {dec:.3g}th sample was kept (decimation without averaging) the white-noise"
                       f" density N appears √{dec:.3g} = {math.sqrt(dec):.3g} times too large (the per-sample σ is"
                       " right); block averages would keep N. Compare N with the datasheet density to tell")
        elif rolloff == "rolls off":
            found.note(f"decimated by {dec:.3g} from {odr_f:g} Hz through an anti-alias filter"
                       " (roll-off present)")
    elif dec < 0.99:
        found.note(f"the log rate {rate_f:g} Hz exceeds the sensor's output rate {odr_f:g} Hz:"
                   " samples are repeated")
    return dec


def _check_saturation(x: np.ndarray, q: _Levels, full_scale: Optional[float], u: str, found: _Findings) -> int:
    """Samples piled up at the extremes (or at ±full_scale): the number that look saturated."""
    quantized = q.step is not None
    values, counts = q.values, q.counts
    saturated = 0
    where: list[str] = []
    if values is None:
        top, bottom = float(x.max()), float(x.min())
        hi, lo = _pile_up(x, top, 0, False), _pile_up(x, bottom, 0, False)
    elif values.size > 2:
        top, bottom = float(values[-1]), float(values[0])
        hi = _pile_up(x, top, int(counts[-2]), quantized)  # type: ignore[index]
        lo = _pile_up(x, bottom, int(counts[1]), quantized)  # type: ignore[index]
    else:
        hi = lo = 0
    if hi or lo:
        saturated = hi + lo
        where = [f"{c} at {v:.6g}{u}" for c, v in ((hi, top), (lo, bottom)) if c]
    if full_scale is not None:
        fs = float(full_scale)
        if not (fs > 0 and math.isfinite(fs)):
            raise ParameterError(f"full_scale={full_scale!r} must be a positive number")
        beyond = int(np.count_nonzero(np.abs(x) >= fs * (1.0 - 1e-9)))
        if beyond > saturated:
            saturated = beyond
            where = [f"{beyond} at or beyond ±{fs:g}{u}"]
    if saturated:
        found.warn(SaturationWarning,
                   f"{saturated} samples ({100.0 * saturated / x.size:.3g} %) look saturated ({', '.join(where)}):"
                   " clipped segments bias every deviation; cut them out")
    return saturated


@dataclass(frozen=True)
class _Runs:
    """Runs of identical samples: those long enough to be stuck, and the fraction of repeats."""

    stuck_runs: int
    stuck_samples: int
    longest: int
    threshold: int
    repeated: float


def _check_runs(x: np.ndarray, q: _Levels, rate_f: float, found: _Findings) -> _Runs:
    """Stuck output (runs too long for chance) and held samples (too many equal neighbours)."""
    n, n_levels, counts = x.size, q.n_levels, q.counts
    same = x[1:] == x[:-1]
    starts, lengths = _repeat_runs(same)
    longest = int(lengths.max()) if lengths.size else min(n, 1)
    p_same = float(np.sum((counts / n) ** 2)) if counts is not None else 0.0
    repeated = float(np.mean(same)) if n > 1 else 0.0
    p_run = max(p_same, repeated)
    if n > 1 and 0.0 < p_run < 1.0:
        threshold = 1 + max(1, math.ceil(math.log(0.01 / n) / math.log(p_run)))
    else:
        threshold = n + 1
    threshold = max(threshold, 3)
    stuck = lengths >= threshold
    stuck_runs = int(stuck.sum()) if n_levels != 1 else 0
    stuck_samples = int(lengths[stuck].sum()) if stuck_runs else 0
    if stuck_runs:
        first = int(np.argmax(stuck))
        longest_s = float(lengths[stuck].max()) / rate_f
        msg = (f"{stuck_runs} run(s) of ≥ {threshold} identical samples ({stuck_samples} samples, longest"
               f" {longest} = {longest_s:.3g} s, first at index {int(starts[first])}):"
               " stuck output or dropped updates")
        if stuck_samples >= 1e-3 * n or longest_s >= 1.0:
            found.warn(StuckValueWarning, msg)
        else:
            found.note(msg + f"; too short to change the figures ({100 * stuck_samples / n:.2g} % of the record)")
    if n > 1 and n_levels != 1 and repeated > 3.0 * p_same + 0.05:
        found.warn(StuckValueWarning,
                   f"{100 * repeated:.3g} % of consecutive samples are equal (chance: {100 * p_same:.2g} %):"
                   " the log is recorded faster than the sensor updates (held samples); use the sensor's rate")
    return _Runs(stuck_runs, stuck_samples, longest if n else 0, int(threshold), repeated)
