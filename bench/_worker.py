"""One measurement in a fresh process; started by bench/run.py, not meant to be run by hand.

Usage: ``python bench/_worker.py '<json spec>'``. The spec says what to measure
(``mode`` "time" or "mem"), which library (``lib``), which statistic, the data
(``n``, ``noise``, ``seed``) and, for peers, the averaging factors ``m``.

The worker regenerates the seeded data itself (the same bytes in every worker;
it reports a digest so that the parent can check) and prints one line per event,
prefixed with ``@@bench`` and followed by JSON, so that whatever a library prints
on stdout cannot be mistaken for a result. A parent that kills the worker on a
timeout still gets every event printed before.
"""

from __future__ import annotations

import gc
import hashlib
import json
import resource
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

PREFIX = "@@bench "
#: α of the power-law noise types accepted by ``noise``.
NOISE_ALPHA = {"wpm": 2, "fpm": 1, "wfm": 0, "ffm": -1, "rwfm": -2}


def emit(event: str, **fields: object) -> None:
    sys.stdout.write(PREFIX + json.dumps({"event": event, **fields}) + "\n")
    sys.stdout.flush()


def make_data(n: int, noise: str, seed: int) -> np.ndarray:
    """``n`` centred fractional-frequency samples at 1 Hz.

    Centred so that MTIE and TIE rms, which are not invariant to a frequency
    offset, see the same phase in both libraries: allantools removes the mean
    frequency when it integrates, sigmatau integrates the samples as given.
    White FM is drawn directly (no temporaries: the memory runs rely on that).
    """
    rng = np.random.default_rng(seed)
    if noise == "wfm":
        y = rng.standard_normal(n)
    else:
        from sigmatau.generate import power_law_noise

        y = power_law_noise(n, NOISE_ALPHA[noise], rng=rng)
    y -= y.mean()
    return y


def digest(y: np.ndarray) -> str:
    return hashlib.sha1(y.tobytes()).hexdigest()[:16]


def source_digest() -> str:
    """Digest of sigmatau's source files as this process sees them.

    The code may change while a long run goes on (other work on the same
    checkout); the parent reports when the measurements saw different versions.
    """
    import sigmatau

    h = hashlib.sha1()
    root = Path(sigmatau.__file__).parent
    for path in sorted(root.rglob("*.py")):
        h.update(str(path.relative_to(root)).encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:12]


def make_call(spec: dict, y: np.ndarray):
    """A no-argument callable running the requested statistic, and a function
    turning its result into ``(m, dev)`` lists."""
    lib, stat = spec["lib"], spec["stat"]
    m = spec.get("m")
    if lib in ("sigmatau", "sigmatau-default"):
        import sigmatau

        func = getattr(sigmatau, stat)
        kwargs: dict = {"rate": 1.0, "data_type": "freq"}
        if m is not None:
            kwargs["m"] = np.asarray(m, dtype=np.int64)
        if lib == "sigmatau":
            kwargs["ci"] = None

        def values(res):
            return [int(v) for v in res.m], [float(v) for v in res.dev]

        return (lambda: func(y, **kwargs)), values
    if lib == "allantools":
        import allantools as module
    elif lib == "compat":
        import sigmatau.compat.allantools as module
    else:
        raise SystemExit(f"unknown lib {lib!r}")
    func = getattr(module, stat)
    # τ = m·τ0 at 1 Hz, also for Theo1 (allantools' convention for its τ).
    taus = np.asarray(m, dtype=float)

    def values(res):
        return [int(round(t)) for t in res[0]], [float(v) for v in res[1]]

    return (lambda: func(y, rate=1.0, data_type="freq", taus=taus)), values


def time_job(spec: dict) -> None:
    y = make_data(spec["n"], spec["noise"], spec["seed"])
    emit("data", digest=digest(y), src=source_digest())
    call, values = make_call(spec, y)
    spent = 0.0
    for k in range(spec["repeat"]):
        gc.collect()
        t0 = time.perf_counter()
        res = call()
        dt = time.perf_counter() - t0
        spent += dt
        if k == 0:
            m, dev = values(res)
            emit("values", m=m, dev=dev)
        emit("run", seconds=dt)
        del res
        if spent >= spec["budget"]:
            break
    emit("done")


def _rss_now_kib() -> int:
    with open("/proc/self/statm") as fh:
        pages = int(fh.read().split()[1])
    return pages * resource.getpagesize() // 1024


def mem_job(spec: dict) -> None:
    import sigmatau

    func = getattr(sigmatau, spec["stat"])
    kwargs = {"rate": 1.0, "data_type": "freq"}
    if spec.get("ci") == "none":
        kwargs["ci"] = None
    # Warm-up on a short record: lazy imports, FFT plans and caches are not the
    # statistic's working memory.
    func(make_data(4096, "wfm", spec["seed"]), **kwargs)
    y = make_data(spec["n"], "wfm", spec["seed"])
    emit("data", digest=digest(y), src=source_digest())
    gc.collect()
    hwm_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # KiB on Linux
    rss_before = _rss_now_kib()
    tracemalloc.start()
    t0 = time.perf_counter()
    res = func(y, **kwargs)
    dt = time.perf_counter() - t0
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    hwm_after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    emit("mem", seconds=dt, input_bytes=int(y.nbytes), tracemalloc_peak=int(peak),
         hwm_before_kib=int(hwm_before), rss_before_kib=int(rss_before),
         hwm_after_kib=int(hwm_after), n_tau=int(len(res)))
    emit("done")


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    spec = json.loads(argv[0])
    if spec["mode"] == "time":
        time_job(spec)
    elif spec["mode"] == "mem":
        mem_job(spec)
    else:
        raise SystemExit(f"unknown mode {spec['mode']!r}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
