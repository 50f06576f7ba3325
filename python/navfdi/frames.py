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

A third check is of the logs' time lines (before the run, an error): a vehicle's turns are in
both logs — the IMU's rotation rate and the GNSS course's rate of change — and must line up in
time. A GNSS log in UTC read as GPS time (18 s apart since 2017), or a time-zone mix-up, runs
and gives hundreds of metres of error; so does a gyro unit read wrong, which makes the IMU's
turns 57 times the course's or a 57th of it (:func:`check_turns`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from navfdi._errors import ScenarioError, ScenarioWarning
from navfdi._intervals import alarm_intervals
from navfdi._lc_schema import _rot

__all__ = ["FrameWarning", "check_gravity", "check_turns", "frame_warnings", "GRAVITY_TOLERANCE_DEG", "HEADING_TOLERANCE_DEG",
           "VELOCITY_EXCLUSION_SHARE", "TIME_LAG_TOLERANCE_S", "TURN_RATE_RATIO", "REANCHOR_WARNINGS"]

#: A run whose INS was moved back onto the fixes FDE held out this many times or more is
#: said in a :class:`FrameWarning` (once can be a fault under way at the alignment).
REANCHOR_WARNINGS = 2

#: Largest angle (deg) between the body-frame median specific force and the body's up axis.
GRAVITY_TOLERANCE_DEG = 30.0
#: Median |heading − course| (deg, at speed) beyond which the forward axis is wrong.
HEADING_TOLERANCE_DEG = 30.0
#: Share of GNSS velocity tests left out beyond which the frames are suspect.
VELOCITY_EXCLUSION_SHARE = 0.2
#: Share of a positions-only receiver's tested fixes left out above which a run warns: the
#: displacement checks and this INS do not agree (the recorded drive with FDE and positions
#: alone left 99 % out before its causes were fixed; 2 % now, none without FDE).
POSITION_EXCLUSION_SHARE = 0.5

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


#: Largest lag (s) between the IMU's and the GNSS log's turns that :func:`check_turns`
#: lets through (receivers' latencies and IMU time stamps are tenths of a second).
TIME_LAG_TOLERANCE_S = 1.5
#: Largest factor between the IMU's rotation rate and the GNSS course's rate in turns that
#: :func:`check_turns` lets through (a gyro unit read wrong is 57.3 off).
TURN_RATE_RATIO = 2.0
#: Lags searched (s, both ways).
_MAX_LAG_S = 40.0
#: The correlation from which :func:`check_turns` speaks on a log whose IMU turns at most once.
_ONE_TURN_CORRELATION = 0.7
#: Standard errors of a chance correlation a lag's must reach in :func:`check_turns`: over
#: ``n`` independent 2 s windows at speed a correlation by chance has σ 1/√n, and the best of
#: 161 lags of a heavy-tailed noisy course reaches 4σ.
_CHANCE_SIGMAS = 5.0


def _windowed_rate(x: np.ndarray, t: np.ndarray, half: float = 1.0) -> np.ndarray:
    """The rate of ``x`` at times ``t`` (s) from the samples about ``half`` s (default 1 s)
    either side, or one sample when they are further apart; NaN at the ends."""
    m = max(1, int(round(half / float(np.median(np.diff(t))))))
    out = np.full(len(t), np.nan)
    if len(t) > 2 * m:
        out[m:-m] = (x[2 * m:] - x[:-2 * m]) / (t[2 * m:] - t[:-2 * m])
    return out


