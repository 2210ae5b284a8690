"""Chunked statistics (sigmatau.chunked) against the in-memory functions.

The reference is always the public in-memory function on the same samples.
Tolerance 1e-12 relative on the variance (issue 7). Measured against exact
integer arithmetic the chunked window sums are within a few 1e-16; the
largest difference to the in-memory result seen on these data, 1.5e-13, is
the in-memory phase MDEV's own round-off on random-walk FM phase (one running
sum over the whole record). Chunk sizes are primes that divide no N here and
are smaller than the largest averaging factors.
"""

from __future__ import annotations

import hashlib
import subprocess
import sys
import tracemalloc
import warnings
from pathlib import Path

import numpy as np
import pytest

import sigmatau
from helpers import assert_same_result
from _noise import NOISES
from sigmatau.scale import chunked
from sigmatau.errors import DataError, ParameterError

RTOL = 1e-12
N = 100_003
NOISE_TYPES = ("WPM", "WFM", "FFM", "RWFM")
CHUNKS = (9973, 4099)  # both below the largest octave factor N/4


def _series(noise: str, data_type: str, n: int = N) -> np.ndarray:
    rng = np.random.default_rng(sorted(NOISES).index(noise) + 100)
    y = NOISES[noise](n, rng) * 1e-9 + 2.5e-7  # a frequency offset, as real oscillators have
    return y if data_type == "freq" else np.cumsum(y) * 0.01 + 3.0


def _assert_same(got: sigmatau.StabilityResult, ref: sigmatau.StabilityResult, rtol: float = RTOL) -> None:
    assert_same_result(got, ref, rtol)


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


# ---------------------------------------------------------------- equality grid


@pytest.mark.parametrize("noise", NOISE_TYPES)
@pytest.mark.parametrize("data_type", ["freq", "phase"])
@pytest.mark.parametrize("stat", chunked.STATISTICS)
def test_matches_in_memory(stat, data_type, noise):
    data = _series(noise, data_type)
    chunk = CHUNKS[(chunked.STATISTICS.index(stat) + NOISE_TYPES.index(noise)) % 2]
    func = getattr(sigmatau, stat)
    ref = func(data, rate=50.0, data_type=data_type)
    got = func(chunked.from_array(data, chunk_size=chunk), rate=50.0, data_type=data_type)
    _assert_same(got, ref)


@pytest.mark.slow
@pytest.mark.parametrize("data_type", ["freq", "phase"])
def test_statistics_of_one_series_share_its_noise_identification(data_type, monkeypatch):
    """Every statistic computed on one ChunkedSeries reuses the noise identification the others
    already streamed (the lag-1 sums, B1, R(n) at each factor, each a pass over the file): each
    result equal, bit for bit, to the same statistic on a series of its own, with fewer
    identification passes in all."""
    from sigmatau.scale.chunked import noiseid as chunked_noiseid

    data = _series("FFM", data_type)
    calls = {"lag1": 0, "b1": 0}
    for name in calls:
        real = getattr(chunked_noiseid, f"_{name}")

        def counting(*args, _real=real, _name=name, **kwargs):
            calls[_name] += 1
            return _real(*args, **kwargs)

        monkeypatch.setattr(chunked_noiseid, f"_{name}", counting)
    order = ("oadev", "ohdev", "totdev", "mdev", "tdev", "adev", "hdev")
    shared = chunked.from_array(data, chunk_size=CHUNKS[1])
    got = {stat: getattr(sigmatau, stat)(shared, rate=50.0, data_type=data_type) for stat in order}
    with_sharing = dict(calls)
    calls.update(lag1=0, b1=0)
    for stat in order:
        alone = getattr(sigmatau, stat)(chunked.from_array(data, chunk_size=CHUNKS[1]), rate=50.0,
                                        data_type=data_type)
        for field in ("var", "alpha", "edf", "ci_low", "ci_high"):
            np.testing.assert_array_equal(getattr(got[stat], field), getattr(alone, field), err_msg=f"{stat} {field}")
        assert got[stat].ci_reason == alone.ci_reason, stat
    assert with_sharing["lag1"] < calls["lag1"] / 2, (with_sharing, calls)
    assert with_sharing["b1"] <= calls["b1"], (with_sharing, calls)


