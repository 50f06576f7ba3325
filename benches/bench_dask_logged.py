"""A campaign on a recorded log, in-process and on a 2-worker Dask ``LocalCluster``.

Usage: ``python benches/bench_dask_logged.py [RUNS] [SCENARIO]`` (default 2000 runs of
``drive_lc``: its two variants, 4000 filter runs over the 7.5-minute 200 Hz drive) prints a
markdown table: wall time in-process (2 threads) and on the cluster (2 worker processes × 1
thread) with each ship mode, the bytes each worker received, the time and share of the wall
time spent shipping the prepared logs, and the workers' peak memory. The cluster's runs are
checked equal to the in-process ones.
"""

from __future__ import annotations

import sys
import tempfile
import time

import pandas as pd

import navfdi


def main() -> None:
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
    name = sys.argv[2] if len(sys.argv) > 2 else "drive_lc"
    from dask import distributed

    t0 = time.perf_counter()
    local = navfdi.montecarlo(name, runs=runs, seed=0, workers=2, progress=False)
    local_s = time.perf_counter() - t0
    rows = [("in-process, 2 threads", local_s, "", "", "", "")]
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        with tempfile.TemporaryDirectory() as shared:
            for ship in ("scatter", shared):
                t0 = time.perf_counter()
                remote = navfdi.montecarlo(name, runs=runs, seed=0, client=client, progress=False, ship=ship)
                wall = time.perf_counter() - t0
                pd.testing.assert_frame_equal(local.runs, remote.runs)
                t = remote.transfer
                label = "scatter" if ship == "scatter" else "shared directory"
                rows.append((f"Dask, 2 workers, {label}", wall, f"{t.bytes_per_worker / 1e6:.2f}", f"{t.ship_seconds:.2f}",
                             f"{100 * t.ship_seconds / wall:.2f} %", f"{max(t.peak_worker_rss.values()) / 1e6:.0f}"))
    print(f"{name}: {runs} runs per variant ({len(local.points)} variants); cluster runs equal the in-process ones\n")
    print("| backend | wall (s) | MB per worker | shipping (s) | shipping share | peak worker RSS (MB) |")
    print("|---|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r[0]} | {r[1]:.1f} | {r[2]} | {r[3]} | {r[4]} | {r[5]} |")


if __name__ == "__main__":
    main()
