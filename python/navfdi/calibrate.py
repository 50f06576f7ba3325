"""Calibration from the log: what a loosely coupled scenario's IMU settings can be estimated
from its own files (``navfdi calibrate SCENARIO``).

* **Rest intervals**: GNSS epochs below the static speed (or 2.5× the receiver's velocity σ),
  at least :data:`MIN_REST` s long, confirmed by the IMU (the gyro's spread over the interval
  below 2 deg/s).
* **IMU white noise** per axis from the rest intervals (each interval's samples less their
  mean; the median over the intervals): density = σ / √rate, with its σ from the sample count; **gyro bias** as the mean rate
  at rest. A vibrating engine raises the noise above the datasheet's: that is the point, the
  filter needs the noise it will see.
* **Boresight** (pitch and yaw of the IMU beyond its nominal axes): the filter runs without
  its non-holonomic constraint (GNSS-aided only) and the direction of its velocity in the
  body frame is the vehicle's forward axis as the IMU sees it: pitch = median atan2(−v_d,
  v_f), yaw = median atan2(v_r, v_f) over epochs at speed (≥ :data:`MIN_SPEED`) without a turn
  (yaw rate below 3 deg/s, where the IMU's lateral velocity from its lever arm to the rear
  axle is small), once the heading σ has converged.
  Its σ is the filter's own attitude σ with the spread of the epochs. The yaw is read a second
  way that no heading enters — the direction of the specific force in the body frame
  (:func:`_yaw_by_specific_force`) — and the two are combined by their variances. Roll is not
  observable this way and is kept.
* **IMU time offset**: the offset (± :data:`MAX_LAG` s) that makes the filter's own GNSS and
  constraint innovations smallest (their mean normalised square per degree of freedom,
  fault-free, without FDE), on a 0.05 s grid refined by a parabola; its σ from the
  curvature. Reference-free: no truth is used.

* **GNSS σ scale**: reported, per GNSS channel, as the calibrated filter finds it from its
  innovations (``noise_scale``, which estimates it in every run; not written).
Each estimate rests on the ones before it (noise, then boresight, then time offset). A
scenario may leave any of ``imu.gyro_noise``, ``imu.accel_noise``, ``boresight`` and
``imu_time_offset`` as ``"auto"``: :func:`resolve_auto` fills them before a run.
"""

from __future__ import annotations

import copy
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from navfdi._errors import ScenarioError

__all__ = ["Calibration", "calibrate", "boresight_shown", "offset_shown", "resolve_auto", "resolve_from_log", "write_calibrated", "MIN_REST", "MAX_LAG", "MIN_SPEED"]

#: Shortest rest interval used (s).
MIN_REST = 3.0
#: Largest IMU time offset searched (s).
MAX_LAG = 0.5
#: Slowest forward speed at which the boresight is read (m/s).
MIN_SPEED = 3.0
#: Least time at speed without turning the boresight needs (s).
MIN_STRAIGHT = 30.0


