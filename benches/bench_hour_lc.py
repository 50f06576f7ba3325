"""A 59-minute loosely coupled log at 10 Hz GNSS, start to finish on the command line.

    python benches/bench_hour_lc.py [RUNS]      # prints the figures of benches/README.md

The log is simulated (``navfdi.simlog.simulate_log``: 3 540 s, IMU at 100 Hz, RTK-like fixes
and velocities at 10 Hz, σ 2 cm) into a temporary folder and its scenario's two GNSS sensors
set to 10 Hz, so every fix is an update (35 400 epochs of position and velocity, 354 000 IMU
samples). Timed: ``navfdi run scenario.toml --no-figures`` in a fresh process (both variants,
``fde`` and ``no_fde``, the console's tables, no files), best of RUNS (default 3), wall and
CPU; and in process, reading and preparing the logs, and the filter with one variant.

KF-GINS is not run here (no package for it): its 0.70 s CPU for the bundled 544 s drive at
100 Hz (the drive data's README, measured by the data's curators) is scaled by the number of
IMU samples, which makes the comparison indicative only.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

KF_GINS_DRIVE_CPU, DRIVE_SAMPLES = 0.70, 54_858


def main() -> None:
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    from navfdi import load_scenario, logs
    from navfdi.simlog import simulate_log

    with tempfile.TemporaryDirectory() as tmp:
        simulate_log(tmp, duration=3540.0, gnss_rate=10.0, imu_rate=100.0, gnss_sigma=0.02, gnss_velocity_sigma=0.02)
        toml = Path(tmp) / "scenario.toml"
        toml.write_text(toml.read_text().replace('rate = "1 Hz"', 'rate = "10 Hz"'))
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        cmd = [sys.executable, "-m", "navfdi", "run", str(toml), "--no-figures"]
        subprocess.run(cmd, check=True, capture_output=True, env=env)  # bytecode caches written
        wall, cpu = [], []
        for _ in range(runs):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            t = time.perf_counter()
            subprocess.run(cmd, check=True, capture_output=True, env=env)
            wall.append(time.perf_counter() - t)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
        sc = load_scenario(toml)
        t = time.perf_counter()
        src = logs.logged_source(sc)
        prepare = time.perf_counter() - t
        fde = sc.variants()[0][1]
        t = time.perf_counter()
        src.run([fde.to_json()])
        one = time.perf_counter() - t
        samples = len(logs.load_source(sc.raw["source"], logs.scenario_folder(sc))["imu_log"].t)
    kf = KF_GINS_DRIVE_CPU * samples / DRIVE_SAMPLES
    print(f"log: {samples} IMU samples, GNSS at 10 Hz over 3540 s")
    print(f"navfdi run scenario.toml --no-figures (both variants): best {min(wall):.2f} s wall, {min(cpu):.2f} s CPU ({runs} runs)")
    print(f"in process: reading and preparing the logs {prepare:.2f} s; the filter, one variant {one:.2f} s = {one / samples * 1e6:.2f} µs per IMU sample")
    print(f"KF-GINS scaled from the drive by IMU samples (indicative): {kf:.2f} s CPU; half of it {kf / 2:.2f} s")


if __name__ == "__main__":
    main()
