"""Units of inertial-sensor noise parameters: parsing, SI ↔ customary, Kalibr conventions.

An IMU channel is declared by the unit of its samples: an angular rate
(``"rad/s"``, ``"deg/s"``, ``"deg/h"``, ``"mdps"`` …) for a gyroscope or a
specific force (``"m/s^2"``, ``"g"``, ``"mg"`` …) for an accelerometer. The five
classic noise terms then have the units of the samples times a power of time
(IEEE Std 952/1554 model, AVAR contributions in the Notes of
:func:`term_unit`):

======  ============================  ====================  ======================
term    unit (input unit u)           gyro SI               accel SI
======  ============================  ====================  ======================
Q       u·s                           rad                   m/s
N       u/√Hz  (= u·√s)               rad/s/√Hz             m/s²/√Hz
B       u                             rad/s                 m/s²
K       u/s/√Hz (= u/√s)              rad/s²/√Hz            m/s³/√Hz
R       u/s                           rad/s²                m/s³
======  ============================  ====================  ======================

Unit expressions are parsed, so any dimensionally correct spelling converts:
``convert(0.66, "deg/sqrt(h)", "rad/s/sqrt(Hz)")``. Symbols: ``rad``, ``mrad``,
``urad``/``µrad``, ``deg``/``°``, ``mdeg``, ``arcmin``, ``arcsec``; ``m``,
``mm``, ``um``/``µm``; ``g`` (standard gravity 9.80665 m/s², **not** gram),
``mg``, ``ug``/``µg``; ``s``, ``ms``, ``us``/``µs``, ``min``, ``h``/``hr``;
``Hz``, ``kHz``; ``dps`` (°/s), ``mdps``. Operators ``/``, ``*``, ``·``,
``^`` (or ², ³, ½), ``sqrt(…)`` or ``√``, and parentheses; ``a/b/c`` means
``a/(b·c)``.

Kalibr (continuous time) and its discrete-time equivalents at the sample rate f:
``σ_d = N·√f`` for the white noise, ``σ_bd = K/√f`` for the bias random walk
(:func:`density_to_discrete`, :func:`random_walk_to_discrete`). A discrete σ is
not a density and the two must not be mixed.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Literal, Mapping, Union

from ..core.validate import check_rate
from ..errors import ParameterError

__all__ = [
    "STANDARD_GRAVITY",
    "TERMS",
    "CUSTOMARY",
    "SensorUnit",
    "parse_unit",
    "convert",
    "sensor_unit",
    "term_unit",
    "density_to_discrete",
    "discrete_to_density",
    "random_walk_to_discrete",
    "discrete_to_random_walk",
]

#: Standard gravity in m/s² (CGPM 1901), the ``g`` of accelerometer datasheets.
STANDARD_GRAVITY = 9.80665

#: The five terms of the IEEE Std 952 model, in order of increasing τ.
TERMS: tuple[str, ...] = ("Q", "N", "B", "K", "R")

Term = Literal["Q", "N", "B", "K", "R"]
Kind = Literal["gyro", "accel"]

# Dimension vector: (angle, length, time). Angle is kept as a dimension so a
# gyroscope unit can never be converted into an accelerometer one.
_Dim = tuple[float, float, float]

_DEG = math.pi / 180.0
_SYMBOLS: dict[str, tuple[float, _Dim]] = {
    "rad": (1.0, (1, 0, 0)),
    "mrad": (1e-3, (1, 0, 0)),
    "urad": (1e-6, (1, 0, 0)),
    "deg": (_DEG, (1, 0, 0)),
    "mdeg": (1e-3 * _DEG, (1, 0, 0)),
    "arcmin": (_DEG / 60.0, (1, 0, 0)),
    "arcsec": (_DEG / 3600.0, (1, 0, 0)),
    "m": (1.0, (0, 1, 0)),
    "mm": (1e-3, (0, 1, 0)),
    "um": (1e-6, (0, 1, 0)),
    "g": (STANDARD_GRAVITY, (0, 1, -2)),
    "mg": (1e-3 * STANDARD_GRAVITY, (0, 1, -2)),
    "ug": (1e-6 * STANDARD_GRAVITY, (0, 1, -2)),
    "s": (1.0, (0, 0, 1)),
    "ms": (1e-3, (0, 0, 1)),
    "us": (1e-6, (0, 0, 1)),
    "min": (60.0, (0, 0, 1)),
    "h": (3600.0, (0, 0, 1)),
    "Hz": (1.0, (0, 0, -1)),
    "kHz": (1e3, (0, 0, -1)),
    "dps": (_DEG, (1, 0, -1)),
    "mdps": (1e-3 * _DEG, (1, 0, -1)),
}
_ALIASES = {
    "°": "deg", "degree": "deg", "degrees": "deg", "radian": "rad", "radians": "rad",
    "µrad": "urad", "μrad": "urad", "µm": "um", "μm": "um", "µg": "ug", "μg": "ug",
    "µs": "us", "μs": "us", "sec": "s", "hr": "h", "hour": "h", "hours": "h",
    "″": "arcsec", "asec": "arcsec", "′": "arcmin", "hz": "Hz", "khz": "kHz",
    "gee": "g", "G": "g",
}
_SUPERSCRIPTS = {"²": "^2", "³": "^3", "½": "^0.5", "⁻¹": "^-1", "⁻²": "^-2"}
_TOKEN = re.compile(r"\s*(sqrt|√|[A-Za-zµμ°″′]+|\d+(?:\.\d*)?|[()*/·^.\-+])")


@dataclass(frozen=True)
class _Parsed:
    factor: float
    dim: _Dim


def _mul(a: _Parsed, b: _Parsed, sign: float = 1.0) -> _Parsed:
    return _Parsed(a.factor * b.factor**sign, tuple(x + sign * y for x, y in zip(a.dim, b.dim)))  # type: ignore[arg-type]


def _pow(a: _Parsed, p: float) -> _Parsed:
    return _Parsed(a.factor**p, tuple(x * p for x in a.dim))  # type: ignore[arg-type]


class _Parser:
    def __init__(self, text: str):
        self.text = text
        s = text
        for sup, rep in _SUPERSCRIPTS.items():
            s = s.replace(sup, rep)
        pos, toks = 0, []
        while pos < len(s):
            if s[pos].isspace():
                pos += 1
                continue
            mt = _TOKEN.match(s, pos)
            if mt is None:
                raise ParameterError(f"unit {text!r}: cannot read {s[pos:]!r}")
            toks.append(mt.group(1))
            pos = mt.end()
        self.toks = toks
        self.i = 0

    def _peek(self):
        return self.toks[self.i] if self.i < len(self.toks) else None

    def _take(self):
        tok = self._peek()
        self.i += 1
        return tok

    def parse(self) -> _Parsed:
        if not self.toks:
            raise ParameterError(f"unit {self.text!r} is empty")
        out = self._expr()
        if self._peek() is not None:
            raise ParameterError(f"unit {self.text!r}: unexpected {self._peek()!r}")
        return out

    def _expr(self) -> _Parsed:
        acc = self._factor()
        while True:
            nxt = self._peek()
            if nxt in ("*", "/", "·", "."):
                op = self._take()
                acc = _mul(acc, self._factor(), -1.0 if op == "/" else 1.0)
            elif nxt is not None and (nxt in ("sqrt", "√", "(") or nxt[0].isalpha() or nxt[0] in "µμ°″′"):
                acc = _mul(acc, self._factor())  # juxtaposition ("m s^-2") multiplies
            else:
                return acc

    def _number(self) -> float:
        sign = 1.0
        if self._peek() in ("-", "+"):
            sign = -1.0 if self._take() == "-" else 1.0
        if self._peek() == "(":
            self._take()
            num = self._number()
            if self._peek() == "/":
                self._take()
                num /= self._number()
            if self._take() != ")":
                raise ParameterError(f"unit {self.text!r}: missing ')' in an exponent")
            return sign * num
        tok = self._take()
        try:
            return sign * float(tok)
        except (TypeError, ValueError):
            raise ParameterError(f"unit {self.text!r}: exponent expected, got {tok!r}") from None

    def _factor(self) -> _Parsed:
        tok = self._take()
        if tok is None:
            raise ParameterError(f"unit {self.text!r} ends early")
        if tok in ("sqrt", "√"):
            if self._peek() == "(":
                self._take()
                inner = self._expr()
                if self._take() != ")":
                    raise ParameterError(f"unit {self.text!r}: missing ')'")
            else:
                inner = self._factor_atom(self._take())
            base = _pow(inner, 0.5)
        elif tok == "(":
            base = self._expr()
            if self._take() != ")":
                raise ParameterError(f"unit {self.text!r}: missing ')'")
        else:
            base = self._factor_atom(tok)
        if self._peek() == "^":
            self._take()
            base = _pow(base, self._number())
        elif self._peek() is not None and re.fullmatch(r"\d+(?:\.\d*)?", self._peek()):
            base = _pow(base, float(self._take()))  # "s2", "m/s2"
        return base

    def _factor_atom(self, tok: object) -> _Parsed:
        if tok is None:
            raise ParameterError(f"unit {self.text!r} ends early")
        if isinstance(tok, str) and re.fullmatch(r"\d+(?:\.\d*)?", tok):
            return _Parsed(float(tok), (0, 0, 0))
        if tok == "dph":  # degrees per hour, as navigation texts write it
            return _Parsed(_DEG / 3600.0, (1, 0, -1))
        name = _ALIASES.get(tok, tok)
        if name not in _SYMBOLS:
            raise ParameterError(
                f"unit {self.text!r}: unknown symbol {tok!r}; known: {sorted(_SYMBOLS)} (g is standard gravity)"
            )
        f, d = _SYMBOLS[name]
        return _Parsed(f, d)


def parse_unit(unit: str) -> tuple[float, _Dim]:
    """Factor to SI and dimension ``(angle, length, time)`` of a unit expression.

    Parameters
    ----------
    unit : str
        For example ``"deg/h"``, ``"µg/√Hz"``, ``"m/s/sqrt(h)"``, ``"rad/s^2/sqrt(Hz)"``.

    Returns
    -------
    (float, tuple)
        ``value_SI = value · factor``; exponents of angle (rad), length (m) and
        time (s).

    Examples
    --------
    >>> from sigmatau.units import parse_unit
    >>> f, dim = parse_unit("deg/sqrt(h)")
    >>> round(f, 10), dim
    (0.0002908882, (1, 0, -0.5))
    """
    if not isinstance(unit, str):
        raise ParameterError(f"unit={unit!r} must be a string such as 'rad/s' or 'm/s^2'")
    p = _Parser(unit).parse()
    dim = tuple(int(x) if float(x).is_integer() else float(x) for x in p.dim)
    return p.factor, dim  # type: ignore[return-value]


def convert(value: Union[float, "object"], from_unit: str, to_unit: str):
    """Convert ``value`` between two units of the same dimension.

    Parameters
    ----------
    value : float or array_like
    from_unit, to_unit : str
        Unit expressions (see the module docstring).

    Returns
    -------
    float or numpy.ndarray

    Raises
    ------
    ParameterError
        If a unit cannot be parsed or the dimensions differ (e.g. a gyro unit
        into an accelerometer unit, or a density into a discrete σ).

    Examples
    --------
    >>> from sigmatau.units import convert
    >>> round(convert(0.0135, "deg/s/sqrt(Hz)", "deg/sqrt(h)"), 3)     # ADIS16448 ARW
    0.81
    >>> round(convert(1.0, "deg/sqrt(h)", "rad/sqrt(s)"), 7)
    0.0002909
    >>> round(convert(80, "ug/sqrt(Hz)", "m/s^2/sqrt(Hz)"), 7)           # LSM6DSL accel
    0.0007845
    """
    f1, d1 = parse_unit(from_unit)
    f2, d2 = parse_unit(to_unit)
    if any(abs(a - b) > 1e-12 for a, b in zip(d1, d2)):
        raise ParameterError(
            f"cannot convert {from_unit!r} (dimension {_dim_text(d1)}) to {to_unit!r} (dimension {_dim_text(d2)})"
        )
    return value * (f1 / f2)


def _dim_text(d: _Dim) -> str:
    names = ("rad", "m", "s")
    parts = [f"{n}^{e:g}" for n, e in zip(names, d) if e != 0]
    return "·".join(parts) or "1"


# ------------------------------------------------------------------- sensor units

#: Time exponent added to the input unit for each term (Q: ·s, N: ·√s, B: 1, K: /√s, R: /s).
_TERM_TIME = {"Q": 1.0, "N": 0.5, "B": 0.0, "K": -0.5, "R": -1.0}

#: Customary units offered beside SI, per sensor kind and term (what datasheets and
#: navigation texts print).
CUSTOMARY: Mapping[str, Mapping[str, tuple[str, ...]]] = {
    "gyro": {
        "Q": ("urad", "arcsec"),
        "N": ("deg/sqrt(h)", "deg/s/sqrt(Hz)", "mdps/sqrt(Hz)"),
        "B": ("deg/h",),
        "K": ("deg/h/sqrt(h)",),
        "R": ("deg/h^2",),
    },
    "accel": {
        "Q": ("mm/s",),
        "N": ("m/s/sqrt(h)", "ug/sqrt(Hz)"),
        "B": ("mg", "ug"),
        "K": ("m/s/h/sqrt(h)", "ug/sqrt(s)"),
        "R": ("ug/s", "m/s/h^2"),
    },
}

_SI = {"gyro": "rad/s", "accel": "m/s^2"}
_PRETTY = {"sqrt(Hz)": "√Hz", "sqrt(h)": "√h", "sqrt(s)": "√s", "^2": "²", "^3": "³", "deg": "°",
           "ug": "µg", "urad": "µrad", "um": "µm"}

# Nice spellings of term units for the common input units: {input: {term: unit}}.
_TERM_NAMES = {
    "rad/s": {"Q": "rad", "N": "rad/s/sqrt(Hz)", "B": "rad/s", "K": "rad/s^2/sqrt(Hz)", "R": "rad/s^2"},
    "deg/s": {"Q": "deg", "N": "deg/s/sqrt(Hz)", "B": "deg/s", "K": "deg/s^2/sqrt(Hz)", "R": "deg/s^2"},
    "deg/h": {"Q": "deg/h*s", "N": "deg/h/sqrt(Hz)", "B": "deg/h", "K": "deg/h/s/sqrt(Hz)", "R": "deg/h/s"},
    "m/s^2": {"Q": "m/s", "N": "m/s^2/sqrt(Hz)", "B": "m/s^2", "K": "m/s^3/sqrt(Hz)", "R": "m/s^3"},
    "g": {"Q": "g*s", "N": "g/sqrt(Hz)", "B": "g", "K": "g/s/sqrt(Hz)", "R": "g/s"},
    "mg": {"Q": "mg*s", "N": "mg/sqrt(Hz)", "B": "mg", "K": "mg/s/sqrt(Hz)", "R": "mg/s"},
}
_CANONICAL = {
    "rad/s": "rad/s", "rad/sec": "rad/s", "deg/s": "deg/s", "°/s": "deg/s", "dps": "deg/s",
    "deg/sec": "deg/s", "deg/h": "deg/h", "°/h": "deg/h", "deg/hr": "deg/h", "dph": "deg/h",
    "m/s^2": "m/s^2", "m/s²": "m/s^2", "m/s2": "m/s^2", "m/s/s": "m/s^2", "g": "g", "mg": "mg",
}


def pretty(unit: str) -> str:
    """Display form of a unit expression (√, superscripts, °, µ)."""
    out = unit
    for a, b in _PRETTY.items():
        out = out.replace(a, b)
    return out.replace("*", "·")


@dataclass(frozen=True)
class SensorUnit:
    """The declared unit of an IMU channel's samples.

    Attributes
    ----------
    name : str
        The unit as declared (canonical spelling for the common ones).
    kind : {"gyro", "accel"}
        Angular rate or specific force, from the dimension.
    to_si : float
        Factor from the declared unit to rad/s or m/s².
    """

    name: str
    kind: Kind
    to_si: float

    @property
    def si(self) -> str:
        """SI unit of the samples: ``"rad/s"`` or ``"m/s^2"``."""
        return _SI[self.kind]

    def term_unit(self, term: str) -> str:
        """Unit of the term ``"Q"``, ``"N"``, ``"B"``, ``"K"`` or ``"R"`` in the declared unit."""
        return term_unit(self.name, term)

    def term_si(self, term: str) -> str:
        """SI unit of the term."""
        return term_unit(self.si, term)

    def term_to_si(self, term: str) -> float:
        """Factor from the term's declared unit to its SI unit."""
        return float(convert(1.0, self.term_unit(term), self.term_si(term)))


