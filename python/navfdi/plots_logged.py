"""Figures of a run on recorded logs (``loosely_coupled``, or ``tight`` with a strapdown INS):
the track, the errors against the reference with the filter's ±3σ, and the estimated IMU
biases."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from navfdi.record import RunRecord

_R = 6_378_137.0


def windows(run: RunRecord) -> tuple[list[tuple[float, float]], list[tuple[float, float, str]]]:
    """The run's outage windows ``(start, end)`` (s, any sensor, merged duplicates) and fault
    windows ``(start, end, id)``."""
    outs: list[tuple[float, float]] = []
    for s in run.scenario.core["sensors"]:
        for a, b in s.get("outages", []):
            if (a, b) not in outs:
                outs.append((a, b))
    return outs, [(f["start"], f["end"], f["id"]) for f in run.scenario.faults()]


def _shade(ax: Any, run: RunRecord) -> None:
    outs, faults = windows(run)
    for a, b in outs:
        ax.axvspan(a, b, color="tab:gray", alpha=0.15, lw=0)
    for a, b, _ in faults:
        ax.axvspan(a, b, color="tab:red", alpha=0.12, lw=0)


def _legend_patches(ax: Any, run: RunRecord) -> None:
    outs, faults = windows(run)
    if outs:
        ax.axvspan(np.nan, np.nan, color="tab:gray", alpha=0.15, lw=0, label="GNSS outage")
    if faults:
        ax.axvspan(np.nan, np.nan, color="tab:red", alpha=0.12, lw=0, label="fault window")


def plot_logged(run: RunRecord, out: Path, prefix: str = "") -> list[Path]:
    """Write ``{prefix}track.png`` (east/north of the GNSS antenna from the first epoch, m;
    the reference's scored epochs grey, shifted by the run's mean offset when the error is
    mostly that offset; outages and fault windows highlighted),
    ``{prefix}errors.png`` (east, north, up error against the reference at the epochs it
    scores, m, with the filter's ±3σ; outages grey, faults red), ``{prefix}biases.png``
    (estimated gyro biases in deg/h and accelerometer biases in mg with ±1σ) and
    ``{prefix}attitude.png`` (roll, pitch, heading in degrees; the course of the velocity
    beside the heading above 2 m/s). Returns the paths written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rec = run.record
    nav, cols = rec["nav"], list(rec["nav_columns"])
    t = run.t
    lat, lon = nav[:, cols.index("lat")], nav[:, cols.index("lon")]
    ok = np.isfinite(lat)
    i0 = int(np.argmax(ok))
    east = (lon - lon[i0]) * _R * np.cos(lat[i0])
    north = (lat - lat[i0]) * _R
    err = rec["error"]
    sig = rec["sigma"]
    var = f", variant {run.variant}" if prefix else ""
    paths: list[Path] = []

    fig, ax = plt.subplots(figsize=(7.5, 7), constrained_layout=True)
    scored = np.isfinite(err[:, 6])
    # A reference with a steady offset of its own (walk_tc's base) is drawn shifted by the
    # run's mean offset, said in the legend, so that the tracks can be compared.
    off = run.reference_offset()
    shift = (float(off[0]), float(off[1])) if run.steady_offset() else (0.0, 0.0)
    label = "reference (scored epochs)" if shift == (0.0, 0.0) else f"reference + the run's mean offset ({shift[0]:.1f} m E, {shift[1]:.1f} m N)"
    ax.plot(east - err[:, 6] + shift[0], north - err[:, 7] + shift[1], ".", ms=2, color="tab:gray", label=label)
    ax.plot(east, north, lw=0.9, color="tab:blue", label="navfdi (GNSS antenna)")
    outs, faults = windows(run)
    for j, (a, b) in enumerate(outs):
        m = (t >= a) & (t < b) & ok
        ax.plot(east[m], north[m], lw=2.0, color="tab:orange", label="during GNSS outages" if j == 0 else None)
    for j, (a, b, fid) in enumerate(faults):
        m = (t >= a) & (t < b) & ok
        ax.plot(east[m], north[m], lw=2.0, color="tab:red", label="during faults" if j == 0 else None)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"{run.scenario.name}{var}: track from the first navigation epoch ({int(scored.sum())} scored epochs)", fontsize=10)
    paths.append(out / f"{prefix}track.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)

    fig, axes = plt.subplots(3, 1, figsize=(9, 7.5), sharex=True, constrained_layout=True)
    for ax, (j, name) in zip(axes, [(6, "east"), (7, "north"), (8, "up")]):
        _shade(ax, run)
        ax.fill_between(t, -3 * sig[:, j], 3 * sig[:, j], color="tab:blue", alpha=0.15, lw=0, label="±3σ (filter)")
        ax.plot(t[scored], err[scored, j], ".", ms=2, color="tab:blue", label="error at scored epochs")
        ax.set_ylabel(f"{name} error [m]")
        ax.grid(alpha=0.3)
    _legend_patches(axes[0], run)
    axes[0].legend(fontsize=8, ncol=4, loc="upper left")
    axes[0].set_title(f"{run.scenario.name}{var}: position error against the reference (epochs {run.scored_label()})", fontsize=10)
    axes[-1].set_xlabel("time [s]")
    paths.append(out / f"{prefix}errors.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)

    fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True, constrained_layout=True)
    for ax, (what, scale, unit) in zip(axes, [("gyro", np.degrees(1.0) * 3600, "deg/h"), ("accel", 1e3 / 9.80665, "mg")]):
        _shade(ax, run)
        for axis in "xyz":
            v = nav[:, cols.index(f"{what}_bias_{axis}")] * scale
            s = nav[:, cols.index(f"{what}_bias_{axis}_sigma")] * scale
            line = ax.plot(t, v, lw=0.9, label=f"{axis}")
            ax.fill_between(t, v - s, v + s, color=line[0].get_color(), alpha=0.12, lw=0)
        ax.set_ylabel(f"{what} bias [{unit}]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=3, loc="upper left")
    axes[0].set_title(f"{run.scenario.name}{var}: estimated IMU biases (body axes) with ±1σ", fontsize=10)
    axes[-1].set_xlabel("time [s]")
    paths.append(out / f"{prefix}biases.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)

    # Attitude: roll, pitch, heading, and the course of the velocity (which follows the GNSS
    # velocity) where the speed is above 2 m/s: a car's heading follows its course.
    fig, axes = plt.subplots(3, 1, figsize=(9, 7), sharex=True, constrained_layout=True)
    deg = np.degrees
    for ax, c in zip(axes[:2], ("roll", "pitch")):
        _shade(ax, run)
        ax.plot(t, deg(nav[:, cols.index(c)]), lw=0.9, color="tab:blue", label=c)
        ax.set_ylabel(f"{c} [deg]")
        ax.grid(alpha=0.3)
    _shade(axes[2], run)
    ve, vn = nav[:, cols.index("vel_e")], nav[:, cols.index("vel_n")]
    fast = np.hypot(ve, vn) > 2.0
    axes[2].plot(t, deg(nav[:, cols.index("yaw")]) % 360, ".", ms=1.5, color="tab:blue", label="heading")
    axes[2].plot(t[fast], deg(np.arctan2(ve[fast], vn[fast])) % 360, ".", ms=1.5, color="tab:orange", label="course of the velocity (> 2 m/s)")
    axes[2].set_ylabel("heading [deg]")
    axes[2].set_ylim(0, 360)
    axes[2].grid(alpha=0.3)
    axes[2].legend(fontsize=8, loc="upper left", markerscale=6)
    axes[0].set_title(f"{run.scenario.name}{var}: attitude of the body frame (forward-right-down)", fontsize=10)
    axes[-1].set_xlabel("time [s]")
    paths.append(out / f"{prefix}attitude.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)
    return paths
