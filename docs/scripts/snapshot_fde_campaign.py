"""Snapshot FDE power on the walk's RINEX: steps injected into every satellite in turn, exact
exclusion per size and elevation with the global test, data snooping (w-test) and both,
beside RTKLIB's RAIM (``rnx2rtkp``, ``pos1-posopt5 = on``) on the same faulted files.

Usage: ``python docs/scripts/snapshot_fde_campaign.py [WEIGHTING [SLOPE [FACTOR]]]`` (default ``cn0``; or
``elevation``; SLOPE the C/N0 model's ``cn0_slope``, a number or ``auto``, default 1; FACTOR the
σ factor, default ``auto``: ``elevation 1 1`` is the σ model as given) prints the markdown tables of ``docs/gnss_real.md``. Needs RTKLIB's
``rnx2rtkp`` on the PATH (Debian package ``rtklib``) for its column.

Settings: G + E (C1C, C1X), 10° mask, α = 0.01, the allocation's power β0 = 0.8, the σ factor
``--noise auto`` estimates on the clean file (kept for every faulted run, as the fault-free
first pass of ``noise_scale="auto"`` would give it). Fault window 20–100 s (320 epochs at
4 Hz). A satellite-epoch counts when the faulty satellite is in the solution's set (used or
excluded); exact = it alone is excluded. RTKLIB's exclusions are read from its solution
status file (``$SAT`` lines list the satellites it kept): exact = the faulty satellite missing
and every other satellite of the clean RTKLIB run kept. The 1.5 × MDB row steps each satellite
by 1.5 × its own median minimal detectable bias over the window (reported by navfdi).
"""

from __future__ import annotations

import gzip
import shutil
import subprocess
import sys
import tempfile
import warnings
from collections import defaultdict
from pathlib import Path

import numpy as np

from navfdi.gnss import gnss_solve
from noise_auto_bursts import add_to_first_code  # same folder (run as a script)

DATA = Path(__file__).resolve().parents[2] / "python" / "navfdi" / "data" / "walk_0827"
OBS, NAV = DATA / "gnss_1730.obs.gz", DATA / "gnss_1730.nav"
T0, T1 = 20.0, 100.0
SIZES = [5.0, 10.0, 20.0, 40.0]
TESTS = ["global", "wtest", "both", "auto"]
RTKLIB_CONF = """pos1-posmode=single
pos1-elmask=10
pos1-navsys=9
pos1-ionoopt=brdc
pos1-tropopt=saas
pos1-posopt5=on
out-outstat=residual
"""


def faulted_rinex(src: Path, dst: Path, sat: str, size: float) -> None:
    """``src`` with ``size`` m added to ``sat``'s first observation (C1C / C1X) over the window."""
    add_to_first_code(src, dst, lambda s, t: size if s == sat and T0 <= t < T1 else 0.0)


def rtklib_kept(obs: Path, work: Path) -> dict[float, set[str]]:
    """RTKLIB single-point RAIM on ``obs``: per epoch (s of week), the satellites it kept."""
    conf, pos = work / "raim.conf", work / "out.pos"
    conf.write_text(RTKLIB_CONF)
    subprocess.run(["rnx2rtkp", "-k", str(conf), "-o", str(pos), str(obs), str(NAV)], check=True, capture_output=True)
    kept: dict[float, set[str]] = defaultdict(set)
    for line in (work / "out.pos.stat").read_text().splitlines():
        if line.startswith("$SAT"):
            f = line.split(",")
            kept[round(float(f[2]), 2)].add(f[3])
    return kept


