"""GNSS solution logs in the formats receivers and tools write, read into one
:class:`~navfdi.logs.PosLog` for the loosely coupled filter.

``[source] gnss`` is a path or a table ``{ file = …, format = …, … }``. Formats:

* ``pos`` — an RTKLIB solution (``.pos``; :func:`navfdi.logs.read_pos`);
* ``solution`` — ``navfdi gnss``'s own ``solution.csv`` (``gps_seconds``, ``lat``, ``lon``,
  ``height``, ``sd_e/n/u`` when present, ``vel_e/n/u``, ``used``; epochs without a solution are left
  out; without σ columns the sensors' ``noise`` is used);
* ``rinex`` — RINEX observation and navigation files, solved epoch by epoch by navfdi's own
  single-point positioning with satellite FDE (:func:`navfdi.gnss.gnss_solve`) as the log is
  read: ``obs``, ``nav`` (paths), ``systems`` (letters, default ``["G"]``),
  ``elevation_mask`` (angle, default ``"10 deg"``), ``weighting`` (``elevation``, ``cn0``,
  ``rtklib``), ``test`` (``global``, ``wtest``, ``both``, ``auto``). σ east, north, up from
  the geometry and the solve's weights (:func:`navfdi._gnss_geometry.enu_sigma`), velocity from the
  Doppler; the same as writing ``solution.csv`` with ``navfdi gnss`` and reading it;
* ``nmea`` — NMEA 0183 sentences: ``GGA`` (position; the height above the ellipsoid is the
  altitude above mean sea level plus the geoid separation the sentence gives; or ``GNS``, the
  multi-constellation fix, where an epoch has no ``GGA``), ``RMC`` (date,
  speed and course → horizontal velocity), ``VTG`` (speed and course), ``GST`` (σ of latitude,
  longitude and altitude). Times are UTC, turned into GPST with the leap seconds; a log without
  ``RMC`` needs ``date = "YYYY-MM-DD"`` in the table. Sentences with a bad checksum are
  refused with their line;
* ``ubx`` — a u-blox binary log (``.ubx``, ``.ubx.gz``): the receiver's UBX-NAV-PVT solutions
  (:func:`read_ubx`; other messages skipped);
* ``gnsslogger`` — an Android GnssLogger file's ``Fix`` records of one ``provider`` (default
  ``"GPS"``; :func:`read_gnsslogger_fixes`): positions and their 68 %
  accuracies as σ, no velocity;
* ``rosbag`` — a ROS 1 ``.bag`` file or ROS 2 bag folder: a ``sensor_msgs/NavSatFix``
  ``topic`` (the bag's only one by default), with ``velocity_topic`` (east, north, up twists)
  and ``time_scale`` (``"unix"``, ROS time; or ``"gpst"``) (:func:`read_ros_fixes`);
* ``csv`` — any CSV with a ``columns`` mapping: ``time`` (one column of GPS seconds, or
  ``[week, seconds]``, or an ISO date-time column with ``time_scale = "utc"`` or ``"gpst"``),
  ``lat``, ``lon`` (deg), ``height`` (m above the ellipsoid; or ``height_msl`` with
  ``undulation`` m) — or ``ecef`` (three columns x, y, z, m, WGS 84 Earth-centred
  Earth-fixed; a row of zeros is no fix) —, optional ``sd`` (three columns σ east, north, up,
  m), ``vel`` (three columns east, north, up, m/s), ``sd_vel``, each also as ECEF x, y, z
  columns (``sd_ecef``, ``vel_ecef``, ``sd_vel_ecef``: turned to east, north, up at the fix; σ
  as a diagonal covariance), ``satellites`` (the count the receiver used).

Every format: fixes from fewer than four satellites (where the log gives the count: ``.pos``
``ns``, ``GGA``, ``solution.csv``'s ``used``, a CSV's ``satellites``) are left out, and so are
``GGA`` fixes of quality 6–8 (dead reckoning, manual, simulator), each with a
:class:`~navfdi.LeftOutFixesWarning` saying how many and from when.

Without a ``format`` it is told from the file: ``.pos`` / ``.pos.gz``, ``.ubx`` / ``.ubx.gz`` or
UBX sync bytes at the start, a CSV whose header has
``gps_seconds`` and ``lat`` (``solution``), lines that start with ``$`` (``nmea``), GnssLogger's
``#`` lines or records (``gnsslogger``).
"""

from __future__ import annotations

import csv
import datetime as _dt
import gzip
import io
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from navfdi._errors import ScenarioError
from navfdi._schema import SECTIONS, keys
from navfdi._logtime import EPOCH_READERS, GPS_EPOCH, time_unit, unix_to_gps, utc_to_gps
from navfdi.logs import PosLog, _gpst, read_pos, repeated_rows, text_layout

__all__ = ["read_gnss", "read_solution_csv", "read_nmea", "read_gnss_csv", "read_gnsslogger_fixes", "read_ros_fixes", "FORMATS"]

#: The formats ``[source] gnss`` accepts.
FORMATS = ("pos", "solution", "nmea", "csv", "rinex", "ubx", "gnsslogger", "rosbag")
#: The keys of ``format = "rinex"`` beside ``format`` (:data:`navfdi._schema.SECTIONS`).
RINEX_KEYS = tuple(k for k in SECTIONS["source.gnss.rinex"].keys if k != "format")


