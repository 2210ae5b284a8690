"""Benchmark sigmatau against allantools: times, speed-ups, agreement and peak memory.

Run ``python bench/run.py`` (everything, 40-60 minutes on the 2-core reference
machine), ``--quick`` (5-10 minutes, smaller sizes), ``--tiny`` (the same plan on
300-sample records: a smoke test of the command itself) or pick statistics and
sizes with ``--stats`` and ``--sizes``. bench/README.md explains the method
and every option; the results go to bench/results/ as Markdown and CSV.
"""

from __future__ import annotations

import argparse
import csv
import datetime as _dt
import io
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Optional

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
WORKER = HERE / "_worker.py"
PREFIX = "@@bench "

CLASSIC = ["adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "totdev"]
TOTALS = ["mtotdev", "ttotdev", "htotdev"]
#: Statistics allantools has, in the order they are run.
PEER_STATS = CLASSIC + ["tierms", "theo1"] + TOTALS + ["mtie", "pdev"]
#: Peers whose cost is O(N·m) per τ in Python loops or window reductions.
SLOW_PEERS = {"theo1", "mtotdev", "ttotdev", "htotdev", "mtie", "pdev"}
#: The modified Hadamard family and PDEV (issue 15): O(N) per τ like the classic statistics.
MODERN = ["mhdev", "ldev", "pdev"]
ALL_STATS = [
    "stdev", "ostdev", "adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "mhdev", "ldev", "pdev", "totdev",
    "mtotdev", "ttotdev", "htotdev", "mhtotdev", "theo1", "theobr", "theoh", "mtie", "tierms",
]
NOISES = ("wfm", "wpm", "fpm", "ffm", "rwfm")

#: Record lengths (frequency samples) of each target: full run, --quick and --tiny.
SIZES = {
    "full": {"classic": 10**6, "theo1_peer": 10**4, "theo1_own": 10**6, "total_peer": 10**4,
             "total_own": 10**6, "mtie": 10**6, "pdev_peer": 10**4, "modern_own": 10**6, "memory": 10**7},
    "quick": {"classic": 10**5, "theo1_peer": 10**3, "theo1_own": 10**5, "total_peer": 10**3,
              "total_own": 10**4, "mtie": 10**5, "pdev_peer": 10**3, "modern_own": 10**5, "memory": 10**5},
    # Smoke test of the command (tests/test_bench.py): every target, nothing measured meaningfully.
    "tiny": {"classic": 300, "theo1_peer": 300, "theo1_own": 300, "total_peer": 300,
             "total_own": 300, "mtie": 300, "pdev_peer": 300, "modern_own": 300, "memory": 300},
}


def plan_mode(args: argparse.Namespace) -> str:
    """Which SIZES row the target plan uses."""
    return "tiny" if args.tiny else ("quick" if args.quick else "full")


@dataclass(frozen=True)
class Target:
    key: str
    text: str
    stats: tuple[str, ...]
    size: str
    kind: str  # "peer": speed-up ≥ bound; "own": time/OADEV ≤ bound; "memory": peak/input < bound
    bound: float


TARGETS = [
    Target("classic", "classic statistics no slower than allantools", tuple(CLASSIC), "classic", "peer", 1.0),
    Target("theo1-peer", "Theo1 ≥ 100× faster than allantools", ("theo1",), "theo1_peer", "peer", 100.0),
    Target("theo1-own", "Theo1 within 100× our OADEV time", ("theo1",), "theo1_own", "own", 100.0),
    Target("total-peer", "MTOT/TTOT/HTOT ≥ 1000× faster than allantools", tuple(TOTALS), "total_peer", "peer", 1000.0),
    Target("total-own", "MTOT/TTOT/HTOT within 300× our OADEV time", tuple(TOTALS), "total_own", "own", 300.0),
    Target("mtie-peer", "MTIE ≥ 100× faster than allantools", ("mtie",), "mtie", "peer", 100.0),
    Target("pdev-peer", "PDEV ≥ 100× faster than allantools", ("pdev",), "pdev_peer", "peer", 100.0),
    Target("modern-own", "MHDEV/LDEV/PDEV within 10× our OADEV time", tuple(MODERN), "modern_own", "own", 10.0),
    Target("mhtot-own", "MHTOTDEV within 300× our OADEV time", ("mhtotdev",), "total_own", "own", 300.0),
    Target("memory", "peak memory of every statistic < 10× the input", tuple(ALL_STATS), "memory", "memory", 10.0),
]


# --- measurements -------------------------------------------------------------------


@dataclass
class Measurement:
    """What one worker process reported."""

    variant: str
    runs: list[float] = field(default_factory=list)
    timed_out: bool = False
    timeout: float = 0.0
    error: str = ""
    m: Optional[list[int]] = None
    dev: Optional[list[float]] = None
    digest: str = ""
    src: str = ""
    mem: Optional[dict] = None

    @property
    def best(self) -> Optional[float]:
        return min(self.runs) if self.runs else None


@dataclass
class TimingCase:
    stat: str
    n: int
    peer: bool
    results: dict[str, Measurement] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)


