"""The numbers of docs/walk_tc.md: the tight filter on the recorded walk (bundled ``walk_tc``)
against its reference, beside single-point positioning on the same epochs.

    python docs/scripts/walk_tc_numbers.py [--rtklib]

``--rtklib`` also runs Debian's ``rnx2rtkp`` (RTKLIB 2.4.3, single point, GPS+Galileo, 10° mask)
on the same RINEX files. Every horizontal spread is about the reference (the receiver's RTK
solution) with the mean offset over the compared epochs removed: that reference's base is off
by several metres (data README).
"""

from __future__ import annotations

import gzip
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

import navfdi
from navfdi import logs

R_EARTH = 6.371e6
HIGH, LOW = "E26", "G27"   # elevation about 80° and 32°
WINDOW = (50.0, 90.0)
OUTAGES = [(30.0, 40.0), (60.0, 70.0), (85.0, 95.0), (100.0, 110.0)]


def base() -> navfdi.Scenario:
    return navfdi.load_scenario("walk_tc").with_value("faults", [])


def runs(sc: navfdi.Scenario) -> dict[str, dict]:
    src = logs.logged_source(sc)
    return {name: src.run([v.to_json()])[0] for name, v in sc.variants()}


def moved(r: dict, r0: dict) -> np.ndarray:
    """Horizontal distance (m) of run ``r``'s antenna from ``r0``'s per epoch."""
    a, b = r["nav"], r0["nav"]
    dn = (a[:, 0] - b[:, 0]) * R_EARTH
    de = (a[:, 1] - b[:, 1]) * R_EARTH * np.cos(b[:, 0])
    return np.hypot(dn, de)


def spread(en: np.ndarray) -> tuple[float, float]:
    """RMS and max of the horizontal error (east, north columns) with its mean removed."""
    d = en - en.mean(axis=0)
    h = np.hypot(d[:, 0], d[:, 1])
    return float(np.sqrt(np.mean(h**2))), float(h.max())


def reference_en(t_gps: np.ndarray, lat: np.ndarray, lon: np.ndarray, ref: logs.PosLog) -> tuple[np.ndarray, np.ndarray]:
    """East, north (m) of positions minus the reference at the matching epochs (within 10 ms),
    and the mask of matched epochs."""
    k = np.clip(np.searchsorted(ref.t, t_gps), 1, len(ref.t) - 1)
    k = np.where(np.abs(ref.t[k - 1] - t_gps) < np.abs(ref.t[k] - t_gps), k - 1, k)
    ok = np.abs(ref.t[k] - t_gps) < 0.01
    lat0 = np.radians(ref.lat[k])
    e = (np.radians(lon) - np.radians(ref.lon[k])) * R_EARTH * np.cos(lat0)
    n = (np.radians(lat) - lat0) * R_EARTH
    return np.column_stack([e, n]), ok


