"""Result types shared by every stage (statistics, uncertainty, noise identification)."""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, fields
from typing import Any, Optional

import numpy as np

from .present import data_frame, html_table, noise_name, plot

__all__ = ["StabilityResult", "json_ready"]

_ARRAY_FIELDS = (
    "taus", "m", "var", "dev", "n", "bias_factor",
    "alpha", "alpha_estimate", "edf", "ci_low", "ci_high", "n_effective",
)


@dataclass(frozen=True, repr=False, eq=False)
class StabilityResult:
    """One statistic evaluated over a grid of averaging times.

    Attributes
    ----------
    statistic : str
        Name of the statistic (``"oadev"``, ``"mtotdev"`` …).
    taus : numpy.ndarray
        Averaging times τ in seconds (0.75·m·τ0 for Theo1/TheoBR).
    m : numpy.ndarray
        Averaging factors.
    var, dev : numpy.ndarray
        The variance and the deviation ``sqrt(var)``. For TDEV/TTOT they are in
        the phase unit (seconds for clocks); for MTIE/TIE rms ``dev`` is the time
        error and ``var = dev**2``.
    n : numpy.ndarray
        Number of terms summed by the estimator at each τ.
    rate : float
        Sample rate in Hz (τ0 = 1/rate).
    data_type : {"freq", "phase"}
        Kind of the input data.
    n_points : int
        Number of phase points N behind the estimate (frequency samples + 1).
    bias : str
        Bias correction applied to ``var``: ``"none"`` or a description such as
        ``"stable32 alpha=0"``.
    bias_factor : numpy.ndarray or None
        Divisor applied to the raw variance at each τ (1 where none).
    alpha, alpha_estimate, edf, ci_low, ci_high, confidence, ci_reason
        Noise type (integer and fractional), equivalent degrees of freedom and
        the deviation interval at ``confidence``; ``None`` until filled.
    n_missing : int
        Samples of the input that were missing (NaN gaps, :mod:`sigmatau.core.gaps`);
        ``n`` then counts only the terms whose samples are all present.
    n_effective : numpy.ndarray or None
        With gaps: at each τ, the phase points of a contiguous record that gives
        ``n`` terms; the EDF is computed for it. None without gaps (``n_points``).
    """

    statistic: str
    taus: np.ndarray
    m: np.ndarray
    var: np.ndarray
    dev: np.ndarray
    n: np.ndarray
    rate: float
    data_type: str
    n_points: int
    bias: str = "none"
    bias_factor: Optional[np.ndarray] = None
    alpha: Optional[np.ndarray] = None
    alpha_estimate: Optional[np.ndarray] = None
    edf: Optional[np.ndarray] = None
    ci_low: Optional[np.ndarray] = None
    ci_high: Optional[np.ndarray] = None
    confidence: Optional[float] = None
    ci_reason: Optional[tuple[str, ...]] = None
    n_missing: int = 0
    n_effective: Optional[np.ndarray] = None

    def __post_init__(self) -> None:
        for name in _ARRAY_FIELDS:
            value = getattr(self, name)
            if value is not None:
                arr = np.array(value, copy=True)
                arr.setflags(write=False)
                object.__setattr__(self, name, arr)

    def __len__(self) -> int:
        return int(self.taus.size)

    def columns(self) -> list[str]:
        """Names of the per-τ columns present in this result, in table order."""
        cols = ["m", "taus", "n"]
        if self.alpha is not None:
            cols.append("alpha")
        if self.ci_low is not None:
            cols.append("ci_low")
        cols.append("dev")
        if self.ci_high is not None:
            cols.append("ci_high")
        if self.edf is not None:
            cols.append("edf")
        return cols

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python dictionary of every field (arrays as lists), JSON-ready."""
        out: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, np.ndarray):
                value = value.tolist()
            elif isinstance(value, tuple):
                value = list(value)
            out[f.name] = value
        return out

    def to_table(self) -> str:
        """Fixed-width text table, one row per τ (the layout of a Stable32 run)."""
        cols = self.columns()
        head = {"m": "m", "taus": "tau [s]", "n": "n", "alpha": "alpha",
                "ci_low": "min dev", "dev": "dev", "ci_high": "max dev", "edf": "edf"}
        rows = [[head[c] for c in cols]]
        for i in range(len(self)):
            row = []
            for c in cols:
                v = float(getattr(self, c)[i])
                if not np.isfinite(v):
                    row.append("-")
                elif c in ("m", "n", "alpha"):
                    row.append(str(int(v)))
                else:
                    row.append(f"{v:.2f}" if c == "edf" else f"{v:.6e}")
            rows.append(row)
        widths = [max(len(r[j]) for r in rows) for j in range(len(cols))]
        lines = ["  ".join(cell.rjust(w) for cell, w in zip(r, widths)) for r in rows]
        return "\n".join([self._title(), *lines])

    def _title(self) -> str:
        """The statistic, data type, rate, N, missing samples, bias and confidence in one line."""
        title = f"{self.statistic}  ({self.data_type} data, rate {self.rate:g} Hz, N = {self.n_points} phase points"
        if self.n_missing:
            title += f", {self.n_missing} samples missing"
        title += f", bias: {self.bias}"
        if self.confidence is not None:
            title += f", {100 * self.confidence:.1f} % interval"
        return title + ")"

    def _column(self, name: str) -> list[Any]:
        """A per-τ column as Python values, NaN where the field is absent."""
        value = getattr(self, name)
        return [float("nan")] * len(self) if value is None else value.tolist()

    def _repr_html_(self) -> str:
        """The table of :meth:`to_table` as HTML, for notebooks."""
        rows = zip(self.taus.tolist(), self.m.tolist(), self.n.tolist(), self._column("alpha"),
                   [noise_name(a) for a in self._column("alpha")], self._column("ci_low"), self.dev.tolist(),
                   self._column("ci_high"), self._column("edf"))
        return html_table(["τ [s]", "m", "n", "α", "noise", "min dev", "dev", "max dev", "EDF"], rows,
                          caption=self._title())

    def to_pandas(self) -> Any:
        """A pandas DataFrame, one row per τ (tidy: a ``statistic`` column, so results concatenate).

        Columns ``statistic``, ``tau_s``, ``m``, ``n``, ``alpha``, ``noise`` (WPM … RRFM),
        ``dev``, ``dev_low``, ``dev_high``, ``edf`` and ``var``; NaN where a value is
        absent. ``frame.attrs`` holds ``rate_hz``, ``data_type``, ``n_points``, ``n_missing``,
        ``bias`` and ``confidence``. Needs pandas (extra ``pandas``).

        Examples
        --------
        >>> import numpy as np, sigmatau
        >>> r = sigmatau.oadev(np.random.default_rng(0).standard_normal(1000), m=[1, 2, 4])
        >>> frame = r.to_pandas()
        >>> list(frame.columns)[:4], frame["m"].tolist()
        (['statistic', 'tau_s', 'm', 'n'], [1, 2, 4])
        """
        alpha = self._column("alpha")
        return data_frame({
            "statistic": [self.statistic] * len(self), "tau_s": self.taus.tolist(), "m": self.m.tolist(),
            "n": self.n.tolist(), "alpha": alpha, "noise": [noise_name(a) for a in alpha],
            "dev": self.dev.tolist(), "dev_low": self._column("ci_low"), "dev_high": self._column("ci_high"),
            "edf": self._column("edf"), "var": self.var.tolist(),
        }, attrs={"rate_hz": self.rate, "data_type": self.data_type, "n_points": self.n_points,
                  "n_missing": self.n_missing, "bias": self.bias, "confidence": self.confidence})

    def plot(self, ax: Any = None, **kw: Any) -> Any:
        """Draw σ(τ) with its interval band on log–log axes (matplotlib, extra ``plot``).

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure's when None.
        **kw
            ``label`` (default the statistic's name), ``color``, ``unit`` (for the y label),
            ``band`` (draw the interval, default True) and other keywords of ``Axes.plot``.

        Returns
        -------
        matplotlib.axes.Axes
        """
        return plot("stability", self, ax=ax, **kw)

    def to_csv(self) -> str:
        """CSV text with a header row and one row per τ."""
        cols = self.columns()
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerow(cols)
        for i in range(len(self)):
            writer.writerow([repr(getattr(self, c)[i].item()) for c in cols])
        return buf.getvalue()

    def __repr__(self) -> str:
        if len(self) == 0:
            return f"StabilityResult({self.statistic}, empty)"
        return (
            f"StabilityResult({self.statistic}, {len(self)} τ from {self.taus[0]:.4g} s to"
            f" {self.taus[-1]:.4g} s, dev {self.dev[0]:.4g} … {self.dev[-1]:.4g},"
            f" {self.data_type} data at {self.rate:g} Hz)"
        )

    def __str__(self) -> str:
        return self.to_table()


def json_ready(obj: Any) -> Any:
    """``obj`` with numpy scalars/arrays as Python values and NaN/inf as None (strict JSON).

    >>> json_ready({"a": np.float64("nan"), "b": np.arange(2), "c": (1.5, float("inf"))})
    {'a': None, 'b': [0, 1], 'c': [1.5, None]}
    """
    if isinstance(obj, dict):
        return {str(k): json_ready(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_ready(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_ready(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if obj is None or isinstance(obj, str):
        return obj
    return str(obj)