@dataclass
class MemoryCase:
    stat: str
    n: int
    result: Optional[Measurement] = None


def run_worker(spec: dict, timeout: float, variant: str) -> Measurement:
    """Run one measurement in a fresh interpreter, killed after ``timeout`` seconds."""
    cmd = [sys.executable, str(WORKER), json.dumps(spec)]
    res = Measurement(variant=variant, timeout=timeout)
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=REPO)
        out, err, code = proc.stdout, proc.stderr, proc.returncode
    except subprocess.TimeoutExpired as exc:
        out, err, code = exc.stdout or "", exc.stderr or "", None
        res.timed_out = True
    out = out.decode(errors="replace") if isinstance(out, bytes) else out
    err = err.decode(errors="replace") if isinstance(err, bytes) else err
    for line in out.splitlines():
        if not line.startswith(PREFIX):
            continue
        ev = json.loads(line[len(PREFIX):])
        if ev["event"] == "run":
            res.runs.append(ev["seconds"])
        elif ev["event"] == "values":
            res.m, res.dev = ev["m"], ev["dev"]
        elif ev["event"] == "data":
            res.digest = ev["digest"]
            res.src = ev.get("src", "")
        elif ev["event"] == "mem":
            res.mem = ev
    if code not in (0, None):
        tail = [ln for ln in err.strip().splitlines() if ln.strip()]
        res.error = tail[-1] if tail else f"exit code {code}"
    return res


def octave_grid(stat: str, n_points: int) -> Optional[list[int]]:
    """sigmatau's default octave averaging factors, without computing the statistic.

    Used only when our own run timed out, to still give the peer the same τ grid.
    """
    from sigmatau.core import driver as _driver
    from sigmatau.stats import allan, hadamard, theo, tie, total
    from sigmatau.core.taus import select_m

    for module in (allan, hadamard, total, theo, tie):
        for obj in vars(module).values():
            if isinstance(obj, _driver.Statistic) and obj.name == stat:
                ms = select_m(stat, n_points=n_points, rate=1.0, taus="octave", m=None,
                              points_per_decade=10, m_min=obj.min_m, m_max=obj.max_m(n_points),
                              stop_ratio=obj.stop_ratio, even=obj.even, tau_factor=obj.tau_factor)
                return [int(v) for v in ms]
    return None


def max_rel_diff(a: Measurement, b: Measurement) -> tuple[Optional[float], str]:
    """Largest |a/b − 1| over the common averaging factors, and a note on the grids."""
    if not (a.m and b.m and a.dev and b.dev):
        return None, ""
    da, db = dict(zip(a.m, a.dev)), dict(zip(b.m, b.dev))
    common = sorted(set(da) & set(db))
    note = "" if set(da) == set(db) else f"τ grids differ ({len(da)} vs {len(db)} points)"
    diffs = [abs(da[k] - db[k]) / abs(db[k]) for k in common if db[k] != 0.0]
    return (max(diffs) if diffs else None), note


# --- plan ----------------------------------------------------------------------------


def parse_sizes(text: str) -> list[int]:
    sizes = []
    for part in text.split(","):
        part = part.strip()
        if not part:
            continue
        value = float(part)
        if value < 10 or value != int(value):
            raise argparse.ArgumentTypeError(f"size {part!r} must be a whole number ≥ 10")
        sizes.append(int(value))
    return sizes


def parse_stats(text: str) -> list[str]:
    stats = [s.strip() for s in text.split(",") if s.strip()]
    bad = [s for s in stats if s not in ALL_STATS]
    if bad:
        raise argparse.ArgumentTypeError(f"unknown statistic(s) {bad}; choose from {ALL_STATS}")
    return stats


