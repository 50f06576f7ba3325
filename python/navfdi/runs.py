"""Scenario runs of any architecture (federated, centralized, tight): the whole epoch loop runs in Rust.

:func:`run_scenario` simulates one run (truth and measurements from ``seed``), filters it
with isolation and, on the same measurements, without isolation, and returns a
:class:`ScenarioRun` with tables (:meth:`ScenarioRun.events`, :meth:`ScenarioRun.fault_table`,
:meth:`ScenarioRun.timeseries`) and :meth:`ScenarioRun.write` for the files of ``navfdi run``.

Event matching (``events.csv``, the tables) is the Rust engine that Monte-Carlo campaigns
use too (``navfdi_core::metrics``): an alarm interval of a detector on a channel belongs
to a fault on that channel's sensor when it overlaps the fault window ``[start, end]`` and
began after the end of the previous fault window on the same sensor (an alarm still raised from
an earlier fault is not a new detection). ``delay = alarm_start − fault_start``, or 0 when a
false alarm was already raised when the fault began.
"""

from __future__ import annotations

import math
import platform
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from navfdi import _core, _json
from navfdi._intervals import AlarmInterval, alarm_intervals, match_events, tested_epochs, window_alarm
from navfdi._text import fit
from navfdi._lc_schema import POSITIONS_ONLY, positions_only_channels
from navfdi.consistency import consistency, format_consistency, no_reference_line
from navfdi._timeseries import timeseries_columns
from navfdi.frames import FrameWarning, frame_warnings
from navfdi.record import ERROR_COLUMNS, RunRecord, integrity_figures
from navfdi.scenario import NeverAppliedWarning, Scenario, fault_on, load_scenario

#: What the columns of the per-fault tables mean (printed once after them).
FAULT_TABLE_LEGEND = [
    "detected: the alarm raised inside the fault window (or 1 s after); onset: already in alarm",
    "when the fault began (a false or earlier alarm, not a detection); in alarm: share of the",
    "fault's epochs in alarm; lasting from: start of the alarm still raised at its last epoch.",
]

#: Note of a fault that never reached a measurement (left out of the detection figures).
NEVER_APPLIED = "never applied: no measurement of its sensor (or satellite) in its window"


@dataclass(frozen=True)
class FaultMatch:
    """One detector's result for one fault (a row of :meth:`ScenarioRun.fault_table`).

    Attributes
    ----------
    fault_id, subfilter, detector : str
        What was tested.
    fault_start, fault_end : float
        Fault window (s).
    detected_at : float or None
        Start of the first matching alarm interval (s); None if missed.
    cleared_at : float or None
        End of the last matching interval (s); None if missed or never cleared.
    delay : float or None
        Detection delay (s).
    lasting_from : float or None
        Start of the alarm interval still raised at the last epoch of the fault window (s):
        when the detector's alarm became lasting (with a large ``pf`` the first alarm is often
        a false alarm). None when not in alarm then.
    note : str
        E.g. ``"missed: in alarm since 326 s (before the fault)"`` when a detector raised no
        new alarm because it was already in alarm.
    in_alarm_at_onset : bool
        The detector was already in alarm when the fault began (an alarm raised before it:
        not a detection).
    alarm_fraction : float
        Share of the fault's epochs in alarm (NaN when no epoch lies in the window).

    A detection is an alarm onset inside the fault window or up to 1 s after its end
    (:data:`navfdi._intervals.GRACE`), the rule of ``run``, ``montecarlo`` and ``demo``.
    """

    fault_id: str
    subfilter: str
    detector: str
    fault_start: float
    fault_end: float
    detected_at: float | None
    cleared_at: float | None
    delay: float | None
    lasting_from: float | None
    note: str
    in_alarm_at_onset: bool = False
    alarm_fraction: float = float("nan")


