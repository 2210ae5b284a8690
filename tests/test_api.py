"""The public API is pinned, and importing sigmatau stays light."""

import subprocess
import sys

import sigmatau

STATISTICS = [
    "stdev", "ostdev", "adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "mhdev", "ldev", "pdev",
    "totdev", "mtotdev", "ttotdev", "htotdev", "mhtotdev", "theo1", "theobr", "theoh", "mtie", "tierms",
]
OTHER_NAMES = [
    "theobr_kappa", "compute_channels", "NoiseModel", "imu", "units", "checks",
    "ONE_SIGMA", "edf", "deviation_interval", "identify", "local_slopes", "fit_power_law",
    "power_law_noise", "mixed_noise", "confidence", "datasets", "filterchain", "generate", "noiseid", "prep",
    "dynamic", "DynamicResult", "StationarityCheck",
    "compare", "gcodev", "three_cornered_hat", "cornered_hat",
    "spectral", "psd", "spectrum_to_sigma", "rms_jitter", "deadtime_correction",
]


def test_public_names_are_exported():
    for name in STATISTICS + ["StabilityResult", "SigmaTauError", "ParameterError", "DataError",
                              "SigmaTauWarning", "RangeWarning", "frequency_to_phase",
                              "phase_to_frequency", "__version__"] + OTHER_NAMES:
        assert name in sigmatau.__all__, name
        assert hasattr(sigmatau, name), name


def test_all_lists_only_existing_names():
    missing = [n for n in sigmatau.__all__ if not hasattr(sigmatau, n)]
    assert missing == []


def test_statistics_share_one_signature():
    import inspect

    expected = ["data", "rate", "data_type", "taus", "m", "points_per_decade"]
    uncertainty = {"alpha", "confidence", "ci"}
    for name in STATISTICS:
        params = inspect.signature(getattr(sigmatau, name)).parameters
        assert list(params)[: len(expected)] == expected, name
        assert params["rate"].default == 1.0
        assert params["data_type"].default == "freq"
        assert params["taus"].default == "octave"
        assert all(p.kind is p.KEYWORD_ONLY for p in list(params.values())[1:]), name
        assert uncertainty <= set(params), name
        assert params["ci"].default == "chi2" and params["alpha"].default is None


def test_error_hierarchy():
    assert issubclass(sigmatau.ParameterError, ValueError)
    assert issubclass(sigmatau.ParameterError, sigmatau.SigmaTauError)
    assert issubclass(sigmatau.DataError, sigmatau.SigmaTauError)
    assert issubclass(sigmatau.RangeWarning, sigmatau.SigmaTauWarning)
    assert issubclass(sigmatau.SigmaTauWarning, UserWarning)


def test_import_loads_no_plotting_or_io_backend():
    code = (
        "import sys, sigmatau; "
        "heavy = [m for m in ('matplotlib', 'rosbags', 'h5py', 'pyarrow', 'pandas', 'dask') if m in sys.modules]; "
        "print(','.join(heavy))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_import_defers_heavy_scipy_modules():
    # scipy.stats and scipy.optimize double the import time; they load only when used.
    code = "import sys, sigmatau; print([m for m in ('scipy.stats', 'scipy.optimize') if m in sys.modules])"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


#: Names that users could reach at these paths before the package was split into layers
#: (issue 12), outside the modules' ``__all__``: they stay reachable there.
KEPT_PATHS = {
    "sigmatau.imu": ["DEVIATION_RANGE", "NoiseModel", "analyze", "simulate", "from_curve", "kalibr_config"],
    "sigmatau.analysis": ["IMU_GROUPS", "Reference", "TERMS", "analyze_log", "log_from_arrays"],
    "sigmatau.outputs": ["FORMULA_TRIGGERS", "umask", "write_outputs", "csv_cell", "kalibr_yaml", "read_manifest"],
    "sigmatau.batch": ["PathLike", "add_cli", "analyze_many", "expand_patterns", "load_limits"],
    "sigmatau.chunked": ["PathLike", "VFun", "from_npy", "compute", "DEFAULT_CHUNK", "ChunkedSeries"],
    "sigmatau.confidence": ["Sided", "Version", "edf", "chi2_interval", "deviation_interval"],
    "sigmatau.noiseid": ["Family", "LAG1_MIN_POINTS", "identify", "b1_min_averages"],
    "sigmatau.generate": ["ExpectedStatistic", "Method", "NoiseType", "RngLike", "expected_variance_discrete"],
    "sigmatau.units": ["Kind", "Term", "pretty", "convert"],
    "sigmatau.checks": ["check_samples", "check_timestamps", "TimestampWarning", "estimate_lsb"],
    "sigmatau.plots": ["sigma_tau_figure", "signal_figure", "save_figure"],
    "sigmatau.cli": ["main", "DEMO_IMU", "EXIT_OK", "EXIT_DATA", "EXIT_USAGE", "EXIT_INTERNAL"],
}


def test_public_paths_survive_the_layering():
    import importlib

    missing = [f"{mod}.{name}" for mod, names in KEPT_PATHS.items()
               for name in names if not hasattr(importlib.import_module(mod), name)]
    assert missing == []


def test_modules_moved_into_layers_keep_their_old_paths_and_pickles():
    import importlib
    import pickle

    import numpy as np

    for old, name in (("result", "StabilityResult"), ("taus", "select_m"), ("allan", "oadev"),
                      ("hadamard", "ohdev"), ("theo", "theobr_kappa"), ("tie", "mtie"), ("total", "totdev"),
                      ("channels", "compute_channels"), ("htmlreport", "render")):
        assert hasattr(importlib.import_module(f"sigmatau.{old}"), name), old
    # A result pickled by a version before the layers names its class sigmatau.result.StabilityResult.
    res = sigmatau.oadev(np.random.default_rng(2).standard_normal(500))
    old_pickle = pickle.dumps(res, protocol=0).replace(b"sigmatau.core.result", b"sigmatau.result")
    assert b"sigmatau.result\nStabilityResult" in old_pickle
    back = pickle.loads(old_pickle)
    np.testing.assert_array_equal(back.dev, res.dev)
