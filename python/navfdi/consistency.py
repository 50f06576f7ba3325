"""What a run on recorded logs says about its own filter, with or without a reference: per
aiding channel the mean normalised innovation, the alarm rate against pf and the whiteness
of the innovations; the estimated IMU biases' convergence; the heading against the course.

For a consistent Kalman filter the innovation ``r`` of a measurement with ``m`` components
has ``λ = rᵀS⁻¹r ~ χ²(m)`` and its whitened form ``L⁻¹r`` (``S = LLᵀ``) is white, unit
variance noise: so the mean of ``λ/m`` over N tests lies in ``[χ²₀.₀₂₅(Σm)/Σm,
χ²₀.₉₇₅(Σm)/Σm]``, the chi-square test alarms at its ``pf``, and the lag-1
autocorrelation of the whitened innovation over consecutive tests lies within
``±1.96/√n``. These are the filter's own evidence; they need no reference trajectory.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from navfdi import _core

if TYPE_CHECKING:
    from navfdi.record import RunRecord

__all__ = ["consistency", "format_consistency", "detector_pf", "no_reference_line"]


def detector_pf(core: dict[str, Any], channel: str, detector: str) -> float:
    """The false-alarm probability ``pf`` of detector ``detector`` on channel ``channel`` in a
    scenario's SI form ``core`` (NaN when not found or the detector has none)."""
    arch = core.get("architecture", "federated")
    groups: list[dict[str, Any]] = []
    if arch == "loosely_coupled":
        lc = core["loosely_coupled"]
        groups = [*lc["sensors"], *({"sensor": k, **lc[k]} for k in ("zupt", "nhc") if lc.get(k))]
    elif arch == "centralized":
        groups = core["centralized"]["sensors"]
    elif arch == "federated":
        groups = core["federated"]["subfilters"]
    for g in groups:
        if g.get("sensor") == channel:
            for d in g.get("detectors", []):
                if d["name"] == detector and d.get("pf") is not None:
                    return float(d["pf"])
    return math.nan


def _wilson(k: int, n: int) -> tuple[float, float]:
    if n == 0:
        return math.nan, math.nan
    z = 1.959963984540054
    p = k / n
    den = 1 + z * z / n
    c = (p + z * z / (2 * n)) / den
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return (0.0 if k == 0 else max(0.0, c - h)), (1.0 if k == n else min(1.0, c + h))


def _lag1(white: np.ndarray, tested: np.ndarray) -> tuple[float, int]:
    """Lag-1 autocorrelation of the whitened innovation over consecutive tests, pooled over
    components (each component's mean removed): ``(ρ₁, pairs)``."""
    w = white[tested]
    if len(w) < 3:
        return math.nan, 0
    w = w - np.nanmean(w, axis=0)
    a, b = w[:-1], w[1:]
    ok = np.isfinite(a) & np.isfinite(b)
    num = float(np.sum(a[ok] * b[ok]))
    den = math.sqrt(float(np.sum(a[ok] ** 2)) * float(np.sum(b[ok] ** 2)))
    return (num / den if den > 0 else math.nan), int(ok.sum())