def sensor_unit(unit: str) -> SensorUnit:
    """Parse the declared unit of an IMU channel.

    Parameters
    ----------
    unit : str
        Angular rate (``"rad/s"``, ``"deg/s"``, ``"dps"``, ``"mdps"``,
        ``"deg/h"`` …) or specific force (``"m/s^2"``, ``"g"``, ``"mg"`` …).

    Returns
    -------
    SensorUnit

    Raises
    ------
    ParameterError
        If the unit is neither an angle per time nor a length per time².

    Examples
    --------
    >>> from sigmatau.units import sensor_unit
    >>> u = sensor_unit("deg/s")
    >>> u.kind, u.term_unit("N"), u.term_si("K")
    ('gyro', 'deg/s/sqrt(Hz)', 'rad/s^2/sqrt(Hz)')
    """
    if not isinstance(unit, str):
        raise ParameterError(f"unit={unit!r} must be a string such as 'rad/s', 'deg/s', 'g' or 'm/s^2'")
    name = _CANONICAL.get(unit.strip(), unit.strip())
    factor, dim = parse_unit(name)
    if dim == (1, 0, -1):
        kind: Kind = "gyro"
    elif dim == (0, 1, -2):
        kind = "accel"
    else:
        raise ParameterError(
            f"unit={unit!r} has dimension {_dim_text(dim)}; an IMU channel is an angular rate"
            " (rad/s, deg/s, deg/h, mdps) or a specific force (m/s^2, g, mg)"
        )
    return SensorUnit(name=name, kind=kind, to_si=factor)


