"""20 m steps and 0.5 m/s ramps on simulated logs whose receiver and IMU differ from the
campaigns' one: what a user's own log may be (docs/meter_fde.md, "Receivers the campaigns do
not use").

Per setting and seed (1-3): a 600 s simulated car drive (navfdi.simlog.simulate_log; the car
stops for 20 s at 279-299 s) with the scenario it writes, fault-free and with six faults drawn
per seed (onset uniform in 60-480 s, north or east; steps 20 m for 30 s, ramps 0.5 m/s for 40 s),
each run with FDE and without, scored with meter_fde_campaign's metrics. Per row: the fault-free
horizontal RMS (FDE / no FDE), the share of faults left out at their first fix, the share of
fault fixes left out, the median and largest horizontal error in the fault (FDE; no FDE's
median), the share of runs whose error in the fault stays within 3x the fault-free RMS, the
share with a fix left out more than 5 s after the end, the largest error 20-60 s after the end,
and clean fixes left out (outside the fault and the 10 s after it).

Usage: ``python docs/scripts/receiver_sweep.py {step|ramp} [SETTING ...]``
"""

from __future__ import annotations

import copy
import sys
import tempfile
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import meter_fde_campaign as mc  # noqa: E402

import navfdi  # noqa: E402
from navfdi.scenario import from_dict, load_scenario  # noqa: E402
from navfdi.simlog import simulate_log  # noqa: E402

GM = {"gnss_sigma": 2.0, "gnss_tau": 30.0, "gnss_white": 0.5}
MEMS = {"gyro_bias": 300.0, "accel_bias": 10.0, "gyro_noise": 0.02, "accel_noise": 0.3}
URBAN = {"burst_rate": 1 / 60, "burst_size": 15.0, "burst_duration": 8.0, "stale_rate": 1 / 120, "stale_duration": 4.0}

#: Receiver and IMU settings (simulate_log's arguments; 1 Hz fixes unless ``gnss_rate``).
SETTINGS: dict[str, dict[str, Any]] = {
    "σ 2 m Gauss-Markov τ 30 s + 0.5 m white": GM,
    "the same, MEMS IMU (300 deg/h, 10 mg)": {**GM, **MEMS},
    "σ 5 m, τ 60 s + 1 m white": {"gnss_sigma": 5.0, "gnss_tau": 60.0, "gnss_white": 1.0},
    "σ 2 m reported as 0.7 m": {**GM, "reported_sigma": 0.7},
    "σ 1 m reported as 5 m": {"gnss_sigma": 1.0, "gnss_tau": 30.0, "gnss_white": 0.3, "reported_sigma": 5.0},
    "positions only, σ 3 m": {"gnss_sigma": 3.0, "gnss_tau": 30.0, "gnss_white": 0.5, "gnss_velocity": False},
    "5 Hz fixes": {**GM, "gnss_rate": 5.0},
    "10 Hz, positions only": {**GM, "gnss_rate": 10.0, "gnss_velocity": False},
    "white 1 m": {"gnss_sigma": 0.0, "gnss_tau": 0.0, "gnss_white": 1.0},
    "urban (15 m bursts, stale spells), MEMS IMU": {**GM, **MEMS, **URBAN},
}


def log_scenario(folder: str, seed: int, setting: dict[str, Any]) -> navfdi.Scenario:
    """The simulated log of ``setting`` in ``folder`` and its scenario, its sensors at the
    receiver's rate."""
    kw: dict[str, Any] = {"duration": 600, "seed": seed, "gnss_rate": 1.0, "gnss_velocity_sigma": 0.1, **setting}
    simulate_log(folder, **kw)
    base = load_scenario(str(Path(folder) / "scenario.toml"))
    raw = copy.deepcopy(dict(base.raw))
    for s in raw["sensors"]:
        s["rate"] = f"{kw['gnss_rate']:g} Hz"
    return from_dict(raw, source=base.source)


def sweep(name: str, kind: str) -> list[str]:
    """The markdown rows (one per seed) of setting ``name`` for ``kind`` (step or ramp)."""
    rows = []
    for seed in (1, 2, 3):
        folder = tempfile.mkdtemp(prefix="navfdi_sweep_")
        base = log_scenario(folder, seed, SETTINGS[name])
        natural = mc._natural(folder)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            clean = navfdi.run_scenario(from_dict({**dict(base.raw), "faults": []}, source=base.source)).runs
        rms = {}
        for v in ("fde", "no_fde"):
            e = clean[v].record["error"]
            h = np.hypot(e[:, 6], e[:, 7])
            rms[v] = float(np.sqrt(np.nanmean(h**2)))
        clean_out = clean["fde"].t[mc._excluded(clean["fde"])]
        rng = np.random.default_rng(seed)
        out = []
        for _ in range(6):
            onset = float(rng.uniform(60, 480))
            comp = ["pos_n", "pos_e"][int(rng.integers(2))]
            size, length = ("20 m", 30.0) if kind == "step" else ("0.5 m/s", 40.0)
            fault = {"id": "f", "sensor": "gnss_pos", "components": [comp], "kind": kind, "magnitude": size,
                     "start": f"{onset} s", "end": f"{onset + length} s"}
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                out.append(mc._one(base, fault, natural, clean_out))
        g = lambda k: np.array([r[k] for r in out])  # noqa: E731
        rows.append(f"| {name} | {seed} | {rms['fde']:.2f} / {rms['no_fde']:.2f} | {g('first_fix_excluded').mean():.2f} | "
                    f"{np.nanmean(g('share')):.2f} | {np.median(g('fde.err')):.1f} / {g('fde.err').max():.1f} ({np.median(g('no_fde.err')):.1f}) | "
                    f"{np.mean(g('fde.err') <= 3 * rms['fde']):.2f} | {g('late').mean():.2f} | {np.nanmax(g('fde.after')):.1f} | "
                    f"{g('false').sum():.0f} / {g('clean').sum():.0f} |")
    return rows


def main() -> None:
    kind = sys.argv[1] if len(sys.argv) > 1 else "step"
    if kind not in ("step", "ramp"):
        raise SystemExit(f"{kind!r}: step or ramp")
    names = sys.argv[2:] or list(SETTINGS)
    print(f"| receiver / IMU ({kind}s) | seed | fault-free RMS, FDE / no FDE [m] | left out at the first fix | fixes left out | "
          "error in the fault, median / max (no FDE median) [m] | within 3x | left out > 5 s after | max error 20-60 s after [m] | clean fixes left out |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name in names:
        for row in sweep(name, kind):
            print(row, flush=True)


if __name__ == "__main__":
    main()
