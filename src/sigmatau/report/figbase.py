"""Shared pieces of the figures: style, matplotlib set-up, log axes, the panel record, saving.

Part of :mod:`sigmatau.report.plots` (which re-exports the public names):
matplotlib is imported only inside functions, the figures use the
object-oriented API on an Agg canvas, and layout and rendering are serialised
by :data:`_RENDER_LOCK` (see the :mod:`~sigmatau.report.plots` docstring).
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

from ..core.result import StabilityResult
from ..errors import ParameterError

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ..imu.model import NoiseModel

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
    "mhdev": "#009E73", "mhtotdev": "#009E73", "ldev": "#CC79A7", "pdev": "#E69F00",
}
_FALLBACK_COLORS = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#D55E00", "#000000")

#: Colour of each IMU model term (Paul Tol's muted palette).
TERM_COLORS: Mapping[str, str] = {"Q": "#AA4499", "N": "#44AA99", "B": "#999933", "K": "#CC6677",
                                  "R": "#882255"}

_MARKERS = {"oadev": "o", "adev": "o", "mdev": "s", "mtotdev": "s", "ohdev": "^", "hdev": "^",
            "htotdev": "^", "totdev": "D", "theoh": "P", "theo1": "P", "theobr": "P", "tdev": "v",
            "ttotdev": "v", "stdev": "x", "ostdev": "x", "mtie": "*", "tierms": "*", "mhdev": "<",
            "mhtotdev": "<", "ldev": "v", "pdev": ">"}
_DISPLAY = {"oadev": "OADEV", "adev": "ADEV", "mdev": "MDEV", "tdev": "TDEV", "hdev": "HDEV",
            "ohdev": "OHDEV", "totdev": "TOTDEV", "mtotdev": "MTOTDEV", "ttotdev": "TTOTDEV",
            "htotdev": "HTOTDEV", "theo1": "Theo1", "theobr": "TheoBR", "theoh": "TheoH",
            "stdev": "STDEV", "ostdev": "OSTDEV", "mtie": "MTIE", "tierms": "TIE rms",
            "mhdev": "MHDEV", "ldev": "LDEV", "mhtotdev": "MHTOTDEV", "pdev": "PDEV",
            "oadev_raw": "OADEV before temperature compensation"}
#: Statistics in the phase (time-error) unit: drawn on a right-hand axis.
_TIME_STATS = frozenset({"tdev", "ttotdev", "mtie", "tierms", "ldev"})
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
    """A white Figure with constrained layout on its own Agg canvas (no pyplot)."""
    Figure, FigureCanvasAgg = matplotlib_modules()
    fig = Figure(figsize=figsize, layout="constrained", facecolor="white")
    FigureCanvasAgg(fig)
    return fig


def _freeze_layout(fig: "Figure") -> None:
    """Lay the figure out once with the constrained layout, then fix the positions.

    One execution of the engine is enough because every decoration of our
    figures has a size independent of where the axes end up: the panel
    legends below the σ–τ panels hang a fixed distance (in points) under their
    axes (:data:`_BELOW_AXES_PT`), titles sit at a fixed height, and the tick
    labels do not depend on the axes size. (Legends anchored in axes
    fractions moved with the axes height, which took up to three executions to
    settle.) Each execution measures every axes' tight bounding box twice —
    the most expensive step of a figure — so this is done once per figure, and
    fixing the result makes every later save (PNG, SVG, PDF, again) lay the
    figure out identically without layout passes.
    """
    engine = fig.get_layout_engine()
    if engine is None:
        return
    with _RENDER_LOCK:
        engine.execute(fig)
    fig.set_layout_engine("none")


#: Distance in points from the bottom of a σ–τ panel to the top of its term legend: below the
#: τ tick labels and the τ axis label, at 8.5 pt and 9.5 pt (what the legend's former anchor at
#: 17 % of the 2.6-inch axes height gave).
_BELOW_AXES_PT = 32.0


def _below_axes(ax: "Axes", points: float) -> Any:
    """A transform from axes fractions to display, shifted down by ``points``.

    Anchors a legend a fixed distance below the axes, whatever the axes
    height: the layout then needs a single pass (see :func:`_freeze_layout`).
    """
    from matplotlib.transforms import ScaledTranslation

    fig = ax.get_figure()
    return ax.transAxes + ScaledTranslation(0.0, -points / 72.0, fig.dpi_scale_trans)


def _set_title(ax: "Axes", text: str, fontsize: float) -> None:
    """Set a panel title at the fixed height matplotlib would choose, skipping its automatic placement.

    Matplotlib re-places an automatically positioned title on every draw and
    every layout measurement, measuring the tight bounding box of the y axis
    (and of every twin's) each time, which made up about a fifth of the time of
    a figure. Our log–log panels have neither tick labels nor an axis label at
    the top nor an offset text, so the automatic position is always y = 1
    (plus the usual title pad): giving it explicitly draws the title at the
    same place.
    """
    ax.set_title(text, fontsize=fontsize, y=1.0)


def _pretty(unit: str) -> str:
    """The unit as printed on a figure (``deg/s`` → ``°/s``)."""
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
            return self._label(x, self._label_minor())

        def format_ticks(self, values: Any) -> list[str]:
            # Matplotlib labels all ticks of an axis through this method on every layout
            # measurement and draw (hundreds of times per figure, dozens of minor ticks
            # each): whether minor ticks are labelled depends on the view only, so it
            # is decided once per call rather than once per tick.
            label_minor = self._label_minor()
            return [self._label(x, label_minor) for x in values]

        def _label_minor(self) -> bool:
            """Whether minor ticks get labels: fewer than two decades (two major ticks) in view."""
            if not minor or self.axis is None:
                return minor
            lo, hi = sorted(self.axis.get_view_interval())
            if not lo > 0:
                return False
            return math.floor(math.log10(hi) + 1e-9) - math.ceil(math.log10(lo) - 1e-9) + 1 < 2

        @staticmethod
        def _label(x: float, label_minor: bool) -> str:
            if not (x > 0 and math.isfinite(x)):
                return ""
            e = math.floor(math.log10(x) + 1e-9)
            mant = x / 10.0**e
            power = "10" + str(e).translate(_SUPERSCRIPT)
            if not minor:
                return power if abs(mant - 1.0) < 1e-6 else ""
            if not label_minor or round(mant) not in (2, 3, 5):
                return ""
            return f"{round(mant)}×{power}"

    return _Log()


def _log_axis(axis: Any) -> None:
    """Unicode ``10ⁿ`` tick labels on one log axis."""
    axis.set_major_formatter(_log_formatter(False))
    axis.set_minor_formatter(_log_formatter(True))


def _style_log_axes(ax: "Axes") -> None:
    """Log–log axes with the house grid, ticks and labels."""
    ax.set_xscale("log")
    ax.set_yscale("log")
    _log_axis(ax.xaxis)
    _log_axis(ax.yaxis)
    ax.grid(True, **_GRID)
    ax.grid(True, **_GRID_MINOR)
    ax.tick_params(labelsize=_FS, which="both", direction="in", top=True)
    for side in ("top", "right"):
        ax.spines[side].set_linewidth(0.6)
    _spines_out_of_layout(ax)


def _spines_out_of_layout(ax: "Axes") -> None:
    """Leave the spines of axes with inward ticks out of the layout's measurements.

    A spine's extent is the axes edge plus the tick marks that stick out of it,
    and measuring it makes matplotlib recompute all ticks of the axis (four
    spines: four tick computations per axes and measurement). With the ticks
    pointing inwards nothing sticks out, so the layout is the same without them.
    """
    for spine in ax.spines.values():
        spine.set_in_layout(False)


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


def _positive(a: Optional[np.ndarray], n: int) -> np.ndarray:
    """The positive finite values of ``a`` (NaN elsewhere); all NaN when ``a`` is missing or not of length ``n``."""
    if a is None:
        return np.full(n, np.nan)
    a = np.asarray(a, dtype=float)
    if a.shape != (n,):
        return np.full(n, np.nan)
    return np.where(np.isfinite(a) & (a > 0), a, np.nan)


# ------------------------------------------------------------------- σ–τ panel


@dataclass
class _Panel:
    """One σ–τ panel being drawn: its axes and the data ranges its artists cover."""

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
        """Widen the σ range (or the right axis range) to the positive finite ``values``."""
        v = np.asarray(values, dtype=float)
        v = v[np.isfinite(v) & (v > 0)]
        if v.size:
            if twin:
                self.tlo, self.thi = min(self.tlo, float(v.min())), max(self.thi, float(v.max()))
            else:
                self.ylo, self.yhi = min(self.ylo, float(v.min())), max(self.yhi, float(v.max()))

    def take_x(self, taus: np.ndarray) -> None:
        """Widen the τ range to the positive finite ``taus``."""
        t = np.asarray(taus, dtype=float)
        t = t[np.isfinite(t) & (t > 0)]
        if t.size:
            self.xlo, self.xhi = min(self.xlo, float(t.min())), max(self.xhi, float(t.max()))


def _log_limits(lo: float, hi: float, pad_lo: float, pad_hi: float, min_span: float = 1.1
                ) -> tuple[float, float]:
    """Padded log-axis limits around ``lo … hi`` spanning at least ``min_span`` decades; (0.1, 10) without data."""
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