@pytest.mark.slow
@pytest.mark.parametrize("stat", ["mdev", "oadev", "ohdev"])
@pytest.mark.parametrize("noise", ["WFM", "RWFM"])
def test_long_record_frequency(stat, noise):
    # 10^6 samples and a chunk of 65537: long running sums, many blocks per factor.
    y = _series(noise, "freq", 1_000_003)
    ref = getattr(sigmatau, stat)(y, ci=None)
    got = chunked.compute(stat, y, chunk_size=65537, ci=None)
    _assert_same(got, ref)


@pytest.mark.parametrize("chunk", [16, 17, 1000, 1 << 18])
def test_factors_around_the_chunk_size(chunk):
    # m below, equal to and far above the chunk; a chunk larger than the record.
    y = _series("FFM", "freq", 20_011 if chunk >= 1000 else 2003)
    ms = [1, 2, 15, 16, 17, 100, 999, 1000, 1001, 4000, 6000] if chunk >= 1000 else [1, 2, 15, 16, 17, 33, 100, 500]
    for stat in chunked.STATISTICS:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sigmatau.RangeWarning)
            ref = getattr(sigmatau, stat)(y, m=ms, ci=None)
            got = getattr(sigmatau, stat)(chunked.from_array(y, chunk_size=chunk), m=ms, ci=None)
        _assert_same(got, ref)


@pytest.mark.parametrize("options", [
    dict(alpha=0), dict(ci="simple"), dict(ci=None), dict(confidence=0.95), dict(taus="all"),
    dict(taus=[0.02, 0.2, 2.0]), dict(taus="decade"),
])
def test_options_pass_through(options):
    y = _series("WFM", "freq", 3001 if options.get("taus") != "all" else 401)
    for stat in ("oadev", "mdev", "hdev"):
        ref = getattr(sigmatau, stat)(y, rate=50.0, **options)
        got = getattr(sigmatau, stat)(chunked.from_array(y, chunk_size=97), rate=50.0, **options)
        _assert_same(got, ref)


@pytest.mark.parametrize("bias", ["none", "auto", "published", "estimator"])
def test_totdev_bias(bias):
    y = _series("FFM", "freq", 30_011)
    ref = sigmatau.totdev(y, bias=bias)
    got = sigmatau.totdev(chunked.from_array(y, chunk_size=4099), bias=bias)
    _assert_same(got, ref)
    _assert_same(chunked.compute("totdev", y, chunk_size=4099, bias=bias), ref)


def test_noise_not_identified_has_the_same_reason():
    y = np.full(500, 3.0)  # constant: the autocorrelation is undefined
    for stat in ("oadev", "totdev"):
        ref = getattr(sigmatau, stat)(y)
        got = getattr(sigmatau, stat)(chunked.from_array(y, chunk_size=64))
        _assert_same(got, ref)
        assert "noise type not identified" in got.ci_reason[0]


def test_integer_and_bool_input():
    x = np.random.default_rng(5).integers(-1000, 1000, 5001)
    _assert_same(sigmatau.oadev(chunked.from_array(x, chunk_size=333), data_type="phase"),
                 sigmatau.oadev(x, data_type="phase"))
    b = np.random.default_rng(6).random(2001) < 0.5
    _assert_same(sigmatau.adev(chunked.from_array(b, chunk_size=333)), sigmatau.adev(b))
    col = x.reshape(-1, 1)
    _assert_same(sigmatau.mdev(chunked.from_array(col, chunk_size=333)), sigmatau.mdev(col))