def term_unit(unit: str, term: str) -> str:
    """Unit of one noise term for samples in ``unit``.

    Parameters
    ----------
    unit : str
        Unit of the samples.
    term : {"Q", "N", "B", "K", "R"}

    Returns
    -------
    str
        A unit expression that :func:`convert` understands.

    Notes
    -----
    AVAR contributions (IEEE Std 952 Annex C): ``3Q²/τ²``, ``N²/τ``,
    ``(2 ln 2/π)B²``, ``K²τ/3``, ``R²τ²/2``; with σ in ``u`` and τ in s the
    units follow: Q in u·s, N in u·√s = u/√Hz, B in u, K in u/√s = u/s/√Hz,
    R in u/s.

    Examples
    --------
    >>> from sigmatau.units import term_unit
    >>> term_unit("m/s^2", "K"), term_unit("mdps", "N")
    ('m/s^3/sqrt(Hz)', 'mdps/sqrt(Hz)')
    """
    if term not in _TERM_TIME:
        raise ParameterError(f"term={term!r} must be one of {TERMS}")
    name = _CANONICAL.get(unit.strip(), unit.strip())
    if name in _TERM_NAMES:
        return _TERM_NAMES[name][term]
    wrapped = name if re.fullmatch(r"[A-Za-zµμ°]+", name) else f"({name})"
    return {"Q": f"{wrapped}*s", "N": f"{wrapped}/sqrt(Hz)", "B": name,
            "K": f"{wrapped}/s/sqrt(Hz)", "R": f"{wrapped}/s"}[term]


