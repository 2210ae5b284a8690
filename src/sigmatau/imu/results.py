"""What the IMU noise model reports: parameters, regions, flags and the optimal averaging.

Plain value objects, shared by the read-offs, the fit, :class:`~sigmatau.imu.NoiseModel`
and the design-tip answers: :class:`Parameter` (a coefficient with its
interval and unit), :class:`Region` (where a read-off was taken),
:class:`Flag` (a statement a reader must see) and :class:`OptimalAveraging`,
plus the text helpers of the model's table (``format_duration``, ``_short``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, NamedTuple

from .terms import _num
from .units import CUSTOMARY, TERMS, convert, pretty, term_unit

__all__ = ["Parameter", "Region", "Flag", "OptimalAveraging", "GaussMarkov", "format_duration"]


@dataclass(frozen=True)
class Parameter:
    """One noise coefficient with its interval and unit.

    Attributes
    ----------
    name : {"Q", "N", "B", "K", "R"} or str
        Term (or a derived quantity such as ``"angle error"``).
    value : float
        Estimate; NaN when not resolved. For a term the fit kept that its
        selection could have dropped, the median-unbiased estimate given the
        selection; for one it keeps whatever its estimate (N, nearly always),
        the selected model's value (see :func:`sigmatau.imu.analyze`,
        *Intervals*).
    low, high : float
        Interval at ``confidence``. When not resolved, ``low = 0`` and ``high``
        is an upper bound (``inf`` when not even a bound can be given).
    unit : str
        Unit expression (:func:`sigmatau.units.convert` understands it).
    resolved : bool
        False when the record does not resolve the term.
    method : str
        ``"fit"``, ``"read-off"`` or how the value was derived.
    confidence : float
        Two-sided coverage of ``[low, high]``.
    kind : {"gyro", "accel"}
        Sensor kind, for the SI and customary units.
    note : str
        How an upper bound was obtained, or other remarks.
    """

    name: str
    value: float
    low: float
    high: float
    unit: str
    resolved: bool
    method: str
    confidence: float
    kind: str
    note: str = ""

    def to(self, unit: str) -> "Parameter":
        """The same parameter in another unit (dimension checked).

        Examples
        --------
        >>> from sigmatau.imu import Parameter
        >>> p = Parameter("N", 1.6968e-4, 1.69e-4, 1.70e-4, "rad/s/sqrt(Hz)", True, "fit", 0.683, "gyro")
        >>> round(p.to("deg/sqrt(h)").value, 4)
        0.5833
        """
        f = float(convert(1.0, self.unit, unit))
        return replace(self, value=self.value * f, low=self.low * f, high=self.high * f, unit=unit)

    @property
    def si_unit(self) -> str:
        """SI unit of the term (rad or m based)."""
        base = "rad/s" if self.kind == "gyro" else "m/s^2"
        if self.name in TERMS:
            return term_unit(base, self.name)
        return str(_si_of(self.unit))

    def si(self) -> "Parameter":
        """The parameter in SI units."""
        return self.to(self.si_unit)

    def customary(self) -> list["Parameter"]:
        """The parameter in each customary unit of its term (:data:`sigmatau.units.CUSTOMARY`)."""
        if self.name not in TERMS:
            return []
        return [self.to(u) for u in CUSTOMARY[self.kind][self.name]]

    @property
    def bound(self) -> bool:
        """True when only an upper bound is known."""
        return not self.resolved

    def format(self, digits: int = 4, unit: bool = True) -> str:
        """Short text: ``value [low, high] unit`` or ``< high unit`` when not resolved.

        Enough digits are printed for the interval ends to differ from the value.
        """
        u = f" {pretty(self.unit)}" if unit else ""
        if not self.resolved:
            if math.isfinite(self.high):
                return f"< {self.high:.{digits}g}{u}"
            return "not resolved"
        d = digits
        if self.value > 0 and self.high > self.low:
            rel = (self.high - self.low) / (2.0 * self.value)
            d = min(8, max(digits, math.ceil(-math.log10(rel)) + 2))
        return f"{self.value:.{d}g} [{self.low:.{d}g}, {self.high:.{d}g}]{u}"

    def __str__(self) -> str:
        return f"{self.name} = {self.format()}" + ("" if self.resolved else " (not resolved)")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (NaN and inf become None)."""
        return {"name": self.name, "value": _num(self.value), "low": _num(self.low), "high": _num(self.high),
                "unit": self.unit, "resolved": self.resolved, "method": self.method,
                "confidence": self.confidence, "kind": self.kind, "note": self.note}


def _si_of(unit: str) -> str:
    """SI unit (rad, m and s powers) of any unit expression of the same dimension."""
    from .units import parse_unit

    _, (a, ln, t) = parse_unit(unit)
    parts = []
    if a:
        parts.append("rad" if a == 1 else f"rad^{a:g}")
    if ln:
        parts.append("m" if ln == 1 else f"m^{ln:g}")
    if t:
        parts.append("s" if t == 1 else f"s^{t:g}")
    return "*".join(parts) or "1"


