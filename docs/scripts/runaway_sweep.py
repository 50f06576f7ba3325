"""Fault-free runs on simulated meter-level logs, with and without FDE: does the filter with FDE
ever run away from the fixes? Seeds 1-12, receiver velocities or positions only, multipath
bursts of 0, 15 or 30 m (8 s, once a minute), stale spells; each log with its own set-up.

Usage: ``python docs/scripts/runaway_sweep.py [SEEDS] [city]`` (default 12) prints the markdown
table of ``docs/meter_fde.md`` ("An INS running away from the fixes it holds out"): horizontal
RMS and max of the filter with FDE and without, against the simulator's truth, and the times
the INS was moved back onto the fixes it held out. ``city``: on ``meter_fde_campaign``'s second
route (``CITY``) instead of ``simulate_log``'s default drive.
"""

from __future__ import annotations

import copy
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

import navfdi
from navfdi.scenario import from_dict, load_scenario
from navfdi.simlog import simulate_log


def burst_log_run(folder: Path, seed: int, velocity: bool, burst: float, trajectory: dict | None = None) -> navfdi.VariantRuns:
    """A 600 s simulated car log (σ 2 m Gauss-Markov τ 30 s + 0.5 m white fixes at 1 Hz, with
    the receiver's velocities or not, ``burst`` m multipath bursts of 8 s once a minute when
    non-zero, 4 s stale spells every 2 min; ``trajectory``: a ``[trajectory]`` table, default
    ``simulate_log``'s drive) run fault-free with its own scenario, variants ``fde`` and
    ``no_fde``."""
    route = {"trajectory": trajectory} if trajectory is not None else {}
    log = simulate_log(folder, duration=600, seed=seed, **route, gnss_rate=1.0, gnss_sigma=2.0, gnss_tau=30.0, gnss_white=0.5,
                       gnss_velocity_sigma=0.1, gnss_velocity=velocity, burst_rate=1 / 60 if burst else 0.0,
                       burst_size=burst, burst_duration=8.0, stale_rate=1 / 120, stale_duration=4.0)
    sim = load_scenario(str(log.scenario))
    raw = copy.deepcopy(dict(sim.raw))
    raw.pop("faults", None)
    raw["variants"] = [{"name": "fde"}, {"name": "no_fde", "set": {"loosely_coupled.isolate": False}}]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return navfdi.run_scenario(from_dict(raw, source=sim.source))


def horizontal(run: navfdi.ScenarioRun) -> np.ndarray:
    """Horizontal error (m) per epoch, NaN before navigation."""
    e = run.record["error"]
    return np.hypot(e[:, 6], e[:, 7])


def main() -> None:
    seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 12
    trajectory = None
    if len(sys.argv) > 2:
        if sys.argv[2] != "city":
            raise SystemExit(f"route {sys.argv[2]!r}: only 'city' (or none: the default drive)")
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        from meter_fde_campaign import CITY

        trajectory = CITY
    print("| seed | receiver | bursts [m] | FDE RMS / max [m] | no FDE RMS / max [m] | moved back onto the fixes |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(1, seeds + 1):
            for velocity in (True, False):
                for burst in (0.0, 15.0, 30.0):
                    r = burst_log_run(Path(tmp) / f"{seed}{velocity}{burst:g}", seed, velocity, burst, trajectory)
                    cells = []
                    for v in ("fde", "no_fde"):
                        h = horizontal(r.runs[v])
                        h = h[np.isfinite(h)]
                        cells.append(f"{np.sqrt(np.mean(h**2)):.2f} / {h.max():.1f}")
                    moved = r.runs["fde"].record.get("reanchored", [])
                    print(f"| {seed} | {'velocities' if velocity else 'positions only'} | {burst:g} | {cells[0]} | {cells[1]} | {len(moved)} |", flush=True)


if __name__ == "__main__":
    main()