# -------------------------------------------------------------------- sources


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("chunked")
    y = _series("RWFM", "freq", 50_021)
    paths = {"npy": folder / "y.npy", "f8": folder / "y.f8", "f4": folder / "y.f4", "i4": folder / "y.i4"}
    np.save(paths["npy"], y)
    y.astype("<f8").tofile(paths["f8"])
    y.astype("<f4").tofile(paths["f4"])
    with open(paths["i4"], "wb") as f:
        f.write(b"HEADER16bytes..!")
        np.round(y * 1e9).astype(">i4").tofile(f)
    return y, paths


def test_npy_file(files):
    y, paths = files
    before = _sha256(paths["npy"])
    for mmap in (False, True):
        src = chunked.from_npy(paths["npy"], mmap=mmap, chunk_size=7919)
        assert len(src) == y.size
        for stat in ("oadev", "mdev", "totdev"):
            _assert_same(getattr(sigmatau, stat)(src), getattr(sigmatau, stat)(y))
    _assert_same(chunked.compute("hdev", str(paths["npy"]), chunk_size=7919), sigmatau.hdev(y))
    assert _sha256(paths["npy"]) == before


def test_raw_binary_files(files):
    y, paths = files
    before = {k: _sha256(p) for k, p in paths.items()}
    _assert_same(chunked.compute("ohdev", paths["f8"], dtype="<f8", chunk_size=5003), sigmatau.ohdev(y))
    y4 = y.astype("<f4").astype(float)
    _assert_same(chunked.compute("tdev", paths["f4"], dtype="<f4", chunk_size=5003), sigmatau.tdev(y4))
    yi = np.round(y * 1e9).astype(">i4").astype(float)
    src = chunked.from_binary(paths["i4"], ">i4", offset=16, chunk_size=5003)
    _assert_same(sigmatau.adev(src, data_type="phase"), sigmatau.adev(yi, data_type="phase"))
    part = chunked.from_binary(paths["f8"], "<f8", offset=8 * 10, count=20_000, chunk_size=5003)
    _assert_same(sigmatau.oadev(part), sigmatau.oadev(y[10:20_010]))
    assert {k: _sha256(p) for k, p in paths.items()} == before


def test_hdf5_dataset(tmp_path):
    h5py = pytest.importorskip("h5py")
    y = _series("FFM", "phase", 40_009)
    path = tmp_path / "log.h5"
    with h5py.File(path, "w") as f:
        f.create_dataset("imu/gyro_x", data=y, chunks=(4096,))
        f["col"] = y.reshape(-1, 1)
    before = _sha256(path)
    with chunked.from_hdf5(path, "imu/gyro_x", chunk_size=6007) as src:
        for stat in ("adev", "mdev", "totdev"):
            _assert_same(getattr(sigmatau, stat)(src, data_type="phase"), getattr(sigmatau, stat)(y, data_type="phase"))
    _assert_same(chunked.compute("oadev", path, dataset="col", data_type="phase", chunk_size=6007),
                 sigmatau.oadev(y, data_type="phase"))
    assert _sha256(path) == before


@pytest.mark.slow
def test_dask_array():
    da = pytest.importorskip("dask.array")
    y = _series("WPM", "freq", 30_011)
    arr = da.from_array(y, chunks=7000)
    for stat in ("oadev", "mdev", "ohdev", "totdev"):
        ref = getattr(sigmatau, stat)(y)
        _assert_same(getattr(sigmatau, stat)(arr), ref)  # the public function takes the dask array itself
        _assert_same(chunked.compute(stat, arr, chunk_size=5003), ref)
    phase = da.from_array(_series("WFM", "phase", 30_011), chunks=4000)
    _assert_same(sigmatau.adev(chunked.from_dask(phase, chunk_size=3001), data_type="phase"),
                 sigmatau.adev(phase.compute(), data_type="phase"))


# --------------------------------------------------------------------- errors


def _one_line(exc: BaseException) -> str:
    text = str(exc)
    assert "\n" not in text and text
    return text


