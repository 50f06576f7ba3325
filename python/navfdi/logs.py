"""Recorded logs as a scenario source: IMU CSV logs and RTKLIB ``.pos`` solutions.

A scenario's ``[source]`` table names the files (relative paths resolve against the TOML
file's folder); :func:`read_imu` and :func:`read_pos` read them (in one pass in Rust where the
file has the regular form) and check them, naming the file, line and column of bad input;
:func:`load_source` turns them into the arrays
:class:`navfdi._core.LoggedSource` takes. Time 0 of a logged run is the first epoch of the
GNSS file. All times are GPS time (GPST); heights are whatever the GNSS file holds.
"""

from __future__ import annotations

import gzip
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping, Sequence

import numpy as np

if TYPE_CHECKING:
    import pandas as pd

from ._errors import ScenarioError
from ._schema import SECTIONS as _SECTIONS
from ._logtime import GPS_EPOCH, TIME_UNITS, pos_time, time_unit, unix_to_gps, utc_count_to_gps
from ._logtime import gpst_text as _gpst
from ._imu_warnings import warn_clipped, warn_gaps
from .frames import check_gravity, check_turns

__all__ = ["ImuLog", "PosLog", "read_imu", "read_pos", "load_source", "logged_source", "scenario_folder", "GPS_EPOCH", "integrated_autocorrelation", "range_error_overbound", "range_error_process", "resolve_range_errors", "solve_rinex_source"]

#: Start of GPS time, 1980-01-06 00:00:00 GPST.
_WEEK = 604800.0
_G = 9.80665
_GYRO_UNITS = {"rad/s": 1.0, "deg/s": np.pi / 180.0}
_ACCEL_UNITS = {"m/s^2": 1.0, "m/s2": 1.0, "g": _G}


@dataclass(frozen=True)
class ImuLog:
    """An IMU log: ``t`` (N,) GPS seconds since the GPS epoch, ``gyro`` (N, 3) rad/s and
    ``accel`` (N, 3) m/s² in the IMU's axes (rates, whatever the file held)."""

    t: np.ndarray
    gyro: np.ndarray
    accel: np.ndarray
    path: str


@dataclass(frozen=True)
class PosLog:
    """A GNSS solution: ``t`` (M,) GPS seconds since the GPS epoch, ``lat``, ``lon`` (M,) in
    degrees, ``height`` (M,) m, ``q`` (M,) solution quality (1 fix, 2 float, 5 single, …),
    ``vel`` (M, 3) east, north, up m/s (NaN without velocity columns), ``sd_pos`` (M, 3) and
    ``sd_vel`` (M, 3) σ east, north, up (m, m/s), ``ns`` (M,) satellites the receiver used
    (NaN where the format does not say; None: not read)."""

    t: np.ndarray
    lat: np.ndarray
    lon: np.ndarray
    height: np.ndarray
    q: np.ndarray
    vel: np.ndarray
    sd_pos: np.ndarray
    sd_vel: np.ndarray
    path: str
    ns: np.ndarray | None = None

    def rows(self, t0: float) -> np.ndarray:
        """(M, 14) rows for :class:`navfdi._core.LoggedSource`: time from ``t0`` (s), latitude,
        longitude (rad), height (m), velocity east, north, up, σ position, σ velocity, and the
        solution quality (RTKLIB's codes; 0 where unknown)."""
        q = np.asarray(self.q, float)
        q = np.where(np.isfinite(q) & (q >= 0) & (q <= 255), np.round(q), 0.0)
        return np.column_stack([
            self.t - t0, np.radians(self.lat), np.radians(self.lon), self.height,
            self.vel, self.sd_pos, self.sd_vel, q,
        ]).astype(np.float64)

    def select(self, mask: np.ndarray) -> PosLog:
        """The epochs where ``mask`` (M,) is true."""
        return PosLog(self.t[mask], self.lat[mask], self.lon[mask], self.height[mask], self.q[mask],
                      self.vel[mask], self.sd_pos[mask], self.sd_vel[mask], self.path,
                      None if self.ns is None else self.ns[mask])


#: Largest ratio of decompressed to compressed size accepted for a ``.gz`` log (the core's
#: ``navfdi_core::memory::MAX_INFLATION``): text logs compress 3–20×.
MAX_INFLATION = 200


def _open_text(path: Path) -> list[str]:
    """The lines of a text log (:func:`_read_text`)."""
    return _read_text(path).splitlines()


def _read_text(path: Path) -> str:
    """The text of a log (``.gz`` by its magic bytes, a UTF-8 byte-order mark skipped).
    The path must be a regular file (a device or pipe could stream forever or block); a gzip
    that inflates beyond :data:`MAX_INFLATION` times its size (a compression bomb) is refused
    while it is being read."""
    import zlib

    try:
        st = path.stat()
    except OSError as e:
        raise ScenarioError(f"{path}: cannot read the file ({e.strerror or e})") from None
    import stat as _stat

    if not _stat.S_ISREG(st.st_mode):
        raise ScenarioError(f"{path}: not a regular file (a directory, device or pipe); give the path of a file")
    try:
        raw = path.read_bytes()
    except OSError as e:
        raise ScenarioError(f"{path}: cannot read the file ({e.strerror or e})") from None
    if raw[:2] == b"\x1f\x8b":
        cap = max(len(raw), 1) * MAX_INFLATION
        d = zlib.decompressobj(16 + zlib.MAX_WBITS)
        parts, total, data = [], 0, raw
        try:
            while data:
                chunk = d.decompress(data, 1 << 20)
                total += len(chunk)
                if total > cap:
                    raise ScenarioError(f"{path}: decompresses to more than {cap // 1_000_000} MB ({MAX_INFLATION} times its {len(raw) // 1000} kB): not a plausible log (a compression bomb or a corrupted file)")
                parts.append(chunk)
                data = d.unconsumed_tail or (d.unused_data if d.eof and d.unused_data[:2] == b"\x1f\x8b" else b"")
                if d.eof and data:
                    d = zlib.decompressobj(16 + zlib.MAX_WBITS)
            if not d.eof:
                raise EOFError("truncated")
        except (zlib.error, EOFError) as e:
            raise ScenarioError(f"{path}: not a readable gzip file ({e})") from None
        raw = b"".join(parts)
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise ScenarioError(f"{path}: not a text file (byte {e.start} is not UTF-8)") from None