def _text(path: Path) -> str:
    try:
        raw = path.read_bytes()
    except OSError as e:
        raise ScenarioError(f"source.gnss: {path}: {e.strerror or e}") from None
    if raw[:2] == b"\x1f\x8b":
        raw = gzip.decompress(raw)
    return raw.decode("utf-8-sig", errors="replace")


def _starts_with_ubx(path: Path) -> bool:
    """The file (or its gzip content) starts with the UBX sync bytes 0xB5 0x62."""
    try:
        with open(path, "rb") as f:
            head = f.read(2)
        if head == b"\x1f\x8b":
            with gzip.open(path, "rb") as g:
                head = g.read(2)
    except OSError:
        return False
    return head == b"\xb5\x62"


def read_ubx(path: str | Path) -> PosLog:
    """The UBX-NAV-PVT solutions of a u-blox binary log (``.ubx``, ``.gz`` accepted; in Rust,
    ``navfdi_core::logs::ubx``): GPS time from the receiver's UTC time (to the nanosecond)
    where it marks it valid and resolved, else its time of week in that week; latitude, longitude, height above the ellipsoid, velocity east/north/up (``−velD`` up),
    σ east = σ north = ``hAcc/√2``, σ up = ``vAcc``, σ of each velocity axis ``sAcc/√3``,
    quality 1 (carrier fixed), 2 (float), 4 (differential) or 5 (single), the satellites
    used. Solutions that are not a 3-D fix (fix type other than 3-D or GNSS + dead reckoning)
    or that the receiver does not mark valid (``gnssFixOK``) are left out, and packets with a
    bad checksum skipped, each with a :class:`~navfdi.LeftOutFixesWarning`. Raises
    :class:`~navfdi.ScenarioError` for a file that is not a UBX log, has no NAV-PVT, or no
    valid fix."""
    from navfdi import _core

    path = Path(path)
    try:
        d = _core.read_ubx(str(path))
    except (OSError, ValueError) as e:
        raise ScenarioError(f"source.gnss: {e}") from None
    if d["corrupt"]:
        import warnings

        from navfdi._errors import LeftOutFixesWarning

        warnings.warn(f"source.gnss: {path}: {d['corrupt']} UBX packet(s) with a bad checksum or length skipped", LeftOutFixesWarning, stacklevel=2)
    t, llh, acc, vel, st = d["t"], d["llh"], d["acc"], d["vel_ned"], d["status"].astype(int)
    fix, flags = st[:, 1], st[:, 2]
    three_d = (fix == 3) | (fix == 4)
    ok = three_d & (flags & 1 == 1)
    if not ok.any():
        raise ScenarioError(f"source.gnss: {path}: no NAV-PVT solution is a valid 3-D fix ({len(t)} messages)")
    if (~three_d).any():
        _left_out(path, t[~three_d], "without a 3-D fix (no fix, dead reckoning only, 2-D or time only)")
    if (three_d & ~ok).any():
        _left_out(path, t[three_d & ~ok], "not marked valid by the receiver (gnssFixOK off: outside its accuracy masks)")
    carr = (flags >> 6) & 3
    q = np.where(carr == 2, 1, np.where(carr == 1, 2, np.where(flags & 2 == 2, 4, 5))).astype(float)
    h = acc[:, 0] / math.sqrt(2.0)
    sd_pos = np.column_stack([h, h, acc[:, 1]])
    sd_vel = np.repeat(acc[:, 2:3] / math.sqrt(3.0), 3, axis=1)
    v_enu = np.column_stack([vel[:, 1], vel[:, 0], -vel[:, 2]])
    return PosLog(t[ok], llh[ok, 0], llh[ok, 1], llh[ok, 2], q[ok], v_enu[ok], sd_pos[ok], sd_vel[ok], str(path), st[ok, 0].astype(float))


def _guess(path: Path, text: str) -> str:
    name = path.name.lower()
    if name.endswith((".pos", ".pos.gz")):
        return "pos"
    first = next((ln for ln in text.splitlines() if ln.strip()), "")
    if first.startswith("$") or first.startswith("!"):
        return "nmea"
    if "gps_seconds" in first and "lat" in first.split(","):
        return "solution"
    from navfdi.gnsslogger import is_gnsslogger

    if is_gnsslogger(text):
        return "gnsslogger"
    if first.startswith("%"):
        return "pos"
    raise ScenarioError(f"source.gnss: {path}: format not recognised (an RTKLIB .pos, navfdi's solution.csv, NMEA or a GnssLogger file); "
                        "give source.gnss = { file = …, format = \"csv\", columns = { … } } for another CSV")


def read_gnss(spec: Any, base: Path) -> PosLog:
    """Read ``[source] gnss`` (a path, or a table with ``file``, ``format`` and its options)
    relative to ``base``. Raises :class:`ScenarioError` naming the file, line and field of bad
    input. Fixes the log says were solved from fewer than four satellites are left out
    (:func:`three_d_fixes`)."""
    return three_d_fixes(_read_gnss(spec, base))


