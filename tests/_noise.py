"""Seeded generators of the design tip's seven noise types, for tests only.

Each function takes ``(n, rng)`` (``rng`` a ``numpy.random.Generator``) and
returns n frequency (rate-sensor) samples. The recipes are the tip's
(ST DT0064, "Noise models and generators"):

=====  =======================  ========
name   generator                S_y(f)
=====  =======================  ========
WPM    diff(white)              f^+2
FPM    diff(flicker)            f^+1
WFM    white                    f^0
FFM    flicker (octave sum)     f^-1
RWFM   cumsum(white)            f^-2
FWFM   cumsum(flicker)          f^-3
RRFM   cumsum(cumsum(white))    f^-4
=====  =======================  ========

They only need to have the right character for exercising the estimators on
every kind of data (rough, smooth, drifting); the library's own generators
are tested for their spectra elsewhere.
"""

from __future__ import annotations

from typing import Callable

import numpy as np


def white(n: int, rng: np.random.Generator) -> np.ndarray:
    """White frequency noise (WFM): independent standard normal samples."""
    return rng.standard_normal(n)


def flicker(n: int, rng: np.random.Generator) -> np.ndarray:
    """Flicker (1/f) frequency noise by the tip's octave-sum generator.

    A bank of ``⌊log2 n⌋ + 1`` Gaussian generators is summed. At sample i ≥ 1
    the generator whose index is the number of trailing zeros of i is redrawn,
    so generator k changes every ``2^(k+1)`` samples: each octave contributes
    equal power per octave. A small extra white term fills the top octave.
    """
    n_gen = int(np.floor(np.log2(max(n, 1)))) + 1
    i = np.arange(1, n, dtype=np.int64)
    trailing_zeros = np.log2(i & -i).astype(np.int64)
    out = np.zeros(n)
    for k in range(n_gen):
        redrawn = np.concatenate(([0], np.cumsum(trailing_zeros == k)))
        draws = rng.standard_normal(int(redrawn[-1]) + 1)
        out += draws[redrawn]
    return out + 0.1 * rng.standard_normal(n)


def wpm(n: int, rng: np.random.Generator) -> np.ndarray:
    """White phase noise as frequency: ``diff(white)``."""
    return np.diff(white(n + 1, rng))


def fpm(n: int, rng: np.random.Generator) -> np.ndarray:
    """Flicker phase noise as frequency: ``diff(flicker)``."""
    return np.diff(flicker(n + 1, rng))


def wfm(n: int, rng: np.random.Generator) -> np.ndarray:
    """White frequency noise."""
    return white(n, rng)


def ffm(n: int, rng: np.random.Generator) -> np.ndarray:
    """Flicker frequency noise."""
    return flicker(n, rng)


def rwfm(n: int, rng: np.random.Generator) -> np.ndarray:
    """Random-walk frequency noise: ``cumsum(white)``."""
    return np.cumsum(white(n, rng))


def fwfm(n: int, rng: np.random.Generator) -> np.ndarray:
    """Flicker-walk frequency noise: ``cumsum(flicker)``."""
    return np.cumsum(flicker(n, rng))


def rrfm(n: int, rng: np.random.Generator) -> np.ndarray:
    """Random-run frequency noise: ``cumsum(cumsum(white))``."""
    return np.cumsum(np.cumsum(white(n, rng)))


#: The seven types, in order of α from +2 (WPM) to −4 (RRFM).
NOISES: dict[str, Callable[[int, np.random.Generator], np.ndarray]] = {
    "WPM": wpm,
    "FPM": fpm,
    "WFM": wfm,
    "FFM": ffm,
    "RWFM": rwfm,
    "FWFM": fwfm,
    "RRFM": rrfm,
}