#: The keys of ``[source.imu]`` (:data:`navfdi._schema.SECTIONS`).
IMU_KEYS = tuple(_SECTIONS["source.imu"].keys)


def text_layout(cfg: Mapping[str, Any], where: str) -> tuple[bool, str]:
    """``header`` and ``delimiter`` of a text log's table ``cfg`` (IMU or CSV GNSS): whether the
    first line names the columns (default true), and the separator — one ASCII character
    (default ``","``; ``"tab"`` gives a tab) or ``"whitespace"`` (runs of spaces and tabs).
    :class:`~navfdi.ScenarioError` naming ``where`` otherwise."""
    header = cfg.get("header", True)
    if not isinstance(header, bool):
        raise ScenarioError(f"{where}.header = {header!r}: true (the first line names the columns) or false")
    delim = cfg.get("delimiter", ",")
    if not (isinstance(delim, str) and (delim in ("tab", "whitespace") or (len(delim) == 1 and delim.isascii() and delim not in "\"\r\n"))):
        raise ScenarioError(f"{where}.delimiter = {delim!r}: one ASCII character (\",\", \";\", \" \"), \"tab\" or \"whitespace\" (runs of spaces and tabs)")
    return header, "\t" if delim == "tab" else delim


def check_imu_columns(columns: Mapping[str, Any], where: str = "source.imu") -> float:
    """Check a ``[source.imu]`` table before any file is read: unknown keys (a typo such as
    ``gyro_units`` would otherwise be ignored), the column lists, the units and ``kind``, and
    ``max_gap`` (a positive number of seconds, NaN refused). Returns ``max_gap`` (s).
    Raises :class:`~navfdi.ScenarioError` naming the field."""
    unknown = sorted(set(columns) - set(IMU_KEYS))
    if unknown:
        import difflib

        hints = [f"{u!r} (did you mean {m[0]!r}?)" if (m := difflib.get_close_matches(u, IMU_KEYS, 1)) else repr(u) for u in unknown]
        raise ScenarioError(f"{where}: unknown key(s) {', '.join(hints)}; the keys are {', '.join(IMU_KEYS)}")
    if "clock" in columns or "topic" in columns:
        k = "clock" if "clock" in columns else "topic"
        raise ScenarioError(f"{where}.{k}: read with format = \"{'gnsslogger' if k == 'clock' else 'rosbag'}\" only; a CSV names its columns")
    header, _ = text_layout(columns, where)

    def is_col(c: Any) -> bool:
        # Names with a header line; without one, numbers from 1 (or their text).
        if header:
            return isinstance(c, str)
        return (isinstance(c, int) and not isinstance(c, bool) and c >= 1) or (isinstance(c, str) and c.isdigit() and int(c) >= 1)

    what = "column names" if header else "column numbers (from 1; header = false)"
    for k in ("gyro", "accel"):
        v = columns.get(k)
        if not (isinstance(v, (list, tuple)) and len(v) == 3 and all(is_col(c) for c in v)):
            raise ScenarioError(f"{where}.{k}: three {what} (x, y, z) are required, got {v!r}")
    for k in ("week", "seconds", "time"):
        if k in columns and not is_col(columns[k]):
            raise ScenarioError(f"{where}.{k}: a {what[:-1]} is required, got {columns[k]!r}")
    week = columns.get("gps_week")
    if week is not None:
        if not (isinstance(week, int) and not isinstance(week, bool) and 0 <= week <= 9999):
            raise ScenarioError(f"{where}.gps_week = {week!r}: the GPS week number (0–9999) of a seconds-of-week column")
        if "seconds" not in columns or "week" in columns or "time" in columns or "time_scale" in columns:
            raise ScenarioError(f"{where}.gps_week: with a seconds-of-week column (seconds = …) alone, no week, time or time_scale "
                                "(the column may be in time_unit: u-blox's iTOW is \"ms\")")
    if not header and not ("time" in columns or ("seconds" in columns and ("week" in columns or week is not None))):
        raise ScenarioError(f"{where}: without a header line the time column's number is required (time = …, or week and seconds)")
    scale = columns.get("time_scale", "gpst")
    if scale not in ("gpst", "unix", "utc", "boot"):
        raise ScenarioError(f"{where}.time_scale = {scale!r}: 'gpst' (GPS seconds or ISO date-times in GPS time), 'unix' (Unix time, UTC), "
                            f"'utc' (ISO date-times in UTC) or 'boot' (the IMU's own clock, placed on GPS time by the turns)")
    if "time" not in columns and (scale != "gpst" or ("time_unit" in columns and week is None)):
        raise ScenarioError(f"{where}: time_scale and time_unit are for a single time column (time = …, or seconds of week with gps_week); "
                            "week and seconds are GPS time in seconds")
    time_unit(columns.get("time_unit", "s"), f"{where}.time_unit")
    if columns.get("time_repeats", "refuse") not in ("refuse", "spread"):
        raise ScenarioError(f"{where}.time_repeats = {columns['time_repeats']!r}: \"refuse\" (default) or \"spread\" (samples sharing a stamp spread evenly to the next)")
    gu, au = columns.get("gyro_unit", "rad/s"), columns.get("accel_unit", "m/s^2")
    if gu not in _GYRO_UNITS:
        raise ScenarioError(f"{where}.gyro_unit: {gu!r} is not one of {', '.join(_GYRO_UNITS)}")
    if au not in _ACCEL_UNITS:
        raise ScenarioError(f"{where}.accel_unit: {au!r} is not one of {', '.join(_ACCEL_UNITS)}")
    kind = columns.get("kind", "rates")
    if kind not in ("rates", "increments"):
        raise ScenarioError(f"{where}.kind: {kind!r} is not 'rates' or 'increments'")
    return max_gap_of(columns, where)


def max_gap_of(columns: Mapping[str, Any], where: str = "source.imu") -> float:
    """``[source.imu] max_gap`` (s; default 1): a positive number of seconds or a time string.
    :class:`~navfdi.ScenarioError` naming the field otherwise."""
    gap = columns.get("max_gap", 1.0)
    if isinstance(gap, str):
        from .units import parse

        try:
            gap = parse(gap, "time", f"{where}.max_gap")
        except ValueError as e:
            raise ScenarioError(f"{e} (a number of seconds, e.g. 0.1, or \"0.1 s\")") from None
    if isinstance(gap, bool) or not isinstance(gap, (int, float)) or not (math.isfinite(gap) and gap > 0):
        raise ScenarioError(f"{where}.max_gap: {gap!r}: a positive number of seconds is required")
    return float(gap)


