"""Time as users have it, for scenarios on recorded logs: fault, outage and draw windows in
GPS time (``"2374:243500.0"``, GPS week and seconds of week, or an ISO date-time with its
time scale, ``"2025-07-08T19:25:00 GPST"`` / ``"… UTC"``) as well as in seconds from the
first GNSS epoch, and ``duration`` / ``dt`` taken from the GNSS log when omitted.

:func:`resolve_log_times` rewrites a scenario's user table before it is converted: every
window time in GPS form becomes seconds from the log's first epoch (``"1234.5 s"``), and
missing ``duration`` / ``dt`` become the log's span and median interval."""

from __future__ import annotations

import datetime as _dt
import functools
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from navfdi._errors import ScenarioError

__all__ = ["GPS_EPOCH", "gpst_text", "gps_seconds", "log_epochs", "resolve_log_times", "pos_time", "LEAP_SECONDS", "utc_to_gps", "unix_to_gps", "utc_count_to_gps",
           "TIME_UNITS", "time_unit"]

GPS_EPOCH = _dt.datetime(1980, 1, 6)
_WEEK = 604800.0
#: GPS − UTC (s) from each date on (IERS Bulletin C; 18 s since 2017-01-01).
LEAP_SECONDS = [(_dt.datetime(2006, 1, 1), 14), (_dt.datetime(2009, 1, 1), 15), (_dt.datetime(2012, 7, 1), 16),
                (_dt.datetime(2015, 7, 1), 17), (_dt.datetime(2017, 1, 1), 18)]

_WEEK_SOW = re.compile(r"^\s*(\d{1,5})\s*:\s*(\d+(?:\.\d*)?)\s*$")
_ISO = re.compile(r"^\s*(\d{4}-\d{2}-\d{2})[T ](\d{2}:\d{2}:\d{2}(?:\.\d+)?)\s*(GPST|UTC)\s*$", re.IGNORECASE)


def utc_to_gps(d: _dt.datetime) -> float:
    """GPS seconds since 1980-01-06 of the UTC date-time ``d`` (the leap seconds of its date)."""
    leap = next((n for since, n in reversed(LEAP_SECONDS) if d >= since), 13)
    return (d - GPS_EPOCH).total_seconds() + leap


#: Seconds per unit of a numeric time column (``time_unit``).
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
#: Unix time (s since 1970-01-01 UTC) of the GPS epoch.
_UNIX_GPS_EPOCH = 315_964_800.0


def unix_to_gps(t: np.ndarray) -> np.ndarray:
    """GPS seconds since 1980-01-06 of Unix times ``t`` (s since 1970-01-01 UTC, leap seconds
    not counted), with the leap seconds of each time's date (:data:`LEAP_SECONDS`)."""
    return utc_count_to_gps(np.asarray(t, dtype=float) - _UNIX_GPS_EPOCH)


def utc_count_to_gps(utc: np.ndarray) -> np.ndarray:
    """GPS seconds of UTC times ``utc`` counted in seconds from 1980-01-06 00:00 UTC (a UTC
    calendar time read as if it were GPST): plus the leap seconds of each time's date."""
    utc = np.asarray(utc, dtype=float)
    leap = np.full(utc.shape, 13.0)
    for since, n in LEAP_SECONDS:
        leap[utc >= (since - GPS_EPOCH).total_seconds()] = n
    return utc + leap


def gpst_text(t: float) -> str:
    """GPS seconds ``t`` (since the GPS epoch) as ``YYYY-MM-DD HH:MM:SS.mmm`` (GPS time)."""
    return (GPS_EPOCH + _dt.timedelta(seconds=float(t))).strftime("%Y-%m-%d %H:%M:%S.%f")[:-3]


def time_unit(value: Any, field: str) -> float:
    """Seconds per unit of ``value`` (``"s"``, ``"ms"``, ``"us"``, ``"ns"``); ScenarioError
    naming ``field`` otherwise."""
    if not isinstance(value, str) or value not in TIME_UNITS:
        raise ScenarioError(f"{field} = {value!r}: one of {', '.join(TIME_UNITS)}")
    return TIME_UNITS[value]


@functools.lru_cache(maxsize=64)
def _day_start(date: str) -> float:
    """GPS seconds of 00:00 GPST on ``yyyy/mm/dd`` (a log has few dates: cached)."""
    return (_dt.datetime.strptime(date, "%Y/%m/%d") - GPS_EPOCH).total_seconds()


def pos_time(tok0: str, tok1: str) -> float:
    """GPS seconds of an RTKLIB ``.pos`` time: ``yyyy/mm/dd hh:mm:ss.sss`` or week and seconds.
    Raises ValueError for anything else (a field out of its range included)."""
    if "/" in tok0:
        hms = tok1.split(":")
        if len(hms) != 3 or not all(hms) or not (hms[0].isdigit() and hms[1].isdigit()):
            raise ValueError(tok1)
        h, m, sec = int(hms[0]), int(hms[1]), float(hms[2])
        if not (h < 24 and m < 60 and 0.0 <= sec < 61.0) or not hms[2][0].isdigit():
            raise ValueError(tok1)
        return _day_start(tok0) + h * 3600.0 + m * 60.0 + sec
    return float(tok0) * _WEEK + float(tok1)


