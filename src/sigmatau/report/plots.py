"""Figures: σ–τ plots with intervals and the fitted IMU model; series, PSD and lag plot.

Nothing in the core imports this module and ``import sigmatau`` does not load
matplotlib: the figures are built with the object-oriented API only
(:class:`matplotlib.figure.Figure` on an Agg canvas, no pyplot and no change
to the global ``rcParams`` while drawing), so they work headless, in threads
and in Dask workers. Matplotlib is the optional extra ``plot``
(``pip install "sigmatau[plot]"``).

Plotting never computes a statistic: :func:`sigma_tau_figure` takes
:class:`~sigmatau.result.StabilityResult` curves and the
:class:`~sigmatau.imu.NoiseModel` fitted on them. :func:`signal_figure`
draws the design tip's Figure 2 panels (time series, Welch PSD, lag plot)
for one channel. :func:`save_figure` and :func:`figure_to_data_uri` write
PNG/SVG/PDF with reproducible bytes (no dates, fixed SVG ids).

Colours are the Okabe–Ito palette for the statistics (each statistic keeps
its colour in every panel and figure) and Paul Tol's muted palette for the
model terms, both readable with the common colour-vision deficiencies.

Examples
--------
>>> import numpy as np, sigmatau
>>> from sigmatau import plots                                    # doctest: +SKIP
>>> y = np.random.default_rng(1).normal(size=4096)
>>> ch = plots.ChannelCurves("x", "rad/s", {"oadev": sigmatau.oadev(y, rate=100.0)})  # doctest: +SKIP
>>> fig = plots.sigma_tau_figure([ch], title="white noise")       # doctest: +SKIP
>>> paths = plots.save_figure(fig, "out/sigma_tau")               # doctest: +SKIP
"""

from __future__ import annotations

import base64
import io
import math
import pathlib
import threading
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Mapping, Optional, Sequence, Union

import numpy as np

from ..core.validate import check_rate
from ..errors import DataError, ParameterError
from ..core.result import StabilityResult

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ..imu.model import NoiseModel, Preset

__all__ = [
    "ChannelCurves",
    "STATISTIC_COLORS",
    "TERM_COLORS",
    "sigma_tau_figure",
    "signal_figure",
    "save_figure",
    "figure_to_bytes",
    "figure_to_data_uri",
]

# ----------------------------------------------------------------------- style

#: Colour of each statistic (Okabe–Ito), the same in every panel and figure.
STATISTIC_COLORS: Mapping[str, str] = {
    "oadev": "#0072B2", "adev": "#0072B2",
    "mdev": "#E69F00", "mtotdev": "#E69F00",
    "ohdev": "#009E73", "hdev": "#009E73", "htotdev": "#009E73",
    "totdev": "#56B4E9",
    "theoh": "#D55E00", "theo1": "#D55E00", "theobr": "#D55E00",
    "tdev": "#CC79A7", "ttotdev": "#CC79A7",
    "stdev": "#000000", "ostdev": "#000000",
    "mtie": "#7F7F7F", "tierms": "#7F7F7F",
}
_FALLBACK_COLORS = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#D55E00", "#000000")

#: Colour of each IMU model term (Paul Tol's muted palette).
TERM_COLORS: Mapping[str, str] = {"Q": "#AA4499", "N": "#44AA99", "B": "#999933", "K": "#CC6677",
                                  "R": "#882255"}

_MARKERS = {"oadev": "o", "adev": "o", "mdev": "s", "mtotdev": "s", "ohdev": "^", "hdev": "^",
            "htotdev": "^", "totdev": "D", "theoh": "P", "theo1": "P", "theobr": "P", "tdev": "v",
            "ttotdev": "v", "stdev": "x", "ostdev": "x", "mtie": "*", "tierms": "*"}
_DISPLAY = {"oadev": "OADEV", "adev": "ADEV", "mdev": "MDEV", "tdev": "TDEV", "hdev": "HDEV",
            "ohdev": "OHDEV", "totdev": "TOTDEV", "mtotdev": "MTOTDEV", "ttotdev": "TTOTDEV",
            "htotdev": "HTOTDEV", "theo1": "Theo1", "theobr": "TheoBR", "theoh": "TheoH",
            "stdev": "STDEV", "ostdev": "OSTDEV", "mtie": "MTIE", "tierms": "TIE rms"}
#: Statistics in the phase (time-error) unit: drawn on a right-hand axis.
_TIME_STATS = frozenset({"tdev", "ttotdev", "mtie", "tierms"})
#: Statistics drawn prominently (the one the IMU model is read from).
_PROMINENT = frozenset({"oadev", "adev"})

_TERMS = ("Q", "N", "B", "K", "R")
_SLOPE = {"Q": -1.0, "N": -0.5, "B": 0.0, "K": 0.5, "R": 1.0}
_SLOPE_TEXT = {-1.0: "−1", -0.5: "−½", 0.0: "0", 0.5: "+½", 1.0: "+1"}
_TERM_NAME = {
    "gyro": {"Q": "Q (quantization)", "N": "N (ARW)", "B": "B (bias instability)", "K": "K (RRW)",
             "R": "R (rate ramp)"},
    "accel": {"Q": "Q (quantization)", "N": "N (VRW)", "B": "B (bias instability)", "K": "K (accel. RW)",
              "R": "R (accel. ramp)"},
    None: {"Q": "Q (slope −1)", "N": "N (slope −½)", "B": "B (flicker)", "K": "K (slope +½)",
           "R": "R (slope +1)"},
}
#: Unit in which a term's value is printed on a figure (what datasheets print).
_LABEL_UNIT = {
    "gyro": {"Q": "urad", "N": "deg/sqrt(h)", "B": "deg/h", "K": "deg/h/sqrt(h)", "R": "deg/h^2"},
    "accel": {"Q": "mm/s", "N": "ug/sqrt(Hz)", "B": "ug", "K": "ug/sqrt(s)", "R": "ug/s"},
}

_FS = 8.5          # tick labels and legends
_FS_LABEL = 9.5    # axis labels
_FS_TITLE = 10.5   # panel titles
_GRID = {"which": "major", "color": "0.85", "linewidth": 0.6}
_GRID_MINOR = {"which": "minor", "color": "0.93", "linewidth": 0.4}

