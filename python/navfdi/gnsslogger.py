"""Android phone logs written by Google's GnssLogger app (and GPSTest, which writes the same
format; the Smartphone Decimeter Challenge's ``*_GnssLog.txt`` files are such logs): one text
file of comma-separated records, each line starting with its kind — ``Fix`` (the phone's
location fixes), ``UncalAccel`` / ``Accel`` and ``UncalGyro`` / ``Gyro`` (its IMU), ``Raw``
(GNSS measurements), ``Status``, ``Nav``, ``OrientationDeg``, … — and ``#`` lines naming each
kind's fields.

``[source] gnss = { file = "gnss_log.txt", format = "gnsslogger" }`` reads the ``Fix`` lines of
one location provider (``provider``, default ``"GPS"``: the GNSS chipset's own fixes; ``"FLP"``
is Android's fused location, which already mixes in the phone's IMU and Wi-Fi, and ``"NLP"``
the network's). ``[source.imu] file = "gnss_log.txt", format = "gnsslogger"`` reads the
accelerometer and gyro lines (the uncalibrated ones where the file has them: no bias estimate
of the phone's own applied; else the calibrated ones) and puts them on GPS time through the
phone's boot clock (``elapsedRealtimeNanos``, which stamps every sensor event), placed by the
pairs of boot-clock and GPS time the file itself carries: the ``Raw`` lines'
``ChipsetElapsedRealtimeNanos`` beside their GPS time (``TimeNanos − FullBiasNanos −
BiasNanos``; Android 11 and later, sub-microsecond), else the ``GPS`` fixes' ``UnixTimeMillis``
beside their ``elapsedRealtimeNanos``, else (older GnssLogger versions) the Raw records'
``ElapsedRealtimeMillis`` beside their GPS time (milliseconds, and the delay of the
measurements' delivery), fitted as an offset and a rate (the phone's crystal drifts against
GPS time by tens of ppm), else the sensor lines' own ``utcTimeMillis`` (the phone's wall
clock, set over the network; said in a warning).

The Smartphone Decimeter Challenge's CSV layout reads the same way: one header line
``MessageType,…`` naming every row's fields, a record kind in each row's first field
(``device_imu.csv``: ``UncalAccel`` / ``UncalGyro`` rows with ``MeasurementX/Y/Z``;
``device_gnss.csv``: ``Raw`` rows; ``ground_truth.csv``: ``Fix`` rows of its own provider).
Its IMU file's clock pairs are in another file: ``[source.imu] clock = "device_gnss.csv"``.
"""

from __future__ import annotations

import io
import math
import re
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from navfdi._errors import ScenarioError, ScenarioWarning
from navfdi._logtime import unix_to_gps
from navfdi.logs import ImuLog, _read_text

__all__ = ["is_gnsslogger", "fix_records", "read_gnsslogger_imu", "checked_imu", "PROVIDERS", "IMU_KEYS"]

