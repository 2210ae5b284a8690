"""One Kalibr ``imu.yaml`` entry from the noise models of several axes (:func:`kalibr_config`).

The entry of a single model (:meth:`~sigmatau.imu.NoiseModel.kalibr`) is built
beside the class, in :mod:`sigmatau.imu.noisemodel`; this module combines the
axes by a stated rule.
"""

from __future__ import annotations

import math
from typing import Any, Literal, Sequence

import numpy as np

from ..errors import ParameterError
from .noisemodel import NoiseModel
from .terms import _level, _num

__all__ = ["kalibr_config"]


def kalibr_config(*, gyro: Sequence[NoiseModel], accel: Sequence[NoiseModel],
                  rule: Literal["max", "rms", "mean"] = "max", inflate: float = 1.0,
                  rostopic: str = "/imu0") -> dict[str, Any]:
    """One Kalibr ``imu.yaml`` entry from the models of several axes, with the rule stated.

    Parameters
    ----------
    gyro, accel : sequence of NoiseModel
        One model per axis (usually three each), all at the same rate.
    rule : {"max", "rms", "mean"}
        How the axes are combined: the largest (conservative, default), the
        root mean square, or the mean. An unresolved K enters as its bound.
    inflate : float
        Explicit inflation factor applied to all four values and recorded.
    rostopic : str

    Returns
    -------
    dict
        The four Kalibr values, ``update_rate`` and ``rostopic``, plus
        ``axis_rule``, ``inflation``, ``per_axis`` values, units, which values
        are bounds, and the discrete-time equivalents (labelled).
    """
    if rule not in ("max", "rms", "mean"):
        raise ParameterError(f"rule={rule!r} must be 'max', 'rms' or 'mean'")
    if not gyro or not accel:
        raise ParameterError("give at least one gyro and one accel model")
    for name, models, kind in (("gyro", gyro, "gyro"), ("accel", accel, "accel")):
        for m in models:
            if not isinstance(m, NoiseModel) or m.kind != kind:
                raise ParameterError(f"{name} must hold {kind} NoiseModel objects")
    rates = {m.rate for m in list(gyro) + list(accel)}
    if len(rates) != 1:
        raise ParameterError(f"all models must share one rate, got {sorted(rates)}")
    rate = rates.pop()
    f = _level(inflate, "inflate")
    combine = {"max": np.max, "mean": np.mean, "rms": lambda v: float(np.sqrt(np.mean(np.square(v))))}[rule]
    out: dict[str, Any] = {"rostopic": rostopic, "update_rate": rate}
    per_axis: dict[str, list] = {}
    bounds: list[str] = []
    for models, name in ((accel, "accelerometer"), (gyro, "gyroscope")):
        for term, key in (("N", f"{name}_noise_density"), ("K", f"{name}_random_walk")):
            vals = []
            for m in models:
                p = getattr(m, term).si()
                vals.append(p.value if p.resolved else p.high)
                if not p.resolved:
                    bounds.append(f"{key} (axis {len(vals)})")
            per_axis[key] = [_num(v) for v in vals]
            out[key] = _num(float(combine(np.array(vals))) * f)
    out["axis_rule"] = {"max": "largest of the axes", "rms": "root mean square of the axes",
                        "mean": "mean of the axes"}[rule]
    out["inflation"] = f
    out["per_axis"] = per_axis
    out["bounds_used"] = bounds
    out["units"] = {"accelerometer_noise_density": "m/s^2/sqrt(Hz)", "accelerometer_random_walk": "m/s^3/sqrt(Hz)",
                    "gyroscope_noise_density": "rad/s/sqrt(Hz)", "gyroscope_random_walk": "rad/s^2/sqrt(Hz)"}
    sq = math.sqrt(rate)
    out["discrete"] = {
        "convention": f"discrete-time standard deviations at {rate:g} Hz (not densities)",
        "accelerometer_sigma_d": _num(out["accelerometer_noise_density"] * sq),
        "accelerometer_sigma_bd": _num(out["accelerometer_random_walk"] / sq),
        "gyroscope_sigma_d": _num(out["gyroscope_noise_density"] * sq),
        "gyroscope_sigma_bd": _num(out["gyroscope_random_walk"] / sq),
    }
    return out