def read_imu(path: str | Path, columns: Mapping[str, Any], max_gap: float | None = None) -> ImuLog:
    """Read an IMU CSV log (``.gz`` accepted) with a header line, in one streaming pass in Rust
    (``navfdi_core::logs::imu_csv``).

    ``columns``: ``week`` and ``seconds`` (GPS week and seconds of week) or ``time`` (GPS
    seconds since the GPS epoch, or ISO 8601 date-times, told from the first row); ``gyro``
    and ``accel``: three column names each, x, y, z; ``gyro_unit`` ``"deg/s"`` or
    ``"rad/s"``; ``accel_unit`` ``"g"`` or ``"m/s^2"``; ``gps_week`` (an integer: the week of
    a ``seconds`` column of seconds of week, with no ``week`` column; in ``time_unit``);
    ``time_scale`` ``"gpst"`` (default), ``"unix"`` (Unix time, UTC: turned into GPS time
    with the leap seconds), ``"utc"`` (ISO date-times in UTC, the same) or ``"boot"`` (the
    IMU's own clock: left as read here, placed on GPS time by :func:`load_source` from the
    turns, :func:`navfdi.frames.imu_clock_offset`) and ``time_unit`` ``"s"`` (default),
    ``"ms"``, ``"us"`` or ``"ns"`` for a numeric ``time`` column; ``header`` (default true;
    false: every line is a sample and the columns are numbered from 1) and ``delimiter``
    (default ``","``; one character, ``"tab"``, or ``"whitespace"``: runs of spaces and tabs,
    as column-aligned text); ``kind`` ``"rates"`` (default) or ``"increments"`` (per-sample
    angle and velocity increments, in rad and m/s or deg and g·s, divided by the sample
    interval); ``time_repeats`` ``"refuse"`` (default) or ``"spread"`` (samples sharing a
    time stamp, as loggers stamping in batches write them, spread evenly from the stamp to the
    next); ``max_gap``: the largest interval between samples (s) accepted (default 1; the
    argument overrides the table's; shorter gaps are bridged by the filters, with an
    :class:`~navfdi.ImuGapWarning`); ``format`` ``"csv"`` (default) or ``"gnsslogger"`` (an
    Android GnssLogger file, :func:`navfdi.gnsslogger.read_gnsslogger_imu`: no other key but
    ``file``, ``max_gap`` and ``clock``, the file holding its clock pairs). A UTF-8 byte-order mark and blank lines are accepted
    (line numbers stay the file's). Rows repeating the one before them exactly, and rows
    whose specific force is exactly zero on every axis (a placeholder), are left out with a
    :class:`~navfdi.LeftOutSamplesWarning`. Raises :class:`~navfdi.ScenarioError` naming the
    file, line and column of bad input: a missing column, a row with another number of
    fields, a value that is not a finite number (or not an ISO date-time where the first
    row's is), time not increasing, a gap, a sample beyond any IMU's range (100 rad/s,
    1000 m/s²), a median specific force far from gravity or a median rate over 1 rad/s
    (units), a header with no rows, a compressed file that inflates implausibly, a path that
    is not a regular file.
    """
    from . import _core

    fmt = columns.get("format", "csv")
    if fmt in ("gnsslogger", "rosbag"):
        from . import gnsslogger, rosbag

        allowed = gnsslogger.IMU_KEYS if fmt == "gnsslogger" else rosbag.IMU_KEYS
        other = sorted(set(columns) - set(allowed))
        if other:
            raise ScenarioError(f"source.imu: {', '.join(other)}: not read with format = \"{fmt}\" (the log names its fields, units "
                                f"and clocks itself); the keys are {', '.join(allowed)}")
        gap = float(max_gap) if max_gap is not None else max_gap_of(columns)
        if fmt == "rosbag":
            return rosbag.read_ros_imu(path, columns.get("topic"), columns.get("time_scale", "unix"), gap)
        clock = columns.get("clock")
        if clock is not None and not isinstance(clock, str):
            raise ScenarioError(f"source.imu.clock = {clock!r}: the path of a file whose Raw records pair the phone's boot clock with GPS time")
        return gnsslogger.read_gnsslogger_imu(path, gap, clock)
    if fmt != "csv":
        raise ScenarioError(f"source.imu.format = {fmt!r}: \"csv\" (default), \"gnsslogger\" (an Android GnssLogger file) or \"rosbag\"")
    gap = check_imu_columns(columns)
    if max_gap is not None:
        gap = float(max_gap)
    path = Path(path)
    if "gps_week" in columns:
        time = [columns["seconds"]]
    else:
        time = [columns["time"]] if "time" in columns else [columns.get("week", "gps_week"), columns.get("seconds", "gps_sow_s")]
    gu, au = columns.get("gyro_unit", "rad/s"), columns.get("accel_unit", "m/s^2")
    try:
        t, gyro, accel, (repeated, first, zeroed, first_zero, iso) = _core.read_imu_csv(
            str(path), [str(c) for c in time], [str(c) for c in columns["gyro"]], [str(c) for c in columns["accel"]],
            _GYRO_UNITS[gu], _ACCEL_UNITS[au], columns.get("kind", "rates") == "increments", gap,
            ["source.imu.gyro_unit", "source.imu.accel_unit"], TIME_UNITS[columns.get("time_unit", "s")],
            *text_layout(columns, "source.imu"), columns.get("time_repeats", "refuse") == "spread")
    except OSError as e:
        raise ScenarioError(str(e)) from None
    except ValueError as e:
        raise ScenarioError(str(e)) from None
    if repeated or zeroed:
        import warnings

        from ._errors import LeftOutSamplesWarning

        if repeated:
            warnings.warn(f"the IMU log {path}: {repeated} row(s) repeating the row before them exactly (the same time and values; "
                          f"the first at line {first}) left out", LeftOutSamplesWarning, stacklevel=2)
        if zeroed:
            warnings.warn(f"the IMU log {path}: {zeroed} row(s) with a specific force of exactly zero on every axis (no IMU on Earth "
                          f"measures that: a logger's placeholder for a missing sample; the first at line {first_zero}) left out, "
                          "their intervals bridged as gaps", LeftOutSamplesWarning, stacklevel=2)
    scale = columns.get("time_scale", "gpst")
    if iso and "time_unit" in columns:
        raise ScenarioError(f"source.imu.time_unit: {path}'s time column holds ISO date-times (no unit); leave time_unit out")
    if scale == "utc" and not iso:
        raise ScenarioError(f"source.imu.time_scale = 'utc': for ISO date-times; {path}'s time column holds numbers "
                            "(Unix time takes time_scale = 'unix')")
    if iso and scale in ("utc", "unix"):
        t = utc_count_to_gps(t)
    elif scale == "unix":
        t = unix_to_gps(t)
    if "gps_week" in columns:
        t = t + columns["gps_week"] * 604800.0
    return ImuLog(t, gyro, accel, str(path))


