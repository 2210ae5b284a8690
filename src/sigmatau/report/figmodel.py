"""The IMU model and datasheet overlays of the σ–τ figure (:func:`sigmatau.report.plots.sigma_tau_figure`).

Terms are drawn from a :class:`~sigmatau.imu.NoiseModel` (fitted total,
resolved terms, a Gauss–Markov term when the model has one, upper bounds of
unresolved ones, IEEE 952 read-offs) or from
datasheet values, in the panel's unit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Mapping, Optional

import numpy as np

from ..errors import ParameterError
from .figbase import (_FS, _LABEL_UNIT, _SLOPE_TEXT, _TERM_NAME, _TERMS, TERM_COLORS, ChannelCurves, _kind_of,
                      _Panel, _positive, _pretty)

if TYPE_CHECKING:  # pragma: no cover
    from ..imu.model import NoiseModel

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


def _unit_factor(model: "NoiseModel", unit: str) -> float:
    """Factor from the model's unit to ``unit`` (1 when the panel has no unit)."""
    from ..imu.units import convert

    if not unit or model.unit == unit:
        return 1.0
    try:
        return float(convert(1.0, model.unit, unit))
    except ParameterError:
        raise ParameterError(f"the noise model is in {model.unit!r} but the panel unit is {unit!r},"
                             " which is not the same dimension") from None


@dataclass
class _ModelView:
    """What the model overlay steps share: the model in the panel's unit and the τ span drawn.

    Attributes
    ----------
    model : NoiseModel
    name : str
        Channel name (artist ids and notes).
    f : float
        Factor from the model's unit to the panel's.
    unit : str
        Panel unit (the model's when the panel has none).
    kind : str or None
        ``"gyro"``, ``"accel"`` or None, for the term labels.
    tt : numpy.ndarray
        Dense τ grid the terms are drawn on (the curve's span, widened 1.5×).
    t0, t1 : float
        The span of the model's OADEV curve (or of the panel, without one).
    tg, cg : numpy.ndarray
        τ and deviation of the curve's drawable points (may be empty).
    fitted : tuple of str
        Terms of the whole-curve fit (empty when the model has none).
    total : numpy.ndarray or None
        The fitted total on ``tt``, when there is a fit.
    """

    model: "NoiseModel"
    name: str
    f: float
    unit: str
    kind: Optional[str]
    tt: np.ndarray
    t0: float
    t1: float
    tg: np.ndarray
    cg: np.ndarray
    fitted: tuple
    total: Optional[np.ndarray] = None


def _draw_model(p: _Panel, ch: ChannelCurves, legend: dict, notes: list[str]) -> None:
    """Overlay the channel's IMU model on its σ–τ panel.

    Draws the fitted total, every resolved term (value and uncertainty in the
    label), an upper-bound marker for each unresolved term and the IEEE 952
    read-offs; records the term handles on ``p`` for the panel's own legend.
    """
    model = ch.model
    assert model is not None
    view = _model_view(p, ch, model)
    if view is None:
        return
    handles = []
    if view.fitted:
        handles.append(_draw_total(p, view))
    for term in _TERMS:
        par = getattr(model, term)
        if par.resolved:
            h = _draw_resolved_term(p, view, term, par, notes)
        elif math.isfinite(par.high) and par.high > 0 and view.tg.size:
            h = _draw_term_bound(p, view, term, par, legend)
        else:
            h = None
        if h is not None:
            handles.append(h)
    gm = getattr(model, "gauss_markov", None)
    if gm is not None and gm.resolved and view.fitted:
        handles.append(_draw_gauss_markov(p, view, gm))
    _draw_readoffs(p, view, legend)
    if model.filter_time and model.filter_time > 0:
        notes.append(f"{ch.name}: sensor low-pass τ_f = {model.filter_time:.3g} s (negative 1/τ² term)")
    p.term_handles = handles


