"""Monte-Carlo of the loosely coupled filter's GNSS fault exclusion (docs/meter_fde.md): per
data set (drive_lc's RTK fixes; a simulated car drive with meter-level fixes, σ 2 m
Gauss-Markov τ 30 s + 0.3 m white, written by navfdi.simlog.simulate_log; meter_pos: the same
receiver writing positions only; urban: the same receiver at 1 Hz with multipath bursts and
stale spells; urban_pos: that receiver writing positions only; urban_pos_tactical: the same with
a tactical-grade IMU) and fault shape
(steps 5-40 m for 60 s, ramps 0.1-2 m/s for 40 s), RUNS runs each drawing the onset (60 s to
120 s before the end), the component (north or east) and the size. Per size bin: the share
of runs excluded at the first fix after the onset, the median delay of the first exclusion
and the largest horizontal error before it,
the share of fault fixes excluded, the largest horizontal error in the fault (with FDE and
without), runs with an exclusion left standing more than 5 s after the end, the largest error 20-60 s
after the end (with FDE and without), and false
exclusions per clean tested epoch (Wilson 95 % interval).
drive_pos: drive_lc's fixes alone, its velocity channel removed.
Run: python docs/scripts/meter_fde_campaign.py [RUNS] [drive|drive_pos|meter|meter_pos|urban|urban_pos|urban_pos_tactical]
[step|ramp] [TAU]
(TAU: ``[loosely_coupled] position_correlation`` in s, default 0: white; ``auto``: read from the log)"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import navfdi
from navfdi.montecarlo import wilson
from navfdi.record import RunRecord
from navfdi.scenario import from_dict, load_scenario
from navfdi.simlog import simulate_log


#: A second route for the simulated data sets (``<data set>@city``): city blocks at 8-13 m/s
#: with right-angle turns both ways and three stops, at another latitude and heading, and
#: another noise seed — to check that what the campaigns measure on the default route holds
#: on a route nothing was tuned on.
CITY: dict = {
    "latitude": "22.3 deg", "longitude": "114.2 deg", "height": "10 m", "heading": "-70 deg", "speed": "0 m/s",
    "segments": [
        {"kind": "stationary", "duration": "30 s"},
        {"kind": "accelerate", "duration": "7 s", "acceleration": "1.5 m/s2"},
        {"kind": "level", "duration": "25 s"},
        {"kind": "turn", "duration": "9 s", "rate": "10 deg/s"},
        {"kind": "level", "duration": "30 s"},
        {"kind": "accelerate", "duration": "7 s", "acceleration": "-1.5 m/s2"},
        {"kind": "stationary", "duration": "25 s"},
        {"kind": "accelerate", "duration": "6 s", "acceleration": "1.5 m/s2"},
        {"kind": "level", "duration": "35 s"},
        {"kind": "turn", "duration": "9 s", "rate": "-10 deg/s"},
        {"kind": "level", "duration": "20 s"},
        {"kind": "accelerate", "duration": "4 s", "acceleration": "1 m/s2"},
        {"kind": "level", "duration": "40 s"},
        {"kind": "turn", "duration": "6 s", "rate": "15 deg/s"},
        {"kind": "level", "duration": "30 s"},
        {"kind": "accelerate", "duration": "6 s", "acceleration": "-1.5 m/s2"},
        {"kind": "turn", "duration": "9 s", "rate": "-10 deg/s"},
        {"kind": "accelerate", "duration": "6 s", "acceleration": "1.5 m/s2"},
        {"kind": "level", "duration": "45 s"},
        {"kind": "accelerate", "duration": "8 s", "acceleration": "-1.5 m/s2"},
        {"kind": "stationary", "duration": "15 s"},
        {"kind": "accelerate", "duration": "8 s", "acceleration": "1.5 m/s2"},
        {"kind": "level", "duration": "30 s"},
        {"kind": "turn", "duration": "9 s", "rate": "-10 deg/s"},
        {"kind": "level", "duration": "50 s"},
        {"kind": "turn", "duration": "18 s", "rate": "5 deg/s"},
        {"kind": "level", "duration": "150 s"},
    ],
}


def _base(which: str, folder: str) -> navfdi.Scenario:
    which, _, route = which.partition("@")
    if route not in ("", "city"):
        raise SystemExit(f"route {route!r}: only 'city' (or none: the default drive)")
    if which == "drive":
        return load_scenario("drive_lc")
    if which == "drive_pos":
        # The drive's RTK fixes alone (its velocity channel removed): rnx2rtkp's default output
        # on a consumer IMU.
        sc = load_scenario("drive_lc")
        raw = dict(sc.raw)
        raw["sensors"] = [s for s in raw["sensors"] if s["kind"] != "gnss_velocity"]
        lc = dict(raw["loosely_coupled"])
        lc["sensors"] = [s for s in lc["sensors"] if s["sensor"] != "gnss_vel"]
        raw["loosely_coupled"] = lc
        return from_dict(raw, source=sc.source)
    if which not in ("meter", "meter_pos", "urban", "urban_pos", "urban_pos_tactical"):
        raise SystemExit(f"data set {which!r}: drive, drive_pos, meter, meter_pos, urban, urban_pos or urban_pos_tactical")
    # urban: the meter-level receiver at 1 Hz with 15 m multipath bursts of 8 s once a minute
    # and 4 s stale spells every two minutes (natural errors up to about 60 m); urban_pos: the
    # same receiver writing positions only; urban_pos_tactical: that, with a tactical-grade IMU
    # (biases 1 deg/h and 0.3 mg, noise 0.002 deg/s/sqrt(Hz) and 0.05 mg/sqrt(Hz)) instead of
    # simulate_log's default (10 deg/h, 1 mg, 0.01, 0.1).
    urban = which.startswith("urban")
    imu = {"gyro_bias": 1.0, "accel_bias": 0.3, "gyro_noise": 0.002, "accel_noise": 0.05} if which.endswith("_tactical") else {}
    log = simulate_log(folder, duration=600, seed=2 if route else 1, **({"trajectory": CITY} if route else {}), gnss_sigma=2.0, gnss_tau=30.0, gnss_white=0.3, gnss_velocity_sigma=0.1,
                       gnss_velocity="_pos" not in which, gnss_rate=1.0 if urban else 4.0, **imu,
                       burst_rate=1 / 60 if urban else 0.0, burst_size=15.0 if urban else 0.0, burst_duration=8.0 if urban else 0.0,
                       stale_rate=1 / 120 if urban else 0.0, stale_duration=4.0 if urban else 0.0)
    return load_scenario(str(log.scenario))


def _natural(folder: str) -> np.ndarray | None:
    """The seconds (from the log's start) of the simulated receiver's bursts and stale spells
    (truth.csv), None without a simulated log."""
    path = Path(folder) / "truth.csv"
    if not path.is_file():
        return None
    tab = np.genfromtxt(path, delimiter=",", names=True)
    return np.asarray(tab["time"])[(tab["burst"] > 0) | (tab["stale"] > 0)]


def _excluded(run: RunRecord) -> np.ndarray:
    """Per record epoch: a tested GNSS position fix (some component) left out."""
    sub = next(s for s in run.record["subfilters"] if s["sensor"] == "gnss_pos")
    return (np.asarray(sub["reason"]) > 0) & (np.asarray(sub["dof"]) > 0)


def _one(base: navfdi.Scenario, fault: dict, natural: np.ndarray | None = None, clean_out: np.ndarray | None = None) -> dict[str, float]:
    raw = dict(base.raw)
    raw["faults"] = [fault]
    runs = navfdi.run_scenario(from_dict(raw, source=base.source)).runs
    out: dict[str, float] = {}
    a, b = float(fault["start"].split()[0]), float(fault["end"].split()[0])
    for v in ("fde", "no_fde"):
        x = runs[v]
        t = x.t
        e = x.record["error"]
        hor = np.hypot(e[:, 6], e[:, 7])
        win = (t >= a) & (t < b) & np.isfinite(hor)
        out[f"{v}.err"] = float(hor[win].max()) if win.any() else float("nan")
        # What the fault left behind: the largest error 20-60 s after its end.
        aft = (t >= b + 20.0) & (t < b + 60.0) & np.isfinite(hor)
        out[f"{v}.after"] = float(hor[aft].max()) if aft.any() else float("nan")
    x = runs["fde"]
    t = x.t
    sub = next(s for s in x.record["subfilters"] if s["sensor"] == "gnss_pos")
    tested = np.asarray(sub["dof"]) > 0
    ex = _excluded(x)
    during = tested & (t >= a) & (t < b)
    first = t[during][0] if during.any() else np.nan
    hits = t[ex & (t >= a) & (t < b)]
    # The largest horizontal error before the first exclusion (the whole fault without one).
    hor = np.hypot(x.record["error"][:, 6], x.record["error"][:, 7])
    upto = (t >= a) & (t < (hits[0] if hits.size else b)) & np.isfinite(hor)
    out["pre"] = float(hor[upto].max()) if upto.any() else 0.0
    out["first_fix_excluded"] = float(bool(during.any() and ex[np.flatnonzero(during)[0]]))
    out["delay"] = float(hits[0] - a) if hits.size else float("nan")
    out["share"] = float(ex[during].mean()) if during.any() else float("nan")
    # Fixes of a burst or stale spell are not clean: leaving them out is no false exclusion.
    nat = np.isin(np.round(t), np.round(natural)) if natural is not None else np.zeros(len(t), bool)
    # Left standing after the end: beyond what the fault-free run leaves out there (a burst's
    # hold outlasts the burst by a few fixes in both).
    same = np.isin(t, clean_out) if clean_out is not None else np.zeros(len(t), bool)
    late = t[ex & ~nat & ~same & (t >= b + 5.0) & (t < b + 60.0)]
    out["late"] = float(late.size > 0)
    clean = tested & ~nat & ~((t >= a) & (t < b + 10.0))
    out["false"] = float((ex & clean).sum())
    out["clean"] = float(clean.sum())
    out["first_fix"] = float(first - a)
    return out


def main(runs: int = 500, which: str = "meter", kind: str = "step", tau: float | str = 0.0) -> None:
    folder = tempfile.mkdtemp(prefix="navfdi_meter_")
    base = _base(which, folder)
    natural = _natural(folder)
    if tau:
        raw = dict(base.raw)
        raw["loosely_coupled"] = {**raw["loosely_coupled"], "position_correlation": "auto" if tau == "auto" else f"{tau} s"}
        base = from_dict(raw, source=base.source)
    clean_run = navfdi.run_scenario(from_dict({**dict(base.raw), "faults": []}, source=base.source)).runs["fde"]
    clean_out = clean_run.t[_excluded(clean_run)]
    if "position_errors" in clean_run.record:
        w, g, tc, f = clean_run.record["position_errors"]
        print(f"position errors read from the log: white σ {w:.2f} m, correlated σ {g:.2f} m, τ {tc:.1f} s, variance × {f:.1f}")
    span = float(base.core["duration"])
    rng = np.random.default_rng(0)
    lo, hi, dur, unit = (5.0, 40.0, 60.0, "m") if kind == "step" else (0.1, 2.0, 40.0, "m/s")
    rows = []
    t0 = time.perf_counter()
    for _ in range(runs):
        onset = float(rng.uniform(60.0, span - 120.0))
        size = float(rng.uniform(lo, hi))
        comp = ["pos_n", "pos_e"][int(rng.integers(2))]
        fault = {"id": "f", "sensor": "gnss_pos", "components": [comp], "kind": kind, "magnitude": f"{size} {unit}",
                 "start": f"{onset} s", "end": f"{onset + dur} s"}
        rows.append((size, _one(base, fault, natural, clean_out)))
    wall = time.perf_counter() - t0
    pc = tau if tau == "auto" else f"{tau:g} s"
    print(f"{which} / {kind} (position_correlation {pc}): {runs} runs (2 variants each) in {wall:.0f} s")
    edges = [5, 10, 20, 40] if kind == "step" else [0.1, 0.3, 0.6, 1.0, 2.0]
    print(f"| {kind} [{unit}] | runs | excluded at first fix | median delay [s] | max error before it (median / 95 %) [m] | fixes excluded | max error FDE (median / 95 %) [m] | no FDE (median) [m] | excluded > 5 s after end | max error 20-60 s after end, FDE (median / 95 %) / no FDE (median) [m] |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for a, b in zip(edges[:-1], edges[1:]):
        sel = [r for s, r in rows if a <= s < b + 1e-9]
        if not sel:
            continue
        g = lambda k: np.array([r[k] for r in sel])  # noqa: E731
        d = g("delay")
        med = f"{np.nanmedian(d):.1f}" if np.isfinite(d).any() else "-"
        print(f"| {a:g}-{b:g} | {len(sel)} | {g('first_fix_excluded').mean():.2f} | {med} | "
              f"{np.nanmedian(g('pre')):.2f} / {np.nanpercentile(g('pre'), 95):.2f} | {np.nanmean(g('share')):.2f} | "
              f"{np.nanmedian(g('fde.err')):.2f} / {np.nanpercentile(g('fde.err'), 95):.2f} | {np.nanmedian(g('no_fde.err')):.2f} | {g('late').mean():.2f} | "
              f"{np.nanmedian(g('fde.after')):.2f} / {np.nanpercentile(g('fde.after'), 95):.2f} / {np.nanmedian(g('no_fde.after')):.2f} |")
    # The bound: the error in the fault within 3x the fault-free error (RMS, FDE).
    e0 = clean_run.record["error"]
    rms0 = float(np.sqrt(np.nanmean(e0[:, 6] ** 2 + e0[:, 7] ** 2)))
    within = [f"{a:g}-{b:g}: {np.mean([r['fde.err'] <= 3.0 * rms0 for s, r in rows if a <= s < b + 1e-9]):.2f}"
              for a, b in zip(edges[:-1], edges[1:]) if any(a <= s < b + 1e-9 for s, _ in rows)]
    print(f"\nfault-free horizontal RMS (FDE) {rms0:.2f} m; runs whose error in the fault stays within 3x it: " + ", ".join(within))
    fa = np.array([[r["false"], r["clean"]] for _, r in rows])
    k, n = fa[:, 0].sum(), fa[:, 1].sum()
    lo95, hi95 = wilson(np.array([k]), np.array([n]))
    print(f"\nfalse exclusions per clean tested epoch: {k:.0f} / {n:.0f} = {k / n:.4f} [{lo95[0]:.4f}, {hi95[0]:.4f}]")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 500, sys.argv[2] if len(sys.argv) > 2 else "meter",
         sys.argv[3] if len(sys.argv) > 3 else "step",
         ("auto" if sys.argv[4] == "auto" else float(sys.argv[4])) if len(sys.argv) > 4 else 0.0)
