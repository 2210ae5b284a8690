"""TheoH with Fast TheoBR against the exact TheoBR rows: the difference per noise type, and the time.

    python bench/theoh_fast.py                 # N = 2**20 phase points, 5 noise types × 3 seeds
    python bench/theoh_fast.py --n 4194304     # longer records (minutes per exact run)

For each seeded power-law series, ``sigmatau.theoh(y, method="fast")`` is compared with the exact
definition *at the same averaging factors* (``sigmatau.theoh(y, m=fast.m)``), so the table shows
the estimator's difference alone, not the τ grid's. Printed as Markdown (docs/theoh-fast.md keeps a
run).
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

import sigmatau

NOISES = {2: "WPM", 1: "FPM", 0: "WFM", -1: "FFM", -2: "RWFM"}


def one(n: int, alpha: int, seed: int) -> tuple[np.ndarray, float, float, int]:
    y = sigmatau.power_law_noise(n, alpha=alpha, rng=seed)
    t0 = time.perf_counter()
    fast = sigmatau.theoh(y, method="fast")
    t_fast = time.perf_counter() - t0
    high = fast.bias_factor != 1.0
    t0 = time.perf_counter()
    exact = sigmatau.theoh(y, m=fast.m)
    t_exact = time.perf_counter() - t0
    rel = fast.dev[high] / exact.dev[high] - 1.0
    block = n // (n // max(1, -(-(n + 1) // sigmatau.stats.theo.THEOH_FAST_POINTS)))
    return rel, t_fast, t_exact, block


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1 << 20, help="frequency samples per series (default 2**20)")
    ap.add_argument("--seeds", type=int, default=3, help="seeds per noise type (default 3)")
    args = ap.parse_args()
    print(f"TheoH fast vs exact TheoBR rows, N = {args.n} frequency samples, {args.seeds} seeds per noise type;"
          f" sigmatau {sigmatau.__version__}, numpy {np.__version__}, {platform.processor() or platform.machine()}")
    print()
    print("| noise | rows | mean rel. diff of dev | max abs rel. diff | fast s | exact s |")
    print("|---|---|---|---|---|---|")
    for alpha, name in NOISES.items():
        rels, tf, te = [], 0.0, 0.0
        for seed in range(args.seeds):
            rel, t_fast, t_exact, _ = one(args.n, alpha, 1000 + seed)
            rels.append(rel)
            tf += t_fast
            te += t_exact
        r = np.concatenate(rels)
        print(f"| {name} | {r.size} | {r.mean():+.2e} | {np.abs(r).max():.2e} | {tf / args.seeds:.2f} |"
              f" {te / args.seeds:.2f} |", flush=True)


if __name__ == "__main__":
    main()
