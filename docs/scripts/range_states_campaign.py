"""The range-error model table of docs/integrity.md: ``walk_tc`` with ``[tight.integrity]``
under three models of its time-correlated pseudorange errors — white (σ as given), the
white-noise overbound (``range_errors = "overbound"``) and per-satellite Gauss-Markov states
(``range_states = "auto"``) — RUNS Monte-Carlo runs each (the scenario's drawn faults: a 10–40 m
step or a 0.5–2 m/s ramp on one of 8 satellites from 15–90 s), every FDE placement and the
bank's own (``separation``). Prints per
model and placement the levels, misleading and hazardously misleading epochs, the separation
alarms, the fault epochs with the faulty satellite excluded, the false exclusions outside the
faults and the error about the reference's datum; and the fault-free separation alarm rate of
one run per model.

    python docs/scripts/range_states_campaign.py [RUNS] [seed]
"""

from __future__ import annotations

import sys
import time

import numpy as np

from navfdi import load_scenario, montecarlo, run_scenario

MODELS = {
    "white": {"tight.integrity": {}},
    "overbound": {"tight.integrity": {"range_errors": "overbound"}},
    "gauss-markov": {"tight.integrity": {}, "tight.range_states": "auto"},
}


def main(runs: int = 100, seed: int = 1) -> None:
    base = load_scenario("walk_tc")
    base = base.with_values({"variants": [*base.raw["variants"], {"name": "separation", "set": {"tight.fde": "separation"}}]})
    print("| model | placement | HPL / VPL mean | / snapshot | error > PL h/v | hazardous h/v | separation alarms | fault excluded (runs detected) | false excl. / epoch | error about the datum, RMS |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    clean = {}
    for name, vals in MODELS.items():
        sc = base.with_values(vals, create=True)
        r = run_scenario(sc.with_values({"faults": []}), seed=0)
        clean[name] = {v: run.integrity()["alarm_rate_before_faults"] for v, run in r.runs.items()}
        t0 = time.perf_counter()
        c = montecarlo(sc, runs=runs, seed=seed, progress=False)
        wall = time.perf_counter() - t0
        integ = c.integrity_summary().set_index("variant") if "variant" in c.integrity_summary() else None
        df = c.runs
        for variant, g in df[df["fault_id"] == "sat_fault"].groupby("variant", sort=False):
            i = integ.loc[variant] if integ is not None else c.integrity_summary().iloc[0]
            det = g["fde_detected_epochs"].sum() / max(g["fde_faulty_epochs"].sum(), 1)
            runs_det = (g["fde_detected_epochs"] > 0).mean()
            o = df[(df["fault_id"] == "none") & (df["variant"] == variant)]
            fe = o["fde_false_exclusions"].sum() / max(o["fde_outside_epochs"].sum(), 1)
            err = np.sqrt(np.nanmean(g["hor_rel_rms"].to_numpy(float) ** 2)) if "hor_rel_rms" in g else float("nan")
            print(f"| {name} | {variant} | {i['hpl_mean']:.1f} / {i['vpl_mean']:.1f} m | {i['hpl_ratio_mean']:.2f} / {i['vpl_ratio_mean']:.2f} | "
                  f"{int(i['misleading_h'])} / {int(i['misleading_v'])} | {int(i['hazardous_h'])} / {int(i['hazardous_v'])} | {int(i['alarm_epochs'])} / {int(i['epochs'])} | "
                  f"{100 * det:.0f} % ({100 * runs_det:.0f} %) | {fe:.4f} | {err:.2f} m |")
        print(f"<!-- {name}: {runs} runs in {wall:.0f} s -->", file=sys.stderr)
    print("\nfault-free run: separation alarm rate per placement")
    for name, d in clean.items():
        print(f"| {name} | " + " | ".join(f"{v} {a:.3f}" for v, a in d.items()) + " |")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 100, int(sys.argv[2]) if len(sys.argv) > 2 else 1)
