"""Monte-Carlo campaigns: N runs × sweep points, run and scored in Rust.

Each run is simulated, filtered (isolation active) and reduced to metrics in Rust; the loop
over runs uses rayon with the GIL released. Python only cuts the campaign into chunks (for
the progress bar, Ctrl-C and Dask) and aggregates the streamed metrics; no time series is kept
unless asked for (``keep_series``).

Reproducibility: run ``i`` draws its noise from ``(seed, i)`` and every sweep point uses the
same run indices (common random numbers), so results are bit-identical whatever the number
of threads, the chunk size or the backend (in-process or Dask).

Metric definitions: see :mod:`navfdi_core::montecarlo` (Rust docs) and docs/montecarlo.md.
"""

from __future__ import annotations

import functools
import itertools
import math
import os
import platform
import statistics
import sys
import time
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from navfdi import _core, _json
from navfdi.record import integrity_figures
from navfdi.scenario import NeverAppliedWarning, Scenario, ScenarioError, ScenarioTooLarge, load_scenario

Z95 = statistics.NormalDist().inv_cdf(0.975)

RUN_COLUMNS = [
    "point",
    "run",
    "failed",
    "subfilter",
    "detector",
    "fault_id",
    "pf",
    "detected",
    "delay",
    "clear_delay",
    "at_onset",
    "alarm_fraction",
    "applied",
    "false_alarm_epochs",
    "outside_epochs",
    "wrong_isolations",
    "fde_faulty_epochs",
    "fde_detected_epochs",
    "fde_exclusion_epochs",
    "fde_exact_epochs",
    "fde_after_epochs",
    "fde_after_alarm_epochs",
    "fde_outside_epochs",
    "fde_false_exclusions",
    "att_rms",
    "att_max",
    "pos_rms",
    "pos_max",
    "lat_rms",
    "lat_max",
    "fused_alt_rms",
    "fused_alt_max",
]


#: Satellite-FDE counts per run and cell (tight architecture; for a loosely coupled channel its
#: exclusions of any reason, the channel counted as one satellite; zero otherwise), see
#: ``navfdi_core::metrics::SatFaultMetrics``.
FDE_COUNTS = [c for c in RUN_COLUMNS if c.startswith("fde_")]

#: Figures of :meth:`Campaign.summary` after the key columns and ``runs``.
SUMMARY_FIGURES = [
    "detection_probability",
    "detection_ci_low",
    "detection_ci_high",
    "in_alarm_at_onset",
    "alarm_fraction",
    "delay_mean",
    "delay_median",
    "delay_p95",
    "clear_delay_mean",
    "false_alarm_rate",
    "false_alarm_ci_low",
    "false_alarm_ci_high",
    "wrong_isolations",
    "detection_rate",
    "identification_rate",
    "false_exclusion_rate",
    "after_fault_alarm_rate",
    "error_rms",
    "position_error_rms",
    "latitude_error_rms",
    "fused_alt_rms",
    "not_applied_runs",
]


def wilson(successes: np.ndarray, trials: np.ndarray, z: float = Z95) -> tuple[np.ndarray, np.ndarray]:
    """Wilson score interval for binomial proportions (vectorised); NaN where trials == 0.
    The bounds are clipped to [0, 1], and are exactly 0 at no success and 1 at n (the formula
    gives them only up to rounding, which printed as ``-0.00000``)."""
    k = np.asarray(successes, dtype=float)
    n = np.asarray(trials, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        p = k / n
        denom = 1 + z**2 / n
        centre = (p + z**2 / (2 * n)) / denom
        half = z * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2)) / denom
    lo = np.where((k == 0) & (n > 0), 0.0, np.clip(centre - half, 0.0, 1.0))
    hi = np.where((k == n) & (n > 0), 1.0, np.clip(centre + half, 0.0, 1.0))
    return lo, hi


def parse_sweep(items: Iterable[str], option: str = "--sweep") -> dict[str, list[Any]]:
    """Parse ``PATH=v1,v2,...`` strings (CLI form) into ``{path: [values]}``; ``option`` is
    the option they came from (``--sweep`` or ``--set``), named in errors.

    Values that read as numbers become floats (ints stay ints), ``true``/``false`` become
    booleans, everything else stays a string (e.g. ``"0.2 sigma/s"``).
    """
    out: dict[str, list[Any]] = {}
    for item in items:
        path, sep, values = item.partition("=")
        path = path.strip()
        if not sep or not path or not values.strip():
            example = "faults[0].magnitude=0.1 sigma/s,0.2 sigma/s" if option == "--sweep" else "faults[0].magnitude=30 m"
            form = "PATH=v1,v2,..." if option == "--sweep" else "PATH=VALUE"
            raise ScenarioError(f"{option} {item!r}: expected {form} (e.g. {example})")
        vals: list[Any] = []
        for v in values.split(","):
            v = v.strip()
            if v.lower() in ("true", "false"):
                vals.append(v.lower() == "true")
                continue
            try:
                vals.append(int(v))
                continue
            except ValueError:
                pass
            try:
                vals.append(float(v))
            except ValueError:
                vals.append(v)
        if path in out:
            raise ScenarioError(f"--sweep {path}: given twice")
        out[path] = vals
    return out


@functools.lru_cache(maxsize=8)
def _prepared(spec_json: str) -> _core.PreparedScenario:
    return _core.PreparedScenario(spec_json)


def _chunk(spec_json: str, seed: int, start: int, count: int, threads: int, keep: tuple[int, ...]) -> dict[str, Any]:
    """Run one chunk (also the task executed on Dask workers)."""
    return _prepared(spec_json).run_chunk(seed, start, count, threads, list(keep))


