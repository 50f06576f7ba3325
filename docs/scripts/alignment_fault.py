"""A fault under way at the alignment (docs/meter_fde.md, "A fault under way at the alignment").

Per seed (1-3), with the receiver's velocities and on positions only: a 300 s simulated car
log (σ 2 m Gauss-Markov τ 30 s + 0.5 m white fixes at 1 Hz; the car aligns at 32-36 s) with
a north step on the fixes from the first fix (0 s) to 40 or 60 s, 15 or 30 m, run with FDE and
without; printed: the alignment time and the horizontal RMS / max error from 20 s after the
step's end to the end of the log.

Usage: ``python docs/scripts/alignment_fault.py``
"""

from __future__ import annotations

import copy
import tempfile
import warnings

import numpy as np

import navfdi
from navfdi.scenario import from_dict, load_scenario
from navfdi.simlog import simulate_log


def run(seed: int, velocity: bool, size: float, end: float) -> list[tuple[float, float, float]]:
    """(alignment time, RMS, max) after ``end`` + 20 s for FDE and no FDE."""
    with tempfile.TemporaryDirectory() as tmp:
        log = simulate_log(tmp, duration=300, seed=seed, gnss_rate=1.0, gnss_sigma=2.0, gnss_tau=30.0, gnss_white=0.5,
                           gnss_velocity_sigma=0.1, gnss_velocity=velocity)
        raw = copy.deepcopy(dict(load_scenario(str(log.scenario)).raw))
        raw["variants"] = [{"name": "fde"}, {"name": "no_fde", "set": {"loosely_coupled.isolate": False}}]
        raw["faults"] = [{"id": "f", "sensor": "gnss_pos", "components": ["pos_n"], "kind": "step",
                          "magnitude": f"{size} m", "start": "0 s", "end": f"{end} s"}] if size else []
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = navfdi.run_scenario(from_dict(raw, source=str(log.scenario)))
    out = []
    for v in ("fde", "no_fde"):
        rec = r.runs[v].record
        h, t = np.hypot(rec["error"][:, 6], rec["error"][:, 7]), rec["t"]
        ok = np.isfinite(h)
        after = ok & (t > end + 20)
        out.append((float(t[ok][0]), float(np.sqrt(np.mean(h[after] ** 2))), float(h[after].max())))
    return out


def main() -> None:
    for velocity in (True, False):
        for seed in (1, 2, 3):
            for size, end in ((0, 60), (15, 40), (15, 60), (30, 60)):
                o = run(seed, velocity, size, end)
                print(f"{'velocities' if velocity else 'positions only'}, seed {seed}, {size} m to {end} s: aligned at {o[0][0]:.0f} s;"
                      f" RMS / max from {end + 20} s: FDE {o[0][1]:.2f} / {o[0][2]:.1f} m, no FDE {o[1][1]:.2f} / {o[1][2]:.1f} m", flush=True)


if __name__ == "__main__":
    main()
