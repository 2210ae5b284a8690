"""The main job of issue 13 ("a day at 1 kHz in a minute"): time ``sigmatau analyze`` on
6-channel IMU logs at 1 kHz, against allantools' OADEV on the same six channels.

    python bench/main_job.py                              # 1 h and 6 h records, .npz and CSV
    python bench/main_job.py --hours 24 --formats npy     # a day, binary only

1. Writes seeded 6-channel logs (gyro x/y/z in rad/s, accel x/y/z in m/s^2, 1000 Hz) once and
   keeps them under ``--data`` (default bench/data-main/, git-ignored); a later run reuses them.
   ``npy`` is an uncompressed ``.npz`` (one float64 array per channel, named gyro_x … accel_z,
   plus ``rate``), which ``sigmatau analyze`` reads with its rate and channel names and nothing
   else on the command line; ``csv`` has the header
   ``timestamp [ns],gyro_x [rad/s],…,accel_z [m/s^2]``, the same samples written with 9
   significant digits (float32 precision, what a sensor gives) and integer ns timestamps.
2. Times ``sigmatau analyze LOG --out DIR --no-figures --force`` in a subprocess (wall time; peak
   RSS of the child from ``getrusage(RUSAGE_CHILDREN)`` in a fresh wrapper process per
   measurement), and ``allantools.oadev(y, rate=1000, data_type="freq", taus="octave")`` on the
   same six channels (one fresh process loads the .npz and times the six calls).
3. Prints a Markdown table with the machine, and writes it atomically to
   bench/results/main-job-<date>-<time>.md (rewritten after every measurement).

bench/README.md ("Main job") describes it.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path
from typing import Optional

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(HERE))
from run import _git, _version, machine_info, md_table, write_atomic  # noqa: E402  (bench/run.py)

CHANNELS = ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
UNITS = {"gyro": "rad/s", "accel": "m/s^2"}
#: The simulated IMU (SI units): LSM6DSL datasheet white noise (the presets) with the bias
#: instability and random walk of a typical consumer MEMS part, as `sigmatau simulate` and the
#: demo use (sigmatau.cli.simulate.DEMO_IMU), so the σ–τ curves show the whole bathtub.
SPEC = {
    "gyro": {"preset": "lsm6dsl-gyro", "B": 2.4e-5, "K": 1.5e-6},
    "accel": {"preset": "lsm6dsl-accel", "B": 2.0e-4, "K": 2.0e-5},
}
T0_NS = 1_700_000_000_000_000_000  # first timestamp of the CSV logs (2023-11-14T22:13:20Z)
GENERATOR = "v1"  # bump when the generated data change (part of the cached file names)

#: Fresh wrapper process around one measured command: its RUSAGE_CHILDREN covers that child only.
WRAPPER = r"""
import json, resource, subprocess, sys, time
cmd, timeout = json.loads(sys.argv[1]), float(sys.argv[2])
t = time.perf_counter()
try:
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=timeout)
    rc, out, err = p.returncode, p.stdout, p.stderr
except subprocess.TimeoutExpired as exc:
    rc, out, err = "timeout", exc.stdout or b"", exc.stderr or b""
wall = time.perf_counter() - t
ru = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({"rc": rc, "wall_s": wall, "maxrss_kib": ru.ru_maxrss, "user_s": ru.ru_utime,
                  "sys_s": ru.ru_stime, "stdout": out.decode(errors="replace")[-4000:],
                  "stderr": err.decode(errors="replace")[-2000:]}))
"""

#: allantools on the six channels of one .npz: load, then time each oadev call.
ALLAN = r"""
import json, sys, time
import numpy as np
import allantools
t = time.perf_counter()
with np.load(sys.argv[1]) as z:
    rate = float(z["rate"])
    chans = {k: z[k] for k in json.loads(sys.argv[2])}
load = time.perf_counter() - t
times, first = {}, None
for k, y in chans.items():
    t = time.perf_counter()
    taus, dev, err, ns = allantools.oadev(y, rate=rate, data_type="freq", taus="octave")
    times[k] = time.perf_counter() - t
    if first is None:
        first = {"taus": [float(v) for v in taus], "dev": [float(v) for v in dev]}