_PNG_DPI = 130
#: Matplotlib shares some text-layout state between threads: layout and rendering are
#: serialised in this process (building the artists is not).
_RENDER_LOCK = threading.RLock()


def matplotlib_modules() -> tuple[Any, Any]:
    """Import matplotlib's Figure and Agg canvas, or raise MissingDependencyError naming the extra."""
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError:
        from ..io import MissingDependencyError

        raise MissingDependencyError(
            'figures need the optional package matplotlib, which is not installed;'
            ' install it with: pip install "sigmatau[plot]"'
        ) from None
    return Figure, FigureCanvasAgg


def new_figure(figsize: tuple[float, float]) -> "Figure":
    Figure, FigureCanvasAgg = matplotlib_modules()
    fig = Figure(figsize=figsize, layout="constrained", facecolor="white")
    FigureCanvasAgg(fig)
    return fig


def _freeze_layout(fig: "Figure") -> None:
    """Run the constrained layout until it settles, then fix it.

    Legends below the axes make the layout move a little on every draw; fixing it
    makes every later save (PNG, SVG, PDF, again) lay the figure out identically
    and skips the layout passes there.
    """
    engine = fig.get_layout_engine()
    if engine is None:
        return
    with _RENDER_LOCK:
        for _ in range(3):
            before = [tuple(np.round(ax.get_position().bounds, 6)) for ax in fig.axes]
            engine.execute(fig)
            if [tuple(np.round(ax.get_position().bounds, 6)) for ax in fig.axes] == before:
                break
    fig.set_layout_engine("none")


def _pretty(unit: str) -> str:
    from ..imu.units import pretty

    return pretty(unit)


def _kind_of(unit: str) -> Optional[str]:
    """``"gyro"``/``"accel"`` for an IMU unit, None for anything else (clocks, raw counts)."""
    from ..imu.units import sensor_unit

    try:
        return sensor_unit(unit).kind
    except (ParameterError, ValueError, TypeError, AttributeError):
        return None


_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _log_formatter(minor: bool) -> Any:
    """Tick labels ``10⁻³`` (and ``2×10⁻³`` on minor ticks when fewer than two decades show).

    Plain Unicode rather than mathtext: one font throughout, faster, and free of the
    mathtext parser, which matplotlib shares between threads.
    """
    from matplotlib.ticker import Formatter

    class _Log(Formatter):
        def __call__(self, x: float, pos: Optional[int] = None) -> str:
            if not (x > 0 and math.isfinite(x)):
                return ""
            e = math.floor(math.log10(x) + 1e-9)
            mant = x / 10.0**e
            power = "10" + str(e).translate(_SUPERSCRIPT)
            if not minor:
                return power if abs(mant - 1.0) < 1e-6 else ""
            lo, hi = sorted(self.axis.get_view_interval()) if self.axis is not None else (x, x)
            majors = math.floor(math.log10(hi) + 1e-9) - math.ceil(math.log10(lo) - 1e-9) + 1 if lo > 0 else 2
            if majors >= 2 or round(mant) not in (2, 3, 5):
                return ""
            return f"{round(mant)}×{power}"

    return _Log()


def _log_axis(axis: Any) -> None:
    axis.set_major_formatter(_log_formatter(False))
    axis.set_minor_formatter(_log_formatter(True))


def _style_log_axes(ax: "Axes") -> None:
    ax.set_xscale("log")
    ax.set_yscale("log")
    _log_axis(ax.xaxis)
    _log_axis(ax.yaxis)
    ax.grid(True, **_GRID)
    ax.grid(True, **_GRID_MINOR)
    ax.tick_params(labelsize=_FS, which="both", direction="in", top=True)
    for side in ("top", "right"):
        ax.spines[side].set_linewidth(0.6)


# -------------------------------------------------------------------- channels


@dataclass(frozen=True)
class ChannelCurves:
    """The curves of one channel for :func:`sigma_tau_figure`.

    Attributes
    ----------
    name : str
        Channel name, the panel title (``"gyro x"``).
    unit : str
        Unit of the deviations σ(τ): the unit of the frequency-type samples
        (``"rad/s"``, ``"deg/s"``, ``"m/s^2"``, ``"g"`` …; ``""`` for
        fractional frequency). Time-error statistics (TDEV, MTIE …) are in
        ``unit·s`` and go on a right-hand axis.
    results : mapping of str to StabilityResult
        Statistic name (``"oadev"``, ``"mdev"``, ``"tdev"``, ``"ohdev"``,
        ``"totdev"``, ``"theoh"`` …) → its curve, intervals optional.
    model : NoiseModel, optional
        IMU noise model fitted on the channel's OADEV (:func:`sigmatau.imu.analyze`).
    """

    name: str
    unit: str
    results: Mapping[str, StabilityResult]
    model: Optional["NoiseModel"] = None


def _as_channel(obj: object, i: int) -> ChannelCurves:
    if isinstance(obj, ChannelCurves):
        ch = obj
    elif isinstance(obj, (tuple, list)) and len(obj) in (3, 4):
        ch = ChannelCurves(*obj)
    elif all(hasattr(obj, a) for a in ("name", "unit", "results")):
        ch = ChannelCurves(obj.name, obj.unit, obj.results, getattr(obj, "model", None))  # type: ignore[attr-defined]
    else:
        raise ParameterError(
            f"channels[{i}]={obj!r:.80} must be a ChannelCurves or a (name, unit, results[, model]) tuple"
        )
    if not isinstance(ch.name, str) or not isinstance(ch.unit, str):
        raise ParameterError(f"channels[{i}]: name={ch.name!r} and unit={ch.unit!r} must be strings")
    if not isinstance(ch.results, Mapping):
        raise ParameterError(f"channels[{i}] ({ch.name}): results must be a mapping statistic → StabilityResult,"
                             f" got {type(ch.results).__name__}")
    for key, res in ch.results.items():
        if not (hasattr(res, "taus") and hasattr(res, "dev")):
            raise ParameterError(f"channels[{i}] ({ch.name}): results[{key!r}] must be a StabilityResult,"
                                 f" got {type(res).__name__}")
    if ch.model is not None and not hasattr(ch.model, "term_deviation"):
        raise ParameterError(f"channels[{i}] ({ch.name}): model must be a sigmatau.imu.NoiseModel,"
                             f" got {type(ch.model).__name__}")
    return ch


