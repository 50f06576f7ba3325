"""Regenerate the delay table of docs/yang2013.md: ``python docs/scripts/yang2013_table.py [N]``."""

from __future__ import annotations

import sys

import numpy as np

import navfdi
from navfdi._intervals import alarm_intervals


def lasting(run, det, t_last):
    for iv in alarm_intervals(run.detector("cns", det)["alarm"], run.t):
        if iv.start <= t_last and (iv.end is None or iv.end > t_last):
            return iv
    return None


def main(n: int = 30) -> None:
    sc = navfdi.load_scenario("yang2013").base()
    rows: dict[str, dict[str, list[float]]] = {d: {"first": [], "lasting": [], "clear500": [], "step": [], "clear850": [], "onset_ramp": [], "onset_step": [], "frac_ramp": [], "frac_step": []} for d in ("chi2", "sprt", "joint")}
    ratio = []
    for seed in range(n):
        r = navfdi.run_scenario(sc, seed=seed)
        fm = {(m.fault_id, m.detector): m for m in r.fault_table()}
        for d in rows:
            m = fm[("cns-ramp", d)]
            rows[d]["first"].append(np.nan if m.delay is None else m.delay)
            iv = lasting(r, d, 499.0)
            rows[d]["lasting"].append(np.nan if iv is None else iv.start - 300)
            rows[d]["clear500"].append(np.nan if iv is None or iv.end is None else iv.end - 500)
            s = fm[("cns-step", d)]
            rows[d]["step"].append(np.nan if s.delay is None else s.delay)
            rows[d]["onset_ramp"].append(m.in_alarm_at_onset)
            rows[d]["onset_step"].append(s.in_alarm_at_onset)
            rows[d]["frac_ramp"].append(m.alarm_fraction)
            rows[d]["frac_step"].append(s.alarm_fraction)
            iv = lasting(r, d, 849.0)
            rows[d]["clear850"].append(np.nan if iv is None or iv.end is None else iv.end - 850)
        ratio.append(r.attitude_rms(*r.error_window(), True) / r.attitude_rms(*r.error_window(), False))
    q = lambda v: f"{np.nanmedian(v):.1f} [{np.nanmin(v):.0f}, {np.nanmax(v):.0f}]" if np.isfinite(v).any() else "—"  # noqa: E731
    print(f"{n} seeds; median [min, max] in s")
    print("| detector | ramp: detected | ramp: in alarm at onset | ramp: first alarm delay | ramp: lasting alarm delay | ramp: epochs in alarm | ramp: clears after 500 s | step: detected | step: in alarm at onset | step: delay | step: epochs in alarm | step: clears after 850 s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    pct = lambda v: f"{100 * np.nanmedian(v):.0f} %"  # noqa: E731
    for d, v in rows.items():
        det_r = n - int(np.isnan(v["first"]).sum())
        det_s = n - int(np.isnan(v["step"]).sum())
        print(
            f"| {d} | {det_r} of {n} | {sum(v['onset_ramp'])} of {n} | {q(v['first'])} | {q(v['lasting'])} | {pct(v['frac_ramp'])} | {q(v['clear500'])} "
            f"| {det_s} of {n} | {sum(v['onset_step'])} of {n} | {q(v['step'])} | {pct(v['frac_step'])} | {q(v['clear850'])} |"
        )
    print(f"master attitude RMS from the first fault to the end of the run (300–999 s), with / without isolation: median {np.median(ratio):.3f} [{min(ratio):.3f}, {max(ratio):.3f}]")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 30)
