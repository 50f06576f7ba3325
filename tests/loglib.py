"""Helpers of the tests on recorded-log scenarios: a scenario file run with given faults, the
horizontal error of a run, the same fault-free with FDE and without, and a GNSS log written as NMEA sentences."""

from __future__ import annotations

import datetime as dt
import math
from pathlib import Path

import numpy as np

import navfdi
from navfdi._logtime import GPS_EPOCH
from navfdi.scenario import from_dict, load_scenario


def run_log(path: Path, faults: list[dict] | None = None) -> navfdi.ScenarioRun:
    """The scenario file ``path`` run with ``faults`` (its own left out; none: fault-free)."""
    raw = dict(load_scenario(str(path)).raw)
    raw.pop("faults", None)
    if faults:
        raw["faults"] = faults
    return navfdi.run_scenario(from_dict(raw, source=str(path)))


def run_log_with_and_without_fde(path: Path, faults: list[dict] | None = None) -> dict[str, navfdi.ScenarioRun]:
    """The scenario file ``path`` run on the same measurements twice — fault-free (its own
    faults left out) or with ``faults`` (scenario fault tables) injected: variant ``fde`` as
    written, ``no_fde`` with ``loosely_coupled.isolate = false``."""
    raw = dict(load_scenario(str(path)).raw)
    raw.pop("faults", None)
    if faults:
        raw["faults"] = faults
    raw["variants"] = [{"name": "fde"}, {"name": "no_fde", "set": {"loosely_coupled.isolate": False}}]
    return dict(navfdi.run_scenario(from_dict(raw, source=str(path))).runs)


def horizontal_error(run: navfdi.RunRecordView) -> np.ndarray:
    """Horizontal error per epoch (m; NaN where not scored)."""
    e = run.record["error"]
    return np.hypot(e[:, 6], e[:, 7])


def nmea(body: str) -> str:
    """An NMEA sentence with its checksum."""
    cs = 0
    for ch in body:
        cs ^= ord(ch)
    return f"${body}*{cs:02X}"


def nmea_lines(p: object, undulation: float, rmc: bool = True) -> list[str]:
    """A :class:`navfdi.logs.PosLog` as NMEA: per epoch ``GNGGA`` (altitude above sea level =
    height − ``undulation``, with the geoid separation), ``GNRMC`` (date, speed, course; if
    ``rmc``) and ``GNGST`` (σ latitude, longitude, altitude). Times UTC (GPST − 18 s)."""
    lines = []
    for k in range(len(p.t)):  # type: ignore[attr-defined]
        utc = GPS_EPOCH + dt.timedelta(seconds=float(p.t[k]) - 18.0)  # type: ignore[attr-defined]
        hms = utc.strftime("%H%M%S.") + f"{utc.microsecond // 10000:02d}"
        la, lo = p.lat[k], p.lon[k]  # type: ignore[attr-defined]
        lat = f"{int(abs(la)):02d}{(abs(la) - int(abs(la))) * 60:010.7f}"
        lon = f"{int(abs(lo)):03d}{(abs(lo) - int(abs(lo))) * 60:010.7f}"
        ns, ew = ("N" if la >= 0 else "S"), ("E" if lo >= 0 else "W")
        height, vel, sd = p.height[k], p.vel[k], p.sd_pos[k]  # type: ignore[attr-defined]
        lines.append(nmea(f"GNGGA,{hms},{lat},{ns},{lon},{ew},1,12,0.8,{height - undulation:.4f},M,{undulation:.4f},M,,"))
        if rmc:
            sp = math.hypot(vel[0], vel[1]) / 0.514444
            cog = math.degrees(math.atan2(vel[0], vel[1])) % 360
            lines.append(nmea(f"GNRMC,{hms},A,{lat},{ns},{lon},{ew},{sp:.4f},{cog:.3f},{utc.strftime('%d%m%y')},,,A"))
        lines.append(nmea(f"GNGST,{hms},1.0,0.5,0.4,30.0,{sd[1]:.4f},{sd[0]:.4f},{sd[2]:.4f}"))
    return lines
