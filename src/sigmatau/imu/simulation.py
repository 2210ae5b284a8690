"""Simulate one IMU channel from the five-term noise model (plus Gauss–Markov).

:func:`simulate` is a composition of small steps: resolve the preset, the output
unit, rate and length, the coefficients in that unit, then add each term's
noise (``_five_terms``), an optional Gauss–Markov process, the deterministic
environment (a warm-up transient, a temperature-dependent bias:
``_add_environment``) and quantisation. The order in which the random generator
is drawn from is that of the original single function, so a seed gives the same
samples; the environment draws nothing from it, and without its options the
output is unchanged bit for bit. :func:`temperature_profile` makes the
temperature records (ramp, cycle) that ``simulate(temperature=...)`` takes.
"""

from __future__ import annotations

import math
from typing import Any, Callable, Literal, Optional, Sequence, Union

import numpy as np

from ..core.validate import check_rate
from ..errors import ParameterError
from ..noise.generate import octave_flicker, power_law_noise
from .presets import PRESETS, Preset
from .terms import _level
from .units import TERMS, SensorUnit, convert, sensor_unit, term_unit

__all__ = ["simulate", "temperature_profile"]


def simulate(
    preset: Optional[Union[str, Preset]] = None,
    *,
    duration: float,
    rate: Optional[float] = None,
    unit: Optional[str] = None,
    Q: Optional[float] = None,
    N: Optional[float] = None,
    B: Optional[float] = None,
    K: Optional[float] = None,
    R: Optional[float] = None,
    gauss_markov: Optional[tuple[float, float]] = None,
    bias: float = 0.0,
    lsb: Optional[float] = None,
    flicker: Literal["kasdin", "tip"] = "kasdin",
    rng: Any = None,
    warmup: Optional[tuple[float, float]] = None,
    temperature: Union[None, Sequence[float], np.ndarray, Callable[[np.ndarray], Any]] = None,
    tempco: Union[None, float, Sequence[float]] = None,
) -> np.ndarray:
    """Simulate one IMU channel from the five-term model (plus Gauss–Markov).

    Parameters
    ----------
    preset : str or Preset, optional
        Starting values: a key of :data:`PRESETS` (``"lsm6dsl-gyro"``,
        ``"lsm6dsm-accel"``, ``"adis16448-gyro"``, ``"euroc-gyro"``,
        ``"euroc-accel"`` …) or a :class:`Preset`. Coefficients given as
        keywords replace the preset's.
    duration : float
        Record length in seconds; ``round(duration·rate)`` samples.
    rate : float, optional
        Sample rate in Hz (default: the preset's).
    unit : str, optional
        Unit of the returned samples (default: the preset's SI unit, else
        ``"rad/s"``). The keyword coefficients are in this unit per √Hz etc.:
        Q in unit·s, N in unit/√Hz, B in unit, K in unit/s/√Hz, R in unit/s.
    Q, N, B, K, R : float, optional
        Quantisation, white noise, bias instability, random walk, rate ramp.
    gauss_markov : (sigma, tau_c), optional
        First-order Gauss–Markov term of stationary σ (unit) and correlation
        time τ_c (s).
    bias : float
        Constant offset added to the samples.
    lsb : float, optional
        Round the output to this step (a quantised sensor).
    flicker : {"kasdin", "tip"}
        Generator of the bias-instability term: Kasdin–Walter (exact level)
        or the design tip's octave sum.
    rng : None, int, SeedSequence or numpy.random.Generator
        Source of randomness.
    warmup : (amplitude, time_constant), optional
        A warm-up transient ``A·exp(−t/T)`` added to the samples: A in the
        output unit, T in seconds (> 0), ``t_i = i/rate`` from power-on.
    temperature : array_like or callable, optional
        The sensor's temperature (°C or K, only differences matter) at each
        sample: an array of ``round(duration·rate)`` values (see
        :func:`temperature_profile`) or a function of the time array
        ``t_i = i/rate`` (s) returning them. Without ``tempco`` it has no effect.
    tempco : float or sequence of float, optional
        Temperature sensitivity of the bias: ``c1`` (output unit per kelvin)
        adds ``c1·(T − T̄)``; a sequence ``(c1, c2, …)`` adds the polynomial
        ``Σ_k c_k·(T − T̄)^k`` (unit/K^k). ``T̄`` is the mean of the profile, so
        the bias at the mean temperature stays ``bias``. Needs ``temperature``.

    Returns
    -------
    numpy.ndarray
        The samples.

    Notes
    -----
    Each term is generated so that its expected overlapping Allan variance is
    the model's: N as white samples of σ = N·√f (``h₀ = 2N²``); K as a random
    walk with steps of σ = K/√f (``h₋₂ = K²/(2π²)``; exactly
    ``K²(τ/3 + τ0²/(6τ))`` for point samples); B as flicker frequency noise
    with ``h₋₁ = B²/π`` (plateau ``2 ln 2·h₋₁ = (2 ln 2/π)B²``); Q as white
    angle noise of σ = Q differenced (AVAR exactly ``3Q²/τ²``); R as the ramp
    ``R·(t − T/2)``; Gauss–Markov by the exact AR(1) recursion
    ``x_k = φx_{k−1} + σ√(1−φ²)w_k``, ``φ = e^{−τ0/τ_c}``, started stationary.
    The environment is deterministic and added before quantisation:
    ``A·e^{−t/T} + Σ_k c_k (T(t) − T̄)^k``.

    Examples
    --------
    >>> from sigmatau.imu import simulate
    >>> y = simulate("euroc-gyro", duration=60.0, rng=1)
    >>> y.size
    12000
    >>> y = simulate(duration=10.0, rate=100.0, unit="deg/s", N=0.004, B=0.001, rng=2)
    >>> y.size
    1000
    >>> temp = temperature_profile(600.0, 10.0, "ramp", low=20.0, high=40.0)
    >>> y = simulate(duration=600.0, rate=10.0, N=0.01, warmup=(0.5, 30.0),
    ...              temperature=temp, tempco=0.002, rng=3)
    >>> y.size == temp.size
    True
    """
    pre = _resolve_preset(preset)
    su, rate_f, n = _unit_rate_and_length(pre, unit, rate, duration)
    coef = _coefficients(pre, su, (Q, N, B, K, R))
    if flicker not in ("kasdin", "tip"):
        raise ParameterError(f"flicker={flicker!r} must be 'kasdin' or 'tip'")
    gen = np.random.default_rng(rng)
    y = _five_terms(coef, n, rate_f, bias, flicker, gen)
    if gauss_markov is not None:
        _add_gauss_markov(y, gauss_markov, rate_f, gen)
    if warmup is not None or temperature is not None or tempco is not None:
        _add_environment(y, rate_f, warmup, temperature, tempco)
    if lsb is not None:
        step = _level(lsb, "lsb")
        if step > 0:
            y = step * np.round(y / step)
    return y


