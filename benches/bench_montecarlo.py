"""Monte-Carlo speed and memory, each against a reference measured in the same run.

Usage: ``python benches/bench_montecarlo.py [RUNS]`` (default 1000) prints a markdown table:

* per filter-epoch cost of a campaign (runs × variants × epochs × sub-filters) against the core step
  cost measured in the same process (``run_filter`` per epoch, n = 15, m = 6);
* what the Python layer adds: ``navfdi.montecarlo`` (1 thread) against the same runs through
  ``_core.PreparedScenario.run_chunk`` alone (every variant), interleaved, median of 15 rounds of 25 runs
  (the campaign run against ``run_filter`` on the same two filters is criterion's
  ``campaign_ratio``: ``cargo bench -p navfdi-bench --bench federated``);
* speed-up of 2 threads over 1;
* peak resident memory of a 10 000-run campaign with summaries only, in a fresh process.
"""

from __future__ import annotations

import platform
import resource
import subprocess
import sys
import time

import navfdi
from navfdi import _core
from problem import problem, run_filter


def campaign_seconds(runs: int, workers: int) -> float:
    t0 = time.perf_counter()
    c = navfdi.montecarlo("yang2013", runs=runs, seed=0, workers=workers, chunk_size=32, progress=False)
    dt = time.perf_counter() - t0
    assert not c.partial and c.runs.run.nunique() == runs
    return dt


def python_layer_ratio(runs: int = 25, rounds: int = 15) -> float:
    """Median over ``rounds`` of ``navfdi.montecarlo`` (1 thread) / the same runs through
    ``PreparedScenario.run_chunk`` for every variant, the two timed back to back."""
    jsons = [sc.to_json() for _, sc in navfdi.load_scenario("yang2013").variants()]
    ratios = []
    for _ in range(rounds):
        campaign = campaign_seconds(runs, 1)
        t0 = time.perf_counter()
        for j in jsons:
            _core.PreparedScenario(j).run_chunk(0, 0, runs, 1, [])
        ratios.append(campaign / (time.perf_counter() - t0))
    return sorted(ratios)[len(ratios) // 2]


def core_step_seconds() -> float:
    args = problem(10_000)
    best = min(_time(run_filter, args) for _ in range(5))
    return best / 10_000


def _time(fn, args) -> float:
    t0 = time.perf_counter()
    fn(*args)
    return time.perf_counter() - t0


MEMORY_SCRIPT = """
import resource, navfdi
c = navfdi.montecarlo("yang2013", runs={runs}, seed=0, chunk_size=64, progress=False)
s = c.summary()
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
"""


def peak_memory_mb(runs: int) -> float:
    out = subprocess.run([sys.executable, "-c", MEMORY_SCRIPT.format(runs=runs)], capture_output=True, text=True, check=True)
    return int(out.stdout.strip().splitlines()[-1]) / 1024  # ru_maxrss is KiB on Linux


def main() -> None:
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
    sc = navfdi.load_scenario("yang2013")
    epochs = int(sc.core["duration"] / sc.core["dt"])
    subs = len(sc.core["federated"]["subfilters"])
    variants = max(1, len(sc.raw.get("variants", [])))  # every run runs each variant
    campaign_seconds(20, 1)  # warm-up
    step = core_step_seconds()
    t1 = campaign_seconds(runs, 1)
    t2 = campaign_seconds(runs, 2)
    per_fe = t1 / (runs * variants * epochs * subs)
    print(f"machine: {platform.machine()}, {resource.getpagesize()} B pages, Python {platform.python_version()}; yang2013, {runs} runs × {variants} variants")
    print("| measurement | value | target |")
    print("|---|---:|---|")
    print(f"| core step (run_filter, n=15, m=6), µs/epoch | {step * 1e6:.2f} | reference |")
    print(f"| campaign, 1 thread: {runs} runs | {t1:.2f} s | |")
    print(f"| campaign per filter-epoch, 1 thread, µs | {per_fe * 1e6:.2f} ({per_fe / step:.2f}× the core step) | ≤ 2× |")
    print(f"| campaign, 2 threads | {t2:.2f} s ({t1 / t2:.2f}× faster) | ≥ 1.7× |")
    print(f"| Python layer: campaign / its runs through run_chunk (25 runs, median of 15, interleaved) | {python_layer_ratio():.3f}× | — |")
    mem = peak_memory_mb(10_000)
    print(f"| peak RSS, 10 000 runs, summaries only | {mem:.0f} MB | < 500 MB |")


if __name__ == "__main__":
    main()
