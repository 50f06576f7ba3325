"""Monte-Carlo of docs/integrity.md "Filter protection levels": shao2018_integrity with its
20 m step moved to each of the 10 satellites in view all run long and swept in size (3, 6,
10, 20, 40 m: from under the separation test's reach to far beyond it), then its 0.5 m/s
ramp moved and swept likewise (0.05, 0.1, 0.2, 0.5, 2 m/s); RUNS runs per point (default 20,
i.e. 50 points x 20 runs x 1000 epochs = 10^6 epochs per variant and campaign); then the
onsets of near-threshold steps on the worst pair, and a ramp starting just after an exclusion
has restarted the bank (ONSETS). Prints the
misleading and hazardously misleading epochs, the largest error / protection level and the
filter / snapshot ratio per variant, and the worst point.
Run: python docs/scripts/filter_pl_campaign.py [RUNS]"""

from __future__ import annotations

import sys
import time

from navfdi import montecarlo

SATS = ["G03", "G07", "G16", "G19", "G20", "G23", "E07", "E08", "E17", "E24"]
CAMPAIGNS = {
    "step": ("faults[0]", ["3 m", "6 m", "10 m", "20 m", "40 m"]),
    "ramp": ("faults[1]", ["0.05 m/s", "0.1 m/s", "0.2 m/s", "0.5 m/s", "2 m/s"]),
}


#: Onsets: the worst pair (G16, G19: similar lines of sight) with near-threshold steps moved
#: in time (the step ends at 110 s), and a 0.2 m/s ramp on G16 or G19 starting 5-20 s after the
#: 20 m step on G03 that the separation test excludes (with a bank restart) at about 43 s.
ONSETS = {
    "step onset": {"faults[0].satellite": ["G16", "G19"], "faults[0].magnitude": ["6 m", "10 m"], "faults[0].start": ["5 s", "20 s", "40 s", "60 s", "80 s", "100 s"]},
    "ramp after an exclusion": {"faults[1].satellite": ["G16", "G19"], "faults[1].magnitude": ["0.2 m/s"], "faults[1].start": ["45 s", "50 s", "55 s", "60 s"]},
}


def main(runs: int = 20) -> None:
    sweeps = {kind: {f"{path}.satellite": SATS, f"{path}.magnitude": sizes} for kind, (path, sizes) in CAMPAIGNS.items()}
    sweeps.update(ONSETS)
    for kind, sweep in sweeps.items():
        path = next(iter(sweep)).split(".")[0]
        t0 = time.perf_counter()
        c = montecarlo("shao2018_integrity", runs=runs, seed=0, sweep=sweep, progress=False)
        wall = time.perf_counter() - t0
        t = c.integrity_summary()
        points = len(c.points) // 3
        print(f"\n{kind}: {points} points x {runs} runs x 3 variants in {wall:.0f} s")
        print(f"  {'variant':<11} {'epochs':>9} {'MI h/v':>13} {'HMI h/v':>9} {'err/PL max h/v':>15} {'PL h/v mean [m]':>16} {'/snapshot':>10}")
        for variant, g in t.groupby("variant", sort=False):
            ep = int(g["epochs"].sum())
            mi = f"{int(g['misleading_h'].sum())}/{int(g['misleading_v'].sum())}"
            hmi = f"{int(g['hazardous_h'].sum())}/{int(g['hazardous_v'].sum())}"
            worst = f"{g['error_over_hpl_max'].max():.2f}/{g['error_over_vpl_max'].max():.2f}"
            pl = f"{(g['hpl_mean'] * g['epochs']).sum() / ep:.2f}/{(g['vpl_mean'] * g['epochs']).sum() / ep:.2f}"
            ratio = f"{(g['hpl_ratio_mean'] * g['epochs']).sum() / ep:.3f}/{(g['vpl_ratio_mean'] * g['epochs']).sum() / ep:.3f}"
            print(f"  {variant:<11} {ep:>9} {mi:>13} {hmi:>9} {worst:>15} {pl:>16} {ratio:>10}")
            w = g.loc[g["error_over_vpl_max"].idxmax()]
            where = " ".join(str(w[k]) for k in sweep)
            print(f"    closest vertical point: {where} (error/VPL {w['error_over_vpl_max']:.2f})")
        if kind not in CAMPAIGNS:
            continue
        s = c.summary()
        f = s[(s.fault_id == kind) & (s.variant == "separation")]
        print("  separation: satellite exclusion rate over the fault's epochs, per size (mean over satellites)")
        for size, g in f.groupby(f"{path}.magnitude", sort=False):
            print(f"    {size:>9}: detection {g['detection_rate'].mean():.3f}, identification {g['identification_rate'].mean():.3f}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 20)