def build_plan(args: argparse.Namespace) -> tuple[list[TimingCase], list[MemoryCase], dict[str, int]]:
    """Timing and memory cases for the options, and the size of each target."""
    sizes = SIZES[plan_mode(args)]
    wanted = set(args.stats) if args.stats else None
    cases: dict[tuple[str, int], TimingCase] = {}

    def add(stat: str, n: int, peer: bool) -> None:
        key = (stat, n)
        if key in cases:
            cases[key].peer |= peer
        else:
            cases[key] = TimingCase(stat, n, peer)

    if args.sizes is not None:
        for n in args.sizes:
            for stat in (args.stats or PEER_STATS):
                add(stat, n, stat in PEER_STATS)
    elif not args.no_timing:
        for stat in CLASSIC + ["tierms"]:
            add(stat, sizes["classic"], True)
        add("theo1", sizes["theo1_peer"], True)
        add("theo1", sizes["theo1_own"], False)
        for stat in TOTALS:
            add(stat, sizes["total_peer"], True)
            add(stat, sizes["total_own"], False)
        add("mtie", sizes["mtie"], True)
        add("pdev", sizes["pdev_peer"], True)
        for stat in MODERN:
            add(stat, sizes["modern_own"], False)
        add("mhtotdev", sizes["total_own"], False)
        if wanted is not None:
            cases = {k: c for k, c in cases.items() if c.stat in wanted}
    if args.no_timing:
        cases = {}
    # Our-own-ratio targets need OADEV at the same size.
    own = {s for t in TARGETS if t.kind == "own" for s in t.stats}
    for stat, n in list(cases):
        if stat in own and ("oadev", n) not in cases:
            add("oadev", n, False)
    order = {s: i for i, s in enumerate(["oadev"] + PEER_STATS + ALL_STATS)}
    timing = sorted(cases.values(), key=lambda c: (c.n, order[c.stat]))

    mem_n = args.mem_size if args.mem_size is not None else sizes["memory"]
    run_memory = not args.no_memory and (args.sizes is None or args.mem_size is not None)
    memory = [MemoryCase(s, mem_n) for s in (args.stats or ALL_STATS)] if run_memory else []
    target_sizes = dict(sizes)
    if args.mem_size is not None:
        target_sizes["memory"] = args.mem_size
    return timing, memory, target_sizes


# --- machine ------------------------------------------------------------------------


def _read(path: str) -> str:
    try:
        return Path(path).read_text()
    except OSError:
        return ""


def _version(dist: str) -> str:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return "not installed"


def _git(*args: str) -> str:
    try:
        out = subprocess.run(["git", "--no-optional-locks", "-C", str(REPO), *args],
                             capture_output=True, text=True, timeout=20)
    except (OSError, subprocess.TimeoutExpired):
        return ""
    return out.stdout.rstrip("\n") if out.returncode == 0 else ""


def machine_info() -> dict[str, str]:
    cpuinfo = _read("/proc/cpuinfo")
    models = [ln.split(":", 1)[1].strip() for ln in cpuinfo.splitlines() if ln.startswith("model name")]
    cores = {tuple(block.get(k) for k in ("physical id", "core id"))
             for block in ({ln.split(":", 1)[0].strip(): ln.split(":", 1)[1].strip()
                            for ln in chunk.splitlines() if ":" in ln}
                           for chunk in cpuinfo.split("\n\n") if chunk.strip())}
    mem_kib = next((int(ln.split()[1]) for ln in _read("/proc/meminfo").splitlines()
                    if ln.startswith("MemTotal")), 0)
    try:
        affinity = len(os.sched_getaffinity(0))
    except AttributeError:
        affinity = os.cpu_count() or 0
    dirty = _git("status", "--porcelain", "--", "src")
    info = {
        "date": _dt.datetime.now().astimezone().isoformat(timespec="seconds"),
        "cpu_model": models[0] if models else platform.processor() or "unknown",
        "logical_cpus": str(os.cpu_count()),
        "usable_cpus": str(affinity),
        "physical_cores": str(len(cores)) if cores and None not in next(iter(cores)) else "unknown",
        "ram_gib": f"{mem_kib / 2**20:.1f}",
        "os": platform.platform(),
        "python": platform.python_version(),
        "numpy": _version("numpy"),
        "scipy": _version("scipy"),
        "allantools": _version("allantools"),
        "sigmatau": _version("sigmatau"),
        "sigmatau_commit": _git("rev-parse", "--short", "HEAD") or "unknown",
        "sigmatau_src_changes": ", ".join(ln[3:] for ln in dirty.splitlines()) or "none",
        "load_average_start": " ".join(f"{v:.2f}" for v in os.getloadavg()),
        "thread_env": ", ".join(f"{k}={os.environ[k]}" for k in
                                ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
                                if k in os.environ) or "unset",
    }
    return info


# --- formatting -----------------------------------------------------------------------


def fmt_n(n: int) -> str:
    exp = len(str(n)) - 1
    return f"1e{exp}" if n == 10**exp else f"{n:,}".replace(",", "_")


def fmt_time(meas: Optional[Measurement]) -> str:
    if meas is None:
        return "—"
    if meas.best is not None:
        text = f"{meas.best:.4g}"
        return text + (" (cut)" if meas.timed_out else "")
    if meas.timed_out:
        return f"> {meas.timeout:g} (timeout)"
    return f"error: {meas.error}" if meas.error else "—"


def fmt_ratio(value: Optional[float], relation: str = "") -> str:
    if value is None:
        return "—"
    digits = f"{value:.3g}" if value < 1000 else f"{value:,.0f}"
    return f"{relation}{digits}×"


