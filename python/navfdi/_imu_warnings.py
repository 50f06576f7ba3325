"""What a recorded IMU log holds that the filters model but a user should know: gaps (samples
missing) and samples at the sensor's full scale (clipped). The rules are the Rust core's
(``navfdi_core::arch::inertial::imu_gaps``, ``navfdi_core::ins::clip``): these warnings say
what the mechanisation found, they do not decide it again."""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np

from ._logtime import gpst_text

__all__ = ["warn_gaps", "warn_clipped"]


def warn_gaps(imu: Any) -> None:
    """An :class:`~navfdi.ImuGapWarning` where the IMU log ``imu`` (an
    :class:`~navfdi.logs.ImuLog`: ``t`` (N,) GPS s, ``path``) has intervals longer than
    ``_core.IMU_GAP_FACTOR`` times its median one (samples missing; the gaps the Rust core's
    mechanisation finds, the same upper median): how many, their total, the longest and its
    GPS time. The mechanisation bridges them and raises the filter's noise."""
    from . import _core
    from ._errors import ImuGapWarning

    dt = np.diff(imu.t)
    if len(dt) < 2:
        return
    med = float(np.partition(dt, len(dt) // 2)[len(dt) // 2])
    factor = _core.IMU_GAP_FACTOR
    gap = np.flatnonzero(dt > factor * med)
    if len(gap):
        k = int(gap[np.argmax(dt[gap])])
        warnings.warn(
            f"the IMU log {imu.path} has {len(gap)} gap(s) longer than {factor:g}× its median sample interval "
            f"({med:.4g} s; samples missing), {float(dt[gap].sum()):.3g} s in all, the longest {float(dt[k]):.3g} s after "
            f"{gpst_text(imu.t[k])} GPST: each is bridged by the samples either side, and the filter's noise over it "
            "raised by their own scatter acting for the whole gap",
            ImuGapWarning, stacklevel=3)


def warn_clipped(imu: Any) -> None:
    """An :class:`~navfdi.ImuClippingWarning` where samples of the IMU log ``imu`` (``t``,
    ``gyro`` (N, 3) rad/s, ``accel`` (N, 3) m/s², ``path``) sit at the sensor's full scale
    (``_core.imu_clipped``): which channels, at what value, how many samples, the first one's
    GPS time. The samples are kept and the filter's noise over each run raised as over a gap
    of its length."""
    from . import _core
    from ._errors import ImuClippingWarning

    mask, channels = _core.imu_clipped(np.ascontiguousarray(imu.gyro, float), np.ascontiguousarray(imu.accel, float))
    if not channels:
        return
    said = [f"{sensor} {'xyz'[axis]} at {value / 9.80665:+.2f} g" if sensor == "accel" else f"{sensor} {'xyz'[axis]} at {math.degrees(value):+.0f} deg/s"
            for sensor, axis, value, _ in channels]
    said = [f"{s} ({n} samples)" for s, (*_, n) in zip(said, channels)]
    first = int(np.argmax(np.asarray(mask, bool)))
    warnings.warn(
        f"the IMU log {imu.path}: {int(np.sum(mask))} sample(s) at the sensor's full scale (clipped: {', '.join(said)}; the first at "
        f"{gpst_text(imu.t[first])} GPST): the motion beyond the range is not in the log. They are kept, and the filter's noise "
        "over each run raised as over a gap of its length; a wider range (±4 g or more, ±500 deg/s or more) keeps it",
        ImuClippingWarning, stacklevel=3)
