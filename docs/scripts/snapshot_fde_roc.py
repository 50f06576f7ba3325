"""The default snapshot FDE against the σ model as given, at matched false-exclusion rates.

Usage: ``python docs/scripts/snapshot_fde_roc.py`` prints the markdown table of
``docs/gnss_real.md`` ("At equal false exclusions"). Both settings run the global test on the
walk's RINEX (G + E, 10° mask) at several α: the default (``--weighting auto``, which takes
the C/N0 model on this file, and ``--noise auto``'s factor from the clean file) and the σ
model as given (``--weighting elevation --noise 1``, the default before 2026-11-27). Per α:
the share of the clean file's epochs with an exclusion, and the exact exclusion of 5 m and
10 m steps injected into each satellite in view in turn (20–100 s; the campaign script's
counting: a satellite-epoch counts when the faulty satellite is in the solution's set, exact
= it alone is excluded), mean over the satellites. A detector is compared with another at
the same false-exclusion rate (the operating points of both are printed), not at the same α.
"""

from __future__ import annotations

import sys
import warnings

import numpy as np

from navfdi.gnss import gnss_solve
from snapshot_fde_campaign import NAV, OBS, T0, T1  # same folder (run as a script)

SIZES = [5.0, 10.0]
SETTINGS = {
    "default (C/N0 model, --noise auto)": dict(weighting="auto", noise_scale="auto"),
    "σ model as given (elevation, factor 1)": dict(weighting="elevation", noise_scale=1.0),
}
ALPHAS = [1e-6, 1e-4, 1e-3, 0.01, 0.05, 0.2]


def main() -> None:
    warnings.simplefilter("ignore")
    alphas = [float(a) for a in sys.argv[1:]] or ALPHAS
    print("| setting | α | clean epochs with an exclusion | 5 m exact | 10 m exact |")
    print("|---|---:|---:|---:|---:|")
    for name, kw in SETTINGS.items():
        common: dict[str, object] = dict(systems="G,E", **kw)
        first = gnss_solve(OBS, NAV, **common).config  # the factor and slope on the clean file
        common["noise_scale"], common["cn0_slope"] = first["noise_scale"], first["cn0_slope"]
        for alpha in alphas:
            clean = gnss_solve(OBS, NAV, alpha=alpha, **common)
            sol, sats = clean.solution, clean.satellites
            tt = (sol["gps_seconds"] - sol["gps_seconds"].iloc[0]).to_numpy()
            win = np.flatnonzero((tt >= T0) & (tt < T1))
            inwin = sats[sats["epoch"].isin(win) & sats["status"].isin(["used", "excluded"])]
            counts = inwin.groupby("satellite", observed=True).size()
            cand = sorted(s for s, n in counts.items() if n >= 0.9 * len(win))
            exact: dict[float, list[float]] = {s: [] for s in SIZES}
            for sat in cand:
                for size in SIZES:
                    s = gnss_solve(OBS, NAV, alpha=alpha, faults=[f"{sat}:step:{size:.3f}m:{T0:g}s:{T1:g}s"], **common)
                    st = s.satellites
                    ep = st[st["epoch"].isin(win) & (st["satellite"] == sat) & st["status"].isin(["used", "excluded"])]["epoch"].to_numpy()
                    exact[size].append((s.solution["excluded"].to_numpy()[ep] == sat).mean() if len(ep) else np.nan)
            false = (sol["excluded"] != "").mean()
            print(f"| {name} (factor {float(common['noise_scale']):.2f}) | {alpha:g} | {false:.1%} | {np.nanmean(exact[5.0]):.1%} | {np.nanmean(exact[10.0]):.1%} |", flush=True)


if __name__ == "__main__":
    main()