def speedup(peer: Optional[Measurement], ours: Optional[Measurement]) -> tuple[Optional[float], str]:
    """allantools time / our time, with "> " or "< " when one side timed out."""
    if peer is None or ours is None:
        return None, ""
    if peer.best is not None and ours.best is not None:
        return peer.best / ours.best, ""
    if peer.best is None and peer.timed_out and ours.best is not None:
        return peer.timeout / ours.best, "> "
    if ours.best is None and ours.timed_out and peer.best is not None:
        return peer.best / ours.timeout, "< "
    return None, ""


def md_table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


# --- report -------------------------------------------------------------------------


@dataclass
class Report:
    args: argparse.Namespace
    argv: list[str]
    machine: dict[str, str]
    timing: list[TimingCase]
    memory: list[MemoryCase]
    target_sizes: dict[str, int]
    skipped: list[str] = field(default_factory=list)
    finished: bool = False

    def source_versions(self) -> dict[str, list[str]]:
        """sigmatau source digest -> the measurements that ran on it (sigmatau's code
        may change while a long run goes on)."""
        seen: dict[str, list[str]] = {}
        for c in self.timing:
            for variant, m in c.results.items():
                if m.src and variant != "allantools":
                    seen.setdefault(m.src, []).append(f"{c.stat} N={fmt_n(c.n)} {variant}")
        for mc in self.memory:
            if mc.result is not None and mc.result.src:
                seen.setdefault(mc.result.src, []).append(f"memory {mc.stat} N={fmt_n(mc.n)}")
        return seen

    def case(self, stat: str, n: int) -> Optional[TimingCase]:
        return next((c for c in self.timing if c.stat == stat and c.n == n), None)

    # targets
    def evaluate(self) -> list[dict[str, str]]:
        rows = []
        for t in TARGETS:
            n = self.target_sizes[t.size]
            verdicts, measured = [], []
            for stat in t.stats:
                v, text = self._judge(t, stat, n)
                if v is not None:
                    verdicts.append(v)
                    measured.append(f"{stat} {text}")
            if not verdicts:
                continue
            if all(v == "met" for v in verdicts):
                overall = "met"
            elif any(v == "not met" for v in verdicts):
                overall = "not met"
            else:
                overall = "incomplete"
            detail = "; ".join(measured)
            rows.append({"target": t.key, "n": fmt_n(n), "criterion": t.text,
                         "measured": detail, "verdict": overall})
        return rows

    def _judge(self, t: Target, stat: str, n: int) -> tuple[Optional[str], str]:
        if t.kind == "memory":
            case = next((c for c in self.memory if c.stat == stat and c.n == n), None)
            if case is None or case.result is None:
                return None, ""
            r = case.result
            if r.mem is None:
                why = f"timed out after {r.timeout:g} s" if r.timed_out else (r.error or "no result")
                return "incomplete", why
            ratio = mem_ratio(r.mem)
            return ("met" if ratio < t.bound else "not met"), f"{ratio:.2f}×"
        case = self.case(stat, n)
        if case is None:
            return None, ""
        ours = case.results.get("sigmatau")
        if t.kind == "peer":
            peer = case.results.get("allantools")
            if peer is None:
                return None, ""
            ratio, rel = speedup(peer, ours)
            if ratio is None:
                return "incomplete", "no timing"
            default_ratio, drel = speedup(peer, case.results.get("sigmatau-default"))
            text = fmt_ratio(ratio, rel)
            if default_ratio is not None:
                text += f" (default ci: {fmt_ratio(default_ratio, drel)})"
            if rel == "> ":
                return ("met" if ratio >= t.bound else "incomplete"), text
            if rel == "< ":
                return ("not met" if ratio < t.bound else "incomplete"), text
            return ("met" if ratio >= t.bound else "not met"), text
        base = self.case("oadev", n)
        base_m = base.results.get("sigmatau") if base else None
        if ours is None or base_m is None or base_m.best is None:
            return None, ""
        if ours.best is None:
            if ours.timed_out:
                ratio = ours.timeout / base_m.best
                return ("not met" if ratio > t.bound else "incomplete"), f"> {ratio:.3g}× OADEV (timeout)"
            return "incomplete", ours.error or "no timing"
        ratio = ours.best / base_m.best
        text = f"{ratio:.3g}× OADEV ({ours.best:.4g} s / {base_m.best:.4g} s)"
        return ("met" if ratio <= t.bound else "not met"), text

    # tables
    def timing_rows(self) -> list[list[str]]:
        rows = []
        for c in self.timing:
            r = c.results
            ours, default, peer, comp = (r.get(k) for k in ("sigmatau", "sigmatau-default", "allantools", "compat"))
            grid = ours.m if ours and ours.m else (peer.m if peer and peer.m else None)
            grid_text = f"{len(grid)} (m ≤ {max(grid)})" if grid else "—"
            s1, rel1 = speedup(peer, ours)
            s2, rel2 = speedup(peer, default)
            diff, _ = max_rel_diff(ours, peer) if ours and peer else (None, "")
            cdiff, _ = max_rel_diff(comp, peer) if comp and peer else (None, "")
            runs = "/".join(str(len(m.runs)) if m else "–" for m in (ours, default, comp, peer))
            rows.append([
                c.stat, fmt_n(c.n), grid_text, fmt_time(ours), fmt_time(default), fmt_time(comp),
                fmt_time(peer), fmt_ratio(s1, rel1), fmt_ratio(s2, rel2),
                "—" if diff is None else f"{diff:.1e}", "—" if cdiff is None else f"{cdiff:.1e}",
                runs, "; ".join(c.notes),
            ])
        return rows

    def memory_rows(self) -> list[list[str]]:
        rows = []
        for c in self.memory:
            r = c.result
            if r is None:
                rows.append([c.stat, fmt_n(c.n), "—", "—", "—", "—", "—", "not run"])
                continue
            if r.mem is None:
                why = f"timed out after {r.timeout:g} s" if r.timed_out else (r.error or "no result")
                rows.append([c.stat, fmt_n(c.n), f"{8 * c.n / 1e6:.0f}", "—", "—", "—", "—", why])
                continue
            mm = r.mem
            rise_mb, exact = rss_rise(mm)
            rows.append([
                c.stat, fmt_n(c.n), f"{mm['input_bytes'] / 1e6:.0f}", f"{mm['tracemalloc_peak'] / 1e6:.1f}",
                f"{rise_mb:.1f}" + ("" if exact else " (≤)"), f"{mem_ratio(mm):.2f}×",
                f"{mm['seconds']:.3g}", "",
            ])
        return rows

    def markdown(self) -> str:
        mode = plan_mode(self.args) if (self.args.quick or self.args.tiny) else (
            "custom" if self.args.sizes is not None or self.args.stats else "full")
        mi = self.machine
        out = [
            f"# sigmatau vs allantools — benchmark of {mi['date']}",
            "",
            f"Command: `{' '.join(['python bench/run.py', *self.argv])}` (mode: {mode})"
            + ("" if self.finished else " — **incomplete: run still going or interrupted**"),
            "",
            "## Machine",
            "",
            f"- CPU: {mi['cpu_model']}; {mi['logical_cpus']} logical CPUs ({mi['usable_cpus']} usable),"
            f" {mi['physical_cores']} physical cores; RAM {mi['ram_gib']} GiB; {mi['os']}",
            f"- Python {mi['python']}, numpy {mi['numpy']}, scipy {mi['scipy']},"
            f" allantools {mi['allantools']}, sigmatau {mi['sigmatau']} (commit {mi['sigmatau_commit']};"
            f" uncommitted changes in src: {mi['sigmatau_src_changes']})",
            self._source_line(),
            f"- Load average (1, 5, 15 min) at start: {mi['load_average_start']}"
            + (f"; at end: {mi['load_average_end']}" if "load_average_end" in mi else "")
            + f". BLAS/OpenMP thread variables: {mi['thread_env']}.",
            "",
            "## Method",
            "",
            f"- Data: {self.args.noise.upper()} fractional-frequency samples, seed {self.args.seed},"
            " centred (mean removed), rate 1 Hz, `data_type=\"freq\"` in both libraries; N counts"
            " frequency samples (N + 1 phase points). Every worker regenerates the same bytes"
            " (checked by digest).",
            "- τ grid: sigmatau's default octave grid of the statistic (m = 1, 2, 4 … up to N/stop"
            " ratio; Theo1 even m up to N − 1), passed to allantools and to sigmatau.compat.allantools"
            " as τ = m·τ0 (for Theo1 that is allantools' τ convention; sigmatau reports 0.75·m·τ0)."
            " Same estimator: raw MTOT/TTOT/HTOT (no bias correction), HTOT m = 1 as OHDEV.",
            f"- Timing: each (library, statistic, N) in a fresh process; wall time of one call"
            f" (`time.perf_counter`), best of up to {self.args.repeat} calls, no new call started"
            f" once the calls so far took {self.args.budget:g} s (so slow calls run once)."
            " The machine is shared: best-of-k is the least disturbed run, and ratios between"
            " rows are more reliable than absolute times.",
            "- `sigmatau ci=None` is the bare estimator (`ci=None`: no noise identification, no"
            " intervals) and is what the targets use; `default` is the same call with the default"
            " `ci=\"chi2\"` (noise identification, EDF and χ² interval at every τ). `compat` is"
            " `sigmatau.compat.allantools` (allantools' signature, bare estimator).",
            f"- Time-outs: allantools {self.args.peer_timeout:g} s, sigmatau {self.args.own_timeout:g} s,"
            f" memory runs {self.args.mem_timeout:g} s; a process past its time-out is killed and"
            " reported as \"> time-out\" (speed-ups then are bounds). \"(cut)\" marks a time whose"
            " repeats were cut by the time-out.",
            "- Agreement: largest |dev_sigmatau/dev_allantools − 1| over the common τ.",
            "- Memory: one process per statistic, default call (`ci=\"chi2\"`) on white FM data of"
            " N samples after a warm-up call on 4096 samples. Two measures of the memory the call"
            " adds on top of its input: the `tracemalloc` peak (every NumPy buffer and Python"
            " object allocated during the call) and the rise of the process's resident high-water"
            " mark (`ru_maxrss`) above the resident size just before the call (also catches"
            " allocations tracemalloc cannot see, e.g. inside compiled FFT code). The ratio uses"
            " the larger of the two, divided by the input's size (8·N bytes).",
            "",
        ]
        targets = self.evaluate()
        if targets:
            out += ["## Targets", "", md_table(["target", "N", "criterion", "measured", "verdict"],
                                               [[r["target"], r["n"], r["criterion"], r["measured"], r["verdict"]]
                                                for r in targets]), ""]
        if self.timing:
            out += ["## Timing (seconds; speed-up = allantools time / sigmatau time)", "",
                    md_table(["statistic", "N", "τ points", "sigmatau ci=None", "sigmatau default",
                              "compat", "allantools", "speed-up ci=None", "speed-up default",
                              "max rel. diff sigmatau", "max rel. diff compat",
                              "runs (ours/default/compat/allantools)", "notes"], self.timing_rows()), ""]
        if self.memory:
            out += ["## Peak memory of the default call (MB = 10⁶ bytes)", "",
                    md_table(["statistic", "N", "input MB", "tracemalloc peak MB", "RSS rise MB",
                              "ratio to input", "call time s", "notes"], self.memory_rows()), ""]
        if self.skipped:
            out += ["## Not run", ""] + [f"- {s}" for s in self.skipped] + [""]
        return "\n".join(out)

    def _source_line(self) -> str:
        versions = self.source_versions()
        if len(versions) <= 1:
            digest = next(iter(versions), "not recorded")
            return f"- sigmatau source digest (src/sigmatau/**/*.py, as every worker saw it): {digest}"
        parts = [f"{d}: {len(v)} measurements (first {v[0]}, last {v[-1]})" for d, v in versions.items()]
        return ("- **sigmatau's source changed during the run** (other work on the same checkout);"
                " digests in order of first use: " + "; ".join(parts) + ". The CSV gives each"
                " measurement's digest.")

    def csv_text(self) -> str:
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(["section", "statistic", "n", "variant", "quantity", "value", "unit", "note"])
        for k, v in self.machine.items():
            w.writerow(["machine", "", "", "", k, v, "", ""])
        for k in ("noise", "seed", "repeat", "budget", "peer_timeout", "own_timeout", "mem_timeout"):
            w.writerow(["settings", "", "", "", k, getattr(self.args, k), "", ""])
        for c in self.timing:
            for variant, m in c.results.items():
                note = "timeout" if m.timed_out else m.error
                w.writerow(["timing", c.stat, c.n, variant, "seconds_best",
                            "" if m.best is None else repr(m.best), "s", note])
                w.writerow(["timing", c.stat, c.n, variant, "runs", len(m.runs), "", ""])
                if m.src:
                    w.writerow(["timing", c.stat, c.n, variant, "sigmatau_src_digest", m.src, "", ""])
                if m.timed_out:
                    w.writerow(["timing", c.stat, c.n, variant, "timeout", m.timeout, "s", ""])
                if m.m:
                    w.writerow(["timing", c.stat, c.n, variant, "n_tau", len(m.m), "", ""])
            peer = c.results.get("allantools")
            for variant in ("sigmatau", "sigmatau-default", "compat"):
                ours = c.results.get(variant)
                ratio, rel = speedup(peer, ours)
                if ratio is not None:
                    w.writerow(["timing", c.stat, c.n, variant, "speedup_vs_allantools", repr(ratio), "x",
                                {"> ": "lower bound", "< ": "upper bound"}.get(rel, "")])
                diff, note = max_rel_diff(ours, peer) if ours and peer else (None, "")
                if diff is not None:
                    w.writerow(["timing", c.stat, c.n, variant, "max_rel_diff_vs_allantools", repr(diff), "", note])
        for c in self.memory:
            r = c.result
            if r is None:
                continue
            if r.mem is None:
                w.writerow(["memory", c.stat, c.n, "sigmatau-default", "status",
                            "timeout" if r.timed_out else "error", "", r.error])
                continue
            rise_mb, exact = rss_rise(r.mem)
            w.writerow(["memory", c.stat, c.n, "sigmatau-default", "sigmatau_src_digest", r.src, "", ""])
            for q, v, u in (("input_bytes", r.mem["input_bytes"], "B"),
                            ("tracemalloc_peak", r.mem["tracemalloc_peak"], "B"),
                            ("rss_rise", int(rise_mb * 1e6), "B"),
                            ("ratio_to_input", repr(mem_ratio(r.mem)), "x"),
                            ("seconds", repr(r.mem["seconds"]), "s")):
                w.writerow(["memory", c.stat, c.n, "sigmatau-default", q, v, u,
                            "" if exact or q != "rss_rise" else "upper bound"])
        for row in self.evaluate():
            w.writerow(["target", row["target"], row["n"], "", "verdict", row["verdict"], "", row["measured"]])
        for s in self.skipped:
            w.writerow(["skipped", "", "", "", "", "", "", s])
        return buf.getvalue()