def _stat_color(stat: str, order: list[str]) -> str:
    if stat in STATISTIC_COLORS:
        return STATISTIC_COLORS[stat]
    if stat not in order:
        order.append(stat)
    return _FALLBACK_COLORS[order.index(stat) % len(_FALLBACK_COLORS)]


def _positive(a: Optional[np.ndarray], n: int) -> np.ndarray:
    if a is None:
        return np.full(n, np.nan)
    a = np.asarray(a, dtype=float)
    if a.shape != (n,):
        return np.full(n, np.nan)
    return np.where(np.isfinite(a) & (a > 0), a, np.nan)


# ------------------------------------------------------------------ datasheet


def _term_sigma(term: str, coef: float, taus: np.ndarray) -> np.ndarray:
    """σ of one term with coefficient ``coef`` (IEEE 952 AVAR contributions, continuous time)."""
    from ..imu.model import B_FACTOR

    t = np.asarray(taus, dtype=float)
    return {
        "Q": math.sqrt(3.0) * coef / t,
        "N": coef / np.sqrt(t),
        "B": np.full(t.shape, B_FACTOR * coef),
        "K": coef * np.sqrt(t / 3.0),
        "R": coef * t / math.sqrt(2.0),
    }[term]


def _datasheet_terms(datasheet: object, unit: str) -> dict[str, float]:
    """Datasheet coefficients in the term units of ``unit``."""
    from ..imu.units import convert, term_unit

    if datasheet is None:
        return {}
    out: dict[str, float] = {}
    if hasattr(datasheet, "kind") and hasattr(datasheet, "N") and not isinstance(datasheet, Mapping):
        preset: Any = datasheet
        kind = _kind_of(unit)
        if kind != preset.kind:
            what = "not an IMU unit" if kind is None else f"a {kind} unit"
            raise ParameterError(f"datasheet preset {getattr(preset, 'name', '?')!r} is a {preset.kind} preset"
                                 f" but the panel unit {unit!r} is {what}")
        for term in _TERMS:
            v = float(getattr(preset, term))
            if v > 0:
                out[term] = float(convert(v, term_unit(preset.unit, term), term_unit(unit, term)))
        return out
    if not isinstance(datasheet, Mapping):
        raise ParameterError(f"datasheet={datasheet!r:.80} must be a mapping term → value or a sigmatau.imu.Preset")
    for term, value in datasheet.items():
        if term not in _TERMS:
            raise ParameterError(f"datasheet term {term!r} must be one of {_TERMS}")
        if isinstance(value, (tuple, list)) and len(value) == 2:
            v = float(convert(float(value[0]), str(value[1]), term_unit(unit, term)))
        else:
            try:
                v = float(value)
            except (TypeError, ValueError):
                raise ParameterError(
                    f"datasheet[{term!r}]={value!r} must be a number or a (value, unit) pair") from None
        if not math.isfinite(v) or v < 0:
            raise ParameterError(f"datasheet[{term!r}]={value!r} must be a non-negative finite number")
        if v > 0:
            out[term] = v
    return out


def _term_text(term: str, value: float, unit: str, kind: Optional[str], rel: Optional[float] = None,
               bound: bool = False) -> str:
    """``"N (ARW) 0.240 °/√h ±0.1 %"`` with the value in the customary unit of the term."""
    from ..imu.units import convert, term_unit

    tu = term_unit(unit, term) if unit else ""
    shown, su = value, tu
    if kind is not None:
        try:
            shown = float(convert(value, tu, _LABEL_UNIT[kind][term]))
            su = _LABEL_UNIT[kind][term]
        except (ParameterError, ValueError):
            pass
    name = _TERM_NAME[kind][term]
    text = f"{name} {'< ' if bound else ''}{shown:.3g} {_pretty(su)}".rstrip()
    if rel is not None and math.isfinite(rel) and rel > 0:
        text += f" ±{100 * rel:.2g} %"
    if bound:
        text += " (not resolved)"
    return text


# ------------------------------------------------------------------- σ–τ panel


@dataclass
class _Panel:
    ax: Any
    twin: Any = None
    ylo: float = math.inf
    yhi: float = -math.inf
    tlo: float = math.inf
    thi: float = -math.inf
    xlo: float = math.inf
    xhi: float = -math.inf
    empty: bool = True
    term_handles: list = None  # type: ignore[assignment]

    def take_y(self, values: np.ndarray, twin: bool = False) -> None:
        v = np.asarray(values, dtype=float)
        v = v[np.isfinite(v) & (v > 0)]
        if v.size:
            if twin:
                self.tlo, self.thi = min(self.tlo, float(v.min())), max(self.thi, float(v.max()))
            else:
                self.ylo, self.yhi = min(self.ylo, float(v.min())), max(self.yhi, float(v.max()))

    def take_x(self, taus: np.ndarray) -> None:
        t = np.asarray(taus, dtype=float)
        t = t[np.isfinite(t) & (t > 0)]
        if t.size:
            self.xlo, self.xhi = min(self.xlo, float(t.min())), max(self.xhi, float(t.max()))


