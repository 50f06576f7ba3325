"""Set-up from the log on random simulated receivers: every ``"auto"`` field of
``[loosely_coupled]`` (``imu_axes``, ``boresight``, ``imu_time_offset``, the IMU's white noise)
estimated before the run, against the run with the true settings.

Usage: ``python docs/scripts/calibrate_sweep.py [SEED] [N]`` (default 2 and 40) prints one line
per simulated log: its set-up (RTK, meter-level or urban fixes at 1, 5 or 10 Hz, with the
receiver's velocities or positions only; any of the 24 axis sets; a boresight of up to 2° per
axis; an IMU time lag of up to 0.3 s), whether the axes came out right, the boresight's and the
offset's errors (deg, s; the roll is the scenario's and not estimated) and the horizontal RMS
of the run with the estimates and with the true settings (m, against the simulator's truth),
or the error that refused it. ``docs/own_log.md`` ("Calibration from the log") and the
changelog quote seeds 2 and 3.
"""

from __future__ import annotations

import copy
import itertools
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

import navfdi
from navfdi._lc_schema import _AXES
from navfdi.scenario import from_dict, load_scenario
from navfdi.simlog import simulate_log

#: The 24 right-handed axis sets (the body axes each IMU axis may point along: ``imu_axes``).
AXIS_SETS = [a for a in itertools.permutations(_AXES, 3) if np.linalg.det(np.array([_AXES[x] for x in a], float)) > 0.5]


def draw(rng: np.random.Generator) -> tuple[str, dict]:
    """A random receiver, IMU mounting and time lag: its kind and ``simulate_log``'s arguments."""
    kw: dict = dict(duration=float(rng.choice([200, 400, 600])), seed=int(rng.integers(1, 50)),
                    gnss_rate=float(rng.choice([1.0, 5.0, 10.0])), imu_rate=float(rng.choice([100.0, 200.0])),
                    gnss_velocity=bool(rng.random() < 0.5))
    kind = str(rng.choice(["rtk", "meter", "urban"]))
    if kind == "rtk":
        kw.update(gnss_sigma=0.02, gnss_tau=20.0, gnss_white=0.01)
    else:
        kw.update(gnss_sigma=float(rng.choice([1.0, 2.0, 3.0])), gnss_tau=float(rng.choice([0.0, 10.0, 30.0])), gnss_white=0.5)
        if kind == "urban":
            kw.update(burst_rate=1 / 60, burst_size=15.0, burst_duration=8.0, stale_rate=1 / 120, stale_duration=4.0)
    kw.update(imu_axes=AXIS_SETS[int(rng.integers(len(AXIS_SETS)))],
              boresight_deg=tuple(float(x) for x in np.round(rng.uniform(-2, 2, 3), 2)),
              time_lag=float(np.round(rng.uniform(-0.3, 0.3), 2)), gyro_bias=float(rng.choice([1.0, 10.0])))
    return kind, kw


def one(kind: str, kw: dict) -> str:
    """The line for one simulated log (see the module's description)."""
    log = simulate_log(Path(tempfile.mkdtemp()), scenario_mounting="nominal", **kw)
    base = copy.deepcopy(dict(load_scenario(str(log.scenario)).raw))
    base.pop("faults", None)
    auto = copy.deepcopy(base)
    lc = auto["loosely_coupled"]
    lc["imu"] = {**lc["imu"], "gyro_noise": "auto", "accel_noise": "auto"}
    lc.update(boresight="auto", imu_time_offset="auto", imu_axes="auto")
    truth = copy.deepcopy(base)
    truth["loosely_coupled"]["imu_time_offset"] = f"{kw['time_lag']} s"
    truth["loosely_coupled"]["boresight"] = [f"{b} deg" for b in kw["boresight_deg"]]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ra = navfdi.run_scenario(from_dict(auto, source=str(log.scenario)))
        rt = navfdi.run_scenario(from_dict(truth, source=str(log.scenario)))
    c = ra.runs["fde"].calibration
    axes_ok = c.imu_axes is not None and list(c.imu_axes) == list(kw["imu_axes"])
    bore = None if c.boresight is None else np.round(np.array(c.boresight) - kw["boresight_deg"], 2).tolist()
    lag = None if c.imu_time_offset is None else round(c.imu_time_offset - kw["time_lag"], 3)
    return (f"axes right {axes_ok} | boresight error {bore} | offset error {lag} | RMS with the estimates "
            f"{ra.runs['fde'].errors()['hor_rms']:.3f}, with the true settings {rt.runs['fde'].errors()['hor_rms']:.3f}")


def main() -> None:
    seed = int(sys.argv[1]) if len(sys.argv) > 1 else 2
    n = int(sys.argv[2]) if len(sys.argv) > 2 else 40
    rng = np.random.default_rng(seed)
    for i in range(n):
        kind, kw = draw(rng)
        tag = f"{i} {kind} " + " ".join(f"{k}={v}" for k, v in kw.items() if k != "gnss_white")
        try:
            print(tag, "|", one(kind, kw), flush=True)
        except Exception as e:  # noqa: BLE001 - the sweep reports every refusal
            print(tag, "| refused:", type(e).__name__, str(e)[:300], flush=True)


if __name__ == "__main__":
    main()