#: The location providers a phone's ``Fix`` records name (GPS: the GNSS chipset's own fixes;
#: FLP: Android's fused location; NLP: the network's). Others are read as the file names them
#: (the Smartphone Decimeter Challenge's ``ground_truth.csv`` writes its reference as Fix
#: records of its own provider).
PROVIDERS = ("GPS", "FLP", "NLP")
#: The keys ``[source.imu]`` takes with ``format = "gnsslogger"``.
IMU_KEYS = ("file", "format", "max_gap", "clock")
#: A horizontal accuracy of 68 % (Android's ``Location.getAccuracy``) is this many σ of each
#: horizontal axis for a circular normal error: √(−2 ln 0.32).
_H68 = math.sqrt(-2.0 * math.log(0.32))
#: A vertical accuracy of 68 % is this many σ (the normal's 68 % two-sided quantile).
_V68 = 0.9945
#: The record kinds read; the rest (Raw's measurements, Status, Nav, Mag, …) are skipped.
_KINDS = ("Fix", "UncalAccel", "Accel", "UncalGyro", "Gyro", "Raw")
#: Fields of each kind when the file has no ``#`` line naming them (GnssLogger 3's layout).
_DEFAULT_FIELDS = {
    "Fix": "Provider,LatitudeDegrees,LongitudeDegrees,AltitudeMeters,SpeedMps,AccuracyMeters,BearingDegrees,UnixTimeMillis,"
           "SpeedAccuracyMps,BearingAccuracyDegrees,elapsedRealtimeNanos,VerticalAccuracyMeters,MockLocation",
    "UncalAccel": "utcTimeMillis,elapsedRealtimeNanos,UncalAccelXMps2,UncalAccelYMps2,UncalAccelZMps2,BiasXMps2,BiasYMps2,BiasZMps2",
    "Accel": "utcTimeMillis,elapsedRealtimeNanos,AccelXMps2,AccelYMps2,AccelZMps2",
    "UncalGyro": "utcTimeMillis,elapsedRealtimeNanos,UncalGyroXRadPerSec,UncalGyroYRadPerSec,UncalGyroZRadPerSec,"
                 "DriftXRadPerSec,DriftYRadPerSec,DriftZRadPerSec",
    "Gyro": "utcTimeMillis,elapsedRealtimeNanos,GyroXRadPerSec,GyroYRadPerSec,GyroZRadPerSec",
    "Raw": "utcTimeMillis,TimeNanos,LeapSecond,TimeUncertaintyNanos,FullBiasNanos,BiasNanos,BiasUncertaintyNanos,DriftNanosPerSecond,"
           "DriftUncertaintyNanosPerSecond,HardwareClockDiscontinuityCount,Svid,TimeOffsetNanos,State,ReceivedSvTimeNanos,"
           "ReceivedSvTimeUncertaintyNanos,Cn0DbHz,PseudorangeRateMetersPerSecond,PseudorangeRateUncertaintyMetersPerSecond,"
           "AccumulatedDeltaRangeState,AccumulatedDeltaRangeMeters,AccumulatedDeltaRangeUncertaintyMeters,CarrierFrequencyHz,"
           "CarrierCycles,CarrierPhase,CarrierPhaseUncertainty,MultipathIndicator,SnrInDb,ConstellationType,AgcDb,BasebandCn0DbHz,"
           "FullInterSignalBiasNanos,FullInterSignalBiasUncertaintyNanos,SatelliteInterSignalBiasNanos,"
           "SatelliteInterSignalBiasUncertaintyNanos,CodeType,ChipsetElapsedRealtimeNanos",
}
#: Field names older GnssLogger versions wrote for the same quantities.
_ALIASES = {"Latitude": "LatitudeDegrees", "Longitude": "LongitudeDegrees", "Altitude": "AltitudeMeters", "Accuracy": "AccuracyMeters",
            "Speed": "SpeedMps", "Bearing": "BearingDegrees", "(UTC)TimeInMs": "UnixTimeMillis"}


@dataclass(frozen=True)
class _Records:
    """The kinds read from one file: per kind its field names and its lines' text after the
    kind; the file's path, read again to name a bad line's number."""

    fields: dict[str, list[str]]
    lines: dict[str, list[str]]
    path: Path

    def line_number(self, kind: str, j: int) -> int:
        """The file's line number (from 1) of ``kind``'s ``j``-th record."""
        text = _read_text(self.path)
        for i, m in enumerate(re.finditer(rf"^{kind},", text, re.M)):
            if i == j:
                return text.count("\n", 0, m.start()) + 1
        return 0


_CACHE: dict[tuple[str, int, int], _Records] = {}


def is_gnsslogger(text: str) -> bool:
    """Whether ``text`` reads as a GnssLogger file: a ``#`` line naming a ``Fix``, ``Raw`` or
    sensor record's fields, or a first record line of one of those kinds."""
    lines = [ln for ln in text[:20000].splitlines() if ln.strip()]
    if lines and lines[0].startswith("MessageType,"):
        # The Smartphone Decimeter Challenge's CSV layout: one header, a record kind per row.
        return len(lines) > 1 and lines[1].split(",", 1)[0] in _KINDS + ("UncalMag", "Mag", "OrientationDeg", "Status")
    for line in lines:
        s = line.lstrip("# ").split(",", 1)[0]
        if s in _KINDS or s in ("Status", "Nav", "UncalMag", "OrientationDeg"):
            return "," in line
        if line.strip() and not line.startswith("#"):
            return False
    return False


