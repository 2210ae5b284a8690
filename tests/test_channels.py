"""Several channels at once give exactly the serial results."""

import numpy as np
import pytest

import sigmatau
from sigmatau import DataError, ParameterError


def _channels(n=20_000, k=4):
    rng = np.random.default_rng(11)
    return {f"c{i}": np.cumsum(rng.standard_normal(n)) * 1e-3 + rng.standard_normal(n) for i in range(k)}


@pytest.mark.parametrize("stat", [sigmatau.oadev, sigmatau.mdev, sigmatau.mtotdev, sigmatau.theo1])
def test_parallel_equals_serial(stat):
    data = _channels()
    parallel = sigmatau.compute_channels(stat, data, workers=2, rate=50.0)
    for name, values in data.items():
        serial = stat(values, rate=50.0)
        np.testing.assert_array_equal(parallel[name].dev, serial.dev)
        np.testing.assert_array_equal(parallel[name].ci_high, serial.ci_high)
    assert list(parallel) == list(data)


def test_two_dimensional_input_names_columns():
    data = np.column_stack(list(_channels(k=3).values()))
    out = sigmatau.compute_channels(sigmatau.ohdev, data, ci=None)
    assert list(out) == ["0", "1", "2"]
    np.testing.assert_array_equal(out["2"].dev, sigmatau.ohdev(data[:, 2], ci=None).dev)


def test_errors_are_one_line():
    with pytest.raises(DataError, match="shape"):
        sigmatau.compute_channels(sigmatau.oadev, np.zeros(10))
    with pytest.raises(DataError, match="no channels"):
        sigmatau.compute_channels(sigmatau.oadev, {})
    with pytest.raises(ParameterError, match="workers=0"):
        sigmatau.compute_channels(sigmatau.oadev, _channels(k=2), workers=0)
    with pytest.raises(DataError, match="channel 'c1'"):
        sigmatau.compute_channels(sigmatau.oadev, {"c0": np.ones(10), "c1": [1.0, np.nan, 2.0]})


def test_long_factor_silence_stays_in_its_thread():
    """R(n) silences its long-τ RangeWarning for its own thread only.

    It used ``warnings.catch_warnings``, whose filters are process-wide: a worker
    of ``compute_channels`` restored them while another was inside, and the
    warning escaped as an error (CI, ``test_parallel_equals_serial[theo1]``).
    """
    import threading

    from sigmatau.errors import RangeWarning
    from sigmatau.core.taus import long_factors_expected

    x = np.random.default_rng(3).standard_normal(4000)
    inside, release = threading.Event(), threading.Event()

    def hold():
        with long_factors_expected():
            inside.set()
            release.wait(10)

    worker = threading.Thread(target=hold)
    worker.start()
    try:
        assert inside.wait(10)
        with pytest.warns(RangeWarning, match="few degrees of freedom"):
            sigmatau.oadev(x, m=[1500], ci=None)
    finally:
        release.set()
        worker.join()
    with long_factors_expected():
        sigmatau.oadev(x, m=[1500], ci=None)  # filterwarnings=error: a warning here fails the test