def read_pos(path: str | Path) -> PosLog:
    """Read an RTKLIB solution file (``.pos``, ``.gz`` accepted): time in GPST, UTC or JST as
    ``yyyy/mm/dd hh:mm:ss.sss`` or GPS week and seconds (UTC and JST turned into GPST with the
    leap seconds); positions as latitude/longitude/height in decimal degrees or
    degrees-minutes-seconds, or as ECEF x/y/z (turned into latitude/longitude/height, σ and
    velocities rotated to east/north/up); with or without the velocity columns
    (:mod:`navfdi._pos_forms`). Raises :class:`~navfdi.ScenarioError` naming the file, line and
    column of bad input."""
    from ._pos_forms import pos_form

    path = Path(path)
    text = _read_text(path)
    lines = text.splitlines()
    form = pos_form(path, [ln for ln in lines if ln.startswith("%")])
    fields = form.tokens
    # The regular form in one pass in Rust (the same numbers to the bit); anything else, and
    # every error, line by line here.
    from . import _core

    fast = _core.pos_rows(text, len(fields))
    a, line_of = (fast[0], fast[1].tolist()) if fast is not None else _pos_rows(path, lines, fields)
    if not len(a):
        raise ScenarioError(f"{path}: no solution epochs")
    _check_pos_values(path, fields, a[:, 1:], line_of)
    col = form.columns(path, {n: a[:, j + 1] for j, n in enumerate(fields)}, line_of)
    if form.angles == "xyz":
        names = [n for n in col if n.split("(")[0] in ("latitude", "longitude", "height", "sde", "sdn", "sdu", "ve", "vn", "vu", "sdve", "sdvn", "sdvu")]
        _check_pos_values(path, names, np.column_stack([col[n] for n in names]), line_of)

    def get(name: str, default: float = np.nan) -> np.ndarray:
        # Exact names without their unit ("sdu(m)" is sdu, never sdun's).
        for k, v in col.items():
            if k.split("(")[0] == name:
                return v
        return np.full(len(a), default)

    times = form.gpst(a[:, 0])
    again = repeated_rows(a)
    if again.any():
        from .gnss_logs import _left_out

        _left_out(path, times[again], f"repeating the epoch before them exactly (the first at line {line_of[int(np.argmax(again))]})")
        keep = ~again
        a, times, line_of = a[keep], times[keep], [n for n, k in zip(line_of, keep) if k]
        col = {k: v[keep] for k, v in col.items()}
    steps = np.diff(times)
    if (steps <= 0).any():
        i = int(np.argmax(steps <= 0))
        raise ScenarioError(f"{path}, line {line_of[i + 1]}: epoch {i + 2} ({times[i + 1]:.3f} s) does not come after the one before it")
    vel = np.column_stack([get("ve"), get("vn"), get("vu")])
    sd_vel = np.column_stack([get("sdve"), get("sdvn"), get("sdvu")])
    # RTKLIB names the height "height(m)"; an ellipsoidal height may be labelled "ellh(m)".
    height = get("height") if any(k.split("(")[0] == "height" for k in col) else get("ellh")
    return PosLog(times, get("latitude"), get("longitude"), height, get("Q", 0), vel,
                  np.column_stack([get("sde"), get("sdn"), get("sdu")]), sd_vel, str(path), get("ns"))


def _pos_rows(path: Path, lines: Sequence[str], fields: Sequence[str]) -> tuple[np.ndarray, list[int]]:
    """The data rows of a ``.pos`` file's ``lines`` one by one (:func:`read_pos`'s reader for
    what the Rust pass does not take, and its errors): ``(values, line numbers)``, values
    (N, 1 + len(fields)): GPS seconds, then the fields."""
    data = []
    line_of: list[int] = []
    for i, ln in enumerate(lines):
        if ln.startswith("%") or not ln.strip():
            continue
        tok = ln.split()
        if len(tok) < 2 + len(fields):
            raise ScenarioError(f"{path}, line {i + 1}: {len(tok)} fields, the header names {2 + len(fields)}")
        try:
            t = pos_time(tok[0], tok[1])
        except ValueError:
            raise ScenarioError(f"{path}, line {i + 1}, column 'GPST': {tok[0]} {tok[1]!r} is not a GPST time") from None
        try:
            vals = [float(x) for x in tok[2:2 + len(fields)]]
        except ValueError:
            j = next(j for j, x in enumerate(tok[2:2 + len(fields)]) if not _isfloat(x))
            raise ScenarioError(f"{path}, line {i + 1}, column {fields[j]!r}: {tok[2 + j]!r} is not a number") from None
        data.append([t, *vals])
        line_of.append(i + 1)
    return np.asarray(data, float).reshape(len(data), 1 + len(fields)), line_of


def _pos_limit(name: str) -> tuple[float, float] | None:
    """The range of values a receiver on or near the Earth reports in a ``.pos`` column (by its
    name's prefix): heights to 100 km, speeds to 10 km/s, σ to 100 km and 1 km/s (the
    off-diagonal ``sdne``… terms signed); None for the other columns (Q, ns, age, ratio)."""
    cross = name.startswith(("sdne", "sdeu", "sdun", "sdue", "sdxy", "sdyz", "sdzx", "sdvne", "sdveu", "sdvun", "sdvxy", "sdvyz", "sdvzx"))
    for prefix, lim in (("latitude", (-90.0, 90.0)), ("longitude", (-180.0, 360.0)), ("height", (-1e4, 1e5)), ("ellh", (-1e4, 1e5)),
                        ("sdv", (-1e3 if cross else 0.0, 1e3)), ("sd", (-1e5 if cross else 0.0, 1e5)), ("v", (-1e4, 1e4))):
        if name.startswith(prefix):
            return lim
    return None