def test_non_finite_in_a_middle_chunk():
    # The NaN is a gap (tests/test_chunked_gaps.py), the inf an error: the in-memory one.
    y = _series("WFM", "freq", 50_000)
    y[31_337] = np.nan
    y[40_000] = np.inf
    with pytest.raises(DataError) as err:
        sigmatau.oadev(chunked.from_array(y, chunk_size=4096))
    with pytest.raises(DataError) as ref:
        sigmatau.oadev(y)
    assert _one_line(err.value) == str(ref.value)
    assert "1 infinite value" in str(ref.value) and "index 40000" in str(ref.value)


def test_too_short_and_empty():
    for data, dtype in (([1.0, 2.0], "phase"), ([1.0], "freq")):
        with pytest.raises(DataError) as err:
            sigmatau.oadev(chunked.from_array(np.array(data), chunk_size=16), data_type=dtype)
        with pytest.raises(DataError) as ref:
            sigmatau.oadev(np.array(data), data_type=dtype)
        assert _one_line(err.value) == str(ref.value)
    with pytest.raises(DataError, match="empty"):
        sigmatau.oadev(chunked.from_array(np.empty(0)))


@pytest.mark.parametrize("data_type", ["freq", "phase"])
@pytest.mark.parametrize("stat", chunked.STATISTICS)
def test_extreme_scales_match_in_memory(stat, data_type):
    # The in-memory path scales the data by a power of two; the streamed one did not
    # (before: mdev/tdev a DataError on a NaN variance, totdev a -inf noise estimate at 1e150).
    base = _series("WFM", data_type, 5003) * 1e9  # deviations near 1, so 1e±150 stays in float64
    func = getattr(sigmatau, stat)
    for scale in (1e-150, 1e-100, 1e100, 1e150):
        data = base * scale
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sigmatau.SigmaTauWarning)
            ref = func(data, rate=50.0, data_type=data_type)
            got = func(chunked.from_array(data, chunk_size=997), rate=50.0, data_type=data_type)
        _assert_same(got, ref)


@pytest.mark.parametrize("scale", [1e-170, 1e-300, 1e170])
def test_unrepresentable_variance_is_the_in_memory_error(scale):
    # Before: a silent 0 at 1e-170 and 1e-300 (squares underflow), a bare "-inf + inf in
    # fsum" ValueError from totdev at 1e170.
    data = _series("WFM", "freq", 5003) * 1e9 * scale
    for stat in chunked.STATISTICS:
        func = getattr(sigmatau, stat)
        with pytest.raises(DataError) as ref:
            func(data)
        with pytest.raises(DataError) as err:
            func(chunked.from_array(data, chunk_size=997))
        assert _one_line(err.value) == str(ref.value)


def test_bad_shapes_and_dtypes(tmp_path):
    with pytest.raises(DataError, match="1-D"):
        chunked.from_array(np.zeros((10, 3)))
    with pytest.raises(DataError, match="real numbers"):
        chunked.from_array(np.zeros(10, dtype=complex))
    np.save(tmp_path / "m.npy", np.zeros((100, 2)))
    np.save(tmp_path / "s.npy", np.array(["a", "b"]))
    np.save(tmp_path / "o.npy", np.array([{}, 1], dtype=object), allow_pickle=True)
    for name, match in (("m.npy", "1-D"), ("s.npy", "real numbers"), ("o.npy", "not a readable .npy")):
        with pytest.raises(DataError, match=match) as err:
            chunked.from_npy(tmp_path / name)
        _one_line(err.value)
    (tmp_path / "odd.bin").write_bytes(b"\0" * 12)
    with pytest.raises(DataError, match="whole number") as err:
        chunked.from_binary(tmp_path / "odd.bin", "<f8")
    _one_line(err.value)
    with pytest.raises(DataError, match="count=5"):
        chunked.from_binary(tmp_path / "odd.bin", "<f4", count=5)
    for bad in ("U3", "c16", "nonsense"):
        with pytest.raises(ParameterError):
            chunked.from_binary(tmp_path / "odd.bin", bad)
    with pytest.raises(ParameterError, match="dtype="):
        chunked.compute("oadev", tmp_path / "odd.bin")
    for size in (0, 8, 1.5, True):
        with pytest.raises(ParameterError, match="chunk_size"):
            chunked.from_array(np.zeros(100), chunk_size=size)