def _resolve_preset(preset: Optional[Union[str, Preset]]) -> Optional[Preset]:
    """The :class:`Preset` named or given, None without one; :class:`ParameterError` otherwise."""
    if preset is None:
        return None
    if isinstance(preset, str):
        if preset not in PRESETS:
            raise ParameterError(f"preset={preset!r} must be one of {sorted(PRESETS)}")
        return PRESETS[preset]
    if isinstance(preset, Preset):
        return preset
    raise ParameterError(f"preset={preset!r} must be a preset name or a Preset")


def _unit_rate_and_length(pre: Optional[Preset], unit: Optional[str], rate: Optional[float],
                          duration: float) -> tuple[SensorUnit, float, int]:
    """Output unit (checked against the preset's sensor kind), sample rate and number of samples.

    Parameters
    ----------
    pre : Preset or None
    unit, rate : as in :func:`simulate` (None: the preset's)
    duration : float
        Record length (s).

    Returns
    -------
    su : SensorUnit
    rate : float
    n : int
        ``round(duration·rate)``, at least 2.
    """
    out_unit = unit if unit is not None else (pre.unit if pre is not None else "rad/s")
    su = sensor_unit(out_unit)
    if pre is not None and su.kind != pre.kind:
        raise ParameterError(f"unit={out_unit!r} is a {su.kind} unit but preset {pre.name!r} is a {pre.kind}")
    if rate is None:
        if pre is None:
            raise ParameterError("rate is required without a preset")
        rate = pre.rate
    rate_f = check_rate(rate)
    dur = _level(duration, "duration")
    n = int(round(dur * rate_f))
    if n < 2:
        raise ParameterError(f"duration={duration!r} at rate={rate_f:g} Hz gives {n} samples; need at least 2")
    return su, rate_f, n


