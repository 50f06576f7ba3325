"""Monte-Carlo of docs/drive_lc.md: 200 runs of drive_lc, each drawing its GNSS fault's start
(60-480 s), component (north or east position) and shape and size (10-40 m steps or 0.2-1 m/s
ramps, 60 s long); detection probability and delay per shape and size, per variant.
Run: python docs/scripts/drive_lc_campaign.py [RUNS]"""

from __future__ import annotations

import sys
import time

import numpy as np

from navfdi import montecarlo


def main(runs: int = 200) -> None:
    t0 = time.perf_counter()
    c = montecarlo("drive_lc", runs=runs, seed=0, progress=False)
    wall = time.perf_counter() - t0
    print(f"{runs} runs x 2 variants: {wall:.1f} s wall on this machine")
    df = c.runs[c.runs.fault_id == "gnss_fault"]
    bins = {"step": [10, 20, 30, 40], "ramp": [0.2, 0.4, 0.6, 0.8, 1.0]}
    unit = {"step": "m", "ramp": "m/s"}
    for variant in ("fde", "no_fde"):
        for det in ("chi2", "exclude"):
            g = df[(df.variant == variant) & (df.detector == det)]
            print(f"\n{variant} / {det}: P(det), median and 95th-percentile delay [s], largest horizontal error in the fault (median) [m]")
            for kind, edges in bins.items():
                k = g[g.fault_kind == kind]
                for lo, hi in zip(edges[:-1], edges[1:]):
                    b = k[(k.fault_magnitude >= lo) & (k.fault_magnitude < hi + 1e-9)]
                    if not len(b):
                        continue
                    d = b.delay[b.detected].to_numpy()
                    med = f"{np.median(d):6.2f}" if d.size else "     -"
                    p95 = f"{np.percentile(d, 95):6.2f}" if d.size else "     -"
                    print(f"  {kind:4s} {lo:g}-{hi:g} {unit[kind]:3s} runs {len(b):3d}  P(det) {b.detected.mean():5.2f}  delay {med} / {p95}  error {np.nanmedian(b.fault_hor_max):6.2f}")
    s = c.summary()
    none = s[(s.fault_id == "none") & (s.detector.isin(["chi2", "exclude"]))]
    print("\nfalse alarms per tested epoch outside the faults (+10 s):")
    for _, r in none.iterrows():
        print(f"  {r.variant:7s} {r.subfilter:8s} {r.detector:8s} {r.false_alarm_rate:.4f} [{r.false_alarm_ci_low:.4f}, {r.false_alarm_ci_high:.4f}]")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 200)