print(json.dumps({"load_s": load, "times": times, "total_s": sum(times.values()), "first": first}))
"""


# --- data ------------------------------------------------------------------------------


def samples(hours: float, rate: float) -> int:
    return int(round(hours * 3600 * rate))


def hours_label(hours: float) -> str:
    return f"{hours:g}h".replace(".", "p")


def log_path(data: Path, hours: float, rate: float, seed: int, fmt: str) -> Path:
    ext = ".npz" if fmt == "npy" else ".csv"
    return data / f"imu-{hours_label(hours)}-{rate:g}Hz-seed{seed}-{GENERATOR}{ext}"


def simulate_channel(name: str, hours: float, rate: float, seed: int):
    """One channel, its own seeded stream (channel j of SeedSequence(seed).spawn(6))."""
    import numpy as np

    from sigmatau.imu import simulate

    group = name.split("_")[0]
    s = SPEC[group]
    stream = np.random.SeedSequence(seed).spawn(len(CHANNELS))[CHANNELS.index(name)]
    return simulate(s["preset"], duration=hours * 3600, rate=rate, unit=UNITS[group], B=s["B"], K=s["K"],
                    rng=np.random.default_rng(stream))


def write_npz(path: Path, hours: float, rate: float, seed: int) -> None:
    """An uncompressed .npz written one channel at a time (memory: one channel being generated).

    The channel is the block: the bias-instability (flicker) term is one FFT convolution over the
    whole record, so a channel cannot be cut into independent pieces without changing its
    long-τ statistics.
    """
    import numpy as np

    tmp = path.with_name(f".{path.name}.tmp")
    try:
        with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_STORED, allowZip64=True) as zf:
            for name in CHANNELS:
                y = simulate_channel(name, hours, rate, seed)
                with zf.open(f"{name}.npy", "w", force_zip64=True) as fh:
                    np.lib.format.write_array(fh, np.ascontiguousarray(y, dtype=np.float64))
                del y
            with zf.open("rate.npy", "w") as fh:
                np.lib.format.write_array(fh, np.float64(rate))
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def write_csv(path: Path, npz: Path, block: int = 200_000) -> None:
    """The .npz's samples as CSV with ns timestamps, written in blocks of rows."""
    import numpy as np

    with np.load(npz) as z:
        rate = float(z["rate"])
        cols = [z[k] for k in CHANNELS]
    n = cols[0].size
    step_ns = 1e9 / rate
    if step_ns != int(step_ns):
        raise SystemExit(f"rate {rate:g} Hz: the step is not a whole number of ns")
    header = "timestamp [ns]," + ",".join(f"{k} [{UNITS[k.split('_')[0]]}]" for k in CHANNELS)
    row = "%d" + ",%.9g" * len(CHANNELS) + "\n"
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        with open(tmp, "w", encoding="ascii", newline="") as fh:
            fh.write(header + "\n")
            for i in range(0, n, block):
                j = min(n, i + block)
                ts = (T0_NS + np.arange(i, j, dtype=np.int64) * int(step_ns)).tolist()
                fh.write("".join(row % r for r in zip(ts, *(c[i:j].tolist() for c in cols))))
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def ensure_logs(args, log) -> list[dict]:
    """Write the logs not yet in --data; one entry per (hours, format) with how it was obtained."""
    out = []
    for hours in args.hours:
        npz = log_path(args.data, hours, args.rate, args.seed, "npy")
        for fmt in (["npy"] if "npy" in args.formats or "csv" in args.formats else []) + (
                ["csv"] if "csv" in args.formats else []):
            path = log_path(args.data, hours, args.rate, args.seed, fmt)
            entry = {"hours": hours, "format": fmt, "path": path, "cached": path.exists(), "gen_s": None}
            if not path.exists():
                log(f"writing {path} ({samples(hours, args.rate):,} samples × 6 channels) …")
                t = time.perf_counter()
                write_npz(path, hours, args.rate, args.seed) if fmt == "npy" else write_csv(path, npz)
                entry["gen_s"] = time.perf_counter() - t
                log(f"  {entry['gen_s']:.1f} s, {path.stat().st_size / 1e9:.2f} GB")
            entry["size"] = path.stat().st_size
            if fmt in args.formats:
                out.append(entry)
    return out


