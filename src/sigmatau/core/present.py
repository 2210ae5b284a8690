"""How results present themselves in a notebook: HTML tables, pandas frames and ``plot()``.

Every result type (:class:`~sigmatau.core.result.StabilityResult`, the IMU
``NoiseModel``, the main job's ``ChannelAnalysis`` and ``LogAnalysis``) has a
``_repr_html_`` built with :func:`html_table` (every cell escaped: names come from
the user's files), a ``to_pandas()`` built with :func:`data_frame` (pandas is an
optional extra, imported only then) and a ``plot(ax=None, **kw)`` that draws on
matplotlib axes. Drawing lives in the report layer, which the statistics core
may not import; the package registers it here (:func:`register_plotter`, done by
``sigmatau/__init__.py`` the way dask arrays are registered with the driver), and
the figure code is imported on the first ``plot()`` call.
"""

from __future__ import annotations

import html
import math
from typing import Any, Callable, Iterable, Mapping, Optional, Sequence

from ..errors import MissingDependencyError

__all__ = ["NOISE_NAMES", "noise_name", "html_table", "data_frame", "concat_frames", "register_plotter", "plot"]

#: Short names of the power-law noise types, keyed by the frequency exponent α.
NOISE_NAMES: Mapping[int, str] = {
    2: "WPM", 1: "FPM", 0: "WFM", -1: "FFM", -2: "RWFM", -3: "FWFM", -4: "RRFM",
}


def noise_name(alpha: Any) -> str:
    """The short name of the noise type α (``"WFM"``), or ``""`` when α is missing or unknown.

    Examples
    --------
    >>> noise_name(0), noise_name(-2.0), noise_name(float("nan"))
    ('WFM', 'RWFM', '')
    """
    try:
        a = float(alpha)
    except (TypeError, ValueError):
        return ""
    if not math.isfinite(a) or a != int(a):
        return ""
    return NOISE_NAMES.get(int(a), "")


def _cell(value: Any) -> str:
    """One escaped table cell: floats in 4 significant digits, missing values as an em dash."""
    if value is None:
        return "—"
    if isinstance(value, float):
        return "—" if not math.isfinite(value) else html.escape(f"{value:.4g}")
    return html.escape(str(value))


def html_table(headers: Sequence[str], rows: Iterable[Sequence[Any]], *, caption: str = "",
               notes: Sequence[str] = ()) -> str:
    """A small HTML table for a notebook, every header, cell, caption and note escaped.

    Examples
    --------
    >>> text = html_table(["a"], [["<b>"]], caption="x & y")
    >>> "<caption>x &amp; y</caption>" in text, "<td>&lt;b&gt;</td>" in text, "<b>" in text
    (True, True, False)
    """
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in headers)
    body = "".join("<tr>" + "".join(f"<td>{_cell(v)}</td>" for v in row) + "</tr>" for row in rows)
    cap = f"<caption>{html.escape(caption)}</caption>" if caption else ""
    extra = "".join(f"<p>{html.escape(n)}</p>" for n in notes)
    return f"<div><table>{cap}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>{extra}</div>"


def _pandas() -> Any:
    try:
        import pandas
    except ImportError:
        raise MissingDependencyError('to_pandas() needs pandas: pip install "sigmatau[pandas]"') from None
    return pandas


def data_frame(columns: Mapping[str, Sequence[Any]], *, attrs: Optional[Mapping[str, Any]] = None) -> Any:
    """A pandas DataFrame of ``columns`` (in order), with ``attrs`` (units, rate, confidence …).

    Raises
    ------
    MissingDependencyError
        pandas is not installed (extra ``pandas``).
    """
    pd = _pandas()
    frame = pd.DataFrame({k: list(v) for k, v in columns.items()})
    frame.attrs.update(dict(attrs or {}))
    return frame


def concat_frames(frames: Sequence[Any], *, attrs: Optional[Mapping[str, Any]] = None) -> Any:
    """Frames stacked row-wise (a tidy long table), with ``attrs``; an empty frame when there are none."""
    pd = _pandas()
    frame = pd.concat(list(frames), ignore_index=True) if frames else pd.DataFrame()
    frame.attrs = dict(attrs or {})
    return frame


#: kind → function(obj, ax=None, **kw) returning the axes; filled by the package's __init__.
_PLOTTERS: dict[str, Callable[..., Any]] = {}


def register_plotter(kind: str, func: Callable[..., Any]) -> None:
    """Register the function that draws results of ``kind`` (``"stability"``, ``"model"``,
    ``"channel"``, ``"log"``); called with ``(obj, ax=None, **kw)``, returning the axes."""
    _PLOTTERS[kind] = func


def plot(kind: str, obj: Any, ax: Any = None, **kw: Any) -> Any:
    """Draw ``obj`` with the plotter registered for ``kind``; the matplotlib axes it drew on."""
    func = _PLOTTERS.get(kind)
    if func is None:  # only when the core is used without the package's __init__
        raise MissingDependencyError("plot() needs the sigmatau package's figure layer: import sigmatau first")
    return func(obj, ax=ax, **kw)