class ScenarioRun(RunRecord):
    """Result of :func:`run_scenario`: one run's records (:class:`~navfdi.record.RunRecord`:
    ``scenario``, ``seed``, ``t``, ``record``, ``baseline``, ``variant`` and the accessors
    by channel and detector) with its tables, time series, figures and files."""

    # ---- satellite FDE (tight architecture) -----------------------------------------------
    def satellite_table(self):
        """Satellite FDE per fault on the ``gnss_ranges`` sensor (tight architecture), one row
        per fault and one ``none`` row for the epochs outside faults and their after-windows
        (pandas DataFrame; empty for other architectures). Columns: ``fault_id, satellite,
        faulty_epochs, detection_rate`` (faulty epochs with the faulty satellite excluded /
        faulty epochs in which it was in view), ``exclusion_epochs, identification_rate``
        (epochs with exactly the faulty satellite excluded / epochs with any exclusion in the
        window), ``after_epochs, after_fault_alarm_rate`` (epochs with any exclusion among the
        50 measured epochs after the fault ends), ``outside_epochs, false_exclusion_rate``
        (satellites excluded per epoch outside faults). Counts come from the Rust metrics
        engine that Monte-Carlo uses."""
        import pandas as pd

        cols = ["fault_id", "satellite", "faulty_epochs", "detection_rate", "exclusion_epochs", "identification_rate", "after_epochs", "after_fault_alarm_rate", "outside_epochs", "false_exclusion_rate"]
        sat = self.record.get("satellites")
        if sat is None:
            return pd.DataFrame(columns=cols)
        faults = self.scenario.faults()
        rows = []
        ratio = lambda a, b: a / b if b else float("nan")  # noqa: E731
        for m in sat["metrics"]:
            f = None if m["fault"] is None else faults[m["fault"]]
            rows.append(
                {
                    "fault_id": "none" if f is None else f["id"],
                    "satellite": None if f is None else f.get("satellite"),
                    "faulty_epochs": m["faulty_epochs"],
                    "detection_rate": ratio(m["detected_epochs"], m["faulty_epochs"]) if f else float("nan"),
                    "exclusion_epochs": m["exclusion_epochs"],
                    "identification_rate": ratio(m["exact_epochs"], m["exclusion_epochs"]) if f else float("nan"),
                    "after_epochs": m["after_epochs"],
                    "after_fault_alarm_rate": ratio(m["after_alarm_epochs"], m["after_epochs"]) if f else float("nan"),
                    "outside_epochs": m["outside_epochs"],
                    "false_exclusion_rate": float("nan") if f else ratio(m["false_exclusions"], m["outside_epochs"]),
                }
            )
        return pd.DataFrame(rows, columns=cols)

    # ---- filter protection levels (tight architecture with [tight.integrity]) ---------------
    def integrity(self) -> dict[str, float] | None:
        """The filter protection levels of the run against its true position error (None
        without ``[tight.integrity]``), counted by the Rust metrics engine Monte-Carlo uses:
        ``epochs`` (with finite levels), ``misleading_h``, ``misleading_v`` (epochs whose
        horizontal / vertical error exceeds the HPL / VPL), ``hazardous_h``, ``hazardous_v`` (of
        those, without an alarm of the separation test), ``alarm_epochs``,
        ``error_over_hpl_max``, ``error_over_vpl_max`` (largest error / level), ``hpl_mean``,
        ``vpl_mean`` (m), ``hpl_snapshot_mean``, ``vpl_snapshot_mean`` (m, snapshot ARAIM of
        the same epochs' pseudoranges) and ``hpl_ratio_mean``, ``vpl_ratio_mean`` (filter /
        snapshot, mean over the epochs with both), ``alarm_rate_before_faults`` (share of the
        epochs before the first fault — all of them without faults — in which the separation
        test alarms; its allocation is ``P_FA``, 3.9e-6 by default). On recorded logs the errors are
        taken about the reference's own datum: the mean offset of a fault-free pass of the same
        filter on the same log (the run's own without faults)."""
        it = self.record.get("integrity")
        if it is None or "metrics" not in it:
            return None
        mean = lambda v: float(np.nanmean(v)) if np.isfinite(v).any() else float("nan")  # noqa: E731
        t = np.asarray(self.t)
        first = min((f["start"] for f in self.scenario.faults()), default=np.inf)
        before = np.isfinite(np.asarray(it["hpl"], float)) & (t < first)
        alarm = np.asarray(it["alarm"], bool)
        return {
            **integrity_figures(it["metrics"]),
            "hpl_snapshot_mean": mean(it["hpl_snapshot"]),
            "vpl_snapshot_mean": mean(it["vpl_snapshot"]),
            "alarm_rate_before_faults": float((alarm & before).sum()) / before.sum() if before.any() else float("nan"),
        }

    def _integrity_lines(self) -> list[str]:
        i = self.integrity()
        if i is None:
            return []
        return [
            f"filter protection levels ({i['epochs']} epochs): HPL/VPL mean {i['hpl_mean']:.2f}/{i['vpl_mean']:.2f} m, "
            f"{i['hpl_ratio_mean']:.2f}/{i['vpl_ratio_mean']:.2f} of snapshot ARAIM's",
            f"  error > PL h/v: {i['misleading_h']}/{i['misleading_v']} epochs; with no alarm (hazardous) "
            f"{i['hazardous_h']}/{i['hazardous_v']}; largest error/PL {i['error_over_hpl_max']:.2f}/{i['error_over_vpl_max']:.2f}",
        ] + self._range_error_lines() + ([
            f"  the separation test alarms at {i['alarm_rate_before_faults']:.0%} of the epochs before any fault (allocated "
            f"{(self.scenario.core['tight'].get('integrity') or {}).get('p_fa_vert', 3.9e-6):g}): the filter's "
            + ("range-error" if (self.scenario.core.get("tight") or {}).get("range_states") else "white-noise") + " model does not describe these errors (time-correlated on real receivers), so the levels are not usable here",
        ] if i["alarm_rate_before_faults"] > 0.01 else [])

    def _range_error_lines(self) -> list[str]:
        """The range-error model in force — ``[tight] range_states`` or the overbound of
        ``[tight.integrity] range_errors`` — if any."""
        from navfdi._lc_schema import range_error_factor

        if rs := (self.scenario.core.get("tight") or {}).get("range_states"):
            return [f"  range errors: Gauss-Markov range-error states per satellite, {rs['fraction']:.3g} of the variance correlated over {rs['tau']:.3g} s"]
        f = range_error_factor(self.scenario.raw)
        if not isinstance(f, float):
            return []
        return [f"  range errors: white-noise overbound of their time correlation, pseudorange variance x {f:.3g} (sigma x {math.sqrt(f):.2f})"]

    def _satellite_lines(self) -> list[str]:
        if self.record.get("satellites") is None:
            return []  # no satellite FDE (and no pandas import for the console's sake)
        tab = self.satellite_table()
        if not len(tab):
            return []
        sat = self.record["satellites"]
        measured = np.asarray(sat["status"]) != sat["status_names"].index("no_measurement")
        n = sat["in_view"][measured].sum(axis=1) if measured.any() else sat["in_view"].sum(axis=1)
        core = self.scenario.core
        if core.get("architecture") == "ultra_tight":
            u = core["ultra_tight"]
            how = f"{u['method']} AIME, {'excluding' if u['exclude'] else 'reporting only'}; {_span(n)} tracked channels in view"
        else:
            how = f"{core['tight']['fde']}; {_span(n)} satellites in view"
        lines = [f"satellite FDE ({how}):"]
        lines.append(f"  {'fault':<10} {'sat':<5} {'detection':>10} {'identification':>15} {'after-fault alarms':>19} {'false excl./epoch':>18}")
        pct = lambda v: "-" if v != v else f"{100 * v:.2f} %"  # noqa: E731
        for _, r in tab.iterrows():
            lines.append(
                f"  {r['fault_id']:<10} {r['satellite'] if isinstance(r['satellite'], str) else '-':<5} {pct(r['detection_rate']):>10} {pct(r['identification_rate']):>15} "
                f"{pct(r['after_fault_alarm_rate']):>19} {'-' if r['false_exclusion_rate'] != r['false_exclusion_rate'] else format(r['false_exclusion_rate'], '.4f'):>18}"
            )
        if core.get("architecture") == "tight":
            lines.append("  (paper 001: method 1 detection 83.33 %, identification 100 %; method 2 80.67 %, 86.36 %)")
        return lines

    # ---- tables ----------------------------------------------------------------------------
    def fault_applied(self, fault_id: str) -> bool:
        """Whether the fault ``fault_id`` ever reached a measurement (its sensor measured inside
        its window and, for a satellite fault, the satellite was in view)."""
        applied = self.record.get("faults_applied")
        ids = [f["id"] for f in self.scenario.faults()]
        return applied is None or fault_id not in ids or bool(applied[ids.index(fault_id)])

    def _faults_on(self, sensor: str) -> list[dict[str, Any]]:
        return sorted((f for f in self.scenario.faults() if fault_on(f, sensor)), key=lambda f: f["start"])

    def events(self):
        """One row per alarm interval: ``subfilter, detector, alarm_start, alarm_end, tests,
        fault_id, fault_start, fault_end, delay`` (times in s; ``alarm_start`` is the first
        alarmed test, ``alarm_end`` the first passing test after it, empty when the alarm never
        ends; ``tests`` the detector's tests the interval spans — a sensor slower than the
        record is tested only at its own epochs, and the epochs between its tests neither end
        an interval nor count; fault columns empty where no fault matches); the state
        chi-square test (``[state_chi2]``) as subfilter ``navigation``, detector
        ``state_chi2``, matched to every fault; the loosely coupled filter's exclusion
        intervals as detector ``excluded:{reason}`` (``test``, ``step``, ``stale``, ``ramp``, ``receiver``:
        the tested epochs at which the channel, or some of its components, was left out for
        that reason); and each time the loosely coupled INS, run away from the fixes it held out
        or held off them too long, was moved back onto them (or, on positions alone, replaced by
        a copy of the filter carried without GNSS) as subfilter ``navigation``, detector ``reanchored``
        (``alarm_start = alarm_end`` its time, no fault). Returns a pandas DataFrame."""
        import pandas as pd

        rows = []
        def add(channel: str, detector: str, d: dict[str, Any], faults: list[dict[str, Any]]) -> None:
            for iv, fi in self._events(d, faults):
                f = None if fi is None else faults[fi]
                rows.append({"subfilter": channel, "detector": detector, "alarm_start": iv.start, "alarm_end": iv.end, "tests": iv.tests,
                             "fault_id": f["id"] if f else None, "fault_start": f["start"] if f else None, "fault_end": f["end"] if f else None,
                             "delay": max(iv.start - f["start"], 0.0) if f else None})

        for s in self.record["subfilters"]:
            faults = self._faults_on(s["sensor"])
            for d in s["detectors"]:
                add(s["sensor"], d["name"], d, faults)
        st = self.record.get("state_chi2")
        if st is not None:
            # The state test watches the whole navigation solution: matched to every fault.
            add("navigation", "state_chi2", st, sorted(self.scenario.faults(), key=lambda f: f["start"]))
        for s in self.record["subfilters"]:
            if "noise_scale" not in s:
                continue
            reason = np.asarray(s["reason"])
            for r in np.unique(reason[reason > 0]):
                # An exclusion interval: the tested epochs left out for one reason.
                add(s["sensor"], f"excluded:{s['reason_names'][r]}", {"alarm": list(reason == r), "statistic": s["statistic"]}, self._faults_on(s["sensor"]))
        for t in self.record.get("reanchored", []):
            rows.append({"subfilter": "navigation", "detector": "reanchored", "alarm_start": float(t), "alarm_end": float(t), "tests": 1,
                         "fault_id": None, "fault_start": None, "fault_end": None, "delay": None})
        cols = ["subfilter", "detector", "alarm_start", "alarm_end", "tests", "fault_id", "fault_start", "fault_end", "delay"]
        df = pd.DataFrame(rows, columns=cols)
        for c in ("alarm_start", "alarm_end", "fault_start", "fault_end", "delay"):
            df[c] = df[c].astype(float)
        return df

    def _events(self, d: dict[str, Any], faults: list[dict[str, Any]]) -> list[tuple[AlarmInterval, int | None]]:
        """Alarm intervals of detector record ``d`` over its tests with the index of the fault
        each detects (the Rust engine)."""
        return match_events(d["alarm"], self.t, [(f["start"], f["end"]) for f in faults], tested_epochs(d["statistic"]))

    def fault_table(self) -> list[FaultMatch]:
        """Per fault and detector: detected at, cleared at, delay (the paper's Tables 2–4)."""
        out = []
        for s in self.record["subfilters"]:
            faults = self._faults_on(s["sensor"])
            matched = {d["name"]: self._events(d, faults) for d in s["detectors"]} if faults else {}
            for fi, f in enumerate(faults):
                for d in s["detectors"]:
                    ivs = [iv for iv, m in matched[d["name"]] if m == fi]
                    note = ""
                    det: float | None
                    clr: float | None
                    delay: float | None
                    if not self.fault_applied(f["id"]):
                        out.append(FaultMatch(f["id"], s["sensor"], d["name"], f["start"], f["end"], None, None, None, None, NEVER_APPLIED))
                        continue
                    if ivs:
                        det, clr = ivs[0].start, ivs[-1].end
                        delay = max(det - f["start"], 0.0)
                        if clr is None:
                            note = "not cleared by the end of the run"
                    else:
                        det = clr = delay = None
                        note = "missed"
                    tested = tested_epochs(d["statistic"])
                    at_onset, fraction = window_alarm(d["alarm"], self.t, f["start"], f["end"], tested)
                    if at_onset and not ivs:
                        since = [iv.start for iv in alarm_intervals(d["alarm"], self.t, tested) if iv.start < f["start"] and (iv.end is None or iv.end > f["start"])]
                        note = f"missed: in alarm since {since[0]:g} s (before the fault)" if since else "missed: in alarm before the fault"
                    lasting = None
                    last = self.t[(self.t < f["end"]) & tested]
                    if last.size:
                        tl = float(last[-1])
                        for iv in alarm_intervals(d["alarm"], self.t, tested):
                            if iv.start <= tl and (iv.end is None or iv.end > tl):
                                lasting = iv.start
                    out.append(FaultMatch(f["id"], s["sensor"], d["name"], f["start"], f["end"], det, clr, delay, lasting, note, at_onset, fraction))
        return out

    def format_tables(self, legend: bool = True) -> str:
        """The per-fault tables as printed by ``navfdi run`` (at most 100 characters wide): per
        fault and detector when the alarm was raised (``detected``: inside the window or 1 s
        after), the delay, when it cleared, whether the detector was already in alarm when
        the fault began (``onset``; not a detection), the share of the fault's epochs in alarm,
        and when the alarm still raised at the window's end began (``lasting``); notes on
        their own lines. ``legend``: end with the columns' meaning (once per output)."""
        fmt = lambda v: "-" if v is None else f"{v:g}"  # noqa: E731
        lines = calibration_lines(self.calibration) if legend else []
        by_fault: dict[str, list[FaultMatch]] = {}
        for m in self.fault_table():
            by_fault.setdefault(m.fault_id, []).append(m)
        for fid, rows in by_fault.items():
            r0 = rows[0]
            lines.append(f"fault {fid} on {r0.subfilter}: {r0.fault_start:g}–{r0.fault_end:g} s")
            lines.append(f"  {'detector':<10} {'detected [s]':>12} {'delay [s]':>9} {'cleared [s]':>11} {'onset':>6} {'in alarm':>9} {'lasting from [s]':>16}")
            for m in rows:
                frac = "-" if m.alarm_fraction != m.alarm_fraction else f"{100 * m.alarm_fraction:.0f} %"
                lines.append(
                    f"  {m.detector:<10} {fmt(m.detected_at):>12} {fmt(m.delay):>9} {fmt(m.cleared_at):>11} {'yes' if m.in_alarm_at_onset else 'no':>6} {frac:>9} {fmt(m.lasting_from):>16}"
                )
                if m.note:
                    lines.append(f"    {m.detector}: {m.note}")
            lines.append("")
        if legend and by_fault:
            lines += FAULT_TABLE_LEGEND + [""]
        note = self.mdb_note()
        if note:
            lines.append(note)
            lines.append("")
        sat_lines = self._satellite_lines()
        if sat_lines:
            lines += sat_lines + [""]
        pl_lines = self._integrity_lines()
        if pl_lines:
            lines += pl_lines + [""]
        if "nav" in self.record:
            lines += format_consistency(consistency(self)) + [""]
            for sen, c in self.exclusion_counts().items():
                why = ", ".join(f"{n} {c[n]}" for n in c if n != "tested" and c[n])
                lines.append(f"{sen}: left out (wholly or in part) at {sum(v for n, v in c.items() if n != 'tested')} of {c['tested']} tested epochs" + (f" ({why})" if why else ""))
                lines += [f"  {sen}: {POSITIONS_ONLY}"] if sen in positions_only_channels(self.scenario.raw) else []
            e = self.errors()
        if "nav" in self.record and not e["scored"]:
            lines.append(no_reference_line(self.scenario))
        elif "nav" in self.record:
            lines.append(f"horizontal error against the {int(e['scored'])} reference epochs {self.scored_label()}: RMS {e['hor_rms']:.3f} m, max {e['hor_max']:.3f} m; vertical RMS {e['ver_rms']:.3f} m")
            steady = self.steady_offset()
            if steady:
                lines.append(
                    f"  mostly a steady offset (E {e['offset_e']:.2f} m, N {e['offset_n']:.2f} m, mean outside faults); without it: "
                    f"RMS {e['hor_rel_rms']:.3f} m, max {e['hor_rel_max']:.3f} m")
            for name, _, _ in self.windows():
                rel = f" ({e[name + '.hor_rel_max']:.3f} m offset removed)" if steady else ""
                lines.append(f"  {name}: horizontal RMS {e[name + '.hor_rms']:.3f} m, max {e[name + '.hor_max']:.3f} m{rel}")
        elif self.baseline is not None:
            lines.append(self._error_summary())
        return fit("\n".join(lines).rstrip() + "\n")

    def attitude_rms(self, t0: float, t1: float, isolation: bool = True) -> float:
        """RMS of the master attitude error (all three axes) over ``[t0, t1)`` in rad."""
        e = self.error(isolation)[:, :3]
        sel = (self.t >= t0) & (self.t < t1)
        return float(np.sqrt(np.mean(e[sel] ** 2)))

    def error_window(self) -> tuple[float, float]:
        """``(t0, t1)`` (s) of the error comparison printed by ``navfdi run`` and reported in the
        docs: from the first fault's start to the end of the run, ``[t0, t1)`` (the last epoch
        included)."""
        faults = self.scenario.faults()
        t0 = min((f["start"] for f in faults), default=float(self.t[0]))
        return t0, float(self.t[-1]) + 1e-9

    def _error_summary(self) -> str:
        t0, t1 = self.error_window()
        a = np.degrees(self.attitude_rms(t0, t1, True)) * 3600
        b = np.degrees(self.attitude_rms(t0, t1, False)) * 3600
        span = "first fault to end of run" if self.scenario.faults() else "whole run: no faults"
        return f"master attitude error RMS over {t0:g}–{self.t[-1]:g} s ({span}): {a:.2f} arcsec with isolation, {b:.2f} arcsec without"

    def timeseries(self):
        """Per-epoch table (pandas DataFrame): ``t`` (s from time 0; runs on recorded logs
        also ``gps_week`` and ``gps_sow``, GPST, beside it); per sub-filter ``{sub}.statistic``,
        ``{sub}.isolated``, ``{sub}.fused`` (loosely coupled GNSS channels also
        ``{sub}.excluded``: why the measurement or some of its components were left out —
        ``test``, ``step``, ``stale``, ``ramp``, ``receiver``, empty when used as measured — and
        ``{sub}.noise_scale``, the σ scale its tests used) and per detector ``{sub}.{det}.statistic``,
        ``.threshold``, ``.alarm``; ``{sub}.mdb.{component}`` (minimal detectable bias, in the
        component's unit; centralized architecture); master ``error.{col}``, ``sigma.{col}`` and, without
        isolation, ``error_no_isolation.{col}`` (attitude in rad, velocity m/s, position m).
        With altitude fusion: ``fused_alt.error`` (m) and per fused sensor
        ``fused_alt.{sensor}.error`` (its height measurement error, m) and ``.weight``
        (normalised, 0 when it did not contribute). With ``[modes]``: ``mode`` (``q1``, ``q2``, ``q3``). With ``[state_chi2]``:
        ``state_chi2.statistic, .threshold, .alarm, .ready, .ill_conditioned``. Tight architecture: ``fde.status`` (passed, excluded, unidentified, no_solution, alarm,
        no_measurement), ``fde.used`` (satellites updating the filter), ``fde.excluded``
        (comma-separated names) and per satellite ever in view ``sat.{name}.in_view``,
        ``.excluded`` and ``.w`` (w-test statistic of its pseudorange, NaN when not tested);
        with ``[tight.integrity]``: ``integrity.hpl``, ``.vpl`` (filter protection levels, m),
        ``.hpl_snapshot``, ``.vpl_snapshot`` (snapshot ARAIM of the same epoch, m),
        ``.statistic`` (largest normalised separation ``|Δ|/T``), ``.alarm``, ``.modes``
        (sub-filters)."""
        import pandas as pd

        return pd.DataFrame(timeseries_columns(self))

    def errors(self) -> dict[str, float]:
        """Navigation-error RMS and maximum |error| over the whole run, per component of the
        master (or centralized) solution: ``{comp}_rms`` and ``{comp}_max`` for ``pos_e,
        pos_n, pos_u, lat_m`` (m; ``lat_m`` is the latitude error in metres, = ``pos_n``),
        ``vel_e, vel_n, vel_u`` (m/s) and ``att_e, att_n, att_u`` (rad); with altitude fusion
        also ``fused_alt_rms``, ``fused_alt_max`` (m, error of the fused altitude measurement
        over the epochs it existed) and ``fused_alt_predict_only`` (fraction of epochs in which
        no sensor contributed)."""
        if "nav" in self.record:
            return self._logged_errors()
        e = self.record["error"]
        cols = dict(zip(ERROR_COLUMNS, e.T))
        cols["lat_m"] = cols["pos_n"]
        out: dict[str, float] = {}
        for c in ["pos_e", "pos_n", "pos_u", "lat_m", "vel_e", "vel_n", "vel_u", "att_e", "att_n", "att_u"]:
            v = cols[c]
            out[f"{c}_rms"] = float(np.sqrt(np.mean(v**2)))
            out[f"{c}_max"] = float(np.max(np.abs(v)))
        if "fused_alt" in self.record:
            f = self.record["fused_alt"]
            ok = np.isfinite(f)
            out["fused_alt_rms"] = float(np.sqrt(np.mean(f[ok] ** 2))) if ok.any() else float("nan")
            out["fused_alt_max"] = float(np.max(np.abs(f[ok]))) if ok.any() else float("nan")
            out["fused_alt_predict_only"] = float(1.0 - ok.mean())
        return out

    def windows(self) -> list[tuple[str, float, float]]:
        """Scoring windows of a logged run: ``(name, start, end)`` (s) per sensor outage
        (``outage[start-end]``) and fault (``fault id``)."""
        out: list[tuple[str, float, float]] = []
        for sen in self.scenario.core["sensors"]:
            for a, b in sen.get("outages", []):
                name = f"outage[{a:g}-{b:g}]"
                if all(n != name for n, _, _ in out):
                    out.append((name, a, b))
        out += [(f["id"], f["start"], f["end"]) for f in self.scenario.faults()]
        return out

    def _logged_errors(self) -> dict[str, float]:
        """Errors of a run on recorded logs against its reference, over the epochs the
        reference scores (not used as input): ``hor_rms``, ``hor_max`` (m, horizontal),
        ``ver_rms``, ``ver_max`` (m), ``vel_rms``, ``vel_max`` (m/s, 3-D), ``scored`` (epochs),
        and the same horizontal/vertical numbers per outage and fault window
        (``{window}.hor_rms`` ...); ``offset_e``, ``offset_n``, ``offset_u`` (m, the run's mean
        error over the scored epochs outside the fault windows) and ``hor_rel_rms``,
        ``hor_rel_max``, ``{window}.hor_rel_max`` (m, horizontal with that offset removed)."""
        e = self.record["error"]
        hor = np.hypot(e[:, 6], e[:, 7])
        ver = np.abs(e[:, 8])
        vel = np.linalg.norm(e[:, 3:6], axis=1)
        ok = np.isfinite(hor)

        def stats(sel: np.ndarray, prefix: str) -> dict[str, float]:
            m = sel & ok
            if not m.any():
                return {f"{prefix}hor_rms": float("nan"), f"{prefix}hor_max": float("nan"), f"{prefix}ver_rms": float("nan"), f"{prefix}ver_max": float("nan")}
            return {
                f"{prefix}hor_rms": float(np.sqrt(np.mean(hor[m] ** 2))), f"{prefix}hor_max": float(hor[m].max()),
                f"{prefix}ver_rms": float(np.sqrt(np.mean(ver[m] ** 2))), f"{prefix}ver_max": float(ver[m].max()),
            }

        out = stats(np.ones_like(ok), "")
        # The run's mean offset to the reference (over the scored epochs outside the fault
        # windows) and the horizontal error without it: for a reference with an offset of its
        # own (walk_tc's base).
        off = self.reference_offset()
        out.update({"offset_e": float(off[0]), "offset_n": float(off[1]), "offset_u": float(off[2])})
        rel = np.hypot(e[:, 6] - off[0], e[:, 7] - off[1])
        out["hor_rel_rms"] = float(np.sqrt(np.mean(rel[ok] ** 2))) if ok.any() else float("nan")
        out["hor_rel_max"] = float(rel[ok].max()) if ok.any() else float("nan")
        out["vel_rms"] = float(np.sqrt(np.mean(vel[ok] ** 2))) if ok.any() else float("nan")
        out["vel_max"] = float(vel[ok].max()) if ok.any() else float("nan")
        out["scored"] = float(ok.sum())
        for name, a, b in self.windows():
            w = (self.t >= a) & (self.t < b) & ok
            out.update(stats(w, f"{name}."))
            out[f"{name}.hor_rel_max"] = float(rel[w].max()) if w.any() else float("nan")
        return out

    def summary(self) -> dict[str, Any]:
        """The scenario as run (user form and SI form), seed, versions, and key results."""
        return {
            "scenario": self.scenario.raw,
            "scenario_si": self.scenario.core,
            "source": self.scenario.source,
            "seed": self.seed,
            "versions": {"navfdi": _core.__version__, "python": platform.python_version(), "numpy": np.__version__},
            "faults": [m.__dict__ for m in self.fault_table()],
            "integrity": self.integrity(),
            **({"consistency": consistency(self)} if "nav" in self.record else {}),
            **({"exclusions": self.exclusion_counts()} if "nav" in self.record else {}),
        }

    def exclusion_counts(self) -> dict[str, dict[str, int]]:
        """Per loosely coupled GNSS channel, the tested epochs left out (wholly or in some
        components) per reason (``test``, ``step``, ``stale``, ``ramp``, ``receiver``) and ``tested``, the
        epochs it was tested at. Empty for other architectures."""
        out: dict[str, dict[str, int]] = {}
        for s in self.record["subfilters"]:
            if "noise_scale" not in s:
                continue
            reason = np.asarray(s["reason"])
            tested = tested_epochs(s["statistic"])
            row = {"tested": int(np.sum(tested))}
            for r, name in enumerate(s["reason_names"]):
                if r:
                    row[name] = int(np.sum((reason == r) & tested))
            out[s["sensor"]] = row
        return out

    def write(self, out: str | Path, figures: bool = True) -> list[Path]:
        """Write ``events.csv``, ``timeseries.parquet``, ``summary.json`` and (optionally) PNG
        figures to directory ``out`` (created if needed). Returns the paths written."""
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        paths = [out / "events.csv", out / "timeseries.parquet", out / "errors.csv", out / "summary.json"]
        events = self.events().rename(columns=EVENT_UNITS)
        events.to_csv(paths[0], index=False)
        self.timeseries().to_parquet(paths[1], index=False)
        import pandas as pd

        errors = pd.DataFrame([{"variant": self.variant, **self.errors()}]).rename(columns=_error_unit)
        errors.to_csv(paths[2], index=False)
        paths[3].write_text(_json.dumps(self.summary(), default=float), encoding="utf-8")
        figs: list[Path] = []
        if figures:
            from navfdi.plots import plot_run

            figs = plot_run(self, out)
        paths += figs
        t = self.t
        series = {f"{c} [m]": self.record["error"][:, 6 + i] for i, c in enumerate(("east", "north", "up"))}
        windows = [(f["start"], f["end"]) for f in self.scenario.faults()]
        paths.append(_report(self.scenario, self.seed, out, [("errors.csv", errors), ("events.csv", events)], figs, (t, series, windows, "time [s]"), self._headline()))
        return paths

    def _headline(self) -> dict[str, Any]:
        """The numbers a reader of the report looks for first: navigation-error RMS and, per
        fault and deciding detector, detection, delay, onset and share in alarm."""
        e = self.errors()
        if "nav" in self.record:
            head: dict[str, Any] = {"horizontal error RMS [m]": e["hor_rms"], "horizontal error max [m]": e["hor_max"], "vertical error RMS [m]": e["ver_rms"]}
            for m in self.fault_table():
                key = f"{m.fault_id} · {m.subfilter}/{m.detector}"
                head[f"{key}: delay [s]"] = float("nan") if m.delay is None else m.delay
            return head
        out: dict[str, Any] = {"latitude error RMS [m]": e["lat_m_rms"], "east error RMS [m]": e["pos_e_rms"], "up error RMS [m]": e["pos_u_rms"], "attitude error RMS [arcsec]": float(np.degrees(np.sqrt((e["att_e_rms"] ** 2 + e["att_n_rms"] ** 2 + e["att_u_rms"] ** 2) / 3)) * 3600)}
        if "fused_alt_rms" in e:
            out["fused altitude error RMS [m]"] = e["fused_alt_rms"]
        for m in self.fault_table():
            key = f"{m.fault_id} · {m.subfilter}/{m.detector}"
            out[f"{key}: delay [s]"] = float("nan") if m.delay is None else m.delay
            out[f"{key}: in alarm [%]"] = 100 * m.alarm_fraction
        i = self.integrity()
        if i is not None:
            out["HPL mean [m]"], out["VPL mean [m]"] = i["hpl_mean"], i["vpl_mean"]
            out["VPL filter/snapshot"] = i["vpl_ratio_mean"]
            out["hazardously misleading epochs, horizontal"] = i["hazardous_h"]
            out["hazardously misleading epochs, vertical"] = i["hazardous_v"]
        return out