def _coefficients(pre: Optional[Preset], su: SensorUnit, given: tuple[Optional[float], ...]) -> dict[str, float]:
    """Q, N, B, K, R in the output unit: the keyword value when given, else the preset's
    (converted from SI), else 0."""
    coef = {}
    for t, value in zip(TERMS, given):
        if value is not None:
            coef[t] = _level(value, t)
        elif pre is not None:
            coef[t] = float(convert(getattr(pre, t), term_unit(pre.unit, t), su.term_unit(t)))
        else:
            coef[t] = 0.0
    return coef


def _five_terms(coef: dict[str, float], n: int, rate_f: float, bias: float, flicker: str,
                gen: np.random.Generator) -> np.ndarray:
    """``bias`` plus the noise of each non-zero term (see :func:`simulate`, Notes).

    The terms draw from ``gen`` in the order N, Q, B, K (R is deterministic),
    so a seed gives the same samples as before the split.
    """
    tau0 = 1.0 / rate_f
    y = np.full(n, float(bias))
    if coef["N"] > 0:
        y += coef["N"] * math.sqrt(rate_f) * gen.standard_normal(n)
    if coef["Q"] > 0:
        y += np.diff(coef["Q"] * gen.standard_normal(n + 1)) * rate_f
    if coef["B"] > 0:
        h = coef["B"] ** 2 / math.pi
        if flicker == "kasdin":
            y += power_law_noise(n, -1, h=h, rate=rate_f, rng=gen)
        else:
            rows = int(n).bit_length() + 4
            y += octave_flicker(n, sigma=math.sqrt(h * math.log(2.0)), rows=rows, rng=gen)
    if coef["K"] > 0:
        y += np.cumsum(coef["K"] * math.sqrt(tau0) * gen.standard_normal(n))
    if coef["R"] > 0:
        y += coef["R"] * (np.arange(n) * tau0 - 0.5 * (n - 1) * tau0)
    return y


def _add_gauss_markov(y: np.ndarray, gauss_markov: Any, rate_f: float, gen: np.random.Generator) -> None:
    """Add, in place, a stationary first-order Gauss–Markov process ``(sigma, tau_c)`` to ``y``.

    The exact AR(1) recursion ``x_k = φx_{k−1} + σ√(1−φ²)w_k``, ``φ = e^{−τ0/τ_c}``,
    started from its stationary distribution (``x_0 = σw_0``).
    """
    try:
        sigma, tau_c = (float(v) for v in gauss_markov)
    except (TypeError, ValueError):
        raise ParameterError(f"gauss_markov={gauss_markov!r} must be (sigma, tau_c)") from None
    if not (sigma >= 0 and tau_c > 0 and math.isfinite(sigma) and math.isfinite(tau_c)):
        raise ParameterError(f"gauss_markov={gauss_markov!r} needs sigma >= 0 and tau_c > 0")
    if sigma > 0:
        from scipy.signal import lfilter  # imported here: keeps `import sigmatau` light

        tau0 = 1.0 / rate_f
        phi = math.exp(-tau0 / tau_c)
        w = gen.standard_normal(y.size) * sigma * math.sqrt(1.0 - phi * phi)
        w[0] = sigma * gen.standard_normal()
        y += lfilter([1.0], [1.0, -phi], w)