def rss_rise(mm: dict) -> tuple[float, bool]:
    """Rise of the resident high-water mark over the RSS before the call, in MB.

    When the high-water mark did not move, the call's peak stayed below the
    earlier one and the value is only an upper bound.
    """
    rise_kib = max(0, mm["hwm_after_kib"] - mm["rss_before_kib"])
    return rise_kib * 1024 / 1e6, mm["hwm_after_kib"] > mm["hwm_before_kib"]


def mem_ratio(mm: dict) -> float:
    rise_mb, _ = rss_rise(mm)
    return max(mm["tracemalloc_peak"], rise_mb * 1e6) / mm["input_bytes"]


def write_atomic(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file and ``os.replace``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def output_paths(out: Optional[str], mode: str) -> tuple[Path, Path]:
    if out and Path(out).suffix in (".md", ".csv"):
        stem = Path(out).with_suffix("")
    else:
        folder = Path(out) if out else HERE / "results"
        stamp = _dt.datetime.now().strftime("%Y%m%d-%H%M%S")
        stem = folder / f"bench-{stamp}{'' if mode == 'full' else '-' + mode}"
    return stem.with_suffix(".md"), stem.with_suffix(".csv")


# --- running ------------------------------------------------------------------------


def run_timing_case(case: TimingCase, args: argparse.Namespace, log) -> None:
    base = {"mode": "time", "stat": case.stat, "n": case.n, "noise": args.noise, "seed": args.seed,
            "repeat": args.repeat, "budget": args.budget}

    def one(variant: str, timeout: float, m: Optional[list[int]] = None) -> Measurement:
        spec = dict(base, lib=variant, m=m)
        t0 = time.monotonic()
        meas = run_worker(spec, timeout, variant)
        case.results[variant] = meas
        log(f"  {case.stat:8s} N={fmt_n(case.n):6s} {variant:17s} {fmt_time(meas):>22s}"
            f"  ({len(meas.runs)} run{'s' if len(meas.runs) != 1 else ''}, {time.monotonic() - t0:.1f} s wall)")
        return meas

    ours = one("sigmatau", args.own_timeout)
    if not args.no_default:
        if ours.best is None:
            case.notes.append("default call not run: the bare one did not finish")
        else:
            one("sigmatau-default", args.own_timeout)
    if not case.peer or case.stat not in PEER_STATS:
        return
    grid = ours.m or octave_grid(case.stat, case.n + 1)
    if not grid:
        case.notes.append("peers not run: τ grid unknown")
        return
    if not args.no_compat:
        one("compat", args.own_timeout, grid)
    if args.no_peers:
        return
    if args.skip_slow_peers and case.stat in SLOW_PEERS:
        case.notes.append("allantools skipped (--skip-slow-peers)")
        return
    peer = one("allantools", args.peer_timeout, grid)
    digests = {m.digest for m in case.results.values() if m.digest}
    if len(digests) > 1:
        case.notes.append("DATA DIFFER between workers")
    diff, note = max_rel_diff(ours, peer)
    if note:
        case.notes.append(note)
    if diff is not None:
        log(f"  {case.stat:8s} N={fmt_n(case.n):6s} max rel. diff sigmatau vs allantools: {diff:.1e}")


def run_memory_case(case: MemoryCase, args: argparse.Namespace, log) -> None:
    spec = {"mode": "mem", "stat": case.stat, "n": case.n, "seed": args.seed}
    t0 = time.monotonic()
    case.result = run_worker(spec, args.mem_timeout, "memory")
    r = case.result
    if r.mem:
        rise, _ = rss_rise(r.mem)
        text = (f"tracemalloc {r.mem['tracemalloc_peak'] / 1e6:8.1f} MB, RSS rise {rise:8.1f} MB,"
                f" ratio {mem_ratio(r.mem):5.2f}× input")
    else:
        text = f"timed out after {args.mem_timeout:g} s" if r.timed_out else f"error: {r.error}"
    log(f"  memory   N={fmt_n(case.n):6s} {case.stat:8s} {text}  ({time.monotonic() - t0:.1f} s wall)")


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python bench/run.py",
        description="Time sigmatau against allantools on the same seeded data, check that they agree,"
                    " measure peak memory, and write a Markdown and a CSV report.",
    )
    size_mode = p.add_mutually_exclusive_group()
    size_mode.add_argument("--quick", action="store_true",
                           help="smaller sizes (see README): minutes instead of most of an hour")
    size_mode.add_argument("--tiny", action="store_true",
                           help="every target on 300-sample records: seconds; checks the command, not the code")
    p.add_argument("--stats", type=parse_stats, default=None,
                   help="comma-separated statistics to run (default: those of the targets)")
    p.add_argument("--sizes", type=parse_sizes, default=None,
                   help="comma-separated record lengths, e.g. 1e4,1e6: time every selected statistic"
                        " at each size instead of the target plan (memory only with --mem-size)")
    p.add_argument("--mem-size", type=lambda s: parse_sizes(s)[0], default=None,
                   help="record length of the memory runs (default 1e7; 1e5 with --quick, 300 with --tiny)")
    p.add_argument("--no-memory", action="store_true", help="skip the memory runs")
    p.add_argument("--no-timing", action="store_true", help="skip the timing runs")
    p.add_argument("--no-peers", action="store_true", help="do not run allantools")
    p.add_argument("--skip-slow-peers", action="store_true",
                   help="do not run allantools' theo1, mtotdev, ttotdev, htotdev and mtie (O(N·m) each τ)")
    p.add_argument("--no-compat", action="store_true", help="do not time sigmatau.compat.allantools")
    p.add_argument("--no-default", action="store_true", help="do not time the default (ci='chi2') call")
    p.add_argument("--repeat", type=int, default=5, help="best of up to this many calls (default 5)")
    p.add_argument("--budget", type=float, default=20.0,
                   help="start no new repeat once the calls so far took this many seconds (default 20)")
    p.add_argument("--peer-timeout", type=float, default=900.0,
                   help="seconds before an allantools measurement is killed (default 900)")
    p.add_argument("--own-timeout", type=float, default=600.0,
                   help="seconds before a sigmatau measurement is killed (default 600)")
    p.add_argument("--mem-timeout", type=float, default=600.0,
                   help="seconds before a memory measurement is killed (default 600)")
    p.add_argument("--noise", choices=NOISES, default="wfm", help="noise type of the timing data (default wfm)")
    p.add_argument("--seed", type=int, default=20240601, help="seed of the data (default 20240601)")
    p.add_argument("--out", default=None,
                   help="output folder (default bench/results) or a file name ending in .md or .csv"
                        " (both files are written, with the same stem)")
    return p