class _Variants(dict):
    """``{variant: ScenarioRun}`` whose missing key names the variants there are."""

    def __missing__(self, key: object) -> ScenarioRun:
        raise KeyError(f"no variant {key!r}; the variants are: {', '.join(map(repr, self))}")


class VariantRuns:
    """Result of :func:`run_scenario` for a scenario with ``[[variants]]``: one
    :class:`ScenarioRun` per variant, all on the same simulated measurements.

    Attributes
    ----------
    scenario : Scenario
        The scenario as given (with its variants).
    seed : int
        Random seed.
    runs : dict
        ``{variant name: ScenarioRun}`` in the scenario's order.
    """

    def __init__(self, scenario: Scenario, seed: int, runs: dict[str, ScenarioRun]):
        runs = _Variants(runs)
        self.scenario = scenario
        self.seed = seed
        self.runs = runs

    def __getitem__(self, name: str) -> ScenarioRun:
        """The run of variant ``name`` (``KeyError`` naming the variants otherwise)."""
        return self.runs[name]

    def events(self):
        """:meth:`ScenarioRun.events` of every variant, with a first column ``variant``."""
        import pandas as pd

        frames = [r.events().assign(variant=name) for name, r in self.runs.items()]
        df = pd.concat(frames, ignore_index=True)
        return df[["variant", *[c for c in df.columns if c != "variant"]]]

    def timeseries(self):
        """:meth:`ScenarioRun.timeseries` of every variant stacked (long format), with a first
        column ``variant``."""
        import pandas as pd

        frames = [r.timeseries().assign(variant=name) for name, r in self.runs.items()]
        df = pd.concat(frames, ignore_index=True)
        return df[["variant", *[c for c in df.columns if c != "variant"]]]

    def errors(self):
        """One row per variant: ``variant`` and :meth:`ScenarioRun.errors` (RMS and maximum per
        component, m, m/s, rad). Returns a pandas DataFrame (``errors.csv``)."""
        import pandas as pd

        return pd.DataFrame([{"variant": name, **r.errors()} for name, r in self.runs.items()])

    def satellite_table(self):
        """:meth:`ScenarioRun.satellite_table` of every variant, with a first column
        ``variant`` (``satellites.csv``; empty without a tight architecture)."""
        import pandas as pd

        frames = [r.satellite_table().assign(variant=name) for name, r in self.runs.items()]
        df = pd.concat(frames, ignore_index=True)
        return df[["variant", *[c for c in df.columns if c != "variant"]]]

    def format_tables(self) -> str:
        """Per-variant fault tables and the error comparison, as printed by ``navfdi run``."""
        first_run = next(iter(self.runs.values()))
        parts = ["\n".join(calibration_lines(first_run.calibration))] if first_run.calibration is not None else []
        seen_notes: set[str] = set()
        for name, r in self.runs.items():
            text = r.format_tables(legend=False)
            # Lines identical in every variant (the MDB's λ0 remark) are printed once.
            kept = [ln for ln in text.split("\n") if not (ln.startswith("MDB note") and ln in seen_notes)]
            seen_notes.update(ln for ln in kept if ln.startswith("MDB note"))
            parts.append(f"== variant {name} ==\n" + "\n".join(kept))
        if any(r.fault_table() for r in self.runs.values()):
            parts.append("\n".join(FAULT_TABLE_LEGEND) + "\n")
        # errors()'s rows as dicts (no pandas for the console), each with every variant's keys.
        err = [{"variant": name, **r.errors()} for name, r in self.runs.items()]
        err = [{k: row.get(k, float("nan")) for row2 in err for k in row2} for row in err]
        if "hor_rms" in err[0] and not any(row["scored"] > 0 for row in err):
            parts.append(no_reference_line(self.scenario) + "\n")
            return fit("\n".join(parts))
        if "hor_rms" in err[0]:
            first = next(iter(self.runs.values()))
            lines = [f"navigation error per variant against the reference epochs {first.scored_label()}: RMS / max"]
            lines.append(f"  {'variant':<14} {'window':<22} {'horizontal [m]':>18} {'vertical [m]':>18}")
            steady = all(r.steady_offset() for r in self.runs.values())
            if steady:
                lines[0] += "; horizontal also with each run's mean offset removed"
                lines[1] = f"  {'variant':<14} {'window':<22} {'horizontal [m]':>18} {'offset removed':>18} {'vertical [m]':>16}"
            for row in err:
                for name in ["", *[w[0] + "." for w in first.windows()]]:
                    head = f"  {row['variant']:<14} {(name[:-1] or 'whole run'):<22} {row[name + 'hor_rms']:>8.3f} / {row[name + 'hor_max']:<7.3f}"
                    rel = f" {(row['hor_rel_rms'] if not name else float('nan')):>8.3f} / {row[name + 'hor_rel_max']:<7.3f}" if steady else ""
                    lines.append(f"{head}{rel.replace('nan', '  -')} {row[name + 'ver_rms']:>8.3f} / {row[name + 'ver_max']:<7.3f}")
            parts.append("\n".join(lines) + "\n")
            return fit("\n".join(parts))
        lines = ["navigation error per variant (whole run): RMS / max"]
        lines.append(f"  {'variant':<14} {'lat [m]':>16} {'east [m]':>16} {'up [m]':>16} {'vel N [m/s]':>16}")
        for row in err:
            lines.append(
                f"  {row['variant']:<14} {row['lat_m_rms']:>7.3f} / {row['lat_m_max']:<6.2f} {row['pos_e_rms']:>7.3f} / {row['pos_e_max']:<6.2f}"
                f" {row['pos_u_rms']:>7.3f} / {row['pos_u_max']:<6.2f} {row['vel_n_rms']:>7.4f} / {row['vel_n_max']:<6.3f}"
            )
        first = next(iter(self.runs.values()))
        t0, t1 = first.error_window()
        arcsec = np.degrees(1.0) * 3600
        rms = ", ".join(f"{name} {r.attitude_rms(t0, t1) * arcsec:.2f}" for name, r in self.runs.items())
        span = "first fault to end of run" if first.scenario.faults() else "whole run: no faults"
        lines.append(f"master attitude error RMS over {t0:g}–{first.t[-1]:g} s ({span}), arcsec: {rms}")
        if "fused_alt_rms" in err[0]:
            lines.append("fused altitude error per variant: RMS / max [m], share of epochs predicting only in height")
            for row in err:
                lines.append(f"  {row['variant']:<14} {row['fused_alt_rms']:>7.3f} / {row['fused_alt_max']:<6.2f} {row['fused_alt_predict_only']:>6.1%}")
        parts.append("\n".join(lines) + "\n")
        return fit("\n".join(parts))

    def summary(self) -> dict[str, Any]:
        """Scenario, seed, versions and per-variant fault tables and errors (loosely coupled: also
        each variant's ``consistency`` and ``exclusions``, as in :meth:`ScenarioRun.summary`)."""
        return {
            "scenario": self.scenario.raw,
            "source": self.scenario.source,
            "seed": self.seed,
            "versions": {"navfdi": _core.__version__, "python": platform.python_version(), "numpy": np.__version__},
            "variants": {
                name: {
                    "scenario_si": r.scenario.core,
                    "faults": [m.__dict__ for m in r.fault_table()],
                    "errors": r.errors(),
                    "satellites": r.satellite_table().to_dict(orient="records"),
                    "integrity": r.integrity(),
                    **({"consistency": consistency(r), "exclusions": r.exclusion_counts()} if "nav" in r.record else {}),
                }
                for name, r in self.runs.items()
            },
        }

    def write(self, out: str | Path, figures: bool = True) -> list[Path]:
        """Write ``events.csv``, ``timeseries.parquet`` (both with a ``variant`` column),
        ``errors.csv``, ``summary.json``, ``satellites.csv`` (tight architecture) and
        per-variant figures (``{variant}_*.png``)."""
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        paths = [out / "events.csv", out / "timeseries.parquet", out / "errors.csv", out / "summary.json"]
        events = self.events().rename(columns=EVENT_UNITS)
        events.to_csv(paths[0], index=False)
        self.timeseries().to_parquet(paths[1], index=False)
        errors = self.errors().rename(columns=_error_unit)
        errors.to_csv(paths[2], index=False)
        paths[3].write_text(_json.dumps(self.summary(), default=float), encoding="utf-8")
        tables = [("errors.csv", errors), ("events.csv", events)]
        sats = self.satellite_table()
        if len(sats):
            paths.append(out / "satellites.csv")
            sats.to_csv(paths[-1], index=False)
            tables.append(("satellites.csv", sats))
        figs: list[Path] = []
        if figures:
            from navfdi.plots import plot_identified_satellites, plot_run, plot_variant_errors

            for name, r in self.runs.items():
                figs += plot_run(r, out, prefix=f"{name}_")
            figs += plot_variant_errors(self, out)
            figs += plot_identified_satellites(self, out)
        paths += figs
        first = next(iter(self.runs.values()))
        series = {f"{name}: horizontal [m]": np.hypot(r.record["error"][:, 6], r.record["error"][:, 7]) for name, r in self.runs.items()}
        windows = [(f["start"], f["end"]) for f in self.scenario.faults()]
        headline: dict[str, Any] = {}
        for name, r in self.runs.items():
            headline.update({f"{name}: {k}": v for k, v in r._headline().items()})
        paths.append(_report(self.scenario, self.seed, out, tables, figs, (first.t, series, windows, "time [s]"), headline))
        return paths


