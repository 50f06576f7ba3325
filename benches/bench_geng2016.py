"""Paper 003 (geng2016) speed, against references measured in the same process.

Usage: ``python benches/bench_geng2016.py [RUNS]`` (default 1000) prints a markdown table:

* one ``geng2016`` run with both variants (simulation, master filter, 8 sensor sub-filters,
  residual and state tests, altitude fusion, records), best of 20;
* the sum of its filters' ``run_filter`` costs with the same n, m and T: per variant the
  master (n = 15, m = 9: GNSS 3 + SLAM 3 + baro + RA + fused altitude) and two sub-filters per
  sensor (m = 3, 3, 1, 1), each over the run's 500 epochs; target: the run ≤ 3× that sum;
* ``navfdi.montecarlo("geng2016", runs=RUNS)`` on 2 workers; target: 1000 runs < 30 s.
"""

from __future__ import annotations

import platform
import sys
import time

import numpy as np

import navfdi
from problem import best, problem


def filters_seconds(epochs: int) -> float:
    """Sum of run_filter costs of one run's filters (both variants)."""
    x0, P0, Phi, Q, _, _, _ = problem(epochs)
    rng = np.random.default_rng(0)
    total = 0.0
    for m in [9] + [3, 3, 1, 1] * 2:
        H = np.zeros((m, 15))
        for i in range(m):
            H[i, 6 + i % 3] = 1.0
        R = np.eye(m)
        zs = rng.standard_normal((epochs, m))
        total += best(lambda: navfdi.run_filter(x0, P0, Phi, Q, zs, H, R), 20)
    return 2 * total


def main() -> None:
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
    sc = navfdi.load_scenario("geng2016")
    epochs = round(sc.core["duration"] / sc.core["dt"])
    navfdi.run_scenario(sc, seed=0)  # warm up
    one = best(lambda: navfdi.run_scenario(sc, seed=1), 20)
    ref = filters_seconds(epochs)
    t0 = time.perf_counter()
    c = navfdi.montecarlo(sc, runs=runs, seed=0, workers=2, progress=False)
    mc = time.perf_counter() - t0
    assert not c.partial
    print(f"geng2016 ({epochs} epochs, 2 variants), {platform.processor() or platform.machine()}, Python {platform.python_version()}\n")
    print("| measurement | value | target |\n|---|---:|---|")
    print(f"| one run, both variants (`run_scenario`) | {one * 1e3:.2f} ms | |")
    print(f"| sum of its filters' `run_filter` costs (2 × [m = 9 master + 8 sub-filters]) | {ref * 1e3:.2f} ms | |")
    print(f"| ratio | **{one / ref:.2f}×** | ≤ 3×: {'met' if one <= 3 * ref else 'not met'} |")
    print(f"| `navfdi.montecarlo`, {runs} runs, 2 workers | **{mc:.1f} s** | {'< 30 s for 1000: ' + ('met' if mc < 30 else 'not met') if runs == 1000 else ''} |")


def test_bench_geng2016_run(benchmark):
    """pytest-benchmark form of the run (disabled by default: runs once as a smoke test)."""
    sc = navfdi.load_scenario("geng2016")
    res = benchmark(navfdi.run_scenario, sc, 1)
    assert set(res.runs) == {"no_isolation", "isolation"}


def test_bench_geng2016_filters_reference(benchmark):
    """The reference: its filters' run_filter costs (smoke-tested with a short run)."""
    assert benchmark(filters_seconds, 50) > 0


if __name__ == "__main__":
    main()
