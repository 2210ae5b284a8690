"""Data preparation: the steps applied to a record before its statistics (Stable32's editing set).

Each step is a pure function: it takes a 1-D series (NaN marks a missing sample, a gap, as in
Stable32; every step tolerates gaps) and keyword-only options, never modifies its input, and
returns a :class:`PrepResult` — the corrected series as a new array plus a record of what was
done (step, parameters, estimates with standard errors, indices affected) whose ``to_dict()``
is JSON-safe for results.json.

* :func:`frequency_offset` — remove the mean frequency (phase: the linear phase slope);
* :func:`drift` — estimate and remove frequency drift with Stable32's models (phase:
  quadratic, diff2, 3point, greenhall; frequency: linear, bisection, log, diffusion);
* :func:`outliers` — median-absolute-deviation check, report or replace by gaps;
* :func:`fill` — fill gaps by linear interpolation;
* :func:`part` — keep a sample or time range;
* :func:`average` — decimate by an averaging factor;
* :func:`warmup` — detect the settling of the bias after power-on and cut it off
  (:func:`drop_warmup` cuts a given duration);
* :func:`temperature_fit` — fit the bias against temperature and remove its
  temperature-dependent part.

Layer: beside ``stats`` and ``noise``; it may import ``sigmatau.errors``, ``sigmatau.core``, numpy
and scipy only, and nothing below the entry points imports it except the pipeline and the CLI.
"""

from __future__ import annotations

from ._drift import DRIFT_MODELS, NOMINAL_NOISE, drift
from ._edit import average, fill, gap_runs, part
from ._offset import frequency_offset
from ._outliers import outliers
from ._result import Estimate, PrepResult, PrepWarning
from ._temperature import temperature_fit
from ._warmup import drop_warmup, warmup

__all__ = [
    "PrepResult",
    "Estimate",
    "PrepWarning",
    "frequency_offset",
    "drift",
    "outliers",
    "fill",
    "part",
    "average",
    "warmup",
    "drop_warmup",
    "temperature_fit",
    "gap_runs",
    "DRIFT_MODELS",
    "NOMINAL_NOISE",
]
