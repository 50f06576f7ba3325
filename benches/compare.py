"""Per-epoch cost of navfdi's Python API against filterpy, measured in one process.

Usage: ``python benches/compare.py [T]``. Prints a markdown table for benches/README.md:
best-of-N wall time per epoch (µs) and the speed-up over filterpy (predict + update, n = 15,
m = 6, T = 10 000 by default).
"""

from __future__ import annotations

import platform
import sys
import time

from problem import T, filterpy_loop, problem, run_filter, step_api


def best(fn, args, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn(*args)
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    epochs = int(sys.argv[1]) if len(sys.argv) > 1 else T
    args = problem(epochs)
    ref = best(filterpy_loop, args, 3) / epochs
    rows = [
        ("filterpy KalmanFilter (predict + update)", ref),
        ("navfdi KalmanFilter step API", best(step_api, args, 5) / epochs),
        ("navfdi run_filter", best(run_filter, args, 10) / epochs),
    ]
    print(f"machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}, T = {epochs}")
    print("| implementation | µs / epoch | speed-up vs filterpy |")
    print("|---|---:|---:|")
    for name, t in rows:
        print(f"| {name} | {t * 1e6:.2f} | {ref / t:.1f}× |")


if __name__ == "__main__":
    main()