def _east_north_m(lat: np.ndarray, lon: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """East and north (m; a sphere's, scaled at the median latitude) of the fixes ``lat``,
    ``lon`` (deg), and which fixes repeat the one before them exactly (a receiver writing its
    last fix while it has none)."""
    lat, lon = np.asarray(lat, float), np.asarray(lon, float)
    r = 6_371_000.0
    n = np.radians(lat) * r
    e = np.radians(lon) * r * np.cos(np.radians(np.nanmedian(lat)))
    repeated = np.zeros(len(lat), bool)
    repeated[1:] = (lat[1:] == lat[:-1]) & (lon[1:] == lon[:-1])
    return e, n, repeated


def _position_velocity(t: np.ndarray, lat: np.ndarray, lon: np.ndarray, half: float) -> tuple[np.ndarray, np.ndarray]:
    """East and north velocity (m/s) at the epochs ``t`` from the positions (deg) differenced
    over ``half`` s either side (:func:`_windowed_rate`). A fix that repeats the one before it
    is no end of a difference: NaN there. A stale fix differenced with a fresh one gives the
    distance covered while it was stale as a velocity — the catch-up after 4 s of repeats at
    12 m/s read as 29–35 m/s turning at 60 deg/s, which lined up with a turn 15 s away at a
    correlation of 0.94 in :func:`check_turns`."""
    e, n, repeated = _east_north_m(lat, lon)
    e, n = np.where(repeated, np.nan, e), np.where(repeated, np.nan, n)
    return _windowed_rate(e, t, half), _windowed_rate(n, t, half)


def _east_north_velocity(t: np.ndarray, vel: np.ndarray, lat: np.ndarray, lon: np.ndarray,
                         half: float) -> tuple[np.ndarray, np.ndarray, bool]:
    """East and north velocity (m/s) at the GNSS epochs ``t``: the receiver's where it writes
    them (more than half finite), else the positions (deg) differenced over ``half`` s either
    side (:func:`_position_velocity`); and whether they came from the positions."""
    ve, vn = np.asarray(vel, float)[:, 0], np.asarray(vel, float)[:, 1]
    if np.isfinite(ve).mean() > 0.5:
        return ve, vn, False
    return (*_position_velocity(t, lat, lon, half), True)


def _turn_signals(imu_t: np.ndarray, gyro: np.ndarray, t: np.ndarray, vel: np.ndarray, lat: np.ndarray,
                  lon: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The GNSS epochs (s) at speed, the course's rate there (rad/s, magnitude; velocity, or
    the positions' differences without one) and the IMU's rotation-rate magnitude (rad/s)
    averaged over 2 s windows (the course's span) on the IMU's time line; None without enough of either."""
    t = np.asarray(t, float)
    if len(t) < 30 or len(imu_t) < 100:
        return None
    # Without velocities the positions' differences over about 2 s (one fix's noise would
    # swamp a course over a fraction of a second).
    ve, vn, _ = _east_north_velocity(t, vel, lat, lon, 1.0)
    fin = np.isfinite(ve) & np.isfinite(vn)
    if fin.sum() < 30:
        return None
    t, ve, vn = t[fin], ve[fin], vn[fin]
    # Its rate over about 2 s as well (a noisy course differenced over one fix interval
    # swamps the turns).
    rate = np.abs(_windowed_rate(np.unwrap(np.arctan2(ve, vn)), t))
    ok = np.isfinite(rate) & (np.hypot(ve, vn) > 3.0)
    if ok.sum() < 30:
        return None
    w = np.linalg.norm(np.asarray(gyro, float), axis=1)
    dt = float(imu_t[-1] - imu_t[0]) / max(len(imu_t) - 1, 1)
    k = max(1, int(round(2.0 / dt))) if dt > 0 else 1
    # A centred moving mean of k samples (cumulative sums: one pass).
    c = np.concatenate([[0.0], np.cumsum(w)])
    lo = np.clip(np.arange(len(w)) - k // 2, 0, len(w))
    hi = np.clip(lo + k, 0, len(w))
    smooth = (c[hi] - c[lo]) / np.maximum(hi - lo, 1)
    return t[ok], rate[ok], smooth


def check_turns(imu_t: np.ndarray, gyro: np.ndarray, gnss: Any, time_offset: float, field: str) -> None:
    """Refuse GNSS and IMU logs whose turns disagree: in time (time lines seconds apart) or in
    size (the gyro's unit).

    The lag that best lines up the GNSS course's rate of change with the IMU's
    rotation-rate magnitude (2 s averages; correlated at the GNSS epochs at speed over
    ±40 s in 0.5 s steps, then refined in 0.1 s steps) must be within
    :data:`TIME_LAG_TOLERANCE_S`; at that lag, the IMU's
    rate per unit of the course's (1 for a ground vehicle, whose turns are its course's) must
    not be off 1 by more than :data:`TURN_RATE_RATIO`: refused when the least-squares slopes
    both ways (the noisy course's rate bends one down, the other up) are both beyond it. Said only where
    the evidence is clear: the course turns (σ of its rate ≥ 1 deg/s over ≥ 30 epochs at
    > 3 m/s) and the best lag's correlation is ≥ 0.4 and 5 standard errors of a chance one
    (1/√n over the n independent 2 s windows at speed: on 200 s of meter-level positions with
    multipath bursts a burst lined up with a turn 32 s away at 0.40; for a lag, also 0.1 above the
    correlation with no lag; and ≥ 0.7 where the IMU turns at most once over those epochs:
    one turn against a noisy course can line up with noise, and a course's noise alone can
    pass for turns). A straight road or a walk says nothing and passes.

    Parameters
    ----------
    imu_t : ndarray, shape (N,)
        IMU sample times, GPS seconds (as read, before the time offset).
    gyro : ndarray, shape (N, 3)
        Angular rate in the IMU's axes (rad/s); only its magnitude is used, so the mounting
        does not enter.
    gnss : PosLog
        The GNSS log (``t`` GPS seconds, ``vel`` east/north/up m/s or NaN, ``lat``/``lon`` deg).
    time_offset : float
        The scenario's IMU time offset (s), added to the IMU's times.
    field : str
        The scenario section for the message.

    Raises
    ------
    ScenarioError
        With the lag found (s), the correlations and what an 18 s lag means; or with the
        ratio of the rates and the gyro unit it points to.
    """
    imu_t = np.asarray(imu_t, float) + float(time_offset)
    sig = _turn_signals(imu_t, gyro, gnss.t, gnss.vel, gnss.lat, gnss.lon)
    if sig is None:
        return
    tg, rate, w = sig
    if not np.std(rate) >= math.radians(1.0):
        return
    # The IMU's rate on a 0.1 s grid once; each lag (a row) reads it at the GNSS epochs' times
    # plus the lag, inside the IMU log only (the mask), and is correlated with the course's.
    wg = _rate_grid(imu_t, w)
    if len(wg) < 2:
        return

    def corr_at(lags: np.ndarray) -> np.ndarray:
        return _lag_correlation(tg, rate, float(imu_t[0]), wg, lags)[0]

    # ±40 s in 0.5 s steps, then ±0.5 s about the best in 0.1 s steps.
    coarse = np.arange(-_MAX_LAG_S, _MAX_LAG_S + 1e-9, 0.5)
    rc = corr_at(coarse)
    if not np.isfinite(rc).any():
        return
    fine = float(coarse[int(np.nanargmax(rc))]) + np.arange(-0.5, 0.5 + 1e-9, 0.1)
    rf = corr_at(fine)
    if not np.isfinite(rf).any():
        return
    best = int(np.nanargmax(rf))
    lag, r_best = float(np.round(fine[best], 1)), float(rf[best])
    r0 = float(corr_at(np.zeros(1))[0])
    # The course's rate and the IMU's are 2 s averages: the epochs at speed hold span / 2 s
    # independent windows, over which a chance correlation has σ 1/√n.
    windows = len(tg) * float(np.median(np.diff(tg))) / 2.0 if len(tg) > 1 else 0.0
    if not r_best >= max(0.4, _CHANCE_SIGMAS / math.sqrt(max(windows, 1.0))):
        return
    # One turn matched against a noisy course (a short log of meter-level positions) can line
    # up with noise elsewhere as well as with itself, and a course's noise alone can pass for
    # turns: a lag, or the turns' size, is said from two turns of the IMU or more, or where the
    # correlation is clear (a gyro unit read wrong scales the IMU's turns below the count's
    # 2 deg/s, not the correlation).
    if r_best < _ONE_TURN_CORRELATION and _turn_count(imu_t, w, tg) < 2:
        return
    if abs(lag) <= TIME_LAG_TOLERANCE_S or not (not math.isfinite(r0) or r_best - r0 >= 0.1):
        _check_turn_size(tg, rate, imu_t, w, lag, field)
        return
    hint = ""
    if abs(abs(lag) - 18.0) <= 1.0:
        hint = " 18 s is GPS − UTC (the leap seconds since 2017): one log is likely in UTC and read as GPS time (a CSV's time_scale = \"utc\")."
    elif abs(abs(lag) - 19.0) <= 1.0:
        hint = " 19 s is TAI − GPS: one log is likely in TAI."
    # The GNSS epoch stamped tg turns with the IMU stamped tg + lag: the GNSS stamps are −lag
    # after the IMU's, and an IMU offset of −lag (added to its times) lines them up.
    raise ScenarioError(
        f"the GNSS log {gnss.path} and the IMU log: the vehicle's turns are stamped {abs(lag):.1f} s later in the "
        f"{'GNSS' if lag < 0 else 'IMU'} log than in the {'IMU' if lag < 0 else 'GNSS'} log (the GNSS course's rate against the "
        f"IMU's rotation rate: correlation {r_best:.2f} at that lag, {r0:.2f} at none).{hint} Fix the time stamps, or if the "
        f"IMU's clock really is offset, set {field}.imu_time_offset = \"{-lag:+.1f} s\" (added to the IMU's times)")


def _turn_count(imu_t: np.ndarray, w: np.ndarray, tg: np.ndarray) -> int:
    """Turns of the IMU (its 2 s mean rotation-rate magnitude ``w``, rad/s, at ``imu_t``, s)
    over the GNSS epochs at speed ``tg`` (s): spells of at least 3 s above 2 deg/s (as alarm
    intervals, :func:`navfdi._intervals.alarm_intervals`)."""
    inside = (imu_t >= tg[0]) & (imu_t <= tg[-1])
    t = imu_t[inside]
    if t.size == 0:
        return 0
    spells = alarm_intervals(w[inside] > math.radians(2.0), t)
    return sum(1 for iv in spells if (t[-1] if iv.end is None else iv.end) - iv.start >= 3.0)


def _rate_grid(imu_t: np.ndarray, w: np.ndarray) -> np.ndarray:
    """The IMU's rotation-rate magnitude ``w`` (rad/s, at ``imu_t``) on a 0.1 s grid from
    ``imu_t[0]``, read once for every lag :func:`_lag_correlation` tries."""
    return np.interp(np.arange(imu_t[0], imu_t[-1], 0.1), imu_t, w)


def _lag_correlation(tg: np.ndarray, rate: np.ndarray, grid0: float, wg: np.ndarray, lags: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Correlation of the course's ``rate`` at the GNSS epochs ``tg`` with the IMU's rotation
    rate ``wg`` (on a 0.1 s grid from ``grid0``) read at ``tg + lag``, for each of ``lags``
    (s), over the epochs inside the IMU log; and the number of those epochs. NaN where fewer
    than 30."""
    idx = np.rint((tg[None, :] + lags[:, None] - grid0) / 0.1).astype(np.int64)
    m = ((idx >= 0) & (idx < len(wg))).astype(float)
    y = wg[np.clip(idx, 0, len(wg) - 1)] * m
    x = rate[None, :] * m
    n = m.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        mx, my = x.sum(axis=1) / n, y.sum(axis=1) / n
        sxy = (x * y).sum(axis=1) - n * mx * my
        sxx = (x * x).sum(axis=1) - n * mx * mx
        syy = (y * y).sum(axis=1) - n * my * my
        return np.where((n >= 30) & (sxx > 0) & (syy > 0), sxy / np.sqrt(sxx * syy), np.nan), n


def imu_clock_offset(imu_t: np.ndarray, gyro: np.ndarray, gnss: Any, field: str = "source.imu") -> tuple[float, float, float]:
    """The offset (s) that puts IMU times stamped on the IMU's own clock (seconds since power-up,
    or any clock with an unknown origin) on the GNSS log's GPS time: the lag that best lines up
    the IMU's rotation-rate magnitude with the GNSS course's rate of change (the signals of
    :func:`check_turns`), searched over every placement of the IMU log that covers at least half
    of the GNSS epochs it can, in 0.5 s steps, then refined in 0.1 s steps (the loosely coupled
    filter's ``imu_time_offset`` refines further). Returns ``(offset, correlation, next)``:
    the offset to add to the IMU's times, the correlation there and the best one at least 10 s
    away.

    Raises :class:`~navfdi.ScenarioError` naming ``field`` when the logs do not say it clearly:
    no turns at speed (σ of the course's rate below 1 deg/s, or fewer than 30 epochs above
    3 m/s), a best correlation below 0.5, or another placement within 0.15 of it."""
    imu_t = np.asarray(imu_t, float)
    sig = _turn_signals(imu_t, gyro, gnss.t, gnss.vel, gnss.lat, gnss.lon)
    why = (f"{field}.time_scale = \"boot\": the IMU's clock cannot be placed on GPS time from the turns"
           f" (its turn rate is matched to the GNSS track's)")
    if sig is None or not np.std(sig[1]) >= math.radians(1.0):
        raise ScenarioError(f"{why}: the GNSS log has too few turns at speed (above 3 m/s); give the IMU's times in GPS time")
    tg, rate, w = sig
    wg = _rate_grid(imu_t, w)
    # Lags that put some IMU sample at some GNSS epoch, in chunks (lags × epochs floats).
    lags = np.arange(np.floor(imu_t[0] - tg[-1]), np.ceil(imu_t[-1] - tg[0]) + 0.5, 0.5)
    if len(lags) > 2_000_000:
        raise ScenarioError(f"{why}: the IMU log spans {imu_t[-1] - imu_t[0]:.0f} s; give the IMU's times in GPS time")
    r, n = np.empty(len(lags)), np.empty(len(lags))
    step = max(1, 4_000_000 // max(len(tg), 1))
    for k in range(0, len(lags), step):
        r[k:k + step], n[k:k + step] = _lag_correlation(tg, rate, float(imu_t[0]), wg, lags[k:k + step])
    r[n < 0.5 * n.max()] = np.nan
    if not np.isfinite(r).any():
        raise ScenarioError(f"{why}: the logs never overlap by enough epochs")
    b = int(np.nanargmax(r))
    fine = lags[b] + np.arange(-0.5, 0.5 + 1e-9, 0.1)
    rf = _lag_correlation(tg, rate, float(imu_t[0]), wg, fine)[0]
    lag = float(fine[int(np.nanargmax(rf))]) if np.isfinite(rf).any() else float(lags[b])
    best = float(np.nanmax(rf)) if np.isfinite(rf).any() else float(r[b])
    far = np.abs(lags - lags[b]) >= 10.0
    nxt = float(np.nanmax(r[far])) if np.isfinite(r[far]).any() else float("nan")
    if not best >= 0.5:
        raise ScenarioError(f"{why}: the best placement lines the turns up with a correlation of {best:.2f} only (0.5 needed); give the IMU's times in GPS time")
    if math.isfinite(nxt) and best - nxt < 0.15:
        raise ScenarioError(f"{why}: two placements {abs(lags[b] - lags[int(np.nanargmax(np.where(far, r, np.nan)))]):.0f} s apart line the turns up "
                            f"about as well (correlations {best:.2f} and {nxt:.2f}); give the IMU's times in GPS time")
    # The GNSS epoch tg turns with the IMU sample stamped tg + lag: add −lag to the IMU's times.
    return -lag, best, nxt


#: The IMU clock's rate against GPS time is estimated from windows of at least this long (s)
#: and at least this many of them (:func:`imu_clock_drift`).
DRIFT_WINDOW = 120.0
DRIFT_WINDOWS = 3


def imu_clock_drift(imu_t: np.ndarray, gyro: np.ndarray, gnss: Any, offset: float) -> tuple[float, float, float, float, int]:
    """The rate (s per s) at which an IMU's own clock runs against GPS time, where the log is
    long and turns enough to tell: ``imu_t + offset`` (:func:`imu_clock_offset`) is lined up
    with the GNSS course's rate again in windows of at least :data:`DRIFT_WINDOW` s (six over
    the log, fewer for a short one), each to a fraction of the 0.1 s grid (a parabola through
    the correlation's peak), searched within ±(0.5 s + 0.6 % of the window's distance from the
    log's middle); the windows' lags fitted by a line in time, weighted by their correlation.
    Returns ``(lag, rate, its standard error, t_mid, windows)``: with ``u = t + offset`` the
    IMU's GPS time is ``u − lag − rate · (u − t_mid)`` (``t_mid`` the GNSS epochs' middle,
    ``lag`` the placement's remainder there) — (0, 0, inf, t_mid, n) where fewer than
    :data:`DRIFT_WINDOWS` windows line up (correlation 0.5 at least)."""
    imu_t = np.asarray(imu_t, float) + offset
    sig = _turn_signals(imu_t, gyro, gnss.t, gnss.vel, gnss.lat, gnss.lon)
    if sig is None:
        return 0.0, 0.0, math.inf, 0.0, 0
    tg, rate, w = sig
    wg = _rate_grid(imu_t, w)
    span = float(tg[-1] - tg[0])
    n_win = int(min(6, span // DRIFT_WINDOW))
    mid = 0.5 * (tg[0] + tg[-1])
    if n_win < DRIFT_WINDOWS:
        return 0.0, 0.0, math.inf, mid, 0
    edges = np.linspace(tg[0], tg[-1], n_win + 1)
    centres, lags, weights = [], [], []
    for a, b in zip(edges[:-1], edges[1:]):
        sel = (tg >= a) & (tg <= b)
        if sel.sum() < 30 or not np.std(rate[sel]) >= math.radians(1.0):
            continue
        c = 0.5 * (a + b)
        reach = 0.5 + 0.006 * abs(c - mid)
        cand = np.arange(-reach, reach + 1e-9, 0.1)
        r = _lag_correlation(tg[sel], rate[sel], float(imu_t[0]), wg, cand)[0]
        if not np.isfinite(r).any():
            continue
        k = int(np.nanargmax(r))
        if not r[k] >= 0.5 or k == 0 or k == len(cand) - 1 or not np.isfinite(r[k - 1]) or not np.isfinite(r[k + 1]):
            continue
        den = r[k - 1] - 2 * r[k] + r[k + 1]
        frac = 0.5 * (r[k - 1] - r[k + 1]) / den if den < 0 else 0.0
        centres.append(c - mid)
        lags.append(float(cand[k]) + 0.1 * float(np.clip(frac, -0.5, 0.5)))
        weights.append(float(r[k]))
    if len(lags) < DRIFT_WINDOWS:
        return 0.0, 0.0, math.inf, mid, len(lags)
    x, y, wt = np.array(centres), np.array(lags), np.array(weights)
    A = np.column_stack([np.ones_like(x), x]) * np.sqrt(wt)[:, None]
    coef, *_ = np.linalg.lstsq(A, y * np.sqrt(wt), rcond=None)
    res = y - (coef[0] + coef[1] * x)
    dof = max(len(y) - 2, 1)
    s2 = float((wt * res**2).sum() / dof)
    cov = s2 * np.linalg.inv(A.T @ A)
    se = float(math.sqrt(max(cov[1, 1], 0.0))) if len(y) > 2 else math.inf
    return float(coef[0]), float(coef[1]), se, mid, len(y)


#: The body axes an IMU axis may point along (forward-right-down body frame).
_BODY = {"forward": (1, 0, 0), "back": (-1, 0, 0), "right": (0, 1, 0), "left": (0, -1, 0), "down": (0, 0, 1), "up": (0, 0, -1)}


def estimate_imu_axes(imu_t: np.ndarray, accel: np.ndarray, gnss: Any, field: str = "loosely_coupled") -> tuple[list[str], float, float]:
    """Where the IMU's x, y, z axes point in a ground vehicle (``imu_axes``: forward, back,
    right, left, down, up), from the log alone: the IMU axis nearest the median specific
    force is up (refused beyond 30°); of the four axes across it, the one whose specific force
    follows the GNSS along-track acceleration (the speed's rate) and whose right-hand
    neighbour follows the centripetal acceleration (speed × the course's rate), 2 s averages at
    the GNSS epochs above 3 m/s (6 s from positions alone), is forward. Returns ``(axes, score, next)``: the sum of the two
    correlations for the axes chosen and for the next best choice (each at most 2).

    Raises :class:`~navfdi.ScenarioError` naming ``field`` when the log does not say it: no
    axis within 30° of gravity, fewer than 30 epochs at speed, or a score below 1 or within
    0.5 of the next."""
    accel = np.asarray(accel, float)
    why = f"{field}.imu_axes = \"auto\": the IMU's axes cannot be told from the log"
    up = np.median(accel, axis=0)
    up = up / np.linalg.norm(up)
    k = int(np.argmax(np.abs(up)))
    if not abs(up[k]) >= math.cos(math.radians(30.0)):
        raise ScenarioError(f"{why}: the median specific force {np.round(up, 2).tolist()} (IMU x, y, z) is more than 30° from every axis; "
                            "give imu_axes (or mounting) by hand")
    down = np.zeros(3)
    down[k] = -np.sign(up[k])  # the IMU axis vector (in IMU axes) that points down in the body
    t = np.asarray(gnss.t, float)
    # With velocities, rates over 2 s; from positions alone (differenced twice: metres of
    # noise) over 6 s, the vehicle's accelerations lasting that long.
    ve, vn, from_positions = _east_north_velocity(t, gnss.vel, gnss.lat, gnss.lon, 3.0)
    half = 3.0 if from_positions else 1.0
    speed = np.hypot(ve, vn)
    a_long = _windowed_rate(speed, t, half)
    # The course unwrapped over the epochs that have one (NaN stays NaN: no rate across it).
    course = np.arctan2(ve, vn)
    has = np.isfinite(course)
    course[has] = np.unwrap(course[has])
    a_lat = speed * _windowed_rate(course, t, half)
    ok = np.isfinite(a_long) & np.isfinite(a_lat) & (speed > 3.0) & (t >= imu_t[0] + half) & (t <= imu_t[-1] - half)
    if ok.sum() < 30:
        raise ScenarioError(f"{why}: fewer than 30 GNSS epochs above 3 m/s inside the IMU log; give imu_axes (or mounting) by hand")
    # The IMU's specific force averaged over 2 s about each epoch (cumulative sums).
    dt = float(imu_t[-1] - imu_t[0]) / max(len(imu_t) - 1, 1)
    m = max(1, int(round(half / dt)))
    c = np.vstack([np.zeros(3), np.cumsum(accel, axis=0)])
    i = np.searchsorted(imu_t, t[ok])
    lo, hi = np.clip(i - m, 0, len(imu_t)), np.clip(i + m, 0, len(imu_t))
    f = (c[hi] - c[lo]) / np.maximum(hi - lo, 1)[:, None]

    def corr(x: np.ndarray, y: np.ndarray) -> float:
        x, y = x - x.mean(), y - y.mean()
        d = math.sqrt(float((x * x).sum() * (y * y).sum()))
        return float((x * y).sum()) / d if d > 0 else -1.0

    scored = []
    for j in range(3):
        if j == k:
            continue
        for sgn in (1.0, -1.0):
            fwd = np.zeros(3)
            fwd[j] = sgn
            right = np.cross(down, fwd)  # forward × right = down in a right-handed frame
            scored.append((corr(f @ fwd, a_long[ok]) + corr(f @ right, a_lat[ok]), fwd, right))
    scored.sort(key=lambda s: -s[0])
    best, fwd, right = scored[0]
    nxt = scored[1][0]
    if not best >= 1.0 or best - nxt < 0.5:
        raise ScenarioError(f"{why}: the forward axis is not clear (the accelerations along and across the track fit the best choice "
                            f"with {best:.2f} and the next with {nxt:.2f} of 2); give imu_axes (or mounting) by hand")
    names = []
    for a in range(3):
        # IMU axis a points along body direction (forward, right, down components).
        v = (fwd[a], right[a], down[a])
        names.append(next(n for n, u in _BODY.items() if u == tuple(int(round(x)) for x in v)))
    return names, float(best), float(nxt)


def _check_turn_size(tg: np.ndarray, rate: np.ndarray, imu_t: np.ndarray, w: np.ndarray, lag: float, field: str) -> None:
    """The IMU's rotation-rate magnitude ``w`` against the course's ``rate`` (rad/s) at the
    GNSS epochs ``tg`` shifted by ``lag`` (s): refused when their slope is off 1 by more than
    :data:`TURN_RATE_RATIO` (see :func:`check_turns`)."""
    at = tg + lag
    inside = (at >= imu_t[0]) & (at <= imu_t[-1])
    x, y = rate[inside], np.interp(at[inside], imu_t, w)
    x0, y0 = x - x.mean(), y - y.mean()
    sxx, syy, sxy = float((x0 * x0).sum()), float((y0 * y0).sum()), float((x0 * y0).sum())
    if len(x) < 30 or not (sxx > 0 and sxy > 0):
        return
    # The course's rate is the noisy one (a receiver's velocity, or positions differenced):
    # regressed on it the slope is pulled toward 0, regressed the other way it is pushed up.
    # The true ratio lies between the two; refuse only when both are off the same way.
    lo, hi = sxy / sxx, syy / sxy
    if lo <= TURN_RATE_RATIO and hi >= 1.0 / TURN_RATE_RATIO:
        return
    deg = math.degrees(1.0)
    hint = ""
    if lo / 2.0 <= deg <= 2.0 * hi:
        hint = " 180/π is in that range: the gyro columns are likely in deg/s read as rad/s (source.imu.gyro_unit = \"deg/s\")."
    elif lo / 2.0 <= 1.0 / deg <= 2.0 * hi:
        hint = " π/180 is in that range: the gyro columns are likely in rad/s read as deg/s (source.imu.gyro_unit = \"rad/s\")."
    raise ScenarioError(
        f"source.imu: in the vehicle's turns the IMU's rotation rate is {lo:.3g}–{hi:.3g} times the GNSS course's rate "
        f"(least squares both ways over {len(x)} epochs at speed, the logs lined up at {lag:+.1f} s); a ground vehicle "
        f"turns with its course, so the ratio should be near 1.{hint} Check the gyro unit and columns ({field} is not the cause)")


def _left_out_share(sub: Mapping[str, Any]) -> float:
    """Share of a loosely coupled channel's tested epochs (``sub``: a record's subfilter)
    left out for any reason; NaN with fewer than 20 tested."""
    tested = np.asarray(sub["dof"]) > 0
    n = int(tested.sum())
    return float(((np.asarray(sub["reason"]) > 0) & tested).sum() / n) if n >= 20 else math.nan


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
    from navfdi._lc_schema import positions_only_channels

    only = positions_only_channels(run.scenario.raw)
    for s in run.record["subfilters"]:
        if s["sensor"] not in only or "noise_scale" not in s:
            continue
        share = _left_out_share(s)
        if share > POSITION_EXCLUSION_SHARE:
            out.append(
                f"{s['sensor']}: {share:.0%} of the GNSS positions were left out. On positions alone FDE checks the "
                f"fixes' displacement against the INS's, and here the two disagree (the IMU's noise, mounting or time offset, or an "
                f"IMU these checks do not fit): compare with the run without FDE ({sec}.isolate = false), and give the receiver's "
                f"velocities (a gnss or gnss_velocity sensor) if it writes them")
    moved = consistency.get("reanchored", [])
    if len(moved) >= REANCHOR_WARNINGS:
        imu = f"{sec}.imu.gyro_noise and accel_noise = \"auto\" read them from the log's rest"
        out.append(
            f"the INS ran away from the GNSS fixes FDE held out and was moved back onto them {len(moved)} times (first at "
            f"{moved[0]:g} s): FDE and the INS disagree about fixes the run without FDE takes in. The set-up is the first suspect: "
            f"the IMU's noise set below what the log has ({imu}; a density measured at another sample rate does not carry over), "
            f"its mounting or time offset, or the fixes' σ — compare with the run without FDE ({sec}.isolate = false)")
    for s in run.record["subfilters"]:
        if "noise_scale" not in s or s["sensor"] not in _velocity_sensors(run):
            continue
        share = _left_out_share(s)
        if share > VELOCITY_EXCLUSION_SHARE:
            out.append(
                f"{s['sensor']}: {share:.0%} of the GNSS velocities were left out: the IMU's mounting ({sec}.imu_axes / "
                f"mounting), its time offset ({sec}.imu_time_offset) or the velocity σ is likely wrong")
    return out


def _velocity_sensors(run: Any) -> set[str]:
    return {s["name"] for s in run.scenario.core["sensors"] if s.get("kind") in ("gnss_velocity", "gnss")}