def _report(sc: Scenario, seed: int, out: Path, tables: list[tuple[str, Any]], figures: list[Path], series: Any, headline: dict[str, Any]) -> Path:
    """``report.html`` of a run (see :mod:`navfdi.report`)."""
    from navfdi.report import write_report

    return write_report(
        out / "report.html",
        f"navfdi run {sc.name}",
        f"{sc.raw.get('description', '')} — seed {seed}, architecture {sc.core.get('architecture', 'federated')}",
        headline,
        tables,
        figures,
        scenario_text=sc.text(),
        series=series,
        notes=" ".join(FAULT_TABLE_LEGEND),
    )


def run_scenario(scenario: Scenario | str | Path, seed: int = 0, compare_isolation: bool = True) -> ScenarioRun | VariantRuns:
    """Simulate and filter one run of a scenario (the loop runs in Rust, GIL released).

    A scenario with ``[[variants]]`` is simulated once and every variant filters the same
    measurements; the result is then a :class:`VariantRuns`.

    Parameters
    ----------
    scenario : Scenario, str or Path
        A loaded scenario, a bundled name (e.g. ``"yang2013"``) or a TOML path.
    seed : int
        Seed of the run's noise (ChaCha8, stream 0).
    compare_isolation : bool
        Also filter the same measurements with isolation disabled (for the error comparison;
        scenarios without variants).

    Returns
    -------
    ScenarioRun or VariantRuns
    """
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed < 2**64:
        raise ValueError(f"seed = {seed!r}: must be an integer in 0 .. 2**64 - 1")
    if "source" in sc.raw:
        return _run_logged(sc, int(seed), compare_isolation)
    if sc.variant_names():
        variants = sc.variants()
        recs = _core.run_variants([v.to_json() for _, v in variants], int(seed))
        _warn_never_applied(sc, recs[0])
        return VariantRuns(sc, int(seed), {name: ScenarioRun(v, int(seed), rec, None, name) for (name, v), rec in zip(variants, recs)})
    recs = _core.run_scenario(sc.to_json(), int(seed), 0, [True, False] if compare_isolation else [True])
    _warn_never_applied(sc, recs[0])
    return ScenarioRun(sc, int(seed), recs[0], recs[1] if compare_isolation else None)