def read_reference(spec: Any, base: Path) -> tuple[PosLog, bool]:
    """Read ``[source] reference``: an RTKLIB ``.pos`` path as before, or any GNSS log format
    as ``[source] gnss`` takes it (a path told by its content, or a table with ``file``,
    ``format`` and its options; not ``rinex``: a reference is a solution). Returns the log and
    whether its qualities mean anything (False for a ``csv``, which has no quality column, and
    for a GnssLogger file or a ROS bag, whose fixes say no RTK-fixed quality: all their epochs
    are the reference). Messages and warnings name ``source.reference``."""
    import warnings

    if isinstance(spec, str) and spec.lower().endswith((".pos", ".pos.gz")):
        return read_pos(spec if Path(spec).is_absolute() else base / spec), True
    cfg: Mapping[str, Any] = spec if isinstance(spec, Mapping) else {"file": spec}
    if cfg.get("format") == "rinex":
        raise ScenarioError("source.reference: format = \"rinex\" is a solve, not a reference; give the reference's solution (a .pos, NMEA, UBX or CSV log)")
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        try:
            log = _read_gnss(cfg, base)
        except ScenarioError as e:
            raise ScenarioError(str(e).replace("source.gnss", "source.reference")) from None
    for w in said:
        warnings.warn_explicit(str(w.message).replace("source.gnss", "source.reference"), w.category, w.filename, w.lineno)
    return log, _format_of(cfg, base) not in ("csv", "gnsslogger", "rosbag")


#: Fewest satellites of a 3-D fix (three coordinates and the receiver clock).
MIN_SATELLITES = 4


def three_d_fixes(pos: PosLog) -> PosLog:
    """``pos`` without the epochs whose satellite count (``ns``) is below
    :data:`MIN_SATELLITES`: no 3-D solution (a receiver holding its height or extrapolating its
    last fix writes such epochs), said in a :class:`~navfdi.LeftOutFixesWarning`; epochs with no
    count (NaN, or 0 as converters write) are kept. Refuses a log with nothing left."""
    if pos.ns is None:
        return pos
    # A count of 0 is no count: tools that write other solutions as RTKLIB's .pos fill 0.
    few = np.isfinite(pos.ns) & (pos.ns > 0) & (pos.ns < MIN_SATELLITES)
    if not few.any():
        return pos
    if few.all():
        raise ScenarioError(f"source.gnss: {pos.path}: every fix is from fewer than {MIN_SATELLITES} satellites (no 3-D solution)")
    _left_out(pos.path, pos.t[few], f"from fewer than {MIN_SATELLITES} satellites (no 3-D solution: a held height or an extrapolated fix)")
    return pos.select(~few)


def _left_out(path: str | Path, t: np.ndarray, why: str) -> None:
    """A :class:`~navfdi.LeftOutFixesWarning`: ``len(t)`` fixes of ``path`` left out, ``why``."""
    import warnings

    from navfdi._errors import LeftOutFixesWarning

    warnings.warn(f"source.gnss: {path}: {len(t)} fix(es) {why} left out (the first at {_gpst(t[0])} GPST)", LeftOutFixesWarning, stacklevel=2)


def _read_gnss(spec: Any, base: Path) -> PosLog:
    cfg: Mapping[str, Any] = spec if isinstance(spec, Mapping) else {"file": spec}
    if cfg.get("format") == "rinex":
        return read_rinex_solution(cfg, base)
    allowed = keys("source.gnss")
    unknown = sorted(set(cfg) - allowed)
    if unknown:
        raise ScenarioError(f"source.gnss: unknown key(s) {', '.join(unknown)} (allowed: {', '.join(sorted(allowed))})")
    f = cfg.get("file")
    if not isinstance(f, str):
        raise ScenarioError("source.gnss: a file path is required")
    path = Path(f) if Path(f).is_absolute() else base / f
    fmt = cfg.get("format")
    if fmt is not None and fmt not in FORMATS:
        raise ScenarioError(f"source.gnss.format = {fmt!r}: one of {', '.join(FORMATS)}")
    if fmt == "pos" or (fmt is None and path.name.lower().endswith((".pos", ".pos.gz"))):
        return _only(cfg, "pos", read_pos(path))
    if fmt == "ubx" or (fmt is None and (path.name.lower().endswith((".ubx", ".ubx.gz")) or _starts_with_ubx(path))):
        return _only(cfg, "ubx", read_ubx(path))
    from navfdi.rosbag import is_rosbag

    if fmt == "rosbag" or (fmt is None and is_rosbag(path)):
        return _only(cfg, "rosbag", read_ros_fixes(path, cfg.get("topic"), cfg.get("velocity_topic"), cfg.get("time_scale", "unix")))
    text = _text(path)
    fmt = fmt or _guess(path, text)
    if fmt == "pos":
        return _only(cfg, "pos", read_pos(path))
    if fmt == "solution":
        return _only(cfg, "solution", read_solution_csv(path, text))
    if fmt == "nmea":
        return _only(cfg, "nmea", read_nmea(path, text, cfg.get("date")))
    if fmt == "gnsslogger":
        return _only(cfg, "gnsslogger", read_gnsslogger_fixes(path, cfg.get("provider", "GPS")))
    return _only(cfg, "csv", read_gnss_csv(path, text, cfg))


def _format_of(cfg: Mapping[str, Any], base: Path) -> str:
    """The format a ``[source] gnss`` table names, or the one :func:`_read_gnss` tells from its
    file (the file already read without error)."""
    if isinstance(cfg.get("format"), str):
        return str(cfg["format"])
    path = Path(cfg["file"]) if Path(cfg["file"]).is_absolute() else base / cfg["file"]
    if path.name.lower().endswith((".pos", ".pos.gz")):
        return "pos"
    if path.name.lower().endswith((".ubx", ".ubx.gz")) or _starts_with_ubx(path):
        return "ubx"
    from navfdi.rosbag import is_rosbag

    if is_rosbag(path):
        return "rosbag"
    return _guess(path, _text(path))


