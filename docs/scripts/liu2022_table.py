"""Print docs/liu2022.md's tables from Monte-Carlo output directories.

Delay table (the faults swept):

    navfdi montecarlo liu2022 --runs 100 --sweep "faults[0].magnitude=0.05 m/s,0.1 m/s,0.2 m/s,0.5 m/s" \\
        --sweep "ultra_tight.cn0=48 dB-Hz,28 dB-Hz" --out out/liu2022
    python docs/scripts/liu2022_table.py out/liu2022

Fault-free false-alarm table (the same campaign with the ramp set to 0 m/s):

    navfdi montecarlo liu2022 --runs 100 --sweep "faults[0].magnitude=0 m/s" \\
        --sweep "ultra_tight.cn0=48 dB-Hz,28 dB-Hz" --out out/liu2022_clean
    python docs/scripts/liu2022_table.py out/liu2022_clean

Either directory works: the delay table lists the slopes it finds (a campaign without faulty
runs prints none), the false-alarm table is printed for every campaign.
"""

from __future__ import annotations

import sys

import pandas as pd


def main(out: str) -> None:
    s = pd.read_csv(f"{out}/summary.csv")
    cn0s = sorted(s["ultra_tight.cn0"].dropna().unique()) if "ultra_tight.cn0" in s else [None]
    mag = "faults[0].magnitude"
    sub = s[s.fault_id.str.startswith("ramp") & (s.subfilter == "G17")]
    slopes = [v for v in (sorted(sub[mag].dropna().unique(), key=lambda x: float(str(x).split()[0])) if mag in sub else []) if float(str(v).split()[0]) > 0]
    if slopes:
        print("delay mean [s] (P(det)) per method; first alarm raised inside the ramp")
        for cn0 in cn0s:
            print(cn0 or "")
            for slope in slopes:
                row = [str(slope)]
                for v in ("m1", "m2", "m3"):
                    sel = sub[(sub.variant == v) & (sub[mag] == slope)]
                    if cn0 is not None:
                        sel = sel[sel["ultra_tight.cn0"] == cn0]
                    if sel.empty:
                        row.append("—")
                        continue
                    r = sel.iloc[0]
                    row.append(f"{r.delay_mean:.1f} ({r.detection_probability:.2f})" if r.detection_probability > 0 else "— (0.00)")
                print(" | ".join(row))
    else:
        print("no faulty runs (a 0 m/s campaign): delay table skipped")
    nf = s[s.fault_id == "none"]
    keys = ["variant"] + (["ultra_tight.cn0"] if cn0s != [None] else [])
    print("false alarms per channel-epoch after arming: mean over channels [widest 95 % interval]")
    for key, g in nf.groupby(keys):
        print(*(key if isinstance(key, tuple) else (key,)), f"{g.false_alarm_rate.mean():.5f}", f"[{g.false_alarm_ci_low.min():.5f}, {g.false_alarm_ci_high.max():.5f}]")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
