"""Two faults at once on the bundled static file (``tests/data/rinex``, G + E): every pair of
the satellites used throughout 10–50 s biased by the same step (default 30 m) over that
window; the share of the window's epochs in which exactly the two are excluded, per test.

Usage: ``python docs/scripts/two_faults.py [STEP_M]`` prints the line of ``docs/gnss_real.md``.
"""

from __future__ import annotations

import itertools
import sys
import warnings
from pathlib import Path

from navfdi.gnss import gnss_solve

DATA = Path(__file__).resolve().parents[2] / "tests" / "data" / "rinex"
OBS, NAV = str(DATA / "rover.obs.gz"), str(DATA / "base.nav")


def main() -> None:
    warnings.simplefilter("ignore")
    step = float(sys.argv[1]) if len(sys.argv) > 1 else 30.0
    given = {"weighting": "elevation", "noise_scale": 1.0}  # the σ model as given, as documented
    clean = gnss_solve(OBS, NAV, systems="G,E", **given)
    sats = clean.satellites
    t = (sats["time"] - sats["time"].min()).dt.total_seconds()
    window = sats[(t >= 10) & (t < 50) & (sats["status"] == "used")]
    n_epochs = window["epoch"].nunique()
    counts = window["satellite"].astype(str).value_counts()
    always = sorted(s for s, c in counts.items() if c == n_epochs)
    for test in ("global", "wtest"):
        exact, pairs = 0.0, 0
        for a, b in itertools.combinations(always, 2):
            run = gnss_solve(OBS, NAV, systems="G,E", test=test, faults=[f"{a}:step:{step:g}m:10s:50s", f"{b}:step:{step:g}m:10s:50s"], **given)
            sol = run.solution
            tt = sol["gps_seconds"] - sol["gps_seconds"].iloc[0]
            ex = sol.loc[(tt >= 10) & (tt < 50), "excluded"].fillna("").astype(str).str.split()
            exact += float(ex.apply(lambda s: sorted(s) == sorted([a, b])).mean())
            pairs += 1
        print(f"{test}: {len(always)} satellites, {pairs} pairs, {step:g} m each: both and only both excluded in {exact / pairs:.1%} of the epochs")


if __name__ == "__main__":
    main()
