"""``sigmatau simulate``: a seeded simulated log (IMU presets, explicit terms, or power-law noise)."""

from __future__ import annotations

import argparse
import textwrap
from pathlib import Path
from typing import Any, Optional

from .common import (
    EXIT_OK, _Console, _EPILOG_ERRORS, _Formatter, _UsageError, _atomic_npy, _atomic_npz, _check_replaceable,
    _say, _write_csv, _write_stable32,
)

__all__ = ["add_cli"]

#: The demo's simulated IMU: LSM6DSL datasheet noise densities (as quoted in
#: ST DT0064) with bias instability and random walk of a typical consumer MEMS
#: part added so the σ–τ curves show the whole bathtub. Illustrative values, SI.
DEMO_IMU = {
    "gyro": {"preset": "lsm6dsl-gyro", "B": 2.4e-5, "K": 1.5e-6},    # B ≈ 5 °/h, K ≈ 18.6 °/h/√h
    "accel": {"preset": "lsm6dsl-accel", "B": 2.0e-4, "K": 2.0e-5},  # B ≈ 20 µg, K ≈ 2 µg/√s
}


def _simulated_imu(duration: float, rate: float, seed: int, *, gyro_unit: str = "rad/s",
                   accel_unit: str = "m/s^2", spec: Optional[dict] = None,
                   env: Optional[dict] = None) -> dict[str, Any]:
    """Six channels simulated with :func:`sigmatau.imu.simulate`, independent seeded streams;
    ``env[group]`` holds its ``warmup=``, ``temperature=`` and ``tempco=`` (in the unit written)."""
    import numpy as np

    from ..imu.model import simulate
    from ..imu.units import convert, term_unit

    spec = spec or DEMO_IMU
    streams = np.random.SeedSequence(seed).spawn(6)
    out: dict[str, Any] = {}
    j = 0
    for group, unit in (("gyro", gyro_unit), ("accel", accel_unit)):
        s = spec.get(group)
        if s is None:
            continue
        si = "rad/s" if group == "gyro" else "m/s^2"
        coefs = {t: float(convert(v, term_unit(si, t), term_unit(unit, t))) for t, v in s.items() if t in "QNBKR"}
        for axis in "xyz":
            out[f"{group}_{axis}"] = simulate(s.get("preset"), duration=duration, rate=rate, unit=unit,
                                              rng=np.random.default_rng(streams[j]), **coefs,
                                              **((env or {}).get(group) or {}))
            j += 1
    return out


def _coef(text: Optional[str], group: str, term: str, unit: str) -> Optional[float]:
    """A coefficient given as 'value [unit]', in the term's unit for samples in ``unit``."""
    from ..errors import SigmaTauError
    from ..imu.units import convert, term_unit

    if text is None:
        return None
    num, _, given = text.strip().partition(" ")
    try:
        value = float(num)
    except ValueError:
        raise _UsageError(f"--{group}-{term} {text!r} must be 'value [unit]', e.g. '4 mdps/sqrt(Hz)'") from None
    target = term_unit(unit, term)
    if not given.strip():
        return value
    try:
        return float(convert(value, given.strip(), target))
    except SigmaTauError as exc:
        raise _UsageError(f"--{group}-{term} {text!r}: {exc}") from None