def _add_environment(y: np.ndarray, rate_f: float, warmup: Any, temperature: Any, tempco: Any) -> None:
    """Add, in place, the warm-up transient and the temperature-dependent bias (see :func:`simulate`)."""
    t = np.arange(y.size) / rate_f
    if warmup is not None:
        try:
            amplitude, time_constant = (float(v) for v in warmup)
        except (TypeError, ValueError):
            raise ParameterError(f"warmup={warmup!r} must be (amplitude, time_constant)") from None
        if not (math.isfinite(amplitude) and math.isfinite(time_constant) and time_constant > 0):
            raise ParameterError(f"warmup={warmup!r} needs a finite amplitude and time_constant > 0 (s)")
        y += amplitude * np.exp(-t / time_constant)
    if tempco is None:
        if temperature is not None:
            _temperature_at(temperature, t)  # checked even when it has no effect
        return
    if temperature is None:
        raise ParameterError("tempco needs temperature= (an array or a function of time)")
    coeffs = np.atleast_1d(np.asarray(tempco, dtype=np.float64)) if not isinstance(tempco, str) else None
    if coeffs is None or coeffs.ndim != 1 or coeffs.size == 0 or not np.isfinite(coeffs).all():
        raise ParameterError(f"tempco={tempco!r} must be a finite number or a sequence (c1, c2, ...)")
    dt = _temperature_at(temperature, t)
    dt = dt - dt.mean()
    for k, c in enumerate(coeffs, start=1):
        y += c * dt ** k


def _temperature_at(temperature: Any, t: np.ndarray) -> np.ndarray:
    """The temperature at each sample time: the array given, or the function evaluated on ``t``."""
    values = temperature(t) if callable(temperature) else temperature
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError("temperature must be numeric (an array or a function of time returning one)") from None
    if arr.ndim == 0:
        arr = np.full(t.size, float(arr))
    if arr.shape != t.shape:
        raise ParameterError(f"temperature has shape {arr.shape}; the record has {t.size} samples")
    if not np.isfinite(arr).all():
        raise ParameterError("temperature must be finite at every sample (simulate a gap in the samples instead)")
    return arr


def temperature_profile(duration: float, rate: float, kind: Literal["ramp", "cycle"] = "ramp", *,
                        low: float = 20.0, high: float = 40.0, period: Optional[float] = None) -> np.ndarray:
    """A temperature record for :func:`simulate` (``temperature=``) and for a temperature column.

    Parameters
    ----------
    duration : float
        Record length in seconds; ``round(duration·rate)`` samples, as in :func:`simulate`.
    rate : float
        Sample rate in Hz.
    kind : {"ramp", "cycle"}
        ``"ramp"``: linear from ``low`` to ``high`` over the record,
        ``T(t) = low + (high − low)·t/t_last``. ``"cycle"``: a raised cosine starting at
        ``low``, ``T(t) = low + (high − low)·(1 − cos(2πt/period))/2``.
    low, high : float
        The temperature range (°C).
    period : float, optional
        The cycle's period in seconds (default: the record length, one cycle).

    Returns
    -------
    numpy.ndarray
        The temperature at ``t_i = i/rate``.

    Notes
    -----
    A ramp is the thermal-ramp test of IEEE Std 952-1997 (bias temperature sensitivity from
    a slow, monotonic temperature change); a cycle separates a temperature dependence from a
    drift in time, which a single ramp cannot.

    Examples
    --------
    >>> temperature_profile(4.0, 1.0, "ramp", low=20.0, high=26.0).tolist()
    [20.0, 22.0, 24.0, 26.0]
    """
    rate_f = check_rate(rate)
    n = int(round(_level(duration, "duration") * rate_f))
    if n < 2:
        raise ParameterError(f"duration={duration!r} at rate={rate_f:g} Hz gives {n} samples; need at least 2")
    if kind not in ("ramp", "cycle"):
        raise ParameterError(f"kind={kind!r} must be 'ramp' or 'cycle'")
    lo, hi = float(low), float(high)
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ParameterError(f"low={low!r} and high={high!r} must be finite temperatures")
    t = np.arange(n) / rate_f
    if kind == "ramp":
        return lo + (hi - lo) * t / t[-1]
    per = float(duration) if period is None else float(period)
    if not (math.isfinite(per) and per > 0):
        raise ParameterError(f"period={period!r} must be a positive number of seconds")
    return lo + (hi - lo) * 0.5 * (1.0 - np.cos(2.0 * math.pi * t / per))
