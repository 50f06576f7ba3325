"""Calibration from the log: what a loosely coupled scenario's IMU settings can be estimated
from its own files (``navfdi calibrate SCENARIO``).

* **Rest intervals**: GNSS epochs below the static speed (or 2.5× the receiver's velocity σ),
  at least :data:`MIN_REST` s long, confirmed by the IMU (the gyro's spread over the interval
  below 2 deg/s).
* **IMU white noise** per axis from the rest intervals (each interval's samples less their
  mean; the median over the intervals): density = σ / √rate, with its σ from the sample count; **gyro bias** as the mean rate
  at rest. A vibrating engine raises the noise above the datasheet's: that is the point, the
  filter needs the noise it will see.
* **IMU time offset**: the offset (± :data:`MAX_LAG` s) that makes the filter's own GNSS and
  constraint innovations smallest (their mean normalised square per degree of freedom,
  fault-free, without FDE), on a 0.05 s grid refined by a parabola; its σ from the
  curvature. Reference-free: no truth is used.

It does not (yet) estimate the boresight (pitch and yaw misalignment) or a GNSS σ scale; the
filter's own ``noise_scale`` estimates the latter during the run.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from navfdi._errors import ScenarioError

__all__ = ["Calibration", "calibrate", "MIN_REST", "MAX_LAG"]

#: Shortest rest interval used (s).
MIN_REST = 3.0
#: Largest IMU time offset searched (s).
MAX_LAG = 0.5


@dataclass
class Calibration:
    """What :func:`calibrate` estimated. Densities per IMU axis (x, y, z): ``gyro_noise``
    (deg/s/√Hz), ``accel_noise`` (mg/√Hz), each with ``…_sigma`` (same unit); ``gyro_bias``
    (deg/h, per axis) with its σ; ``imu_time_offset`` (s) with its σ (None when the log has too
    few turns); ``rest`` the rest intervals used ((start, end), s from the first GNSS epoch)."""

    gyro_noise: list[float]
    gyro_noise_sigma: list[float]
    accel_noise: list[float]
    accel_noise_sigma: list[float]
    gyro_bias: list[float]
    gyro_bias_sigma: list[float]
    imu_time_offset: float | None
    imu_time_offset_sigma: float | None
    rest: list[tuple[float, float]] = field(default_factory=list)

    def lines(self) -> list[str]:
        """The console report: each value with its σ."""
        f3 = lambda v, s, u: ", ".join(f"{a:.4g} ± {b:.2g}" for a, b in zip(v, s)) + f" {u}"  # noqa: E731
        out = [f"rest intervals: {len(self.rest)} ({sum(b - a for a, b in self.rest):.1f} s): "
               + ", ".join(f"{a:.1f}–{b:.1f} s" for a, b in self.rest[:6]) + (" …" if len(self.rest) > 6 else ""),
               f"gyro white noise (x, y, z): {f3(self.gyro_noise, self.gyro_noise_sigma, 'deg/s/sqrt(Hz)')}",
               f"accel white noise (x, y, z): {f3(self.accel_noise, self.accel_noise_sigma, 'mg/sqrt(Hz)')}",
               f"gyro bias at rest (x, y, z): {f3(self.gyro_bias, self.gyro_bias_sigma, 'deg/h')}"]
        if self.imu_time_offset is None:
            out.append("IMU time offset: not estimated (too few turns while moving)")
        else:
            out.append(f"IMU time offset: {self.imu_time_offset:+.3f} ± {self.imu_time_offset_sigma:.3f} s")
        return out

    def values(self) -> dict[str, Any]:
        """The scenario values it sets: ``{path: value with unit}``."""
        v: dict[str, Any] = {
            "loosely_coupled.imu.gyro_noise": [f"{x:.4g} deg/s/sqrt(Hz)" for x in self.gyro_noise],
            "loosely_coupled.imu.accel_noise": [f"{x:.4g} mg/sqrt(Hz)" for x in self.accel_noise],
        }
        if self.imu_time_offset is not None:
            v["loosely_coupled.imu_time_offset"] = f"{self.imu_time_offset:.3f} s"
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


def calibrate(scenario: Any) -> Calibration:
    """Estimate a loosely coupled scenario's IMU noise, gyro bias and IMU time offset from its
    own logs (see the module's description). Raises :class:`ScenarioError` when the log has no
    rest interval of :data:`MIN_REST` s."""
    from navfdi import logs
    from navfdi.scenario import load_scenario

    sc = scenario if hasattr(scenario, "core") else load_scenario(scenario)
    if "loosely_coupled" not in sc.core:
        raise ScenarioError("calibrate: a loosely coupled scenario on recorded logs is needed")
    data = logs.load_source(sc.raw["source"], logs.scenario_folder(sc))
    imu, pos, t0 = data["imu_log"], data["gnss_log"], float(data["t0"])
    lc = sc.core["loosely_coupled"]
    t = pos.t - t0
    ti = imu.t - t0
    speed = np.hypot(pos.vel[:, 0], pos.vel[:, 1])
    sd_v = np.nan_to_num(np.nanmax(pos.sd_vel[:, :2], axis=1) if np.isfinite(pos.sd_vel).any() else np.zeros(len(t)), nan=0.0)
    thr = np.maximum(lc["alignment"]["static_speed"], 2.5 * sd_v)
    rest = []
    for a, b in _rest(t, np.nan_to_num(speed, nan=np.inf), thr):
        m = (ti >= a) & (ti <= b)
        if m.sum() > 20 and np.degrees(np.std(np.linalg.norm(imu.gyro[m], axis=1))) < 2.0:
            rest.append((a, b))
    if not rest:
        raise ScenarioError(f"calibrate: no rest interval of {MIN_REST:g} s in the GNSS log (speed below the static speed); "
                            "the noise needs the vehicle at rest")
    rate = 1.0 / float(np.median(np.diff(imu.t)))
    g_res, a_res, g_all = [], [], []
    for a, b in rest:
        m = (ti >= a) & (ti <= b)
        g_res.append(imu.gyro[m] - imu.gyro[m].mean(axis=0))
        a_res.append(imu.accel[m] - imu.accel[m].mean(axis=0))
        g_all.append(imu.gyro[m])
    gr, ar, ga = np.vstack(g_res), np.vstack(a_res), np.vstack(g_all)
    n = len(gr)
    # Per interval, then the quietest: a stop with the driver moving or a door shut is not
    # the sensor's noise (the filter's process noise covers motion).
    gsd = np.degrees(np.median([g.std(axis=0) for g in g_res], axis=0)) / math.sqrt(rate)
    asd = np.median([x.std(axis=0) for x in a_res], axis=0) / 9.80665e-3 / math.sqrt(rate)
    bias = np.degrees(ga.mean(axis=0)) * 3600.0
    # σ of a standard deviation from n samples (white): σ/√(2n); of a mean: σ/√n.
    gsd_s, asd_s = gsd / math.sqrt(2 * n), asd / math.sqrt(2 * n)
    bias_s = np.degrees(ga.std(axis=0)) * 3600.0 / math.sqrt(n)
    noise = {"loosely_coupled.imu.gyro_noise": [f"{x:.6g} deg/s/sqrt(Hz)" for x in gsd],
             "loosely_coupled.imu.accel_noise": [f"{x:.6g} mg/sqrt(Hz)" for x in asd]}
    lag, lag_s = _offset_by_innovations(sc.with_values(noise))
    return Calibration(list(map(float, gsd)), list(map(float, gsd_s)), list(map(float, asd)), list(map(float, asd_s)),
                       list(map(float, bias)), list(map(float, bias_s)), lag, lag_s, rest)


def _offset_by_innovations(sc: Any) -> tuple[float | None, float | None]:
    """The IMU time offset that makes the filter's GNSS and constraint innovations smallest
    (mean normalised innovation squared per degree of freedom, fault-free, without FDE):
    a 0.05 s grid over ± :data:`MAX_LAG` s around the scenario's value, refined by a
    parabola; its σ from the curvature of the misfit. Reference-free."""
    from navfdi.runs import ScenarioRun, run_scenario

    raw = dict(sc.raw)
    raw.pop("faults", None)
    raw.pop("variants", None)
    raw["loosely_coupled"] = {**raw["loosely_coupled"], "isolate": False}
    from navfdi.scenario import from_dict

    base = from_dict(raw, source=sc.source)
    lags = np.arange(-MAX_LAG, MAX_LAG + 1e-9, 0.05)
    misfit = []
    for lag in lags:
        run = run_scenario(base.with_values({"loosely_coupled.imu_time_offset": f"{lag:.4f} s"}), compare_isolation=False)
        assert isinstance(run, ScenarioRun)  # no variants: one run
        num = den = 0.0
        for s in run.record["subfilters"]:
            st, dof = np.asarray(s["statistic"], float), np.asarray(s["dof"], float)
            ok = np.isfinite(st) & (dof > 0)
            num += float(np.sum(np.minimum(st[ok], 100.0 * dof[ok])))
            den += float(np.sum(dof[ok]))
        misfit.append(num / max(den, 1.0))
    m = np.array(misfit)
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


def write_calibrated(source_toml: str | Path, cal: Calibration, out: str | Path) -> Path:
    """Write a copy of the scenario file ``source_toml`` with the calibrated values set (the
    lines of ``gyro_noise``, ``accel_noise`` and ``imu_time_offset`` replaced, commented)."""
    text = Path(source_toml).read_text(encoding="utf-8")
    vals = cal.values()

    def put(text: str, key: str, value: Any, section: str) -> str:
        rendered = ("[" + ", ".join(f'"{x}"' for x in value) + "]") if isinstance(value, list) else f'"{value}"'
        line = f"{key} = {rendered}   # navfdi calibrate"
        pat = re.compile(rf"^{key}\s*=.*$", re.MULTILINE)
        if pat.search(text):
            return pat.sub(line, text, count=1)
        return re.sub(rf"^\[{re.escape(section)}\]\s*$", lambda m: m.group(0) + "\n" + line, text, count=1, flags=re.MULTILINE)

    text = put(text, "gyro_noise", vals["loosely_coupled.imu.gyro_noise"], "loosely_coupled.imu")
    text = put(text, "accel_noise", vals["loosely_coupled.imu.accel_noise"], "loosely_coupled.imu")
    if "loosely_coupled.imu_time_offset" in vals:
        text = put(text, "imu_time_offset", vals["loosely_coupled.imu_time_offset"], "loosely_coupled")
    out = Path(out)
    out.write_text(text, encoding="utf-8")
    return out
