"""Sustained throughput of ``sigmatau.stream.Stream.update``: six channels on one core.

One command::

    python bench/stream.py                              # 6 channels, 2**22 samples each, max_m 2**18
    python bench/stream.py --chunks 1000 --samples 3e6  # one chunk size, a shorter record
    python bench/stream.py --max-m 1048576 --samples 8e6

The data are seeded white FM plus a little random-walk FM (``--seed``), float64, rate
1 kHz, ``(samples, channels)``. For each chunk size a fresh stream with the default
statistics (OADEV, OHDEV, MDEV, TDEV, TOTDEV, noise identification and χ² intervals
when read) is first fed ``4·max_m`` samples untimed, so that every averaging factor up to
``max_m`` has terms, then the rest of the record is fed in chunks of that size and timed:
wall time (``time.perf_counter``) and the process's CPU time. The figure is samples per
second summed over the channels; the best of ``--repeat`` runs. ``results()`` (every
statistic of channel 0, with noise types and intervals) is timed once at the end.

If allantools is importable, ``allantools.oadev(y, rate, data_type="freq", taus="octave")``
times each channel of the same record, in memory and once (one statistic, no noise
identification), and the ratio of the two rates is printed: the stream's statistics are
available at any moment, allantools' once the record is complete. Both run in this process,
one after the other, so the ratio is the trustworthy figure on a busy machine; the load
average before and after is printed. ``Stream.nbytes`` gives the state's size.
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import sys
import time

import numpy as np


def _machine() -> str:
    cpu = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    import sigmatau

    return (f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, numpy {np.__version__},"
            f" sigmatau {sigmatau.__version__}")


def _load() -> str:
    try:
        return "{:.2f} {:.2f} {:.2f}".format(*os.getloadavg())
    except OSError:
        return "n/a"


def make_data(samples: int, channels: int, seed: int) -> np.ndarray:
    """White FM plus random-walk FM 1000 times weaker per sample, ``(samples, channels)``."""
    rng = np.random.default_rng(seed)
    data = rng.standard_normal((samples, channels))
    data += np.cumsum(rng.standard_normal((samples, channels)), axis=0) * 1e-3
    return data


def time_stream(data: np.ndarray, chunk: int, max_m: int, rate: float) -> dict:
    """Feed ``data`` to a fresh stream; time everything after the first ``4·max_m`` samples."""
    from sigmatau.stream import Stream

    stream = Stream(rate, max_m=max_m)
    warm = min(4 * max_m, data.shape[0] // 2)
    for lo in range(0, warm, chunk):
        stream.update(data[lo : min(lo + chunk, warm)])
    gc.collect()
    t_wall, t_cpu = time.perf_counter(), time.process_time()
    for lo in range(warm, data.shape[0], chunk):
        stream.update(data[lo : lo + chunk])
    wall, cpu = time.perf_counter() - t_wall, time.process_time() - t_cpu
    timed = (data.shape[0] - warm) * data.shape[1]
    t0 = time.perf_counter()
    stream.results()
    read = time.perf_counter() - t0
    return {"wall": timed / wall, "cpu": timed / cpu, "results_s": read, "nbytes": stream.nbytes,
            "rows": len(stream.result("oadev"))}


def time_allantools(data: np.ndarray, rate: float) -> float | None:
    """Samples per second of allantools' OADEV over every channel, or None without allantools."""
    try:
        import allantools
    except ImportError:
        return None
    allantools.oadev(data[:4096, 0], rate=rate, data_type="freq", taus="octave")  # warm-up
    gc.collect()
    t0 = time.perf_counter()
    for ch in range(data.shape[1]):
        allantools.oadev(np.ascontiguousarray(data[:, ch]), rate=rate, data_type="freq", taus="octave")
    return data.size / (time.perf_counter() - t0)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=float, default=2**22, help="samples per channel (default 2**22)")
    ap.add_argument("--channels", type=int, default=6)
    ap.add_argument("--chunks", default="1000,100000", help="chunk sizes, comma-separated")
    ap.add_argument("--max-m", type=int, default=2**18, help="the streams' max_m (default 2**18)")
    ap.add_argument("--rate", type=float, default=1000.0)
    ap.add_argument("--repeat", type=int, default=2, help="best of this many runs per chunk size")
    ap.add_argument("--seed", type=int, default=20240601)
    ap.add_argument("--no-peer", action="store_true", help="do not time allantools")
    args = ap.parse_args(argv)

    samples = int(args.samples)
    print(f"machine: {_machine()}")
    print(f"load average before: {_load()}")
    data = make_data(samples, args.channels, args.seed)
    print(f"data: {samples} samples x {args.channels} channels, max_m {args.max_m}, rate {args.rate:g} Hz")
    best: dict[int, dict] = {}
    for chunk in (int(float(c)) for c in args.chunks.split(",")):
        runs = [time_stream(data, chunk, args.max_m, args.rate) for _ in range(args.repeat)]
        best[chunk] = max(runs, key=lambda r: r["wall"])
        r = best[chunk]
        print(f"stream, chunks of {chunk:>7}: {r['wall'] / 1e6:6.2f} M samples/s wall, {r['cpu'] / 1e6:6.2f} M/s CPU"
              f" ({args.channels} channels); results() {r['results_s']:.3f} s ({r['rows']} OADEV rows);"
              f" state {r['nbytes'] / 1e6:.1f} MB")
    peer = None if args.no_peer else time_allantools(data, args.rate)
    if peer is None:
        print("allantools: not timed" + ("" if args.no_peer else " (not importable)"))
    else:
        print(f"allantools.oadev, whole record per channel: {peer / 1e6:6.2f} M samples/s")
        for chunk, r in best.items():
            print(f"ratio stream (chunks of {chunk}) / allantools oadev: {r['wall'] / peer:.2f}")
    target = 1e7
    for chunk, r in best.items():
        verdict = "met" if r["wall"] >= target else "not met"
        print(f"target >= 1e7 samples/s for {args.channels} channels, chunks of {chunk}: {verdict}")
    print(f"load average after: {_load()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
