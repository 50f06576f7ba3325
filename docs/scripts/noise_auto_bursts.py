"""``--noise auto`` on files whose statistic is set by their faults: the walk's RINEX with
multipath-like bursts added to every satellite's first code observation (back-to-back 5–20 s
windows, each biased by ±U(10, 40) m with probability SHARE), beside the clean file.

Usage: ``python docs/scripts/noise_auto_bursts.py`` prints the markdown table of
``docs/gnss_real.md``: per weighting, burst share and seed, the whole file's factor, the factor
with the faults excluded, the one ``auto`` uses, and the share of a 20 m step's epochs
(E26, 40–100 s, bursts on E26 itself kept) with E26 excluded at the factor used and at the
whole file's factor (what ``auto`` gave before). G + E, 10° mask, α = 0.01, global test.
"""

from __future__ import annotations

import gzip
import sys
import tempfile
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

from navfdi.gnss import gnss_solve

DATA = Path(__file__).resolve().parents[2] / "python" / "navfdi" / "data" / "walk_0827"
OBS, NAV = DATA / "gnss_1730.obs.gz", str(DATA / "gnss_1730.nav")
SHARES = [0.05, 0.1, 0.2, 0.3]
SEEDS = [0, 1, 2]


def bursts(dst: Path, share: float, seed: int, obs: Path = OBS) -> Path:
    """``obs`` (RINEX 3, gzip) written to ``dst`` with bursts on every G/E satellite's first
    code: back-to-back 5–20 s windows from a U(0, 20) s start, each biased by ±U(10, 40) m with
    probability ``share`` (numpy ``default_rng(seed)``)."""
    rng = np.random.default_rng(seed)
    lines = gzip.open(obs, "rt").read().splitlines(keepends=True)
    sats = sorted({ln[:3] for ln in lines if ln[:1] in "GE" and ln[1:3].isdigit()})
    plan: dict[str, list[tuple[float, float, float]]] = {}
    for s in sats:
        windows, t = [], rng.uniform(0, 20)
        while t < 140:
            d = rng.uniform(5, 20)
            if rng.random() < share:
                windows.append((t, t + d, float(rng.choice([-1, 1]) * rng.uniform(10, 40))))
            t += d
        plan[s] = windows
    return add_to_first_code(obs, dst, lambda sat, t: sum(v for a, b, v in plan.get(sat, ()) if a <= t < b))


def add_to_first_code(src: Path, dst: Path, bias: Callable[[str, float], float]) -> Path:
    """``src`` (RINEX 3, gzip) written to ``dst`` with ``bias(satellite, t)`` m added to each
    satellite's first observation (its first code: C1C, C1X), ``t`` in s from the first epoch."""
    out, header, t0, t = [], True, None, 0.0
    for line in gzip.open(src, "rt").read().splitlines(keepends=True):
        if header:
            header = "END OF HEADER" not in line
        elif line.startswith(">"):
            f = line[1:].split()
            sec = int(f[3]) * 3600 + int(f[4]) * 60 + float(f[5])
            t0 = sec if t0 is None else t0
            t = sec - t0
        elif line[:1].isalpha() and line[1:3].isdigit() and line[3:17].strip():
            add = bias(line[:3], t)
            if add:
                line = f"{line[:3]}{float(line[3:17]) + add:14.3f}{line[17:]}"
        out.append(line)
    dst.write_text("".join(out))
    return dst


def excluded_share(run, sat: str = "E26", t0: float = 40.0, t1: float = 100.0) -> float:
    """Share of the epochs in [t0, t1) s from the first with ``sat`` among the excluded."""
    sol = run.solution
    t = sol["gps_seconds"] - sol["gps_seconds"].iloc[0]
    excluded = sol.loc[(t >= t0) & (t < t1), "excluded"].fillna("").astype(str)
    return float(excluded.str.split().apply(lambda s: sat in s).mean())


def main() -> None:
    warnings.simplefilter("ignore")
    work = Path(tempfile.mkdtemp())
    print("| weighting | bursts | seed | whole file | faults excluded | used | 20 m on E26 excluded: used / whole file |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for weighting in ("elevation", "cn0"):
        clean = gnss_solve(str(OBS), NAV, systems="G,E", weighting=weighting, noise_scale="auto")
        a = clean.config["noise_scale_auto"]
        step = gnss_solve(str(OBS), NAV, systems="G,E", weighting=weighting, noise_scale=a["scale"], faults=["E26:step:20m:40s:100s"])
        print(f"| {weighting} | none | – | {a['whole_file']:.2f} | {a['faults_excluded']:.2f} | {a['scale']:.2f} ({a['method']}) | {excluded_share(step):.0%} / {excluded_share(step):.0%} |")
        for share in SHARES:
            for seed in SEEDS:
                obs = str(bursts(work / "b.obs", share, seed))
                a = gnss_solve(obs, NAV, systems="G,E", weighting=weighting, noise_scale="auto").config["noise_scale_auto"]
                got = [excluded_share(gnss_solve(obs, NAV, systems="G,E", weighting=weighting, noise_scale=s, faults=["E26:step:20m:40s:100s"])) for s in (a["scale"], a["whole_file"])]
                print(f"| {weighting} | {share:.0%} | {seed} | {a['whole_file']:.2f} | {a['faults_excluded']:.2f} | {a['scale']:.2f} ({a['method']}) | {got[0]:.0%} / {got[1]:.0%} |")
                sys.stdout.flush()


if __name__ == "__main__":
    main()