def _cmd_simulate(args: argparse.Namespace, console: _Console) -> int:
    import numpy as np

    from ..imu.model import PRESETS

    out = Path(args.output)
    suffix = out.suffix.lower()
    if suffix not in (".csv", ".npy", ".npz", ".dat"):
        raise _UsageError(f"output {str(out)!r} must end in .csv, .npy, .npz or .dat (Stable32, with --h)")
    _check_replaceable(out, "output", args.force)
    if args.duration <= 0:
        raise _UsageError(f"--duration {args.duration!r} must be positive")
    if args.rate is not None and args.rate <= 0:
        raise _UsageError(f"--rate {args.rate!r} must be positive")
    n = int(round(args.duration * (args.rate or 1.0)))
    if args.h:
        if args.drop is not None or args.gap:
            raise _UsageError("--drop and --gap apply to simulated IMU logs, not to --h power-law noise")
        return _simulate_power_law(args, out, suffix)
    if suffix == ".dat":
        raise _UsageError("a Stable32 .dat file holds one series: use it with --h (power-law noise)")
    parts = sorted({k.rsplit("-", 1)[0] for k in PRESETS})
    if args.preset not in parts and args.preset != "none":
        raise _UsageError(f"--preset {args.preset!r}: choose from {', '.join(parts)} or none")
    groups = [g.strip() for g in args.sensors.split(",") if g.strip()]
    for g in groups:
        if g not in ("gyro", "accel"):
            raise _UsageError(f"--sensors: {g!r} is not gyro or accel")
    rate = args.rate or (PRESETS[f"{args.preset}-gyro"].rate if args.preset != "none" else None)
    if rate is None:
        raise _UsageError("--rate is needed with --preset none")
    spec: dict[str, dict] = {}
    units = {"gyro": args.gyro_unit or "rad/s", "accel": args.accel_unit or "m/s^2"}
    for g in groups:
        s: dict[str, Any] = {"preset": None if args.preset == "none" else f"{args.preset}-{g}"}
        si = "rad/s" if g == "gyro" else "m/s^2"
        for t in "QNBKR":
            v = _coef(getattr(args, f"{g}_{t}"), g, t, si)
            if v is not None:
                if v < 0:
                    raise _UsageError(f"--{g}-{t} must not be negative")
                s[t] = v
        spec[g] = s
    n = int(round(args.duration * rate))
    if n < 2:
        raise _UsageError(f"--duration {args.duration:g} s at {rate:g} Hz gives fewer than 2 samples")
    env, temperature = _environment(args, groups, n, rate)
    chans = _simulated_imu(args.duration, rate, args.seed, gyro_unit=units["gyro"], accel_unit=units["accel"],
                           spec=spec, env=env)
    if temperature is not None:
        chans["temperature"] = temperature
        units["temperature"] = "degC"
    t = np.arange(n) / rate
    keep = _kept_samples(args, n, rate, suffix)
    if keep is not None:
        t = t[keep]
        chans = {k: v[keep] for k, v in chans.items()}
    if suffix == ".csv":
        header = ["timestamp [s]"] + [f"{k} [{units[k.split('_')[0]]}]" for k in chans]
        _write_csv(out, header, [t, *chans.values()])
    elif suffix == ".npz":
        _atomic_npz(out, {"timestamp": t, **chans, "rate": np.float64(rate)})
    else:
        _atomic_npy(out, np.column_stack(list(chans.values())))
    _say(f"wrote {out}: {len(chans)} channels ({', '.join(f'{k} [{units[k.split(chr(95))[0]]}]' for k in chans)})"
         f" × {t.size:,} samples at {rate:g} Hz, seed {args.seed}", err=True)
    if keep is not None:
        _say(f"  dropped {n - t.size:,} of {n:,} samples (--drop, --gap); the timestamps show where", err=True)
    if suffix == ".npy":
        _say(f"  columns col0..col{len(chans) - 1} = {', '.join(chans)}; no timestamps: read it with"
             f" --rate {rate:g}", err=True)
    return EXIT_OK