def _check_pos_values(path: Path, fields: Sequence[str], values: np.ndarray, line_of: Sequence[int]) -> None:
    """``ScenarioError`` naming the line and column of a value outside what a receiver can
    report (:func:`_pos_limit`; a height of 1e20 m or a σ of 1e300 would otherwise reach the
    filter as a not-positive-definite covariance with no line named)."""
    for j, name in enumerate(fields):
        lim = _pos_limit(name)
        if lim is None:
            continue
        v = values[:, j]
        bad = ~((v >= lim[0]) & (v <= lim[1]))
        if bad.any():
            k = int(np.argmax(bad))
            what = "not a number" if not np.isfinite(v[k]) else f"{float(v[k])!r} is outside [{lim[0]:g}, {lim[1]:g}], what a receiver on or near the Earth reports"
            raise ScenarioError(f"{path}, line {line_of[k]}, column {name!r}: {what}")


def _isfloat(x: str) -> bool:
    try:
        float(x)
        return True
    except ValueError:
        return False


def load_source(source: Mapping[str, Any], base: Path) -> dict[str, Any]:
    """Read a scenario's ``[source]`` table (paths relative to ``base``): returns ``imu``
    (N, 7), ``gnss`` (M, 14) or None, ``reference`` (K, 14) or None arrays and ``rinex``
    (observation and navigation paths, or None) for :class:`navfdi._core.LoggedSource`,
    ``t0`` (GPS seconds of time 0; None for RINEX logs, whose time 0 is the first observation
    epoch and whose arrays keep GPS seconds), and the logs."""
    imu_cfg = source.get("imu")
    if not isinstance(imu_cfg, Mapping):
        raise ScenarioError("source.imu: a table with file and columns is required")
    if imu_cfg.get("format") == "gnsslogger" and isinstance(imu_cfg.get("clock"), str):
        imu_cfg = {**imu_cfg, "clock": str(file_in(imu_cfg, base, "source.imu.clock", "clock"))}
    imu = read_imu(file_in(imu_cfg, base, "source.imu.file"), imu_cfg)
    ref = None
    if "reference" in source:
        from .gnss_logs import read_reference

        ref, has_quality = read_reference(source["reference"], base)
        quality = source.get("reference_quality", [1])
        if not has_quality and "reference_quality" in source:
            raise ScenarioError("source.reference_quality: the reference has no solution quality (a CSV, a GnssLogger file or a ROS bag); leave it out (every epoch is the reference)")
        keep = np.isin(ref.q, quality) if has_quality else np.ones(len(ref.t), bool)
        if not keep.any():
            have = ", ".join(str(int(q)) for q in np.unique(ref.q))
            raise ScenarioError(
                f"source.reference: {ref.path}: no epoch of quality {list(quality)} (source.reference_quality; default [1], "
                f"RTK fixed); the file's qualities are {have}: set reference_quality = [{have}] to score against them")
        ref = ref.select(keep)
    if "rinex_obs" in source:
        if imu_cfg.get("time_scale") == "boot":
            raise ScenarioError("source.imu.time_scale = \"boot\": the IMU's clock is placed by the GNSS log's turns ([source] gnss); "
                                "a tight scenario's RINEX has none: give the IMU's times in GPS time")
        obs = file_in(source, base, "source.rinex_obs", "rinex_obs")
        nav = file_in(source, base, "source.rinex_nav", "rinex_nav")
        for p, name in ((obs, "source.rinex_obs"), (nav, "source.rinex_nav")):
            if not p.is_file():
                raise ScenarioError(f"{name}: {p}: no such file")
        return {
            "imu": np.column_stack([imu.t, imu.gyro, imu.accel]), "gnss": None,
            "reference": None if ref is None else ref.rows(0.0), "rinex": (str(obs), str(nav)),
            "t0": None, "imu_log": imu, "gnss_log": None, "reference_log": ref,
        }
    from .gnss_logs import read_gnss

    pos = read_gnss(source.get("gnss"), base)
    if imu_cfg.get("time_scale") == "boot":
        imu = ImuLog(_boot_times(imu, pos), imu.gyro, imu.accel, imu.path)
    t0 = float(pos.t[0])
    if imu.t[-1] <= pos.t[0] or pos.t[-1] <= imu.t[0]:
        raise ScenarioError(
            f"{pos.path} ({_gpst(pos.t[0])}–{_gpst(pos.t[-1])} GPST) and {imu.path} ({_gpst(imu.t[0])}–{_gpst(imu.t[-1])} GPST) do not overlap in time")
    imu_rows = np.column_stack([imu.t - t0, imu.gyro, imu.accel])
    return {
        "imu": imu_rows, "gnss": pos.rows(t0), "reference": None if ref is None else ref.rows(t0), "rinex": None,
        "t0": t0, "imu_log": imu, "gnss_log": pos, "reference_log": ref,
    }


#: Placements of IMU logs on their own clock already found in this process (a run reads its
#: logs again after estimating its "auto" fields): said once, computed once.
_BOOT_OFFSETS: dict[tuple[Any, ...], tuple[float, float, float, float]] = {}


def _boot_times(imu: ImuLog, pos: PosLog) -> np.ndarray:
    """``imu``'s times put on GPS time from its own clock: the offset that lines its turns up
    with the GNSS track's (:func:`navfdi.frames.imu_clock_offset`) and, where the log tells it
    (three windows or more, the rate beyond three standard errors and 20 ms over the log), the
    clock's rate against GPS time (:func:`navfdi.frames.imu_clock_drift`); said in a
    :class:`~navfdi.ScenarioWarning` the first time."""
    import warnings

    from ._errors import ScenarioWarning
    from .frames import imu_clock_drift, imu_clock_offset

    key = (imu.path, len(imu.t), float(imu.t[0]), float(imu.t[-1]), pos.path, len(pos.t), float(pos.t[0]))
    if key not in _BOOT_OFFSETS:
        off, r, nxt = imu_clock_offset(imu.t, imu.gyro, pos)
        lag, rate, se, mid, windows = imu_clock_drift(imu.t, imu.gyro, pos, off)
        span = float(pos.t[-1] - pos.t[0])
        drifts = windows >= 3 and abs(rate) > 3 * se and abs(rate) * span > 0.02
        said = (f"; its clock runs {1e6 * rate:+.0f} ± {1e6 * se:.0f} ppm against GPS time ({abs(rate) * span:.2f} s over the log, "
                f"from {windows} windows of turns), taken out" if drifts else "")
        warnings.warn(f"source.imu: time_scale = \"boot\": the IMU's clock placed on GPS time by its turns, {off:+.1f} s added to its times "
                      f"(correlation {r:.2f}; the best placement at least 10 s away {nxt:.2f}){said}", ScenarioWarning, stacklevel=3)
        if len(_BOOT_OFFSETS) > 64:
            _BOOT_OFFSETS.clear()
        _BOOT_OFFSETS[key] = (off, lag, rate, mid) if drifts else (off, 0.0, 0.0, mid)
    off, lag, rate, mid = _BOOT_OFFSETS[key]
    u = imu.t + off
    return u - lag - rate * (u - mid) if rate else u


