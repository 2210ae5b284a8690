"""Pass/fail limits of noise terms: a datasheet part, a JSON, YAML or CSV file, or a mapping, in SI."""

from __future__ import annotations

import csv
import io as _io
import json
import math
import os
import warnings
from pathlib import Path
from typing import Any, Mapping

from ...errors import ParameterError, SigmaTauError, SigmaTauWarning
from ...pipeline.analysis import IMU_GROUPS, SI_TERM_UNITS, TERMS
from .common import LIMIT_MARGIN


def load_limits(spec: Any, *, margin: float = LIMIT_MARGIN) -> dict[str, dict[str, dict[str, Any]]]:
    """Upper limits of noise terms, in SI: ``{group: {term: {"max": float, "unit": str, "source": str}}}``.

    Parameters
    ----------
    spec : str, path or mapping or None
        A part with presets in :data:`sigmatau.imu.PRESETS` (``"lsm6dsl"`` …):
        its typical datasheet figures × ``margin``; or a file — JSON or YAML
        ``{"gyro": {"N": "6 mdps/sqrt(Hz)", "B": [1e-4, "rad/s"]}}``, or CSV
        with the columns ``group, term, max, unit`` (UTF-8, a byte-order mark
        allowed) — whose values are the limits as given; or such a mapping.
        A value without unit is SI.
    margin : float
        Factor applied to a preset's typical values (default 1.5); not to
        limits given explicitly (a warning says so when another margin is given).

    Raises
    ------
    ParameterError
        An unknown part, a missing, unreadable or malformed file (the message
        names it and what is wrong), an unknown group, term or unit, a value
        that is not a positive number, a term given twice, or a margin that is
        not a positive finite number.
    """
    from ...pipeline.analysis import datasheet_reference
    from ...imu.units import convert

    if isinstance(margin, bool) or not isinstance(margin, (int, float)) or not (math.isfinite(margin) and margin > 0):
        raise ParameterError(f"limit margin {margin!r} must be a positive finite number")
    if spec is None:
        return {}
    raw: Mapping[str, Any]
    factor, source, where, part = 1.0, "given", "limits: ", False
    if isinstance(spec, (str, os.PathLike)):
        p = Path(spec)
        if p.is_file():
            raw, source = _limits_file(p), f"file {os.fspath(spec)}"
            where = f"limits file {str(p)!r}: "
        elif os.fspath(spec).lower().endswith((".json", ".yaml", ".yml", ".csv")):
            raise ParameterError(f"limits file {os.fspath(spec)!r} does not exist")
        else:
            raw = datasheet_reference(os.fspath(spec))
            factor, source, part = float(margin), f"datasheet {os.fspath(spec)} typical × {float(margin):g}", True
    elif isinstance(spec, Mapping):
        raw = spec
    else:
        raise ParameterError(f"limits={spec!r} must be a part name, a file or a mapping group → term → value")
    if not part and margin != LIMIT_MARGIN:
        warnings.warn(f"limit margin {margin:g} not applied: it multiplies a datasheet part's typical values, and"
                      f" the limits of {'the file' if where != 'limits: ' else 'the mapping'} are used as given",
                      SigmaTauWarning, stacklevel=2)
    out: dict[str, dict[str, dict[str, Any]]] = {}
    for group, terms in raw.items():
        if group not in IMU_GROUPS:
            raise ParameterError(f"{where}group {group!r} must be 'gyro' or 'accel'")
        if not isinstance(terms, Mapping):
            raise ParameterError(f"{where}{group!r} must map terms to values, e.g. {{N: '6 mdps/sqrt(Hz)'}}")
        for term, value in terms.items():
            if term not in TERMS:
                raise ParameterError(f"{where}term {group}.{term} must be one of {', '.join(TERMS)}")
            si = SI_TERM_UNITS[group][term]
            v, unit = _limit_value(value, f"{where}{group}.{term}", si)
            try:
                v_si = float(convert(v, unit, si))
            except SigmaTauError:
                raise ParameterError(f"{where}{group}.{term} unit {unit!r} is not a unit of {si}") from None
            out.setdefault(group, {})[term] = {"max": v_si * factor, "unit": si, "source": source,
                                               "given": f"{v:g} {unit}" + (f" × {factor:g}" if factor != 1 else "")}
    return out


