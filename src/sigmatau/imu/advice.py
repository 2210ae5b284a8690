"""How long must a record still run? The stopping rule of an IMU noise recording (issue 17).

:func:`recording_advice` takes the model of a record so far (:func:`~sigmatau.imu.analyze`)
and says, term by term, how well each coefficient is known and how much longer the record
must run for a target precision: ``N known to ±0.48 %, B resolved (±19 %), Q, K, R not yet
resolved: record ≈ 35 min more for ±10 % on B; at their bounds, …``. The prediction is the
covariance of the model's own fit evaluated for a longer record (:mod:`~sigmatau.imu.forecast`),
applied to the interval measured now; see the Notes of :func:`recording_advice`. Results are
:class:`RecordingAdvice` with one :class:`TermAdvice` per term.

Validation
----------
80-min records at 100 Hz (truths in rad/s units: N = 1e-3, B = 2.75e-4, K = 4e-5), the
advice taken on their first 20 min, its predicted relative half-width for 80 min divided by
the one :func:`~sigmatau.imu.analyze` gives on the 80 min; median [25–75 %] over the 16 runs
of tests/test_imu_advice.py, with the selection-aware intervals of kept terms (a kept B or K
near its detection limit prints a wider interval than ``ĉ ± zσ_c``; the 40-run table measured
before them had B 1.11 beside N, 0.79 and 0.84 beside K, K 1.00):

==========================  ======  =======================  ==============================
configuration               term    predicted / achieved     note
==========================  ======  =======================  ==============================
N                           N       1.000 [0.999, 1.002]     ``√(T/T')``: 0.50 per ×4
N + B                       N       1.001 [0.994, 1.003]
N + B                       B       1.03 [0.84, 1.57]        faster than ``√``: 0.40 per ×4
N + B + K                   N       0.999 [0.997, 1.001]
N + B + K                   B       0.90 [0.74, 1.30]        K, unresolved at 20 min, widens
                                                             B later (not in the curve)
N + B + K, K assumed        B       0.95 [0.78, 1.37]        ``assume={"K": 4e-5}``
N + B + K, K assumed        K       1.03 [1.00, 1.46]        10 runs resolving K at 80 min
==========================  ======  =======================  ==============================

K was a bound after 20 min in 31 of 40 runs and a value after 80 min in 34; given the true K
the advice predicted it resolved after 48 min (median; 40–52 min). The length at which a
term not yet resolved shows is a median: at that length 27 % (K over B) and 73 % (B over
N) of 30 records resolved it, at 1.6× it 70 % and 73 %, at 1/1.6 of it 27 % and 20 %. A
term resolved only just (its realisation came out high) is predicted too narrow (K resolved
at 20 min: 0.6× in 6 runs). One call costs about 0.1 s (20-min model, five terms).

Real data (the ADIS16405 recording of tests/test_imu_real.py, 2.8 h at 100 Hz; advice on
the first 10 or 42 min, compared with the whole record): gyro X and Y (no discrepancy
floor) N 0.99–1.01×, B 0.92× on X and 0.60–0.67× on Y, where K appears later (the limit
above); on the channels whose curve departs from the model (discrepancy floor ε = 15–28 %
per τ, the accelerometers and gyro Z) 0.35–2.3×: ε itself changes with the record, and
the advice can only assume it stays (its summary says so).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal, Mapping, Optional

import numpy as np
from scipy.special import ndtri

from ..errors import ParameterError
from .forecast import _Anchor, _first_time, _h, _h_printed, _Plan
from .noisemodel import NoiseModel
from .terms import _num
from .units import TERMS, pretty

__all__ = ["recording_advice", "RecordingAdvice", "TermAdvice", "HORIZON"]

#: Longest record considered, as a multiple of the current one: a target or a detection
#: that needs more is reported as out of reach (``inf``) rather than extrapolated.
HORIZON = 1000.0

Status = Literal["known", "resolved", "not resolved"]


# ----------------------------------------------------------------------------- results
@dataclass(frozen=True)
class TermAdvice:
    """What the record says about one term, and how much longer it must run.

    Attributes
    ----------
    term : {"Q", "N", "B", "K", "R"}
    status : {"known", "resolved", "not resolved"}
        ``known``: resolved with a relative half-width at most ``target``;
        ``resolved``: resolved but wider; ``not resolved``: only an upper bound.
    value : float
        The model's estimate (NaN when not resolved).
    bound : float
        Upper bound of a term not resolved (``inf`` when there is none), NaN when resolved.
    unit : str
        Unit of ``value`` and ``bound`` (the model's).
    precision : float
        Relative half-width of the interval now, ``(high − low)/(2·value)`` at
        ``confidence`` (NaN when not resolved).
    target : float
        Relative half-width asked for.
    confidence : float
        Two-sided coverage of the intervals the precision refers to.
    assumed : float
        For a term not resolved: the value the predictions assume (the bound unless
        ``assume=`` gave one); NaN when resolved.
    detect_time : float
        Seconds more until the term is resolved (0 when it is; for a term not resolved,
        that of a term of value ``assumed``); ``inf`` beyond the horizon, NaN without a
        prediction.
    extra_time : float
        Seconds more until its precision reaches ``target`` (0 when known; for a term
        not resolved, that of a term of value ``assumed``); ``inf`` beyond the horizon,
        NaN without a prediction.
    basis : str
        How the prediction was made, or why none could be.
    """

    term: str
    status: Status
    value: float
    bound: float
    unit: str
    precision: float
    target: float
    confidence: float
    assumed: float
    detect_time: float
    extra_time: float
    basis: str

    def sentence(self) -> str:
        """One line for a person: status, precision or bound, and the time still needed."""
        u = pretty(self.unit)
        tgt = f"±{_pct(self.target)} %"
        if self.status == "known":
            return f"{self.term} = {self.value:.3g} {u}: known to ±{_pct(self.precision)} % (target {tgt})"
        if self.status == "resolved":
            head = f"{self.term} = {self.value:.3g} {u}: resolved, ±{_pct(self.precision)} %"
            return f"{head}; {_time_clause(self.extra_time, tgt, self.basis)}"
        if not math.isfinite(self.bound):
            return f"{self.term}: not resolved, no bound; {self.basis}"
        head = f"{self.term}: not yet resolved, {self.term} < {self.bound:.3g} {u}"
        return f"{head}; {self._unresolved_clause(tgt, u)}"

    def _unresolved_clause(self, tgt: str, u: str) -> str:
        """The prediction for a term of value ``assumed``: when it would be resolved, then known."""
        at = ("at that bound" if self.assumed == self.bound
              else f"of {self.assumed:.3g} {u} (assumed)")
        if math.isnan(self.detect_time):
            return self.basis
        a = "an" if self.term in ("N", "R") else "a"
        if math.isinf(self.detect_time):
            return f"{a} {self.term} {at} would not be resolved {self.basis}"
        # Resolved "now" at a bound means the bound is looser than what the record could show.
        when = ("already (in about half of such records)" if self.detect_time == 0
                else f"after ≈ {_format_time(self.detect_time)} more")
        known = (f" and known to {tgt} after ≈ {_format_time(self.extra_time)} more"
                 if math.isfinite(self.extra_time) else f", but not known to {tgt} {self.basis}")
        smaller = ""
        if self.assumed == self.bound:
            smaller = (f" ({self.term} is probably smaller)" if self.detect_time == 0
                       else f" (a smaller {self.term} needs longer)")
        return f"{a} {self.term} {at} would be resolved {when}{known}{smaller}"

    def __str__(self) -> str:
        return self.sentence()

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (NaN and inf become None; ``*_time`` in seconds)."""
        return {"term": self.term, "status": self.status, "value": _num(self.value), "bound": _num(self.bound),
                "unit": self.unit, "precision": _num(self.precision), "target": self.target,
                "confidence": self.confidence, "assumed": _num(self.assumed),
                "detect_time_s": _num(self.detect_time), "extra_time_s": _num(self.extra_time),
                "reachable": math.isfinite(self.extra_time), "basis": self.basis, "sentence": self.sentence()}


@dataclass(frozen=True, repr=False, eq=False)
class RecordingAdvice:
    """The stopping rule of a record: per term, how well it is known and how long to go on.

    Attributes
    ----------
    duration : float
        Length of the record so far (s).
    rate : float
        Sample rate (Hz).
    kind : {"gyro", "accel"}
    confidence : float
        Two-sided coverage of the precisions.
    target : float
        Relative half-width asked for.
    max_duration : float
        Longest record the predictions consider (s).
    discrepancy : float
        The model's discrepancy floor ε (relative, per τ), which no record length removes.
    terms : tuple of TermAdvice
        One per term of the model (terms left out with ``analyze(terms=)`` are absent).
    """

    duration: float
    rate: float
    kind: str
    confidence: float
    target: float
    max_duration: float
    discrepancy: float
    terms: tuple[TermAdvice, ...]
    _plan: "_Plan" = field(repr=False)
    _anchors: Mapping[str, "_Anchor"] = field(repr=False)

    def __getitem__(self, term: str) -> TermAdvice:
        for t in self.terms:
            if t.term == term:
                return t
        raise KeyError(term)

    @property
    def complete(self) -> bool:
        """True when every resolved term is known to the target."""
        return all(t.status != "resolved" for t in self.terms)

    @property
    def extra_time(self) -> float:
        """Seconds more until every resolved term is known to the target (0 when complete, NaN
        when one of them has no prediction)."""
        times = [t.extra_time for t in self.terms if t.status == "resolved"]
        return math.nan if any(math.isnan(t) for t in times) else max(times, default=0.0)

    def precision_at(self, duration: float) -> dict[str, float]:
        """Predicted relative half-width of each term after a record of ``duration`` seconds.

        A resolved term's is its current precision scaled as in the Notes of
        :func:`recording_advice`; a term not resolved gets that of a term of value
        ``assumed`` when it would be resolved by then, NaN otherwise (and without a
        prediction).
        """
        t_new = _positive(duration, "duration")
        out = {}
        for adv in self.terms:
            anchor = self._anchors.get(adv.term)
            if anchor is None:
                out[adv.term] = math.nan
            elif adv.status == "not resolved" and not anchor.detection(t_new) >= 1.0:
                out[adv.term] = math.nan
            else:
                out[adv.term] = anchor.precision(t_new)
        return out

    def headline(self) -> str:
        """The live status line: ``N known to ±0.4 %, B resolved (±19 %), K not yet resolved: record ≈ …``."""
        state = []
        for t in self.terms:
            if t.status == "known":
                state.append(f"{t.term} known to ±{_pct(t.precision)} %")
            elif t.status == "resolved":
                state.append(f"{t.term} resolved (±{_pct(t.precision)} %)")
        waiting = [t.term for t in self.terms if t.status == "not resolved"]
        if waiting:
            state.append(f"{', '.join(waiting)} not yet resolved")
        tgt = f"±{_pct(self.target)} %"
        pending = [t for t in self.terms if t.status == "resolved"]
        if not pending:
            todo = [f"every resolved term is known to {tgt}"]
        elif all(math.isfinite(t.extra_time) for t in pending):
            todo = [f"record ≈ {_format_time(self.extra_time)} more for {tgt} on "
                    + ", ".join(t.term for t in pending)]
        else:
            todo = []
            out = [t.term for t in pending if math.isinf(t.extra_time)]
            if out:
                todo.append(f"{tgt} on {', '.join(out)} is not reachable within {_format_time(self.max_duration)}")
            unknown = [t.term for t in pending if math.isnan(t.extra_time)]
            if unknown:
                todo.append(f"no prediction for {', '.join(unknown)}")
        todo += _detection_clause([t for t in self.terms if t.status == "not resolved"
                                   and math.isfinite(t.detect_time)])
        return ", ".join(state) + ": " + "; ".join(todo)

    def summary(self) -> str:
        """A header and one sentence per term (:meth:`TermAdvice.sentence`)."""
        head = (f"after {_format_time(self.duration)} at {self.rate:g} Hz ({self.kind},"
                f" {100 * self.confidence:.1f} % intervals, target ±{_pct(self.target)} %):")
        lines = [head] + [f"  {t.sentence()}" for t in self.terms]
        if self.discrepancy > 0:
            lines.append(f"  note: the curve departs from the model (discrepancy floor {100 * self.discrepancy:.2g} %"
                         " per τ); the predictions assume it stays as it is, and are rough")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.summary()

    def __repr__(self) -> str:
        states = ", ".join(f"{t.term} {t.status}" for t in self.terms)
        return f"RecordingAdvice({_format_time(self.duration)}, target ±{_pct(self.target)} %: {states})"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary: the settings, ``headline``, and one entry per term."""
        return {"duration_s": self.duration, "rate_hz": self.rate, "kind": self.kind,
                "confidence": self.confidence, "target": self.target, "max_duration_s": self.max_duration,
                "discrepancy": self.discrepancy, "complete": self.complete,
                "extra_time_s": _num(self.extra_time), "headline": self.headline(),
                "terms": {t.term: t.to_dict() for t in self.terms}}


# ----------------------------------------------------------------------------- the function
def recording_advice(model: NoiseModel, *, duration: Optional[float] = None, target: float = 0.10,
                     confidence: Optional[float] = None, assume: Optional[Mapping[str, float]] = None,
                     max_duration: Optional[float] = None) -> RecordingAdvice:
    r"""How well each term of a record's noise model is known, and how long to go on recording.

    Parameters
    ----------
    model : NoiseModel
        The model of the record so far (:func:`~sigmatau.imu.analyze`).
    duration : float, optional
        Length of the record behind ``model`` in seconds (default ``model.duration``,
        ``n_samples/rate``).
    target : float
        Relative half-width wanted for every term, in (0, 1); 0.10 is ±10 %.
    confidence : float, optional
        Coverage the precisions refer to, in (0, 1) (default: the model's).
    assume : mapping of str to float, optional
        For terms the record does not resolve: the value (in the term's unit) to
        predict with instead of the upper bound, e.g. a datasheet figure. It enters
        the curve behind every prediction (a K that will appear widens B later).
    max_duration : float, optional
        Longest record considered (s; default ``HORIZON`` = 1000 times ``duration``).

    Returns
    -------
    RecordingAdvice
        ``str()`` gives one sentence per term, :meth:`~RecordingAdvice.headline` the
        live one-liner, :meth:`~RecordingAdvice.to_dict` the JSON form.

    Raises
    ------
    ParameterError
        A model that is not a :class:`NoiseModel` or resolves no term, ``duration`` or
        ``max_duration`` not positive, ``target`` or ``confidence`` outside (0, 1), an
        ``assume`` entry for a term that is resolved or not in the model.

    Notes
    -----
    *Precision now.* The fit's interval on a squared coefficient ``c = P²`` is
    ``ĉ ± z_p·σ_c`` (the unconstrained fit of every term, see ``analyze``,
    *Intervals*), so the relative half-width of ``P`` is

    .. math:: h(a) = \tfrac12\left(\sqrt{1 + a} - \sqrt{\max(1 - a, 0)}\right),
              \qquad a = z_p\,s,\quad s = \sigma_c/c.

    The precision reported now is the interval's, ``(high − low)/(2·value)``
    (at another ``confidence``, ``h(z_p s)``); ``s`` is that fit's, redone on
    the model's curve.

    *How it shrinks.* Each OADEV point at ``τ_i = m_i τ_0`` has the EDF
    ``ν_i = ν(α_i, m_i, N)`` of Greenhall and Riley (SP1065 §5.3) at the noise
    type ``α_i`` of the term that dominates the fitted curve there; away from the
    end of the record ``ν_i ≈ κ_α·T/τ_i``. The fit's covariance is the sandwich

    .. math:: \Sigma_c(T) = B\,A^\mathsf{T} W C W A\,B,\quad B = (A^\mathsf{T} W A)^{-1},
              \quad W_{ii} = \left[\sigma^2(\tau_i)\right]^{-2}(2/\nu_i + \varepsilon^2)^{-1},

    with ``A`` the model's columns (3/τ², 1/τ, 2 ln 2/π, τ/3, τ²/2, and a
    Gauss–Markov column if the model has one), ``C`` the correlation of
    neighbouring τ and ε the model's discrepancy floor — exactly the covariance
    behind the model's intervals (``analyze``, *Intervals*), here evaluated on the
    fitted curve for a record of ``T'`` seconds: the τ grid is extended to
    ``m ≤ N'/stop`` (stop ratio 4 for OADEV) and every ``ν_i`` re-evaluated at
    ``N' = T'·f``. The curve is that of the kept terms at the unconstrained
    fit's ``ĉ`` (free of term selection); a term not resolved is 0 in it unless
    ``assume`` gives it a value. A resolved term's precision is predicted as its
    current one scaled by the model ratio,

    .. math:: h'(T') = h_\text{now}\;\frac{h\!\left(z_p\,s\,r(T')\right)}{h(z_p\,s)},
              \qquad r(T') = \frac{s_\text{model}(T')}{s_\text{model}(T)},

    so that what the model does not describe (an EDF set lower by the noise
    identification, a discrepancy floor) carries over. The asymptotes: a term
    read at fixed τ (N and Q at the short end, B on a flat bottom bounded by N
    and K) has every ``ν_i ∝ T``, so ``r = √(T/T')`` and ``h' ≈ h·√(T/T')``; a
    flat bottom that still runs to the end of the record also gains points
    and falls faster (B over N, 20 → 80 min: ``r = 0.40``).
    A term whose evidence sits at the end of the record (K, R) gains both EDF
    and τ. Before its line crosses the rest of the curve at ``τ_x``, its
    evidence is the last points, ``τ ≈ T/4``, whose EDF is that of a few
    averages whatever ``T``; there its share of the variance grows as
    ``T/τ_x`` (K over a flat B, R over K) or ``(T/τ_x)²`` (K over white noise,
    R over B), and ``s ≈ √(2/ν)/share`` falls as ``1/T`` or ``1/T²``. Once
    ``τ_x`` is well inside the record the points near it carry most of the
    information and the ``√(T/T')`` law returns (K over B: ``s ∝ T^{−0.93}``
    from 20 to 40 min, ``T^{−0.55}`` from 160 to 320 min). The octave grid gains
    a point each time ``N'/4`` passes a power of two, so the predictions move
    in steps there, as the analysis will.

    *Terms not resolved.* For a term known only to be below ``X`` (or assumed at
    ``X``) the curve is rebuilt with ``c = X²`` and the fit of the kept terms and
    this one evaluated on it at growing ``T'``. ``analyze`` keeps a term when
    ``c/σ_c ≥ 3`` or when the curve needs it (its removal sends χ² beyond its
    10⁻⁴ tail), and K and R trade places at the end of the record, so the
    expected significance at which half of the records resolve a term, ``z₅₀``,
    was measured: 3.1 for Q, 2.3 for B, 1.7 for K (``sigmatau.imu.forecast``). The term is
    predicted resolved at the first ``T'`` with ``X²/σ_c(T') ≥ z₅₀`` — a median:
    between a quarter and three quarters of the records resolve it, the lengths
    differ by about a factor of two. At the bound, ``X²/σ_c`` is about
    ``z_{(1+p)/2}`` (≈ 1) now, and a true value below it needs longer. After
    that its precision is that of the interval ``analyze`` will print, which is
    conditional on the selection keeping the term: ``h(z_p·s_model(T'))`` far
    above the detection limit, wider near it (the truncated normal's interval
    in the median record that keeps the term, with the edge at ``z₅₀·σ_c``;
    ``sigmatau.imu.forecast._h_printed``). No
    prediction is made for a term without a finite bound (Q under a low-pass
    filter), none beyond ``max_duration``; with a discrepancy floor ε the
    precision levels off at that of ``2/ν → 0`` and a target below it is
    reported out of reach.

    References
    ----------
    C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances based on
    finite differences", Proc. 35th PTTI (2003); W. J. Riley, *Handbook of
    Frequency Stability Analysis*, NIST SP 1065 (2008), §5.3 (EDF of OAVAR) and
    Table 7; IEEE Std 952-1997 Annex C (the noise terms and their slopes).

    Examples
    --------
    >>> import warnings
    >>> from sigmatau.imu import simulate, analyze, recording_advice, ImuWarning
    >>> y = simulate(duration=1200.0, rate=100.0, N=1e-3, B=2.75e-4, rng=2)
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", ImuWarning)
    ...     model = analyze(y, rate=100.0, unit="rad/s", checks=False)
    >>> advice = recording_advice(model, target=0.10)
    >>> advice["N"].status, advice["B"].status, advice["K"].status
    ('known', 'resolved', 'not resolved')
    >>> 0.5 < advice["B"].extra_time / 3600 < 3     # about an hour more for ±10 % on B
    True
    """
    dur, tgt, conf, horizon, assumed = _recording_advice_iv(model, duration, target, confidence, assume,
                                                            max_duration)
    plan = _Plan.of(model, dur, assumed)
    z_now, z_p = _z(model.confidence), _z(conf)
    advice, anchors = [], {}
    for term, p in model.parameters().items():
        if p.method == "excluded":
            continue
        if p.resolved:
            anchor = _resolved_anchor(plan, term, p, z_now, z_p)
            adv = _resolved_advice(anchor, term, p, tgt, conf, horizon, dur)
        else:
            value = assumed.get(term, p.high)
            anchor = _unresolved_anchor(plan, term, value, z_p)
            adv = _unresolved_advice(anchor, term, p, value, tgt, conf, horizon, dur, model.filter_time)
        if anchor is not None:
            anchors[term] = anchor
        advice.append(adv)
    return RecordingAdvice(dur, model.rate, model.kind, conf, tgt, horizon, model.discrepancy, tuple(advice),
                           plan, anchors)


# ----------------------------------------------------------------------------- checks
def _recording_advice_iv(model: Any, duration: Any, target: Any, confidence: Any, assume: Any, max_duration: Any
                         ) -> tuple[float, float, float, float, dict[str, float]]:
    """The arguments of :func:`recording_advice`, checked: ``(duration, target, confidence,
    max_duration, assumed)`` with the defaults filled in."""
    _check_model(model)
    dur = model.duration if duration is None else _positive(duration, "duration")
    tgt = _fraction(target, "target")
    conf = model.confidence if confidence is None else _fraction(confidence, "confidence")
    horizon = HORIZON * dur if max_duration is None else _positive(max_duration, "max_duration")
    if horizon <= dur:
        raise ParameterError(f"max_duration={max_duration!r} must exceed duration={dur!r} s")
    return dur, tgt, conf, horizon, _check_assume(model, assume)


def _check_model(model: Any) -> None:
    """A :class:`NoiseModel` with at least one resolved term (else nothing anchors a prediction)."""
    if not isinstance(model, NoiseModel):
        raise ParameterError(f"model must be a NoiseModel from sigmatau.imu.analyze, got {type(model).__name__}")
    if not model.resolved:
        raise ParameterError("the model resolves no term (fit terms: none): there is no curve to predict from;"
                             " record longer or check the data")


def _positive(value: Any, name: str) -> float:
    """``value`` as a positive finite float, else a :class:`ParameterError` naming ``name``."""
    if isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name}={value!r} must be a positive number")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={value!r} must be a positive number") from None
    if not (math.isfinite(v) and v > 0):
        raise ParameterError(f"{name}={value!r} must be a positive finite number")
    return v


def _fraction(value: Any, name: str) -> float:
    """``value`` as a float strictly between 0 and 1, else a :class:`ParameterError`."""
    if isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name}={value!r} must be a number in (0, 1)")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={value!r} must be a number in (0, 1)") from None
    if not 0.0 < v < 1.0:
        raise ParameterError(f"{name}={value!r} must be in (0, 1) (0.10 is ±10 %)")
    return v


def _check_assume(model: NoiseModel, assume: Optional[Mapping[str, float]]) -> dict[str, float]:
    """The assumed values, each for a term of the model that it does not resolve."""
    if assume is None:
        return {}
    if not isinstance(assume, Mapping):
        raise ParameterError(f"assume={assume!r} must be a mapping of term to value")
    out = {}
    for term, value in assume.items():
        if term not in TERMS or getattr(model, term).method == "excluded":
            raise ParameterError(f"assume: {term!r} is not a term of the model")
        if getattr(model, term).resolved:
            raise ParameterError(f"assume: {term} is resolved; assume= is for terms the record does not resolve")
        out[term] = _positive(value, f"assume[{term!r}]")
    return out


def _z(confidence: float) -> float:
    """Normal quantile of a two-sided ``confidence`` (the fit's intervals are ĉ ± zσ_c)."""
    return float(ndtri(0.5 + confidence / 2.0))


# ----------------------------------------------------------------------------- one term
def _resolved_anchor(plan: _Plan, term: str, p: Any, z_now: float, z_p: float) -> Optional[_Anchor]:
    """The prediction of a resolved term: its σ̂_c/c now, scaled by the fit's forecast."""
    j = TERMS.index(term)
    s_model = plan.rel_sd(plan.n_now)[j]
    s = plan.s_data[j]
    if not (math.isfinite(s_model) and math.isfinite(s) and s > 0):
        return None
    # The reported precision is the interval's; at another confidence, the same σ_c at z_p.
    h_now = (p.high - p.low) / (2.0 * p.value) if z_p == z_now else _h(z_p * s)
    return _Anchor(plan, j, plan.coef, z_p, s, h_now, s_model, True)


def _unresolved_anchor(plan: _Plan, term: str, value: float, z_p: float) -> Optional[_Anchor]:
    """The prediction of a term not resolved, put into the curve at ``value`` (None without a bound)."""
    if not math.isfinite(value):
        return None
    j = TERMS.index(term)
    coef = plan.coef.copy()
    coef[j] = value**2
    s_model = plan.rel_sd(plan.n_now, coef)[j]
    if not math.isfinite(s_model):
        return None
    # No measurement to anchor on: the model's own σ_c/c, in the interval analyze would print.
    return _Anchor(plan, j, coef, z_p, s_model, _h_printed(j, z_p, s_model), s_model, False)


def _resolved_advice(anchor: Optional[_Anchor], term: str, p: Any, target: float, conf: float, horizon: float,
                     dur: float) -> TermAdvice:
    """Known or resolved, and the record length at which the precision reaches the target."""
    h_now = anchor.h_now if anchor is not None else (p.high - p.low) / (2.0 * p.value)
    common = dict(term=term, value=p.value, bound=math.nan, unit=p.unit, precision=h_now, target=target,
                  confidence=conf, assumed=math.nan, detect_time=0.0)
    if h_now <= target:
        return TermAdvice(status="known", extra_time=0.0, basis="known to the target now", **common)
    if anchor is None:
        return TermAdvice(status="resolved", extra_time=math.nan,
                          basis="no prediction: the fitted curve gives this term no uncertainty", **common)
    t_goal = _first_time(lambda t: anchor.precision(t) - target, dur, horizon)
    return TermAdvice(status="resolved", extra_time=t_goal - dur,
                      basis=_basis(t_goal, horizon, anchor, "the interval now, scaled by the fit's expected"
                                   " covariance for a longer record"), **common)


def _unresolved_advice(anchor: Optional[_Anchor], term: str, p: Any, value: float, target: float, conf: float,
                       horizon: float, dur: float, filter_time: float) -> TermAdvice:
    """Not resolved: when a term of ``value`` would be, and when it would reach the target."""
    common = dict(term=term, status="not resolved", value=math.nan, bound=p.high, unit=p.unit,
                  precision=math.nan, target=target, confidence=conf)
    if anchor is None:
        why = ("no prediction possible: quantisation is masked by the sensor's low-pass filter"
               if term == "Q" and filter_time > 0 else "no prediction possible without a finite bound")
        return TermAdvice(assumed=math.nan, detect_time=math.nan, extra_time=math.nan, basis=why, **common)
    t_det = _first_time(lambda t: 1.0 - anchor.detection(t), dur, horizon)
    t_goal = t_det
    if math.isfinite(t_det) and anchor.precision(t_det) > target:
        t_goal = _first_time(lambda t: anchor.precision(t) - target, t_det, horizon)
    basis = _basis(t_goal if math.isfinite(t_det) else t_det, horizon, anchor,
                   f"the fit's expected covariance with {term} = {value:.3g} added to the curve")
    return TermAdvice(assumed=value, detect_time=t_det - dur, extra_time=t_goal - dur, basis=basis, **common)


def _basis(t_goal: float, horizon: float, anchor: _Anchor, how: str) -> str:
    """The rule followed, or why the target is out of reach."""
    if math.isfinite(t_goal):
        return f"predicted from {how}"
    factor = horizon / (anchor.plan.n_now / anchor.plan.rate)
    floor = ""
    if anchor.plan.eps > 0:
        floor = (f"; the model discrepancy floor ({100 * anchor.plan.eps:.2g} % per τ) does not shrink with"
                 " the record")
    return f"within {_format_time(horizon)} ({_two_digits(factor)}× the record so far){floor}"


def _detection_clause(waiting: list[TermAdvice]) -> list[str]:
    """``at their bounds, Q would show after ≈ 14 min more, B and K would already show`` ([] if none)."""
    if not waiting:
        return []
    later = [f"{t.term} would show after ≈ {_format_time(t.detect_time)} more" for t in waiting if t.detect_time > 0]
    now = [t.term for t in waiting if t.detect_time == 0]
    if now:
        later.append(f"{_and_join(now)} would already show")
    if all(t.assumed == t.bound for t in waiting):
        where = "at its bound" if len(waiting) == 1 else "at their bounds"
    else:
        where = "at the values assumed (or bounds)"
    return [f"{where}, {', '.join(later)}"]


def _and_join(names: list[str]) -> str:
    """``Q``, ``Q and K``, ``Q, K and R``."""
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def _time_clause(extra: float, tgt: str, basis: str) -> str:
    """``record ≈ … more for ±10 %`` or why not."""
    if math.isnan(extra):
        return basis
    if math.isinf(extra):
        return f"{tgt} is not reached {basis}"
    return f"record ≈ {_format_time(extra)} more for {tgt}"


# ----------------------------------------------------------------------------- small helpers
def _pct(fraction: float) -> str:
    """A fraction as a percentage with two significant digits (``0.0039`` → ``0.39``)."""
    p = 100.0 * fraction
    return f"{p:.0f}" if p >= 10 else f"{p:.2g}"


def _format_time(seconds: float) -> str:
    """A duration to two significant digits in s, min, h or days (``inf`` → ``never``)."""
    if not math.isfinite(seconds):
        return "never"
    for unit, size, limit in (("s", 1.0, 90.0), ("min", 60.0, 5400.0), ("h", 3600.0, 172800.0)):
        if seconds < limit:
            return f"{_two_digits(seconds / size)} {unit}"
    return f"{_two_digits(seconds / 86400.0)} days"


def _two_digits(x: float) -> str:
    """Two significant digits, without an exponent above 10 (``417``, ``8.6``, ``0.42``)."""
    return f"{x:.0f}" if x >= 10 else f"{x:.2g}"