#: ``[source.gnss]`` keys that only one format reads.
_FORMAT_KEYS = {"columns": ("csv",), "time_scale": ("csv", "rosbag"), "time_unit": ("csv",), "gps_week": ("csv",), "header": ("csv",),
                "delimiter": ("csv",), "undulation": ("csv",), "date": ("nmea",), "provider": ("gnsslogger",), "topic": ("rosbag",),
                "velocity_topic": ("rosbag",)}


def _only(cfg: Mapping[str, Any], fmt: str, log: PosLog) -> PosLog:
    """``log``, or an error for a key of ``cfg`` that another format reads (it would be ignored)."""
    for k, owners in _FORMAT_KEYS.items():
        if k in cfg and fmt not in owners:
            owner = " or ".join(f"format = \"{o}\"" for o in owners)
            raise ScenarioError(f"source.gnss.{k}: read for {owner} only; this log is read as {fmt} (give {owner} "
                                f"if the file is one, or leave {k} out)")
    return log


def _log(path: Path, t: np.ndarray, lat: np.ndarray, lon: np.ndarray, h: np.ndarray, vel: np.ndarray, sd: np.ndarray, sd_vel: np.ndarray,
         q: np.ndarray | None = None, ns: np.ndarray | None = None) -> PosLog:
    ok = np.isfinite(t) & np.isfinite(lat) & np.isfinite(lon) & np.isfinite(h)
    if not ok.any():
        raise ScenarioError(f"source.gnss: {path}: no epoch with a position")
    order = np.argsort(t[ok], kind="stable")
    sel = np.flatnonzero(ok)[order]
    again = repeated_rows(np.column_stack([t, lat, lon, h, vel, sd, sd_vel] + [v for v in (q, ns) if v is not None])[sel])
    if again.any():
        _left_out(path, t[sel][again], "repeating the epoch before them exactly")
        sel = sel[~again]
    tt = t[sel]
    if (np.diff(tt) <= 0).any():
        i = int(np.argmax(np.diff(tt) <= 0))
        raise ScenarioError(f"source.gnss: {path}: two different epochs at {tt[i]:.3f} GPS s")
    if (np.abs(lat[sel]) > 90).any() or (np.abs(lon[sel]) > 360).any() or (np.abs(h[sel]) > 1e5).any():
        raise ScenarioError(f"source.gnss: {path}: latitude, longitude or height out of range (degrees and metres expected)")
    qq = np.full(len(sel), 5.0) if q is None else q[sel]
    return PosLog(tt, lat[sel], lon[sel], h[sel], qq, vel[sel], sd[sel], sd_vel[sel], str(path), None if ns is None else ns[sel])


def read_gnsslogger_fixes(path: str | Path, provider: str = "GPS") -> PosLog:
    """The ``Fix`` records of ``provider`` (``"GPS"``, ``"FLP"`` or ``"NLP"``) of an Android
    GnssLogger file (:func:`navfdi.gnsslogger.fix_records`) as a :class:`PosLog`: positions
    with σ east and north from the 68 % horizontal accuracy and σ up from the vertical one; no
    velocity (a fix gives its horizontal speed and bearing, no vertical speed: a log of
    positions, for a ``gnss_position`` sensor). Fixes marked ``MockLocation`` are left out with
    a :class:`~navfdi.LeftOutFixesWarning`."""
    from navfdi.gnsslogger import fix_records

    path = Path(path)
    f = fix_records(path, provider)
    mock = f["mock"]
    if mock.any():
        _left_out(path, f["t"][mock], "marked as mock locations (MockLocation = 1: set by an app, not measured)")
    m = ~mock
    sd = np.column_stack([f["sd_h"], f["sd_h"], f["sd_u"]])[m]
    nan3 = np.full((int(m.sum()), 3), np.nan)
    return _log(path, f["t"][m], f["lat"][m], f["lon"][m], f["height"][m], nan3, sd, nan3.copy())


def read_ros_fixes(path: str | Path, topic: str | None = None, velocity_topic: str | None = None, time_scale: str = "unix") -> PosLog:
    """The fixes of a ROS bag's ``sensor_msgs/NavSatFix`` topic (:func:`navfdi.rosbag.fix_messages`)
    as a :class:`PosLog`, with the velocity of ``velocity_topic`` where given. Messages whose
    status says no fix are left out with a :class:`~navfdi.LeftOutFixesWarning`."""
    from navfdi.rosbag import fix_messages

    path = Path(path)
    f = fix_messages(path, topic, velocity_topic, time_scale)
    bad = f["no_fix"] | ~np.isfinite(f["lat"])
    if bad.all():
        raise ScenarioError(f"source.gnss: {path}: every NavSatFix message says no fix (status −1)")
    if bad.any():
        _left_out(path, f["t"][bad], "whose status says no fix (NavSatFix status −1)")
    m = ~bad
    return _log(path, f["t"][m], f["lat"][m], f["lon"][m], f["height"][m], f["vel"][m], f["sd"][m], f["sd_vel"][m], f["q"][m])