def _environment(args: argparse.Namespace, groups: list[str], n: int, rate: float) -> tuple[dict, Optional[Any]]:
    """``simulate()`` keywords per group from ``--temperature``, ``--{group}-tempco`` and
    ``--{group}-warmup``, and the temperature column (None without ``--temperature``)."""
    from ..imu.model import temperature_profile

    env: dict[str, dict] = {g: {} for g in groups}
    temperature = None
    if args.temperature is not None:
        kind, *lims = args.temperature.split(":")
        try:
            low, high = (float(v) for v in lims) if lims else (20.0, 40.0)
        except ValueError:
            raise _UsageError(f"--temperature {args.temperature!r} must be ramp or cycle, optionally"
                              " with :LOW:HIGH in °C (e.g. ramp:20:40)") from None
        if kind not in ("ramp", "cycle"):
            raise _UsageError(f"--temperature {args.temperature!r} must be ramp or cycle (e.g. ramp:20:40)")
        temperature = temperature_profile(n / rate, rate, kind, low=low, high=high)
    for g in groups:
        tc, wu = getattr(args, f"{g}_tempco"), getattr(args, f"{g}_warmup")
        if tc is not None:
            if temperature is None:
                raise _UsageError(f"--{g}-tempco needs --temperature ramp|cycle")
            env[g].update(temperature=temperature, tempco=tc)
        if wu is not None:
            try:
                a, tau = (float(v) for v in wu.split(":"))
            except ValueError:
                raise _UsageError(f"--{g}-warmup {wu!r} must be AMPLITUDE:TIME_CONSTANT (unit written, s)") from None
            if not tau > 0:
                raise _UsageError(f"--{g}-warmup {wu!r}: the time constant must be positive")
            env[g]["warmup"] = (a, tau)
    return env, temperature


def _kept_samples(args: argparse.Namespace, n: int, rate: float, suffix: str) -> Optional[Any]:
    """Which samples to keep after ``--drop SHARE`` (scattered single samples, seeded) and
    ``--gap START:DURATION`` (seconds; repeatable); None when nothing is dropped."""
    import numpy as np

    if args.drop is None and not args.gap:
        return None
    if suffix == ".npy":
        raise _UsageError("--drop and --gap need timestamps to show the missing samples: write .csv or .npz")
    keep = np.ones(n, dtype=bool)
    if args.drop is not None:
        if not 0 <= args.drop < 1:
            raise _UsageError(f"--drop {args.drop!r} must be a share of the samples in [0, 1)")
        rng = np.random.default_rng([args.seed, 2])  # its own stream: the samples stay those of --seed
        keep[rng.choice(n, int(round(args.drop * n)), replace=False)] = False
    for spec in args.gap:
        try:
            start, duration = (float(v) for v in spec.split(":"))
        except ValueError:
            raise _UsageError(f"--gap {spec!r} must be START:DURATION in seconds, e.g. 600:2.5") from None
        if not (start >= 0 and duration > 0):
            raise _UsageError(f"--gap {spec!r}: START must be ≥ 0 and DURATION > 0 seconds")
        keep[int(round(start * rate)):int(round((start + duration) * rate))] = False
    keep[0] = keep[-1] = True  # the record's span stays the simulated one
    return keep


def _simulate_power_law(args: argparse.Namespace, out: Path, suffix: str) -> int:
    import numpy as np

    from ..noise.generate import mixed_noise

    levels: dict[int, float] = {}
    for item in args.h.split(","):
        key, sep, value = item.partition("=")
        try:
            alpha = int(key.strip().lower().lstrip("h"))
            levels[alpha] = float(value)
        except ValueError:
            raise _UsageError(f"--h {args.h!r} must be like 'h0=1e-20,h-1=1e-23' (alpha = 2 … -4)") from None
        if not sep or alpha not in (2, 1, 0, -1, -2, -3, -4):
            raise _UsageError(f"--h: {item!r} must be hALPHA=VALUE with ALPHA in 2 … -4")
    rate = args.rate or 1.0
    n = int(round(args.duration * rate))
    if n < 2:
        raise _UsageError("--duration × --rate gives fewer than 2 samples")
    y = mixed_noise(n, levels, rate=rate, data_type=args.data_type, rng=np.random.default_rng(args.seed))
    name = "phase" if args.data_type == "phase" else "freq"
    t = np.arange(n) / rate
    if suffix == ".csv":
        _write_csv(out, ["timestamp [s]", name], [t, y])
    elif suffix == ".dat":
        _write_stable32(out, y)
    elif suffix == ".npz":
        _atomic_npz(out, {"timestamp": t, name: y, "rate": np.float64(rate)})
    else:
        _atomic_npy(out, y)
    _say(f"wrote {out}: power-law {name} noise {args.h}, {n:,} samples at {rate:g} Hz, seed {args.seed}",
         err=True)
    return EXIT_OK