# --- measuring -------------------------------------------------------------------------


def sigmatau_cmd() -> list[str]:
    exe = Path(sys.executable).parent / "sigmatau"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "sigmatau"]


def measure(cmd: list[str], timeout: float) -> dict:
    p = subprocess.run([sys.executable, "-c", WRAPPER, json.dumps(cmd), str(timeout)],
                       capture_output=True, text=True)
    if p.returncode != 0:
        return {"rc": f"wrapper failed: {p.stderr.strip()[-500:]}", "wall_s": None, "maxrss_kib": None}
    return json.loads(p.stdout.strip().splitlines()[-1])


def compare_oadev(outdir: Path, first: Optional[dict]) -> Optional[float]:
    """Largest relative difference of sigmatau's OADEV of gyro_x (results.json) and allantools'."""
    if not first:
        return None
    try:
        res = json.loads((outdir / "results.json").read_text())
    except (OSError, ValueError):
        return None
    found = [(c["statistics"]["oadev"]["taus"], c["statistics"]["oadev"]["dev"])
             for c in res.get("channels", []) if c.get("name") == "gyro_x" and "oadev" in c.get("statistics", {})]
    if not found:
        return None
    ours = dict(zip((round(float(t), 9) for t in found[0][0]), found[0][1]))
    diffs = [abs(ours[round(t, 9)] / d - 1) for t, d in zip(first["taus"], first["dev"])
             if round(t, 9) in ours and ours[round(t, 9)] and d]
    return max(diffs) if diffs else None


# --- report ----------------------------------------------------------------------------


def fnum(v: Optional[float], digits: int = 1) -> str:
    if v is None:
        return "—"
    if 0 < abs(v) < 10 ** (1 - digits):  # small values: two significant digits
        return f"{v:.2g}"
    return f"{v:.{digits}f}"


def record_label(hours: float) -> str:
    return f"{hours:g} h" if hours >= 1 else f"{hours * 60:g} min"


