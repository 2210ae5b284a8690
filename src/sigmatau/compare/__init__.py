"""Compare devices: Groslambert covariance and cornered hats.

Holds :func:`gcodev` (signed Groslambert covariance of two series that share a
device) and the N-cornered hat (:func:`cornered_hat`, :func:`three_cornered_hat`,
:func:`classical_hat`) with non-negative estimates and confidence intervals.
Sits above the statistics layer: it may import sigmatau.stats, sigmatau.uncertainty,
sigmatau.core, sigmatau.errors, numpy and scipy; never io, report, cli or pipeline.
"""

from .covariance import COV_STATISTICS, CovarianceResult, gcodev
from .hat import DeviceHat, HatResult, classical_hat, cornered_hat, three_cornered_hat

__all__ = ["COV_STATISTICS", "CovarianceResult", "gcodev", "DeviceHat", "HatResult", "classical_hat",
           "cornered_hat", "three_cornered_hat"]