def _draw_statistics(p: _Panel, ch: ChannelCurves, stats: list[str], legend: dict, order: list[str],
                     notes: list[str]) -> None:
    prominent = next((s for s in ("oadev", "adev") if s in stats), None)
    zeros: list[str] = []
    for stat in stats:
        res = ch.results[stat]
        taus = np.asarray(res.taus, dtype=float)
        n = taus.size
        if n == 0:
            continue
        raw = np.asarray(res.dev, dtype=float)
        dev = _positive(raw, n)
        dropped = int(np.sum(np.isfinite(raw) & (raw <= 0))) if raw.shape == (n,) else 0
        if dropped:
            zeros.append(f"{dropped} {_DISPLAY.get(stat, stat)}")
        lo, hi = _positive(getattr(res, "ci_low", None), n), _positive(getattr(res, "ci_high", None), n)
        ok = np.isfinite(taus) & (taus > 0) & np.isfinite(dev)
        if not ok.any():
            continue
        time_stat = stat in _TIME_STATS
        if time_stat and p.twin is None:
            p.twin = p.ax.twinx()
            p.twin.set_yscale("log")
            _log_axis(p.twin.yaxis)
            p.twin.tick_params(labelsize=_FS, which="both", direction="in")
        ax = p.twin if time_stat else p.ax
        color = _stat_color(stat, order)
        strong = stat == prominent
        label = _DISPLAY.get(stat, stat.upper()) + (" (right axis)" if time_stat else "")
        band = None
        both = ok & np.isfinite(lo) & np.isfinite(hi)
        if both.any():
            band = ax.fill_between(taus[ok], np.where(both, lo, np.nan)[ok], np.where(both, hi, np.nan)[ok],
                                   color=color, alpha=0.22 if strong else 0.12, linewidth=0,
                                   zorder=2 if strong else 1.5)
            band.set_gid(f"band-{stat}-{ch.name}")
            p.take_y(lo[both], twin=time_stat)
            p.take_y(hi[both], twin=time_stat)
        (line,) = ax.plot(taus[ok], dev[ok], color=color, marker=_MARKERS.get(stat, "o"),
                          markersize=4.2 if strong else 3.0, linewidth=1.5 if strong else 0.9,
                          alpha=1.0 if strong else 0.8, markeredgewidth=0.6,
                          markerfacecolor=color if strong else "white", zorder=6 if strong else 4)
        line.set_gid(f"curve-{stat}-{ch.name}")
        p.take_y(dev[ok], twin=time_stat)
        p.take_x(taus[ok])
        p.empty = False
        if label not in legend:
            legend[label] = (line, band)
    if zeros:
        notes.append(f"{ch.name}: zero values not shown on the log axis ({', '.join(zeros)})")


def _unit_factor(model: "NoiseModel", unit: str) -> float:
    from ..imu.units import convert

    if not unit or model.unit == unit:
        return 1.0
    try:
        return float(convert(1.0, model.unit, unit))
    except ParameterError:
        raise ParameterError(f"the noise model is in {model.unit!r} but the panel unit is {unit!r},"
                             " which is not the same dimension") from None


def _draw_model(p: _Panel, ch: ChannelCurves, legend: dict, notes: list[str]) -> None:
    from ..imu.model import READ_FACTOR

    model = ch.model
    assert model is not None
    f = _unit_factor(model, ch.unit)
    kind = _kind_of(ch.unit) or getattr(model, "kind", None)
    unit = ch.unit or model.unit
    res = model.result
    taus = np.asarray(res.taus, dtype=float)
    curve = _positive(res.dev, taus.size) * f
    good = np.isfinite(curve) & (taus > 0)
    if good.any():
        p.take_x(taus[good])
        t0, t1 = float(taus[good].min()), float(taus[good].max())
    elif p.xlo < p.xhi:
        t0, t1 = p.xlo, p.xhi
    else:
        return
    tt = np.geomspace(t0 / 1.5, t1 * 1.5, 240)
    fitted = tuple(getattr(model, "fit_terms", ()) or ())
    ax = p.ax
    handles = []
    if fitted:
        with np.errstate(invalid="ignore"):
            total = np.asarray(model.deviation(tt), dtype=float) * f
        (h,) = ax.plot(tt, np.where(total > 0, total, np.nan), color="black", linestyle=(0, (6, 2)),
                       linewidth=1.2, alpha=0.85, zorder=5, label=f"model fit ({', '.join(fitted)})")
        h.set_gid(f"model-{ch.name}")
        handles.append(h)
        p.take_y(total[(tt >= t0) & (tt <= t1)])
    for term in _TERMS:
        par = getattr(model, term)
        color = TERM_COLORS[term]
        if par.resolved:
            if term in fitted:
                with np.errstate(invalid="ignore"):
                    sig = np.asarray(model.term_deviation(term, tt), dtype=float) * f
            else:
                sig = _term_sigma(term, par.value * f, tt)
            if not np.any(np.isfinite(sig) & (sig > 0)):
                notes.append(f"{ch.name}: {term} is a negative (filter) term, not drawn")
                continue
            rel = (par.high - par.low) / (2 * par.value) if par.value > 0 else None
            (h,) = ax.plot(tt, np.where(sig > 0, sig, np.nan), color=color, linestyle=(0, (3, 1.5)),
                           linewidth=1.3, zorder=4.5,
                           label=_term_text(term, par.value * f, unit, kind, rel))
            h.set_gid(f"term-{term}-{ch.name}")
            handles.append(h)
            # Keep each resolved term in view where it matters most (B sits below the curve's minimum).
            inside = (tt >= t0) & (tt <= t1) & np.isfinite(sig) & (sig > 0)
            if fitted and inside.any():
                share = np.where(inside, sig / np.where(total > 0, total, np.inf), -1.0)
                p.take_y([sig[int(np.argmax(share))]])
        elif math.isfinite(par.high) and par.high > 0 and good.any():
            # Upper bound: a short stretch of the term's line where it comes closest to the curve.
            tg, cg = taus[good], curve[good]
            line = _term_sigma(term, par.high * f, tg)
            j = int(np.argmax(line / cg))
            seg = np.geomspace(tg[j] / 4.0, tg[j] * 4.0, 20)
            (h,) = ax.plot(seg, _term_sigma(term, par.high * f, seg), color=color, linestyle=":",
                           linewidth=1.2, marker="", zorder=4.4,
                           label=_term_text(term, par.high * f, unit, kind, bound=True))
            ax.plot([tg[j]], [line[j]], linestyle="", marker="v", markersize=6, color=color,
                    markeredgecolor="black", markeredgewidth=0.5, zorder=7, gid=f"bound-{term}-{ch.name}")
            h.set_gid(f"boundline-{term}-{ch.name}")
            p.take_y([line[j]])
            handles.append(h)
            legend.setdefault("upper bound (term not resolved)", (
                _proxy_marker("v", "0.6"), None))
    # Read-offs: the fixed-slope line in its region, the point where it is read, a faint guide.
    regions = getattr(model, "regions", {}) or {}
    readoff = getattr(model, "readoff", {}) or {}
    for term, reg in regions.items():
        par = readoff.get(term)
        if par is None or not reg.resolved or not par.resolved or not par.value > 0:
            continue
        s0, tr = float(reg.slope), float(reg.tau_read)
        level = par.value / READ_FACTOR.get(term, 1.0) * f
        color = TERM_COLORS.get(term, "0.3")
        guide = np.geomspace(min(t0, tr) / 1.5, max(t1, tr) * 1.5, 50)
        ax.plot(guide, level * (guide / tr) ** s0, color="0.55", linewidth=0.6, linestyle=(0, (1, 2)),
                zorder=1.2, gid=f"guide-{term}-{ch.name}")
        region = np.geomspace(reg.tau_low, reg.tau_high, 30)
        ax.plot(region, level * (region / tr) ** s0, color=color, linewidth=6.0, alpha=0.28,
                solid_capstyle="butt", zorder=1.3, gid=f"region-{term}-{ch.name}")
        mid = math.sqrt(reg.tau_low * reg.tau_high)
        # B is read on the flat bottom itself (any τ there gives the same level).
        t_mark = mid if s0 == 0.0 else tr
        ax.plot([t_mark], [level * (t_mark / tr) ** s0], linestyle="", marker="D", markersize=6.0,
                markerfacecolor="white", markeredgecolor=color, markeredgewidth=1.6, zorder=8,
                gid=f"readoff-{term}-{ch.name}")
        # Below the line (and to the right of a rising one, which would cross a centred label).
        side = ("left", 7) if s0 > 0 else ("center", 0)
        ax.annotate(f"{term}: slope {_SLOPE_TEXT.get(s0, f'{s0:+g}')}", (mid, level * (mid / tr) ** s0),
                    xytext=(side[1], -10), textcoords="offset points", ha=side[0],
                    va="top", fontsize=_FS - 1, color="0.25", zorder=9,
                    bbox={"boxstyle": "round,pad=0.15", "facecolor": "white", "edgecolor": "none",
                          "alpha": 0.75})
        p.take_y([level])
        legend.setdefault("read-off point (IEEE 952)", (_proxy_marker("D", "white", edge="0.2"), None))
        legend.setdefault("read-off region", (_proxy_band(), None))
    if model.filter_time and model.filter_time > 0:
        notes.append(f"{ch.name}: sensor low-pass τ_f = {model.filter_time:.3g} s (negative 1/τ² term)")
    p.term_handles = handles