def read_solution_csv(path: Path, text: str | None = None) -> PosLog:
    """``navfdi gnss``'s ``solution.csv``: its solved epochs (``gps_seconds``, ``lat``, ``lon``,
    ``height``, ``vel_e/n/u``); no σ (the sensors' noise applies)."""
    import pandas as pd

    df = pd.read_csv(io.StringIO(text if text is not None else _text(path)))
    need = {"gps_seconds", "lat", "lon", "height"}
    if not need <= set(df.columns):
        raise ScenarioError(f"source.gnss: {path}: not a navfdi solution.csv (missing {', '.join(sorted(need - set(df.columns)))})")
    return _solution_log(path, df)


def _solution_log(path: Path | str, df: Any) -> PosLog:
    """A :class:`PosLog` from ``navfdi gnss``'s solution table (a DataFrame)."""
    import pandas as pd

    n = len(df)
    three = lambda cols: np.column_stack([df.get(c, pd.Series(np.nan, index=df.index)).to_numpy(float) for c in cols])  # noqa: E731
    vel = three(("vel_e", "vel_n", "vel_u"))
    sd = three(("sd_e", "sd_n", "sd_u"))
    ns = df["used"].to_numpy(float) if "used" in df else None
    return _log(Path(path), df["gps_seconds"].to_numpy(float), df["lat"].to_numpy(float), df["lon"].to_numpy(float), df["height"].to_numpy(float), vel, sd,
                np.full((n, 3), np.nan), ns=ns)


def read_rinex_solution(cfg: Mapping[str, Any], base: Path) -> PosLog:
    """``[source] gnss = { format = "rinex", obs = …, nav = …, … }``: the RINEX files solved
    epoch by epoch (:func:`navfdi.gnss.gnss_solve`, with FDE), as a :class:`PosLog` (see the
    module's description). Paths relative to ``base``."""
    from navfdi._fields import _unit
    from navfdi.gnss import gnss_solve

    unknown = sorted(set(cfg) - {"format", *RINEX_KEYS})
    if unknown:
        raise ScenarioError(f"source.gnss: unknown key(s) {', '.join(unknown)} for format = \"rinex\" (allowed: {', '.join(RINEX_KEYS)})")
    paths = []
    for k in ("obs", "nav"):
        f = cfg.get(k)
        if not isinstance(f, str):
            raise ScenarioError(f"source.gnss.{k}: the RINEX {'observation' if k == 'obs' else 'navigation'} file's path is required (format = \"rinex\")")
        p = Path(f) if Path(f).is_absolute() else base / f
        if not p.is_file():
            raise ScenarioError(f"source.gnss.{k}: {p}: no such file")
        paths.append(p)
    systems = cfg.get("systems", ["G"])
    if isinstance(systems, str):
        systems = [systems]
    if not isinstance(systems, list) or not systems or not all(isinstance(x, str) for x in systems):
        raise ScenarioError(f"source.gnss.systems = {systems!r}: a list of system letters, e.g. [\"G\", \"E\"]")
    mask = math.degrees(_unit(cfg.get("elevation_mask", "10 deg"), "angle", "source.gnss.elevation_mask"))
    kw = {k: cfg[k] for k in ("weighting", "test") if k in cfg}
    for k, v in kw.items():
        if not isinstance(v, str):
            raise ScenarioError(f"source.gnss.{k} = {v!r}: a name (see navfdi gnss --help)")
    if "noise" in cfg:
        v = cfg["noise"]
        if not (v == "auto" or (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0)):
            raise ScenarioError(f"source.gnss.noise = {v!r}: \"auto\" or a positive factor on the solve's sigma (see navfdi gnss --noise)")
        kw["noise_scale"] = v
    try:
        sol = gnss_solve(paths[0], paths[1], systems=systems, mask_deg=mask, exclude=True, **kw)
    except ValueError as e:
        raise ScenarioError(f"source.gnss: {paths[0].name}: {e}") from None
    solved = sol.solution[sol.solution["status"] != "no_solution"]
    if not len(solved):
        raise ScenarioError(f"source.gnss: {paths[0]}: no epoch solved (systems {systems}, mask {mask:g} deg)")
    return _solution_log(paths[0], solved)


def _nmea_fields(line: str, path: Path, i: int) -> list[str] | None:
    line = line.strip()
    if not line.startswith("$"):
        return None
    body, _, cs = line[1:].partition("*")
    if cs:
        want = 0
        for ch in body:
            want ^= ord(ch)
        try:
            got = int(cs[:2], 16)
        except ValueError:
            got = -1
        if got != want:
            raise ScenarioError(f"source.gnss: {path}, line {i}: NMEA checksum *{cs[:2]} does not match the sentence ({want:02X})")
    return body.split(",")


