"""Spectra and the frequency domain: PSD with log-frequency averaging and a power-law
fit (`psd`), σ(τ) ↔ spectrum through transfer functions (`convert`), phase-noise units
and rms jitter (`jitter`), Barnes' bias functions and dead time (`deadtime`).

Same layer as :mod:`sigmatau.stats` (and independent of it): may import
:mod:`sigmatau.core`, :mod:`sigmatau.uncertainty`, :mod:`sigmatau.errors`, numpy and
scipy (scipy lazily, inside the functions that need it).
"""

from .convert import (KIND_OF_STAT, NO_TRANSFER, HFromSigma, SigmaFromSpectrum, sigma_to_h,
                      sigma_to_powerlaw, spectrum_to_sigma, transfer_function)
from .deadtime import DeadTimeCorrection, b1, b2, b3, deadtime_correction, mu_from_alpha
from .psd import PsdResult, psd
from .jitter import (JitterResult, dbc_to_s_phi, rms_jitter, s_phi_to_dbc, s_phi_to_s_x,
                     s_x_to_s_phi, s_x_to_s_y, s_y_to_s_x, to_s_y)

__all__ = [
    "KIND_OF_STAT", "NO_TRANSFER", "HFromSigma", "SigmaFromSpectrum", "sigma_to_h", "sigma_to_powerlaw",
    "spectrum_to_sigma", "transfer_function",
    "DeadTimeCorrection", "b1", "b2", "b3", "deadtime_correction", "mu_from_alpha",
    "JitterResult", "dbc_to_s_phi", "rms_jitter", "s_phi_to_dbc", "s_phi_to_s_x",
    "s_x_to_s_phi", "s_x_to_s_y", "s_y_to_s_x", "to_s_y", "PsdResult", "psd",
]
