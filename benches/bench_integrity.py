"""Speed of the protection levels, in one process.

    python benches/bench_integrity.py

Per epoch: ARAIM (``navfdi.araim``: Python call with its checks, and ``_core.araim_epoch``
alone) with 10 satellites in two constellations and 40 satellites in two constellations
(fault modes up to P_THRES), with fault detection and exclusion on residuals (consistent, and
a 60 m bias on one satellite: every candidate subset recomputed), and the snapshot-RAIM slope levels (``_core.snapshot_pl``) with
10 satellites. The peer, sidereon's ``araim`` (PyPI ``sidereon``, in the ``test`` extra), runs
on the same geometries (the receiver on the equator at the prime meridian, so the east/north/up
lines of sight map to ECEF y/z/x), the same ISM (σ_URA 0.75 m, σ_URE 0.5 m, b_nom 0.5 m,
P_sat 1e-5, P_const 1e-4) and its own LPV-200 allocation; its levels are printed beside
navfdi's.
"""

from __future__ import annotations

import time

import numpy as np

import navfdi
from navfdi import _core


def geometry(n: int) -> tuple[np.ndarray, list[str]]:
    i = np.arange(n)
    az = i * 2.399963
    el = np.radians(10 + 75 * ((i * 7) % n) / max(n - 1, 1))
    los = np.column_stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)])
    return los, ["G" if k % 2 == 0 else "E" for k in i]


def best(f, reps: int) -> float:
    out = []
    for _ in range(5):
        t = time.perf_counter()
        for _ in range(reps):
            f()
        out.append((time.perf_counter() - t) / reps)
    return min(out)


def main() -> None:
    for n, reps in ((10, 2000), (40, 100)):
        los, sys_ = geometry(n)
        t = best(lambda: navfdi.araim(los, sys_), reps)
        r = navfdi.araim(los, sys_)
        letters = sorted(set(sys_), key=sys_.index)
        tropo, user = navfdi.integrity.elevation_variances(np.arcsin(los[:, 2]))
        args = ((-los).tolist(), [letters.index(s) for s in sys_], (0.5625 + tropo + user).tolist(), (0.25 + tropo + user).tolist(), [0.5] * n, [1e-5] * n, [1e-4, 1e-4], (9.8e-8, 2e-9, 3.9e-6, 9e-8, 8e-8, 1e-5, 0.05))
        tc = best(lambda: _core.araim_epoch(*args), reps)
        print(f"ARAIM {n} satellites (2 constellations, {len(r.mode_table['prior'])} modes): navfdi.araim {t * 1e6:.1f} µs, _core.araim_epoch {tc * 1e6:.1f} µs")
        # Fault detection and exclusion: consistent residuals (tests only), and a 60 m bias
        # on one satellite (detection, every single-satellite and constellation candidate).
        y = -los @ np.array([3.0, -2.0, 5.0]) + np.where(np.array(sys_) == "G", 40.0, -25.0)
        tf = best(lambda: _core.araim_epoch(*args, y.tolist()), reps)
        yb = y.copy()
        yb[n // 2] += 60.0
        reps_x = max(reps // 20, 3)
        tx = best(lambda: _core.araim_epoch(*args, yb.tolist()), reps_x)
        rx = navfdi.araim(los, sys_, residuals=yb)
        print(f"  with residuals: {tf * 1e6:.1f} µs; with a 60 m bias (excluded {rx.excluded}, {'available' if rx.available else 'unavailable'}): {tx * 1e6:.1f} µs")
    sidereon_peer()
    los, sys_ = geometry(10)
    clock = [0 if s == "G" else 1 for s in sys_]
    ts = best(lambda: _core.snapshot_pl(los.tolist(), clock, [1.0] * 10, 20.0, 3.29), 20000)
    print(f"snapshot RAIM PL, 10 satellites: {ts * 1e6:.2f} µs")


def sidereon_peer() -> None:
    """sidereon's ``araim`` on the same geometries, when it is installed."""
    try:
        import sidereon as sd
    except ImportError:
        print("sidereon not installed: no peer figures")
        return
    systems = {"G": sd.GnssSystem.GPS, "E": sd.GnssSystem.GALILEO}
    model = sd.SatelliteIsmModel(0.75, 0.5, 0.5, 1e-5)
    ism = sd.Ism([sd.ConstellationIsm(systems[c], 1e-4, model) for c in "GE"], [])
    alloc = sd.IntegrityAllocation.lpv_200()
    for n, reps in ((10, 500), (40, 20)):
        los, sys_ = geometry(n)
        rows = [
            sd.AraimRow(f"{s}{i + 1:02d}", (float(u[2]), float(u[0]), float(u[1])), float(np.arcsin(u[2])), systems[s])
            for i, (u, s) in enumerate(zip(los, sys_))
        ]
        geo = sd.AraimGeometry(rows, sd.Wgs84Geodetic(0.0, 0.0, 0.0), [systems["G"], systems["E"]])
        t = best(lambda: sd.araim(geo, ism, alloc), reps)
        r = sd.araim(geo, ism, alloc)
        ours = navfdi.araim(los, sys_)
        print(
            f"  sidereon {n} satellites: {t * 1e6:.1f} µs, {len(r.fault_modes)} modes, VPL {r.vpl_m:.2f} m, HPL {r.hpl_m:.2f} m, "
            f"available {r.available} (navfdi: {len(ours.modes)} modes, VPL {ours.vpl:.2f} m, HPL {ours.hpl:.2f} m, available {ours.available})"
        )


if __name__ == "__main__":
    main()