def _model_view(p: _Panel, ch: ChannelCurves, model: "NoiseModel") -> Optional[_ModelView]:
    """The model in the panel's unit and the τ span to draw it on; None when there is no span."""
    f = _unit_factor(model, ch.unit)
    kind = _kind_of(ch.unit) or getattr(model, "kind", None)
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
        return None
    return _ModelView(model=model, name=ch.name, f=f, unit=ch.unit or model.unit, kind=kind,
                      tt=np.geomspace(t0 / 1.5, t1 * 1.5, 240), t0=t0, t1=t1, tg=taus[good], cg=curve[good],
                      fitted=tuple(getattr(model, "fit_terms", ()) or ()))


def _draw_total(p: _Panel, v: _ModelView) -> Any:
    """The fitted total as a black dashed line; sets ``v.total`` and returns the line."""
    with np.errstate(invalid="ignore"):
        total = np.asarray(v.model.deviation(v.tt), dtype=float) * v.f
    (h,) = p.ax.plot(v.tt, np.where(total > 0, total, np.nan), color="black", linestyle=(0, (6, 2)),
                     linewidth=1.2, alpha=0.85, zorder=5, label=f"model fit ({', '.join(v.fitted)})")
    h.set_gid(f"model-{v.name}")
    p.take_y(total[(v.tt >= v.t0) & (v.tt <= v.t1)])
    v.total = total
    return h


def _draw_resolved_term(p: _Panel, v: _ModelView, term: str, par: Any, notes: list[str]) -> Any:
    """One resolved term's line with its value in the label; None (and a note) for a negative term."""
    if term in v.fitted:
        with np.errstate(invalid="ignore"):
            sig = np.asarray(v.model.term_deviation(term, v.tt), dtype=float) * v.f
    else:
        sig = _term_sigma(term, par.value * v.f, v.tt)
    if not np.any(np.isfinite(sig) & (sig > 0)):
        notes.append(f"{v.name}: {term} is a negative (filter) term, not drawn")
        return None
    rel = (par.high - par.low) / (2 * par.value) if par.value > 0 else None
    (h,) = p.ax.plot(v.tt, np.where(sig > 0, sig, np.nan), color=TERM_COLORS[term], linestyle=(0, (3, 1.5)),
                     linewidth=1.3, zorder=4.5,
                     label=_term_text(term, par.value * v.f, v.unit, v.kind, rel))
    h.set_gid(f"term-{term}-{v.name}")
    # Keep each resolved term in view where it matters most (B sits below the curve's minimum).
    inside = (v.tt >= v.t0) & (v.tt <= v.t1) & np.isfinite(sig) & (sig > 0)
    if v.fitted and inside.any():
        total = v.total
        share = np.where(inside, sig / np.where(total > 0, total, np.inf), -1.0)
        p.take_y([sig[int(np.argmax(share))]])
    return h


#: Colour of the Gauss–Markov term (Tol's "muted" scheme, beside the five terms' colours).
GM_COLOR = "#332288"


def _draw_gauss_markov(p: _Panel, v: _ModelView, gm: Any) -> Any:
    """The Gauss–Markov term's line, labelled with σ_GM and T_c (each with its relative uncertainty)."""
    with np.errstate(invalid="ignore"):
        sig = np.asarray(v.model.term_deviation("GM", v.tt), dtype=float) * v.f
    s, t = gm.sigma, gm.tau_c
    rel_s = (s.high - s.low) / (2 * s.value) if s.value > 0 else math.nan
    label = (f"Gauss–Markov σ {s.value * v.f:.3g} {_pretty(v.unit)}"
             + (f" ±{100 * rel_s:.2g} %" if math.isfinite(rel_s) and rel_s > 0 else "")
             + f", T_c {t.value:.3g} s [{t.low:.3g}, {t.high:.3g}]")
    (h,) = p.ax.plot(v.tt, np.where(sig > 0, sig, np.nan), color=GM_COLOR, linestyle=(0, (3, 1.5)),
                     linewidth=1.3, zorder=4.5, label=label)
    h.set_gid(f"term-GM-{v.name}")
    inside = (v.tt >= v.t0) & (v.tt <= v.t1) & np.isfinite(sig) & (sig > 0)
    if inside.any():
        p.take_y([float(np.max(sig[inside]))])
    return h