@dataclass
class Campaign:
    """Result of :func:`montecarlo`.

    Attributes
    ----------
    scenario : Scenario
        The base scenario.
    seed : int
        Campaign seed.
    runs_requested : int
        Runs per sweep point asked for.
    sweep : dict
        ``{path: [values]}`` (user form, with units).
    points : list of dict
        One ``{path: value}`` per sweep point (``[{}]`` without a sweep).
    runs : pandas.DataFrame
        One row per run × sub-filter × detector × fault (``none`` for outside faults) × sweep
        point; columns :data:`RUN_COLUMNS` plus one per swept field.
    partial : bool
        True when the campaign was interrupted; ``runs`` then holds the finished runs only.
    backend : str
        ``"local (K threads)"`` or ``"dask (ADDRESS)"``.
    series : dict
        ``{(point, run): record}`` for the runs in ``keep_series`` (record: as
        :func:`navfdi._core.run_scenario` returns).
    transfer : navfdi._dask.Transfer or None
        On a Dask cluster: what was shipped to the workers (bytes per worker, time) and their
        peak memory; None in-process.
    """

    scenario: Scenario
    seed: int
    runs_requested: int
    sweep: dict[str, list[Any]]
    points: list[dict[str, Any]]
    runs: Any
    partial: bool
    backend: str
    series: dict[tuple[int, int], dict[str, Any]] = field(default_factory=dict)
    cells: list[list[tuple[str, str, str, float]]] = field(default_factory=list)
    variants: list[str] = field(default_factory=list)
    never_applied: list[set[str]] = field(default_factory=list)
    transfer: Any = field(default_factory=lambda: None)

    def runs_per_point(self) -> list[int]:
        """Finished runs of each sweep point, in point order (all equal ``runs_requested``
        unless the campaign was interrupted)."""
        done = self.runs.groupby("point")["run"].nunique().to_dict() if len(self.runs) else {}
        return [int(done.get(i, 0)) for i in range(len(self.points))]

    @property
    def sweep_columns(self) -> list[str]:
        """Column names of the point keys: ``variant`` (scenarios with variants) and the swept
        fields."""
        return (["variant"] if self.variants else []) + list(self.sweep)

    def summary(self):
        """One row per sweep point × sub-filter × detector × fault (pandas DataFrame).

        Columns: swept fields, ``subfilter, detector, fault_id, pf, runs,
        detection_probability, detection_ci_low, detection_ci_high`` (Wilson 95 %; a detection is
        an alarm onset inside the fault window or up to 1 s after it), ``in_alarm_at_onset``
        (share of runs already in alarm when the fault began: not detections),
        ``alarm_fraction`` (mean share of the fault's epochs in alarm),
        ``delay_mean, delay_median, delay_p95`` (s, over detected runs), ``clear_delay_mean``,
        ``false_alarm_rate, false_alarm_ci_low, false_alarm_ci_high`` (per epoch outside the
        faults; Wilson 95 % treating epochs as independent trials, which understates the
        interval for detectors with memory such as the SPRT), ``wrong_isolations`` (per run),
        satellite FDE (tight architecture, pooled over runs; for a loosely coupled channel its
        exclusions of any reason — the test, a held step, a stale fix, a ramp — the channel
        counted as one satellite; NaN elsewhere):
        ``detection_rate`` (faulty epochs with the faulty satellite excluded / faulty epochs
        with it in view), ``identification_rate`` (epochs with exactly it excluded / epochs
        with any exclusion in the window), ``false_exclusion_rate`` (satellites excluded per
        epoch outside faults and their 50-epoch after-windows; ``none`` rows),
        ``after_fault_alarm_rate`` (epochs with any exclusion among the 50 measured epochs after
        the fault ends),
        ``error_rms`` (master attitude error RMS over all runs and epochs, rad),
        ``position_error_rms`` (m), ``latitude_error_rms`` (north position, m), ``fused_alt_rms`` (fused-altitude error RMS over
        the runs, m; NaN without altitude fusion), ``runs_requested`` and ``partial`` (True where the point
        has fewer finished runs than requested: an interrupted campaign). Campaigns on
        recorded logs add ``horizontal_error_rms`` (m, against the reference's non-input
        epochs, over the runs) and ``fault_horizontal_error_max_mean``, ``_p95`` (m, each
        run's largest horizontal error inside its fault window; mean and 95th percentile over
        the runs), and the same three with each run's mean horizontal offset to the reference
        (over its scored epochs outside the fault windows) removed:
        ``horizontal_error_rms_offset_removed``, ``fault_horizontal_error_max_offset_removed_mean``,
        ``_p95`` (m); their ``runs`` table also has each run's drawn ``fault_start`` (s),
        ``fault_magnitude`` (SI), ``fault_kind``, ``fault_components`` and ``fault_satellite``
        ("" for none) on its fault rows.
        Fault rows carry NaN
        false-alarm rates; ``none`` rows NaN detection figures. Every point × cell has a row,
        with ``runs = 0`` and NaN figures where an interrupted campaign ran none.
        """
        import pandas as pd

        df = self.completed_runs()
        keys = ["point", *self.sweep_columns, "subfilter", "detector", "fault_id", "pf"]
        per_point = self.runs_per_point()
        rows = []
        seen = set()
        for key, g in df.groupby(keys, sort=False, dropna=False):
            rec = dict(zip(keys, key))
            n = len(g)
            rec["runs"] = n
            is_fault = rec["fault_id"] != "none"
            skipped = is_fault and self.never_applied and rec["fault_id"] in self.never_applied[int(rec["point"])]
            if skipped:
                # Never reached a measurement: no detection figure (it would count alarms that
                # have nothing to do with the fault).
                rec.update({k: math.nan for k in ("detection_probability", "detection_ci_low", "detection_ci_high", "in_alarm_at_onset", "alarm_fraction", "delay_mean", "delay_median", "delay_p95", "clear_delay_mean", "false_alarm_rate", "false_alarm_ci_low", "false_alarm_ci_high", "wrong_isolations")})
            elif is_fault:
                # Runs whose fault never reached a processed measurement (drawn past the end
                # of a partial log) are not missed detections: left out, counted apart.
                rec["not_applied_runs"] = int((~g["applied"].astype(bool)).sum())
                g = g[g["applied"].astype(bool)]
                n = len(g)
                det = int(g["detected"].sum())
                lo, hi = wilson(np.array([det]), np.array([n]))
                d = g.loc[g["detected"], "delay"].to_numpy()
                rec.update(
                    detection_probability=det / n if n else math.nan,
                    detection_ci_low=float(lo[0]),
                    detection_ci_high=float(hi[0]),
                    in_alarm_at_onset=float(g["at_onset"].mean()),
                    alarm_fraction=float(np.nanmean(g["alarm_fraction"])) if g["alarm_fraction"].notna().any() else math.nan,
                    delay_mean=float(d.mean()) if d.size else math.nan,
                    delay_median=float(np.median(d)) if d.size else math.nan,
                    delay_p95=float(np.percentile(d, 95)) if d.size else math.nan,
                    clear_delay_mean=float(np.nanmean(g["clear_delay"])) if g["clear_delay"].notna().any() else math.nan,
                    false_alarm_rate=math.nan,
                    false_alarm_ci_low=math.nan,
                    false_alarm_ci_high=math.nan,
                    wrong_isolations=math.nan,
                )
            else:
                fa, out = int(g["false_alarm_epochs"].sum()), int(g["outside_epochs"].sum())
                lo, hi = wilson(np.array([fa]), np.array([out]))
                rec.update(
                    detection_probability=math.nan,
                    detection_ci_low=math.nan,
                    detection_ci_high=math.nan,
                    in_alarm_at_onset=math.nan,
                    alarm_fraction=math.nan,
                    delay_mean=math.nan,
                    delay_median=math.nan,
                    delay_p95=math.nan,
                    clear_delay_mean=math.nan,
                    false_alarm_rate=fa / out if out else math.nan,
                    false_alarm_ci_low=float(lo[0]),
                    false_alarm_ci_high=float(hi[0]),
                    wrong_isolations=float(g["wrong_isolations"].mean()),
                )
            sums = {k: int(g[k].sum()) for k in FDE_COUNTS}
            ratio = lambda a, b: a / b if b else math.nan  # noqa: E731
            rec["detection_rate"] = ratio(sums["fde_detected_epochs"], sums["fde_faulty_epochs"])
            rec["identification_rate"] = ratio(sums["fde_exact_epochs"], sums["fde_exclusion_epochs"])
            rec["after_fault_alarm_rate"] = ratio(sums["fde_after_alarm_epochs"], sums["fde_after_epochs"])
            rec["false_exclusion_rate"] = ratio(sums["fde_false_exclusions"], sums["fde_outside_epochs"])
            rec["error_rms"] = float(np.sqrt(np.mean(g["att_rms"].to_numpy() ** 2)))
            rec["position_error_rms"] = float(np.sqrt(np.mean(g["pos_rms"].to_numpy() ** 2)))
            rec["latitude_error_rms"] = float(np.sqrt(np.mean(g["lat_rms"].to_numpy() ** 2)))
            fa = g["fused_alt_rms"].to_numpy()
            rec["fused_alt_rms"] = float(np.sqrt(np.mean(fa[np.isfinite(fa)] ** 2))) if np.isfinite(fa).any() else float("nan")
            if "hor_rms" in g:
                hr, fm = g["hor_rms"].to_numpy(float), g["fault_hor_max"].to_numpy(float)
                rec["horizontal_error_rms"] = float(np.sqrt(np.nanmean(hr**2))) if np.isfinite(hr).any() else math.nan
                rec["fault_horizontal_error_max_mean"] = float(np.nanmean(fm)) if np.isfinite(fm).any() else math.nan
                rec["fault_horizontal_error_max_p95"] = float(np.nanpercentile(fm, 95)) if np.isfinite(fm).any() else math.nan
                rr, rm = g["hor_rel_rms"].to_numpy(float), g["fault_hor_rel_max"].to_numpy(float)
                rec["horizontal_error_rms_offset_removed"] = float(np.sqrt(np.nanmean(rr**2))) if np.isfinite(rr).any() else math.nan
                rec["fault_horizontal_error_max_offset_removed_mean"] = float(np.nanmean(rm)) if np.isfinite(rm).any() else math.nan
                rec["fault_horizontal_error_max_offset_removed_p95"] = float(np.nanpercentile(rm, 95)) if np.isfinite(rm).any() else math.nan
            rows.append(rec)
            seen.add((rec["point"], rec["subfilter"], rec["detector"], rec["fault_id"]))
        for point, cells in enumerate(self.cells):
            for sub, det, fid, pf in cells:
                if (point, sub, det, fid) not in seen:
                    rec = {"point": point, **{c: self.points[point][c] for c in self.sweep_columns}, "subfilter": sub, "detector": det, "fault_id": fid, "pf": float(pf), "runs": 0}
                    rows.append(rec)
        extra = [
            "horizontal_error_rms", "fault_horizontal_error_max_mean", "fault_horizontal_error_max_p95", "horizontal_error_rms_offset_removed",
            "fault_horizontal_error_max_offset_removed_mean", "fault_horizontal_error_max_offset_removed_p95",
        ] if "hor_rms" in df else []
        cols = [*keys, "runs", *SUMMARY_FIGURES, *extra]
        out = pd.DataFrame(rows, columns=cols) if rows else pd.DataFrame(columns=cols)
        if rows:
            order = {(p, c[0], c[1], c[2]): i for p, cells in enumerate(self.cells) for i, c in enumerate(cells)}
            out["_order"] = [order.get((r.point, r.subfilter, r.detector, r.fault_id), -1) for r in out.itertuples()]
            out = out.sort_values(["point", "_order"], kind="stable").drop(columns=["_order"]).reset_index(drop=True)
        out["runs_requested"] = self.runs_requested
        out["partial"] = [per_point[int(p)] < self.runs_requested for p in out["point"]] if len(out) else []
        return out.drop(columns=["point"])

    def integrity_summary(self):
        """Filter protection levels against the true position error, one row per sweep point
        (pandas DataFrame; empty unless the scenario's tight filter has ``[tight.integrity]``).

        Columns: swept fields, ``runs``, ``epochs`` (epochs with finite levels, over the runs),
        ``misleading_h``, ``misleading_v`` (epochs whose horizontal / vertical error exceeds the
        HPL / VPL), ``hazardous_h``, ``hazardous_v`` (of those, epochs without an alarm of the
        separation test: hazardously misleading), ``hmi_rate_h``, ``hmi_rate_v`` (per epoch),
        ``alarm_epochs``, ``error_over_hpl_max``, ``error_over_vpl_max`` (the largest error /
        level over all runs: below 1 means no epoch came near), ``hpl_mean``, ``vpl_mean`` (m),
        ``hpl_ratio_mean``, ``vpl_ratio_mean`` (filter level / snapshot ARAIM level of the same
        epoch's pseudoranges, mean over the epochs with both), ``mi_rate_h``, ``mi_rate_v``
        with their 95 % Wilson bounds ``…_lo``, ``…_hi`` (per epoch: epochs of one run are
        correlated, so these bounds are optimistic), and ``hmi_runs`` (runs with at least one
        hazardously misleading epoch, horizontal or vertical) with ``hmi_runs_lo``,
        ``hmi_runs_hi`` (Wilson over the runs, which are independent)."""
        import pandas as pd

        df = self.completed_runs()
        cols = [*self.sweep_columns, "runs", "epochs", "misleading_h", "misleading_v", "hazardous_h", "hazardous_v", "hmi_rate_h", "hmi_rate_v",
                "alarm_epochs", "error_over_hpl_max", "error_over_vpl_max", "hpl_mean", "vpl_mean", "hpl_ratio_mean", "vpl_ratio_mean",
                "mi_rate_h", "mi_rate_h_lo", "mi_rate_h_hi", "mi_rate_v", "mi_rate_v_lo", "mi_rate_v_hi", "hmi_runs", "hmi_runs_lo", "hmi_runs_hi"]
        if "pl_epochs" not in df or not len(df):
            return pd.DataFrame(columns=cols)
        per_run = df.drop_duplicates(["point", "run"])
        rows = []
        sums = ["mi_h_epochs", "mi_v_epochs", "hmi_h_epochs", "hmi_v_epochs", "hpl_sum", "vpl_sum", "hpl_ratio_sum", "vpl_ratio_sum"]
        for point, g in per_run.groupby("point", sort=True):
            f = integrity_figures({
                **{k: g[k].sum() for k in sums},
                "epochs": g["pl_epochs"].sum(),
                "alarm_epochs": g["pl_alarm_epochs"].sum(),
                "compared_epochs": g["pl_compared_epochs"].sum(),
                "error_over_hpl_max": g["error_over_hpl_max"].max(),
                "error_over_vpl_max": g["error_over_vpl_max"].max(),
            })
            ep = f["epochs"]
            hmi_runs = int(((g["hmi_h_epochs"] + g["hmi_v_epochs"]) > 0).sum())
            (mh_lo, mv_lo, r_lo), (mh_hi, mv_hi, r_hi) = wilson(np.array([f["misleading_h"], f["misleading_v"], hmi_runs]),
                                                                np.array([ep, ep, len(g)]))
            rows.append({
                **{c: self.points[int(point)][c] for c in self.sweep_columns},
                "runs": len(g),
                **f,
                "hmi_rate_h": f["hazardous_h"] / ep if ep else math.nan,
                "hmi_rate_v": f["hazardous_v"] / ep if ep else math.nan,
                "mi_rate_h": f["misleading_h"] / ep if ep else math.nan, "mi_rate_h_lo": mh_lo, "mi_rate_h_hi": mh_hi,
                "mi_rate_v": f["misleading_v"] / ep if ep else math.nan, "mi_rate_v_lo": mv_lo, "mi_rate_v_hi": mv_hi,
                "hmi_runs": hmi_runs, "hmi_runs_lo": r_lo, "hmi_runs_hi": r_hi,
            })
        return pd.DataFrame(rows, columns=cols)

    def _integrity_lines(self) -> list[str]:
        """The integrity block of :meth:`format_table` (empty without protection levels)."""
        t = self.integrity_summary()
        if not len(t):
            return []
        lines = ["filter protection levels (error > PL: misleading; without an alarm: hazardous; runs with a"]
        lines.append("  hazardous epoch with their 95 % interval):")
        lines.append(f"  {'point':<16} {'epochs':>8} {'MI h/v':>9} {'HMI h/v':>9} {'err/PL max':>11} {'PL h/v [m]':>10} {'/snapsh.':>9} {'HMI runs':>18}")
        for _, r in t.iterrows():
            name = ", ".join(str(r[c]) for c in self.sweep_columns) or "all"
            name = name if len(name) <= 16 else name[:15] + "…"
            mi = f"{int(r['misleading_h'])}/{int(r['misleading_v'])}"
            hmi = f"{int(r['hazardous_h'])}/{int(r['hazardous_v'])}"
            worst = f"{r['error_over_hpl_max']:.2f}/{r['error_over_vpl_max']:.2f}"
            pl = f"{r['hpl_mean']:.1f}/{r['vpl_mean']:.1f}"
            ratio = f"{r['hpl_ratio_mean']:.2f}/{r['vpl_ratio_mean']:.2f}"
            runs = f"{int(r['hmi_runs'])}/{int(r['runs'])} [{r['hmi_runs_lo']:.2f},{r['hmi_runs_hi']:.2f}]"
            lines.append(f"  {name:<16} {int(r['epochs']):>8} {mi:>9} {hmi:>9} {worst:>11} {pl:>10} {ratio:>9} {runs:>18}")
        # On recorded logs (the only campaigns with a reference, "hor_rms"): alarms over half
        # the epochs are the model's, not the drawn fault's (in simulation a variant that
        # excludes nothing alarms for as long as its fault lasts).
        busy = t[t["alarm_epochs"] > 0.5 * t["epochs"]] if "hor_rms" in self.runs else t.iloc[0:0]
        if len(busy):
            names = ", ".join(", ".join(str(r[c]) for c in self.sweep_columns) or "the campaign" for _, r in busy.iterrows())
            lines.append(f"  the separation test alarms at over half the epochs of {names}:")
            lines.append("  the levels do not hold on these data (see the note of `navfdi run`)")
        lines.append("")
        return lines

    def format_table(self) -> str:
        """The summary as printed by ``navfdi montecarlo``: one block per sweep point (and
        variant) with its navigation error, then one row per channel × detector × fault, at
        most 100 characters wide. A detection is an alarm raised inside the fault window (or
        one epoch after it); ``at onset`` is the share of runs already in alarm when the fault
        began (not detections), ``in alarm`` the mean share of the fault's epochs in alarm.
        Channels with identical outside-fault rows (ultra-tight satellites) are pooled."""
        s = self.summary()
        per_point = self.runs_per_point()
        if len(set(per_point)) == 1:
            done = f"{per_point[0]} of {self.runs_requested} runs per point"
        else:
            done = f"runs per point {', '.join(map(str, per_point))} of {self.runs_requested} each"
        head = f"{self.scenario.name}: {done}, seed {self.seed}, {self.backend}"
        if self.partial:
            head += "  [PARTIAL: interrupted]"
        lines = [head, ""]
        fails = self.failures()
        if fails["count"]:
            lines.insert(1, f"{fails['count']} run(s) failed and are left out of the figures:")
            for msg, k in list(fails["errors"].items())[:3]:
                lines.insert(2, f"  {k} × {msg}")
        arcsec = math.degrees(1) * 3600
        sat_of = {f["id"]: "drawn" if (f.get("draw") or {}).get("satellites") else f.get("satellite") or "" for f in self.scenario.faults()}
        cut = lambda v, n: v if len(v) <= n else v[: n - 1] + "…"  # noqa: E731
        f3 = lambda v: "-" if v != v else f"{v:.2f}"  # noqa: E731
        pct = lambda v: "-" if v != v else f"{100 * v:.0f} %"  # noqa: E731
        keys = self.sweep_columns
        groups = s.groupby(keys, sort=False, dropna=False) if keys else [((), s)]
        for key, g in groups:
            key = key if isinstance(key, tuple) else (key,)
            if keys:
                lines.append("· " + ", ".join(f"{k} = {v}" for k, v in zip(keys, key)))
            r0 = g.iloc[0]
            err = f"  error RMS: attitude {r0['error_rms'] * arcsec:.2f} arcsec, position {r0['position_error_rms']:.3f} m, latitude {r0['latitude_error_rms']:.3f} m"
            if "horizontal_error_rms" in g:
                err = f"  horizontal error RMS {r0['horizontal_error_rms']:.3f} m"
                fm = g["fault_horizontal_error_max_mean"].to_numpy(float)
                if np.isfinite(fm).any():
                    err += f"; largest in the fault: mean {np.nanmax(fm):.2f} m, p95 {np.nanmax(g['fault_horizontal_error_max_p95'].to_numpy(float)):.2f} m"
                if r0["horizontal_error_rms_offset_removed"] < 0.5 * r0["horizontal_error_rms"]:
                    # The error is mostly a steady offset (the reference's own, e.g. walk_tc's).
                    fr = g["fault_horizontal_error_max_offset_removed_mean"].to_numpy(float)
                    lines.append(err)
                    err = f"  run's mean offset removed: RMS {r0['horizontal_error_rms_offset_removed']:.3f} m"
                    if np.isfinite(fr).any():
                        err += f"; largest in the fault: mean {np.nanmax(fr):.2f} m, p95 {np.nanmax(g['fault_horizontal_error_max_offset_removed_p95'].to_numpy(float)):.2f} m"
            if r0["fused_alt_rms"] == r0["fused_alt_rms"]:
                err += f", fused altitude {r0['fused_alt_rms']:.3f} m"
            lines.append(err)
            lines.append(f"  {'channel':<11} {'detector':<8} {'fault':<10} {'runs':>5} {'P(det) [95% CI]':>17} {'onset':>6} {'alarm':>6} {'delay med/p95 [s]':>18}")
            faults = g[g["fault_id"] != "none"]
            outside = g[g["fault_id"] == "none"]
            for _, r in faults.iterrows():
                row = f"  {cut(str(r['subfilter']), 11):<11} {cut(str(r['detector']), 8):<8} {cut(str(r['fault_id']), 10):<10} {int(r['runs']):>5}"
                if r["runs"] == 0:
                    lines.append(row + "  (no finished runs)")
                    continue
                if r["detection_probability"] != r["detection_probability"]:
                    lines.append(row + "  never applied (no measurement in its window)")
                    continue
                ci = f"{r['detection_probability']:.2f} [{r['detection_ci_low']:.2f},{r['detection_ci_high']:.2f}]"
                delay = f"{f3(r['delay_median'])}/{f3(r['delay_p95'])}"
                lines.append(row + f" {ci:>17} {pct(r['in_alarm_at_onset']):>6} {pct(r['alarm_fraction']):>6} {delay:>18}")
            if len(outside):
                by_det = outside.groupby("detector", sort=False)
                for det, o in by_det:
                    pooled = len(o) > 3
                    rows = [(f"{len(o)} channels", o)] if pooled else [(str(r["subfilter"]), o.loc[[i]]) for i, r in o.iterrows()]
                    for name, oo in rows:
                        fa = float((oo["false_alarm_rate"] * oo["runs"]).sum() / max(oo["runs"].sum(), 1)) if pooled else float(oo["false_alarm_rate"].iloc[0])
                        ci = "" if pooled else f" [{oo['false_alarm_ci_low'].iloc[0]:.5f},{oo['false_alarm_ci_high'].iloc[0]:.5f}]"
                        lines.append(f"  {cut(name, 11):<11} {cut(str(det), 8):<8} {'none':<10} {int(oo['runs'].iloc[0]):>5}  false alarms/epoch {fa:.5f}{ci}")
            fde = g[g["detection_rate"].notna() | g["false_exclusion_rate"].notna()]
            if len(fde):
                # A loosely coupled channel's exclusions (any reason) are counted as one
                # satellite's: the column names the channel instead.
                lc = self.scenario.core.get("architecture") == "loosely_coupled"
                title, col = ("exclusions (pooled):   ", "channel ") if lc else ("satellite FDE (pooled):", "sat     ")
                lines.append(f"  {title} {'fault':<10} {col} {'detection':>9} {'identif.':>9} {'after':>7} {'false excl./epoch':>14}")
                seen = set()
                for _, r in fde.iterrows():
                    fe = r["false_exclusion_rate"]
                    who = cut(str(r["subfilter"]), 8) if lc else sat_of.get(r["fault_id"], "")
                    vals = (r["fault_id"], who, pct(r["detection_rate"]), pct(r["identification_rate"]), pct(r["after_fault_alarm_rate"]), "-" if fe != fe else f"{fe:.4f}")
                    if vals in seen:
                        continue
                    seen.add(vals)
                    lines.append(f"  {'':<23} {cut(vals[0], 10):<10} {vals[1]:<8} {vals[2]:>9} {vals[3]:>9} {vals[4]:>7} {vals[5]:>14}")
            lines.append("")
        lines += self._integrity_lines()
        lines.append("P(det): share of runs with an alarm raised inside the fault window (or 1 s after);")
        lines.append("onset: share already in alarm when the fault began (not detections); alarm: mean share")
        lines.append("of the fault's epochs in alarm. summary.csv has every figure with its interval.")
        return "\n".join(lines) + "\n"

    def completed_runs(self):
        """:attr:`runs` without the runs that failed (their ``failed`` column holds the error;
        every figure of theirs is NaN): what the summary tables are computed from."""
        df = self.runs
        return df[df["failed"] == ""] if "failed" in df and len(df) else df

    def failures(self) -> dict[str, Any]:
        """Runs that failed (a numerical failure on their draw): ``count`` (point × run ×
        variant) and
        ``errors``: ``{error message: count}``. The campaign went on without them."""
        df = self.runs
        if "failed" not in df or not len(df):
            return {"count": 0, "errors": {}}
        bad = df[df["failed"] != ""].drop_duplicates(["point", "run", *(["variant"] if "variant" in df else [])])
        return {"count": int(len(bad)), "errors": {str(k): int(v) for k, v in bad["failed"].value_counts().items()}}

    def campaign_info(self) -> dict[str, Any]:
        """What ``campaign.json`` holds."""
        done = self.runs.groupby("point")["run"].nunique().to_dict() if len(self.runs) else {}
        return {
            "scenario": self.scenario.raw,
            "source": self.scenario.source,
            "seed": self.seed,
            "runs_requested": self.runs_requested,
            "runs_completed": {str(k): int(v) for k, v in done.items()},
            "sweep": self.sweep,
            "points": self.points,
            "partial": self.partial,
            "failed_runs": self.failures(),
            "backend": self.backend,
            "transfer": None if self.transfer is None else self.transfer.as_dict(),
            "versions": {"navfdi": _core.__version__, "python": platform.python_version(), "numpy": np.__version__},
        }

    def write(self, out: str | Path, figures: bool = True) -> list[Path]:
        """Write ``runs.parquet``, ``summary.csv``, ``campaign.json`` (and ``integrity.csv``
        with filter protection levels) and PNG plots to ``out``."""
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        paths = [out / "runs.parquet", out / "summary.csv", out / "campaign.json"]
        runs = self.runs.copy()
        for c in self.sweep_columns:
            runs[c] = runs[c].astype(str)
        runs.to_parquet(paths[0], index=False)
        self.summary().to_csv(paths[1], index=False)
        integ = self.integrity_summary()
        if len(integ):
            paths.append(out / "integrity.csv")
            integ.to_csv(paths[-1], index=False)
        paths[2].write_text(_json.dumps(self.campaign_info(), default=str), encoding="utf-8")
        figs: list[Path] = []
        if figures and len(self.runs):
            from navfdi.plots import plot_campaign

            figs = plot_campaign(self, out)
        paths += figs
        paths.append(self._report(out, figs))
        return paths

    def _report(self, out: Path, figures: list[Path]) -> Path:
        """``report.html``: headline figures per point, ``summary.csv`` as a table, the plots,
        the scenario and the command (see :mod:`navfdi.report`)."""
        from navfdi.report import write_report

        s = self.summary()
        integ = self.integrity_summary()
        headline: dict[str, Any] = {"runs per point": self.runs_requested, "partial": self.partial}
        for _, r in s.iterrows():
            key = " · ".join([*(str(r[c]) for c in self.sweep_columns), f"{r['subfilter']}/{r['detector']}", str(r["fault_id"])])
            if r["fault_id"] != "none":
                headline[f"{key}: P(det)"] = r["detection_probability"]
                headline[f"{key}: in alarm [%]"] = 100 * r["alarm_fraction"] if r["alarm_fraction"] == r["alarm_fraction"] else math.nan
            else:
                headline[f"{key}: false alarms/epoch"] = r["false_alarm_rate"]
        return write_report(
            out / "report.html",
            f"navfdi montecarlo {self.scenario.name}",
            f"{self.runs_requested} runs per point, seed {self.seed}, {self.backend}" + (" — PARTIAL (interrupted)" if self.partial else ""),
            headline,
            [("summary.csv", s)] + ([("integrity.csv", integ)] if len(integ) else []),
            figures,
            scenario_text=self.scenario.text(),
            notes="P(det): share of runs with an alarm raised inside the fault window (or 1 s after); in_alarm_at_onset: share already in alarm when the fault began; alarm_fraction: mean share of the fault's epochs in alarm.",
        )