def _proxy_marker(marker: str, face: str, edge: str = "black") -> Any:
    from matplotlib.lines import Line2D

    return Line2D([], [], linestyle="", marker=marker, markersize=6, markerfacecolor=face, markeredgecolor=edge,
                  markeredgewidth=1.0)


def _proxy_band() -> Any:
    from matplotlib.lines import Line2D

    return Line2D([], [], color="0.5", linewidth=6.0, alpha=0.35, solid_capstyle="butt")


def _draw_datasheet(p: _Panel, ch: ChannelCurves, terms: Mapping[str, float], legend: dict) -> None:
    if not terms or p.xlo > p.xhi:
        return
    kind = _kind_of(ch.unit)
    tt = np.geomspace(p.xlo / 1.5, p.xhi * 1.5, 60)
    for term, value in terms.items():
        (h,) = p.ax.plot(tt, _term_sigma(term, value, tt), color="0.45", linestyle="-.", linewidth=1.2,
                         zorder=3, gid=f"datasheet-{term}-{ch.name}")
        label = "datasheet " + _term_text(term, value, ch.unit, kind)
        legend.setdefault(label, (h, None))


def _draw_slope_fan(p: _Panel, xlim: tuple[float, float], ylim: tuple[float, float]) -> None:
    """Slopes −1 … +1 in the emptiest corner, for panels without a model."""
    ax = p.ax
    lx0, lx1 = math.log10(xlim[0]), math.log10(xlim[1])
    ly0, ly1 = math.log10(ylim[0]), math.log10(ylim[1])
    dx, dy = lx1 - lx0, ly1 - ly0
    length = min(0.14 * dx, 0.17 * dy)
    w, h = length / dx, length / dy  # fan size in axes fractions: width w, ±h about its axis
    pts = []
    for a, lim in ((ax, ylim), (p.twin, p.twin.get_ylim() if p.twin is not None else None)):
        if a is None:
            continue
        for line in a.get_lines():
            xd, yd = (np.asarray(v, dtype=float) for v in line.get_data())
            ok = (xd > 0) & (yd > 0)
            if ok.any():
                pts.append(np.column_stack([(np.log10(xd[ok]) - lx0) / dx,
                                            (np.log10(yd[ok]) - math.log10(lim[0])) / math.log10(lim[1] / lim[0])]))
    xy = np.concatenate(pts) if pts else np.empty((0, 2))
    best = None
    for fx, fy in ((0.05, 0.28), (0.05, 0.72), (0.72, 0.72), (0.72, 0.28)):
        inside = (xy[:, 0] > fx - 0.03) & (xy[:, 0] < fx + w + 0.1) & (np.abs(xy[:, 1] - fy) < h + 0.06)
        if best is None or int(inside.sum()) < best[0]:
            best = (int(inside.sum()), fx, fy)
    assert best is not None
    x0, y0 = lx0 + best[1] * dx, ly0 + best[2] * dy
    for sl in (-1.0, -0.5, 0.0, 0.5, 1.0):
        xs = np.array([x0, x0 + length])
        ys = np.array([y0, y0 + sl * length])
        ax.plot(10 ** xs, 10 ** ys, color="0.55", linewidth=0.8, zorder=1.1, gid=f"slope-guide-{sl:+g}")
        ax.text(10 ** (xs[1] + 0.012 * dx), 10 ** ys[1], _SLOPE_TEXT[sl], fontsize=_FS - 1.5, color="0.4",
                va="center", ha="left")
    ax.text(10 ** x0, 10 ** (y0 + length + 0.03 * dy), "slope", fontsize=_FS - 1.5, color="0.4", va="bottom")


def _log_limits(lo: float, hi: float, pad_lo: float, pad_hi: float, min_span: float = 1.1
                ) -> tuple[float, float]:
    if not (math.isfinite(lo) and math.isfinite(hi)) or lo <= 0:
        return (0.1, 10.0)
    span = math.log10(hi / lo)
    lo, hi = lo / 10 ** (pad_lo * span + 0.05), hi * 10 ** (pad_hi * span + 0.05)
    # A minimum span: below one or two decades the log axis labels its minor ticks, which
    # collide along the τ axis.
    short = min_span - math.log10(hi / lo)
    if short > 0:
        lo, hi = lo / 10 ** (short / 2), hi * 10 ** (short / 2)
    return (lo, hi)


