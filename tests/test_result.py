"""StabilityResult: immutability, conversions to dict/table/CSV, repr and len."""

from __future__ import annotations

import csv
import dataclasses
import io
import json

import numpy as np
import pytest

import sigmatau
from sigmatau import StabilityResult
from sigmatau.datasets import nbs1000

ARRAY_FIELDS = ("taus", "m", "var", "dev", "n", "bias_factor", "alpha", "alpha_estimate",
                "edf", "ci_low", "ci_high")


@pytest.fixture
def result():
    return sigmatau.oadev(nbs1000(), m=[1, 10, 100], ci=None)  # the bare estimator; uncertainty fields tested elsewhere


@pytest.fixture
def full():
    """A result with every optional field filled, as later stages will produce."""
    return StabilityResult(
        statistic="oadev",
        taus=[1.0, 10.0],
        m=[1, 10],
        var=[0.0854, 0.00839],
        dev=[0.2922319, 0.09159953],
        n=[999, 981],
        rate=1.0,
        data_type="freq",
        n_points=1001,
        bias="none",
        bias_factor=[1.0, 1.0],
        alpha=[0, 0],
        alpha_estimate=[0.05, 0.36],
        edf=[782.03, 135.071],
        ci_low=[0.2851145, 0.08649995],
        ci_high=[0.2999103, 0.09772219],
        confidence=0.6827,
        ci_reason=("greenhall", "greenhall"),
    )


@pytest.fixture
def empty():
    return StabilityResult("adev", [], [], [], [], [], rate=1.0, data_type="phase", n_points=2)


def test_frozen(result):
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.dev = np.zeros(3)
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.statistic = "adev"
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.edf = np.ones(3)


def test_arrays_read_only(result, full):
    for r in (result, full):
        for name in ARRAY_FIELDS:
            arr = getattr(r, name)
            if arr is None:
                continue
            assert isinstance(arr, np.ndarray)
            assert not arr.flags.writeable
            with pytest.raises(ValueError):
                arr[0] = arr[0]
    with pytest.raises(ValueError):
        result.dev.sort()


def test_arrays_copied_on_construction():
    dev = np.array([1.0, 2.0])
    r = StabilityResult("adev", [1.0, 2.0], [1, 2], dev**2, dev, [5, 4], rate=1.0,
                        data_type="freq", n_points=11)
    dev[0] = 99.0
    assert r.dev.tolist() == [1.0, 2.0]
    # the caller's array stays writeable
    assert dev.flags.writeable


def test_len(result, full, empty):
    assert len(result) == 3
    assert len(full) == 2
    assert len(empty) == 0
    assert len(sigmatau.adev(nbs1000(), taus="all")) == 200


def test_to_dict_json(result, full, empty):
    for r in (result, full, empty):
        d = r.to_dict()
        assert list(d) == [f.name for f in dataclasses.fields(StabilityResult)]
        text = json.dumps(d)
        back = json.loads(text)
        assert back == d
        for name in ARRAY_FIELDS:
            value = getattr(r, name)
            if value is None:
                assert d[name] is None
            else:
                assert d[name] == value.tolist()
    d = result.to_dict()
    assert d["statistic"] == "oadev"
    assert d["m"] == [1, 10, 100]
    assert d["n"] == [999, 981, 801]
    assert d["dev"] == result.dev.tolist()  # full precision, not rounded
    assert d["rate"] == 1.0 and d["data_type"] == "freq" and d["n_points"] == 1001
    assert d["bias"] == "none" and d["edf"] is None
    assert full.to_dict()["ci_reason"] == ["greenhall", "greenhall"]
    assert full.to_dict()["confidence"] == 0.6827


def test_to_dict_is_detached(result):
    d = result.to_dict()
    d["dev"][0] = -1.0
    assert result.dev[0] > 0


def _table_rows(text):
    lines = text.splitlines()
    return lines[0], lines[1].split(), [line.split() for line in lines[2:]]


def test_to_table(result):
    title, header, rows = _table_rows(result.to_table())
    for part in ("oadev", "freq", "rate 1 Hz", "N = 1001", "bias: none"):
        assert part in title
    assert header == ["m", "tau", "[s]", "n", "dev"]
    assert len(rows) == len(result)
    for row, m, tau, n, dev in zip(rows, result.m, result.taus, result.n, result.dev):
        assert int(row[0]) == m and int(row[2]) == n
        assert float(row[1]) == tau
        np.testing.assert_allclose(float(row[3]), dev, rtol=5e-7)
    assert str(result) == result.to_table()


def test_to_table_optional_columns(full):
    title, header, rows = _table_rows(full.to_table())
    assert header == ["m", "tau", "[s]", "n", "alpha", "min", "dev", "dev", "max", "dev", "edf"]
    assert rows[0][:4] == ["1", "1.000000e+00", "999", "0"]
    np.testing.assert_allclose([float(v) for v in rows[1][4:]],
                               [0.08649995, 0.09159953, 0.09772219, 135.07], rtol=5e-7)


def test_to_table_columns_aligned(result):
    lines = result.to_table().splitlines()[1:]
    assert len({len(line) for line in lines}) == 1


def test_to_csv(result, full):
    for r in (result, full):
        rows = list(csv.reader(io.StringIO(r.to_csv())))
        assert rows[0] == r.columns()
        assert len(rows) == len(r) + 1
        for i, row in enumerate(rows[1:]):
            for col, cell in zip(rows[0], row):
                expected = getattr(r, col)[i]
                # full precision: the text reads back to the same number
                assert float(cell) == expected
                if col in ("m", "n", "alpha"):
                    assert cell == str(int(expected))
    assert result.columns() == ["m", "taus", "n", "dev"]
    assert full.columns() == ["m", "taus", "n", "alpha", "ci_low", "dev", "ci_high", "edf"]


def test_empty_outputs(empty):
    assert empty.to_csv() == "m,taus,n,dev\n"
    assert len(empty.to_table().splitlines()) == 2
    assert "empty" in repr(empty)


def test_repr(result, full, empty):
    for r in (result, full, empty):
        text = repr(r)
        assert "\n" not in text
        assert len(text) <= 120
        assert text.startswith("StabilityResult(")
        assert r.statistic in text
    text = repr(result)
    assert "3 τ" in text and "freq" in text
    assert "array" not in text  # no array dump
    assert repr(sigmatau.oadev(nbs1000(), taus="all")).count(",") < 10
