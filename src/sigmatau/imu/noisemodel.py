"""The IMU noise model of one channel, :class:`NoiseModel`, and its optimal averaging time.

:class:`NoiseModel` is what :func:`~sigmatau.imu.analyze` returns: the five
parameters, both extractions, the fitted curve and its covariance, flags, and
the answers derived from them (angle error, optimal averaging, Kalibr values,
comparison with a datasheet). :func:`optimal_averaging` is defined here, beside
the class whose method calls it (a separate module would import the class and
be imported by it: a cycle); its numerical steps are in
:mod:`sigmatau.imu.answers`. The Kalibr entry of one model (``_kalibr_entry``) is
here for the same reason; the multi-axis :func:`~sigmatau.imu.kalibr_config`
is in :mod:`sigmatau.imu.kalibr`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping, Optional, Sequence, Union

import numpy as np

from ..core.present import data_frame, html_table, plot
from ..core.result import StabilityResult
from ..errors import ParameterError
from .answers import _draw_intervals, _flat_range, _minimum_draws, _model_minimum, angle_error
from .checks import DataChecks
from .results import Flag, GaussMarkov, OptimalAveraging, Parameter, Region, _short, format_duration
from .terms import _design, _gm_column, _level, _num
from .units import TERMS, convert, pretty

__all__ = ["NoiseModel", "optimal_averaging"]


@dataclass(frozen=True, repr=False, eq=False)
class NoiseModel:
    """IMU noise model of one channel (see :func:`~sigmatau.imu.analyze`).

    Attributes
    ----------
    Q, N, B, K, R : Parameter
        The five coefficients, from the fit (``method="fit"``) when it could be
        made, else from the read-offs.
    kind : {"gyro", "accel"}
    unit : str
        Unit of the samples (parameters are in this unit per √Hz etc.).
    rate : float
        Sample rate (Hz).
    n_samples : int
        Samples behind the curve.
    confidence : float
        Two-sided coverage of every interval.
    readoff, fit : mapping of str to Parameter
        Both extractions, term by term.
    regions : mapping of str to Region
        Region chosen for each read-off.
    fit_terms : tuple of str
        Terms kept by the fit's term selection: the selected model, drawn over
        the curve (:attr:`coefficients`, :meth:`variance`). The fit's
        parameters are not always its coefficients: the value and interval of
        a term the selection could have dropped are those of the unconstrained
        fit given the selection (see :func:`~sigmatau.imu.analyze`, *Intervals*).
    fit_chi2, fit_dof : float, int
        Weighted residual sum of squares and degrees of freedom of the fit.
    discrepancy : float
        Relative model-discrepancy floor ε added to every point's uncertainty
        when the five-term model does not describe the curve within its
        statistical scatter (0 otherwise).
    filter_time : float
        τ_f (s) of a significant negative 1/τ² term, AVAR ≈ N²/τ·(1 − τ_f/τ):
        the sensor's low-pass filter at the shortest τ (0 when absent).
    flags : tuple of Flag
        Not resolved terms, data problems, read-off vs fit disagreements,
        model inadequacy.
    checks : DataChecks or None
        Data checks (raw-sample input only).
    result : StabilityResult
        The OADEV curve the model was extracted from.
    gauss_markov : GaussMarkov or None
        The first-order Gauss–Markov term (σ_GM, T_c) when the model includes
        one (``analyze(..., gauss_markov=)``), else None.
    gauss_markov_test : dict or None
        What was decided about a GM term: criterion, ΔBIC, effective number of
        points, best correlation time, reason (also when none was kept).
    """

    kind: str
    unit: str
    rate: float
    n_samples: int
    confidence: float
    Q: Parameter
    N: Parameter
    B: Parameter
    K: Parameter
    R: Parameter
    readoff: Mapping[str, Parameter]
    fit: Mapping[str, Parameter]
    regions: Mapping[str, Region]
    fit_terms: tuple[str, ...]
    fit_chi2: float
    fit_dof: int
    discrepancy: float
    filter_time: float
    flags: tuple[Flag, ...]
    checks: Optional[DataChecks]
    result: StabilityResult
    _coef: np.ndarray = field(default=None, repr=False)  # type: ignore[assignment]
    _cov: np.ndarray = field(default=None, repr=False)  # type: ignore[assignment]
    gauss_markov: Optional[GaussMarkov] = None
    gauss_markov_test: Optional[dict] = None
    _gm: Optional[tuple] = field(default=None, repr=False)  # (σ², T_c) of a kept GM term

    # -- access ----------------------------------------------------------------
    def parameters(self) -> dict[str, Parameter]:
        """The five primary parameters by term."""
        return {t: getattr(self, t) for t in TERMS}

    @property
    def duration(self) -> float:
        """Record length in seconds."""
        return self.n_samples / self.rate

    @property
    def resolved(self) -> tuple[str, ...]:
        """Terms the record resolves (primary parameters)."""
        return tuple(t for t in TERMS if getattr(self, t).resolved)

    # -- the fitted curve -------------------------------------------------------
    @property
    def coefficients(self) -> dict[str, float]:
        """Fitted AVAR coefficients ``Q², N², B², K², R²`` of the selected model by term (input units
        squared): the model drawn over the curve, not the parameters' values (which are adjusted for
        the term selection; a term dropped beside a kept one adds its share to it here).

        0 for a dropped term; the ``Q`` entry is negative when it holds the
        sensor's low-pass filter (see ``filter_time``).
        """
        return {t: float(c) for t, c in zip(TERMS, self._coef)}

    @property
    def covariance(self) -> np.ndarray:
        """5×5 covariance of :attr:`coefficients` (order Q, N, B, K, R; zero rows for
        dropped terms), with the τ correlation and any discrepancy floor included."""
        out = np.array(self._cov, dtype=float)
        out.setflags(write=False)
        return out

    def variance(self, taus: Union[float, Sequence[float], np.ndarray]) -> np.ndarray:
        """Allan variance of the fitted model at ``taus`` (kept terms only, a Gauss–Markov term included)."""
        t = np.asarray(taus, dtype=float)
        t1 = np.atleast_1d(t)
        v = _design(t1, self.rate) @ self._coef
        if self._gm is not None:
            v = v + self._gm[0] * _gm_column(t1, self.rate, self._gm[1])
        return v if t.ndim else float(v[0])

    def deviation(self, taus: Union[float, Sequence[float], np.ndarray]) -> np.ndarray:
        """Allan deviation of the fitted model at ``taus``."""
        return np.sqrt(self.variance(taus))

    def term_deviation(self, term: str, taus: Union[float, Sequence[float], np.ndarray]) -> np.ndarray:
        """Deviation contributed by one term of the fit at ``taus`` (0 for a dropped term,
        NaN for a negative 1/τ² filter term, which subtracts variance). ``term="GM"``: the
        Gauss–Markov term (0 when the model has none)."""
        t = np.atleast_1d(np.asarray(taus, dtype=float))
        if term == "GM":
            return np.sqrt(self._gm[0] * _gm_column(t, self.rate, self._gm[1])) if self._gm else np.zeros(t.shape)
        j = TERMS.index(term)
        with np.errstate(invalid="ignore"):
            return np.sqrt(_design(t, self.rate)[:, j] * self._coef[j])

    # -- answers ------------------------------------------------------------------
    def angle_error(self, t: float, *, random_walk: bool = False) -> Parameter:
        """RMS angle (gyro) or velocity (accel) error after integrating for ``t`` seconds.

        ``N·√t`` (the design tip's ARW·√time); with ``random_walk=True`` the
        rate random walk adds ``K²t³/3`` to the variance. The interval follows
        from those of N (and K). Units: the input unit times s (rad for rad/s).
        """
        return angle_error(t, arw=self.N, rrw=self.K if random_walk else None)

    def optimal_averaging(self) -> OptimalAveraging:
        """Averaging time that minimises the deviation (see :func:`optimal_averaging`)."""
        return optimal_averaging(self)

    def kalibr(self, *, inflate: float = 1.0) -> dict[str, Any]:
        """Kalibr (continuous-time) values and their discrete-time equivalents, labelled.

        Parameters
        ----------
        inflate : float
            Factor applied to both values, recorded in the output (some
            estimators want inflated values for low-cost sensors); 1 by default.

        Returns
        -------
        dict
            ``<sensor>_noise_density`` = N and ``<sensor>_random_walk`` = K in
            SI (rad/s/√Hz, rad/s²/√Hz or m/s²/√Hz, m/s³/√Hz), ``update_rate``,
            their units, whether each is resolved (an unresolved K is given as
            its upper bound and labelled so), and ``discrete``: ``σ_d = N·√f``
            and ``σ_bd = K/√f`` at the update rate — discrete standard
            deviations, not densities.
        """
        return _kalibr_entry(self, inflate)

    def compare(self, reference: Mapping[str, tuple[float, str]]) -> list[dict[str, Any]]:
        """Compare with datasheet or published figures given in any unit.

        Parameters
        ----------
        reference : mapping
            Term → ``(value, unit)``, e.g. ``{"N": (0.0135, "deg/s/sqrt(Hz)")}``.

        Returns
        -------
        list of dict
            Per term: the reference value converted to the model's unit, the
            measured value and interval, their ratio and whether the interval
            covers the reference.
        """
        rows = []
        for term, (value, unit) in reference.items():
            if term not in TERMS:
                raise ParameterError(f"reference term {term!r} must be one of {TERMS}")
            p = getattr(self, term)
            ref = float(convert(value, unit, p.unit))
            rows.append({"term": term, "reference": ref, "reference_given": f"{value:g} {unit}",
                         "measured": _num(p.value), "low": _num(p.low), "high": _num(p.high), "unit": p.unit,
                         "ratio": _num(p.value / ref) if p.resolved and ref else None,
                         "covers": bool(p.low <= ref <= p.high), "resolved": p.resolved})
        return rows

    # -- presentation -------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of everything but the curve (which has its own ``to_dict``)."""
        return {
            "kind": self.kind, "unit": self.unit, "rate": self.rate, "n_samples": self.n_samples,
            "duration_s": self.duration, "confidence": self.confidence,
            "parameters": {t: getattr(self, t).to_dict() for t in TERMS},
            "si": {t: getattr(self, t).si().to_dict() for t in TERMS},
            "customary": {t: [p.to_dict() for p in getattr(self, t).customary()] for t in TERMS},
            "readoff": {t: p.to_dict() for t, p in self.readoff.items()},
            "fit": {t: p.to_dict() for t, p in self.fit.items()},
            "regions": {t: r.to_dict() for t, r in self.regions.items()},
            "fit_terms": list(self.fit_terms), "fit_chi2": _num(self.fit_chi2), "fit_dof": self.fit_dof,
            "discrepancy": self.discrepancy, "filter_time": self.filter_time,
            "flags": [f._asdict() for f in self.flags],
            "checks": self.checks.to_dict() if self.checks is not None else None,
            "kalibr": self.kalibr(),
            "gauss_markov": self.gauss_markov.to_dict() if self.gauss_markov is not None else None,
            "gauss_markov_test": self.gauss_markov_test,
        }

    def to_table(self) -> str:
        """Readable table: each term in the input unit, SI and customary units, and its read-off."""
        sensor = "gyroscope" if self.kind == "gyro" else "accelerometer"
        head = (f"IMU noise model: {sensor}, samples in {pretty(self.unit)} at {self.rate:g} Hz,"
                f" {self.n_samples} samples ({format_duration(self.duration)}); OADEV τ {self.result.taus[0]:.3g}"
                f"–{self.result.taus[-1]:.3g} s; {100 * self.confidence:.1f} % intervals;"
                f" fit terms: {', '.join(self.fit_terms) or 'none'}")
        rows = [["term", "value (" + ("fit" if self.fit else "read-off") + ")", "SI", "customary",
                 "read-off", "read-off region"]]
        for t in TERMS:
            p = getattr(self, t)
            si = p.si()
            cust = "; ".join(_short(c) for c in p.customary())
            ro = self.readoff.get(t)
            reg = self.regions.get(t)
            region = (f"{reg.tau_low:.3g}–{reg.tau_high:.3g} s" if reg is not None and reg.resolved else "—")
            rows.append([t, p.format(), _short(si), cust, ro.format() if ro is not None else "—", region])
        widths = [max(len(r[j]) for r in rows) for j in range(len(rows[0]))]
        lines = [head] + ["  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows]
        if self.gauss_markov is not None:
            gm = self.gauss_markov
            lines.append(f"Gauss–Markov term: {gm.format()} ({gm.criterion}: ΔBIC {gm.delta_bic:.3g};"
                         " not in the Kalibr entry, which has no such term)")
        if self.flags:
            lines.append("flags:")
            lines += [f"  - [{f.code}{' ' + f.term if f.term else ''}] {f.message}" for f in self.flags]
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.to_table()

    def __repr__(self) -> str:
        vals = ", ".join(f"{t}={getattr(self, t).format(3, unit=False)}" for t in TERMS)
        return f"NoiseModel({self.kind}, {self.unit}, {self.rate:g} Hz: {vals})"

    def _repr_html_(self) -> str:
        """The table of :meth:`to_table` as HTML, for notebooks."""
        rows = []
        for t in TERMS:
            p = getattr(self, t)
            ro = self.readoff.get(t)
            reg = self.regions.get(t)
            region = f"{reg.tau_low:.3g}–{reg.tau_high:.3g} s" if reg is not None and reg.resolved else "—"
            rows.append([t, p.format(), _short(p.si()), "; ".join(_short(c) for c in p.customary()),
                         ro.format() if ro is not None else "—", region])
        sensor = "gyroscope" if self.kind == "gyro" else "accelerometer"
        caption = (f"IMU noise model: {sensor}, {pretty(self.unit)} at {self.rate:g} Hz,"
                   f" {format_duration(self.duration)}; {100 * self.confidence:.1f} % intervals;"
                   f" fit terms: {', '.join(self.fit_terms) or 'none'}")
        notes = [f"[{f.code}{' ' + f.term if f.term else ''}] {f.message}" for f in self.flags]
        if self.gauss_markov is not None:
            notes.insert(0, f"Gauss–Markov term: {self.gauss_markov.format()}")
        return html_table(["term", "value", "SI", "customary", "read-off", "read-off region"], rows,
                          caption=caption, notes=notes)

    def to_pandas(self) -> Any:
        """A pandas DataFrame, one row per term (Q, N, B, K, R), in the input unit and in SI.

        Columns ``term``, ``value``, ``low``, ``high``, ``unit``, ``value_si``, ``low_si``,
        ``high_si``, ``unit_si``, ``resolved`` (False: only ``high`` is an upper bound),
        ``method`` (fit or read-off), ``readoff`` and ``readoff_unit``; ``frame.attrs``
        holds ``kind``, ``unit``, ``rate_hz``, ``n_samples``, ``duration_s``, ``confidence``
        and ``fit_terms``. Needs pandas (extra ``pandas``).
        """
        cols: dict[str, list[Any]] = {k: [] for k in ("term", "value", "low", "high", "unit", "value_si", "low_si",
                                                      "high_si", "unit_si", "resolved", "method", "readoff",
                                                      "readoff_unit")}
        for t in TERMS:
            p = getattr(self, t)
            si = p.si()
            ro = self.readoff.get(t)
            for key, value in (("term", t), ("value", p.value), ("low", p.low), ("high", p.high),
                               ("unit", p.unit), ("value_si", si.value), ("low_si", si.low), ("high_si", si.high),
                               ("unit_si", si.unit), ("resolved", bool(p.resolved)), ("method", p.method),
                               ("readoff", ro.value if ro is not None else float("nan")),
                               ("readoff_unit", ro.unit if ro is not None else "")):
                cols[key].append(value)
        return data_frame(cols, attrs={"kind": self.kind, "unit": self.unit, "rate_hz": self.rate,
                                       "n_samples": self.n_samples, "duration_s": self.duration,
                                       "confidence": self.confidence, "fit_terms": list(self.fit_terms)})

    def plot(self, ax: Any = None, **kw: Any) -> Any:
        """Draw the OADEV curve with its intervals, the fitted model and each term (matplotlib).

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure's when None.
        **kw
            ``label`` (default: the sensor kind), ``color``, ``terms`` (draw each term's
            line, default True).

        Returns
        -------
        matplotlib.axes.Axes
        """
        return plot("model", self, ax=ax, **kw)


def optimal_averaging(model: NoiseModel, *, draws: int = 400) -> OptimalAveraging:
    """Averaging time that minimises the Allan deviation, with its interval.

    Parameters
    ----------
    model : NoiseModel
        Result of :func:`~sigmatau.imu.analyze`.
    draws : int
        Monte-Carlo draws from the fit's covariance for the interval.

    Returns
    -------
    OptimalAveraging

    Notes
    -----
    The design tip's question — how many samples to average to minimise the
    variance of the output — is answered by the minimum of the fitted
    σ²(τ); for white noise and random walk alone it is at
    ``τ = √3·N/K`` with ``σ² = 2NK/√3``. The interval comes from redrawing the
    squared coefficients from the fit's (Gaussian) covariance, clipped at
    zero, and taking the quantiles of the minimising τ (draws are made with a
    fixed seed, so the answer is reproducible). When neither K nor R is kept the
    model has no minimum: averaging longer keeps helping within the record.

    Examples
    --------
    >>> from sigmatau.imu import simulate, analyze
    >>> y = simulate("euroc-gyro", duration=3600.0, rng=5)
    >>> opt = analyze(y, rate=200.0, unit="rad/s").optimal_averaging()
    >>> 8 < opt.tau < 30          # √3·N/K = 15.2 s
    True
    """
    coef = np.asarray(model._coef, float)
    rate = model.rate
    unit = model.B.unit
    taus = np.asarray(model.result.taus, float)
    k_min = int(np.argmin(model.result.dev))
    data_tau, data_dev = float(taus[k_min]), float(model.result.dev[k_min])
    conf = model.confidence
    tau, dev = _model_minimum(coef, rate)
    taus_mc, devs_mc = _minimum_draws(coef, model._cov, rate, draws)
    t_lo, t_hi, d_lo, d_hi = _draw_intervals(taus_mc, devs_mc, conf)
    if not math.isfinite(tau):
        note = "the fit keeps no K or R term"
        return OptimalAveraging(math.inf, math.inf, dev, taus[-1], math.inf, d_lo, d_hi, math.nan, math.inf,
                                data_tau, data_dev, False, unit, conf, note)
    flat_lo, flat_hi = _flat_range(coef, rate, tau, dev)
    resolved = tau <= taus[-1] * 1.0001
    note = "" if resolved else f"the model's minimum lies beyond the longest τ of the record ({taus[-1]:.3g} s)"
    return OptimalAveraging(tau, tau * rate, dev, t_lo, t_hi, d_lo, d_hi, flat_lo, flat_hi, data_tau, data_dev,
                            bool(resolved), unit, conf, note)


def _kalibr_entry(model: NoiseModel, inflate: float) -> dict[str, Any]:
    """Kalibr entry of one model (see :meth:`NoiseModel.kalibr`); an unresolved value enters as its bound."""
    f = _level(inflate, "inflate")
    if f <= 0:
        raise ParameterError(f"inflate={inflate!r} must be positive")
    name = "gyroscope" if model.kind == "gyro" else "accelerometer"
    n_si, k_si = model.N.si(), model.K.si()
    n_val = n_si.value if n_si.resolved else n_si.high
    k_val = k_si.value if k_si.resolved else k_si.high
    sig = "rad/s" if model.kind == "gyro" else "m/s^2"
    bias = "rad/s^2" if model.kind == "gyro" else "m/s^3"
    return {
        "convention": "Kalibr IMU noise model, continuous time (densities)",
        f"{name}_noise_density": _num(n_val * f),
        f"{name}_random_walk": _num(k_val * f),
        "update_rate": model.rate,
        "units": {f"{name}_noise_density": n_si.unit, f"{name}_random_walk": k_si.unit, "update_rate": "Hz"},
        "resolved": {f"{name}_noise_density": n_si.resolved, f"{name}_random_walk": k_si.resolved},
        "labels": {f"{name}_noise_density": "value" if n_si.resolved else "upper bound (not resolved)",
                   f"{name}_random_walk": "value" if k_si.resolved else "upper bound (not resolved)"},
        "inflation": f,
        "source": n_si.method,
        # Kalibr's model has no correlated (Gauss–Markov) term: a GM term found by the fit is
        # stated here and left out of the values (N and K are those of the model that includes it).
        "gauss_markov": (None if model.gauss_markov is None or not model.gauss_markov.resolved else
                         "a Gauss–Markov term was found (σ = {:.4g} {}, T_c = {:.4g} s); Kalibr has no such"
                         " term, so it is not in these values".format(model.gauss_markov.sigma.value,
                                                                       model.gauss_markov.sigma.unit,
                                                                       model.gauss_markov.tau_c.value)),
        "discrete": {
            "convention": f"discrete-time standard deviations at update_rate = {model.rate:g} Hz;"
                          " not densities: sigma_d = N·√f, sigma_bd = K/√f",
            "sigma_d": _num(n_val * f * math.sqrt(model.rate)),
            "sigma_bd": _num(k_val * f / math.sqrt(model.rate)),
            "units": {"sigma_d": sig, "sigma_bd": bias},
        },
    }