def sigma_tau_figure(
    channels: Sequence[Union[ChannelCurves, tuple]],
    *,
    title: Optional[str] = None,
    datasheet: Optional[Union[Mapping[str, Any], "Preset"]] = None,
    statistics: Optional[Sequence[str]] = None,
) -> "Figure":
    """σ–τ figure of one sensor group: one log–log panel per channel.

    Parameters
    ----------
    channels : sequence of ChannelCurves or (name, unit, results[, model]) tuples
        The channels (e.g. the three gyro axes). Panels share the σ axis when
        every channel has the same unit.
    title : str, optional
        Figure title.
    datasheet : mapping or sigmatau.imu.Preset, optional
        Datasheet terms drawn as grey dash-dot lines: ``{"N": 6.98e-5}`` in
        the term units of the panel's unit, ``{"N": (4.0, "mdps/sqrt(Hz)")}``
        in any unit, or a :data:`sigmatau.imu.PRESETS` entry (SI, converted).
    statistics : sequence of str, optional
        Statistics to draw and their order (default: every one given, OADEV first).

    Returns
    -------
    matplotlib.figure.Figure
        On an Agg canvas; save it with :func:`save_figure`.

    Notes
    -----
    Each statistic is a line with markers and its interval ``ci_low … ci_high``
    as a shaded band where finite; OADEV is drawn strongest. Time-error
    statistics (TDEV, TTOTDEV, MTIE, TIE rms; unit·s) go on a right-hand
    axis. With a :class:`~sigmatau.imu.NoiseModel`: the fitted total, each
    resolved term with its value in customary units, each unresolved term as
    a ▼ upper bound on the term's line where it comes closest to the curve,
    and each read-off as its fixed-slope line over the region it was fitted in
    (shaded), the point where the line is read (◇: N at 1 s, K at 3 s, B at the
    flat bottom …) and a faint guide of that slope across the panel. Panels
    without a model get slope guides (−1 … +1) in a corner.

    Raises
    ------
    ParameterError
        Malformed channels, statistics or datasheet.
    MissingDependencyError
        matplotlib is not installed.
    """
    if isinstance(channels, ChannelCurves):
        channels = [channels]
    if isinstance(channels, (str, bytes, Mapping)) or not hasattr(channels, "__iter__"):
        raise ParameterError(f"channels={channels!r:.80} must be a sequence of ChannelCurves")
    chans = [_as_channel(c, i) for i, c in enumerate(channels)]
    if not chans:
        raise ParameterError("channels is empty: give at least one channel to plot")
    if statistics is not None:
        if isinstance(statistics, str) or not all(isinstance(s, str) for s in statistics):
            raise ParameterError(f"statistics={statistics!r} must be a sequence of statistic names")
        statistics = list(statistics)
    if title is not None and not isinstance(title, str):
        raise ParameterError(f"title={title!r} must be a string")
    ds_terms = [_datasheet_terms(datasheet, ch.unit) for ch in chans]

    n = len(chans)
    ncols = min(n, 3)
    nrows = math.ceil(n / ncols)
    shared = len({ch.unit for ch in chans}) == 1
    fig = new_figure((0.6 + 4.1 * ncols, 1.0 + 4.3 * nrows))
    axes = fig.subplots(nrows, ncols, sharey=shared, sharex=False, squeeze=False).ravel()
    for extra in axes[n:]:
        extra.set_visible(False)

    legend: dict[str, tuple] = {}
    order: list[str] = []
    notes: list[str] = []
    panels: list[_Panel] = []
    for ch, ax, ds in zip(chans, axes, ds_terms):
        _style_log_axes(ax)
        p = _Panel(ax=ax, term_handles=[])
        names = list(ch.results)
        if statistics is not None:
            names = [s for s in statistics if s in ch.results]
        else:
            given = list(names)
            names.sort(key=lambda s: (s not in _PROMINENT, s in _TIME_STATS, given.index(s)))
        _draw_statistics(p, ch, names, legend, order, notes)
        if ch.model is not None:
            _draw_model(p, ch, legend, notes)
        _draw_datasheet(p, ch, ds, legend)
        panels.append(p)

    # Limits: every panel's own, or one σ range for all when the axis is shared.
    ylims = [_log_limits(p.ylo, p.yhi, 0.06, 0.08) for p in panels]
    if shared:
        finite = [p for p in panels if p.ylo <= p.yhi]
        lim = (_log_limits(min(p.ylo for p in finite), max(p.yhi for p in finite), 0.06, 0.08)
               if finite else (0.1, 10.0))
        ylims = [lim] * n
    tl = [p for p in panels if p.twin is not None and p.tlo <= p.thi]
    tlim = _log_limits(min(p.tlo for p in tl), max(p.thi for p in tl), 0.06, 0.08) if tl else None
    for i, (ch, p) in enumerate(zip(chans, panels)):
        ax = p.ax
        xlim = _log_limits(p.xlo, p.xhi, 0.04, 0.04, min_span=2.0) if p.xlo <= p.xhi else (0.1, 10.0)
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylims[i])
        ax.set_xlabel("averaging time τ [s]", fontsize=_FS_LABEL)
        if not shared or i % ncols == 0:
            ax.set_ylabel(f"σ(τ) [{_pretty(ch.unit)}]" if ch.unit else "σ_y(τ) (fractional frequency)",
                          fontsize=_FS_LABEL)
        ax.set_title(ch.name, fontsize=_FS_TITLE)
        if p.twin is not None:
            if tlim is not None:
                p.twin.set_ylim(*tlim)
            last = i % ncols == ncols - 1 or i == n - 1
            if shared and tlim is not None and not last:
                p.twin.tick_params(labelright=False)
            else:
                tunit = f"{ch.unit}·s" if ch.unit else "s"
                p.twin.set_ylabel(f"x(τ) [{_pretty(tunit)}]", fontsize=_FS_LABEL)
        if p.empty:
            ax.text(0.5, 0.5, "no positive deviation to plot\n(constant or empty data?)", transform=ax.transAxes,
                    ha="center", va="center", fontsize=_FS, color="0.3")
        elif ch.model is None:
            _draw_slope_fan(p, xlim, ylims[i])
        if p.term_handles:
            ax.legend(handles=p.term_handles, loc="upper center", bbox_to_anchor=(0.5, -0.17), fontsize=_FS - 0.5,
                      frameon=False, handlelength=2.6, borderaxespad=0.0)
    handles, labels = [], []
    for label, (line, band) in legend.items():
        handles.append((band, line) if band is not None else line)
        labels.append(label)
    if handles:
        from matplotlib.legend_handler import HandlerTuple

        fig.legend(handles, labels, loc="outside lower center", ncols=min(len(handles), 4 if ncols > 1 else 2),
                   fontsize=_FS, frameon=False, handler_map={tuple: HandlerTuple(ndivide=1)}, handlelength=2.4)
    head = title or ""
    if notes:
        import textwrap

        wrapped = textwrap.fill("; ".join(notes), width=int(fig.get_figwidth() * 11))
        head = (head + "\n" if head else "") + wrapped
    if head:
        fig.suptitle(head, fontsize=_FS_TITLE + 1)
    _freeze_layout(fig)
    return fig