def calibration_lines(cal: Any) -> list[str]:
    """The console lines of the values a run estimated from its log (``"auto"`` fields, or a
    boresight the log showed), followed by a blank line; none without."""
    if cal is None:
        return []
    return ["estimated from the log (navfdi calibrate --out writes them):", *("  " + ln for ln in cal.lines()), ""]


def _run_logged(sc: Scenario, seed: int, compare_isolation: bool) -> ScenarioRun | VariantRuns:
    """A scenario on recorded logs: its faults injected into the recorded measurements, every
    variant on the same ones (see :mod:`navfdi.logs`)."""
    from . import logs
    from .calibrate import resolve_from_log

    sc, cal = resolve_from_log(sc)
    src, scored_at, gps_t0 = logs.scored_source(sc)
    if sc.variant_names():
        variants = sc.variants()
        recs = src.run([v.to_json() for _, v in variants])
        _warn_never_applied(sc, recs[0])
        _warn_frames(ScenarioRun(variants[0][1], seed, recs[0], None))
        out = VariantRuns(sc, seed, {name: ScenarioRun(v, seed, rec, None, name) for (name, v), rec in zip(variants, recs)})
        for r in out.runs.values():
            r.scored_at, r.gps_t0, r.calibration = scored_at, gps_t0, cal
        return out
    recs = src.run([sc.to_json()])
    _warn_frames(ScenarioRun(sc, seed, recs[0], None))
    base = src.run([sc.to_json()], isolation=False)[0] if compare_isolation else None
    _warn_never_applied(sc, recs[0])
    run = ScenarioRun(sc, seed, recs[0], base)
    run.scored_at, run.gps_t0, run.calibration = scored_at, gps_t0, cal
    return run