def _records(path: Path) -> _Records:
    if not path.is_file():
        _read_text(path)  # the readers' one error for a missing path, a directory or a device
    st = path.stat()
    key = (str(path.resolve()), st.st_mtime_ns, st.st_size)
    if key in _CACHE:
        return _CACHE[key]
    text = _read_text(path)
    if not is_gnsslogger(text):
        raise ScenarioError(f"{path}: not a GnssLogger file (no Fix, Raw or sensor records, nor '#' lines naming their fields)")
    fields = {k: v.split(",") for k, v in _DEFAULT_FIELDS.items()}
    lines: dict[str, list[str]] = {k: [] for k in _KINDS}
    first = text[:text.find("\n")].strip() if "\n" in text else text.strip()
    if first.startswith("MessageType,"):
        shared = [_ALIASES.get(p.strip(), p.strip()) for p in first.split(",")[1:]]
        fields = {k: shared for k in _KINDS}
    for line in text.splitlines():
        kind = line[:line.find(",")]
        if kind in lines:
            lines[kind].append(line[len(kind) + 1:])
        elif line[:1] == "#":
            parts = [p.strip() for p in line[1:].split(",")]
            if parts[0] in _KINDS and len(parts) > 1:
                fields[parts[0]] = [_ALIASES.get(p, p) for p in parts[1:]]
    rec = _Records(fields, lines, path)
    if len(_CACHE) > 1:
        _CACHE.clear()
    _CACHE[key] = rec
    return rec