def file_in(cfg: Mapping[str, Any], base: Path, name: str, key: str = "file") -> Path:
    """The path ``cfg[key]`` resolved against ``base``; ``name`` is its field path."""
    v = cfg.get(key)
    if not isinstance(v, str):
        raise ScenarioError(f"{name}: a file path is required")
    p = Path(v)
    return p if p.is_absolute() else base / p


def scenario_folder(sc: Any) -> Path:
    """The folder a scenario's relative ``[source]`` paths resolve against: its TOML file's
    (the package's ``scenarios`` folder for a bundled scenario, the working directory for one
    built in Python)."""
    from importlib import resources

    from ._bundled import bundled_scenarios

    if sc.source in bundled_scenarios():
        return Path(str(resources.files("navfdi") / "scenarios"))
    p = Path(sc.source)
    return p.parent if p.suffix == ".toml" else Path.cwd()


def logged_source(sc: Any) -> Any:
    """:func:`scored_source`'s prepared source alone."""
    return scored_source(sc)[0]


def scored_source(sc: Any) -> tuple[Any, str, float]:
    """Read scenario ``sc``'s logs and prepare them (:class:`navfdi._core.LoggedSource`).
    Refuses a mounting that puts gravity on the wrong axis (:func:`navfdi.frames.check_gravity`).
    Checks that the scenario's ``duration`` and ``dt`` match the GNSS log (the RINEX
    observations' epochs for a tight scenario). Returns the source and where its reference
    is scored: ``"held_out"`` (epochs that are not GNSS inputs) or ``"inputs"`` (the input
    epochs, after their update: ``[source] reference_epochs``), and the GPS seconds of the
    run's time 0."""
    from . import _core
    from ._lc_schema import auto_fields

    auto = auto_fields(sc.raw)
    if (sc.raw.get("tight") or {}).get("range_states") == "auto":
        raise ScenarioError("tight.range_states = \"auto\" is estimated from the log before the run: navfdi.run_scenario and "
                            "navfdi.montecarlo do it (navfdi.logs.resolve_range_errors), or give { fraction, tau }")
    if auto:
        raise ScenarioError(f"loosely_coupled.{auto[0]} = \"auto\" is estimated before the run: navfdi.run_scenario and "
                            "navfdi.montecarlo do it (navfdi.calibrate.resolve_auto), or write the values with navfdi calibrate --out")
    data = load_source(sc.raw["source"], scenario_folder(sc))
    for sec, table in (("loosely_coupled", sc.core.get("loosely_coupled")), ("tight.strapdown", (sc.core.get("tight") or {}).get("strapdown"))):
        if isinstance(table, Mapping) and "mounting" in table:
            check_gravity(data["imu_log"].accel, table["mounting"], sec)
        if isinstance(table, Mapping) and data.get("gnss_log") is not None:
            check_turns(data["imu_log"].t, data["imu_log"].gyro, data["gnss_log"], float(table.get("imu_time_offset", 0.0)), sec)
    try:
        if data["rinex"] is not None:
            src = _core.LoggedSource(sc.to_json(), data["imu"], None, data["reference"], data["rinex"])
            t = np.asarray(src.times)
            what = f"the RINEX observations {data['rinex'][0]}"
        else:
            src = None
            t = data["gnss"][:, 0]
            what = f"the GNSS log {data['gnss_log'].path}"
    except ValueError as e:
        raise ScenarioError(str(e)) from None
    if len(t) < 2:
        raise ScenarioError(f"{what} has {len(t)} epoch(s); a run needs at least two")
    span = float(t[-1] - t[0])
    dt = float(np.median(np.diff(t)))
    _warn_partial(data["imu_log"], t, float(src.time0) if src is not None else float(data["t0"]), what)
    warn_gaps(data["imu_log"])
    warn_clipped(data["imu_log"])
    if abs(sc.core["duration"] - span) > max(sc.core["dt"], 1e-6) or abs(sc.core["dt"] - dt) > 1e-3:
        raise ScenarioError(
            f"duration = {sc.core['duration']:g} s, dt = {sc.core['dt']:g} s: {what} spans {span:g} s "
            f"at {dt:g} s epochs; set duration = \"{span:g} s\" and dt = \"{dt:g} s\"")
    if src is not None:
        return src, "held_out", float(src.time0)
    mode = reference_epochs(sc.raw["source"])
    try:
        src = _core.LoggedSource(sc.to_json(), data["imu"], data["gnss"], data["reference"], score_inputs=mode == "inputs")
        if mode == "auto" and data["reference"] is not None and src.scored == 0:
            # Every reference epoch is a GNSS input: scored there, after the update (labelled).
            src = _core.LoggedSource(sc.to_json(), data["imu"], data["gnss"], data["reference"], score_inputs=True)
            src_mode = "inputs"
        else:
            src_mode = "held_out" if mode == "auto" else mode
    except ValueError as e:
        raise ScenarioError(str(e)) from None
    return src, src_mode, float(data["t0"])


def reference_epochs(source: Mapping[str, Any]) -> str:
    """``[source] reference_epochs``: ``"auto"`` (default: the reference epochs that are not
    GNSS inputs, or — when there are none — the input epochs, after their update),
    ``"held_out"`` or ``"inputs"``."""
    mode = source.get("reference_epochs", "auto")
    if mode not in ("auto", "held_out", "inputs"):
        raise ScenarioError(f"source.reference_epochs = {mode!r}: one of \"auto\", \"held_out\", \"inputs\"")
    return str(mode)


#: Seconds by which an IMU log may start after, or end before, the GNSS log without a warning.
PARTIAL_SLACK = 10.0


