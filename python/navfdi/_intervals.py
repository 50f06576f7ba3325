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
        Time (or epoch index) of the first test in alarm.
    end : float or None
        Time of the first passing test after it (the alarm cleared); None if it never cleared.
    tests : int
        Tests the interval spans (each one alarmed); epochs at which the detector did not
        test (its sensor did not measure) are not counted and do not end the interval.
    """

    start: float
    end: float | None
    tests: int = 0


def _tested(tested: ArrayLike | None, n: int) -> list[bool] | None:
    if tested is None:
        return None
    m = np.asarray(tested, dtype=bool)
    if m.shape != (n,):
        raise ValueError(f"tested: expected shape ({n},) to match alarm, got {m.shape}")
    return m.tolist()


def tested_epochs(statistic: ArrayLike) -> np.ndarray:
    """The epochs at which a detector tested: its statistic (T,) is not NaN there (bool,
    shape (T,)). A sensor slower than the record is tested only at its own epochs."""
    return ~np.isnan(np.asarray(statistic, dtype=float))


def alarm_intervals(alarm: ArrayLike, t: ArrayLike | None = None, tested: ArrayLike | None = None) -> list[AlarmInterval]:
    """Alarm intervals of a boolean alarm sequence.

    Parameters
    ----------
    alarm : array_like of bool, shape (T,)
        Alarm flag per epoch.
    t : array_like, shape (T,), optional
        Epoch times (s). Default: epoch indices.
    tested : array_like of bool, shape (T,), optional
        The epochs at which the detector tested (:func:`tested_epochs` of its statistic).
        Alarm flags elsewhere are ignored: an interval runs from the first alarmed test to
        the first passing test. Default: every epoch is a test.

    Returns
    -------
    list of AlarmInterval
        ``(start, end, tests)`` per interval: ``start`` is the time the alarm was raised,
        ``end`` the time of the first passing test afterwards, or None if the alarm was still
        raised at the last test, ``tests`` the tests it spans. Computed by the Rust metrics
        engine (the rule of ``run``, ``montecarlo`` and ``demo``).
    """
    a = np.asarray(alarm, dtype=bool)
    if a.ndim != 1:
        raise ValueError(f"alarm: expected a 1-D array, got shape {a.shape}")
    times = np.arange(a.size, dtype=float) if t is None else np.asarray(t, dtype=float)
    if times.shape != a.shape:
        raise ValueError(f"t: expected shape {a.shape} to match alarm, got {times.shape}")
    return [iv for iv, _ in match_events(a, times, [], tested)]


def match_events(alarm: ArrayLike, t: ArrayLike, windows: Sequence[tuple[float, float]], tested: ArrayLike | None = None) -> list[tuple[AlarmInterval, int | None]]:
    """Alarm intervals (over the epochs ``tested``, default all; see :func:`alarm_intervals`)
    with the index (into ``windows``, sorted by start) of the fault each detects, or None: the
    one matching rule of ``navfdi run``, ``montecarlo`` and ``demo``, computed in Rust
    (``navfdi._core.match_alarms``). An interval detects a fault when its onset lies inside the
    fault's window or up to :data:`GRACE` s after it (the latest-starting such fault); an alarm
    raised before a fault began and still running detects nothing (see :func:`window_alarm`)."""
    a = np.asarray(alarm, dtype=bool)
    times = np.asarray(t, dtype=float)
    starts, ends, tests, faults = _core.match_alarms(times, a.tolist(), [(float(s), float(e)) for s, e in windows], _tested(tested, a.size))
    return [
        (AlarmInterval(float(times[s]), float(times[e]) if e >= 0 else None, int(n)), int(f) if f >= 0 else None)
        for s, e, n, f in zip(starts, ends, tests, faults)
    ]


#: Seconds after a fault's end within which an alarm onset still detects it (the Rust
#: engine's ``navfdi_core::metrics::GRACE``, read from it).
GRACE: float = _core.DETECTION_GRACE


def window_alarm(alarm: ArrayLike, t: ArrayLike, start: float, end: float, tested: ArrayLike | None = None) -> tuple[bool, float]:
    """``(in_alarm_at_onset, alarm_fraction)`` of a fault window ``[start, end)`` (s) over the
    epochs ``tested`` (default all): whether the alarm was already raised before the fault
    began and still on at its first test (not a detection), and the share of the window's
    tests in alarm (NaN when no test lies in it). Computed in Rust
    (``navfdi._core.window_alarm``)."""
    a = np.asarray(alarm, dtype=bool)
    return _core.window_alarm(np.asarray(t, dtype=float), a.tolist(), float(start), float(end), _tested(tested, a.size))