# ------------------------------------------------------------ Kalibr conventions


def density_to_discrete(density: float, *, rate: float) -> float:
    """Discrete-time white-noise σ at ``rate`` from a continuous density: ``σ_d = N·√f``.

    Parameters
    ----------
    density : float
        White-noise density N (u/√Hz), e.g. Kalibr's ``gyroscope_noise_density``.
    rate : float
        Sample rate f in Hz.

    Notes
    -----
    Kalibr's convention (its IMU noise-model wiki: ``σ_d = σ·1/√Δt``). It
    assumes the samples are band-limited to f/2, i.e. averaged rather than merely
    decimated; a log decimated by k without averaging shows a density √k too
    large, while its per-sample σ is the true one.

    Examples
    --------
    >>> from sigmatau.units import density_to_discrete
    >>> round(density_to_discrete(1.6968e-4, rate=200.0), 7)
    0.0023996
    """
    return float(density) * math.sqrt(check_rate(rate))


def discrete_to_density(sigma: float, *, rate: float) -> float:
    """Inverse of :func:`density_to_discrete`: ``N = σ_d/√f``."""
    return float(sigma) / math.sqrt(check_rate(rate))


def random_walk_to_discrete(random_walk: float, *, rate: float) -> float:
    """Discrete-time bias random-walk σ per sample: ``σ_bd = K/√f = K·√Δt``.

    Parameters
    ----------
    random_walk : float
        Continuous random-walk coefficient K (u/s/√Hz), e.g. Kalibr's
        ``gyroscope_random_walk``.
    rate : float
        Sample rate f in Hz.

    Examples
    --------
    >>> from sigmatau.units import random_walk_to_discrete
    >>> round(random_walk_to_discrete(1.9393e-5, rate=200.0), 9)
    1.371e-06
    """
    return float(random_walk) / math.sqrt(check_rate(rate))


def discrete_to_random_walk(sigma: float, *, rate: float) -> float:
    """Inverse of :func:`random_walk_to_discrete`: ``K = σ_bd·√f``."""
    return float(sigma) * math.sqrt(check_rate(rate))