@dataclass
class Calibration:
    """What :func:`calibrate` estimated. Densities per IMU axis (x, y, z): ``gyro_noise``
    (deg/s/√Hz), ``accel_noise`` (mg/√Hz), each with ``…_sigma`` (same unit); ``gyro_bias``
    (deg/h, per axis) with its σ — all None when the log has no rest interval;
    ``boresight`` (roll, pitch, yaw, deg: the scenario's roll, the estimated pitch and yaw,
    the whole boresight on top of ``imu_axes``/``mounting``) with ``boresight_sigma`` (pitch
    and yaw, deg), None when the log has too little driving at speed; ``imu_time_offset`` (s)
    with its σ (None when the log does not tell it: ``imu_time_offset_note`` says why);
    ``rest`` the rest intervals used
    ((start, end), s from the first GNSS epoch); ``straight`` the seconds of driving the
    boresight was read from; ``yaw_parts`` the yaw (deg) and its σ from each of the two
    ways it is read (the velocity direction under the filter's heading, the body-frame specific
    force), before they are combined; ``section`` the scenario table the values belong to
    (``loosely_coupled`` or ``tight.strapdown``); ``gnss_sigma_scale`` per GNSS channel the
    factor on the receiver's σ the calibrated filter finds from its innovations (median, 10th
    and 90th percentile; informative: ``noise_scale = "auto"`` estimates it in every run);
    ``imu_axes`` where the IMU's x, y, z point (asked as ``"auto"`` only) with ``imu_axes_fit``
    (the fit of those axes and of the next best, each at most 2:
    :func:`navfdi.frames.estimate_imu_axes`); ``asked`` the fields estimated (None: all),
    the only ones the console report speaks of."""

    gyro_noise: list[float] | None
    gyro_noise_sigma: list[float] | None
    accel_noise: list[float] | None
    accel_noise_sigma: list[float] | None
    gyro_bias: list[float] | None
    gyro_bias_sigma: list[float] | None
    imu_time_offset: float | None
    imu_time_offset_sigma: float | None
    rest: list[tuple[float, float]] = field(default_factory=list)
    boresight: list[float] | None = field(default_factory=lambda: None)
    boresight_sigma: list[float] | None = field(default_factory=lambda: None)
    straight: float = 0.0
    yaw_parts: dict[str, tuple[float, float]] = field(default_factory=dict)
    section: str = "loosely_coupled"
    gnss_sigma_scale: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    imu_axes: list[str] | None = None
    imu_axes_fit: tuple[float, float] | None = None
    asked: tuple[str, ...] | None = None
    imu_time_offset_note: str = "too few turns while moving"
    #: Why the boresight was estimated though the scenario did not ask (:func:`boresight_shown`).
    boresight_note: str = ""
    #: Why the IMU time offset was estimated though the scenario did not ask (:func:`offset_shown`).
    offset_note: str = ""

    def lines(self) -> list[str]:
        """The console report: each value with its σ."""
        f3 = lambda v, s, u: ", ".join(f"{a:.4g} ± {b:.2g}" for a, b in zip(v, s)) + f" {u}"  # noqa: E731
        asked = set(self.asked) if self.asked is not None else None
        out: list[str]
        if asked is not None and not asked & {"imu.gyro_noise", "imu.accel_noise"}:
            out = []
        elif self.gyro_noise is None or self.accel_noise is None or self.gyro_bias is None:
            out = [f"rest intervals: none of {MIN_REST:g} s (speed below the static speed): IMU noise and gyro bias not estimated"]
        else:
            out = [f"rest intervals: {len(self.rest)} ({sum(b - a for a, b in self.rest):.1f} s): "
                   + ", ".join(f"{a:.1f}–{b:.1f} s" for a, b in self.rest[:6]) + (" …" if len(self.rest) > 6 else ""),
                   f"gyro white noise (x, y, z): {f3(self.gyro_noise, self.gyro_noise_sigma or [], 'deg/s/sqrt(Hz)')}",
                   f"accel white noise (x, y, z): {f3(self.accel_noise, self.accel_noise_sigma or [], 'mg/sqrt(Hz)')}",
                   f"gyro bias at rest (x, y, z): {f3(self.gyro_bias, self.gyro_bias_sigma or [], 'deg/h')}"]
        if self.imu_axes is not None and self.imu_axes_fit is not None:
            out.append(f"IMU axes (x, y, z): {', '.join(self.imu_axes)} (the accelerations along and across the track fit them "
                       f"{self.imu_axes_fit[0]:.2f} of 2, the next best axes {self.imu_axes_fit[1]:.2f})")
        if self.section != "loosely_coupled":
            out.append(f"boresight and IMU time offset: not estimated for [{self.section}] (read through the loosely coupled filter's constraint and innovations)")
            return out
        if asked is not None and "boresight" not in asked:
            pass
        elif self.boresight is None or self.boresight_sigma is None:
            out.append(f"boresight: not estimated (less than {MIN_STRAIGHT:g} s at {MIN_SPEED:g} m/s or more without turning)")
        else:
            b, bs = self.boresight, self.boresight_sigma
            out.append(f"boresight (roll kept, pitch, yaw): {b[0]:+.3f}, {b[1]:+.3f} ± {bs[0]:.3f}, {b[2]:+.3f} ± {bs[1]:.3f} deg "
                       f"(from {self.straight:.0f} s of driving)")
            if self.boresight_note:
                out.append(f"  ({self.boresight_note})")
            if len(self.yaw_parts) > 1:
                out.append("  yaw from " + ", from ".join(f"the {k} {v:+.3f} ± {e:.3f}" for k, (v, e) in self.yaw_parts.items()) + " deg (combined by their variances)")
        if asked is not None and "imu_time_offset" not in asked:
            pass
        elif self.imu_time_offset is None:
            out.append(f"IMU time offset: not estimated ({self.imu_time_offset_note})")
        else:
            out.append(f"IMU time offset: {self.imu_time_offset:+.3f} ± {self.imu_time_offset_sigma:.3f} s")
            if self.offset_note:
                out.append(f"  ({self.offset_note})")
        for name, (med, lo, hi) in self.gnss_sigma_scale.items():
            if hi <= 1.0:
                out.append(f"{name}: the receiver's σ covers the innovations (noise_scale stays at its floor, 1)")
            else:
                out.append(f"{name}: the receiver's σ × {med:.2f} (10-90 %: {lo:.2f}-{hi:.2f}) fits the innovations "
                           "(noise_scale, estimated in every run)")
        return out

    def values(self) -> dict[str, Any]:
        """The scenario values it sets: ``{path: value with unit}``."""
        v: dict[str, Any] = {}
        if self.gyro_noise is not None and self.accel_noise is not None:
            v[f"{self.section}.imu.gyro_noise"] = [f"{x:.4g} deg/s/sqrt(Hz)" for x in self.gyro_noise]
            v[f"{self.section}.imu.accel_noise"] = [f"{x:.4g} mg/sqrt(Hz)" for x in self.accel_noise]
        if self.boresight is not None:
            v["loosely_coupled.boresight"] = [f"{x:.4f} deg" for x in self.boresight]
        if self.imu_time_offset is not None:
            v["loosely_coupled.imu_time_offset"] = f"{self.imu_time_offset:.3f} s"
        if self.imu_axes is not None:
            v["loosely_coupled.imu_axes"] = list(self.imu_axes)
        return v


def _rest(t: np.ndarray, speed: np.ndarray, thr: np.ndarray) -> list[tuple[float, float]]:
    still = speed < thr
    out, start = [], None
    for k in range(len(t)):
        if still[k] and start is None:
            start = t[k]
        if (not still[k] or k == len(t) - 1) and start is not None:
            end = t[k] if still[k] else t[k - 1]
            if end - start >= MIN_REST:
                out.append((float(start), float(end)))
            start = None
    return out


def calibrate(scenario: Any, fields: Sequence[str] | None = None) -> Calibration:
    """Estimate a loosely coupled scenario's IMU noise, gyro bias, boresight (pitch, yaw) and
    IMU time offset from its own logs (see the module's description); for a tight scenario
    with ``[tight.strapdown]``, its IMU noise and gyro bias (rest found with the Doppler speed). ``fields`` (paths in
    ``[loosely_coupled]``, :data:`navfdi._lc_schema.AUTO_FIELDS`) limits the work to what is
    asked (the others keep the scenario's values); None estimates everything the log allows.
    Raises :class:`ScenarioError` when an asked field cannot be estimated from the log (the
    noise needs a rest interval of :data:`MIN_REST` s; the boresight driving at speed), or
    when the scenario is not a loosely coupled one on recorded logs. The internal runs take
    the fixes as white (``position_correlation = "0 s"``) whatever the scenario sets."""
    return _calibrate(scenario, fields, optional=False)


def _internal(sc: Any) -> Any:
    """The scenario the calibration's internal runs use: fault-free, one configuration, every
    ``"auto"`` field at the schema's placeholder, without FDE, the fixes weighted as white
    (``position_correlation = "0 s"``: the misfits are read from the innovations of a filter
    the fixes hold; weighted as correlated, the time offset through multipath bursts read
    0.175 s for a simulated 0.23 s)."""
    from navfdi._lc_schema import _auto
    from navfdi.scenario import from_dict

    raw = copy.deepcopy(dict(sc.raw))
    raw.pop("faults", None)
    raw.pop("variants", None)
    raw["loosely_coupled"] = {**_auto(raw["loosely_coupled"], "loosely_coupled"), "isolate": False, "position_correlation": "0 s"}
    return from_dict(raw, source=sc.source)