# ------------------------------------------------------------- signal figure


def _time_scale(duration: float) -> tuple[float, str]:
    if duration >= 2 * 3600:
        return 3600.0, "h"
    if duration >= 120:
        return 60.0, "min"
    return 1.0, "s"


def _welch(x: np.ndarray, rate: float) -> tuple[np.ndarray, np.ndarray, int]:
    """One-sided Welch PSD (Hann, 50 % overlap), computed in chunks to bound memory."""
    from scipy.signal import welch

    n = x.size
    # Segments of n/16 (≈ 30 averaged with the overlap: ±25 % at the lowest frequencies),
    # a power of two between 16 and 2^18; the log-frequency binning below smooths the rest.
    nperseg = n if n < 32 else int(2 ** min(18, max(4, math.floor(math.log2(n / 16)))))
    step = max(1, nperseg // 2)
    nseg = (n - nperseg) // step + 1
    per_chunk = max(1, (1 << 22) // nperseg)
    acc: Optional[np.ndarray] = None
    freqs = None
    for s in range(0, nseg, per_chunk):
        k = min(per_chunk, nseg - s)
        seg = x[s * step: s * step + (k - 1) * step + nperseg]
        freqs, pxx = welch(seg, fs=rate, window="hann", nperseg=nperseg, noverlap=nperseg - step,
                           detrend="constant", scaling="density", return_onesided=True)
        acc = pxx * k if acc is None else acc + pxx * k
    assert acc is not None and freqs is not None
    return freqs, acc / nseg, nperseg


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


def signal_figure(
    samples: Any,
    *,
    rate: float,
    name: str,
    unit: str,
    model: Optional["NoiseModel"] = None,
    max_points: int = 20000,
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

    Returns
    -------
    matplotlib.figure.Figure

    Notes
    -----
    (a) Time series; long records are drawn as the min/max envelope and the
    mean of ≈1500 display bins. (b) One-sided Welch PSD (Hann window, 50 %
    overlap, segments of about N/16 samples as a power of two ≤ 2¹⁸, so the
    lowest frequencies average ≈30 segments), averaged in 1/40-decade
    frequency bins. The model overlay uses the IEEE 952 spectra doubled to one
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
    try:
        x = np.asarray(samples, dtype=float)
    except (TypeError, ValueError):
        raise DataError(f"samples of {name!r} must be numeric") from None
    if x.ndim != 1:
        raise DataError(f"samples of {name!r} must be 1-D, got shape {x.shape}")
    finite = np.isfinite(x)
    if int(finite.sum()) < 4:
        raise DataError(f"samples of {name!r}: {int(finite.sum())} finite values, at least 4 are needed")
    t_all = None
    if not finite.all():
        t_all = np.flatnonzero(finite) / rate
        x = x[finite]
    n = x.size

    fig = new_figure((12.6, 3.9))
    gs = fig.add_gridspec(1, 3, width_ratios=[1.55, 1.25, 1.0])
    ax_t, ax_f, ax_l = (fig.add_subplot(gs[0, j]) for j in range(3))
    ulabel = _pretty(unit)
    ustr = f" [{ulabel}]" if ulabel else ""
    color = STATISTIC_COLORS["oadev"]

    # (a) time series
    duration = n / rate if t_all is None else float(t_all[-1] - t_all[0]) + 1.0 / rate
    scale, tu = _time_scale(duration)
    nb = 1500
    if n <= 2 * nb:
        t = (np.arange(n) / rate if t_all is None else t_all) / scale
        ax_t.plot(t, x, color=color, linewidth=0.7, gid="series")
    else:
        edges = np.linspace(0, n, nb + 1).astype(np.int64)
        lo = np.minimum.reduceat(x, edges[:-1])
        hi = np.maximum.reduceat(x, edges[:-1])
        mean = np.add.reduceat(x, edges[:-1]) / np.diff(edges)
        tpos = (edges[:-1] + edges[1:]) / 2.0
        t = (tpos / rate if t_all is None else np.interp(tpos, np.arange(n), t_all)) / scale
        binw = n / nb / rate
        env = ax_t.fill_between(t, lo, hi, color=color, alpha=0.3, linewidth=0, label=f"min–max per {binw:.3g} s")
        env.set_gid("envelope")
        ax_t.plot(t, mean, color=color, linewidth=0.8, label=f"mean per {binw:.3g} s", gid="series")
        ax_t.legend(loc="best", fontsize=_FS - 1, frameon=True, framealpha=0.9, edgecolor="none")
    ax_t.set_xlabel(f"time [{tu}]", fontsize=_FS_LABEL)
    ax_t.set_ylabel(f"{name}{ustr}", fontsize=_FS_LABEL)
    ax_t.set_title(f"(a) time series: {n:,} samples at {rate:g} Hz", fontsize=_FS_TITLE)
    ax_t.margins(x=0.0)
    ax_t.grid(True, **_GRID)
    ax_t.tick_params(labelsize=_FS)

    # (b) PSD
    _style_log_axes(ax_f)
    if n >= 16 and np.ptp(x) > 0:
        freqs, pxx, nperseg = _welch(x, rate)
        fb, pb = _log_bin(freqs, pxx)
        pos = pb > 0
        ax_f.plot(fb[pos], pb[pos], color=color, linewidth=1.0, gid="psd",
                  label=f"Welch, {nperseg:,}-point Hann")
        if model is not None and fb.size:
            f_m = np.geomspace(fb[pos].min() if pos.any() else fb[0], rate / 2.0, 200)
            try:
                factor = _unit_factor(model, unit)
            except ParameterError:
                factor = math.nan
            if math.isfinite(factor):
                terms = _model_psd(model, f_m, factor)
                for term, s in terms.items():
                    ax_f.plot(f_m, s, color=TERM_COLORS[term], linestyle=(0, (3, 1.5)), linewidth=1.2,
                              label={"Q": "quantization Q", "N": "white 2N²", "B": "flicker B²/(πf)",
                                     "K": "random walk K²/(2π²f²)", "R": "ramp R"}[term], gid=f"psd-{term}")
                if len(terms) > 1:
                    ax_f.plot(f_m, sum(terms.values()), color="black", linestyle=(0, (6, 2)), linewidth=1.0,
                              label="model sum", gid="psd-model")
            if pos.any():
                ax_f.set_ylim(pb[pos].min() / 3.0, pb[pos].max() * 3.0)
            ax_f.set_xlim(fb[0] / 1.2, rate / 2.0 * 1.2)
        ax_f.legend(loc="best", fontsize=_FS - 1, frameon=True, framealpha=0.9, edgecolor="none")
    else:
        ax_f.text(0.5, 0.5, "no PSD: record too short or constant", transform=ax_f.transAxes,
                  ha="center", va="center", fontsize=_FS, color="0.3")
    ax_f.set_xlabel("frequency [Hz]", fontsize=_FS_LABEL)
    ax_f.set_ylabel(f"PSD [{_psd_unit(unit)}]", fontsize=_FS_LABEL)
    ax_f.set_title("(b) power spectral density (one-sided)", fontsize=_FS_TITLE)

    # (c) lag plot
    a, b = x[:-1], x[1:]
    am, bm = a - a.mean(), b - b.mean()
    den = math.sqrt(float(am @ am) * float(bm @ bm))
    r = float(am @ bm) / den if den > 0 else math.nan
    idx = np.unique(np.linspace(0, n - 2, min(max_points, n - 1)).astype(np.int64))
    ax_l.scatter(a[idx], b[idx], s=2.0, color=color, alpha=0.35 if idx.size > 2000 else 0.7, linewidths=0,
                 rasterized=True, gid="lag")
    lo_, hi_ = float(min(a[idx].min(), b[idx].min())), float(max(a[idx].max(), b[idx].max()))
    pad = (hi_ - lo_) * 0.05 or max(abs(lo_), 1.0) * 0.05
    ax_l.plot([lo_ - pad, hi_ + pad], [lo_ - pad, hi_ + pad], color="0.6", linewidth=0.6, linestyle="--", zorder=0)
    ax_l.set_xlim(lo_ - pad, hi_ + pad)
    ax_l.set_ylim(lo_ - pad, hi_ + pad)
    ax_l.set_aspect("equal", adjustable="box")
    from matplotlib.ticker import MaxNLocator

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
    fig.suptitle(f"{name}: time series, spectrum and lag plot", fontsize=_FS_TITLE + 1)
    _freeze_layout(fig)
    return fig


# ---------------------------------------------------------------------- saving

_FORMATS = ("png", "svg", "pdf")
_MIME = {"png": "image/png", "svg": "image/svg+xml", "pdf": "application/pdf"}


def figure_to_bytes(fig: "Figure", format: str = "png") -> bytes:
    """The figure as PNG, SVG or PDF bytes, reproducible from run to run.

    PNG at 130 dpi; SVG with text as ``<text>`` (small files; the viewer's
    sans-serif font) and ids from a fixed salt; no creation dates anywhere.
    """
    if format not in _FORMATS:
        raise ParameterError(f"format={format!r} must be one of {_FORMATS}")
    import matplotlib

    metadata: dict[str, Any] = {"png": {"Software": None}, "svg": {"Date": None, "Creator": None},
                                "pdf": {"CreationDate": None, "ModDate": None, "Creator": None,
                                        "Producer": None}}[format]
    buf = io.BytesIO()
    # svg.hashsalt and svg.fonttype are read from rcParams at save time only, so they are set
    # for the duration of the save; the lock keeps concurrent saves from undoing each other.
    with _RENDER_LOCK, matplotlib.rc_context({"svg.hashsalt": "sigmatau", "svg.fonttype": "none",
                                            "pdf.fonttype": 42}):
        fig.savefig(buf, format=format, dpi=_PNG_DPI, metadata=metadata, facecolor="white")
    return buf.getvalue()


def save_figure(fig: "Figure", stem: Union[str, pathlib.Path], formats: Sequence[str] = ("png", "svg")
                ) -> list[pathlib.Path]:
    """Write ``stem.png``, ``stem.svg`` (and ``stem.pdf`` if asked) and return their paths.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    stem : str or path
        Path without extension; missing parent directories are created.
    formats : sequence of {"png", "svg", "pdf"}

    Returns
    -------
    list of pathlib.Path
        The files written, in the order of ``formats``.
    """
    if isinstance(formats, str):
        formats = (formats,)
    bad = [f for f in formats if f not in _FORMATS]
    if bad or not formats:
        raise ParameterError(f"formats={tuple(formats)!r} must be a non-empty subset of {_FORMATS}")
    base = pathlib.Path(stem)
    base.parent.mkdir(parents=True, exist_ok=True)
    out = []
    for fmt in dict.fromkeys(formats):
        path = base.with_name(base.name + "." + fmt)
        path.write_bytes(figure_to_bytes(fig, fmt))
        out.append(path)
    return out


def figure_to_data_uri(fig: "Figure", format: str = "png") -> str:
    """The figure as a ``data:`` URI (base64) for ``<img src=…>`` in a self-contained HTML report."""
    data = figure_to_bytes(fig, format)
    return f"data:{_MIME[format]};base64," + base64.b64encode(data).decode("ascii")