def render(state: dict) -> str:
    m = state["machine"]
    rows = []
    for r in state["rows"]:
        n = r["n"]
        a, p = r.get("analyze") or {}, state["allan"].get(r["hours"]) or {}
        ok = a.get("rc") == 0
        wall = a.get("wall_s") if ok else None
        rss = a.get("maxrss_kib") * 1024 if ok and a.get("maxrss_kib") else None
        allan = p.get("total_s")
        wall_txt = fnum(wall) if ok else ("running" if not a else f"failed ({a.get('rc')})")
        rows.append([record_label(r["hours"]), f"{n:,}", r["label"], wall_txt,
                     fnum(rss / 1e9 if rss else None, 2), fnum(rss / (8 * 6 * n) if rss else None, 2),
                     fnum(allan) if allan is not None else (p.get("error") or "—"),
                     fnum(wall / allan if wall and allan else None, 2)])
    table = md_table(["record", "samples/channel", "format", "analyze wall s", "peak RSS GB",
                      "RSS / float64 samples", "allantools OADEV (6 ch) s", "ratio analyze/allantools"], rows)
    detail = []
    for r in state["rows"]:
        a = r.get("analyze") or {}
        if a:
            detail.append([record_label(r["hours"]), r["label"], str(a.get("rc")), fnum(a.get("user_s")),
                           fnum(a.get("sys_s")), fnum(r["size"] / 1e9, 2),
                           "cached" if r["gen_s"] is None else f"{r['gen_s']:.1f}",
                           "—" if r.get("oadev_diff") is None else f"{r['oadev_diff']:.1e}"])
    allan_rows = [[record_label(h), fnum(p.get("load_s")), " / ".join(fnum(v) for v in (p.get("times") or {}).values())
                   or p.get("error", "—"), fnum(p.get("maxrss_kib", 0) * 1024 / 1e9 if p.get("maxrss_kib") else None, 2)]
                  for h, p in state["allan"].items()]
    lines = [
        f"# Main job: `sigmatau analyze` on 6-channel 1 kHz IMU logs — {m['date']}",
        "",
        f"Command: `python bench/main_job.py {' '.join(state['argv'])}`" + ("" if state["done"] else
                                                                           "  (**incomplete: still running or interrupted**)"),
        "",
        table,
        "",
        "analyze: `sigmatau analyze LOG --out DIR --no-figures --force` (default statistics oadev, mdev, tdev,"
        " ohdev, totdev, theoh with noise types and intervals, IMU noise model, report.html, Kalibr imu.yaml),"
        " wall time of the subprocess; peak RSS = `ru_maxrss` of that child (`getrusage(RUSAGE_CHILDREN)` in a fresh"
        " wrapper process). RSS / float64 samples = peak RSS / (8 bytes × 6 channels × samples). allantools: the six"
        " `oadev(y, rate=1000, data_type=\"freq\", taus=\"octave\")` calls on the .npz channels in one fresh process"
        " (loading excluded); the ratio divides analyze's whole job by allantools' OADEV alone.",
        "",
        "## Machine",
        "",
        md_table(["", ""], [[k, str(v)] for k, v in m.items()]),
        "",
        "## Details",
        "",
        md_table(["record", "format", "exit", "analyze user CPU s", "sys CPU s", "log GB", "log written in s",
                  "OADEV gyro_x rel. diff vs allantools"], detail) if detail else "(no measurement yet)",
        "",
        md_table(["record", "allantools load s", "oadev per channel s (gyro x,y,z, accel x,y,z)", "peak RSS GB"],
                 allan_rows) if allan_rows else "",
        "",
        "Data: `sigmatau.imu.simulate` presets lsm6dsl-gyro / lsm6dsl-accel (white noise N of the datasheet) with"
        f" B and K of a consumer MEMS part ({json.dumps(SPEC)}), seed {state['seed']} (channel j: stream j of"
        " `SeedSequence(seed).spawn(6)`), SI units, 1000 Hz. npy = uncompressed .npz (6 float64 arrays + rate);"
        " csv = the same samples at 9 significant digits with integer ns timestamps. The logs are cached under"
        f" {state['data']} and were read from the page cache (RAM ≫ file size).",
    ]
    for r in state["rows"]:
        a = r.get("analyze") or {}
        if a and a.get("rc") != 0:
            lines += ["", f"{record_label(r['hours'])} {r['label']} failed ({a.get('rc')}):", "",
                      "```", (a.get("stderr") or "").strip()[-1500:], "```"]
    return "\n".join(lines) + "\n"


# --- main ------------------------------------------------------------------------------


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--hours", default="1,6", help="record lengths in hours, comma-separated (default 1,6)")
    ap.add_argument("--formats", default="npy,csv", help="npy (an .npz with the rate) and/or csv (default both)")
    ap.add_argument("--data", default=str(HERE / "data-main"), help="where the logs are cached (default bench/data-main)")
    ap.add_argument("--keep", action="store_true", help="keep the analyze output directories (under DATA/out/)")
    ap.add_argument("--with-figures", action="store_true", help="also time analyze with its default figures")
    ap.add_argument("--only-data", action="store_true", help="write the logs that are missing and stop")
    ap.add_argument("--no-allantools", action="store_true", help="do not run allantools")
    ap.add_argument("--seed", type=int, default=13, help="random seed of the logs (default 13)")
    ap.add_argument("--rate", type=float, default=1000.0, help="sample rate in Hz (default 1000)")
    ap.add_argument("--timeout", type=float, default=3600.0, help="time-out of one measurement in s (3600)")
    ap.add_argument("--out", help="report file (default bench/results/main-job-<date>-<time>.md)")
    args = ap.parse_args(argv)
    args.hours = [float(h) for h in args.hours.split(",") if h.strip()]
    args.formats = [f.strip().lower().replace("npz", "npy") for f in args.formats.split(",") if f.strip()]
    for f in args.formats:
        if f not in ("npy", "csv"):
            ap.error(f"--formats: {f!r} is not npy or csv")
    if not args.hours or any(h <= 0 for h in args.hours):
        ap.error("--hours must be positive numbers")
    args.data = Path(args.data)
    return args


