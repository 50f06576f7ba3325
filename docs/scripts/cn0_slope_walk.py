"""The C/N0 model's slope from the file (``--cn0-slope auto``) on the walk's RINEX: the real file
and the file with white code noise added that follows the C/N0 model at a known slope, each
solved with the σ–ε model's slope 1 and with the slope estimated (used where above 1, and
with the estimate forced, to show what the floor keeps out).

Usage: ``python docs/scripts/cn0_slope_walk.py`` prints the markdown table of
``docs/gnss_real.md`` ("The C/N0 model's slope"): per file and slope, the slope used, the σ
factor ``--noise auto`` estimates at it, the fault-free epochs with an exclusion, the median
minimal detectable bias and the share of a 10 m and a 20 m step's epochs (40–100 s) with the
satellite excluded, on E26 (80°, 45–50 dB-Hz) and G23 (50°, the weakest GPS signal). G + E,
10° mask, α = 0.01, global test.
"""

from __future__ import annotations

import gzip
import math
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

from navfdi.gnss import gnss_solve

DATA = Path(__file__).resolve().parents[2] / "python" / "navfdi" / "data" / "walk_0827"
OBS, NAV = DATA / "gnss_1730.obs.gz", str(DATA / "gnss_1730.nav")
SYNTHETIC = [(1.8, 3.0), (0.3, 3.0)]  # (slope, scale) of the added noise


def cn0_noise(src: Path, nav: str, dst: Path, slope: float, scale: float, seed: int = 0) -> Path:
    """``src`` (RINEX 3, gzip) written to ``dst`` with white noise added to every GPS and
    Galileo satellite's first code (C1C, C1X), of the σ the C/N0 model gives at ``slope`` times
    ``scale``: ``scale · √(0.3² + 0.3²/sin² el) · 10^(slope (45 − C/N0)/20)`` m, C/N0 the
    line's own (``S1C`` beside ``C1C``), elevation the clean file's solution's; a satellite
    without either is left as is (numpy ``default_rng(seed)``)."""
    clean = gnss_solve(str(src), nav, systems="G,E", exclude=False, weighting="elevation").satellites
    elevation = {(int(e), str(s)): float(x) for e, s, x in zip(clean["epoch"], clean["satellite"], clean["elevation"])}
    rng = np.random.default_rng(seed)
    types: dict[str, list[str]] = {}
    out, header, last, epoch = [], True, "", -1
    for line in gzip.open(src, "rt").read().splitlines(keepends=True):
        if header:
            if line[60:].startswith("SYS / # / OBS TYPES"):
                last = line[0] if line[0] != " " else last
                types.setdefault(last, []).extend(line[7:60].split())
            header = "END OF HEADER" not in line
        elif line.startswith(">"):
            epoch += 1
        elif line[:1] in ("G", "E") and line[1:3].isdigit():
            ty, el = types[line[0]], elevation.get((epoch, line[:3]), math.nan)
            code = next((c for c in ty if c.startswith("C")), "")
            if code and "S" + code[1:] in ty and math.isfinite(el):
                ci, si = ty.index(code), ty.index("S" + code[1:])
                value, cn0 = line[3 + 16 * ci : 17 + 16 * ci], line[3 + 16 * si : 17 + 16 * si]
                if value.strip() and cn0.strip():
                    sd = scale * 0.3 * math.sqrt(1.0 + 1.0 / math.sin(math.radians(el)) ** 2) * 10 ** (slope * (45.0 - float(cn0)) / 20.0)
                    at = 3 + 16 * ci
                    line = f"{line[:at]}{float(value) + rng.normal(0.0, sd):14.3f}{line[at + 14 :]}"
        out.append(line)
    dst.write_text("".join(out))
    return dst


def excluded(run, sat: str, t0: float = 40.0, t1: float = 100.0) -> float:
    """Share of the epochs in [t0, t1) s from the first with ``sat`` among the excluded."""
    sol = run.solution
    t = sol["gps_seconds"] - sol["gps_seconds"].iloc[0]
    return float(sol.loc[(t >= t0) & (t < t1), "excluded"].fillna("").astype(str).str.split().apply(lambda s: sat in s).mean())


def row(name: str, obs: str, how: str) -> str:
    """One table row: ``how`` is ``"1"`` (the σ–ε slope), ``"auto"`` or ``"estimate"`` (the
    estimate forced, below 1 too)."""
    common = dict(systems="G,E", weighting="cn0")
    slope: float | str = 1.0 if how == "1" else "auto"
    if how == "estimate":
        slope = gnss_solve(obs, NAV, exclude=False, **common).config["cn0_slope_auto"]["estimate"]
    base = gnss_solve(obs, NAV, noise_scale="auto", cn0_slope=slope, **common)
    s, used, scale = base.summary(), base.config["cn0_slope"], base.config["noise_scale"]
    est = base.config.get("cn0_slope_auto", {}).get("estimate", math.nan)
    cells = [name, {"1": "1 (σ–ε)", "auto": "auto", "estimate": "estimate forced"}[how], f"{used:.2f}" + (f" (fitted {est:.2f})" if how == "auto" else ""), f"{scale:.2f}", f"{s['false_exclusion_rate']:.1%}", f"{s['mdb_median']:.1f} m"]
    for sat in ("E26", "G23"):
        for size in (10, 20):
            run = gnss_solve(obs, NAV, noise_scale=scale, cn0_slope=used, faults=[f"{sat}:step:{size}m:40s:100s"], **common)
            cells.append(f"{excluded(run, sat):.0%}")
    return "| " + " | ".join(cells) + " |"


def main() -> None:
    warnings.simplefilter("ignore")
    print("| file | slope | used | σ factor | fault-free epochs with an exclusion | median MDB | E26 10 m | E26 20 m | G23 10 m | G23 20 m |")
    print("|---|---|---|---:|---:|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        files = [("walk (real)", str(OBS))]
        for slope, scale in SYNTHETIC:
            files.append((f"walk + noise at slope {slope:g}", str(cn0_noise(OBS, NAV, Path(tmp) / f"s{slope:g}.obs", slope, scale))))
        for name, obs in files:
            for how in ("1", "auto", "estimate"):
                print(row(name, obs, how), flush=True)
                sys.stdout.flush()


if __name__ == "__main__":
    main()
