"""Wall time and peak memory of chunked statistics against the in-memory path, on one large file.

One command::

    python bench/chunked_memory.py                 # N = 5e7 (400 MB .npy), oadev, mdev, totdev
    python bench/chunked_memory.py --n 2e6 --stats oadev     # a quick look

The script writes seeded noise (white FM by default) to a ``.npy`` file in a
temporary directory, chunk by chunk, then measures each statistic twice, each
time in a fresh process:

* chunked: ``sigmatau.<stat>(sigmatau.chunked.from_npy(path, chunk_size=...))``;
* in memory: ``sigmatau.<stat>(np.load(path))`` (the load is timed separately).

Both use the octave τ grid and the default uncertainty (noise identification,
EDF, χ² interval). Memory is reported two ways: the ``tracemalloc`` peak
(every NumPy buffer) and the growth of the resident high-water mark
(``VmHWM``, restarted just before the data is touched; ``ru_maxrss`` where
that is impossible) over the resident size at that moment. The
file is read from the page cache (it was just written): the times exclude
disk reads. The largest relative difference of the two variances is printed too.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

STATS = ("adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "totdev")


def _rss_kib() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * (os.sysconf("SC_PAGE_SIZE") // 1024)


def _reset_high_water() -> bool:
    """Restart the resident high-water mark (Linux ≥ 4.0): ``ru_maxrss`` would also count the
    parent's memory, which the child shares between fork and exec."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        return True
    except OSError:
        return False


def _high_water_kib(reset: bool) -> int:
    if reset:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def child(spec: dict) -> None:
    import sigmatau
    from sigmatau import chunked

    func = getattr(sigmatau, spec["stat"])
    func(np.random.default_rng(0).standard_normal(4096))  # imports done before measuring
    gc.collect()
    reset = _reset_high_water()
    rss0 = _rss_kib()
    tracemalloc.start()
    t0 = time.perf_counter()
    if spec["mode"] == "chunked":
        data = chunked.from_npy(spec["path"], chunk_size=spec["chunk"])
    else:
        data = np.load(spec["path"])
    t_load = time.perf_counter() - t0
    res = func(data, data_type=spec["data_type"])
    seconds = time.perf_counter() - t0 - t_load
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    hwm = _high_water_kib(reset)
    print(json.dumps({"seconds": seconds, "load": t_load, "tracemalloc": peak, "rss_growth_kib": max(hwm - rss0, 0),
                      "var": res.var.tolist(), "n_tau": len(res)}))


def write_series(path: Path, n: int, noise: str, seed: int, chunk: int = 1 << 22) -> None:
    """Seeded white FM (or random-walk FM) samples written piece by piece into a .npy file."""
    rng = np.random.default_rng(seed)
    out = np.lib.format.open_memmap(path, mode="w+", dtype=np.float64, shape=(n,))
    level = 0.0
    for a in range(0, n, chunk):
        w = rng.standard_normal(min(chunk, n - a))
        if noise == "rwfm":
            w = np.cumsum(w) + level
            level = float(w[-1])
        out[a : a + w.size] = w * 1e-9
    out.flush()
    del out


def run_child(spec: dict) -> dict:
    proc = subprocess.run([sys.executable, __file__, "--child", json.dumps(spec)], capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise SystemExit(f"{spec['stat']} {spec['mode']} failed: {proc.stderr.strip().splitlines()[-1:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=float, default=5e7, help="samples (default 5e7 = 400 MB)")
    parser.add_argument("--stats", default="oadev,mdev,totdev", help=f"comma-separated, from {', '.join(STATS)}")
    parser.add_argument("--chunk", type=int, default=None, help="chunk size in samples (default: the library's)")
    parser.add_argument("--noise", choices=("wfm", "rwfm"), default="wfm")
    parser.add_argument("--data-type", choices=("freq", "phase"), default="freq")
    parser.add_argument("--seed", type=int, default=20240601)
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        child(json.loads(args.child))
        return 0
    from sigmatau.chunked import DEFAULT_CHUNK

    n = int(args.n)
    chunk = args.chunk or DEFAULT_CHUNK
    stats = [s for s in args.stats.split(",") if s]
    bad = sorted(set(stats) - set(STATS))
    if bad:
        parser.error(f"unknown statistic(s) {bad}")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "series.npy"
        t0 = time.perf_counter()
        write_series(path, n, args.noise, args.seed)
        print(f"# {n:.3g} {args.noise} samples ({path.stat().st_size / 1e6:.0f} MB) written in"
              f" {time.perf_counter() - t0:.1f} s; chunk {chunk} samples ({8 * chunk / 2**20:.1f} MiB)", flush=True)
        for stat in stats:
            out = {}
            for mode in ("chunked", "memory"):
                spec = {"stat": stat, "mode": mode, "path": str(path), "chunk": chunk, "data_type": args.data_type}
                out[mode] = run_child(spec)
                m = out[mode]
                print(f"  {stat:6s} {mode:7s} {m['seconds']:8.1f} s (+{m['load']:.1f} s load)"
                      f"  tracemalloc {m['tracemalloc'] / 2**20:8.1f} MiB"
                      f"  RSS growth {m['rss_growth_kib'] / 1024:8.1f} MiB", flush=True)
            a, b = np.array(out["chunked"]["var"]), np.array(out["memory"]["var"])
            rel = float(np.max(np.abs(a / b - 1))) if a.shape == b.shape else float("nan")
            rows.append((stat, out, rel))
    print()
    print(f"N = {n:.3g} ({8 * n / 1e6:.0f} MB float64), {args.noise} {args.data_type} data, octave grid,"
          f" default uncertainty; chunk {chunk} samples ({8 * chunk / 2**20:.1f} MiB); warm page cache")
    print()
    print("| statistic | path | time (s) | tracemalloc peak (MiB) | RSS growth (MiB) | max rel. diff of var |")
    print("|---|---|---:|---:|---:|---:|")
    for stat, out, rel in rows:
        for mode in ("chunked", "memory"):
            m = out[mode]
            label = "chunked" if mode == "chunked" else "in memory (np.load + call)"
            t = m["seconds"] + (m["load"] if mode == "memory" else 0.0)
            print(f"| {stat} | {label} | {t:.1f} | {m['tracemalloc'] / 2**20:.1f} | {m['rss_growth_kib'] / 1024:.1f} |"
                  f" {'' if mode == 'memory' else f'{rel:.1e}'} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
