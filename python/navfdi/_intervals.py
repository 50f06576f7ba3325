"""Turning per-epoch alarm flags into alarm intervals."""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from navfdi import _core


class AlarmInterval(NamedTuple):
    """One interval during which a detector was in alarm.

    Attributes
    ----------
    start : float
        Time (or epoch index) of the first epoch in alarm.
    end : float or None
        Time of the first epoch after the alarm cleared; None if it never cleared.
    """

    start: float
    end: float | None


def alarm_intervals(alarm: ArrayLike, t: ArrayLike | None = None) -> list[AlarmInterval]:
    """Alarm intervals of a boolean alarm sequence.

    Parameters
    ----------
    alarm : array_like of bool, shape (T,)
        Alarm flag per epoch.
    t : array_like, shape (T,), optional
        Epoch times (s). Default: epoch indices.

    Returns
    -------
    list of AlarmInterval
        ``(start, end)`` per interval: ``start`` is the time the alarm was raised, ``end`` the
        time of the first epoch without alarm afterwards, or None if the alarm was still raised
        at the last epoch.
    """
    a = np.asarray(alarm, dtype=bool)
    if a.ndim != 1:
        raise ValueError(f"alarm: expected a 1-D array, got shape {a.shape}")
    times = np.arange(a.size, dtype=float) if t is None else np.asarray(t, dtype=float)
    if times.shape != a.shape:
        raise ValueError(f"t: expected shape {a.shape} to match alarm, got {times.shape}")
    edges = np.diff(a.astype(np.int8), prepend=0, append=0)
    starts = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1)
    out = []
    for s, e in zip(starts, ends):
        out.append(AlarmInterval(float(times[s]), float(times[e]) if e < a.size else None))
    return out


def match_events(alarm: ArrayLike, t: ArrayLike, windows: Sequence[tuple[float, float]]) -> list[tuple[AlarmInterval, int | None]]:
    """Alarm intervals with the index (into ``windows``, sorted by start) of the fault each
    detects, or None: the one matching rule of ``navfdi run``, ``montecarlo`` and ``demo``,
    computed in Rust (``navfdi._core.match_alarms``). An interval detects a fault when its
    onset lies inside the fault's window or up to :data:`GRACE` s after it (the latest-starting
    such fault); an alarm raised before a fault began and still running detects nothing (see
    :func:`window_alarm`)."""
    a = np.asarray(alarm, dtype=bool)
    times = np.asarray(t, dtype=float)
    starts, ends, faults = _core.match_alarms(times, a.tolist(), [(float(s), float(e)) for s, e in windows])
    return [
        (AlarmInterval(float(times[s]), float(times[e]) if e >= 0 else None), int(f) if f >= 0 else None)
        for s, e, f in zip(starts, ends, faults)
    ]



#: Seconds after a fault's end within which an alarm onset still detects it (the Rust
#: engine's ``navfdi_core::metrics::GRACE``, read from it).
GRACE: float = _core.DETECTION_GRACE


def window_alarm(alarm: ArrayLike, t: ArrayLike, start: float, end: float) -> tuple[bool, float]:
    """``(in_alarm_at_onset, alarm_fraction)`` of a fault window ``[start, end)`` (s): whether
    the alarm was already raised before the fault began and still on at its first epoch (not a
    detection), and the share of the window's epochs in alarm (NaN when no epoch lies in it).
    Computed in Rust (``navfdi._core.window_alarm``)."""
    a = np.asarray(alarm, dtype=bool)
    return _core.window_alarm(np.asarray(t, dtype=float), a.tolist(), float(start), float(end))
