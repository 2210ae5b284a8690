"""sigmatau: noise analysis of sensors with the Allan family of variances.

The public API is re-exported here explicitly; see ``__all__``. Submodules
``imu`` (the gyroscope/accelerometer noise model), ``units``, ``checks``,
``noiseid``, ``confidence``, ``generate``, ``filterchain`` and ``datasets`` hold
the rest of the toolkit; ``sigmatau.io`` reads sensor logs (imported on demand).
"""

from __future__ import annotations

import sys as _sys

from . import checks, compare, confidence, datasets, filterchain, generate, imu, noiseid, prep, spectral, units
from .compare import cornered_hat, gcodev, three_cornered_hat
from .spectral import deadtime_correction, psd, rms_jitter, spectrum_to_sigma
from .core.driver import register_streamed as _register_streamed
from .core.present import register_plotter as _register_plotter
from .core.validate import frequency_to_phase, phase_to_frequency
from ._version import __version__
from .stats.allan import adev, mdev, oadev, ostdev, stdev, tdev
from .stats.dynamic import DynamicResult, StationarityCheck, dynamic
from .scale.channels import compute_channels
from .uncertainty.confidence import ONE_SIGMA, deviation_interval, edf
from .errors import DataError, ParameterError, RangeWarning, SigmaTauError, SigmaTauWarning
from .noise.generate import mixed_noise, power_law_noise
from .stats.hadamard import hdev, ohdev
from .stats.modhadamard import ldev, mhdev, mhtotdev
from .stats.parabolic import pdev
from .imu.model import NoiseModel
from .uncertainty.noiseid import fit_power_law, identify, local_slopes
from .core.result import StabilityResult
from .stats.theo import theo1, theobr, theobr_kappa, theoh
from .stats.tie import mtie, tierms
from .stats.total import htotdev, mtotdev, totdev, ttotdev

__all__ = [
    "__version__",
    # statistics
    "stdev", "ostdev", "adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "mhdev", "ldev", "pdev",
    "totdev", "mtotdev", "ttotdev", "htotdev", "mhtotdev", "theo1", "theobr", "theoh", "mtie", "tierms",
    "theobr_kappa", "compute_channels",
    # comparing devices (covariances, cornered hats) and the frequency domain
    "compare", "gcodev", "three_cornered_hat", "cornered_hat",
    "spectral", "psd", "spectrum_to_sigma", "rms_jitter", "deadtime_correction",
    # the statistics over sliding windows (non-stationarity)
    "dynamic", "DynamicResult", "StationarityCheck",
    # uncertainty and noise identification
    "ONE_SIGMA", "edf", "deviation_interval", "identify", "local_slopes", "fit_power_law",
    # noise generation
    "power_law_noise", "mixed_noise",
    # types and errors
    "StabilityResult", "SigmaTauError", "ParameterError", "DataError",
    "SigmaTauWarning", "RangeWarning",
    # conversions
    "frequency_to_phase", "phase_to_frequency",
    # IMU noise model
    "NoiseModel",
    # submodules
    "checks", "confidence", "datasets", "filterchain", "generate", "imu", "noiseid", "prep", "units",
]


def _is_dask(data: object) -> bool:
    # By the type's module: dask is never imported for this test.
    return type(data).__module__.startswith("dask.")


def _dask_record(data: object) -> object:
    # The scale-out layer loads when the first dask object reaches a statistic, not at import.
    from .scale.chunked.sources import adapt_dask

    return adapt_dask(data)


# Dask objects reach the statistics as streamed records (core.driver.StreamedSeries).
_register_streamed(_is_dask, _dask_record)


def _plotter(name: str):  # type: ignore[no-untyped-def]
    # The figure layer (matplotlib) loads on the first plot() call, not at import.
    def draw(obj: object, ax: object = None, **kw: object) -> object:
        from .report import notebook

        return getattr(notebook, name)(obj, ax, **kw)

    return draw


# plot() of the result types (core.present) draws through the report layer's notebook module.
for _kind, _name in (("stability", "plot_result"), ("model", "plot_model"), ("channel", "plot_channel"),
                     ("log", "plot_log")):
    _register_plotter(_kind, _plotter(_name))

# Modules that sat at the top of the package before it was split into layers keep their
# dotted paths: ``import sigmatau.theo`` and ``sigmatau.result.StabilityResult`` still work,
# and results pickled by an earlier version still load.
from .core import result as _result, taus as _taus  # noqa: E402
from .report import html as _html  # noqa: E402
from .scale import channels as _channels  # noqa: E402
from .stats import allan as _allan, hadamard as _hadamard, theo as _theo, tie as _tie, total as _total  # noqa: E402

for _old, _module in {"result": _result, "taus": _taus, "allan": _allan, "hadamard": _hadamard, "theo": _theo,
                      "tie": _tie, "total": _total, "channels": _channels, "htmlreport": _html}.items():
    _sys.modules.setdefault(f"{__name__}.{_old}", _module)
    globals()[_old] = _module
del _old, _module