def _warn_partial(imu: ImuLog, t: np.ndarray, t0: float, what: str) -> None:
    """A :class:`PartialLogWarning` with both spans when the IMU log starts more than
    :data:`PARTIAL_SLACK` s after the GNSS epochs or ends more than that before them (the run
    processes the overlap; faults outside it are never applied). Shorter offsets are the usual
    stagger of two loggers started by hand (the bundled drive's IMU starts 3.4 s after its
    GNSS), and the INS navigates only after its alignment anyway."""
    import warnings

    from ._errors import PartialLogWarning

    g0, g1 = t0 + float(t[0]), t0 + float(t[-1])
    late, early = float(imu.t[0]) - g0, g1 - float(imu.t[-1])
    if late > PARTIAL_SLACK or early > PARTIAL_SLACK:
        parts = ([f"starts {late:.1f} s after"] if late > PARTIAL_SLACK else []) + ([f"ends {early:.1f} s before"] if early > PARTIAL_SLACK else [])
        warnings.warn(
            f"the IMU log {imu.path} ({_gpst(imu.t[0])}–{_gpst(imu.t[-1])} GPST) {' and '.join(parts)} {what} "
            f"({_gpst(g0)}–{_gpst(g1)} GPST): only their overlap is navigated, {float(t[0]) + max(late, 0.0):g}–"
            f"{float(t[-1]) - max(early, 0.0):g} s of the run; faults outside it are never applied",
            PartialLogWarning, stacklevel=3)


def repeated_rows(rows: np.ndarray) -> np.ndarray:
    """(N,) bool: the rows of ``rows`` (N, K) that repeat the row before them exactly (NaN
    equal to NaN) — an epoch or sample a logger wrote twice."""
    same = (rows[1:] == rows[:-1]) | (np.isnan(rows[1:]) & np.isnan(rows[:-1]))
    return np.concatenate([[False], same.all(axis=1)])


def integrated_autocorrelation(arcs: Sequence[tuple[np.ndarray, np.ndarray]], max_lag: int = 2000) -> tuple[float, np.ndarray]:
    """The integrated autocorrelation time ``τ = 1 + 2 Σ_{L≥1} ρ(L)`` (in epochs) of a set of
    arcs of one stationary series: ``arcs`` are ``(epochs, values)`` pairs (integer epoch
    indices, increasing; values with NaN where missing). ``ρ(L)`` is pooled over every pair of
    samples ``L`` epochs apart within an arc (each arc's mean removed); the sum is truncated
    by Geyer's initial positive sequence (pairs ``ρ(2m) + ρ(2m+1)`` summed while positive and
    made non-increasing), which keeps the estimate from summing noise at long lags.

    ``τ`` is the factor by which a white-noise model's variance must grow for the mean of a
    long stretch of the series to have the variance the model gives it (for AR(1) with lag-1
    correlation ρ, ``(1 + ρ)/(1 − ρ)``). Returns ``(τ, ρ)`` with ``ρ`` (K,) the correlations
    used, ``ρ[0] = 1``. ``ValueError`` when the arcs hold fewer than 20 pairs at lag 1."""
    clean = []
    for e, v in arcs:
        e, v = np.asarray(e, dtype=np.int64), np.asarray(v, dtype=float)
        ok = np.isfinite(v)
        e, v = e[ok], v[ok]
        if len(v) >= 2:
            dense = np.full(int(e[-1] - e[0]) + 1, np.nan)
            dense[e - e[0]] = v - v.mean()
            clean.append(dense)
    if not clean:
        raise ValueError("integrated_autocorrelation: no arc with two samples")

    def rho(lag: int) -> tuple[float, int]:
        num, a2, b2, n = 0.0, 0.0, 0.0, 0
        for d in clean:
            if len(d) <= lag:
                continue
            a, b = d[:-lag], d[lag:]
            ok = np.isfinite(a) & np.isfinite(b)
            if ok.any():
                num += float(a[ok] @ b[ok])
                a2 += float(a[ok] @ a[ok])
                b2 += float(b[ok] @ b[ok])
                n += int(ok.sum())
        return (num / math.sqrt(a2 * b2) if a2 > 0 and b2 > 0 else math.nan), n

    r1, n1 = rho(1)
    if n1 < 20:
        raise ValueError(f"integrated_autocorrelation: {n1} pairs one epoch apart; at least 20 are needed")
    if not math.isfinite(r1):
        raise ValueError("integrated_autocorrelation: the series does not vary")
    rhos = [1.0, r1]
    total, prev = 0.0, math.inf
    m = 0
    while 2 * m + 1 <= max_lag:
        while len(rhos) <= 2 * m + 1:
            r, n = rho(len(rhos))
            rhos.append(r if n >= 10 else math.nan)
        g = rhos[2 * m] + rhos[2 * m + 1]
        if not (g > 0):
            break
        g = min(g, prev)
        total += g
        prev = g
        m += 1
    return max(1.0, -1.0 + 2.0 * total), np.asarray(rhos[: max(2, 2 * m)])


def solve_rinex_source(sc: Any) -> tuple[Path, Any]:
    """A tight scenario's ``[source]`` RINEX observations solved epoch by epoch
    (:func:`navfdi.gnss_solve`, with FDE) with the systems and elevation mask of its
    ``[tight] sensor`` and the tight filter's σ model (elevation weights, factor 1): the observation file's path and the :class:`~navfdi.gnss.GnssSolution`."""
    from navfdi.gnss import gnss_solve

    data = sc.raw["source"]
    base = scenario_folder(sc)
    obs = file_in(data, base, "source.rinex_obs", "rinex_obs")
    nav = file_in(data, base, "source.rinex_nav", "rinex_nav")
    name = sc.core["tight"]["sensor"]
    sensor = next(s for s in sc.core["sensors"] if s["name"] == name)
    letters = {"gps": "G", "galileo": "E", "beidou": "C", "qzss": "J"}
    rs = sensor.get("ranges", {})
    systems = [letters[s] for s in rs.get("systems", ["gps"]) if s in letters]
    # The tight filter's own σ model (elevation, factor 1): the residuals normalised by it are
    # what its range-error models are estimated from.
    return obs, gnss_solve(obs, nav, systems=systems, mask_deg=math.degrees(float(rs.get("elevation_mask", 0.0))), exclude=True,
                           weighting="elevation", noise_scale=1.0)