def test_missing_file_and_dataset(tmp_path):
    with pytest.raises(FileNotFoundError) as err:
        chunked.from_npy(tmp_path / "nope.npy")
    assert isinstance(err.value, DataError) and "nope.npy" in _one_line(err.value)
    with pytest.raises(FileNotFoundError):
        chunked.compute("oadev", tmp_path / "nope.bin", dtype="<f8")
    h5py = pytest.importorskip("h5py")
    with h5py.File(tmp_path / "a.h5", "w") as f:
        f["x"] = np.zeros(100)
    with pytest.raises(ParameterError, match="datasets: x") as err:
        chunked.from_hdf5(tmp_path / "a.h5", "y")
    _one_line(err.value)


def test_unsupported_statistics_and_names():
    src = chunked.from_array(np.random.default_rng(0).standard_normal(1000))
    for func in (sigmatau.mtotdev, sigmatau.theo1, sigmatau.theobr, sigmatau.mtie):
        with pytest.raises(ParameterError, match="chunked") as err:
            func(src)
        _one_line(err.value)
    with pytest.raises(ParameterError, match="statistic="):
        chunked.compute("theo1", src)


def test_statistics_without_a_streamed_form_refuse_any_dask_object_by_its_type():
    # The refusal looks at the type only: a 2-D dask array is not opened (nor its shape
    # judged) by a statistic that cannot take chunked data at all.
    da = pytest.importorskip("dask.array")
    for data in (da.zeros(1000, chunks=100), da.zeros((100, 2), chunks=50)):
        for stat in (sigmatau.theobr, sigmatau.theoh, sigmatau.theo1, sigmatau.mtotdev, sigmatau.mtie):
            with pytest.raises(ParameterError, match="does not accept chunked data"):
                stat(data)


def test_import_sigmatau_loads_neither_chunked_nor_dask():
    code = "import sys, sigmatau; print([m for m in ('sigmatau.chunked', 'dask', 'h5py') if m in sys.modules])"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


# --------------------------------------------------------------------- memory


@pytest.mark.slow
def test_peak_memory_follows_the_chunk_not_the_record(tmp_path):
    # A real property of the algorithm: every pass holds a fixed number of
    # chunk-sized arrays (about 30 for MDEV of frequency data, the deepest).
    n, chunk = 2_000_000, 1 << 14
    path = tmp_path / "long.npy"
    np.save(path, _series("RWFM", "freq", n))
    ms = [1, 8, 1000, 100_000]  # the last one six times the chunk
    for stat in ("oadev", "mdev", "totdev"):  # warm up: first-call imports allocate too
        chunked.compute(stat, np.random.default_rng(0).standard_normal(2000), m=[1, 4])
    chunk_bytes = 8 * chunk
    for stat in ("oadev", "mdev", "totdev"):
        src = chunked.from_npy(path, chunk_size=chunk)
        tracemalloc.start()
        try:
            got = chunked.compute(stat, src, m=ms)
            chunked_peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        tracemalloc.start()
        try:
            ref = getattr(sigmatau, stat)(np.load(path), m=ms)
            memory_peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        _assert_same(got, ref)
        assert chunked_peak < 48 * chunk_bytes, (stat, chunked_peak / chunk_bytes)
        assert memory_peak > 8 * n  # the in-memory path holds at least the record
        assert chunked_peak < memory_peak / 4, (stat, chunked_peak, memory_peak)