#: Per-run filter-integrity columns of :attr:`Campaign.runs` (tight filter with
#: ``[tight.integrity]``; repeated on each of the run's cell rows).
INTEGRITY_COLUMNS = (
    "pl_epochs", "mi_h_epochs", "mi_v_epochs", "hmi_h_epochs", "hmi_v_epochs", "pl_alarm_epochs", "pl_compared_epochs",
    "error_over_hpl_max", "error_over_vpl_max", "hpl_sum", "vpl_sum", "hpl_ratio_sum", "vpl_ratio_sum",
)


def _assemble(chunks: list[tuple[int, dict[str, Any]]], cells: list[list[tuple[str, str, str, float]]], points: list[dict[str, Any]], fault_ids: Sequence[str] = ()):
    import pandas as pd

    frames = []
    for point, ch in chunks:
        n = ch["run"].size
        c = len(cells[point])
        sub, det, fid, pf = (np.array([x[i] for x in cells[point]], dtype=object) for i in range(4))
        cols: dict[str, Any] = {
            "point": np.full(n * c, point),
            "run": np.repeat(ch["run"], c),
            "failed": np.repeat(np.asarray(ch.get("failed", [""] * n), dtype=object), c),
            "subfilter": np.tile(sub, n),
            "detector": np.tile(det, n),
            "fault_id": np.tile(fid, n),
            "pf": np.tile(pf.astype(float), n),
        }
        for k in ("detected", "delay", "clear_delay", "at_onset", "alarm_fraction", "applied", "false_alarm_epochs", "outside_epochs", "wrong_isolations", *FDE_COUNTS):
            cols[k] = ch[k].reshape(-1)
        for k in ("att_rms", "att_max", "pos_rms", "pos_max", "lat_rms", "lat_max", "fused_alt_rms", "fused_alt_max"):
            cols[k] = np.repeat(ch[k], c)
        if "fault_start" in ch:
            # Campaigns on recorded logs: each run's drawn fault on its fault rows (NaN / "" on
            # the "none" rows).
            col = {f: j for j, f in enumerate(fault_ids)}
            for k, fill in (("fault_start", np.nan), ("fault_magnitude", np.nan), ("fault_kind", ""), ("fault_components", ""), ("fault_satellite", "")):
                v = np.asarray(ch[k], dtype=object if fill == "" else float).reshape(n, -1)
                cols[k] = [v[r, col[f]] if f in col and col[f] < v.shape[1] else fill for r in range(n) for f in fid]
        if "pl_epochs" in ch:
            for k in INTEGRITY_COLUMNS:
                cols[k] = np.repeat(ch[k], c)
        if np.isfinite(np.asarray(ch["hor_rms"], float)).any():
            # Runs on recorded logs: the horizontal errors against the reference.
            for k in ("hor_rms", "hor_max", "fault_hor_max", "hor_rel_rms", "fault_hor_rel_max"):
                cols[k] = np.repeat(ch[k], c)
        for path, value in points[point].items():
            cols[path] = [value] * (n * c)
        frames.append(pd.DataFrame(cols))
    if not frames:
        return pd.DataFrame(columns=RUN_COLUMNS + list(points[0]))
    df = pd.concat(frames, ignore_index=True)
    return df.sort_values(["point", "run"], kind="stable", ignore_index=True)


