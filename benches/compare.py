"""Per-epoch cost of navfdi's Python API against filterpy, measured in one process.

Usage: ``python benches/compare.py [T]``. Prints a markdown table for benches/README.md:
best-of-N wall time per epoch (µs) and the speed-up over filterpy (predict + update, n = 15,
m = 6, T = 10 000 by default). The implementations are timed in rounds, one run of each per
round (this machine's speed drifts by up to 1.5× within minutes, so separate best-of-N
blocks can compare a fast minute with a slow one); the speed-up is the median of the rounds'
ratios, with their range.
"""

from __future__ import annotations

import platform
import sys
import time

from problem import T, filterpy_loop, problem, run_filter, step_api, step_model_api


def once(fn, args) -> float:
    t0 = time.perf_counter()
    fn(*args)
    return time.perf_counter() - t0


def main() -> None:
    epochs = int(sys.argv[1]) if len(sys.argv) > 1 else T
    rounds = 7
    args = problem(epochs)
    impls = [
        ("filterpy KalmanFilter (predict + update)", filterpy_loop),
        ("navfdi KalmanFilter step API (predict(Phi, Q) + update(z, H, R))", step_api),
        ("navfdi KalmanFilter step API, model fixed (set_model once, step(z))", step_model_api),
        ("navfdi run_filter", run_filter),
    ]
    times: list[list[float]] = [[] for _ in impls]
    for _ in range(rounds):
        for k, (_, fn) in enumerate(impls):
            times[k].append(once(fn, args) / epochs)
    ref = times[0]
    print(f"machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}, T = {epochs}, {rounds} rounds")
    print("| implementation | µs / epoch (best) | speed-up vs filterpy (median of the rounds; range) |")
    print("|---|---:|---:|")
    for (name, _), t in zip(impls, times):
        ratios = sorted(r / x for r, x in zip(ref, t))
        print(f"| {name} | {min(t) * 1e6:.2f} | {ratios[len(ratios) // 2]:.1f}× ({ratios[0]:.1f}–{ratios[-1]:.1f}) |")


if __name__ == "__main__":
    main()