def _residual_arcs(sc: Any) -> tuple[Path, Any, list[tuple[np.ndarray, np.ndarray]]]:
    """The scenario's RINEX log solved (:func:`solve_rinex_source`) and its used satellites'
    normalised residuals ``r/σ``, one ``(epoch indices, values)`` arc per satellite."""
    obs, sol = solve_rinex_source(sc)
    st = sol.satellites
    used = st[st["status"] == "used"]
    arcs = []
    for _, g in used.groupby("satellite", observed=True):
        z = g["residual"].to_numpy(float) / g["sigma"].to_numpy(float)
        arcs.append((g["epoch"].to_numpy(np.int64), z))
    return obs, sol, arcs


def range_error_overbound(sc: Any) -> tuple[float, dict[str, Any]]:
    """The variance factor of ``[tight.integrity] range_errors = "overbound"`` for a tight
    scenario on a recorded RINEX log: the log is solved epoch by epoch
    (:func:`navfdi.gnss_solve`, the scenario's systems and elevation mask, with FDE) and the
    integrated autocorrelation time (:func:`integrated_autocorrelation`, in the log's epochs)
    of the used satellites' normalised residuals ``r/σ``, one arc per satellite, is the
    factor. Returns it (≥ 1) and the details (``rho1``, ``lags`` summed, ``arcs``,
    ``samples``). The reference positions are not used."""
    obs, sol, arcs = _residual_arcs(sc)
    try:
        tau, rho = integrated_autocorrelation(arcs)
    except ValueError as e:
        raise ScenarioError(f"tight.integrity.range_errors = 'overbound': {obs.name}: {e}") from None
    return float(min(tau, 1e4)), {"rho1": float(rho[1]), "lags": int(len(rho) - 1), "arcs": len(arcs), "samples": int(sum(len(a[1]) for a in arcs))}


def range_error_process(sc: Any, max_lag: int = 300) -> tuple[float, float, dict[str, Any]]:
    """The first-order Gauss-Markov model of ``[tight] range_states = "auto"`` for a tight
    scenario on a recorded RINEX log: the log is solved epoch by epoch
    (:func:`solve_rinex_source`) and the autocorrelation ``ρ(L)`` of the used satellites'
    normalised residuals ``r/σ`` (pooled over one arc per satellite,
    :func:`integrated_autocorrelation`) is fitted by ``ρ(L) = a exp(−L Δt/τ)`` for ``L ≥ 1``
    (least squares on ``ln ρ`` over the lags before ``ρ`` first falls below 0.05, at most
    ``max_lag``): ``a`` is the correlated share of the variance (lag 0 holds the white rest),
    ``τ`` the correlation time (s; ``Δt`` the log's median epoch interval). Returns
    ``(fraction, tau, details)`` with ``fraction`` clipped to [0, 0.95] and ``tau`` to
    [Δt, 3600 s]; a series with ``ρ(1) < 0.05`` is white (fraction 0). The reference positions
    are not used; the residuals of a snapshot fit hold only the part of each satellite's error
    that the position and clock do not absorb, so the fit describes that part."""
    obs, sol, arcs = _residual_arcs(sc)
    gps = sol.solution["gps_seconds"].to_numpy(float)
    dt = float(np.median(np.diff(gps))) if len(gps) > 1 else math.nan
    if not (dt > 0):
        raise ScenarioError(f"tight.range_states = 'auto': {obs.name}: fewer than two epochs solved")
    try:
        _, rho = integrated_autocorrelation(arcs, max_lag=max_lag)
    except ValueError as e:
        raise ScenarioError(f"tight.range_states = 'auto': {obs.name}: {e}") from None
    lags, vals = [], []
    for lag in range(1, len(rho)):
        r = float(rho[lag])
        if not (r >= 0.05):
            break
        lags.append(lag)
        vals.append(math.log(r))
    details: dict[str, Any] = {"rho1": float(rho[1]), "lags": len(lags), "arcs": len(arcs), "dt": dt,
                               "samples": int(sum(len(a[1]) for a in arcs))}
    if not lags:
        return 0.0, dt, details
    if len(lags) == 1:
        slope, icpt = math.log(0.05) - vals[0], vals[0] - (math.log(0.05) - vals[0])
    else:
        slope, icpt = (float(v) for v in np.polyfit(np.asarray(lags, float), np.asarray(vals), 1))
    tau = dt * (-1.0 / slope) if slope < 0 else 3600.0
    return float(min(max(math.exp(icpt), 0.0), 0.95)), float(min(max(tau, dt), 3600.0)), details


def resolve_range_errors(sc: Any) -> Any:
    """``sc`` with ``[tight.integrity] range_errors = "overbound"`` replaced by its estimated
    variance factor (:func:`range_error_overbound`; the scenario's pseudorange noise is then
    scaled by its square root) and ``[tight] range_states = "auto"`` by its estimated model
    (:func:`range_error_process`), in the scenario and in the ``[[variants]]`` that set them,
    or ``sc`` itself. A variant left with either unresolved is refused by name."""
    from navfdi._lc_schema import range_error_factor

    import copy

    out = sc
    memo: dict[str, Any] = {}

    def factor() -> float:
        if "f" not in memo:
            memo["f"] = round(range_error_overbound(sc)[0], 3)
        return memo["f"]

    def process() -> dict[str, Any]:
        if "p" not in memo:
            a, tau, _ = range_error_process(sc)
            memo["p"] = {"fraction": round(a, 4), "tau": f"{tau:.4g} s"}
        return memo["p"]

    if range_error_factor(sc.raw) == "overbound":
        out = out.with_values({"tight.integrity.range_errors": factor()})
    if (sc.raw.get("tight") or {}).get("range_states") == "auto":
        out = out.with_values({"tight.range_states": process()})
    # Variants that ask for them: the same estimates (one solve of the log).
    vs = copy.deepcopy(out.raw.get("variants"))
    if isinstance(vs, list):
        changed = False
        for v in vs:
            sets = v.get("set") if isinstance(v, dict) else None
            if not isinstance(sets, dict):
                continue
            if sets.get("tight.range_states") == "auto":
                sets["tight.range_states"], changed = process(), True
            if sets.get("tight.integrity.range_errors") == "overbound":
                sets["tight.integrity.range_errors"], changed = factor(), True
        if changed:
            out = out.with_values({"variants": vs})
        for name, v in out.variants():
            t = v.raw.get("tight") or {}
            if t.get("range_states") == "auto" or (t.get("integrity") or {}).get("range_errors") == "overbound":
                raise ScenarioError(f"variant {name!r}: its range-error model (\"auto\" / \"overbound\") is estimated from the log only when the "
                                    "variant sets tight.range_states or tight.integrity.range_errors by that path; set it so, or give the values")
    return out