def main() -> None:
    warnings.simplefilter("ignore")
    weighting = sys.argv[1] if len(sys.argv) > 1 else "cn0"
    slope: float | str = 1.0 if len(sys.argv) < 3 else (sys.argv[2] if sys.argv[2] == "auto" else float(sys.argv[2]))
    factor: float | str = "auto" if len(sys.argv) < 4 or sys.argv[3] == "auto" else float(sys.argv[3])
    common: dict[str, object] = dict(systems="G,E", weighting=weighting)
    first = gnss_solve(OBS, NAV, noise_scale=factor, cn0_slope=slope, **common).config
    scale = first["noise_scale"]
    common["noise_scale"] = scale
    common["cn0_slope"] = first["cn0_slope"]
    clean = {t: gnss_solve(OBS, NAV, test=t, **common) for t in TESTS}
    sol = clean["global"].solution
    tt = (sol["gps_seconds"] - sol["gps_seconds"].iloc[0]).to_numpy()
    win = np.flatnonzero((tt >= T0) & (tt < T1))
    sats = clean["global"].satellites
    inwin = sats[sats["epoch"].isin(win) & (sats["status"].isin(["used", "excluded"]))]
    counts = inwin.groupby("satellite", observed=True).size()
    cand = sorted(s for s, n in counts.items() if n >= 0.9 * len(win))
    elev = inwin.groupby("satellite", observed=True)["elevation"].mean()
    mdb = {t: clean[t].satellites[clean[t].satellites["epoch"].isin(win)].groupby("satellite", observed=True)["mdb"].median() for t in TESTS}
    print(f"walk_0827, G+E, weighting {weighting} (C/N0 slope {common['cn0_slope']:.2f}), sigma factor {scale:.2f} (--noise {factor}); {len(cand)} satellites in view over {T0:g}-{T1:g} s")
    for t in TESTS:
        c = clean[t].solution
        print(f"clean file, {t}: epochs with an exclusion {(c['excluded'] != '').mean():.2%} (alpha 1 %)")
    rtk = shutil.which("rnx2rtkp") is not None
    rows: dict[tuple[str, str], list[float]] = defaultdict(list)  # (size label, test) -> per-sat exact rates
    per_sat: dict[str, dict[str, float]] = defaultdict(dict)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        plain = work / "clean.obs"
        plain.write_text(gzip.open(OBS, "rt").read())
        kept_clean = rtklib_kept(plain, work) if rtk else {}
        for sat in cand:
            for label, size in [*((f"{s:g} m", s) for s in SIZES), ("1.5 x MDB", 1.5 * float(mdb["global"][sat]))]:
                fault = f"{sat}:step:{size:.3f}m:{T0:g}s:{T1:g}s"
                for t in TESTS:
                    s = gnss_solve(OBS, NAV, test=t, faults=[fault], **common)
                    so, st = s.solution, s.satellites
                    rows_sat = st[st["epoch"].isin(win) & (st["satellite"] == sat) & st["status"].isin(["used", "excluded"])]
                    ep = rows_sat["epoch"].to_numpy()
                    exact = (so["excluded"].to_numpy()[ep] == sat).mean() if len(ep) else np.nan
                    rows[(label, t)].append(exact)
                    per_sat[sat][f"{label} {t}"] = exact
                if rtk:
                    fo = work / "fault.obs"
                    faulted_rinex(OBS, fo, sat, size)
                    kept = rtklib_kept(fo, work)
                    n = ok = 0
                    for tow, ks in kept_clean.items():
                        rel = tow - min(kept_clean)
                        if not (T0 <= rel < T1) or sat not in ks:
                            continue
                        n += 1
                        ok += kept.get(tow, set()) == ks - {sat}
                    rows[(label, "rtklib")].append(ok / n if n else np.nan)
                    per_sat[sat][f"{label} rtklib"] = ok / n if n else np.nan
    cols = TESTS + (["rtklib"] if rtk else [])
    print("\nexact exclusion, mean over satellites (epochs of the fault window with the satellite in view)\n")
    print("| step | " + " | ".join(cols) + " |")
    print("|---|" + "---:|" * len(cols))
    for label in [*(f"{s:g} m" for s in SIZES), "1.5 x MDB"]:
        print(f"| {label} | " + " | ".join(f"{np.nanmean(rows[(label, c)]):.1%}" for c in cols) + " |")
    print("\nby elevation (mean over the satellites of each band)\n")
    bands = [(10, 30), (30, 60), (60, 91)]
    print("| step | test | " + " | ".join(f"{a}-{min(b, 90)} deg" for a, b in bands) + " |")
    print("|---|---|" + "---:|" * len(bands))
    for label in [*(f"{s:g} m" for s in SIZES), "1.5 x MDB"]:
        for c in cols:
            cells = []
            for a, b in bands:
                v = [per_sat[s][f"{label} {c}"] for s in cand if a <= elev[s] < b]
                cells.append(f"{np.nanmean(v):.0%} ({len(v)})" if v else "-")
            print(f"| {label} | {c} | " + " | ".join(cells) + " |")
    print("\nmedian MDB per satellite over the window (m): " + ", ".join(f"{s} {float(mdb['global'][s]):.1f} ({elev[s]:.0f} deg)" for s in cand))


if __name__ == "__main__":
    main()