def _error_unit(c: str) -> str:
    """``errors.csv`` header of an error column: its SI unit appended (``att_e_rms_rad``)."""
    if c == "variant":
        return c
    if c == "fused_alt_predict_only":
        return "fused_alt_predict_only_fraction"
    if c.startswith(("pos_", "lat_m", "fused_alt", "hor_", "ver_", "offset_")) or ".hor_" in c or ".ver_" in c:
        return f"{c}_m"
    if c == "scored":
        return "scored_epochs"
    if c.startswith("vel_"):
        return f"{c}_m_s"
    if c.startswith("att_"):
        return f"{c}_rad"
    return c


#: ``events.csv`` headers: the times carry their unit (s).
EVENT_UNITS = {c: f"{c}_s" for c in ("alarm_start", "alarm_end", "fault_start", "fault_end", "delay")}


def _span(n: np.ndarray) -> str:
    """``"8"`` or ``"7–9"``: the range of a count over the run."""
    lo, hi = int(n.min()), int(n.max())
    return str(lo) if lo == hi else f"{lo}–{hi}"


def _warn_frames(run: ScenarioRun) -> None:
    """:class:`navfdi.frames.FrameWarning` for what a logged run says of its IMU's mounting."""
    for msg in frame_warnings(run, consistency(run)):
        warnings.warn(msg, FrameWarning, stacklevel=4)


def _warn_never_applied(sc: Scenario, record: dict[str, Any]) -> None:
    for f, applied in zip(sc.faults(), record.get("faults_applied", [])):
        if not applied:
            where = f" (satellite {f['satellite']})" if f.get("satellite") else ""
            warnings.warn(
                f"fault {f['id']} on {f['sensor']}{where}: never applied: the sensor takes no measurement"
                f"{' with the satellite in view' if where else ''} inside [{f['start']:g}, {f['end']:g}) s"
                f"{' that the INS navigated (before its alignment or after the IMU log ends)' if 'nav' in record else ''}; it is left out of the detection tables",
                NeverAppliedWarning,
                stacklevel=3,
            )