def _table(rec: _Records, kind: str, path: Path, need: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The ``need`` fields of ``kind``'s lines as arrays (numbers as the file writes them:
    int64 where every value is an integer, float64 with NaN for empty fields; ``Provider`` as
    text). :class:`ScenarioError` naming the line of a field that is not a number."""
    import pandas as pd

    names = rec.fields[kind]
    missing = [n for n in need if n not in names]
    if missing:
        raise ScenarioError(f"{path}: the {kind} records have no {', '.join(missing)} field (their fields: {', '.join(names)})")
    cols = [names.index(n) for n in need]
    try:
        # Named columns: a record that leaves trailing fields out reads them as empty.
        df = pd.read_csv(io.StringIO("\n".join(rec.lines[kind])), header=None, names=range(len(names)), usecols=cols, engine="c",
                         dtype={c: str for c, n in zip(cols, need) if n == "Provider"}, na_values=[""], keep_default_na=False)
    except (ValueError, pd.errors.ParserError) as e:
        long = next((j for j, ln in enumerate(rec.lines[kind]) if ln.count(",") >= len(names)), None)
        if long is not None:
            raise ScenarioError(f"{path}: line {rec.line_number(kind, long)}: a {kind} record with {rec.lines[kind][long].count(',') + 2} "
                                f"fields; the file's '# {kind},…' line names {len(names) + 1}") from None
        raise ScenarioError(f"{path}: the {kind} records cannot be read ({e})") from None
    out: dict[str, np.ndarray] = {}
    for n, c in zip(need, cols):
        col = df[c]
        if n == "Provider":
            out[n] = col.fillna("").to_numpy(str)
        elif col.dtype.kind in "if":
            out[n] = col.to_numpy()
        else:
            v = pd.to_numeric(col, errors="coerce")
            bad = (v.isna() & col.notna()).to_numpy()
            j = int(np.argmax(bad))
            raise ScenarioError(f"{path}: line {rec.line_number(kind, j)}: {kind} field {n} = {str(col.iloc[j])!r} is not a number")
    return out


def fix_records(path: str | Path, provider: str = "GPS") -> dict[str, np.ndarray]:
    """The ``Fix`` records of ``provider`` (``"GPS"``, ``"FLP"`` or ``"NLP"``) of a GnssLogger
    file, as arrays (M,): ``t`` GPS seconds (from ``UnixTimeMillis``, UTC, with the leap
    seconds), ``lat``, ``lon`` (deg), ``height`` (m above the WGS 84 ellipsoid: Android's
    ``AltitudeMeters``), ``sd_h`` σ of each horizontal axis from the 68 % horizontal accuracy
    (``AccuracyMeters`` / √(−2 ln 0.32)), ``sd_u`` σ up from ``VerticalAccuracyMeters`` (NaN
    where absent) and ``mock`` (``MockLocation`` set). Read by
    :func:`navfdi.gnss_logs.read_gnsslogger_fixes`. Raises :class:`~navfdi.ScenarioError` for a
    provider with no fix (naming the ones the file has), a field that is not a number (with its
    line), a file that is not a GnssLogger log."""
    path = Path(path)
    if not isinstance(provider, str) or not provider:
        raise ScenarioError(f"source.gnss.provider = {provider!r}: a provider's name as the Fix records write it ({', '.join(PROVIDERS)}, …)")
    rec = _records(path)
    if not rec.lines["Fix"]:
        raise ScenarioError(f"{path}: a GnssLogger file without Fix records (the phone's location fixes): nothing to read as GNSS positions")
    tab = _table(rec, "Fix", path, ("Provider",))
    have = sorted(set(tab["Provider"].tolist()))
    keep = tab["Provider"] == provider
    if not keep.any():
        raise ScenarioError(f"{path}: no Fix of provider {provider!r}; the file has {', '.join(have)} (source.gnss.provider)")
    names = rec.fields["Fix"]
    opt = tuple(n for n in ("VerticalAccuracyMeters", "MockLocation") if n in names)
    f = _table(rec, "Fix", path, ("LatitudeDegrees", "LongitudeDegrees", "AltitudeMeters", "AccuracyMeters", "UnixTimeMillis") + opt)
    f = {k: np.asarray(v[keep], float) for k, v in f.items()}
    n = int(keep.sum())
    sd_h, sd_u = f["AccuracyMeters"] / _H68, f.get("VerticalAccuracyMeters", np.full(n, np.nan)) / _V68
    return {
        "t": unix_to_gps(f["UnixTimeMillis"] / 1e3), "lat": f["LatitudeDegrees"], "lon": f["LongitudeDegrees"],
        "height": f["AltitudeMeters"], "sd_h": np.where(sd_h > 0, sd_h, np.nan), "sd_u": np.where(sd_u > 0, sd_u, np.nan),
        "mock": f.get("MockLocation", np.zeros(n)) == 1,
    }


def _raw_gps(r: dict[str, np.ndarray], ok: np.ndarray) -> np.ndarray:
    """GPS seconds of the Raw records ``ok``: TimeNanos − FullBiasNanos (in integers where the
    file has every value), then the sub-ns BiasNanos (float64 keeps today's GPS seconds to
    0.24 µs)."""
    whole = r["TimeNanos"][ok] - r["FullBiasNanos"][ok]
    return (whole // 10**9).astype(float) + (whole % 10**9).astype(float) / 1e9 - np.nan_to_num(r["BiasNanos"][ok].astype(float)) / 1e9


def _boot_to_gps(rec: _Records, path: Path) -> tuple[float, float, str]:
    """(a, b, how): GPS seconds = a + b · boot seconds, from the file's own pairs of the two
    clocks (module docstring), and which pairs were used."""
    Pairs = tuple[np.ndarray, np.ndarray, str]

    def raw(field: str, per_second: float, how: str) -> Pairs | None:
        if not (rec.lines["Raw"] and field in rec.fields["Raw"]):
            return None
        r = _table(rec, "Raw", path, ("TimeNanos", "FullBiasNanos", "BiasNanos", field))
        ok = np.isfinite(r["TimeNanos"]) & np.isfinite(r["FullBiasNanos"]) & (r[field] > 0)
        return (r[field][ok] / per_second, _raw_gps(r, ok), how) if ok.sum() >= 2 else None

    def fixes() -> Pairs | None:
        if not (rec.lines["Fix"] and "elapsedRealtimeNanos" in rec.fields["Fix"]):
            return None
        f = _table(rec, "Fix", path, ("Provider", "UnixTimeMillis", "elapsedRealtimeNanos"))
        ok = (f["Provider"] == "GPS") & np.isfinite(f["UnixTimeMillis"]) & (f["elapsedRealtimeNanos"] > 0)
        return (f["elapsedRealtimeNanos"][ok] / 1e9, unix_to_gps(f["UnixTimeMillis"][ok] / 1e3), "the GPS fixes' boot-clock times") \
            if ok.sum() >= 2 else None

    # In order of precision; older GnssLogger versions give the boot-clock time (ms) at which
    # the measurements arrived.
    pairs = (raw("ChipsetElapsedRealtimeNanos", 1e9, "the Raw records' chipset boot-clock times") or fixes()
             or raw("ElapsedRealtimeMillis", 1e3, "the Raw records' arrival times on the boot clock (ms)"))
    if pairs is None:
        return math.nan, 1.0, ""
    boot, gps, how = pairs
    order = np.argsort(boot)
    boot, gps = boot[order], gps[order]
    b0 = float(boot[0])
    keep = np.ones(len(boot), bool)
    a, b = float(np.median(gps - boot)), 1.0
    for _ in range(5):
        if keep.sum() >= 3 and boot[keep][-1] - boot[keep][0] > 10.0:
            b, a0 = np.polyfit(boot[keep] - b0, gps[keep], 1)
            a = float(a0 - b * b0)
        else:
            a, b = float(np.median(gps[keep] - boot[keep])), 1.0
        res = gps - (a + b * boot)
        scale = 1.4826 * float(np.median(np.abs(res[keep] - np.median(res[keep])))) + 1e-6
        new = np.abs(res) <= 5 * scale
        if (new == keep).all():
            break
        keep = new
    if not abs(b - 1.0) < 1e-3:
        raise ScenarioError(f"{path}: the phone's boot clock runs {1e6 * (b - 1):+.0f} ppm against GPS time by {how}: not a clock (at most ±1000 ppm)")
    return a, float(b), how


def read_gnsslogger_imu(path: str | Path, max_gap: float = 1.0, clock: str | Path | None = None) -> ImuLog:
    """The IMU of a GnssLogger file as an :class:`~navfdi.logs.ImuLog`: specific force (m/s²)
    and rate (rad/s) in the phone's axes (Android's: x to the right of the screen, y up it, z
    out of it), from ``UncalAccel`` / ``UncalGyro`` where the file has them (else ``Accel`` /
    ``Gyro``), at the slower sensor's sample times with the other interpolated to them (or
    averaged over each interval where it runs more than 1.5× as fast), on GPS time (module
    docstring; ``clock``: another file whose records hold the pairs, e.g. the Decimeter
    Challenge's ``device_gnss.csv`` beside its ``device_imu.csv``). Samples logged twice (the
    same time) are left out with a
    :class:`~navfdi.LeftOutSamplesWarning`; a wall-clock placement is said in a
    :class:`~navfdi.ScenarioWarning`. Raises :class:`~navfdi.ScenarioError` for a file without
    accelerometer or gyro records, a value that is not a number (with its line), a gap longer
    than ``max_gap`` seconds or a sample beyond any IMU's range."""
    path = Path(path)
    rec = _records(path)
    series = []
    for kinds, what in ((("UncalAccel", "Accel"), "accelerometer"), (("UncalGyro", "Gyro"), "gyro")):
        kind = next((k for k in kinds if rec.lines[k]), None)
        if kind is None:
            raise ScenarioError(f"{path}: no {what} records ({' or '.join(kinds)}) in this GnssLogger file: "
                                "turn the sensors on in GnssLogger's settings, or give the IMU in another file")
        unit = "Mps2" if what == "accelerometer" else "RadPerSec"
        names = tuple(f"{kind}{ax}{unit}" for ax in "XYZ")
        if names[0] not in rec.fields[kind] and "MeasurementX" in rec.fields[kind]:
            names = ("MeasurementX", "MeasurementY", "MeasurementZ")  # the CSV layout's names
        tab = _table(rec, kind, path, ("utcTimeMillis", "elapsedRealtimeNanos") + names)
        boot = tab["elapsedRealtimeNanos"] / 1e9
        v = np.column_stack([tab[n] for n in names])
        good = np.isfinite(boot) & np.isfinite(v).all(axis=1)
        if not good.all():
            j = int(np.argmax(~good))
            raise ScenarioError(f"{path}: line {rec.line_number(kind, j)}: a {kind} record without a time or a value")
        order = np.argsort(boot, kind="stable")
        boot, v, utc = boot[order], v[order], tab["utcTimeMillis"][order]
        twice = np.r_[False, np.diff(boot) == 0]
        if twice.any():
            from navfdi._errors import LeftOutSamplesWarning

            warnings.warn(f"the IMU log {path}: {int(twice.sum())} {kind} record(s) at the time of the one before them left out",
                          LeftOutSamplesWarning, stacklevel=2)
            boot, v, utc = boot[~twice], v[~twice], utc[~twice]
        if len(boot) < 2:
            raise ScenarioError(f"{path}: {len(boot)} {kind} record(s): too few for an IMU log")
        series.append((boot, v, utc, kind))
    (ta, fa, ua, ka), (tg, wg, ug, kg) = series
    lo, hi = max(ta[0], tg[0]), min(ta[-1], tg[-1])
    if not hi > lo:
        raise ScenarioError(f"{path}: the {ka} and {kg} records do not overlap in time")
    base_is_gyro = len(tg) <= len(ta)
    tb = tg if base_is_gyro else ta
    tb = tb[(tb >= lo) & (tb <= hi)]
    if len(tb) < 2:
        raise ScenarioError(f"{path}: the {ka} and {kg} records overlap for less than two samples")
    if base_is_gyro:
        acc, rate = _resample(ta, fa, tb), wg[(tg >= lo) & (tg <= hi)]
    else:
        acc, rate = fa[(ta >= lo) & (ta <= hi)], _resample(tg, wg, tb)
    a, b, how = _boot_to_gps(rec, path) if clock is None else _boot_to_gps(_records(Path(clock)), Path(clock))
    if not how:
        utc = (ug if base_is_gyro else ua)
        sel = (tg if base_is_gyro else ta)
        sel_ok = (sel >= lo) & (sel <= hi) & np.isfinite(utc)
        if not sel_ok.any():
            raise ScenarioError(f"{path}: no clock to put the IMU on GPS time: no Raw records with chipset boot times, no GPS fixes "
                                "with boot times, and no wall-clock times on the sensor records")
        off = float(np.median(unix_to_gps(utc[sel_ok] / 1e3) - sel[sel_ok]))
        a, b = off, 1.0
        warnings.warn(f"the IMU log {path}: placed on GPS time by the phone's wall clock (the sensor records' utcTimeMillis, set over "
                      "the network: its error against GPS time is not known here, tens of ms or more); the file has no Raw records "
                      "with chipset boot times and no GPS fixes with boot times", ScenarioWarning, stacklevel=2)
    return checked_imu(a + b * tb, rate, acc, path, max_gap)


