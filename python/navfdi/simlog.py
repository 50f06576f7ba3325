"""Simulated recorded logs: an IMU CSV, a receiver's GNSS solution (``.pos``), the truth as a
reference ``.pos`` and a ready loosely coupled scenario, written to a folder — the same files a
user brings, with every error known. Used to measure FDE and calibration where the truth is
known (``navfdi_core::sim::logs``).

The GNSS errors are what a receiver's own single-point fix has: a first-order Gauss-Markov
error per axis (``gnss_sigma`` m, correlation time ``gnss_tau`` s), white noise, multipath
bursts (an offset held for seconds) and stale fixes (the last fix repeated while moving). The
IMU can be mounted in any orientation (its axes named as in a scenario's ``imu_axes``), with a
boresight error (roll, pitch, yaw, deg) and a time-stamp lag (s).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from navfdi import _core
from navfdi._lc_schema import axes_mounting, true_mounting

__all__ = ["SimulatedLog", "simulate_log", "CAR_DRIVE"]

#: A 10-minute car drive (ground vehicle: turns do not bank): 30 s at rest, then streets with
#: turns both ways, a stop, and faster stretches.
CAR_DRIVE: dict[str, Any] = {
    "latitude": "40.1 deg", "longitude": "-105.15 deg", "height": "1600 m", "heading": "30 deg", "speed": "0 m/s",
    "segments": [
        {"kind": "stationary", "duration": "30 s"},
        {"kind": "accelerate", "duration": "8 s", "acceleration": "1.5 m/s2"},
        {"kind": "level", "duration": "40 s"},
        {"kind": "turn", "duration": "15 s", "rate": "6 deg/s"},
        {"kind": "level", "duration": "60 s"},
        {"kind": "turn", "duration": "10 s", "rate": "-9 deg/s"},
        {"kind": "accelerate", "duration": "6 s", "acceleration": "1 m/s2"},
        {"kind": "level", "duration": "70 s"},
        {"kind": "turn", "duration": "30 s", "rate": "3 deg/s"},
        {"kind": "accelerate", "duration": "10 s", "acceleration": "-1.8 m/s2"},
        {"kind": "stationary", "duration": "20 s"},
        {"kind": "accelerate", "duration": "10 s", "acceleration": "1.5 m/s2"},
        {"kind": "level", "duration": "50 s"},
        {"kind": "turn", "duration": "20 s", "rate": "-4.5 deg/s"},
        {"kind": "level", "duration": "90 s"},
        {"kind": "turn", "duration": "12 s", "rate": "7.5 deg/s"},
        {"kind": "level", "duration": "120 s"},
    ],
}

#: GPS week and seconds of week of the simulated logs' time 0.
START = (2374, 240_000.0)

@dataclass(frozen=True)
class SimulatedLog:
    """The files :func:`simulate_log` wrote and what it knows: ``folder``, ``imu`` (CSV),
    ``gnss`` and ``reference`` (``.pos``), ``scenario`` (TOML), ``truth`` (the GNSS errors per
    epoch: ``time`` s from the first epoch, ``error_e/n/u`` m, ``stale``, ``burst``, CSV) and
    ``settings`` (every simulated value, SI)."""

    folder: Path
    imu: Path
    gnss: Path
    reference: Path
    scenario: Path
    truth: Path
    settings: dict[str, Any]


def _pos_lines(table: np.ndarray, q: int, velocity: bool = True) -> list[str]:
    """RTKLIB ``.pos`` lines of a solution table; without ``velocity`` the velocity columns
    are left out, as ``rnx2rtkp`` writes by default."""
    week, sow0 = START
    head = "%  GPST                  latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)  sdne(m)  sdeu(m)  sdun(m) age(s)  ratio"
    out = ["% program   : navfdi simulate_log",
           head + ("  vn(m/s)  ve(m/s)  vu(m/s)  sdvn  sdve  sdvu  sdvne  sdveu  sdvun" if velocity else "")]
    for r in table:
        t, lat, lon, h, ve, vn, vu, se, sn, su, sve, svn, svu = r
        line = f"{week} {sow0 + t:.3f} {math.degrees(lat):.9f} {math.degrees(lon):.9f} {h:.4f} {q} 9 {sn:.4f} {se:.4f} {su:.4f} 0 0 0 0 0"
        if velocity:
            line += f" {vn:.5f} {ve:.5f} {vu:.5f} {svn:.5f} {sve:.5f} {svu:.5f} 0 0 0"
        out.append(line)
    return out


def simulate_log(
    out: str | Path,
    *,
    duration: float = 600.0,
    seed: int = 0,
    run: int = 0,
    trajectory: Mapping[str, Any] | None = None,
    imu_axes: Sequence[str] = ("forward", "right", "down"),
    boresight_deg: Sequence[float] = (0.0, 0.0, 0.0),
    time_lag: float = 0.0,
    lever_arm: Sequence[float] = (0.0, 0.0, 0.0),
    imu_rate: float = 100.0,
    gyro_noise: float = 0.01,
    accel_noise: float = 0.1,
    gyro_bias: float = 10.0,
    accel_bias: float = 1.0,
    gnss_rate: float = 4.0,
    gnss_sigma: float = 0.5,
    gnss_tau: float = 0.0,
    gnss_white: float = 0.0,
    gnss_velocity_sigma: float = 0.05,
    gnss_velocity: bool = True,
    reported_sigma: float | None = None,
    burst_rate: float = 0.0,
    burst_size: float = 0.0,
    burst_duration: float = 0.0,
    stale_rate: float = 0.0,
    stale_duration: float = 0.0,
    scenario_mounting: str = "true",
) -> SimulatedLog:
    """Simulate a car drive's logs into folder ``out`` (created) and write a ready loosely
    coupled scenario beside them.

    Parameters
    ----------
    out : path
        Folder for ``imu.csv``, ``gnss.pos``, ``reference.pos``, ``truth.csv``,
        ``scenario.toml``.
    duration : float
        Seconds of logs (≤ 86 400).
    seed, run : int
        The random stream ``(seed, run)``.
    trajectory : mapping, optional
        A ``[trajectory]`` table with units (segments); default :data:`CAR_DRIVE`. A ground
        vehicle: turns do not bank.
    imu_axes : three str
        Where the IMU's x, y, z axes point in the vehicle (forward, back, right, left, down,
        up).
    boresight_deg : three float
        The IMU's misalignment beyond its nominal axes: roll, pitch, yaw (deg).
    time_lag : float
        Seconds the IMU's time stamps lag the truth (the scenario's ``imu_time_offset`` that
        undoes it is ``+time_lag``).
    lever_arm : three float
        The GNSS antenna from the IMU in the vehicle's forward-right-down frame (m): the fixes
        and their velocities are the antenna's, and so is the reference's position (the
        filters record the antenna's), its velocity the IMU's. The scenario gets it as
        ``lever_arm`` (as a tape measure gives it).
    imu_rate : float
        IMU samples per second.
    gyro_noise, accel_noise : float
        White noise densities, deg/s/√Hz and mg/√Hz (per axis).
    gyro_bias, accel_bias : float
        σ of the constant biases drawn per run, deg/h and mg.
    gnss_rate : float
        GNSS solutions per second (the scenario's sensors take 1 Hz of them; the other epochs
        are the reference's scored epochs).
    gnss_sigma, gnss_tau, gnss_white : float
        Gauss-Markov position error σ (m per axis) and correlation time (s; 0 white), and
        white noise σ (m).
    gnss_velocity_sigma : float
        Velocity noise σ (m/s per axis).
    gnss_velocity : bool
        The receiver writes velocities; False: ``gnss.pos`` has positions only (as
        ``rnx2rtkp`` writes by default) and the scenario a ``gnss_position`` sensor only.
    reported_sigma : float, optional
        The position σ the receiver writes (default: the true total σ).
    burst_rate, burst_size, burst_duration : float
        Multipath bursts per second, their horizontal σ per axis (m) and duration (s).
    stale_rate, stale_duration : float
        Stale spells per second while moving and their duration (s).
    scenario_mounting : ``"true"`` or ``"nominal"``
        The scenario gets the IMU's true mounting (axes and boresight), or only its axis names
        (``imu_axes``: what a user knows before calibrating).

    Returns
    -------
    SimulatedLog
    """
    from navfdi.scenario import convert_trajectory

    if scenario_mounting not in ("true", "nominal"):
        raise ValueError(f"scenario_mounting = {scenario_mounting!r}: 'true' or 'nominal'")
    tr = convert_trajectory(trajectory or CAR_DRIVE, float(duration))
    mount = true_mounting(imu_axes, boresight_deg)
    g = 9.80665
    noise = {
        "imu_rate": float(imu_rate), "gyro_noise": math.radians(gyro_noise), "accel_noise": accel_noise * 1e-3 * g,
        "gyro_bias": math.radians(gyro_bias / 3600.0), "accel_bias": accel_bias * 1e-3 * g,
        "gnss_dt": 1.0 / gnss_rate, "gnss_pos": float(gnss_sigma), "gnss_vel": float(gnss_velocity_sigma),
        "gnss_tau": float(gnss_tau), "gnss_white": float(gnss_white), "burst_rate": float(burst_rate),
        "burst_size": float(burst_size), "burst_duration": float(burst_duration), "stale_rate": float(stale_rate),
        "stale_duration": float(stale_duration), "reported_pos": float(reported_sigma or 0.0),
        "mounting": list(mount), "time_lag": float(time_lag), "ground": True, "lever_arm": [float(v) for v in lever_arm],
    }
    sim = _core.simulate_logs(json.dumps(tr), float(duration), noise, int(seed), int(run))
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    week, sow0 = START
    imu = sim["imu"]
    paths = {k: folder / n for k, n in (("imu", "imu.csv"), ("gnss", "gnss.pos"), ("reference", "reference.pos"), ("truth", "truth.csv"), ("scenario", "scenario.toml"))}
    deg = math.degrees(1.0)
    with open(paths["imu"], "w", encoding="utf-8") as f:
        f.write("gps_week,gps_sow_s,gyro_x_dps,gyro_y_dps,gyro_z_dps,acc_x_mps2,acc_y_mps2,acc_z_mps2\n")
        rows = np.column_stack([np.full(len(imu), week), sow0 + imu[:, 0], imu[:, 1:4] * deg, imu[:, 4:7]])
        np.savetxt(f, rows, fmt=["%d", "%.6f", "%.7f", "%.7f", "%.7f", "%.6f", "%.6f", "%.6f"], delimiter=",")
    paths["gnss"].write_text("\n".join(_pos_lines(sim["gnss"], 5, gnss_velocity)) + "\n", encoding="utf-8")
    paths["reference"].write_text("\n".join(_pos_lines(sim["reference"], 1)) + "\n", encoding="utf-8")
    err = sim["gnss_error"]
    with open(paths["truth"], "w", encoding="utf-8") as f:
        f.write("time,error_e,error_n,error_u,stale,burst\n")
        for k in range(len(err)):
            f.write(f"{sim['gnss'][k, 0]:.3f},{err[k, 0]:.4f},{err[k, 1]:.4f},{err[k, 2]:.4f},{int(sim['stale'][k])},{int(sim['burst'][k])}\n")
    span = float(sim["gnss"][-1, 0] - sim["gnss"][0, 0])
    settings = {**noise, "duration": float(duration), "seed": int(seed), "run": int(run), "imu_axes": list(imu_axes),
                "boresight_deg": list(map(float, boresight_deg)), "mounting_deg": [math.degrees(a) for a in mount]}
    if scenario_mounting == "true":
        mline = "mounting = [" + ", ".join(f'"{math.degrees(a):.6f} deg"' for a in mount) + "]"
    else:
        mline = "imu_axes = [" + ", ".join(f'"{a}"' for a in imu_axes) + "]"
    reported = reported_sigma or math.hypot(gnss_sigma, gnss_white)
    vel_sensor = vel_channel = ""
    if gnss_velocity:
        vel_sensor = f"""[[sensors]]
name = "gnss_vel"
kind = "gnss_velocity"
noise = "{gnss_velocity_sigma:g} m/s"
rate = "1 Hz"
"""
        vel_channel = """[[loosely_coupled.sensors]]
sensor = "gnss_vel"
detectors = [{ name = "chi2", kind = "chi2", pf = 1e-4 }, { name = "exclude", kind = "chi2", pf = 1e-7 }]
decision = "exclude"
"""
    paths["scenario"].write_text(f"""# Simulated car drive (navfdi.simulate_log, seed {seed}, run {run}); truth.csv has the GNSS errors.
name = "simulated_drive"
description = "Loosely coupled INS/GNSS on simulated logs"
architecture = "loosely_coupled"
duration = "{span:g} s"
dt = "{1.0 / gnss_rate:g} s"

[source]
gnss = "gnss.pos"
reference = "reference.pos"

[source.imu]
file = "imu.csv"
week = "gps_week"
seconds = "gps_sow_s"
gyro = ["gyro_x_dps", "gyro_y_dps", "gyro_z_dps"]
accel = ["acc_x_mps2", "acc_y_mps2", "acc_z_mps2"]
gyro_unit = "deg/s"
accel_unit = "m/s^2"

[[sensors]]
name = "gnss_pos"
kind = "gnss_position"
noise = "{reported:g} m"
rate = "1 Hz"

{vel_sensor}
[loosely_coupled]
{mline}
lever_arm = [{", ".join(f'"{float(v):g} m"' for v in lever_arm)}]
imu_time_offset = "{time_lag if scenario_mounting == 'true' else 0.0:g} s"

[loosely_coupled.imu]
gyro_noise = "{max(gyro_noise, 1e-6):g} deg/s/sqrt(Hz)"
accel_noise = "{max(accel_noise, 1e-6):g} mg/sqrt(Hz)"
gyro_bias = "{max(gyro_bias, 1e-3) / 3600.0:g} deg/s"
accel_bias = "{max(accel_bias, 1e-3) * 1e-3 * g:g} m/s2"
bias_tau = "3600 s"

[loosely_coupled.alignment]
speed = "2 m/s"
sigma_level = "1 deg"
sigma_heading = "5 deg"
sigma_position = "{max(reported, 0.1):g} m"
sigma_velocity = "0.2 m/s"

[[loosely_coupled.sensors]]
sensor = "gnss_pos"
detectors = [{{ name = "chi2", kind = "chi2", pf = 1e-4 }}, {{ name = "exclude", kind = "chi2", pf = 1e-5 }}]
decision = "exclude"

{vel_channel}
[loosely_coupled.nhc]
noise = "0.1 m/s"
threshold = "1 m/s"
rate_threshold = "30 deg/s"
detectors = [{{ name = "chi2", kind = "chi2", pf = 1e-4 }}]

[[variants]]
name = "fde"

[[variants]]
name = "no_fde"
set = {{ "loosely_coupled.isolate" = false }}
""", encoding="utf-8")
    return SimulatedLog(folder, paths["imu"], paths["gnss"], paths["reference"], paths["scenario"], paths["truth"], settings)
