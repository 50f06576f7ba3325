"""Regenerate the numbers of docs/geng2016.md: ``python docs/scripts/geng2016_table.py [RUNS]``
(default 1000 Monte-Carlo runs; 20 seeds for the per-seed figures)."""

from __future__ import annotations

import copy
import math
import sys

import numpy as np
from scipy import stats

import navfdi


def per_seed(seeds: range) -> None:
    sc = navfdi.load_scenario("geng2016")
    ratios: dict[str, list[float]] = {"chi2": [], "state": []}
    iso: dict[str, list[float]] = {"gnss": [], "baro": [], "ra": []}
    rms: dict[str, list[float]] = {"isolation": [], "no_isolation": []}
    for seed in seeds:
        res = navfdi.run_scenario(sc, seed=seed)
        r = res["isolation"]
        for det in ratios:
            med = {s: np.nanmedian(r.detector(s, det)["statistic"]) for s in ("gnss", "baro", "ra")}
            ratios[det].append(med["ra"] / max(med["gnss"], med["baro"]))
        for s in iso:
            present = np.isfinite(r.detector(s, "chi2")["statistic"])
            iso[s].append(r.isolated(s)[present].mean())
        for v in rms:
            f = res[v].record["fused_alt"]
            rms[v].append(math.sqrt(np.nanmean(f**2)))
    print(f"## {len(seeds)} seeds, variant isolation")
    for det, v in ratios.items():
        print(f"RA / max(GNSS, baro) median {det} statistic: min {min(v):.1f}, median {np.median(v):.1f}")
    for s, v in iso.items():
        print(f"{s} isolated (of epochs measured): min {min(v):.3f}, median {np.median(v):.3f}, max {max(v):.3f}")
    ri, rn = np.array(rms["isolation"]), np.array(rms["no_isolation"])
    print(f"fused-altitude RMS: isolation {math.sqrt(np.mean(ri**2)):.3f} m, no_isolation {math.sqrt(np.mean(rn**2)):.3f} m, pooled ratio {math.sqrt(np.mean(ri**2) / np.mean(rn**2)):.3f}, per-seed ratio {np.min(ri / rn):.2f}–{np.max(ri / rn):.2f}")


def drift(seeds: range) -> None:
    print("\n## baro ramp from 10 s (isolation variant): sustained detection (≥ 20 % of a 2 s window)")
    base = navfdi.load_scenario("geng2016").raw
    for slope in ("0.02 m/s", "0.05 m/s", "0.1 m/s", "0.2 m/s"):
        raw = copy.deepcopy(base)
        raw["faults"] = [{"id": "baro-drift", "sensor": "baro", "components": "all", "kind": "ramp", "magnitude": slope, "start": "10 s", "end": "50 s"}]
        sc = navfdi.load_scenario(raw)
        out = {"chi2": ([], []), "state": ([], [])}
        for seed in seeds:
            r = navfdi.run_scenario(sc, seed=seed)["isolation"]
            t = r.t
            for det, (delays, rates) in out.items():
                a = r.detector("baro", det)["alarm"]
                k = np.convolve(a.astype(float), np.ones(20) / 20)[: t.size]
                hit = np.flatnonzero((k >= 0.2) & (t >= 10))
                delays.append(t[hit[0]] - 10 if hit.size else np.nan)
                rates.append(a[t >= 10].mean())
        for det, (delays, rates) in out.items():
            d = np.array(delays)
            med = f"{np.nanmedian(d):.1f} s" if np.isfinite(d).any() else "-"
            print(f"{slope:>9} {det:>5}: detected {np.isfinite(d).sum()}/{len(d)}, median delay {med}, alarm rate after 10 s {np.mean(rates):.3f}")


def campaign(runs: int) -> None:
    print(f"\n## Monte-Carlo, {runs} runs")
    for label, strip_bias in (("as bundled (baro offset σ 0.1 m)", False), ("without the baro offset", True)):
        sc = navfdi.load_scenario("geng2016")
        if strip_bias:
            raw = copy.deepcopy(sc.raw)
            for s in raw["sensors"]:
                s.pop("bias", None)
            sc = navfdi.load_scenario(raw)
        c = navfdi.montecarlo(sc, runs=runs, seed=0, progress=False)
        s = c.summary().set_index(["variant", "subfilter", "detector"])
        fi, fn = s.loc[("isolation", "ra", "chi2"), "fused_alt_rms"], s.loc[("no_isolation", "ra", "chi2"), "fused_alt_rms"]
        print(f"{label}: fused-altitude RMS isolation {fi:.3f} m, no_isolation {fn:.3f} m, ratio {fi / fn:.3f}")
        for sub in ("gnss", "slam", "baro"):
            for det in ("chi2", "state"):
                row = s.loc[("isolation", sub, det)]
                print(f"  isolation {sub:>4} {det:>5}: false alarms per epoch {row.false_alarm_rate:.4f} [{row.false_alarm_ci_low:.4f}, {row.false_alarm_ci_high:.4f}]")
    # The navigation solution's own state test (not in the summary: it has no sensor).
    sc = navfdi.load_scenario("geng2016")
    al, n = 0, 0
    for seed in range(min(runs, 200)):
        st = navfdi.run_scenario(sc, seed=seed)["isolation"].record["state_chi2"]
        ready = st["ready"] & ~st["ill_conditioned"]
        al += int(st["alarm"][ready].sum())
        n += int(ready.sum())
    lo, hi = stats.binom.interval(0.99, n, 0.01)
    print(f"navigation state test (isolation, {min(runs, 200)} runs): {al}/{n} = {al / n:.4f} per tested epoch (99 % interval of pf = 0.01 for independent epochs: {lo / n:.4f}–{hi / n:.4f})")


if __name__ == "__main__":
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
    per_seed(range(20))
    drift(range(20))
    campaign(n)
