"""Numbers of docs/drive_lc.md: the bundled drive_lc scenario fault-free, with the README's two
GNSS outages, and with a 20 m step on the north or east GNSS position over 440–500 s.
Run: python docs/scripts/drive_lc_numbers.py"""

from __future__ import annotations

import time

import numpy as np

from navfdi import load_scenario, run_scenario

OUT = [(100.0, 160.0), (280.0, 340.0)]


def hor(r):
    e = r.record["error"]
    return np.hypot(e[:, 6], e[:, 7])


def main() -> None:
    sc = load_scenario("drive_lc").with_value("faults", [])
    t0 = time.perf_counter()
    free = run_scenario(sc)
    print(f"fault-free (both variants, files read): {time.perf_counter() - t0:.2f} s")
    for v in ("fde", "no_fde"):
        e = free[v].errors()
        print(f"  {v:7s} horizontal RMS {e['hor_rms']:.3f} m, max {e['hor_max']:.3f} m, vertical RMS {e['ver_rms']:.3f} m over {int(e['scored'])} epochs")
        for s in free[v].record["subfilters"]:
            n = int(np.isfinite(s["statistic"]).sum())
            for d in s["detectors"]:
                print(f"      {s['sensor']:8s} {d['name']:8s} tested {n:5d}  alarms {int(d['alarm'].sum()):3d} ({d['alarm'].sum() / max(n, 1):.2%})")
    win = [[f"{a:g} s", f"{b:g} s"] for a, b in OUT]
    out = run_scenario(sc.with_values({"sensors[0].outages": win, "sensors[1].outages": win}, create=True))
    print("outages: horizontal error after 10/20/30/60 s; time back under 1 m after GNSS returns")
    for v in ("fde", "no_fde"):
        r = out[v]
        h, t = hor(r), r.t
        for a, b in OUT:
            at = [h[int(np.argmin(np.abs(t - min(a + d, b - 0.25))))] for d in (10, 20, 30, 60)]
            back = np.flatnonzero((t >= b) & np.isfinite(h) & (h < 1.0))
            print(f"  {v:7s} {a:g}-{b:g} s: " + " / ".join(f"{x:.2f}" for x in at) + f" m; back under 1 m after {t[back[0]] - b:.2f} s")
    bare = sc.with_values({"sensors[0].outages": win, "sensors[1].outages": win}, create=True)
    raw = dict(bare.raw)
    raw["loosely_coupled"] = {k: v for k, v in raw["loosely_coupled"].items() if k not in ("zupt", "nhc")}
    from navfdi.scenario import from_dict

    r = run_scenario(from_dict(raw, source=sc.source))["fde"]
    h, t = hor(r), r.t
    for a, b in OUT:
        at = [h[int(np.argmin(np.abs(t - min(a + d, b - 0.25))))] for d in (10, 20, 30, 60)]
        print(f"  fde without zupt and nhc {a:g}-{b:g} s: " + " / ".join(f"{x:.2f}" for x in at) + " m")
    for comp in ("pos_n", "pos_e"):
        f = {"id": "step", "sensor": "gnss_pos", "components": [comp], "kind": "step", "magnitude": "20 m", "start": "440 s", "end": "500 s"}
        runs = run_scenario(sc.with_value("faults", [f], create=True))
        for v in ("fde", "no_fde"):
            r = runs[v]
            t, h = r.t, hor(r)
            w = (t >= 440) & (t < 500)
            al = r.detector("gnss_pos", "exclude")["alarm"]
            first = t[np.flatnonzero(al & (t >= 440))[0]] - 440
            yaw = np.unwrap(np.nan_to_num(r.record["nav"][:, 8]))
            ref = np.unwrap(np.nan_to_num(free[v].record["nav"][:, 8]))
            print(f"  step {comp} {v:7s}: alarm {first:.2f} s after onset, max horizontal error in the fault {np.nanmax(h[w]):.2f} m, heading change {np.degrees(np.abs(yaw - ref)[w].max()):.2f} deg")


if __name__ == "__main__":
    main()