def checked_imu(t: np.ndarray, gyro: np.ndarray, accel: np.ndarray, path: Path, max_gap: float) -> ImuLog:
    """An :class:`~navfdi.logs.ImuLog` of ``t`` (N,) GPS s, ``gyro`` (N, 3) rad/s and ``accel``
    (N, 3) m/s² read from a log other than a CSV, with the CSV reader's checks and limits
    (``_core.IMU_MAX_RATE``, ``IMU_MAX_SPECIFIC_FORCE``, ``IMU_MEDIAN_SPECIFIC_FORCE``,
    ``IMU_MAX_MEDIAN_RATE``): times increasing, no gap longer than ``max_gap`` s, no sample
    beyond any IMU's range, a median specific force near gravity (not a log with gravity
    removed) and a median rate a vehicle turns at. :class:`~navfdi.ScenarioError` naming
    ``path``."""
    from navfdi import _core

    gyro, accel = np.ascontiguousarray(gyro, float), np.ascontiguousarray(accel, float)
    if len(t) < 2 or not (np.isfinite(t).all() and np.isfinite(gyro).all() and np.isfinite(accel).all()):
        raise ScenarioError(f"{path}: {len(t)} IMU sample(s), or a sample that is not a finite number")
    dt = np.diff(t)
    if not (dt > 0).all():
        j = int(np.argmax(~(dt > 0)))
        raise ScenarioError(f"{path}: the IMU's time does not increase at {t[j + 1]:.6f} GPS s (after {t[j]:.6f} s)")
    big_w, big_f = _core.IMU_MAX_RATE, _core.IMU_MAX_SPECIFIC_FORCE
    beyond = (np.abs(gyro) > big_w).any(axis=1) | (np.abs(accel) > big_f).any(axis=1)
    if beyond.any():
        j = int(np.argmax(beyond))
        raise ScenarioError(f"{path}: an IMU sample at {t[j]:.3f} GPS s beyond any IMU's range ({big_w:g} rad/s, {big_f:g} m/s²)")
    if (dt > max_gap).any():
        j = int(np.argmax(dt > max_gap))
        raise ScenarioError(f"{path}: a gap of {dt[j]:.3f} s in the IMU log exceeds source.imu.max_gap = {max_gap:g} s "
                            f"(at {t[j]:.3f} GPS s); raise max_gap to bridge it")
    lo, hi = _core.IMU_MEDIAN_SPECIFIC_FORCE
    f = float(np.median(np.linalg.norm(accel, axis=1)))
    if not lo <= f <= hi:
        raise ScenarioError(f"{path}: the IMU's median specific force is {f:.3g} m/s²; at rest it is about 9.8 (a log with gravity "
                            "removed — a 'free' or 'linear' acceleration — cannot be mechanised: give the accelerometer's own output)")
    w = float(np.median(np.linalg.norm(gyro, axis=1)))
    if w > _core.IMU_MAX_MEDIAN_RATE:
        raise ScenarioError(f"{path}: the IMU's median angular rate is {w:.3f} rad/s ({math.degrees(w):.0f} deg/s): no vehicle turns "
                            "that fast most of the time (deg/s written as rad/s?)")
    return ImuLog(np.asarray(t, float), gyro, accel, str(path))