def add_cli(sub: Any) -> None:
    """Register ``sigmatau simulate`` on the command's subparsers."""
    sim = sub.add_parser(
        "simulate", help="write a simulated log (IMU presets, explicit Q/N/B/K/R, or power-law h_alpha)",
        formatter_class=_Formatter,
        description="Write a seeded simulated log as CSV (with timestamps and units in the header), .npz or .npy."
                    " IMU channels follow the five-term model (quantisation Q, white noise N, bias instability B,"
                    " random walk K, ramp R) from a part's preset with any term overridden; --h writes one"
                    " power-law noise channel instead.",
        epilog=textwrap.dedent("""
            examples:
              sigmatau simulate imu.csv --preset lsm6dsl --duration 7200
              sigmatau simulate gyro.csv --preset none --sensors gyro --rate 200 --gyro-N '0.2 deg/sqrt(h)' \\
                  --gyro-B '3 deg/h' --gyro-K '1e-5'
              sigmatau simulate clock.npy --h 'h0=1e-22,h-1=1e-26' --duration 100000 --rate 1
            """) + _EPILOG_ERRORS)
    sim.add_argument("output", help="file to write: .csv, .npz, .npy, or .dat (a Stable32 data file, with --h)")
    sim.add_argument("--preset", default="lsm6dsl", help="part: lsm6dsl (default), lsm6dsm, adis16448, euroc, none")
    sim.add_argument("--sensors", default="gyro,accel", help="gyro, accel or both (default); three axes each")
    sim.add_argument("--duration", type=float, default=3600.0, help="seconds (default 3600)")
    sim.add_argument("--rate", type=float, help="Hz (default: the preset's)")
    sim.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    sim.add_argument("--gyro-unit", help="unit of the gyro samples written (default rad/s)")
    sim.add_argument("--accel-unit", help="unit of the accel samples written (default m/s^2)")
    for g in ("gyro", "accel"):
        for t, what in (("Q", "quantisation"), ("N", "white noise density"), ("B", "bias instability"),
                        ("K", "random walk"), ("R", "ramp")):
            sim.add_argument(f"--{g}-{t}", dest=f"{g}_{t}", metavar="'VALUE [UNIT]'",
                             help=f"{g} {what} (SI when no unit)")
    sim.add_argument("--h", help="power-law noise instead: levels like 'h0=1e-20,h-1=1e-23' (alpha 2 … -4)")
    sim.add_argument("--data-type", choices=["freq", "phase"], default="freq", help="with --h: what to write")
    sim.add_argument("--temperature", metavar="ramp|cycle[:LOW:HIGH]",
                     help="write a temperature column (°C; default range 20:40) that --gyro-tempco and"
                          " --accel-tempco act on")
    for g in ("gyro", "accel"):
        sim.add_argument(f"--{g}-tempco", dest=f"{g}_tempco", type=float, metavar="VALUE",
                         help=f"{g} bias temperature coefficient, in the {g} unit written per °C")
        sim.add_argument(f"--{g}-warmup", dest=f"{g}_warmup", metavar="A:T",
                         help=f"{g} warm-up transient A·exp(−t/T): amplitude in the unit written, T in s")
    sim.add_argument("--drop", type=float, metavar="SHARE",
                     help="leave out this share of the samples, scattered (dropped messages; .csv/.npz)")
    sim.add_argument("--gap", action="append", default=[], metavar="START:DURATION",
                     help="leave out DURATION seconds from START (repeatable; .csv/.npz)")
    sim.add_argument("--force", action="store_true", help="replace an existing file")
    sim.add_argument("--quiet", action="store_true", help="no progress output")
    sim.add_argument("--debug", action="store_true", help="show the traceback of an error")
    sim.set_defaults(func=_cmd_simulate)
