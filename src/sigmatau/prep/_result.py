"""What a preparation step returns: the corrected series and the record of what was done."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core.result import json_ready
from ..errors import SigmaTauWarning

__all__ = ["Estimate", "PrepResult", "PrepWarning"]


class PrepWarning(SigmaTauWarning):
    """A preparation step did something the caller should know about (samples left out, a weak fit)."""


@dataclass(frozen=True)
class Estimate:
    """An estimated quantity with its standard uncertainty (one standard error).

    ``stderr`` is NaN when it cannot be estimated; ``unit`` names the unit in words
    (``"data/s"`` is the unit of the data per second).
    """

    value: float
    stderr: float
    unit: str = ""

    def to_dict(self) -> dict[str, Any]:
        """``{"value", "stderr", "unit"}``, JSON-safe."""
        return json_ready({"value": self.value, "stderr": self.stderr, "unit": self.unit})

    def __repr__(self) -> str:
        unit = f" {self.unit}" if self.unit else ""
        return f"{self.value:.6g} ± {self.stderr:.2g}{unit}"


@dataclass(frozen=True)
class PrepResult:
    """The outcome of one preparation step.

    Attributes
    ----------
    step : str
        The step's name (``"drift"``, ``"outliers"``, ...).
    data : numpy.ndarray
        The corrected series: a new, read-only float64 array (NaN marks a gap).
    data_type : str or None
        ``"freq"`` or ``"phase"``: what ``data`` holds; None for the steps that treat both
        alike (fill, part).
    parameters : dict
        The options the step ran with (model, k, factor, ...), as given or resolved.
    estimates : dict of str to Estimate
        What the step estimated, each with its standard error.
    indices : numpy.ndarray
        Indices (into the input) of the samples the step flagged, filled or left out; empty
        when it changes every sample alike (frequency offset, drift) or keeps a range (part,
        whose range is in ``details``).
    details : dict
        Other facts of the run (counts, noise assumption, the part kept, ...).
    notes : tuple of str
        Sentences for a report: what was done and what to keep in mind.
    """

    step: str
    data: np.ndarray
    data_type: str | None
    parameters: dict[str, Any] = field(default_factory=dict)
    estimates: dict[str, Estimate] = field(default_factory=dict)
    indices: np.ndarray = field(default_factory=lambda: np.empty(0, dtype=np.int64))
    details: dict[str, Any] = field(default_factory=dict)
    notes: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """The record without the series, JSON-safe (NaN and ±inf become ``None``).

        >>> from sigmatau.prep import fill
        >>> fill([1.0, float("nan"), 3.0]).to_dict()["indices"]
        [1]
        """
        return json_ready({
            "step": self.step,
            "data_type": self.data_type,
            "n": int(self.data.size),
            "gaps": int(np.count_nonzero(np.isnan(self.data))),
            "parameters": self.parameters,
            "estimates": {k: v.to_dict() for k, v in self.estimates.items()},
            "indices": self.indices,
            "details": self.details,
            "notes": list(self.notes),
        })

    def __repr__(self) -> str:
        est = ", ".join(f"{k}={v!r}" for k, v in self.estimates.items())
        return (f"PrepResult(step={self.step!r}, n={self.data.size}, data_type={self.data_type!r}, "
                f"indices={self.indices.size}{', ' + est if est else ''})")