def _resample(t: np.ndarray, v: np.ndarray, at: np.ndarray) -> np.ndarray:
    """``v`` (N, 3) sampled at ``t`` (N,), at the times ``at`` (K,): linearly interpolated where
    ``t``'s rate is within 1.5× ``at``'s, else its mean over each of ``at``'s intervals (the
    half-intervals either side of each time) from its running integral (no aliasing of the
    faster sensor's vibration into the slower one's rate)."""
    n_here = np.searchsorted(t, at[-1]) - np.searchsorted(t, at[0])
    if n_here <= 1.5 * len(at):
        return np.column_stack([np.interp(at, t, v[:, k]) for k in range(v.shape[1])])
    mid = np.r_[at[0] - 0.5 * (at[1] - at[0]), 0.5 * (at[1:] + at[:-1]), at[-1] + 0.5 * (at[-1] - at[-2])]
    area = np.vstack([np.zeros((1, v.shape[1])), np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t)[:, None], axis=0)])
    at_mid = np.column_stack([np.interp(mid, t, area[:, k]) for k in range(v.shape[1])])
    width = np.diff(mid)
    width[width <= 0] = np.nan
    out = np.diff(at_mid, axis=0) / width[:, None]
    # An interval reaching past the faster sensor's first or last sample: interpolated.
    bad = ~np.isfinite(out).all(axis=1) | (mid[:-1] < t[0]) | (mid[1:] > t[-1])
    if bad.any():
        out[bad] = np.column_stack([np.interp(at[bad], t, v[:, k]) for k in range(v.shape[1])])
    return out


def clear_cache() -> None:
    """Forget the files read in this process (they are kept while their size and time stay)."""
    _CACHE.clear()