def _draw_term_bound(p: _Panel, v: _ModelView, term: str, par: Any, legend: dict) -> Any:
    """An unresolved term: a short stretch of its upper-bound line where it comes closest to the curve."""
    color = TERM_COLORS[term]
    tg, cg = v.tg, v.cg
    line = _term_sigma(term, par.high * v.f, tg)
    j = int(np.argmax(line / cg))
    seg = np.geomspace(tg[j] / 4.0, tg[j] * 4.0, 20)
    (h,) = p.ax.plot(seg, _term_sigma(term, par.high * v.f, seg), color=color, linestyle=":",
                     linewidth=1.2, marker="", zorder=4.4,
                     label=_term_text(term, par.high * v.f, v.unit, v.kind, bound=True))
    p.ax.plot([tg[j]], [line[j]], linestyle="", marker="v", markersize=6, color=color,
              markeredgecolor="black", markeredgewidth=0.5, zorder=7, gid=f"bound-{term}-{v.name}")
    h.set_gid(f"boundline-{term}-{v.name}")
    p.take_y([line[j]])
    legend.setdefault("upper bound (term not resolved)", (
        _proxy_marker("v", "0.6"), None))
    return h


def _draw_readoffs(p: _Panel, v: _ModelView, legend: dict) -> None:
    """Read-offs: the fixed-slope line in its region, the point where it is read, a faint guide."""
    from ..imu.model import READ_FACTOR

    ax = p.ax
    regions = getattr(v.model, "regions", {}) or {}
    readoff = getattr(v.model, "readoff", {}) or {}
    for term, reg in regions.items():
        par = readoff.get(term)
        if par is None or not reg.resolved or not par.resolved or not par.value > 0:
            continue
        s0, tr = float(reg.slope), float(reg.tau_read)
        level = par.value / READ_FACTOR.get(term, 1.0) * v.f
        color = TERM_COLORS.get(term, "0.3")
        guide = np.geomspace(min(v.t0, tr) / 1.5, max(v.t1, tr) * 1.5, 50)
        ax.plot(guide, level * (guide / tr) ** s0, color="0.55", linewidth=0.6, linestyle=(0, (1, 2)),
                zorder=1.2, gid=f"guide-{term}-{v.name}")
        region = np.geomspace(reg.tau_low, reg.tau_high, 30)
        ax.plot(region, level * (region / tr) ** s0, color=color, linewidth=6.0, alpha=0.28,
                solid_capstyle="butt", zorder=1.3, gid=f"region-{term}-{v.name}")
        mid = math.sqrt(reg.tau_low * reg.tau_high)
        # B is read on the flat bottom itself (any τ there gives the same level).
        t_mark = mid if s0 == 0.0 else tr
        ax.plot([t_mark], [level * (t_mark / tr) ** s0], linestyle="", marker="D", markersize=6.0,
                markerfacecolor="white", markeredgecolor=color, markeredgewidth=1.6, zorder=8,
                gid=f"readoff-{term}-{v.name}")
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


def _proxy_marker(marker: str, face: str, edge: str = "black") -> Any:
    """A legend-only marker artist."""
    from matplotlib.lines import Line2D

    return Line2D([], [], linestyle="", marker=marker, markersize=6, markerfacecolor=face, markeredgecolor=edge,
                  markeredgewidth=1.0)


def _proxy_band() -> Any:
    """A legend-only shaded-band artist (the read-off region)."""
    from matplotlib.lines import Line2D

    return Line2D([], [], color="0.5", linewidth=6.0, alpha=0.35, solid_capstyle="butt")


def _draw_datasheet(p: _Panel, ch: ChannelCurves, terms: Mapping[str, float], legend: dict) -> None:
    """Datasheet terms as grey dash-dot lines across the panel."""
    if not terms or p.xlo > p.xhi:
        return
    kind = _kind_of(ch.unit)
    tt = np.geomspace(p.xlo / 1.5, p.xhi * 1.5, 60)
    for term, value in terms.items():
        (h,) = p.ax.plot(tt, _term_sigma(term, value, tt), color="0.45", linestyle="-.", linewidth=1.2,
                         zorder=3, gid=f"datasheet-{term}-{ch.name}")
        label = "datasheet " + _term_text(term, value, ch.unit, kind)
        legend.setdefault(label, (h, None))
