"""The snapshot tests on heavy-tailed residuals: false exclusions and power of the global test,
data snooping (w-test) and ``auto`` as the number of satellites grows, with the σ factor that
``--noise auto`` fits (the whole file's: the 90th percentile of ``T / χ²₀.₉(dof)`` without
exclusion).

Usage: ``python docs/scripts/heavy_tails_tests.py [EPOCHS]`` (default 2000 per case) prints
the markdown table of ``docs/gnss_real.md``.

Per case: a receiver at 45° N, 7° E; per epoch n satellites at elevations uniform in 10–90°
and random azimuths; code errors of unit σ as given to the solver, drawn from
* ``gauss``: the normal distribution (what the tests assume);
* ``t4``: Student's t with 4 degrees of freedom, scaled to unit variance (heavy tails, no
  satellite worse than another);
* ``mix``: 10 % of the satellite-epochs with 3× the σ (a share of satellites degraded by
  multipath at any time).
α = 0.01. False exclusions: epochs with any exclusion, fault-free. Power: a step of 6 × the
fitted σ on one satellite (each in turn), exact = it alone excluded.
"""

from __future__ import annotations

import sys

import numpy as np
from scipy.stats import chi2

import navfdi
from navfdi.gnss import enu_rotation, lla_to_ecef

ALPHA = 0.01
SIZES = (8, 12, 17, 25, 36)
KINDS = ("gauss", "t4", "mix")
TESTS = ("global", "wtest", "auto")
STEP = 6.0  # × the fitted σ


def draw(kind: str, n: int, rng: np.random.Generator) -> np.ndarray:
    """n unit-variance code errors of the given kind (m)."""
    if kind == "gauss":
        return rng.standard_normal(n)
    if kind == "t4":
        return rng.standard_t(4, n) / np.sqrt(2.0)  # t4 has variance 2
    if kind == "mix":
        return np.where(rng.random(n) < 0.1, 3.0, 1.0) * rng.standard_normal(n)
    raise ValueError(kind)


def case(kind: str, n: int, epochs: int, seed: int = 1) -> dict[str, float]:
    """False-exclusion rate and exact exclusion of a 6σ step per test, and the fitted factor."""
    rng = np.random.default_rng(seed)
    rx = np.asarray(lla_to_ecef(45.0, 7.0, 200.0))
    rot = enu_rotation(45.0, 7.0)
    x0 = [*rx, 0.0]
    geo, pr = [], []
    for _ in range(epochs):
        el = np.radians(rng.uniform(10.0, 90.0, n))
        az = rng.uniform(0.0, 2.0 * np.pi, n)
        u = np.column_stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)]) @ rot
        sats = rx + 2.2e7 * u
        geo.append(sats)
        pr.append(np.linalg.norm(sats - rx, axis=1) + 100.0 + draw(kind, n, rng))
    ones = np.ones(n)
    t = [navfdi.snapshot_fde(g, p, ones, alpha=ALPHA, x0=x0).statistic / chi2.ppf(0.9, n - 4) for g, p in zip(geo, pr)]
    f = float(np.sqrt(np.quantile(t, 0.9)))
    sigma = np.full(n, f)
    out: dict[str, float] = {"factor": f}
    for test in TESTS:
        false = exact = 0
        for i, (g, p) in enumerate(zip(geo, pr)):
            false += len(navfdi.snapshot_fde(g, p, sigma, alpha=ALPHA, x0=x0, test=test).excluded) > 0
            j = i % n
            q = p.copy()
            q[j] += STEP * f
            exact += list(navfdi.snapshot_fde(g, q, sigma, alpha=ALPHA, x0=x0, test=test).excluded) == [j]
        out[f"{test}_false"] = false / epochs
        out[f"{test}_exact"] = exact / epochs
    return out


def main() -> None:
    epochs = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
    print(f"{epochs} epochs per case, α = {ALPHA}; false exclusions (fault-free) and a {STEP:g}σ step excluded exactly")
    print()
    print("| errors | satellites | σ factor fitted | false: global / wtest / auto | 6σ step exact: global / wtest / auto |")
    print("|---|---:|---:|---|---|")
    for kind in KINDS:
        for n in SIZES:
            r = case(kind, n, epochs)
            false = " / ".join(f"{100 * r[f'{t}_false']:.1f} %" for t in TESTS)
            exact = " / ".join(f"{100 * r[f'{t}_exact']:.0f} %" for t in TESTS)
            print(f"| {kind} | {n} | {r['factor']:.2f} | {false} | {exact} |", flush=True)


if __name__ == "__main__":
    main()