def _calibrate(scenario: Any, fields: Sequence[str] | None, optional: bool) -> Calibration:
    """:func:`calibrate`; ``optional``: a field the log cannot give is left unestimated (None
    in the calibration) instead of refused, unless the scenario itself sets it to ``"auto"``."""
    from navfdi._lc_schema import AUTO_FIELDS, auto_fields
    from navfdi.scenario import load_scenario

    sc = scenario if hasattr(scenario, "core") else load_scenario(scenario)
    if "source" in sc.raw and "strapdown" in (sc.core.get("tight") or {}):
        return _calibrate_tight(sc, fields)
    if "loosely_coupled" not in sc.core or "source" not in sc.raw:
        raise ScenarioError("calibrate: a loosely coupled scenario, or a tight one with [tight.strapdown], on recorded logs is needed")
    asked = set(AUTO_FIELDS if fields is None else fields)
    if fields is None and "imu_axes" not in auto_fields(sc.raw):
        asked.discard("imu_axes")  # the scenario's own axes or mounting are the user's
    unknown = asked - set(AUTO_FIELDS)
    if unknown:
        raise ScenarioError(f"calibrate: cannot estimate {sorted(unknown)}; the fields are {list(AUTO_FIELDS)}")
    required = set(auto_fields(sc.raw)) | (set() if fields is None or optional else asked)
    # The internal runs: fault-free, one configuration, every "auto" field a value.
    base = _internal(sc)
    from navfdi import logs

    data = logs.load_source(sc.raw["source"], logs.scenario_folder(sc))
    axes = None
    if "imu_axes" in asked:
        from navfdi.frames import estimate_imu_axes

        if data.get("gnss_log") is None:
            raise ScenarioError("calibrate: loosely_coupled.imu_axes = \"auto\" needs a GNSS solution log ([source] gnss)")
        axes = estimate_imu_axes(data["imu_log"].t, data["imu_log"].accel, data["gnss_log"])
        base = base.with_values({"loosely_coupled.imu_axes": axes[0]}, create=True)
    rest, noise = [], None
    if asked & {"imu.gyro_noise", "imu.accel_noise"}:
        rest = _rest_intervals(base.core["loosely_coupled"]["alignment"]["static_speed"], data)
        if rest:
            noise = _noise(data["imu_log"], float(data["t0"]), rest)
            base = base.with_values({f"loosely_coupled.imu.{k}": [f"{x:.6g} {u}" for x in noise[k][0]]
                                     for k, u in (("gyro_noise", "deg/s/sqrt(Hz)"), ("accel_noise", "mg/sqrt(Hz)"))})
        elif required & {"imu.gyro_noise", "imu.accel_noise"}:
            raise ScenarioError(f"calibrate: no rest interval of {MIN_REST:g} s in the GNSS log (speed below the static speed); "
                                "the IMU noise needs the vehicle at rest: give loosely_coupled.imu.gyro_noise and accel_noise (the datasheet's)")
    src = logs.logged_source(base)
    bore = lag = lag_s = None
    offset_note = ""
    # The boresight read from a run with a wrong time offset is off (and the reverse): with
    # both asked, a second round starts from the first's values.
    for _ in range(2 if {"boresight", "imu_time_offset"} <= asked else 1):
        if "boresight" in asked:
            bore = _boresight_from_drive(base, src, data)
            if bore is None and "boresight" in required:
                raise ScenarioError(f"calibrate: loosely_coupled.boresight: less than {MIN_STRAIGHT:g} s at {MIN_SPEED:g} m/s or more "
                                    "without turning in the log; give the boresight (roll, pitch, yaw) or \"0 deg\"")
            if bore is not None:
                base = base.with_values({"loosely_coupled.boresight": [f"{x:.6f} deg" for x in bore[0]]}, create=True)
        if "imu_time_offset" in asked:
            fix_sigma = _positions_alone_sigma(data["gnss_log"])
            if fix_sigma > OFFSET_POSITIONS_SIGMA:
                if "imu_time_offset" in required:
                    raise ScenarioError(
                        f"calibrate: loosely_coupled.imu_time_offset: on positions alone of {fix_sigma:.2g} m "
                        f"(above {OFFSET_POSITIONS_SIGMA:g} m) the log does not tell the offset (simulated: 0.16-0.56 s off in 9 of 23 "
                        "such logs, at a stated sigma of 0.01-0.04 s); give it (0 s where the IMU is stamped on the receiver's "
                        "clock), or a log with the receiver's velocities")
                lag, lag_s = None, None
                offset_note = f"positions alone of {fix_sigma:.2g} m: the log does not tell it"
            else:
                lag, lag_s = _offset_by_innovations(base, src)
            if lag is None and "imu_time_offset" in required:
                raise ScenarioError(f"calibrate: loosely_coupled.imu_time_offset: no minimum of the innovations within ±{MAX_LAG:g} s "
                                    "of the scenario's value (too few turns while moving); give the offset")
            if lag is not None:
                base = base.with_values({"loosely_coupled.imu_time_offset": f"{lag:.6f} s"}, create=True)
    cal = Calibration(None, None, None, None, None, None, lag, lag_s, rest)
    if offset_note:
        cal.imu_time_offset_note = offset_note
    if noise is not None:
        (cal.gyro_noise, cal.gyro_noise_sigma), (cal.accel_noise, cal.accel_noise_sigma), (cal.gyro_bias, cal.gyro_bias_sigma) = (
            noise["gyro_noise"], noise["accel_noise"], noise["gyro_bias"])
    if bore is not None:
        cal.boresight, cal.boresight_sigma, cal.straight, cal.yaw_parts = bore
    if axes is not None:
        cal.imu_axes, cal.imu_axes_fit = axes[0], (axes[1], axes[2])
    cal.asked = None if fields is None else tuple(sorted(asked))
    if fields is None:
        cal.gnss_sigma_scale = _sigma_scales(base, src)
    return cal


def _sigma_scales(sc: Any, src: Any) -> dict[str, tuple[float, float, float]]:
    """Per GNSS channel, the factor the filter finds on the receiver's σ from its innovations
    (``noise_scale``, estimated through the run): median and 10th-90th percentiles over the
    epochs once it is estimated."""
    rec = src.run([sc.to_json()])[0]
    out = {}
    for s_ in rec["subfilters"]:
        v = np.asarray(s_.get("noise_scale", []), float)
        v = v[np.isfinite(v)]
        if len(v):
            out[str(s_["sensor"])] = (float(np.median(v)), float(np.percentile(v, 10)), float(np.percentile(v, 90)))
    return out


