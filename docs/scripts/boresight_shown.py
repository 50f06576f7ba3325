"""A boresight the scenario does not give (docs/own_log.md, "A boresight the scenario does not
give"): simulated drives (600 s, 10 deg/h IMU) whose IMU is yawed 3° or pitched 2° from the car,
their scenarios naming the nominal axes only, run with the boresight read from the log (the
default), taken as 0 (``boresight = "0 deg"``) and the true one; fault-free horizontal RMS
with FDE, and without FDE with the boresight as 0. Receivers: RTK 2 cm with velocities,
σ 2 m Gauss-Markov (τ 30 s) + 0.3 m white with velocities, the same as positions alone at 1 Hz.

Run: python docs/scripts/boresight_shown.py [SEEDS...] (default 3 4)"""

from __future__ import annotations

import sys
import tempfile
import warnings

import navfdi
from navfdi.scenario import load_scenario
from navfdi.simlog import simulate_log

RECEIVERS = {
    "RTK 2 cm, with velocities": {"gnss_sigma": 0.02},
    "σ 2 m τ 30 s, with velocities": {"gnss_sigma": 2.0, "gnss_tau": 30.0, "gnss_white": 0.3},
    "σ 2 m τ 30 s, positions alone, 1 Hz": {"gnss_sigma": 2.0, "gnss_tau": 30.0, "gnss_white": 0.3, "gnss_velocity": False, "gnss_rate": 1.0},
}
BORESIGHTS = {"yaw 3°": (0.0, 0.0, 3.0), "pitch 2°": (0.0, 2.0, 0.0)}


def main(seeds: list[int]) -> None:
    print("| receiver | boresight | read (pitch, yaw deg) | taken as 0 | without FDE | read from the log | true boresight |")
    print("|---|---|---|---:|---:|---:|---:|")
    for rname, kw in RECEIVERS.items():
        for bname, bore in BORESIGHTS.items():
            cells: list[list[str]] = [[] for _ in range(5)]
            for seed in seeds:
                log = simulate_log(tempfile.mkdtemp(prefix="bore_"), seed=seed, boresight_deg=bore, scenario_mounting="nominal", **kw)
                sc = load_scenario(str(log.scenario))
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    read = navfdi.run_scenario(sc)
                    zero = navfdi.run_scenario(sc.with_values({"loosely_coupled.boresight": "0 deg"}, create=True))
                    true = navfdi.run_scenario(sc.with_values({"loosely_coupled.boresight": [f"{b} deg" for b in bore]}, create=True))
                cal = read.runs["fde"].calibration
                cells[0].append("—" if cal is None or cal.boresight is None else f"{cal.boresight[1]:.2f}, {cal.boresight[2]:.2f}")
                for j, (res, v) in enumerate(((zero, "fde"), (zero, "no_fde"), (read, "fde"), (true, "fde")), start=1):
                    cells[j].append(f"{res.runs[v].errors()['hor_rms']:.3f}")
            print(f"| {rname} | {bname} | " + " | ".join(" / ".join(c) + ("" if j == 0 else " m") for j, c in enumerate(cells)) + " |", flush=True)


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [3, 4])
