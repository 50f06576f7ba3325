"""Turning per-epoch alarm flags into alarm intervals."""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple, TypeVar

import numpy as np
from numpy.typing import ArrayLike


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


F = TypeVar("F")


def match_fault(interval: AlarmInterval, windows: Sequence[tuple[float, float]], faults: Sequence[F]) -> F | None:
    """The fault an alarm interval detects: the one rule of ``navfdi run``, ``montecarlo`` (in
    Rust, kept equal by a test) and ``demo``.

    An interval belongs to the first fault (in start order) whose window ``[start, end]`` it
    overlaps and that began after the previous fault's window ended: an alarm still raised from
    an earlier fault is not a new detection.

    Parameters
    ----------
    interval : AlarmInterval
        The alarm interval (s).
    windows : sequence of (start, end)
        Fault windows (s) of the faults on the tested sensor, sorted by start.
    faults : sequence
        The faults themselves, parallel to ``windows``; the matching one is returned.
    """
    prev_end = -np.inf
    end = np.inf if interval.end is None else interval.end
    for (f_start, f_end), f in zip(windows, faults):
        if interval.start <= f_end and end > f_start and interval.start >= prev_end:
            return f
        prev_end = f_end
    return None
