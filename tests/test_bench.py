"""The benchmark command bench/run.py (its plan, its verdicts and one tiny real run).

The real run uses ``--tiny`` (300-sample records) restricted to one statistic,
so it checks the command end to end (worker processes, allantools, report
files) in a few seconds; the numbers it produces mean nothing. It is skipped
when allantools is not installed (``pip install -e ".[bench]"``).
"""

from __future__ import annotations

import csv
import importlib.util
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parent.parent / "bench"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_run", BENCH / "run.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["bench_run"] = module  # dataclasses look their module up by name
    spec.loader.exec_module(module)
    yield module
    sys.modules.pop("bench_run", None)


def test_tiny_plan_covers_every_target(bench):
    args = bench.build_parser().parse_args(["--tiny"])
    timing, memory, sizes = bench.build_plan(args)
    assert set(sizes.values()) == {300}
    planned = {(c.stat, c.n) for c in timing}
    for target in bench.TARGETS:
        if target.kind == "memory":
            assert sorted(mc.stat for mc in memory) == sorted(target.stats)
        else:
            assert all((s, 300) in planned for s in target.stats), target.key
    assert ("oadev", 300) in planned  # the "own" targets divide by our OADEV time
    with pytest.raises(SystemExit):
        bench.build_parser().parse_args(["--tiny", "--quick"])


def _meas(bench, variant, seconds=None, mem=None, timed_out=False):
    m = bench.Measurement(variant=variant, timed_out=timed_out, timeout=10.0)
    if seconds is not None:
        m.runs = [seconds]
    m.mem = mem
    return m


def test_verdicts(bench):
    args = bench.build_parser().parse_args(["--tiny"])
    timing, memory, sizes = bench.build_plan(args)
    report = bench.Report(args=args, argv=["--tiny"], machine=bench.machine_info(), timing=timing,
                          memory=memory, target_sizes=sizes)
    speeds = {"adev": 1.0, "oadev": 2.0, "mdev": 0.5}  # allantools time / ours
    for c in timing:
        c.results["sigmatau"] = _meas(bench, "sigmatau", 1.0)
        if c.stat in speeds:
            c.results["allantools"] = _meas(bench, "allantools", speeds[c.stat])
    mem = {"tracemalloc_peak": 2400, "input_bytes": 2400, "hwm_before_kib": 0, "rss_before_kib": 0,
           "hwm_after_kib": 0, "seconds": 0.1}
    memory[0].result = _meas(bench, "memory", mem=mem)
    memory[1].result = _meas(bench, "memory", mem=dict(mem, tracemalloc_peak=24000))
    memory[2].result = _meas(bench, "memory", timed_out=True)
    rows = {r["target"]: r for r in report.evaluate()}
    assert rows["classic"]["verdict"] == "not met"  # mdev is slower
    assert "adev 1×" in rows["classic"]["measured"] and "oadev 2×" in rows["classic"]["measured"]
    assert rows["theo1-own"]["verdict"] == "met" and "1× OADEV" in rows["theo1-own"]["measured"]
    assert rows["memory"]["verdict"] == "not met"  # 10× is not under 10×
    assert "timed out" in rows["memory"]["measured"]
    assert "theo1-peer" not in rows  # no allantools time: nothing to judge
    text = report.markdown()
    assert "## Targets" in text and "| classic | 300 |" in text


@pytest.mark.slow
def test_tiny_run_end_to_end(bench, tmp_path):
    pytest.importorskip("allantools")
    out = tmp_path / "smoke.md"
    code = bench.main(["--tiny", "--stats", "oadev", "--repeat", "1", "--no-compat", "--no-default", "--out", str(out)])
    assert code == 0
    text = out.read_text()
    assert "(mode: tiny)" in text
    assert "| classic | 300 |" in text and "| memory | 300 |" in text
    with out.with_suffix(".csv").open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    kinds = {(r.get("kind") or r.get("section") or "", r.get("statistic") or r.get("stat") or "") for r in rows}
    assert any("oadev" in k[1] for k in kinds), rows[:2]
    assert "DATA DIFFER" not in text
