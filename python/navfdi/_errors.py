"""The exceptions and warnings of scenarios and fault injection (re-exported by
:mod:`navfdi.scenario` and :mod:`navfdi`)."""

from __future__ import annotations


class ScenarioError(ValueError):
    """A scenario that cannot be run; the message names the field path and the value."""


class ScenarioTooLarge(ScenarioError, MemoryError):
    """A scenario (or campaign) that would need more memory than is available; the message
    says how much and which fields to change. Both a :class:`ScenarioError` and a
    ``MemoryError``."""


class ScenarioWarning(UserWarning):
    """Something in a scenario that runs but may not be what was meant (e.g. a trajectory
    shorter than the run, whose last segment is then held)."""


class NeverAppliedWarning(UserWarning):
    """An injected fault that never reached a measurement (its sensor never measures inside
    the window, its satellite is never in view or never observed, its system is not
    selected, its window is outside the file): it says nothing about the detectors and is
    left out of the detection statistics."""


class PartialLogWarning(ScenarioWarning):
    """A recorded log that covers only part of another (an IMU log that starts after or ends
    before the GNSS log): the run processes their overlap only, the message gives both spans,
    and a fault outside the processed span is never applied (not missed)."""


class ImuGapWarning(ScenarioWarning):
    """An IMU log with gaps: intervals between samples longer than twice its median interval
    (samples missing, as loggers drop them). Each gap is bridged by the samples either side
    and the error filter's noise is raised over it by those samples' own scatter acting for
    the whole gap (the mean of two samples is not the mean of the missing ones); the message
    gives how many, their total and the longest one's length and GPS time. Gaps longer than
    ``source.imu.max_gap`` are refused."""


class ImuClippingWarning(ScenarioWarning):
    """IMU samples at the sensor's full scale (clipped): a channel holding its largest or
    smallest value, exactly, on three or more consecutive samples, at a range such sensors are
    built with (±2 g, ±250 deg/s, …). The motion beyond the range is not in the log; the
    samples are kept and the error filter's noise over each run is raised as over a gap of
    its length. The message gives the channels, their value and count, and the first one's GPS
    time."""


class LeftOutSamplesWarning(ScenarioWarning):
    """IMU log rows left out as the log is read: a row that repeats the one before it exactly
    (the same time and values — a logger writing a sample twice; nothing is lost), or whose
    specific force is exactly zero on every axis (a logger's placeholder for a sample it did
    not get; the interval is bridged as a gap). The message gives how many and the first
    one's line."""


class LeftOutFixesWarning(ScenarioWarning):
    """GNSS log epochs that are not GNSS measurements and are left out as the log is read: a
    position the receiver estimated without satellites (NMEA ``GGA`` quality 6, dead
    reckoning), entered by hand (7) or simulated (8), or a fix from fewer than four
    satellites (no 3-D solution: held or extrapolated). The message gives how many, why and
    the first one's GPS time."""