def _calibrate_tight(sc: Any, fields: Sequence[str] | None) -> Calibration:
    """:func:`calibrate` for a tight scenario's ``[tight.strapdown]``: the IMU noise and gyro
    bias from the rest intervals, found with the receiver's Doppler speed (the RINEX solved by
    :func:`navfdi.gnss.gnss_solve` with the scenario's systems and mask); the white noise from
    first differences, which the slow motion of a hand at rest leaves out. The boresight and
    the time offset are the loosely coupled filter's (its constraint and innovations)."""
    from navfdi import logs
    from navfdi.gnss_logs import _solution_log

    noise_fields = {"imu.gyro_noise", "imu.accel_noise"}
    if fields is not None and set(fields) - noise_fields:
        raise ScenarioError(f"calibrate: [tight.strapdown] gets its IMU noise from the log; {sorted(set(fields) - noise_fields)} "
                            "are estimated for [loosely_coupled] scenarios only")
    data = logs.load_source(sc.raw["source"], logs.scenario_folder(sc))
    obs, solved = logs.solve_rinex_source(sc)
    sol = solved.solution
    pos = _solution_log(obs, sol[sol["status"] != "no_solution"])
    t0 = float(pos.t[0])
    # A handheld receiver is never still: intervals at rest by the Doppler speed with a hand's
    # motion (below 20 deg/s of spread), the noise from first differences.
    rest = _rest_intervals(sc.core["tight"]["strapdown"]["alignment"]["static_speed"], {**data, "gnss_log": pos, "t0": t0}, still_deg_s=20.0)
    if not rest:
        raise ScenarioError(f"calibrate: no rest interval of {MIN_REST:g} s in {Path(obs).name} (Doppler speed below the static speed); "
                            "the IMU noise needs the receiver at rest: give tight.strapdown.imu.gyro_noise and accel_noise (the datasheet's)")
    noise = _noise(data["imu_log"], t0, rest, differences=True)
    return Calibration(*noise["gyro_noise"], *noise["accel_noise"], *noise["gyro_bias"], None, None, rest, section="tight.strapdown")


def _rest_intervals(static_speed: float, data: dict[str, Any], still_deg_s: float = 2.0) -> list[tuple[float, float]]:
    """The GNSS rest intervals of at least :data:`MIN_REST` s (speed below ``static_speed``
    m/s or 2.5× the receiver's velocity σ) that a still gyro confirms (the spread of its rate
    below ``still_deg_s``).

    A log of positions only (fewer than half its velocities written) gives its speed from the
    positions differenced over 4 s (:func:`_position_speed`), bounded by 3.5× the σ that
    difference has from the fixes' σ (the larger of the σ they write and their own scatter),
    and each interval is trimmed to where the accelerometer is still (:func:`_still_accel`)."""
    imu, pos, t0 = data["imu_log"], data["gnss_log"], float(data["t0"])
    t = pos.t - t0
    ti = imu.t - t0
    speed = np.hypot(pos.vel[:, 0], pos.vel[:, 1])
    from_positions = not np.isfinite(speed).mean() > 0.5
    if from_positions:
        speed, sd_v = _position_speed(pos)
    else:
        sd_v = np.nan_to_num(np.nanmax(pos.sd_vel[:, :2], axis=1) if np.isfinite(pos.sd_vel).any() else np.zeros(len(t)), nan=0.0)
    # From positions the accelerometer's trim below tells a still car from a moving one; the
    # speed only has to rule out a steady cruise, above the noise of its differences.
    thr = np.maximum(static_speed, (3.5 if from_positions else 2.5) * sd_v)
    rest = []
    for a, b in _rest(t, np.nan_to_num(speed, nan=np.inf), thr):
        if from_positions:
            # Meter-level positions call a car pulling away (under 3.7 m/s at σ 3 m) still;
            # its accelerometer does not: the interval's longest run of still seconds.
            still = _still_accel(ti, imu.accel, a, b)
            if still is None:
                continue
            a, b = still
        m = (ti >= a) & (ti <= b)
        if m.sum() > 20 and np.degrees(np.std(np.linalg.norm(imu.gyro[m], axis=1))) < still_deg_s:
            rest.append((a, b))
    return rest


#: Largest change of a 1 s mean of the specific force (m/s², any axis) from the interval's
#: median one that a rest found from positions alone keeps (:func:`_still_accel`): 5 mg,
#: a tenth of a gentle pull-away's acceleration.
STILL_ACCEL = 0.05


def _still_accel(ti: np.ndarray, accel: np.ndarray, a: float, b: float) -> tuple[float, float] | None:
    """The longest run of whole seconds in ``[a, b]`` (s, on the IMU's times ``ti``) whose mean
    specific force ``accel`` (m/s²) is within :data:`STILL_ACCEL` of the seconds' median on
    every axis, less a second at each end (an acceleration sets in within one); None when
    shorter than :data:`MIN_REST`."""
    edges = np.arange(a, b + 1e-9, 1.0)
    if len(edges) < 2:
        return None
    idx = np.searchsorted(ti, edges)
    means = np.array([accel[i:j].mean(axis=0) if j > i else np.full(3, np.nan) for i, j in zip(idx[:-1], idx[1:])])
    ok = np.all(np.abs(means - np.nanmedian(means, axis=0)) <= STILL_ACCEL, axis=1)
    best, run, start = (0, 0), 0, 0
    for k, good in enumerate(ok):
        run, start = (run + 1, start) if good else (0, k + 1)
        if run > best[1] - best[0]:
            best = (start, start + run)
    # A second off each end: the acceleration sets in within one.
    lo, hi = best[0] + 1, best[1] - 1
    if hi - lo < MIN_REST:
        return None
    return float(edges[lo]), float(edges[hi])


def _fix_sigma(pos: Any) -> np.ndarray:
    """The horizontal σ (m) of each fix of the GNSS log ``pos``: the larger of the σ it writes
    (its larger horizontal component; 0 where not written) and the fixes' own scatter over the
    log (the median size of their third differences, a 2D Gaussian's 1.1774 σ, over √20;
    fixes that repeat the last left out)."""
    from navfdi.frames import _east_north_m

    e, n, repeated = _east_north_m(pos.lat, pos.lon)
    d3 = np.hypot(np.diff(e[~repeated], 3), np.diff(n[~repeated], 3))
    own = float(np.median(d3)) / 1.1774 / math.sqrt(20.0) if d3.size >= 10 else 0.0
    written = np.nanmax(pos.sd_pos[:, :2], axis=1) if np.isfinite(pos.sd_pos).any() else np.zeros(len(e))
    return np.maximum(np.nan_to_num(written, nan=0.0), own)


