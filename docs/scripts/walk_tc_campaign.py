"""The Monte-Carlo table of docs/walk_tc.md: ``navfdi montecarlo walk_tc`` (a random satellite of
the eight in view all along, start 15–90 s, a 40 s step of 10–40 m or ramp of 0.5–2 m/s per
run), paper 001's satellite-FDE rates per variant and fault shape with 95 % intervals from a
bootstrap over the runs (the runs are the independent units; epochs of one run are not).

    python docs/scripts/walk_tc_campaign.py [runs] [seed]
"""

from __future__ import annotations

import sys

import numpy as np

import navfdi

RATES = {
    "detection": ("fde_detected_epochs", "fde_faulty_epochs"),
    "identification": ("fde_exact_epochs", "fde_exclusion_epochs"),
    "after-fault alarms": ("fde_after_alarm_epochs", "fde_after_epochs"),
}


def pooled(df, num: str, den: str, rng: np.random.Generator, reps: int = 2000) -> str:
    """Pooled ratio sum(num)/sum(den) over the runs of ``df`` with a bootstrap 95 % interval."""
    n, d = df[num].to_numpy(float), df[den].to_numpy(float)
    if d.sum() == 0:
        return "-"
    idx = rng.integers(0, len(n), size=(reps, len(n)))
    boot = n[idx].sum(axis=1) / np.maximum(d[idx].sum(axis=1), 1)
    lo, hi = np.percentile(boot, [2.5, 97.5])
    return f"{100 * n.sum() / d.sum():.1f} % [{100 * lo:.1f}, {100 * hi:.1f}]"


def main() -> None:
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 500
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 1
    c = navfdi.montecarlo("walk_tc", runs=runs, seed=seed, progress=False)
    r = c.runs
    rng = np.random.default_rng(0)
    f = r[r["fault_id"] == "sat_fault"]
    print(f"{runs} runs, seed {seed}")
    print("| variant | shape | runs | " + " | ".join(RATES) + " | horizontal max in the fault (offset removed), mean / p95 |")
    print("|---|---|---:|" + "---|" * (len(RATES) + 1))
    for (variant, kind), g in f.groupby(["variant", "fault_kind"], sort=False):
        cells = [pooled(g, *RATES[k], rng) for k in RATES]
        m = g["fault_hor_rel_max"].to_numpy(float)
        print(f"| {variant} | {kind} | {len(g)} | " + " | ".join(cells) + f" | {np.nanmean(m):.2f} / {np.nanpercentile(m, 95):.2f} m |")
    print("\nfault-free epochs (outside the fault windows): false exclusions per epoch")
    for variant, g in r[r["fault_id"] == "none"].groupby("variant", sort=False):
        print(f"| {variant} | {pooled(g, 'fde_false_exclusions', 'fde_outside_epochs', rng)} |")
    print("\nby size (innovation): detection rate")
    g = f[f["variant"] == "innovation"]
    for kind, lo, hi, unit in (("step", 10, 20, "m"), ("step", 20, 30, "m"), ("step", 30, 40, "m"), ("ramp", 0.5, 1.0, "m/s"), ("ramp", 1.0, 1.5, "m/s"), ("ramp", 1.5, 2.0, "m/s")):
        sel = g[(g["fault_kind"] == kind) & (g["fault_magnitude"] >= lo) & (g["fault_magnitude"] < hi)]
        print(f"| {kind} {lo}–{hi} {unit} | {len(sel)} | {pooled(sel, 'fde_detected_epochs', 'fde_faulty_epochs', rng)} |")
    print("\nby satellite (innovation): detection rate")
    for sat, sel in g.groupby("fault_satellite"):
        print(f"| {sat} | {len(sel)} | {pooled(sel, 'fde_detected_epochs', 'fde_faulty_epochs', rng)} |")


if __name__ == "__main__":
    main()