def _limit_value(value: Any, what: str, si: str) -> tuple[float, str]:
    """``(value, unit)`` of one limit given as a number (SI), ``'value unit'`` or ``(value, unit)``.

    Raises ParameterError naming ``what`` otherwise, or when the value is not positive.
    """
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        v, unit = float(value), si
    elif isinstance(value, str):
        num, _, unit = value.strip().partition(" ")
        try:
            v = float(num)
        except ValueError:
            raise ParameterError(f"{what}={value!r} must be 'value unit', e.g. '6 mdps/sqrt(Hz)'") from None
        unit = unit.strip() or si
    elif isinstance(value, (list, tuple)) and len(value) == 2:
        try:
            v, unit = float(value[0]), str(value[1])
        except (TypeError, ValueError):
            raise ParameterError(f"{what}={value!r} must be (value, unit)") from None
    else:
        raise ParameterError(f"{what}={value!r} must be a number, 'value unit' or (value, unit)")
    if not (math.isfinite(v) and v > 0):
        raise ParameterError(f"{what}={value!r} must be positive")
    return v, unit


def _limits_file(p: Path) -> dict[str, Any]:
    """The mapping group → term → value of a limits file (JSON, YAML or CSV by its suffix)."""
    name = str(p)
    try:
        text = p.read_text(encoding="utf-8-sig")  # -sig: spreadsheets save CSV with a byte-order mark
    except UnicodeDecodeError as exc:
        raise ParameterError(f"limits file {name!r} is not UTF-8 text (byte {exc.start})") from None
    except OSError as exc:
        raise ParameterError(f"limits file {name!r} cannot be read: {exc.strerror or exc}") from None
    suffix = p.suffix.lower()
    if suffix == ".csv":
        return _limits_csv(text, name)
    if suffix in (".yaml", ".yml"):
        try:
            import yaml
        except ImportError:
            from ...io import MissingDependencyError

            raise MissingDependencyError("YAML limits need PyYAML; install it with: pip install pyyaml,"
                                         " or give the limits as JSON or CSV") from None
        try:
            data = yaml.safe_load(text)
        except yaml.YAMLError as exc:
            mark = getattr(exc, "problem_mark", None)
            at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
            problem = getattr(exc, "problem", None) or type(exc).__name__
            raise ParameterError(f"limits file {name!r} is not valid YAML{at}: {problem}") from None
    else:
        try:
            data = json.loads(text, object_pairs_hook=_no_duplicate_keys)
        except ValueError as exc:
            raise ParameterError(f"limits file {name!r} is not valid JSON: {exc}") from None
    if not isinstance(data, Mapping):
        raise ParameterError(f"limits file {name!r} must map groups to terms to values, e.g."
                             " {gyro: {N: '6 mdps/sqrt(Hz)'}}")
    return dict(data)


def _no_duplicate_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object, refused when a key appears twice (JSON would keep the last silently)."""
    keys = [k for k, _ in pairs]
    twice = sorted({k for k in keys if keys.count(k) > 1})
    if twice:
        raise ValueError(f"{', '.join(map(repr, twice))} given twice")
    return dict(pairs)


def _limits_csv(text: str, name: str) -> dict[str, Any]:
    """The mapping group → term → value of a CSV limits file (columns ``group, term, max``, ``unit``)."""
    try:
        rows = list(csv.reader(_io.StringIO(text)))
    except csv.Error as exc:
        raise ParameterError(f"limits file {name!r} is not valid CSV: {exc}") from None
    header = [h.strip().lower() for h in rows[0]] if rows else []
    if not {"group", "term", "max"} <= set(header):
        raise ParameterError(f"limits file {name!r}: CSV needs the columns group, term, max (and unit)")
    col = {h: i for i, h in enumerate(header)}
    data: dict[str, dict[str, Any]] = {}
    for number, row in enumerate(rows[1:], start=2):
        if not any(c.strip() for c in row):
            continue
        cells = {h: (row[i].strip() if i < len(row) else "") for h, i in col.items()}
        if not (cells["group"] and cells["term"] and cells["max"]):
            raise ParameterError(f"limits file {name!r}: row {number} needs a group, a term and a max")
        try:
            v = float(cells["max"])
        except ValueError:
            raise ParameterError(f"limits file {name!r}: row {number}: max={cells['max']!r} is not a number") from None
        terms = data.setdefault(cells["group"], {})
        if cells["term"] in terms:
            raise ParameterError(f"limits file {name!r}: row {number}: {cells['group']}.{cells['term']} is given"
                                 " twice")
        unit = cells.get("unit", "")
        terms[cells["term"]] = (v, unit) if unit else v
    return data