def _positions_alone_sigma(pos: Any) -> float:
    """The median horizontal σ (m) of the GNSS log ``pos``'s fixes (:func:`_fix_sigma`) when it
    has positions alone (fewer than half its velocities written); 0 with velocities. Above
    :data:`OFFSET_POSITIONS_SIGMA` the log does not tell the IMU time offset."""
    return float(np.median(_fix_sigma(pos))) if not np.isfinite(pos.vel[:, 0]).mean() > 0.5 else 0.0


def _position_speed(pos: Any, half: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal speed (m/s) at the fixes of the GNSS log ``pos`` from its positions
    differenced over ``half`` s either side (:func:`navfdi.frames._position_velocity`: no
    difference ends at a repeated fix), and its σ (m/s): √2 × the fixes' horizontal σ
    (:func:`_fix_sigma`) over the span."""
    from navfdi.frames import _position_velocity

    ve, vn = _position_velocity(pos.t, pos.lat, pos.lon, half)
    dt = float(np.median(np.diff(pos.t))) if len(pos.t) > 1 else 1.0
    span = 2.0 * max(1, int(round(half / dt))) * dt
    return np.hypot(ve, vn), math.sqrt(2.0) * _fix_sigma(pos) / span


def _noise(imu: Any, t0: float, rest: list[tuple[float, float]], differences: bool = False) -> dict[str, tuple[list[float], list[float]]]:
    """White noise densities (deg/s/√Hz, mg/√Hz) and gyro bias (deg/h) per axis from the rest
    intervals, each with its σ. ``differences``: the noise from the samples' first differences
    (σ = SD(Δx)/√2), which a slow motion (a hand holding the receiver) leaves out; else from
    the samples about their mean."""
    ti = imu.t - t0
    rate = 1.0 / float(np.median(np.diff(imu.t)))
    g_res, a_res, g_all = [], [], []
    for a, b in rest:
        m = (ti >= a) & (ti <= b)
        if differences:
            g_res.append(np.diff(imu.gyro[m], axis=0) / math.sqrt(2.0))
            a_res.append(np.diff(imu.accel[m], axis=0) / math.sqrt(2.0))
        else:
            g_res.append(imu.gyro[m] - imu.gyro[m].mean(axis=0))
            a_res.append(imu.accel[m] - imu.accel[m].mean(axis=0))
        g_all.append(imu.gyro[m])
    ga = np.vstack(g_all)
    n = len(ga)
    # Per interval, then the quietest: a stop with the driver moving or a door shut is not
    # the sensor's noise (the filter's process noise covers motion).
    gsd = np.degrees(np.median([g.std(axis=0) for g in g_res], axis=0)) / math.sqrt(rate)
    asd = np.median([x.std(axis=0) for x in a_res], axis=0) / 9.80665e-3 / math.sqrt(rate)
    bias = np.degrees(ga.mean(axis=0)) * 3600.0
    # σ of a standard deviation from n samples (white): σ/√(2n); of a mean: σ/√n.
    as_list = lambda v: [float(x) for x in v]  # noqa: E731
    return {"gyro_noise": (as_list(gsd), as_list(gsd / math.sqrt(2 * n))),
            "accel_noise": (as_list(asd), as_list(asd / math.sqrt(2 * n))),
            "gyro_bias": (as_list(bias), as_list(np.degrees(ga.std(axis=0)) * 3600.0 / math.sqrt(n)))}


def _boresight_from_drive(sc: Any, src: Any, data: dict[str, Any]) -> tuple[list[float], list[float], float, dict[str, tuple[float, float]]] | None:
    """The boresight (roll kept, pitch, yaw, deg), its σ (pitch, yaw, deg), the seconds used
    and the yaw with its σ from each way it is read: the direction of the GNSS-aided filter's
    velocity in the body frame, and the IMU's specific force in the log ``data``
    (:func:`_yaw_by_specific_force`), combined by their variances (see the module's
    description); None with less than :data:`MIN_STRAIGHT` s of driving."""
    raw = copy.deepcopy(dict(sc.raw))
    lc = raw["loosely_coupled"]
    lc.pop("nhc", None)
    lc.pop("zupt", None)
    from navfdi._lc_schema import _rot
    from navfdi.scenario import from_dict

    rec = src.run([from_dict(raw, source=sc.source).to_json()])[0]
    cols = {c: rec["nav"][:, j] for j, c in enumerate(rec["nav_columns"])}
    t = np.asarray(rec["t"], float)
    y = cols["yaw"]
    # The velocity in the body frame: v_b = C_b^nᵀ v_n with C_b^n = R_z(yaw) R_y(pitch) R_x(roll)
    # (north-east-down), the rotation of the mounting convention.
    v_n = np.column_stack([cols["vel_n"], cols["vel_e"], -cols["vel_u"]])
    c_bn = np.array([_rot(a, b, c) for a, b, c in zip(cols["roll"], cols["pitch"], y)]).reshape(-1, 3, 3)
    vf, vr, vdn = np.einsum("kji,kj->ik", c_bn, v_n)
    sig = np.asarray(rec["sigma"], float)
    s_yaw, s_level = sig[:, 2], np.hypot(sig[:, 0], sig[:, 1]) / math.sqrt(2.0)
    rate = np.full(len(t), np.inf)
    ok = np.isfinite(y)
    if ok.sum() > 2:  # NaN before the alignment
        rate[ok] = np.abs(np.gradient(np.unwrap(y[ok]), t[ok]))
    moving = np.isfinite(vf) & np.isfinite(s_yaw) & (vf >= MIN_SPEED) & (rate <= math.radians(3.0))
    if not moving.any():
        return None
    # After the heading has converged: its σ within twice its median at speed.
    settled = moving & (s_yaw <= 2.0 * float(np.median(s_yaw[moving])))
    first = t[np.argmax(settled)] if settled.any() else np.inf
    use = settled & (t >= first)
    dt = float(np.median(np.diff(t))) if len(t) > 1 else 1.0
    span = float(use.sum()) * dt
    if span < MIN_STRAIGHT:
        return None
    pitch = np.arctan2(-vdn[use], vf[use])
    yaw = np.arctan2(vr[use], vf[use])
    # The epochs' spread, taken as independent over 10 s, beside the filter's attitude σ.
    n_eff = max(1.0, span / 10.0)

    def est(a: np.ndarray, s: np.ndarray) -> tuple[float, float]:
        med = float(np.median(a))
        spread = 1.4826 * float(np.median(np.abs(a - med)))
        return math.degrees(med), math.degrees(math.hypot(float(np.median(s)), spread / math.sqrt(n_eff)))

    (pb, ps), (yb, ys) = est(pitch, s_level[use]), est(yaw, s_yaw[use])
    # The yaw again from the specific force in the body frame (independent of the heading),
    # the two combined by their variances.
    speed = np.hypot(cols["vel_n"], cols["vel_e"])
    lc_core = sc.core["loosely_coupled"]
    by_force = _yaw_by_specific_force(data, lc_core["mounting"], float(lc_core["imu_time_offset"]), t, speed)
    given = sc.raw["loosely_coupled"].get("boresight")
    roll0, pitch0, yaw0 = (math.degrees(v) for v in _given_boresight(given))
    parts = {"velocity direction": (yaw0 + yb, ys)}
    if by_force is not None:
        yf, yfs, _ = by_force
        parts["specific force"] = (yaw0 + yf, yfs)
        wv, wf = ys**-2, yfs**-2
        yb, ys = (wv * yb + wf * yf) / (wv + wf), (wv + wf) ** -0.5
    # Small angles: the residual boresight adds to the one the run had.
    return [roll0, pitch0 + pb, yaw0 + yb], [ps, ys], span, parts


#: Bins of the specific-force yaw (s), and the least number of them it needs.
FORCE_BIN = 1.0
FORCE_MIN_BINS = 30


def _yaw_by_specific_force(data: dict[str, Any], mount: Sequence[float], offset: float, t_run: np.ndarray, speed: np.ndarray) -> tuple[float, float, int] | None:
    """The yaw boresight left beyond the run's mounting (deg), its σ (deg) and the number of
    1 s bins used, from the direction of the specific force in the body frame: a car's
    horizontal acceleration is along its forward axis (dv/dt) plus the centripetal v·ω_z to
    its right, so in the IMU's body frame, rotated by a yaw boresight ψ, the right-axis force
    left after v·ω_z is tan ψ times the forward one. Over 1 s bins of the IMU at ≥
    :data:`MIN_SPEED` m/s turning below 3 deg/s, each run of consecutive bins about its own
    mean (road bank and roll out), the slope by least squares; its σ from the residuals,
    inflated for their lag-1 correlation. No heading enters: the filter's heading error
    (≈ 0.1° on a 10 deg/h IMU) does not reach it. None with fewer than
    :data:`FORCE_MIN_BINS` bins. ``mount`` the run's mounting (rad), ``offset`` its IMU time
    offset (s), ``t_run`` (s from the first GNSS epoch) and ``speed`` (m/s) the run's epochs."""
    from navfdi._lc_schema import _rot

    imu = data["imu_log"]
    m = _rot(*mount).T
    f = imu.accel @ m.T
    wz = imu.gyro @ m.T[:, 2]
    ti = imu.t - float(data["t0"]) + offset
    ok = np.isfinite(speed)
    if ok.sum() < 2 or len(ti) < 2:
        return None
    edges = np.arange(ti[0], ti[-1], FORCE_BIN)
    b = np.digitize(ti, edges) - 1
    n_bins = len(edges)
    cnt = np.bincount(b, minlength=n_bins)[:n_bins].astype(float)
    mean = lambda x: np.bincount(b, weights=x, minlength=n_bins)[:n_bins] / np.maximum(cnt, 1.0)  # noqa: E731
    ff, fr, w = mean(f[:, 0]), mean(f[:, 1]), mean(wz)
    v = np.interp(edges + 0.5 * FORCE_BIN, t_run[ok], speed[ok], left=np.nan, right=np.nan)
    rate = len(ti) / max(ti[-1] - ti[0], 1e-9)
    good = (cnt >= 0.5 * rate * FORCE_BIN) & (v >= MIN_SPEED) & (np.abs(w) <= math.radians(3.0))
    y_all = fr - v * w
    idx = np.flatnonzero(good)
    if len(idx) < FORCE_MIN_BINS:
        return None
    run = np.cumsum(np.r_[1, np.diff(idx) > 1])
    x, y, keep = ff[idx].copy(), y_all[idx].copy(), np.zeros(len(idx), bool)
    for r in np.unique(run):
        k = run == r
        if k.sum() >= 5:
            keep |= k
            x[k] -= x[k].mean()
            y[k] -= y[k].mean()
    x, y = x[keep], y[keep]
    sxx = float(np.sum(x * x))
    if len(x) < FORCE_MIN_BINS or sxx <= 0.0:
        return None
    slope = float(np.sum(x * y)) / sxx
    e = y - slope * x
    rho = float(np.clip(np.sum(e[1:] * e[:-1]) / max(float(np.sum(e * e)), 1e-300), 0.0, 0.95))
    se = math.sqrt(float(np.sum(e * e)) / (len(x) - 1) / sxx * (1 + rho) / (1 - rho))
    return math.degrees(math.atan(slope)), math.degrees(se), int(len(x))


def _given_boresight(v: Any) -> list[float]:
    """The scenario's ``boresight`` (rad), zeros when absent."""
    from navfdi._lc_schema import _axes

    return [0.0, 0.0, 0.0] if v is None else _axes(v, "angle", "loosely_coupled.boresight")


#: Most an epoch's normalised innovation squared counts per degree of freedom in the time
#: offset's misfit (:func:`_offset_by_innovations`; 3σ): beyond it the innovation is a fault's
#: (a multipath burst, a stale fix), the same at every offset tried. Counted up to 100, 15 m
#: bursts once a minute set the misfit: on three of four simulated urban logs no minimum was
#: found, and on the fourth one was, confidently wrong (−0.44 s, σ 0.01 s, for +0.19 s).
MISFIT_CAP = 9.0
#: Horizontal σ (m) of a log of positions only above which the time offset is not estimated
#: (:func:`calibrate`): on 23 simulated meter-level logs of positions only the innovations'
#: minimum was 0.16–0.56 s off in nine (eight with multipath bursts), its σ 0.01–0.04 s; on
#: ten RTK ones within 0.01 s.
OFFSET_POSITIONS_SIGMA = 0.5


def _misfit(rec: dict[str, Any]) -> tuple[float, float]:
    """A run's misfit to its measurements: the mean normalised innovation squared per degree
    of freedom over its GNSS and constraint updates, each epoch's capped at
    :data:`MISFIT_CAP` per degree of freedom; and the degrees of freedom counted."""
    num = den = 0.0
    for s in rec["subfilters"]:
        st, dof = np.asarray(s["statistic"], float), np.asarray(s["dof"], float)
        ok = np.isfinite(st) & (dof > 0)
        num += float(np.sum(np.minimum(st[ok], MISFIT_CAP * dof[ok])))
        den += float(np.sum(dof[ok]))
    return num / max(den, 1.0), den


def _offset_by_innovations(sc: Any, src: Any) -> tuple[float | None, float | None]:
    """The IMU time offset that makes the filter's GNSS and constraint innovations smallest
    (mean normalised innovation squared per degree of freedom, each epoch's capped at
    :data:`MISFIT_CAP`, fault-free, without FDE):
    a 0.05 s grid over ± :data:`MAX_LAG` s, refined by a
    parabola; its σ from the curvature of the misfit. Reference-free."""
    lags = np.arange(-MAX_LAG, MAX_LAG + 1e-9, 0.05)
    recs = src.run([sc.with_values({"loosely_coupled.imu_time_offset": f"{lag:.4f} s"}, create=True).to_json() for lag in lags])
    fits = [_misfit(rec) for rec in recs]
    m = np.array([f[0] for f in fits])
    den = fits[-1][1]
    k = int(np.argmin(m))
    if k in (0, len(lags) - 1):
        return None, None
    y0, y1, y2 = m[k - 1], m[k], m[k + 1]
    h = float(lags[1] - lags[0])
    den2 = y0 - 2 * y1 + y2
    best = float(lags[k]) + (0.5 * h * (y0 - y2) / den2 if den2 > 0 else 0.0)
    # The misfit's rise over its minimum, read as a χ² per degree of freedom: Δ = 1/N at 1σ.
    n_dof = max(den, 1.0)
    sigma = math.sqrt(2.0 * h * h / (den2 * n_dof)) if den2 > 0 else float("nan")
    return best, sigma


#: A scenario that gives no ``boresight`` has it estimated before the run where the log shows
#: its pitch or yaw beyond this (deg) and :data:`BORESIGHT_SHOWN_SIGMAS` σ
#: (:func:`boresight_shown`). Traced on simulated drives (nominal axes, the boresight taken as
#: 0): a 3° yaw on RTK fixes put the constraint against them and FDE left half of them out
#: (1.56 m RMS against 0.06 m without FDE); a 2° pitch on meter-level positions alone, 48 m
#: against 4.1 m. On 60 simulated logs with the true mounting the specific-force yaw read at
#: most 0.54°.
BORESIGHT_SHOWN_DEG = 1.0
#: See :data:`BORESIGHT_SHOWN_DEG`.
BORESIGHT_SHOWN_SIGMAS = 4.0
#: A read pitch or yaw beyond this (deg) is no boresight but axes named wrong (90° off, a
#: simulated log read 67°): not used, and the run's frame checks name the axes.
BORESIGHT_SHOWN_MAX = 10.0


def boresight_shown(sc: Any) -> Calibration | None:
    """For a loosely coupled scenario ``sc`` on recorded logs that names its IMU's axes
    (``imu_axes``) and gives no ``boresight`` (mounting angles are taken as measured): the
    boresight its log shows (:func:`calibrate` with ``boresight`` alone: one run of the filter
    with GNSS only) when its pitch or yaw is beyond :data:`BORESIGHT_SHOWN_DEG` and
    :data:`BORESIGHT_SHOWN_SIGMAS` σ (and within :data:`BORESIGHT_SHOWN_MAX`) and the filter
    with it fits the log better than with none (:func:`_misfit` of two runs without FDE), with
    ``boresight_note`` saying so; None otherwise (a boresight given, too little driving to read
    one, one within those bounds or beyond the largest, or one that does not fit better)."""
    lc = sc.raw.get("loosely_coupled")
    # Mounting angles are the user's measurement of the whole rotation, boresight included.
    if not isinstance(lc, dict) or "boresight" in lc or "mounting" in lc or "source" not in sc.raw or "loosely_coupled" not in sc.core:
        return None
    cal = _calibrate(sc, ["boresight"], optional=True)
    if cal.boresight is None or cal.boresight_sigma is None:
        return None
    shown = [(name, v, e) for name, v, e in zip(("pitch", "yaw"), cal.boresight[1:], cal.boresight_sigma)
             if abs(v) > max(BORESIGHT_SHOWN_DEG, BORESIGHT_SHOWN_SIGMAS * e)]
    if not shown or max(abs(v) for v in cal.boresight[1:]) > BORESIGHT_SHOWN_MAX:
        return None
    # The estimate must fit the log better than none (a biased read — the pitch from meter-level
    # positions alone on a poor gyro, 1.8° at 8σ on a simulated log with none — does not).
    from navfdi import logs

    base = _internal(sc)
    with_it = base.with_values({"loosely_coupled.boresight": cal.values()["loosely_coupled.boresight"]}, create=True)
    zero, est = logs.logged_source(base).run([base.to_json(), with_it.to_json()])
    if _misfit(est)[0] >= _misfit(zero)[0]:
        return None
    what = " and ".join(f"{name} {v:+.2f} ± {e:.2f} deg" for name, v, e in shown)
    cal.boresight_note = (f"the scenario gives no boresight and a first read of the log shows the IMU's {what} from the car: estimated "
                          "before the run (boresight = \"0 deg\" keeps none)")
    return cal


#: An IMU time offset a scenario does not give is used where its log's innovations show one
#: beyond this (s) and :data:`OFFSET_SHOWN_SIGMAS` σ (:func:`offset_shown`). Traced on
#: simulated drives with the offset taken as 0: RTK fixes, 0.1 s ran FDE at 0.35–0.50 m RMS
#: (0.045 m without FDE), 0.3 s at 2.2–2.5 m (0.11 m); σ 2 m fixes with velocities, 0.3 s at
#: 2.1–2.4 m (1.2–2.1 m).
OFFSET_SHOWN_S = 0.02
#: See :data:`OFFSET_SHOWN_S`.
OFFSET_SHOWN_SIGMAS = 4.0
#: The offsets (s) either side of the scenario's at which the misfit is read first: where it
#: is larger on both sides, the offset is within about half of this and the search is not run.
OFFSET_PROBE = 0.05


def offset_shown(sc: Any) -> tuple[float, float] | None:
    """For a loosely coupled scenario ``sc`` on recorded logs that gives no
    ``imu_time_offset``: the offset (s) and its σ (s) its log shows — the one that makes the
    filter's innovations smallest (the search of :func:`calibrate`) — where it is beyond
    :data:`OFFSET_SHOWN_S` and :data:`OFFSET_SHOWN_SIGMAS` σ; None otherwise, without a search
    where the misfit at 0 is below that at ± :data:`OFFSET_PROBE` s (three runs), and on
    meter-level positions alone (above :data:`OFFSET_POSITIONS_SIGMA`: the log does not tell
    it)."""
    lc = sc.raw.get("loosely_coupled")
    if not isinstance(lc, dict) or "imu_time_offset" in lc or "source" not in sc.raw or "loosely_coupled" not in sc.core:
        return None
    from navfdi import logs

    data = logs.load_source(sc.raw["source"], logs.scenario_folder(sc))
    pos = data.get("gnss_log")
    if pos is None or len(pos.t) < 3:
        return None
    if _positions_alone_sigma(pos) > OFFSET_POSITIONS_SIGMA:
        return None
    base = _internal(sc)
    src = logs.logged_source(base)
    probe = src.run([base.with_values({"loosely_coupled.imu_time_offset": f"{x:.4f} s"}, create=True).to_json()
                     for x in (-OFFSET_PROBE, 0.0, OFFSET_PROBE)])
    m = [_misfit(r)[0] for r in probe]
    if m[1] <= min(m[0], m[2]):
        return None
    lag, sigma = _offset_by_innovations(base, src)
    if lag is None or sigma is None or not math.isfinite(sigma) or abs(lag) <= max(OFFSET_SHOWN_S, OFFSET_SHOWN_SIGMAS * sigma):
        return None
    return lag, sigma


def resolve_auto(sc: Any) -> tuple[Any, Calibration | None]:
    """``sc`` with its ``"auto"`` ``[loosely_coupled]`` fields (:data:`navfdi._lc_schema.AUTO_FIELDS`)
    replaced by their estimates from the log (:func:`calibrate`) and the estimates; ``(sc,
    None)`` when it has none. A scenario that names its IMU's axes without a ``boresight``, or
    gives no ``imu_time_offset``, has them estimated too where its log shows them
    (:func:`boresight_shown`, :func:`offset_shown`); the calibration says so
    (``boresight_note``, ``offset_note``)."""
    from navfdi._lc_schema import auto_fields

    auto = auto_fields(sc.raw)
    # IMU axes read from the log: the mounting a boresight or an offset is read with is not
    # known yet (calibrate reads the axes first, then those asked).
    shown = boresight_shown(sc) if "imu_axes" not in auto else None
    with_bore = sc if shown is None else sc.with_values({"loosely_coupled.boresight": shown.values()["loosely_coupled.boresight"]}, create=True)
    lag = offset_shown(with_bore) if "imu_axes" not in auto else None
    lag_note = "" if lag is None else (f"the scenario gives no IMU time offset and a first read of the log's innovations shows {lag[0]:+.3f} ± {lag[1]:.3f} s: "
                                       "estimated before the run (imu_time_offset = \"0 s\" keeps none)")
    # Both shown: read again together (each biases the other: a 0.2 s offset read a 1.5° pitch 1.2°).
    if not auto and (shown is None) != (lag is None):
        cal = shown if shown is not None else Calibration(None, None, None, None, None, None, None, None, [])
        cal.asked = tuple(sorted([*(["boresight"] if shown is not None else []), *(["imu_time_offset"] if lag is not None else [])]))
        if lag is None:
            return with_bore, cal
        cal.imu_time_offset, cal.imu_time_offset_sigma, cal.offset_note = lag[0], lag[1], lag_note
        return with_bore.with_values({"loosely_coupled.imu_time_offset": f"{lag[0]:.6f} s"}, create=True), cal
    auto = [*auto, *(["boresight"] if shown is not None else []), *(["imu_time_offset"] if lag is not None else [])]
    if not auto:
        return sc, None
    cal = _calibrate(sc, auto, optional=True)  # the scenario's own "auto" fields stay required
    if shown is not None:
        cal.boresight_note = shown.boresight_note
    if lag is not None and cal.imu_time_offset is not None:
        cal.offset_note = lag_note
    vals = {k: v for k, v in cal.values().items() if k.split(".", 1)[1] in auto}
    return sc.with_values(vals, create=True), cal


def resolve_from_log(sc: Any) -> tuple[Any, Calibration | None]:
    """``sc`` with every value it asks to be estimated from its own log filled in — the
    ``"auto"`` fields of ``[loosely_coupled]`` (:func:`resolve_auto`) and ``[tight.integrity]
    range_errors = "overbound"`` (:func:`navfdi.logs.resolve_range_errors`) — and the
    calibration that filled the former (None without)."""
    from navfdi import logs

    out, cal = resolve_auto(sc)
    return logs.resolve_range_errors(out), cal


def write_calibrated(source_toml: str | Path, cal: Calibration, out: str | Path) -> Path:
    """Write a copy of the scenario file ``source_toml`` with the calibrated values set (the
    lines of ``gyro_noise``, ``accel_noise``, ``boresight``, ``imu_time_offset`` and
    ``imu_axes`` replaced or added, commented)."""
    text = Path(source_toml).read_text(encoding="utf-8")
    vals = cal.values()

    def put(text: str, key: str, value: Any, section: str) -> str:
        rendered = ("[" + ", ".join(f'"{x}"' for x in value) + "]") if isinstance(value, list) else f'"{value}"'
        line = f"{key} = {rendered}   # navfdi calibrate"
        pat = re.compile(rf"^{key}\s*=.*$", re.MULTILINE)
        if pat.search(text):
            return pat.sub(line, text, count=1)
        return re.sub(rf"^\[{re.escape(section)}\]\s*$", lambda m: m.group(0) + "\n" + line, text, count=1, flags=re.MULTILINE)

    sec = cal.section
    if f"{sec}.imu.gyro_noise" in vals:
        text = put(text, "gyro_noise", vals[f"{sec}.imu.gyro_noise"], f"{sec}.imu")
        text = put(text, "accel_noise", vals[f"{sec}.imu.accel_noise"], f"{sec}.imu")
    if "loosely_coupled.boresight" in vals:
        text = put(text, "boresight", vals["loosely_coupled.boresight"], "loosely_coupled")
    if "loosely_coupled.imu_time_offset" in vals:
        text = put(text, "imu_time_offset", vals["loosely_coupled.imu_time_offset"], "loosely_coupled")
    if "loosely_coupled.imu_axes" in vals:
        text = put(text, "imu_axes", vals["loosely_coupled.imu_axes"], "loosely_coupled")
    out = Path(out)
    out.write_text(text, encoding="utf-8")
    return out