def main(argv: Optional[list[str]] = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(argv)

    def log(msg: str) -> None:
        print(f"[{_dt.datetime.now(_dt.timezone.utc):%H:%M:%S}Z] {msg}", file=sys.stderr, flush=True)

    report = Path(args.out) if args.out else (
        HERE / "results" / f"main-job-{_dt.datetime.now():%Y%m%d-%H%M%S}.md")
    args.data.mkdir(parents=True, exist_ok=True)
    logs = ensure_logs(args, log)
    if args.only_data:
        for e in logs:
            log(f"{e['path']}: {e['size'] / 1e9:.2f} GB" + (" (cached)" if e["cached"] else f", written in {e['gen_s']:.1f} s"))
        return 0
    machine = machine_info()
    machine["load_average_start"] = " ".join(f"{v:.2f}" for v in os.getloadavg())
    machine["sigmatau_commit"] = _git("rev-parse", "HEAD")[:12] or machine["sigmatau_commit"]
    # The compiled kernels (extra `fast`) run when numba imports, unless SIGMATAU_NUMBA=0.
    machine["numba"] = _version("numba")
    machine["SIGMATAU_NUMBA"] = os.environ.get("SIGMATAU_NUMBA", "unset")
    state = {"machine": machine, "rows": [], "allan": {}, "argv": argv, "done": False, "seed": args.seed,
             "data": str(args.data)}
    for e in logs:
        variants = [("no-figures", ["--no-figures"])] + ([("figures", [])] if args.with_figures else [])
        for vname, extra in variants:
            label = ("npz" if e["format"] == "npy" else "csv") + ("" if vname == "no-figures" else " + figures")
            state["rows"].append({**e, "n": samples(e["hours"], args.rate), "label": label, "extra": extra})

    def save() -> None:
        write_atomic(report, render(state))

    outroot = args.data / "out"
    outroot.mkdir(parents=True, exist_ok=True)
    save()
    for hours in args.hours:
        for r in [r for r in state["rows"] if r["hours"] == hours]:
            outdir = outroot / f"{r['path'].stem}-{r['label'].replace(' + ', '-')}"
            cmd = sigmatau_cmd() + ["analyze", str(r["path"]), "--out", str(outdir), *r["extra"], "--force"]
            log(f"analyze {r['path'].name} ({r['label']}) …")
            r["analyze"] = measure(cmd, args.timeout)
            a = r["analyze"]
            log(f"  rc {a.get('rc')}, {fnum(a.get('wall_s'))} s, peak RSS "
                f"{fnum((a.get('maxrss_kib') or 0) / 2**20, 2)} GiB")
            r["outdir"] = outdir
            save()
        if not args.no_allantools:
            npz = log_path(args.data, hours, args.rate, args.seed, "npy")
            log(f"allantools oadev × 6 on {npz.name} …")
            res = measure([sys.executable, "-c", ALLAN, str(npz), json.dumps(CHANNELS)], args.timeout)
            if res.get("rc") == 0:
                p = json.loads(res["stdout"].strip().splitlines()[-1])
                p["maxrss_kib"] = res["maxrss_kib"]
            else:
                p = {"error": f"failed ({res.get('rc')})", "stderr": res.get("stderr")}
            state["allan"][hours] = p
            log(f"  {fnum(p.get('total_s'))} s ({p.get('error', 'ok')})")
            for r in state["rows"]:
                if r["hours"] == hours and r.get("outdir"):
                    r["oadev_diff"] = compare_oadev(r["outdir"], p.get("first"))
            save()
        for r in state["rows"]:
            if r["hours"] == hours and r.get("outdir") and not args.keep:
                shutil.rmtree(r["outdir"], ignore_errors=True)
    machine["load_average_end"] = " ".join(f"{v:.2f}" for v in os.getloadavg())
    state["done"] = True
    save()
    text = render(state)
    print(text)
    log(f"report: {report}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
