"""Checks that an IMU's mounting is right, before and after a run on recorded logs.

The body frame is forward-right-down (x forward, y right, z down); ``mounting`` (roll, pitch,
yaw) or ``imu_axes`` (where the IMU's x, y, z point) gives the IMU's orientation in it. A wrong
one runs — the filter levels whatever it is given — and gives metres of error with no
message. Two checks catch it:

* **Gravity** (before the run, an error): the median specific force over the IMU log,
  rotated into the body frame, must point up (body −z) within :data:`GRAVITY_TOLERANCE_DEG`.
  A ground vehicle's accelerations average out over a log; gravity does not. The message
  names the IMU axis that carries gravity and the ``imu_axes`` entry to change.
* **Heading against course** (after the run, a warning): a car's heading follows the course
  of its velocity; a median difference above :data:`HEADING_TOLERANCE_DEG` at speed means
  the forward axis is wrong. GNSS velocities left out at more than
  :data:`VELOCITY_EXCLUSION_SHARE` of their tests point the same way.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from navfdi._errors import ScenarioError, ScenarioWarning
from navfdi._lc_schema import _rot

__all__ = ["FrameWarning", "check_gravity", "frame_warnings", "GRAVITY_TOLERANCE_DEG", "HEADING_TOLERANCE_DEG", "VELOCITY_EXCLUSION_SHARE"]

#: Largest angle (deg) between the body-frame median specific force and the body's up axis.
GRAVITY_TOLERANCE_DEG = 30.0
#: Median |heading − course| (deg, at speed) beyond which the forward axis is wrong.
HEADING_TOLERANCE_DEG = 30.0
#: Share of GNSS velocity tests left out beyond which the frames are suspect.
VELOCITY_EXCLUSION_SHARE = 0.2

_NAMES = ("x", "y", "z")


class FrameWarning(ScenarioWarning):
    """A run on recorded logs whose results say the IMU's mounting is wrong."""


def check_gravity(accel: np.ndarray, mounting: Sequence[float], field: str) -> None:
    """Refuse a mounting that puts gravity on the wrong axis.

    Parameters
    ----------
    accel : ndarray, shape (N, 3)
        Specific force in the IMU's axes (m/s²), the whole log.
    mounting : three float
        Roll, pitch, yaw (rad) of the IMU in the forward-right-down body frame.
    field : str
        The scenario section (``loosely_coupled`` or ``tight.strapdown``) for the message.

    Raises
    ------
    ScenarioError
        Naming the IMU axis that carries gravity, where the mounting puts it, and the fix.
    """
    a = np.asarray(accel, dtype=float)
    if a.ndim != 2 or a.shape[1] != 3 or len(a) == 0:
        return
    f = np.median(a, axis=0)
    g = float(np.linalg.norm(f))
    if not (g > 3.0):  # no gravity to speak of (or free fall): nothing to check against
        return
    c_imu_b = _rot(*mounting).T
    u = (c_imu_b @ f) / g  # the specific force (up, at rest) in the body: should be −z
    angle = math.degrees(math.acos(max(-1.0, min(1.0, float(-u[2])))))
    if angle <= GRAVITY_TOLERANCE_DEG:
        return
    k = int(np.argmax(np.abs(f)))
    sign = "+" if f[k] > 0 else "-"
    names = ("forward", "right", "down")
    where = c_imu_b @ np.eye(3)[k] * (1.0 if f[k] > 0 else -1.0)  # the up-pointing IMU axis, in the body
    j = int(np.argmax(np.abs(where)))
    put = names[j] if where[j] > 0 else ("back", "left", "up")[j]
    raise ScenarioError(
        f"{field}.mounting / imu_axes: the IMU's {sign}{_NAMES[k]} axis carries gravity (median specific force "
        f"{f[0]:+.2f}, {f[1]:+.2f}, {f[2]:+.2f} m/s² over the log), so it points up, but the mounting puts it "
        f"{put}: the levelled attitude would be {angle:.0f}° off. Name that axis 'up' in "
        f"{field}.imu_axes (imu_axes[{k}] = \"{'up' if sign == '+' else 'down'}\"), with the two others where they point "
        "(a right-handed set; body frame forward-right-down)")


def frame_warnings(run: Any, consistency: dict[str, Any]) -> list[str]:
    """The frame problems a finished logged run shows (messages for :class:`FrameWarning`):
    heading against course, and GNSS velocities left out. ``consistency`` is
    :func:`navfdi.consistency.consistency` of ``run``."""
    out: list[str] = []
    sec = "tight.strapdown" if "tight" in run.scenario.core else "loosely_coupled"
    h = consistency.get("heading", {})
    med = h.get("median_deg", math.nan)
    if h.get("epochs", 0) >= 10 and med > HEADING_TOLERANCE_DEG:
        out.append(
            f"the heading differs from the velocity's course by {med:.0f}° (median over {h['epochs']} epochs above 5 m/s): "
            f"the IMU's forward axis is likely wrong; check {sec}.imu_axes (which IMU axis points forward) or the yaw of {sec}.mounting")
    for s in run.record["subfilters"]:
        if "noise_scale" not in s or s["sensor"] not in _velocity_sensors(run):
            continue
        tested = np.asarray(s["dof"]) > 0
        left = (np.asarray(s["reason"]) > 0) & tested
        if tested.sum() >= 20 and left.mean() / max(tested.mean(), 1e-12) > VELOCITY_EXCLUSION_SHARE:
            share = left.sum() / tested.sum()
            out.append(
                f"{s['sensor']}: {share:.0%} of the GNSS velocities were left out: the IMU's mounting ({sec}.imu_axes / "
                f"mounting), its time offset ({sec}.imu_time_offset) or the velocity σ is likely wrong")
    return out


def _velocity_sensors(run: Any) -> set[str]:
    return {s["name"] for s in run.scenario.core["sensors"] if s.get("kind") in ("gnss_velocity", "gnss")}