def main(argv: Optional[list[str]] = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    args = build_parser().parse_args(argv)
    if args.repeat < 1:
        print("error: --repeat must be at least 1", file=sys.stderr)
        return 2
    timing, memory, target_sizes = build_plan(args)
    report = Report(args=args, argv=argv, machine=machine_info(), timing=timing, memory=memory,
                    target_sizes=target_sizes)
    if args.no_peers:
        report.skipped.append("allantools: --no-peers")
    elif args.skip_slow_peers:
        report.skipped.append("allantools theo1, mtotdev, ttotdev, htotdev, mtie: --skip-slow-peers")
    if not args.no_peers and _version("allantools") == "not installed":
        print("error: allantools is not installed (pip install allantools, or run with --no-peers)",
              file=sys.stderr)
        return 2
    md_path, csv_path = output_paths(args.out, plan_mode(args))

    def save() -> None:
        write_atomic(md_path, report.markdown())
        write_atomic(csv_path, report.csv_text())

    def log(text: str) -> None:
        print(text, flush=True)

    log(f"sigmatau benchmark: {len(timing)} timing cases, {len(memory)} memory cases;"
        f" writing {md_path.relative_to(Path.cwd()) if md_path.is_relative_to(Path.cwd()) else md_path}")
    try:
        for case in timing:
            run_timing_case(case, args, log)
            save()
        for mcase in memory:
            run_memory_case(mcase, args, log)
            save()
    except KeyboardInterrupt:
        log("interrupted: the report holds what was measured so far")
        report.machine["load_average_end"] = " ".join(f"{v:.2f}" for v in os.getloadavg())
        save()
        return 130
    report.machine["load_average_end"] = " ".join(f"{v:.2f}" for v in os.getloadavg())
    report.finished = True
    save()
    print()
    print(report.markdown())
    print(f"\nwritten: {md_path}\n         {csv_path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