def _circ(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi


def consistency(run: RunRecord) -> dict[str, Any]:
    """The filter's own consistency figures of a run on recorded logs (empty dict for other
    runs). Keys:

    * ``channels``: per aiding channel (GNSS sensors, ``zupt``, ``nhc``) a dict with
      ``tests`` (epochs it was tested outside the injected fault windows and the 10 s after
      each), ``mean_nis`` (mean of ``λ/m``) and ``nis_interval`` (its 95 % interval for a
      consistent filter), ``median_ratio`` (median of ``λ`` over the median of χ²(m): 1 for
      a consistent filter, robust to the outliers that dominate the mean), ``lag1`` (lag-1
      autocorrelation of the whitened innovation over consecutive tests) and
      ``lag1_bound`` (1.96/√pairs), ``excluded`` (share of its tests excluded, wholly or
      in part) and ``detectors``: per detector ``alarms``, ``rate``, ``rate_ci`` (95 %
      Wilson) and ``pf``;
    * ``biases``: per estimated IMU bias (``gyro_bias_x`` …, rad/s or m/s²) its ``final``
      value, ``sigma_first`` and ``sigma_final`` (1σ at the first navigation epoch and the
      last) and ``reduction`` (``sigma_final / sigma_first``: below 1, the data told the
      filter something about it);
    * ``heading``: ``epochs`` (speed above 5 m/s), ``median_deg`` and ``p95_deg`` of the
      absolute difference between the heading and the course of the filter's velocity (which
      follows the GNSS velocity) — a car's heading follows its course, so a large steady
      difference is a yaw mounting error;
    * ``navigating_from``: time of the first navigation epoch (s);
    * ``converged_at``: time (s) from which the filter counted as converged (every tested
      GNSS channel's predicted σ within ``loosely_coupled.convergence`` times its own σ;
      before it only gross innovations exclude), NaN when it never did;
    * ``reanchored``: times (s) at which the INS was moved back onto the fixes it held out:
      running away from them (their distance growing faster than 3 m/s over 10 s), or held
      off them longer than the fixes it agreed with before plus 30 s (it had started from a
      fault's fixes at the alignment; a held height alone moves the height alone); on
      positions alone also where two copies of the filter carried without GNSS called a hold
      the INS's error — the INS is then replaced by the younger copy;
    * ``position_errors`` (with ``position_correlation = "auto"`` only): the first position
      channel's error model read from the log's fixes against the receiver's velocities —
      ``white`` and ``correlated`` σ (m), ``tau`` (s) and ``weight``, the factor on the fixes'
      position variance in the update (``correlated`` and ``tau`` 0 and ``weight`` 1 where
      the log shows no correlation, ``white`` then holding the velocities' noise too; NaN σ
      and τ and weight 1 where the log could not say: no velocities, or too short);
    * ``position_wander`` (fixes taken as white, where the log shows a correlation): the same
      figures, ``weight`` being what ``"auto"`` would use — the console suggests it.
    """
    rec = run.record
    if "nav" not in rec:
        return {}
    t = run.t
    core = run.scenario.core
    clean = np.ones(len(t), bool)
    for f in run.scenario.faults():
        clean &= ~((t >= f["start"]) & (t < f["end"] + 10.0))
    channels: dict[str, Any] = {}
    for s in rec["subfilters"]:
        lam = np.asarray(s["statistic"], float)
        dof = np.asarray(s["dof"], float)
        tested = np.isfinite(lam) & (dof > 0) & clean
        n = int(tested.sum())
        ch: dict[str, Any] = {"tests": n}
        if n:
            total = float(dof[tested].sum())
            ch["mean_nis"] = float(np.mean(lam[tested] / dof[tested]))
            # χ²(m)'s median per test, computed once per distinct m (a few values over many tests).
            ms, inv = np.unique(dof[tested].astype(int), return_inverse=True)
            med = np.array([_core.chi2_threshold(0.5, int(m)) for m in ms])[inv]
            ch["median_ratio"] = float(np.median(lam[tested] / med))
            ch["nis_interval"] = (_core.chi2_threshold(0.975, int(total)) / total, _core.chi2_threshold(0.025, int(total)) / total)
            ch["excluded"] = float(np.asarray(s["isolated"], bool)[tested].mean())
        else:
            ch["mean_nis"], ch["median_ratio"], ch["nis_interval"], ch["excluded"] = math.nan, math.nan, (math.nan, math.nan), math.nan
        if "whitened" in s and n >= 3:
            r1, pairs = _lag1(np.asarray(s["whitened"], float), tested)
            ch["lag1"], ch["lag1_bound"] = r1, (1.959963984540054 / math.sqrt(pairs) if pairs else math.nan)
        else:
            ch["lag1"], ch["lag1_bound"] = math.nan, math.nan
        dets = {}
        for d in s["detectors"]:
            dt = ~np.isnan(np.asarray(d["statistic"], float)) & clean
            k = int((np.asarray(d["alarm"], bool) & dt).sum())
            m = int(dt.sum())
            dets[d["name"]] = {"alarms": k, "tests": m, "rate": k / m if m else math.nan, "rate_ci": _wilson(k, m), "pf": detector_pf(core, s["sensor"], d["name"])}
        ch["detectors"] = dets
        channels[s["sensor"]] = ch
    nav, cols = rec["nav"], list(rec["nav_columns"])
    ok = np.isfinite(nav[:, cols.index("lat")])
    biases: dict[str, Any] = {}
    if ok.any():
        first, last = int(np.argmax(ok)), int(len(ok) - 1 - np.argmax(ok[::-1]))
        for what in ("gyro", "accel"):
            for axis in "xyz":
                c = f"{what}_bias_{axis}"
                s0, s1 = nav[first, cols.index(c + "_sigma")], nav[last, cols.index(c + "_sigma")]
                biases[c] = {"final": float(nav[last, cols.index(c)]), "sigma_first": float(s0), "sigma_final": float(s1), "reduction": float(s1 / s0) if s0 > 0 else math.nan}
    ve, vn = nav[:, cols.index("vel_e")], nav[:, cols.index("vel_n")]
    fast = ok & (np.hypot(ve, vn) > 5.0)
    heading: dict[str, Any] = {"epochs": int(fast.sum()), "median_deg": math.nan, "p95_deg": math.nan}
    if fast.any():
        d = np.abs(np.degrees(_circ(nav[fast, cols.index("yaw")] - np.arctan2(ve[fast], vn[fast]))))
        heading.update(median_deg=float(np.median(d)), p95_deg=float(np.percentile(d, 95)))
    return {
        "channels": channels, "biases": biases, "heading": heading,
        "navigating_from": float(t[int(np.argmax(ok))]) if ok.any() else math.nan,
        "converged_at": float(rec.get("converged_at", math.nan)),
        "reanchored": [float(x) for x in rec.get("reanchored", [])],
        **{k: dict(zip(("white", "correlated", "tau", "weight"), map(float, rec[k])))
           for k in ("position_errors", "position_wander") if k in rec},
    }


def format_consistency(c: dict[str, Any]) -> list[str]:
    """Console lines for :func:`consistency`'s figures (no line holds a NaN: missing figures
    are said in words)."""
    if not c:
        return []
    conv = "never converged (only gross innovations excluded)" if not math.isfinite(c["converged_at"]) else f"converged at {c['converged_at']:g} s"
    nav = "never navigated" if not math.isfinite(c["navigating_from"]) else f"navigating from {c['navigating_from']:g} s"
    re = c.get("reanchored", [])
    if re:
        conv += "; the INS ran away from (or stayed off) the fixes it held out and was moved back onto them (or replaced by a copy carried without GNSS) " + (f"{len(re)} times, first" if len(re) > 1 else "once,") + f" at {re[0]:g} s"
    lines = [f"filter consistency (its own innovations outside fault windows; {nav}, {conv};",
             "  consistent: mean λ/m in the interval, median λ over χ²(m)'s median 1, lag-1 ρ within ±white):"]
    lines.append(f"  {'channel':<10} {'tests':>6} {'mean λ/m':>9} {'consistent':>13} {'median':>7} {'lag-1 ρ':>8} {'white':>7} {'excluded':>9}")
    for name, ch in c["channels"].items():
        if not ch["tests"]:
            lines.append(f"  {name:<10} {0:>6}   never tested")
            continue
        lo, hi = ch["nis_interval"]
        r1 = "-" if not math.isfinite(ch["lag1"]) else f"{ch['lag1']:+.2f}"
        white = "-" if not math.isfinite(ch["lag1"]) else f"±{ch['lag1_bound']:.2f}"
        lines.append(f"  {name:<10} {ch['tests']:>6} {ch['mean_nis']:>9.2f} {f'{lo:.2f}–{hi:.2f}':>13} {ch['median_ratio']:>7.2f} {r1:>8} {white:>7} {100 * ch['excluded']:>8.1f}%")
    lines.append("  alarm rate per test against pf (95 % interval):")
    for name, ch in c["channels"].items():
        for dn, d in ch["detectors"].items():
            if not d["tests"]:
                continue
            lo, hi = d["rate_ci"]
            pf = "" if not math.isfinite(d["pf"]) else f" (pf {d['pf']:g}{', within' if lo <= d['pf'] <= hi else ''})"
            lines.append(f"    {name}/{dn}: {d['alarms']} of {d['tests']} = {d['rate']:.4f} [{lo:.4f}, {hi:.4f}]{pf}")
    b = c["biases"]
    if b:
        g = [b[f"gyro_bias_{a}"] for a in "xyz"]
        a = [b[f"accel_bias_{a}"] for a in "xyz"]
        dph = math.degrees(1.0) * 3600
        mg = 1e3 / 9.80665
        lines.append("  IMU biases at the end (x, y, z) and their σ as a share of the first:")
        lines.append("    gyro  " + ", ".join(f"{v['final'] * dph:+.1f}" for v in g) + " deg/h; σ " + ", ".join(f"{v['reduction']:.2f}" for v in g))
        lines.append("    accel " + ", ".join(f"{v['final'] * mg:+.2f}" for v in a) + " mg;    σ " + ", ".join(f"{v['reduction']:.2f}" for v in a))
    pe = c.get("position_errors")
    if pe is not None:
        if not math.isfinite(pe["white"]):
            lines.append("  GNSS position errors (position_correlation auto): not read from the log (no receiver velocities, or too short): taken as white")
        elif pe["correlated"] > 0:
            lines.append(f"  GNSS position errors (position_correlation auto): white σ {pe['white']:.2f} m, correlated σ {pe['correlated']:.2f} m with τ {pe['tau']:.1f} s; each fix's variance × {pe['weight']:.1f} in the update")
        else:
            lines.append("  GNSS position errors (position_correlation auto): white (no correlation the log shows)")
    pw = c.get("position_wander")
    if pw is not None:
        lines.append(f"  GNSS position errors: the fixes wander against the receiver's velocities (correlated σ {pw['correlated']:.2f} m, τ {pw['tau']:.1f} s) but are taken as white;"
                     f" position_correlation = \"auto\" would weight each fix's variance × {pw['weight']:.1f} (docs/meter_fde.md)")
    h = c["heading"]
    if h["epochs"]:
        lines.append(f"  heading against the velocity's course above 5 m/s ({h['epochs']} epochs): median {h['median_deg']:.2f}°, 95 % {h['p95_deg']:.2f}°")
    else:
        lines.append("  heading against course: never above 5 m/s")
    return lines


def no_reference_line(scenario: Any) -> str:
    """The console line of a logged run with no scored reference epoch: why there are no
    error figures."""
    if (scenario.raw.get("source") or {}).get("reference") is None:
        return "no reference: no [source] reference given, so no error figures (the filter's own consistency is above)"
    return "no reference epoch scored: every reference epoch was a GNSS input or outside the navigated span (the filter's own consistency is above)"
