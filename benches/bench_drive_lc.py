"""Speed of the loosely coupled filter on the recorded drive.

    python benches/bench_drive_lc.py            # prints the figures of benches/README.md
    python -m pytest benches/bench_drive_lc.py --benchmark-enable

* the whole drive (54 858 IMU samples, 2 197 record epochs) through the strapdown INS, its
  15-state filter, the constraints and the detectors, in process (files already read):
  ``LoggedSource.run`` with one scenario, GIL released; per IMU sample;
* reading and checking the two gzip files, and the IMU log alone (its Rust reader);
* 200 Monte-Carlo runs of ``drive_lc`` (both variants, faults drawn per run) on all cores.

KF-GINS (C++) took 0.70 s CPU for the same drive (data README; measured by the data's
curators, not here).
"""

from __future__ import annotations

import time

import numpy as np

from navfdi import load_scenario, logs, montecarlo


def _setup():
    sc = load_scenario("drive_lc").with_value("faults", [])
    data = logs.load_source(sc.raw["source"], logs.scenario_folder(sc))
    src = logs.logged_source(sc)
    return sc, data, src


def best(f, reps: int = 7) -> float:
    out = []
    for _ in range(reps):
        t = time.perf_counter()
        f()
        out.append(time.perf_counter() - t)
    return min(out)


def main() -> None:
    sc, data, src = _setup()
    fde = [v for n, v in sc.variants() if n == "fde"][0].to_json()
    n_imu = data["imu"].shape[0]
    run = best(lambda: src.run([fde]))
    print(f"whole drive, one variant: {run * 1e3:.1f} ms = {run / n_imu * 1e6:.2f} µs per IMU sample ({n_imu} samples); KF-GINS 700 ms CPU")
    read = best(lambda: logs.load_source(sc.raw["source"], logs.scenario_folder(sc)), 3)
    print(f"reading and checking the two .gz logs: {read * 1e3:.0f} ms")
    cfg = sc.raw["source"]["imu"]
    path = logs.scenario_folder(sc) / cfg["file"]
    imu = best(lambda: logs.read_imu(path, cfg))
    print(f"reading and checking the IMU log alone (Rust, one pass): {imu * 1e3:.1f} ms = {imu / n_imu * 35_000 * 1e3:.1f} ms per 35 000 rows")
    t = time.perf_counter()
    montecarlo("drive_lc", runs=200, seed=0, progress=False)
    print(f"200 Monte-Carlo runs x 2 variants: {time.perf_counter() - t:.1f} s")


def test_read_imu_csv(benchmark) -> None:
    sc = load_scenario("drive_lc")
    cfg = sc.raw["source"]["imu"]
    imu = benchmark(logs.read_imu, logs.scenario_folder(sc) / cfg["file"], cfg)
    assert len(imu.t) == 54_858


def test_drive_filter(benchmark) -> None:
    sc, data, src = _setup()
    fde = [v for n, v in sc.variants() if n == "fde"][0].to_json()
    recs = benchmark(src.run, [fde])
    assert np.isfinite(recs[0]["nav"][-1, 0])


if __name__ == "__main__":
    main()