#: Bytes per row of :attr:`Campaign.runs` (pandas, object columns included), measured.
_ROW_BYTES = 400.0


def _check_campaign_memory(base: Scenario, runs: int, points: int, keep: tuple[int, ...]) -> None:
    """Refuse a campaign whose per-run table and kept series would not fit in memory (the
    estimate and the message come from the Rust core)."""
    try:
        _core.check_campaign_memory(base.to_json(), float(runs), float(points), float(len(keep)), _ROW_BYTES)
    except MemoryError as e:
        raise ScenarioTooLarge(str(e)) from None


#: Threads per core a campaign may ask for (``workers``).
MAX_THREADS_PER_CORE = 4


def max_workers() -> int:
    """The most threads :func:`montecarlo` accepts: :data:`MAX_THREADS_PER_CORE` per core of
    this machine."""
    return MAX_THREADS_PER_CORE * (os.cpu_count() or 1)


def montecarlo(
    scenario: Scenario | str | Path,
    runs: int,
    seed: int = 0,
    sweep: Mapping[str, Sequence[Any]] | None = None,
    workers: int | None = None,
    client: Any = None,
    chunk_size: int | None = None,
    keep_series: Sequence[int] = (),
    progress: bool | None = None,
    ship: str | os.PathLike[str] = "scatter",
) -> Campaign:
    """Run a Monte-Carlo campaign.

    A scenario with ``[[variants]]`` runs every variant at every sweep point on the same
    simulated measurements (run ``i`` draws from ``(seed, i)`` whatever the variant); the
    results carry a ``variant`` column.

    Parameters
    ----------
    scenario : Scenario, str or Path
        Scenario or bundled name / TOML path.
    runs : int
        Runs per sweep point (≥ 1).
    seed : int
        Campaign seed; run ``i`` uses ``(seed, i)``.
    sweep : mapping, optional
        ``{path: [values]}`` of user-level fields (e.g. ``{"faults[0].magnitude": ["0.05
        sigma/s", "0.1 sigma/s"]}``); the campaign runs the cartesian product of the values.
        Every point is validated before anything runs.
    workers : int, optional
        Threads for the in-process backend (default: all cores; at most :func:`max_workers`,
        4 per core).
    client : dask.distributed.Client, optional
        Run chunks on a Dask cluster instead (``pip install navfdi[dask]``); the runs are
        bit-identical to the in-process ones.
    chunk_size : int, optional
        Runs per chunk (default 16, or enough for 4 chunks per Dask worker thread).
    keep_series : sequence of int
        Run indices (each in ``0 .. runs - 1``) whose full time series to keep
        (``Campaign.series``).
    progress : bool, optional
        Show a progress bar (default: when stderr is a terminal).
    ship : str or path
        With ``client`` and recorded logs: how each prepared source reaches the workers, once
        per worker — ``"scatter"`` (sent by the client) or a directory every worker sees at the
        same path (written there, read by each worker); see :mod:`navfdi._dask`.

    Returns
    -------
    Campaign
        With ``partial=True`` if interrupted by Ctrl-C (the finished runs are kept).

    Raises
    ------
    ValueError
        Bad ``runs``, ``seed``, ``workers``, ``chunk_size`` or ``keep_series``.
    ScenarioError
        A malformed sweep (path, values given as a string, invalid value at some point).
    ScenarioTooLarge
        The per-run table and kept series would not fit in memory (also a ``MemoryError``).
    """
    if isinstance(runs, bool) or not isinstance(runs, (int, np.integer)) or runs < 1:
        raise ValueError(f"runs = {runs!r}: must be a positive integer")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed < 2**64:
        raise ValueError(f"seed = {seed!r}: must be an integer in 0 .. 2**64 - 1")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise ValueError(f"workers = {workers!r}: must be a positive integer")
    if workers is not None and workers > max_workers():
        cores = os.cpu_count() or 1
        raise ValueError(f"workers = {workers}: this machine has {cores} core(s); at most {max_workers()} threads ({MAX_THREADS_PER_CORE} per core) are allowed (more only add overhead; each thread holds a run)")
    if workers is not None and client is not None:
        raise ValueError("workers and client are exclusive: threads are set by the Dask workers")
    base = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    if sweep is not None and not isinstance(sweep, Mapping):
        raise ScenarioError(f"sweep = {sweep!r}: expected a mapping {{path: [values]}}")
    sweep_lists: dict[str, list[Any]] = {}
    for k, v in (sweep or {}).items():
        if isinstance(v, (str, bytes)) or isinstance(v, Mapping) or not isinstance(v, Iterable):
            raise ScenarioError(f"sweep {k} = {v!r}: expected a list of values, e.g. [{v!r}]")
        sweep_lists[str(k)] = list(v)
    for k, v in sweep_lists.items():
        if not v:
            raise ScenarioError(f"sweep {k}: no values")
    combos = [dict(zip(sweep_lists, combo)) for combo in itertools.product(*sweep_lists.values())] if sweep_lists else [{}]
    if "source" in base.raw:
        from navfdi.calibrate import resolve_from_log

        base, _ = resolve_from_log(base)
    variant_names = base.variant_names()
    variant_scenarios = base.variants()  # [("base", base)] without variants
    points = [({"variant": name} if variant_names else {}) | combo for name, _ in variant_scenarios for combo in combos]
    scenarios = []
    for (_, vsc), combo in ((v, c) for v in variant_scenarios for c in combos):  # validate every point first
        sc = vsc
        for path, value in combo.items():
            try:
                sc = sc.with_value(path, value)
            except ScenarioError as e:
                raise ScenarioError(f"sweep {path}={value!r}: {e}") from None
        scenarios.append(sc)
    if isinstance(keep_series, (str, bytes)) or not isinstance(keep_series, Iterable):
        raise ValueError(f"keep_series = {keep_series!r}: expected a list of run indices")
    keep_list = list(keep_series)
    for idx in keep_list:
        if isinstance(idx, bool) or not isinstance(idx, (int, np.integer)):
            raise ValueError(f"keep_series: {idx!r} is not a run index (an integer)")
        if not 0 <= idx < runs:
            raise ValueError(f"keep_series: run {idx} is outside the campaign's runs 0..{runs - 1}")
    keep = tuple(sorted({int(idx) for idx in keep_list}))
    _check_campaign_memory(base, int(runs), len(points), keep)
    threads = workers or 0
    if chunk_size is None:
        chunk_size = 16
    if chunk_size < 1:
        raise ValueError(f"chunk_size = {chunk_size}: must be at least 1")
    # Chunk by chunk across the points (variants, sweep values), so that an interrupted
    # campaign holds about as many runs of each point and still compares them.
    tasks = [(p, s, min(chunk_size, runs - s)) for s in range(0, runs, chunk_size) for p in range(len(points))]
    jsons = [sc.to_json() for sc in scenarios]
    logged = "source" in base.raw
    if str(ship) != "scatter" and client is None:
        raise ValueError(f"ship = {str(ship)!r}: only a campaign on a Dask cluster (client) ships its logs")
    if str(ship) != "scatter" and not Path(ship).is_dir():
        raise ValueError(f"ship = {str(ship)!r}: give \"scatter\" or a directory every Dask worker sees at this path")
    if logged:
        from navfdi import logs

        prepared: list[Any] = [logs.logged_source(sc) for sc in scenarios]
    else:
        prepared = [_prepared(j) if client is None else _core.PreparedScenario(j) for j in jsons]
    cells = [pr.cells for pr in prepared]
    never = [{f["id"] for f, ok in zip(sc.faults(), pr.faults_applied) if not ok} for sc, pr in zip(scenarios, prepared)]
    for pi, ids in enumerate(never):
        for fid in sorted(ids):
            at = f" at sweep point {points[pi]}" if points[pi] else ""
            warnings.warn(f"fault {fid}{at}: never applied (its sensor takes no measurement, or its satellite is not in view, inside its window); it is left out of the detection figures", NeverAppliedWarning, stacklevel=2)
    show = sys.stderr.isatty() if progress is None else progress
    bar = None
    if show:
        from tqdm import tqdm

        bar = tqdm(total=runs * len(points), unit="run", desc=base.name, file=sys.stderr)
    done: list[tuple[int, dict[str, Any]]] = []
    partial = False
    transfer: Any = None
    backend = f"local ({threads or 'all'} threads)"
    try:
        if client is None:
            for p, s, c in tasks:
                kept = tuple(k for k in keep if s <= k < s + c)
                ch = prepared[p].run_chunk(int(seed), s, c, threads, list(kept)) if logged else _chunk(jsons[p], int(seed), s, c, threads, kept)
                done.append((p, ch))
                if bar is not None:
                    bar.update(c)
        else:
            from navfdi import _dask

            info: dict[str, Any] = client.scheduler_info() if hasattr(client, "scheduler_info") else {}
            backend = f"dask ({info.get('address', 'client')})"
            started = time.perf_counter()
            sources, transfer = _dask.ship_sources(client, base.name, prepared, ship) if logged else (None, _dask.Transfer("scenario"))
            try:
                _dask.run_chunks(client, tasks, int(seed), keep, sources, jsons, _chunk, transfer, done, bar)
            finally:
                transfer.wall_seconds = time.perf_counter() - started
    except KeyboardInterrupt:
        partial = True
    finally:
        if bar is not None:
            bar.close()
    series = {(p, int(r)): rec for p, ch in done for r, rec in ch["records"].items()}
    runs_df = _assemble(sorted(done, key=lambda x: (x[0], int(x[1]["run"][0]))), cells, points, [f["id"] for f in base.faults()])
    return Campaign(base, int(seed), int(runs), sweep_lists, points, runs_df, partial, backend, series, cells, variant_names, never, transfer)