def gps_seconds(value: Any, field: str) -> float | None:
    """GPS seconds since 1980-01-06 of a time given in GPS form (``"WEEK:SOW"`` or an ISO
    date-time followed by ``GPST`` or ``UTC``); None for anything else (a duration such as
    ``"440 s"``). A malformed GPS form raises :class:`ScenarioError` naming ``field``."""
    if not isinstance(value, str):
        return None
    m = _WEEK_SOW.match(value)
    if m:
        week, sow = int(m.group(1)), float(m.group(2))
        if not sow < _WEEK:
            raise ScenarioError(f"{field} = {value!r}: seconds of week must be below 604800")
        return week * _WEEK + sow
    m = _ISO.match(value)
    if m:
        try:
            d = _dt.datetime.fromisoformat(f"{m.group(1)}T{m.group(2)}")
        except ValueError:
            raise ScenarioError(f"{field} = {value!r}: not a date and time (YYYY-MM-DDTHH:MM:SS GPST|UTC)") from None
        return utc_to_gps(d) if m.group(3).upper() == "UTC" else (d - GPS_EPOCH).total_seconds()
    if re.match(r"^\s*\d{4}-\d{2}-\d{2}[T ]", value) or ":" in value:
        raise ScenarioError(f"{field} = {value!r}: a GPS time is 'WEEK:SECONDS' (e.g. \"2374:243500.0\") or "
                            "'YYYY-MM-DDTHH:MM:SS GPST' (or UTC)")
    return None


#: Readers of a ``[source] gnss`` entry's epoch times (GPS s), registered by
#: :mod:`navfdi.gnss_logs` (which reads every format it accepts).
EPOCH_READERS: list[Any] = []


def _folder(source: str) -> Path:
    from importlib import resources

    from navfdi._bundled import bundled_scenarios

    if source in bundled_scenarios():
        return Path(str(resources.files("navfdi") / "scenarios"))
    p = Path(source)
    return p.parent if p.suffix == ".toml" else Path.cwd()


def log_epochs(src: Mapping[str, Any], source: str) -> tuple[np.ndarray | None, str]:
    """GPS seconds of the GNSS log's epochs (``[source] gnss`` in any format
    :mod:`navfdi.gnss_logs` reads, through :data:`EPOCH_READERS`; or ``rinex_obs``), and ``""``;
    or None and the reader's reason when the file cannot be read."""
    base = _folder(source)
    if src.get("gnss") is not None and EPOCH_READERS:
        try:
            return np.asarray(EPOCH_READERS[0](src["gnss"], base), dtype=float), ""
        except ScenarioError as e:
            return None, str(e)
    if isinstance(src.get("rinex_obs"), str):
        from navfdi import _core

        try:
            return np.asarray(_core.read_rinex_obs(str(base / src["rinex_obs"]))["epoch_times"], dtype=float), ""
        except (OSError, ValueError) as e:
            return None, str(e)
    return None, "no [source] gnss or rinex_obs"


def _windows(raw: Mapping[str, Any]) -> list[tuple[list[Any], int, str]]:
    """Every window time of the table: (container, index, field name)."""
    out: list[tuple[list[Any], int, str]] = []
    for i, s in enumerate(raw.get("sensors") or []):
        if isinstance(s, dict):
            for j, w in enumerate(s.get("outages") or []):
                if isinstance(w, list):
                    out += [(w, k, f"sensors[{i}].outages[{j}][{k}]") for k in range(len(w))]
    for i, f in enumerate(raw.get("faults") or []):
        if isinstance(f, dict):
            box = [f.get("start"), f.get("end")]
            out += [(box, 0, f"faults[{i}].start"), (box, 1, f"faults[{i}].end")]
            d = f.get("draw")
            if isinstance(d, dict) and isinstance(d.get("start"), list):
                out += [(d["start"], k, f"faults[{i}].draw.start[{k}]") for k in range(len(d["start"]))]
    return out


def resolve_log_times(raw: Mapping[str, Any], source: str) -> Mapping[str, Any]:
    """``raw`` with GPS-form window times turned into seconds from the GNSS log's first
    epoch and missing ``duration`` / ``dt`` filled from the log; ``raw`` itself when it needs
    neither (or has no ``[source]``)."""
    src = raw.get("source")
    if not isinstance(src, Mapping):
        return raw
    gps = [(box, k, name, s) for box, k, name in _windows(raw) if (s := gps_seconds(box[k], name)) is not None]
    missing = [k for k in ("duration", "dt") if k not in raw]
    if not gps and not missing:
        return raw
    t, why = log_epochs(src, source)
    if t is None or len(t) < 2:
        why = why or f"{0 if t is None else len(t)} epoch(s)"
        if missing:
            raise ScenarioError(f"{', '.join(missing)}: not given, and the GNSS log's epochs could not be read to take "
                                f"{'them' if len(missing) > 1 else 'it'} from (give {' and '.join(missing)} or check [source]): {why}")
        raise ScenarioError(f"{gps[0][2]}: a GPS time, but the GNSS log's epochs could not be read to place it: {why}")
    out = {k: v for k, v in raw.items()}
    t0 = float(t[0])
    span = float(t[-1] - t0)
    if "duration" in missing:
        out["duration"] = f"{span!r} s"
    if "dt" in missing:
        out["dt"] = f"{float(np.median(np.diff(t)))!r} s"
    if gps:
        import copy

        out["sensors"] = copy.deepcopy(raw.get("sensors"))
        out["faults"] = copy.deepcopy(raw.get("faults"))
        for _, k, name, s in gps:
            rel = s - t0
            if not -1.0 <= rel <= span + 3600.0:
                raise ScenarioError(f"{name}: GPS time {s:.3f} s is {rel:+.1f} s from the GNSS log's first epoch "
                                    f"(the log spans {span:g} s): not this log's time")
            # Write it back where it came from.
            _set(out, name, f"{rel!r} s")
    return out


def _set(table: dict[str, Any], path: str, value: str) -> None:
    parts: list[Any] = [p if p else int(i) for p, i in re.findall(r"([A-Za-z_]\w*)|\[(\d+)\]", path)]
    node: Any = table
    for p in parts[:-1]:
        node = node[p]
    node[parts[-1]] = value