@dataclass(frozen=True)
class Region:
    """Where a read-off was taken.

    Attributes
    ----------
    term : str
    slope : float
        Nominal ADEV slope of the term.
    tau_low, tau_high : float
        Ends of the region (s); NaN when no region was found.
    tau_read : float
        τ at which the fixed-slope line is read (1 s for N, 3 s for K …).
    points : int
        Number of τ of the curve in the region.
    resolved : bool
    rule : str
        How the region (or the bound) was chosen.
    """

    term: str
    slope: float
    tau_low: float
    tau_high: float
    tau_read: float
    points: int
    resolved: bool
    rule: str

    def to_dict(self) -> dict[str, Any]:
        return {"term": self.term, "slope": self.slope, "tau_low": _num(self.tau_low),
                "tau_high": _num(self.tau_high), "tau_read": self.tau_read, "points": self.points,
                "resolved": self.resolved, "rule": self.rule}


@dataclass(frozen=True)
class GaussMarkov:
    """The first-order Gauss–Markov term of a noise model (see :mod:`sigmatau.imu.gaussmarkov`).

    Attributes
    ----------
    sigma : Parameter
        Stationary standard deviation σ_GM (unit of the samples); its interval is
        from the fit's covariance at the chosen correlation time.
    tau_c : Parameter
        Correlation time T_c (s), interval from the profile of the fit's χ².
    delta_bic : float
        BIC of the five-term model minus that with the GM term (> 0 favours GM).
    n_eff : float
        Effective number of points behind the BIC penalty.
    criterion : str
        ``"BIC"``.
    margin : float
        ΔBIC above which the term is kept with ``gauss_markov="auto"``.
    note : str
        How the term was chosen.
    """

    sigma: Parameter
    tau_c: Parameter
    delta_bic: float
    n_eff: float
    criterion: str
    margin: float
    note: str = ""

    @property
    def resolved(self) -> bool:
        """True when the model keeps the term (σ and T_c have values)."""
        return self.sigma.resolved

    def format(self, digits: int = 4) -> str:
        """``σ = … , T_c = …`` with intervals, or the bound of σ when not resolved."""
        if not self.resolved:
            return f"σ {self.sigma.format(digits)} (not resolved)"
        return f"σ = {self.sigma.format(digits)}, T_c = {self.tau_c.format(digits)}"

    def __str__(self) -> str:
        return f"Gauss–Markov {self.format()}"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (NaN and inf become None)."""
        return {"sigma": self.sigma.to_dict(), "tau_c": self.tau_c.to_dict(), "delta_bic": _num(self.delta_bic),
                "n_eff": _num(self.n_eff), "criterion": self.criterion, "margin": self.margin,
                "resolved": self.resolved, "note": self.note}


class Flag(NamedTuple):
    """A statement about the model that a reader must see.

    ``code`` is one of ``"not-resolved"``, ``"quantized"``, ``"data"``,
    ``"disagreement"``, ``"model"``; ``term`` names the term concerned (or "").
    """

    code: str
    term: str
    message: str

    def __str__(self) -> str:
        return self.message


@dataclass(frozen=True)
class OptimalAveraging:
    """The averaging time that minimises the Allan deviation ("how many samples to average").

    Attributes
    ----------
    tau : float
        τ of the minimum of the fitted model (s); ``inf`` when the model keeps
        falling (no K or R term).
    m : float
        ``tau·rate``: the number of samples to average.
    dev : float
        Model deviation at ``tau`` (its asymptote when ``tau`` is infinite).
    tau_low, tau_high : float
        Interval of ``tau`` at ``confidence`` (Monte Carlo over the fit's
        covariance).
    dev_low, dev_high : float
        Interval of ``dev``.
    flat_low, flat_high : float
        τ range over which the model stays within 5 % of ``dev``.
    data_tau, data_dev : float
        τ and deviation of the lowest point of the measured curve.
    resolved : bool
        False when the minimum lies beyond the record.
    unit : str
        Unit of ``dev``.
    confidence : float
    note : str
    """

    tau: float
    m: float
    dev: float
    tau_low: float
    tau_high: float
    dev_low: float
    dev_high: float
    flat_low: float
    flat_high: float
    data_tau: float
    data_dev: float
    resolved: bool
    unit: str
    confidence: float
    note: str = ""

    def to_dict(self) -> dict[str, Any]:
        return {k: (_num(v) if isinstance(v, float) else v) for k, v in self.__dict__.items()}

    def __str__(self) -> str:
        if not self.resolved:
            return (f"no minimum within the record: averaging longer keeps helping ({self.note});"
                    f" lowest measured point {self.data_dev:.4g} {pretty(self.unit)} at τ = {self.data_tau:.4g} s")
        return (f"average τ = {self.tau:.4g} s ({self.m:.4g} samples) [{self.tau_low:.3g}, {self.tau_high:.3g}] s"
                f" for σ = {self.dev:.4g} [{self.dev_low:.3g}, {self.dev_high:.3g}] {pretty(self.unit)};"
                f" within 5 % from {self.flat_low:.3g} to {self.flat_high:.3g} s")


def _short(p: Parameter) -> str:
    """Value and unit for the table's SI and customary columns (``< bound`` when not resolved)."""
    if not p.resolved:
        return f"< {p.high:.3g} {pretty(p.unit)}" if math.isfinite(p.high) else "—"
    return f"{p.value:.4g} {pretty(p.unit)}"


def format_duration(seconds: float) -> str:
    """A duration in the largest of s, min and h that keeps it at least 1 (three digits)."""
    if seconds >= 3600:
        return f"{seconds / 3600:.3g} h"
    if seconds >= 60:
        return f"{seconds / 60:.3g} min"
    return f"{seconds:.3g} s"