def main() -> None:
    sc = base()
    folder = logs.scenario_folder(sc)
    obs, nav = folder / sc.raw["source"]["rinex_obs"], folder / sc.raw["source"]["rinex_nav"]
    ref = logs.read_pos(folder / sc.raw["source"]["reference"])
    src = logs.logged_source(sc)
    t0 = src.time0
    r0 = runs(sc)
    print("## Fault-free: horizontal spread about the reference (mean offset removed), RMS / max [m]")
    first = next(iter(r0.values()))
    t_gps = first["t"] + t0
    alive = np.isfinite(first["nav"][:, 0])
    spp = navfdi.gnss_solve(str(obs), str(nav), systems="G,E", weighting="elevation", noise_scale=1.0)
    s = spp.solution
    en_spp, ok_spp = reference_en(s["gps_seconds"].to_numpy(float), s["lat"].to_numpy(float), s["lon"].to_numpy(float), ref)
    ok_spp &= np.isfinite(en_spp).all(axis=1)
    common = np.isin(np.round(s["gps_seconds"].to_numpy(float), 2), np.round(t_gps[alive], 2)) & ok_spp
    peers = {"navfdi gnss --weighting elevation --noise 1 (SPP + FDE, the σ model as given)": en_spp[common]}
    s2 = navfdi.gnss_solve(str(obs), str(nav), systems="G,E", weighting="cn0", noise_scale="auto").solution
    en2, ok2 = reference_en(s2["gps_seconds"].to_numpy(float), s2["lat"].to_numpy(float), s2["lon"].to_numpy(float), ref)
    peers["navfdi gnss --weighting cn0 --noise auto"] = en2[common & ok2]
    if "--rtklib" in sys.argv and shutil.which("rnx2rtkp"):
        with tempfile.TemporaryDirectory() as d:
            o = Path(d) / "walk.obs"
            with gzip.open(obs, "rb") as f:
                o.write_bytes(f.read())
            out = Path(d) / "walk.pos"
            subprocess.run(["rnx2rtkp", "-p", "0", "-sys", "G,E", "-m", "10", "-o", str(out), str(o), str(nav)], check=True, capture_output=True)
            rt = logs.read_pos(out)
        en_rt, ok_rt = reference_en(rt.t, rt.lat, rt.lon, ref)
        ts = s["gps_seconds"].to_numpy(float)[common]
        near = np.abs(rt.t[:, None] - ts[None, :]).min(axis=1) < 0.02
        keep = ok_rt & near
        peers["RTKLIB 2.4.3 rnx2rtkp single"] = en_rt[keep]
    for name, en in peers.items():
        rms, mx = spread(en)
        print(f"| {name} | {rms:.2f} / {mx:.2f} | {len(en)} epochs |")
    for name, r in r0.items():
        e = r["error"]
        en, ok = e[:, 6:8], np.isfinite(e[:, 6])
        rms, mx = spread(en[ok])
        excl = np.asarray(r["satellites"]["excluded"]).any(axis=1)
        measured = np.asarray(r["satellites"]["status"]) != 5
        print(f"| tight, {name} | {rms:.2f} / {mx:.2f} | {ok.sum()} epochs; exclusions in {excl[measured].sum()} of {measured.sum()} epochs; offset E {en[ok, 0].mean():.2f} N {en[ok, 1].mean():.2f} m |")
    print("\n## 20 m step on one satellite, 50–90 s")
    for sat in (HIGH, LOW):
        f = {"id": "step", "sensor": "gnss", "satellite": sat, "components": ["pseudorange"], "kind": "step", "magnitude": "20 m", "start": "50 s", "end": "90 s"}
        rf = runs(sc.with_value("faults", [f]))
        for name, r in rf.items():
            t = r["t"]
            w = (t >= WINDOW[0]) & (t < WINDOW[1])
            sat_rec = r["satellites"]
            j = sat_rec["names"].index(sat)
            ex = np.asarray(sat_rec["excluded"])
            fw = w & np.asarray(sat_rec["in_view"])[:, j] & (np.asarray(sat_rec["status"]) != 5)
            exact = (ex[fw, j] & (ex[fw].sum(axis=1) == 1)).mean()
            d = moved(r, r0[name])
            print(f"| {sat} | {name} | {100 * exact:.1f} % | {np.nanmax(d[w]):.2f} m | {np.nanmax(d[t >= WINDOW[1]]):.2f} m |")
    print("\n## 10 s GNSS outages: largest drift from the fault-free run, and 2 s after the satellites return")
    for a, b in OUTAGES:
        so = sc.with_value("sensors[0].outages", [[f"{a} s", f"{b} s"]], create=True)
        ro = runs(so)["innovation"]
        d = moved(ro, r0["innovation"])
        t = ro["t"]
        k2 = np.searchsorted(t, b + 2.0)
        print(f"| {a:g}–{b:g} s | {np.nanmax(d[(t >= a) & (t < b)]):.2f} m | {d[k2]:.2f} m |")


if __name__ == "__main__":
    main()
