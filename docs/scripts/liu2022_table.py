"""Print docs/liu2022.md's tables from a Monte-Carlo output directory:

    navfdi montecarlo liu2022 --runs 100 --sweep "faults[0].magnitude=0.05 m/s,0.1 m/s,0.2 m/s,0.5 m/s" \
        --sweep "ultra_tight.cn0=48 dB-Hz,28 dB-Hz" --out out/liu2022
    python docs/scripts/liu2022_table.py out/liu2022
"""
import pandas as pd, numpy as np, sys
s = pd.read_csv(sys.argv[1] + "/summary.csv")
sub = s[(s.fault_id.str.startswith("ramp")) & (s.subfilter=="G17")]
for cn0 in ["48 dB-Hz", "28 dB-Hz"]:
    print(cn0)
    for slope in ["0.05 m/s","0.1 m/s","0.2 m/s","0.5 m/s"]:
        row=[slope]
        for v in ["m1","m2","m3"]:
            r = sub[(sub.variant==v)&(sub["faults[0].magnitude"]==slope)&(sub["ultra_tight.cn0"]==cn0)].iloc[0]
            row.append(f"{r.delay_mean:.1f} ({r.detection_probability:.2f})" if r.detection_probability>0 else f"— (0.00)")
        print(" | ".join(row))
nf = s[(s.fault_id=="none")]
for (v,c),g in nf.groupby(["variant","ultra_tight.cn0"]):
    print(v,c, f"{g.false_alarm_rate.mean():.5f}", f"[{g.false_alarm_ci_low.min():.5f}, {g.false_alarm_ci_high.max():.5f}]")