def _deg(v: str, hemi: str) -> float:
    if not v:
        return math.nan
    d = float(v)
    deg = int(d // 100)
    out = deg + (d - 100 * deg) / 60.0
    return -out if hemi in ("S", "W") else out


#: GGA fix quality → RTKLIB's solution quality (:attr:`navfdi.logs.PosLog.q`: 1 fixed, 2 float,
#: 3 SBAS, 4 DGPS, 5 single): GPS SPS and PPS → 5, DGPS → 4, RTK fixed → 1, RTK float → 2, SBAS
#: (NMEA 4.1's 9) → 3.
GGA_QUALITY = {1: 5, 2: 4, 3: 5, 4: 1, 5: 2, 9: 3}
#: GGA fix qualities that are not GNSS measurements: left out as the log is read.
GGA_NOT_MEASURED = {6: "estimated, dead reckoning", 7: "manual input", 8: "simulator"}
#: GNS mode letters as the GGA quality they stand for (autonomous, differential, precise, RTK
#: fixed, RTK float, estimated, manual, simulator; ``N``, no fix, is skipped).
GNS_MODE = {"A": 1, "D": 2, "P": 3, "R": 4, "F": 5, "E": 6, "M": 7, "S": 8}
_GNS_LETTER = {v: k for k, v in GNS_MODE.items()}


def _fix(r: dict[str, float], f: list[str], code: int, sep: int) -> None:
    """Fill row ``r`` from the fields ``f`` of a ``GGA`` or ``GNS`` sentence (the same latitude,
    longitude, satellite and altitude fields; the geoid separation at ``sep``) of GGA quality
    ``code``, stored on RTKLIB's scale (negative: not a GNSS measurement)."""
    r["lat"], r["lon"] = _deg(f[2], f[3]), _deg(f[4], f[5])
    r["h"] = float(f[9]) + (float(f[sep]) if f[sep] else 0.0)
    r["q"] = float(GGA_QUALITY.get(code, -code))
    if f[7]:
        r["ns"] = float(f[7])


def read_nmea(path: Path, text: str | None = None, date: str | None = None) -> PosLog:
    """NMEA 0183 ``GGA`` / ``GNS`` / ``RMC`` / ``VTG`` / ``GST`` sentences (any talker) into a log; see the
    module's description. The GGA quality is turned into RTKLIB's (:data:`GGA_QUALITY`); fixes
    of qualities 6–8 (:data:`GGA_NOT_MEASURED`) are left out with a
    :class:`~navfdi.LeftOutFixesWarning`; the satellite count is read into ``ns``."""
    text = text if text is not None else _text(path)
    day: _dt.date | None = None
    if date is not None:
        try:
            day = _dt.date.fromisoformat(str(date))
        except ValueError:
            raise ScenarioError(f"source.gnss.date = {date!r}: YYYY-MM-DD") from None
    rows: dict[str, dict[str, float]] = {}
    order: list[str] = []
    pending_day: dict[str, _dt.date] = {}

    def row(hms: str) -> dict[str, float]:
        if hms not in rows:
            rows[hms] = {}
            order.append(hms)
        return rows[hms]

    for i, ln in enumerate(text.splitlines(), 1):
        f = _nmea_fields(ln, path, i)
        if not f or len(f[0]) < 5:
            continue
        kind = f[0][-3:]
        try:
            if kind == "GGA" and len(f) >= 12 and f[1] and f[6] not in ("", "0"):
                code = int(f[6])
                if code not in GGA_QUALITY and code not in GGA_NOT_MEASURED:
                    raise ScenarioError(f"source.gnss: {path}, line {i}: GGA fix quality {code} is none of NMEA 0183's (0–9)")
                _fix(row(f[1]), f, code, 11)
            elif kind == "GNS" and len(f) >= 11 and f[1] and f[6].strip("N"):
                # Mode per system (GPS, GLONASS, Galileo, …): the best one is the fix's.
                if any(c != "N" and c not in GNS_MODE for c in f[6]):
                    raise ScenarioError(f"source.gnss: {path}, line {i}: GNS mode indicator {f[6]!r} has a letter none of NMEA 0183's (NADPRFEMS)")
                codes = [GNS_MODE[c] for c in f[6] if c != "N"]
                measured = [c for c in codes if c in GGA_QUALITY]
                code = min(measured, key=GGA_QUALITY.__getitem__) if measured else min(codes)
                r = row(f[1])
                if "lat" not in r:  # a GGA of the same epoch is read instead
                    _fix(r, f, code, 10)
            elif kind == "RMC" and len(f) >= 10 and f[1] and f[2] == "A":
                r = row(f[1])
                pending_day[f[1]] = _dt.datetime.strptime(f[9], "%d%m%y").date()
                if f[7] and f[8]:
                    sp, cog = float(f[7]) * 0.514444, math.radians(float(f[8]))
                    r["ve"], r["vn"] = sp * math.sin(cog), sp * math.cos(cog)
            elif kind == "VTG" and len(f) >= 8 and f[1] and f[7]:
                # No time in VTG: it belongs to the last timed sentence.
                if order:
                    sp, cog = float(f[7]) / 3.6, math.radians(float(f[1]))
                    rows[order[-1]].setdefault("ve", sp * math.sin(cog))
                    rows[order[-1]].setdefault("vn", sp * math.cos(cog))
            elif kind == "GST" and len(f) >= 9 and f[1] and f[6] and f[7] and f[8]:
                r = row(f[1])
                r["sdn"], r["sde"], r["sdu"] = float(f[6]), float(f[7]), float(f[8].split("*")[0])
        except ScenarioError:
            raise
        except (ValueError, IndexError):
            raise ScenarioError(f"source.gnss: {path}, line {i}: malformed {kind} sentence: {ln.strip()[:80]!r}") from None
    if not order:
        raise ScenarioError(f"source.gnss: {path}: no NMEA GGA/GNS/RMC sentences")
    if day is None and not pending_day:
        raise ScenarioError(f"source.gnss: {path}: no RMC sentence gives the date; add date = \"YYYY-MM-DD\" (UTC) to source.gnss")
    t, cur, prev_sec = [], day, None
    for hms in order:
        d = pending_day.get(hms, cur)
        if d is None:
            d = next(iter(pending_day.values()))
        sec = int(hms[0:2]) * 3600 + int(hms[2:4]) * 60 + float(hms[4:])
        if day is not None and hms not in pending_day and prev_sec is not None and sec < prev_sec - 43200:
            d = d + _dt.timedelta(days=1)  # midnight rollover
        cur, prev_sec = d, sec
        t.append(utc_to_gps(_dt.datetime.combine(d, _dt.time()) + _dt.timedelta(seconds=sec)))
    g = lambda k: np.array([rows[h].get(k, math.nan) for h in order])  # noqa: E731
    vel = np.column_stack([g("ve"), g("vn"), np.where(np.isfinite(g("ve")), 0.0, np.nan)])
    sd = np.column_stack([g("sde"), g("sdn"), g("sdu")])
    q, tt = g("q"), np.array(t)
    # GGA qualities with no GNSS solution behind them (estimated, manual, simulated).
    for code, name in GGA_NOT_MEASURED.items():
        hit = q == -code
        if hit.any():
            _left_out(path, tt[hit], f"of GGA quality {code} or GNS mode {_GNS_LETTER[code]} ({name}: not a GNSS measurement)")
    lat = np.where(q > 0, g("lat"), np.nan)  # no position: dropped by _log
    if not np.isfinite(lat).any() and (q < 0).any():
        raise ScenarioError(f"source.gnss: {path}: no GGA fix of a GNSS quality (every one is {', '.join(sorted({GGA_NOT_MEASURED.get(-int(x), '?') for x in q[q < 0]}))})")
    return _log(path, tt, lat, g("lon"), g("h"), vel, sd, np.full_like(sd, np.nan), q, g("ns"))


def read_gnss_csv(path: Path, text: str, cfg: Mapping[str, Any]) -> PosLog:
    """A CSV with a ``columns`` mapping (see the module's description)."""
    cols = cfg.get("columns")
    if not isinstance(cols, Mapping):
        raise ScenarioError("source.gnss.columns: a table mapping time, lat, lon, height or ecef (and optionally sd, vel, sd_vel) to the file's column names")
    allowed = {"time", "lat", "lon", "height", "height_msl", "ecef", "sd", "vel", "sd_vel", "sd_ecef", "vel_ecef", "sd_vel_ecef", "satellites"}
    unknown = sorted(set(cols) - allowed)
    if unknown:
        raise ScenarioError(f"source.gnss.columns: unknown key(s) {', '.join(unknown)} (allowed: {', '.join(sorted(allowed))})")
    cmap: dict[str, Any] = dict(cols)
    has_header, delim = text_layout(cfg, "source.gnss")
    if delim == "whitespace":
        rows = [(i + 1, ln.split()) for i, ln in enumerate(text.splitlines())]
    else:
        rows = list(enumerate(csv.reader(io.StringIO(text), delimiter=delim), start=1))
    rows = [(i, r) for i, r in rows if r and any(x.strip() for x in r)]
    if not rows:
        raise ScenarioError(f"source.gnss: {path}: empty file")
    if has_header:
        header = [h.strip() for h in rows[0][1]]
        rows = rows[1:]
    else:
        # Columns by their number from 1 (names "1", "2", …; integers in the mapping too).
        header = [str(k) for k in range(1, len(rows[0][1]) + 1)]
    data = [r for _, r in rows]
    line_of = [i for i, _ in rows]

    def col(name: Any, key: str) -> list[str]:
        name = str(name)
        if name not in header:
            where = f"columns: {', '.join(header)}" if has_header else f"the first line has {len(header)} columns, numbered from 1"
            raise ScenarioError(f"source.gnss.columns.{key} = {name!r}: no such column in {path} ({where})")
        j = header.index(name)
        return [r[j].strip() if j < len(r) else "" for r in data]

    def num(name: Any, key: str) -> np.ndarray:
        out = []
        for i, v in enumerate(col(name, key)):
            try:
                out.append(float(v) if v else math.nan)
            except ValueError:
                raise ScenarioError(f"source.gnss: {path}, line {line_of[i]}, column {str(name)!r}: {v!r} is not a number") from None
        return np.array(out)

    def three(key: str) -> np.ndarray:
        v = cmap.get(key)
        if v is None:
            return np.full((len(data), 3), np.nan)
        if not (isinstance(v, list) and len(v) == 3):
            raise ScenarioError(f"source.gnss.columns.{key}: three column names ({'x, y, z' if key.endswith('ecef') else 'east, north, up'})")
        return np.column_stack([num(c, key) for c in v])

    tc = cmap.get("time")
    if not has_header:
        # Column numbers may be given as integers.
        cmap = {k: ([str(x) for x in v] if isinstance(v, list) else str(v) if isinstance(v, int) and not isinstance(v, bool) else v) for k, v in cmap.items()}
        tc = cmap.get("time")
    week = cfg.get("gps_week")
    if week is not None and not (isinstance(week, int) and not isinstance(week, bool) and 0 <= week <= 9999):
        raise ScenarioError(f"source.gnss.gps_week = {week!r}: the GPS week number (0–9999) of a seconds-of-week time column")
    scale = str(cfg.get("time_scale", "gpst")).lower()
    if scale not in ("gpst", "utc", "unix"):
        raise ScenarioError(f"source.gnss.time_scale = {scale!r}: 'gpst', 'utc' (ISO date-times) or 'unix' (a numeric column of Unix time)")
    unit = time_unit(cfg.get("time_unit", "s"), "source.gnss.time_unit")
    if isinstance(tc, list) and len(tc) == 2:
        if scale == "unix" or "time_unit" in cfg:
            raise ScenarioError("source.gnss: time_scale = 'unix' and time_unit are for a single numeric time column; [week, seconds] is GPS time in seconds")
        t = num(tc[0], "time") * 604800.0 + num(tc[1], "time")
    elif isinstance(tc, str):
        vals = col(tc, "time")
        try:
            t = np.array([float(v) for v in vals]) * unit
            if scale == "unix":
                t = unix_to_gps(t)
        except ValueError:
            if scale == "unix":
                raise ScenarioError(f"source.gnss.columns.time = {tc!r}: time_scale = 'unix' needs numbers (Unix time in {cfg.get('time_unit', 's')})") from None
            try:
                ds = [_dt.datetime.fromisoformat(v.replace("Z", "")) for v in vals]
            except ValueError:
                raise ScenarioError(f"source.gnss.columns.time = {tc!r}: GPS seconds or ISO date-times") from None
            t = np.array([utc_to_gps(d) if scale == "utc" else (d - GPS_EPOCH).total_seconds() for d in ds])
    else:
        raise ScenarioError("source.gnss.columns.time: a column name (GPS seconds or ISO date-time) or [week, seconds]")
    if week is not None:
        if not isinstance(tc, str) or scale != "gpst":
            raise ScenarioError("source.gnss.gps_week: for a single time column of GPS time of week (time = …, time_scale \"gpst\"; "
                                "in time_unit: u-blox's iTOW is \"ms\")")
        t = t + week * 604800.0
    sats = cmap.get("satellites")
    if sats is not None and not isinstance(sats, str):
        raise ScenarioError("source.gnss.columns.satellites: a column name (the satellites the receiver used)")
    ns = None if sats is None else num(sats, "satellites")
    if "ecef" in cmap:
        geo = [k for k in ("lat", "lon", "height", "height_msl") if k in cmap]
        if geo:
            raise ScenarioError(f"source.gnss.columns: ecef (x, y, z) or lat, lon and height, not both (also given: {', '.join(geo)})")
        lat, lon, h = _ecef_positions(three("ecef"))
    else:
        lat, lon, h = _geodetic_positions(cfg, cmap, num)

    def enu(key: str, sd: bool) -> np.ndarray:
        # East, north, up columns, or their ECEF x, y, z form turned to them at each fix.
        if f"{key}_ecef" not in cmap:
            return three(key)
        if key in cmap:
            raise ScenarioError(f"source.gnss.columns: {key} (east, north, up) or {key}_ecef (x, y, z), not both")
        return _ecef_to_enu(three(f"{key}_ecef"), lat, lon, sd)

    none = np.isfinite(t) & ~(np.isfinite(lat) & np.isfinite(lon) & np.isfinite(h))
    if none.any() and not none[np.isfinite(t)].all():
        _left_out(path, t[none], "without a position (empty, or ECEF zeros: no fix)")
    return _log(path, t, lat, lon, h, enu("vel", False), enu("sd", True), enu("sd_vel", True), ns=ns)


def _ecef_positions(xyz: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Latitude, longitude (deg) and height (m) of ECEF positions ``xyz`` (M, 3) m; a row of
    zeros (what receivers write without a fix) is NaN."""
    from .gnss import ecef_to_lla

    xyz = np.where((xyz == 0.0).all(axis=1, keepdims=True), np.nan, xyz)
    lla = ecef_to_lla(xyz)
    return lla[:, 0], lla[:, 1], lla[:, 2]


def _ecef_to_enu(v: np.ndarray, lat: np.ndarray, lon: np.ndarray, sd: bool) -> np.ndarray:
    """ECEF vectors ``v`` (M, 3) turned to east, north, up at ``lat``, ``lon`` (deg); with
    ``sd``, σ of x, y, z (a diagonal covariance) turned to the σ of east, north, up."""
    from .gnss import enu_rotation

    r = enu_rotation(lat, lon)
    if sd:
        return np.sqrt(np.einsum("kij,kj->ki", r * r, v * v))
    return np.einsum("kij,kj->ki", r, v)


def _geodetic_positions(cfg: Mapping[str, Any], cmap: Mapping[str, Any], num: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Latitude, longitude (deg) and height above the ellipsoid (m) of a CSV's ``lat``,
    ``lon`` and ``height`` (or ``height_msl`` + ``undulation``) columns."""
    for k in ("lat", "lon"):
        if not isinstance(cmap.get(k), str):
            raise ScenarioError(f"source.gnss.columns.{k}: the column name is required (or ecef: three columns x, y, z)")
    if isinstance(cmap.get("height"), str):
        h = num(cmap["height"], "height")
    elif isinstance(cmap.get("height_msl"), str):
        und = cfg.get("undulation")
        if not isinstance(und, (int, float)) or isinstance(und, bool):
            raise ScenarioError("source.gnss.undulation: the geoid undulation (m) that turns height_msl into a height above the ellipsoid")
        h = num(cmap["height_msl"], "height_msl") + float(und)
    else:
        raise ScenarioError("source.gnss.columns: height (above the ellipsoid) or height_msl with source.gnss.undulation")
    return num(cmap["lat"], "lat"), num(cmap["lon"], "lon"), h


EPOCH_READERS.append(lambda spec, base: read_gnss(spec, base).t)
