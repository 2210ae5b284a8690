"""The signal figure of one channel: time series, Welch PSD with the model's spectra, lag plot.

Public through :mod:`sigmatau.report.plots` (:func:`signal_figure`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Optional

import numpy as np

from ..core.validate import check_rate
from ..errors import DataError, ParameterError
from .figbase import (_FS, _FS_LABEL, _FS_TITLE, _GRID, _TERMS, STATISTIC_COLORS, TERM_COLORS, _freeze_layout,
                      _pretty, _set_title, _style_log_axes, new_figure)
from .figmodel import _unit_factor

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from ..imu.model import NoiseModel

def _time_scale(duration: float) -> tuple[float, str]:
    """Divisor and unit of the time axis: hours, minutes or seconds."""
    if duration >= 2 * 3600:
        return 3600.0, "h"
    if duration >= 120:
        return 60.0, "min"
    return 1.0, "s"


#: Most Welch segments averaged for the PSD panel. Up to this many (records up to 129 · 2¹⁷
#: samples, 4.7 h at 1 kHz) every segment is used; longer records average this many segments
#: spread evenly over the record, so the panel costs the same for a day as for five hours. 128
#: half-overlapping segments still leave only ±9 % scatter in the lowest frequency bins (the
#: docstring's goal is ≈30 segments), and the label says how many were used.
_MAX_WELCH_SEGMENTS = 128


def _welch(x: np.ndarray, rate: float) -> tuple[np.ndarray, np.ndarray, int, int, int]:
    """One-sided Welch PSD (Hann, 50 % overlap, each segment's mean removed) of the PSD panel.

    :func:`sigmatau.imu.checks.welch_density` with segments of about N/16
    samples, at most :data:`_MAX_WELCH_SEGMENTS` of them, windowed and
    transformed in single precision on all cores: single precision changes the
    plotted PSD by about 1e-6 relative, far below the line width, and halves
    the cost of the transforms, which dominate the figure's data work.

    Returns
    -------
    freqs, pxx : numpy.ndarray
    nperseg : int
        Segment length.
    used, nseg : int
        Segments averaged, out of the record's ``nseg`` half-overlapping ones.
    """
    from ..imu.checks import welch_density

    n = x.size
    # Segments of n/16 (≈ 30 averaged with the overlap: ±25 % at the lowest frequencies),
    # a power of two between 16 and 2^18; the log-frequency binning below smooths the rest.
    nperseg = n if n < 32 else int(2 ** min(18, max(4, math.floor(math.log2(n / 16)))))
    nseg = (n - nperseg) // (nperseg - nperseg // 2) + 1
    freqs, pxx = welch_density(x, rate, nperseg, remove_mean=False, max_segments=_MAX_WELCH_SEGMENTS,
                               single=True, workers=-1)
    return freqs, pxx, nperseg, min(nseg, _MAX_WELCH_SEGMENTS), nseg


def _log_bin(f: np.ndarray, p: np.ndarray, per_decade: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """Average the PSD in logarithmic frequency bins (keeps every low-frequency point)."""
    keep = (f > 0) & np.isfinite(p)
    f, p = f[keep], p[keep]
    if f.size < 2:
        return f, p
    lf = np.log10(f)
    idx = np.floor((lf - lf[0]) * per_decade + 1e-9).astype(np.int64)
    counts = np.bincount(idx)
    used = counts > 0
    fb = np.bincount(idx, weights=lf)[used] / counts[used]
    pb = np.bincount(idx, weights=p)[used] / counts[used]
    return 10 ** fb, pb


def _psd_unit(unit: str) -> str:
    """Unit of the PSD axis: ``unit²/Hz``."""
    u = _pretty(unit)
    if not u:
        return "1/Hz"
    return (f"({u})" if any(c in u for c in "/·* ") else u) + "²/Hz"


def _model_psd(model: "NoiseModel", f: np.ndarray, factor: float) -> dict[str, np.ndarray]:
    """One-sided PSD of each resolved term (IEEE 952 Annex C two-sided forms × 2)."""
    out: dict[str, np.ndarray] = {}
    tau0 = 1.0 / model.rate
    w = 2.0 * math.pi * f
    for term in _TERMS:
        par = getattr(model, term)
        if not par.resolved or not par.value > 0:
            continue
        c = par.value * factor
        out[term] = {
            "Q": 2.0 * tau0 * (w * c) ** 2,
            "N": np.full(f.shape, 2.0 * c * c),
            "B": c * c / (math.pi * f),
            "K": 2.0 * (c / w) ** 2,
            "R": 2.0 * c * c / w**3,
        }[term]
    return out


@dataclass(frozen=True)
class SignalData:
    """What :func:`signal_figure` draws, computed from the samples (:func:`prepare_signal`).

    The passes over the record (min/max envelope, Welch PSD, lag-1
    correlation) are here, apart from the drawing, so that the main job can
    prepare several channels in threads (numpy releases the GIL) while
    matplotlib draws one figure at a time.

    Attributes
    ----------
    x : numpy.ndarray
        The finite samples (the caller's array when all are finite; not copied).
    times : numpy.ndarray or None
        Their times in seconds when NaN were dropped, else None.
    envelope : tuple of numpy.ndarray or None
        ``(edges, lo, hi, mean)`` of the display bins for long records, else None.
    psd : tuple or None
        ``(freqs, pxx, nperseg, used, nseg)`` of :func:`_welch`, or None (too short or constant).
    r1 : float
        Lag-1 correlation of the whole record.
    """

    x: np.ndarray
    times: Optional[np.ndarray]
    envelope: Optional[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]
    psd: Optional[tuple[np.ndarray, np.ndarray, int, int, int]]
    r1: float


#: Display bins of the time-series panel: longer records are drawn as min/max envelope and mean.
_SERIES_BINS = 1500


def prepare_signal(samples: Any, *, rate: float, name: str) -> SignalData:
    """The data of :func:`signal_figure` for one channel: every pass over the record, no drawing.

    Raises
    ------
    DataError
        Non-numeric or non-1-D samples, or fewer than 4 finite values.
    """
    rate = check_rate(rate)
    x, t_all = _finite_samples(samples, rate, name)
    envelope = None
    if x.size > 2 * _SERIES_BINS:
        edges = np.linspace(0, x.size, _SERIES_BINS + 1).astype(np.int64)
        envelope = (edges, np.minimum.reduceat(x, edges[:-1]), np.maximum.reduceat(x, edges[:-1]),
                    np.add.reduceat(x, edges[:-1]) / np.diff(edges))
    psd = _welch(x, rate) if x.size >= 16 and np.ptp(x) > 0 else None
    return SignalData(x, t_all, envelope, psd, _lag1_correlation(x))


def signal_figure(
    samples: Any,
    *,
    rate: float,
    name: str,
    unit: str,
    model: Optional["NoiseModel"] = None,
    max_points: int = 20000,
    prepared: Optional[SignalData] = None,
) -> "Figure":
    """The design tip's Figure 2 for one channel: time series, PSD and lag plot.

    Parameters
    ----------
    samples : array_like
        1-D samples (NaN are ignored).
    rate : float
        Sample rate in Hz.
    name : str
        Channel name (titles).
    unit : str
        Unit of the samples (axis labels).
    model : NoiseModel, optional
        When given, the PSD shows each resolved term's spectrum and their sum.
    max_points : int
        Largest number of points drawn in the lag plot (subsampled evenly).
    prepared : SignalData, optional
        :func:`prepare_signal` of these samples, computed beforehand (in
        another thread, say); ``samples`` is then not read again.

    Returns
    -------
    matplotlib.figure.Figure

    Notes
    -----
    (a) Time series; long records are drawn as the min/max envelope and the
    mean of ≈1500 display bins. (b) One-sided Welch PSD (Hann window, 50 %
    overlap, segments of about N/16 samples as a power of two ≤ 2¹⁸, so the
    lowest frequencies average ≈30 segments; at most 128 segments, spread
    evenly over longer records and counted in the label), averaged in
    1/40-decade frequency bins. The model overlay uses the IEEE 952 spectra doubled to one
    side: white ``2N²``, flicker ``B²/(πf)``, random walk ``K²/(2π²f²)``,
    quantisation ``2τ0(2πf)²Q²``, ramp ``2R²/(2πf)³`` — so a channel with
    ADEV σ(1 s) = N shows the level 2N². (c) Lag plot ``x[k+1]`` against
    ``x[k]`` with the lag-1 correlation coefficient of the whole record.
    """
    rate = check_rate(rate)
    if not isinstance(name, str) or not isinstance(unit, str):
        raise ParameterError(f"name={name!r} and unit={unit!r} must be strings")
    if isinstance(max_points, bool) or not isinstance(max_points, (int, np.integer)) or max_points < 100:
        raise ParameterError(f"max_points={max_points!r} must be an integer ≥ 100")
    data = prepare_signal(samples, rate=rate, name=name) if prepared is None else prepared

    fig = new_figure((12.6, 3.9))
    gs = fig.add_gridspec(1, 3, width_ratios=[1.55, 1.25, 1.0])
    ax_t, ax_f, ax_l = (fig.add_subplot(gs[0, j]) for j in range(3))
    ulabel = _pretty(unit)
    ustr = f" [{ulabel}]" if ulabel else ""
    color = STATISTIC_COLORS["oadev"]
    _draw_series(ax_t, data, rate, f"{name}{ustr}", color)
    _draw_psd(ax_f, data, rate, unit, model, color)
    _draw_lag(ax_l, data, max_points, ustr, color)
    fig.suptitle(f"{name}: time series, spectrum and lag plot", fontsize=_FS_TITLE + 1)
    _freeze_layout(fig)
    return fig


def _finite_samples(samples: Any, rate: float, name: str) -> tuple[np.ndarray, Optional[np.ndarray]]:
    """The finite samples, and their times in seconds when NaN were dropped (else None).

    Raises
    ------
    DataError
        Non-numeric or non-1-D samples, or fewer than 4 finite values.
    """
    try:
        x = np.asarray(samples, dtype=float)
    except (TypeError, ValueError):
        raise DataError(f"samples of {name!r} must be numeric") from None
    if x.ndim != 1:
        raise DataError(f"samples of {name!r} must be 1-D, got shape {x.shape}")
    if x.size >= 4 and math.isfinite(float(np.sum(x))):
        return x, None  # one cheap pass: a finite sum means every sample is finite
    finite = np.isfinite(x)
    if int(finite.sum()) < 4:
        raise DataError(f"samples of {name!r}: {int(finite.sum())} finite values, at least 4 are needed")
    t_all = None
    if not finite.all():
        t_all = np.flatnonzero(finite) / rate
        x = x[finite]
    return x, t_all


def _draw_series(ax_t: Any, data: SignalData, rate: float, ylabel: str, color: str) -> None:
    """Panel (a): the samples, or for long records the min/max envelope and mean of ≈1500 bins."""
    x, t_all = data.x, data.times
    n = x.size
    duration = n / rate if t_all is None else float(t_all[-1] - t_all[0]) + 1.0 / rate
    scale, tu = _time_scale(duration)
    nb = _SERIES_BINS
    if data.envelope is None:
        t = (np.arange(n) / rate if t_all is None else t_all) / scale
        ax_t.plot(t, x, color=color, linewidth=0.7, gid="series")
    else:
        edges, lo, hi, mean = data.envelope
        tpos = (edges[:-1] + edges[1:]) / 2.0
        t = (tpos / rate if t_all is None else np.interp(tpos, np.arange(n), t_all)) / scale
        binw = n / nb / rate
        env = ax_t.fill_between(t, lo, hi, color=color, alpha=0.3, linewidth=0, label=f"min–max per {binw:.3g} s")
        env.set_gid("envelope")
        ax_t.plot(t, mean, color=color, linewidth=0.8, label=f"mean per {binw:.3g} s", gid="series")
        ax_t.legend(loc="best", fontsize=_FS - 1, frameon=True, framealpha=0.9, edgecolor="none")
    ax_t.set_xlabel(f"time [{tu}]", fontsize=_FS_LABEL)
    ax_t.set_ylabel(ylabel, fontsize=_FS_LABEL)
    ax_t.set_title(f"(a) time series: {n:,} samples at {rate:g} Hz", fontsize=_FS_TITLE)
    ax_t.margins(x=0.0)
    ax_t.grid(True, **_GRID)
    ax_t.tick_params(labelsize=_FS)


def _draw_psd(ax_f: Any, data: SignalData, rate: float, unit: str, model: Optional["NoiseModel"],
              color: str) -> None:
    """Panel (b): the log-binned Welch PSD, with the model's term spectra when there is a model."""
    _style_log_axes(ax_f)
    if data.psd is not None:
        freqs, pxx, nperseg, used, nseg = data.psd
        fb, pb = _log_bin(freqs, pxx)
        pos = pb > 0
        some = f", {used:,} of {nseg:,} segments" if used < nseg else ""
        ax_f.plot(fb[pos], pb[pos], color=color, linewidth=1.0, gid="psd",
                  label=f"Welch, {nperseg:,}-point Hann{some}")
        if model is not None and fb.size:
            f_m = np.geomspace(fb[pos].min() if pos.any() else fb[0], rate / 2.0, 200)
            _draw_model_psd(ax_f, model, unit, f_m)
            if pos.any():
                ax_f.set_ylim(pb[pos].min() / 3.0, pb[pos].max() * 3.0)
            ax_f.set_xlim(fb[0] / 1.2, rate / 2.0 * 1.2)
        ax_f.legend(loc="best", fontsize=_FS - 1, frameon=True, framealpha=0.9, edgecolor="none")
    else:
        ax_f.text(0.5, 0.5, "no PSD: record too short or constant", transform=ax_f.transAxes,
                  ha="center", va="center", fontsize=_FS, color="0.3")
    ax_f.set_xlabel("frequency [Hz]", fontsize=_FS_LABEL)
    ax_f.set_ylabel(f"PSD [{_psd_unit(unit)}]", fontsize=_FS_LABEL)
    _set_title(ax_f, "(b) power spectral density (one-sided)", _FS_TITLE)


def _draw_model_psd(ax_f: Any, model: "NoiseModel", unit: str, f_m: np.ndarray) -> None:
    """Each resolved term's spectrum on ``f_m`` and their sum; nothing when the units do not convert."""
    try:
        factor = _unit_factor(model, unit)
    except ParameterError:
        factor = math.nan
    if not math.isfinite(factor):
        return
    terms = _model_psd(model, f_m, factor)
    for term, s in terms.items():
        ax_f.plot(f_m, s, color=TERM_COLORS[term], linestyle=(0, (3, 1.5)), linewidth=1.2,
                  label={"Q": "quantization Q", "N": "white 2N²", "B": "flicker B²/(πf)",
                         "K": "random walk K²/(2π²f²)", "R": "ramp R"}[term], gid=f"psd-{term}")
    if len(terms) > 1:
        ax_f.plot(f_m, sum(terms.values()), color="black", linestyle=(0, (6, 2)), linewidth=1.0,
                  label="model sum", gid="psd-model")


def _lag1_correlation(x: np.ndarray, chunk: int = 1 << 16) -> float:
    """Pearson correlation of ``x[k]`` with ``x[k+1]`` over the whole record; NaN when either is constant.

    Accumulated over chunks of the record shifted by its mean (so the sums do
    not cancel), in one pass and O(chunk) memory: centring the two
    overlapping views of a day-long record at once took two temporary copies
    of it (0.7 GB each for 86 M samples).
    """
    m = x.size - 1
    c = float(np.mean(x))
    sa = sb = saa = sbb = sab = 0.0
    for s in range(0, m, chunk):
        d = x[s: min(s + chunk, m) + 1] - c
        da, db = d[:-1], d[1:]
        sa += float(da.sum())
        sb += float(db.sum())
        # einsum, not @: BLAS threads stall on a busy machine (core.numeric.sumsq)
        saa += float(np.einsum("i,i->", da, da))
        sbb += float(np.einsum("i,i->", db, db))
        sab += float(np.einsum("i,i->", da, db))
    cov = sab - sa * sb / m
    den = math.sqrt(max(saa - sa * sa / m, 0.0) * max(sbb - sb * sb / m, 0.0))
    return cov / den if den > 0 else math.nan


def _draw_lag(ax_l: Any, data: SignalData, max_points: int, ustr: str, color: str) -> None:
    """Panel (c): ``x[k+1]`` against ``x[k]`` (at most ``max_points``) and the lag-1 correlation r₁."""
    from matplotlib.ticker import MaxNLocator

    x = data.x
    n = x.size
    a, b = x[:-1], x[1:]
    r = data.r1
    idx = np.unique(np.linspace(0, n - 2, min(max_points, n - 1)).astype(np.int64))
    ax_l.scatter(a[idx], b[idx], s=2.0, color=color, alpha=0.35 if idx.size > 2000 else 0.7, linewidths=0,
                 rasterized=True, gid="lag")
    lo_, hi_ = float(min(a[idx].min(), b[idx].min())), float(max(a[idx].max(), b[idx].max()))
    pad = (hi_ - lo_) * 0.05 or max(abs(lo_), 1.0) * 0.05
    ax_l.plot([lo_ - pad, hi_ + pad], [lo_ - pad, hi_ + pad], color="0.6", linewidth=0.6, linestyle="--", zorder=0)
    ax_l.set_xlim(lo_ - pad, hi_ + pad)
    ax_l.set_ylim(lo_ - pad, hi_ + pad)
    ax_l.set_aspect("equal", adjustable="box")
    ax_l.xaxis.set_major_locator(MaxNLocator(nbins=5))
    ax_l.yaxis.set_major_locator(MaxNLocator(nbins=5))
    ax_l.grid(True, **_GRID)
    ax_l.tick_params(labelsize=_FS)
    ax_l.set_xlabel(f"x[k]{ustr}", fontsize=_FS_LABEL)
    ax_l.set_ylabel(f"x[k+1]{ustr}", fontsize=_FS_LABEL)
    rtext = "n/a" if not math.isfinite(r) else f"{r:.3f}"
    ax_l.set_title(f"(c) lag plot, r₁ = {rtext}", fontsize=_FS_TITLE)
    if idx.size < n - 1:
        ax_l.text(0.98, 0.02, f"{idx.size:,} of {n - 1:,} pairs", transform=ax_l.transAxes, ha="right",
                  va="bottom", fontsize=_FS - 1.5, color="0.35")
