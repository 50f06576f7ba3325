"""Real GNSS data: RINEX reading, single-point positioning and satellite FDE.

:func:`read_rinex` reads a RINEX 3 observation or navigation file (plain or ``.gz``) into a
pandas table; :func:`gnss_solve` solves every epoch of an observation file with the broadcast
ephemerides of a navigation file, runs the global test + w-test exclusion (METHODS §10) on
each, optionally with faults injected into chosen satellites' pseudoranges, and returns a
:class:`GnssSolution` (tables, summary, outputs). Reading and solving run in Rust
(``navfdi._core``); this module converts units, builds tables and scores.

Times are GPST. ``time`` columns are pandas timestamps in GPST (no leap seconds applied);
``gps_seconds`` are seconds since 1980-01-06 00:00:00 GPST.
"""

from __future__ import annotations

import gzip
import math
import numbers
import os
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Sequence

from typing import TYPE_CHECKING

import numpy as np

from navfdi import _core, _json
from navfdi._gnss_coverage import check_ephemeris_coverage, left_out_systems, raise_if_nothing_solved
from navfdi._gnss_geometry import enu_sigma
from navfdi._gnss_auto import MAX_NOISE_SCALE, new_run, resolve_auto, scaled_factors
from navfdi._gnss_noise import by_system_text, robust_sd, robust_sd_by
from navfdi._gnss_noise import estimate_noise_scale as estimate_noise_scale  # the public name it had here
from navfdi.scenario import NeverAppliedWarning

if TYPE_CHECKING:
    from navfdi.gnss_integrity import IntegritySettings
    import pandas as pd

# pandas (with pyarrow, ~80 MB resident) is imported where a table is built, not with the
# package: `gnss_solve` solves a file with only numpy and the core loaded, frees the file's
# observations, and then builds its tables (the peak memory of a day-length file).

#: The GPS time origin (1980-01-06 00:00:00 GPST), as numpy datetime64.
GPS_EPOCH = np.datetime64("1980-01-06T00:00:00", "ns")
_A = 6_378_137.0
_E2 = (1 / 298.257223563) * (2 - 1 / 298.257223563)


def _release_freed_memory() -> None:
    """Hand the heap pages freed by a dropped run back to the operating system (glibc's
    ``malloc_trim``; a no-op elsewhere): without it the freed observations of a large file stay
    resident and the tables, pyarrow's own pool and the figures are added on top."""
    import ctypes
    import ctypes.util

    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        libc.malloc_trim(0)
    except (OSError, AttributeError):
        pass


def gps_time(seconds: np.ndarray) -> pd.DatetimeIndex:
    """GPS seconds since 1980-01-06 (n,) → GPST timestamps (n,), to the nanosecond."""
    ns = np.round(np.asarray(seconds, dtype=float) * 1e9).astype("int64")
    import pandas as pd

    return pd.DatetimeIndex(GPS_EPOCH + pd.to_timedelta(ns, unit="ns"))


def lla_to_ecef(lat_deg: float, lon_deg: float, height: float) -> np.ndarray:
    """WGS-84 geodetic latitude, longitude (deg) and ellipsoidal height (m) → ECEF (3,) m."""
    lat, lon = math.radians(lat_deg), math.radians(lon_deg)
    n = _A / math.sqrt(1 - _E2 * math.sin(lat) ** 2)
    return np.array([(n + height) * math.cos(lat) * math.cos(lon), (n + height) * math.cos(lat) * math.sin(lon), (n * (1 - _E2) + height) * math.sin(lat)])


def ecef_to_lla(xyz: np.ndarray) -> np.ndarray:
    """ECEF (n, 3) m → geodetic latitude, longitude (deg) and height (m) (n, 3); NaN rows stay NaN."""
    xyz = np.atleast_2d(np.asarray(xyz, dtype=float))
    x, y, z = xyz[:, 0], xyz[:, 1], xyz[:, 2]
    p = np.hypot(x, y)
    lon = np.arctan2(y, x)
    lat = np.arctan2(z, p * (1 - _E2))
    h = np.zeros_like(p)
    for _ in range(10):
        n = _A / np.sqrt(1 - _E2 * np.sin(lat) ** 2)
        h = p / np.cos(lat) - n
        lat = np.arctan2(z, p * (1 - _E2 * n / (n + h)))
    return np.column_stack([np.degrees(lat), np.degrees(lon), h])


def enu_rotation(lat_deg: Any, lon_deg: Any) -> np.ndarray:
    """Rotation from ECEF to east-north-up at a geodetic latitude, longitude (deg): (3, 3) for
    scalars, (n, 3, 3) for arrays of shape (n,)."""
    la, lo = np.radians(lat_deg), np.radians(lon_deg)
    sl, cl, so, co = np.sin(la), np.cos(la), np.sin(lo), np.cos(lo)
    rows = [[-so, co, np.zeros_like(so)], [-sl * co, -sl * so, cl], [cl * co, cl * so, sl]]
    return np.moveaxis(np.array(rows, dtype=float), (0, 1), (-2, -1))


def _kind(path: str) -> str:
    with open(path, "rb") as f:
        head = f.read(2)
    opener: Any = gzip.open if head == b"\x1f\x8b" else open
    try:
        with opener(path, "rb") as f:
            first = f.readline(200).decode("ascii", "replace")
    except (OSError, EOFError) as e:
        raise _core.FileFormatError(f"{path}: cannot read it ({e})") from None
    return first[20:21] if len(first) > 20 else ""


def read_rinex(path: str | os.PathLike[str]) -> pd.DataFrame:
    """Read a RINEX 3 or 4 observation or navigation file (plain or ``.gz``; observation files
    also Hatanaka-compressed, ``.crx`` / ``.crx.gz``) with the ``rinex`` crate.

    Observation files give a long table, one row per epoch, satellite and observable:
    ``time`` (GPST timestamp), ``epoch`` (int), ``satellite`` (category, ``G05``),
    ``observable`` (category, ``C1C``), ``value`` (float64: m, cycles, Hz or dB-Hz).
    Navigation files give one row per GPS/Galileo/BeiDou/QZSS ephemeris (``satellite``,
    ``toc``, ``toe`` as GPST timestamps, the clock and Keplerian elements in s and rad, ``tgd``
    s, ``health``, ``unhealthy``, ``accuracy`` m, ``fnav``, ``iod``). Header facts are in
    ``df.attrs`` (``kind``, ``version``; observation: ``receiver``, ``dropped`` observation
    types, ``approx_position``, ``flags``; navigation: ``klobuchar``, ``records``).

    Raises ``FileNotFoundError`` for a missing file and :class:`navfdi.FileFormatError` (a
    ``ValueError``) naming the line for malformed, truncated or unsupported files.
    """
    import pandas as pd

    p = os.fspath(path)
    check_input_file(p, "path")
    kind = _kind(p)
    if kind == "N":
        d = _core.read_rinex_nav(p)
        cols = {k: v for k, v in d.items() if k not in ("klobuchar", "records", "version")}
        df = pd.DataFrame(cols)
        df["toc"] = gps_time(df["toc"].to_numpy())
        df["toe"] = gps_time(df["toe"].to_numpy())
        df["health"] = df["health"].astype("int64")
        df.attrs.update(kind="navigation", version=d["version"], klobuchar=d["klobuchar"], records=d["records"])
        return df
    d = _core.read_rinex_obs(p)
    sats = pd.Categorical.from_codes(d["sat"].astype("int64"), categories=d["satellites"]) if len(d["satellites"]) else pd.Categorical([])
    obs = pd.Categorical.from_codes(d["code"].astype("int64"), categories=d["observables"]) if len(d["observables"]) else pd.Categorical([])
    df = pd.DataFrame({"time": gps_time(d["time"]), "epoch": d["epoch"].astype("int64"), "satellite": sats, "observable": obs, "value": d["value"]})
    df.attrs.update(kind="observation", version=d["version"], receiver=d["receiver"], dropped=list(d["dropped"]), approx_position=d["approx_position"], flags=d["flags"].tolist())
    return df


_FAULT = re.compile(r"^\s*([A-Za-z]\d{1,2})\s*:\s*(step|ramp|quadratic)\s*:\s*([^:]+):\s*([^:]+):\s*([^:]+)$")
_MAG_UNITS = {"step": {"m": 1.0, "cm": 0.01}, "ramp": {"m/s": 1.0, "cm/s": 0.01}, "quadratic": {"m/s2": 1.0, "m/s^2": 1.0}}


@dataclass(frozen=True)
class GnssFault:
    """A fault added to one satellite's pseudoranges from ``start`` to ``end`` (s after the
    first epoch; ``end`` exclusive): ``step`` ``magnitude`` m, ``ramp`` m/s, ``quadratic`` m/s²."""

    satellite: str
    shape: str
    magnitude: float
    start: float
    end: float

    @staticmethod
    def parse(text: str, what: str = "fault") -> GnssFault:
        """Parse ``SAT:SHAPE:SIZE:START:END``, e.g. ``G13:step:20m:100s:200s`` or
        ``G29:ramp:0.5m/s:100s:300s`` (quadratic sizes in ``m/s2``; times in s, min or h, at
        most 1e9 s; ``END`` may be ``end`` for the end of the file). ``what`` names the
        argument in errors (``--fault`` on the command line, ``faults[i]`` in the API)."""
        m = _FAULT.match(text)
        if not m:
            raise ValueError(f"{what} {text!r}: expected SAT:SHAPE:SIZE:START:END, e.g. G13:step:20m:100s:200s or G29:ramp:0.5m/s:100s:300s")
        sat, shape, size, start, end = m.groups()
        mag = _with_unit(size, _MAG_UNITS[shape], f"{what} {text!r}: size")
        t_units = {"s": 1.0, "min": 60.0, "h": 3600.0}
        t0 = _with_unit(start, t_units, f"{what} {text!r}: start")
        t1 = math.inf if end.strip() == "end" else _with_unit(end, t_units, f"{what} {text!r}: end")
        for name, v in (("start", t0), ("end", t1)):
            if math.isfinite(v) and v > MAX_FAULT_TIME:
                raise ValueError(f"{what} {text!r}: {name} {v:g} s is beyond any observation file (at most {MAX_FAULT_TIME:g} s, about 30 years)")
        if not (0 <= t0 < t1):
            raise ValueError(f"{what} {text!r}: needs 0 <= start < end")
        return GnssFault(sat.upper() if len(sat) == 3 else f"{sat[0].upper()}{int(sat[1:]):02d}", shape, mag, t0, t1)

    def label(self) -> str:
        """``SAT:SHAPE:SIZE:START:END`` in SI units (m, m/s, m/s², s)."""
        return _fault_label(self)


def _fault_label(f: GnssFault) -> str:
    return f"{f.satellite}:{f.shape}:{f.magnitude:g}:{f.start:g}:{f.end:g}"


def _with_unit(text: str, units: dict[str, float], what: str) -> float:
    m = re.fullmatch(r"\s*([-+0-9.eE]+)\s*([A-Za-z/^0-9]+)\s*", text)
    if not m or m.group(2) not in units:
        raise ValueError(f"{what} {text.strip()!r}: expected a number with a unit ({', '.join(units)})")
    try:
        v = float(m.group(1))
    except ValueError:
        raise ValueError(f"{what} {text.strip()!r}: {m.group(1)!r} is not a number") from None
    if not math.isfinite(v):
        raise ValueError(f"{what} {text.strip()!r}: must be finite")
    return v * units[m.group(2)]


#: Latest fault start or end accepted (s after the first epoch): about 30 years.
MAX_FAULT_TIME = 1e9


def check_input_file(path: str | os.PathLike[str], name: str) -> None:
    """Raise an ``OSError`` naming ``name`` unless ``path`` is an existing regular file: "no
    such file", "is a directory", or "not a regular file" (a device, pipe or socket)."""
    p = os.fspath(path)
    if os.path.isdir(p):
        raise IsADirectoryError(21, f"{name}: is a directory, not a file", p)
    if not os.path.exists(p):
        raise FileNotFoundError(2, f"{name}: no such file", p)
    if not os.path.isfile(p):
        raise OSError(f"{name}: {p}: not a regular file (a device, pipe or socket); give the path of a file")


def check_ecef_truth(t_ecef: np.ndarray) -> None:
    """Raise ``ValueError`` unless ``t_ecef`` is (3,) finite ECEF metres within 100 km of the
    Earth's surface (the range the ``LAT,LON,H`` form accepts); a latitude/longitude/height
    given as numbers is named as such."""
    if t_ecef.shape != (3,) or not np.all(np.isfinite(t_ecef)):
        raise ValueError("truth: expected ECEF (3,) in m or 'LAT,LON,H'")
    r = float(np.linalg.norm(t_ecef))
    if not 6.25e6 <= r <= 6.48e6:
        hint = ""
        if abs(t_ecef[0]) <= 90 and abs(t_ecef[1]) <= 360:
            hint = f"; for latitude, longitude and height give the string '{t_ecef[0]:g},{t_ecef[1]:g},{t_ecef[2]:g}' (deg, deg, m)"
        raise ValueError(f"truth {t_ecef.tolist()}: {r / 1e3:.3f} km from the Earth's centre is not an ECEF position within 100 km of the surface (6 357–6 478 km){hint}")


def parse_truth(text: str) -> np.ndarray:
    """``LAT,LON,H`` (deg, deg, m; commas or spaces) → ECEF (3,) m."""
    parts = [p for p in re.split(r"[,\s]+", text.strip()) if p]
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        raise ValueError(f"truth {text!r}: expected LAT,LON,H in deg, deg, m") from None
    if len(vals) != 3 or not all(math.isfinite(v) for v in vals) or abs(vals[0]) > 90 or abs(vals[1]) > 360 or abs(vals[2]) > 1e5:
        raise ValueError(f"truth {text!r}: expected LAT,LON,H with |LAT| <= 90 deg, |LON| <= 360 deg, |H| <= 100 km")
    return lla_to_ecef(*vals)


def read_truth_file(path: str | os.PathLike[str]) -> np.ndarray:
    """A file whose first non-comment line is ``LAT LON H`` (deg, deg, m) → ECEF (3,) m. It
    must be a regular text file (not a directory, device or pipe; a byte-order mark is
    accepted); only its first 64 kB are read. ``ValueError`` / ``OSError`` name it."""
    name = f"--truth-file {os.fspath(path)}"
    check_input_file(path, "--truth-file")
    with open(path, "rb") as f:
        head = f.read(65536)
    try:
        text = head.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        if len(head) == 65536 and e.start >= 65532:
            text = head[: e.start].decode("utf-8-sig")
        else:
            raise ValueError(f"{name}: not a text file (byte {e.start} is not UTF-8); give a file whose first line is 'LAT LON H'") from None
    for line in text.splitlines():
        if line.strip() and not line.lstrip().startswith(("#", "%")):
            try:
                return parse_truth(line)
            except ValueError as e:
                raise ValueError(f"{name}: {e}") from None
    raise ValueError(f"{name}: no 'LAT LON H' line found")


@dataclass
class GnssSolution:
    """Result of :func:`gnss_solve`.

    ``solution``: one row per epoch (``time`` GPST ISO 8601, ``gps_seconds``, ``x, y, z`` ECEF
    m, ``lat, lon`` deg, ``height`` m, ``sd_e, sd_n, sd_u`` m (σ of the position from the used
    satellites' geometry and weights: :func:`navfdi._gnss_geometry.enu_sigma`), ``dof``,
    ``statistic``, ``threshold`` of the final test,
    ``first_statistic``, ``first_threshold``, ``first_dof`` of the test on all satellites,
    ``excluded`` (space-separated names), ``status`` (``passed``, ``excluded``,
    ``unidentified``, ``no_solution``), ``used``, ``faulty`` (satellites with an injected
    fault), ``clock_G`` … (m), and with a truth ``east, north, up`` errors in m).
    ``satellites``: per epoch and satellite (``epoch``, ``time``, ``satellite``, ``elevation``,
    ``azimuth`` deg, ``residual``, ``sigma``, ``iono``, ``tropo``, ``fault`` m, ``cn0``
    (the signal's recorded C/N0, dB-Hz; NaN where the file has none), ``w``,
    ``sat_x, sat_y, sat_z`` (satellite ECEF at transmission, m), ``sat_clock`` (s),
    ``status``). ``truth``: ECEF (3,) m or None. ``config``: the settings. Velocity from Doppler:
    ``vx, vy, vz`` (ECEF) and ``vel_e, vel_n, vel_u`` (m/s), ``clock_drift`` (m/s),
    ``vel_statistic``, ``vel_threshold`` of the rate test, ``vel_used``, ``vel_excluded``.
    """

    solution: pd.DataFrame
    satellites: pd.DataFrame
    truth: np.ndarray | None
    config: dict[str, Any]
    faults: list[GnssFault] = field(default_factory=list)

    def fault_note(self, f: GnssFault) -> str:
        """Why fault ``f`` never reached a tested pseudorange ("" when it did): its system not
        selected, its satellite never observed, its window outside the file, or the satellite
        never used inside the window (below the mask, no ephemeris, …)."""
        sol, sats = self.solution, self.satellites
        t = sol["gps_seconds"].to_numpy()
        tau = t - t[0] if len(t) else t
        active = np.flatnonzero((tau >= f.start) & (tau < f.end))
        rows = sats[(sats["satellite"] == f.satellite) & sats["epoch"].isin(active)]
        if rows["status"].isin(["used", "excluded"]).any():
            return ""
        systems = self.config["systems"]
        if f.satellite[:1] not in systems:
            return f"system {f.satellite[:1]} is not among the selected systems ({', '.join(systems)})"
        if not (sats["satellite"] == f.satellite).any():
            return f"{f.satellite} is never observed in {Path(self.config['obs']).name}"
        if len(tau) and f.start > tau[-1]:
            return f"its window starts at {f.start:g} s, after the last epoch ({tau[-1]:g} s)"
        counts = ", ".join(f"{k} {v}" for k, v in rows["status"].value_counts().items() if v > 0) or "not observed"
        return f"{f.satellite} is never used inside its window ({counts})"

    def summary(self) -> dict[str, Any]:
        """Counts and rates: epochs solved, horizontal/vertical RMS and maxima against the truth
        (m), exclusions per satellite, false exclusions per clean epoch against α, the
        sequential detectors' alarms per clean satellite-epoch, and per injected fault the
        epochs it was active, the share in which exactly that satellite was excluded, and the
        first epoch (s after the fault's start) at which the global test failed, the satellite
        was excluded, and its SPRT, AIME and CUSUM (on the whitened residuals) alarmed (alarm onsets)."""
        sol, sats = self.solution, self.satellites
        solved = sol["status"] != "no_solution"
        out: dict[str, Any] = {"epochs": int(len(sol)), "solved": int(solved.sum()), "alpha": self.config["alpha"], "systems": self.config["systems"], "codes": self.config.get("codes", {})}
        if self.truth is not None and solved.any():
            e, n, u = (sol.loc[solved, c].to_numpy() for c in ("east", "north", "up"))
            out["horizontal_rms"] = float(np.sqrt(np.mean(e**2 + n**2)))
            out["vertical_rms"] = float(np.sqrt(np.mean(u**2)))
            out["horizontal_max"] = float(np.max(np.hypot(e, n)))
            out["vertical_max"] = float(np.max(np.abs(u)))
            vok = solved & sol["vel_e"].notna()
            if vok.any():
                # The truth is a fixed position: the true velocity is zero.
                ve = sol.loc[vok, ["vel_e", "vel_n", "vel_u"]].to_numpy()
                out["velocity_epochs"] = int(vok.sum())
                out["velocity_rms"] = float(np.sqrt(np.mean(np.sum(ve**2, axis=1))))
                out["velocity_horizontal_rms"] = float(np.sqrt(np.mean(ve[:, 0] ** 2 + ve[:, 1] ** 2)))
        if "integrity" in self.config:
            from navfdi.gnss_integrity import integrity_summary

            out["integrity"] = integrity_summary(self)
        out["noise_scale"] = self.config.get("noise_scale", 1.0)
        if "noise_scale_auto" in self.config:
            out["noise_scale_auto"] = dict(self.config["noise_scale_auto"])
        if "weighting_auto" in self.config:
            out["weighting_auto"] = dict(self.config["weighting_auto"])
        out["cn0_slope"] = self.config.get("cn0_slope", 1.0)
        if "cn0_slope_auto" in self.config:
            out["cn0_slope_auto"] = dict(self.config["cn0_slope_auto"])
        out["test"], out["power"] = self.config.get("test", "global"), self.config.get("power", 0.8)
        out["k0_median"] = float(np.nanmedian(sol["k0"])) if "k0" in sol and sol["k0"].notna().any() else math.nan
        out["alpha0_median"] = float(np.nanmedian(sol["alpha0"])) if "alpha0" in sol and sol["alpha0"].notna().any() else math.nan
        clean = sats["epoch"].isin(np.flatnonzero((sol["faulty"] == "").to_numpy())) & (sats["status"] == "used")
        w = sats.loc[clean, "w"].to_numpy(float)
        w = w[np.isfinite(w)]
        mdb = sats.loc[clean, "mdb"].to_numpy(float) if "mdb" in sats else np.array([])
        out["mdb_median"] = float(np.nanmedian(mdb)) if np.isfinite(mdb).any() else math.nan
        out["clean_w_sd"] = float(np.std(w)) if w.size > 1 else math.nan
        out["clean_w_sd_robust"] = robust_sd(w)
        # Per system and per C/N0 class: where the σ model misfits a receiver (see robust_sd_by).
        out["clean_w_sd_robust_by_system"], out["clean_w_sd_robust_by_cn0"] = robust_sd_by(sats.loc[clean])
        out["skipped"] = {k: int(v) for k, v in sats["status"].value_counts().items() if k in ("no_ephemeris", "unhealthy", "bad_ephemeris", "below_mask", "unsolved") and v > 0}
        excl = sats[sats["status"] == "excluded"]
        out["exclusions"] = {str(k): int(v) for k, v in excl["satellite"].value_counts().items() if v > 0}
        clean = solved & (sol["faulty"] == "")
        fa = clean & (sol["excluded"] != "")
        gf = clean & (sol["first_statistic"] >= sol["first_threshold"])
        out["clean_epochs"] = int(clean.sum())
        out["false_exclusion_epochs"] = int(fa.sum())
        out["false_exclusion_rate"] = float(fa.sum() / clean.sum()) if clean.any() else math.nan
        out["global_alarm_rate_clean"] = float(gf.sum() / clean.sum()) if clean.any() else math.nan
        t = sol["gps_seconds"].to_numpy()
        tau = t - t[0] if len(t) else t
        # Masks over the satellite rows, not copies of them (a day file has ~10^5 rows).
        clean_mask = sats["status"].isin(["used", "excluded"]).to_numpy().copy()
        for f in self.faults:
            active_ep = np.flatnonzero((tau >= f.start) & (tau < f.end))
            clean_mask &= ~((sats["satellite"] == f.satellite) & sats["epoch"].isin(active_ep)).to_numpy()
        n_clean = int(clean_mask.sum())
        out["clean_satellite_epochs"] = n_clean
        for det in ("sprt", "aime", "cusum"):
            a = sats[f"{det}_alarm"].to_numpy()[clean_mask]
            out[f"{det}_false_alarm_rate"] = float(a.mean()) if n_clean else math.nan
        per_fault = []
        for f in self.faults:
            note = self.fault_note(f)
            if note:
                per_fault.append({"fault": _fault_label(f), "satellite": f.satellite, "applied": False, "note": note, "epochs": 0})
                continue
            active = (tau >= f.start) & (tau < f.end)
            rows = sats[(sats["satellite"] == f.satellite) & sats["epoch"].isin(np.flatnonzero(active))]
            tested = rows[rows["status"].isin(["used", "excluded"])]
            epochs_tested = tested["epoch"].to_numpy()
            exact = [set(sol["excluded"].iat[i].split()) == {f.satellite} for i in epochs_tested]
            hit = [f.satellite in sol["excluded"].iat[i].split() for i in epochs_tested]
            alarm = [bool(sol["first_statistic"].iat[i] >= sol["first_threshold"].iat[i]) for i in epochs_tested]
            first_alarm = next((float(tau[i] - f.start) for i, a in zip(epochs_tested, alarm) if a), math.nan)
            first_excl = next((float(tau[i] - f.start) for i, h in zip(epochs_tested, hit) if h), math.nan)
            others = [sorted(set(sol["excluded"].iat[i].split()) - {f.satellite}) for i in epochs_tested]
            seq = {}
            sat_rows = sats[sats["satellite"] == f.satellite].set_index("epoch")
            for det in ("sprt", "aime", "cusum"):
                # First alarm onset (not an alarm already on when the fault starts).
                al = sat_rows[f"{det}_alarm"].reindex(range(len(sol)), fill_value=False).to_numpy()
                onset = al & ~np.concatenate([[False], al[:-1]])
                hits = [i for i in epochs_tested if onset[i]]
                seq[f"first_{det}_after"] = float(tau[hits[0]] - f.start) if hits else math.nan
            per_fault.append(
                {
                    "fault": _fault_label(f),
                    "satellite": f.satellite,
                    "applied": True,
                    "epochs": int(len(epochs_tested)),
                    "excluded_exactly": int(sum(exact)),
                    "excluded_rate": float(np.mean(exact)) if exact else math.nan,
                    "other_exclusions": int(sum(len(o) for o in others)),
                    "first_alarm_after": first_alarm,
                    "first_exclusion_after": first_excl,
                    **seq,
                }
            )
        out["faults"] = per_fault
        return out

    def format_summary(self) -> str:
        """The summary as printed by ``navfdi gnss``."""
        s = self.summary()
        codes = ", ".join(f"{k} {v}" for k, v in self.config.get("codes", {}).items())
        lines = [f"epochs {s['epochs']}, solved {s['solved']} ({codes or ', '.join(self.config['systems'])}; mask {self.config['mask_deg']:g} deg; alpha {s['alpha']:g})"]
        others, left_out = left_out_systems(self.config["systems"], self.config.get("systems_in_files", []))
        if others:
            lines.append(f"the files also have {left_out}, not used: --systems {','.join([*self.config['systems'], *others])} uses {'it' if len(others) == 1 else 'them'}")
        if "horizontal_rms" in s:
            lines.append(f"error vs truth: horizontal RMS {s['horizontal_rms']:.3f} m (max {s['horizontal_max']:.2f}), vertical RMS {s['vertical_rms']:.3f} m (max {s['vertical_max']:.2f})")
        ig = s.get("integrity")
        if ig:
            line = f"integrity ({ig['allocation']}): available {ig['availability']:.1%} of solved epochs, {ig['alarm_epochs']} alarm epochs"
            if "araim_vertical_hazardously_misleading" in ig:
                hmi = sum(ig[f"{k}_{d}_hazardously_misleading"] for k in ("araim", "raim") for d in ("horizontal", "vertical"))
                mi = {k: ig[f"{k}_horizontal_misleading"] + ig[f"{k}_vertical_misleading"] for k in ("araim", "raim")}
                line += f"; error > PL while available: ARAIM {mi['araim']}, snapshot RAIM {mi['raim']} epochs; hazardously misleading {hmi}"
            lines.append(line)
            for reason, count in sorted(ig.get("failed_epochs", {}).items(), key=lambda kv: -kv[1]):
                lines.append(f"  integrity not computed at {count} epoch(s): {reason}")
            from navfdi.gnss_integrity import not_holding

            lines += not_holding(self, ig)
        skipped = ", ".join(f"{k} {v}" for k, v in sorted(s["skipped"].items())) or "none"
        lines.append(f"satellite-epochs skipped: {skipped}")
        ex = ", ".join(f"{k} {v}" for k, v in sorted(s["exclusions"].items())) or "none"
        lines.append(f"exclusions per satellite: {ex}")
        lines.append(f"sequential detectors, alarms per clean satellite-epoch: SPRT {s['sprt_false_alarm_rate']:.4f}, AIME {s['aime_false_alarm_rate']:.4f}, CUSUM {s['cusum_false_alarm_rate']:.4f}")
        lines.append(f"clean epochs {s['clean_epochs']}: false-exclusion epochs {s['false_exclusion_epochs']} (rate {s['false_exclusion_rate']:.4f}), global alarms {s['global_alarm_rate_clean']:.4f} vs alpha {s['alpha']:g}")
        names = {"global": "global chi-square test", "wtest": "data snooping (largest |w|)", "both": "global test or largest |w|", "auto": "per epoch the more powerful of the global test and data snooping"}
        lines.append(
            f"test: {names.get(s['test'], s['test'])}; allocation alpha {s['alpha']:g}, power {s['power']:g} → w-test k0 {s['k0_median']:.2f} "
            f"(alpha0 {s['alpha0_median']:.1e} per satellite; medians); minimal detectable bias median {s['mdb_median']:.2f} m; "
            f"clean w SD {s['clean_w_sd']:.2f} (robust {s['clean_w_sd_robust']:.2f}{by_system_text(s)}; 1 when the sigma fit)")
        if "weighting_auto" in self.config:
            wa = self.config["weighting_auto"]
            if any(math.isfinite(v) for v in wa["tail"].values()):
                lines.append(f"weighting: {wa['chosen']}, chosen from the file (--weighting auto; the statistic's tail ratio "
                             + ", ".join(f"{kk} {v:.3f}" for kk, v in wa["tail"].items()) + "; 0 for a model of the right shape)")
            else:
                lines.append(f"weighting: {wa['chosen']} (--weighting auto: too few epochs to compare the models; 20 tested needed)")
        if "cn0_slope_auto" in self.config:
            c = self.config["cn0_slope_auto"]
            if c["settled"] or math.isfinite(c["estimate"]):
                how = f"fitted {c['estimate']:.2f} in {c['solves']} solves over {c['bins']} C/N0 bins spanning {c['span_dbhz']:.0f} dB-Hz"
                how += "" if c["estimate"] >= c["slope"] else f", not below the sigma-epsilon model's {c['slope']:g}"
                how += "" if c["settled"] else f"; {c['reason']}"
            else:
                how = f"not estimated: {c['reason']}"
            lines.append(f"C/N0 slope {c['slope']:.2f} (variance decades per 10 dB-Hz; --cn0-slope auto: {how})")
        if self.config.get("noise_scale_estimated"):
            a = self.config.get("noise_scale_auto", {})
            detail = ""
            if a and not math.isfinite(a["whole_file"]):
                lines.append("noise: sigma factor 1 (--noise auto: too few epochs could be tested to estimate it; 20 needed)")
            else:
                if a:
                    detail = f": {a['method']} (whole file {a['whole_file']:.3f}, with the faults excluded {a['faults_excluded']:.3f} after {a['iterations']} solves)"
                lines.append(f"noise: sigma scaled by {s['noise_scale']:.3f}, estimated from the file (--noise auto){detail}")
        elif s["global_alarm_rate_clean"] > 5 * s["alpha"]:
            cn0 = self.config.get("weighting") == "elevation" and bool(s.get("clean_w_sd_robust_by_cn0"))  # the file records C/N0
            lines.append(f"the global test alarms at {s['global_alarm_rate_clean']:.1%} of clean epochs against alpha {s['alpha']:g}: the noise model does not fit this receiver; --noise auto (noise_scale='auto', the default) estimates a sigma factor from the file" + ("; it records C/N0: --weighting auto (the default) takes the C/N0 model where its statistics fit better" if cn0 else ""))
        for f in s["faults"]:
            if not f["applied"]:
                lines.append(f"fault {f['fault']}: never applied ({f['note']}); left out of the statistics")
                continue
            lines.append(
                f"fault {f['fault']}: {f['epochs']} epochs tested, {f['satellite']} alone excluded in {f['excluded_exactly']} ({f['excluded_rate']:.1%}); first alarm {f['first_alarm_after']:g} s, first exclusion {f['first_exclusion_after']:g} s after the start (SPRT {f['first_sprt_after']:g} s, AIME {f['first_aime_after']:g} s, CUSUM {f['first_cusum_after']:g} s); other satellites excluded {f['other_exclusions']} times"
            )
        from navfdi._text import fit

        return fit("\n".join(lines)) + "\n"

    def write(self, out: str | os.PathLike[str], figures: bool = True) -> list[Path]:
        """Write ``solution.csv``, ``satellites.parquet``, ``summary.json`` and (``figures``)
        ``errors.png``, ``statistic.png``, ``exclusions.png`` into ``out`` (created)."""
        d = Path(out)
        d.mkdir(parents=True, exist_ok=True)
        paths = [d / "solution.csv", d / "satellites.parquet", d / "summary.json"]
        # 15 significant digits: GPS seconds (~1.4e9) keep their milliseconds at 4 Hz and more.
        self.solution.to_csv(paths[0], index=False, float_format="%.15g")
        # The satellite names as plain strings; `assign` shares the other columns (pandas'
        # copy-on-write) where a `copy()` doubled the table in memory.
        sats = self.satellites.assign(satellite=self.satellites["satellite"].astype(str))
        sats.to_parquet(paths[1], index=False)
        del sats
        summary = self.summary()  # once: the JSON and the report share it
        paths[2].write_text(_json.dumps({"summary": summary, "config": self.config}, default=_json_default) + "\n")
        from navfdi._gnss_plots import plot

        figs: list[Path] = plot(self, d) if figures else []
        if figures and "integrity" in self.config and self.truth is not None:
            from navfdi.gnss_integrity import plot_stanford

            figs += plot_stanford(self, d)
        paths += figs
        paths.append(self._report(d, figs, summary))
        return paths

    def _report(self, d: Path, figures: list[Path], s: dict[str, Any]) -> Path:
        """``report.html``: the summary's numbers (``s``, :meth:`summary`), per-fault results,
        the solution (first 200 epochs as a table; the whole error series interactive), the
        figures and the settings."""
        import pandas as pd

        from navfdi.report import write_report

        headline = {k: v for k, v in s.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
        headline.update({f"integrity {k}": v for k, v in s.get("integrity", {}).items() if isinstance(v, (int, float)) and not isinstance(v, bool)})
        tables = [("faults", pd.DataFrame(s["faults"]))] if s["faults"] else []
        tables.append(("solution.csv (first 200 epochs)", self.solution.head(200)))
        t = self.solution["gps_seconds"].to_numpy()
        tau = t - t[0] if len(t) else t
        series = None
        if "east" in self.solution:
            series = (tau, {f"{c} [m]": self.solution[c].to_numpy() for c in ("east", "north", "up")}, [(f.start, f.end) for f in self.faults], "time since first epoch [s]")
        return write_report(
            d / "report.html",
            f"navfdi gnss {Path(self.config['obs']).name}",
            f"{', '.join(self.config['systems'])}; mask {self.config['mask_deg']:g} deg; alpha {self.config['alpha']:g}",
            headline,
            tables,
            figures,
            scenario_text=_json.dumps(self.config, default=_json_default),
            series=series,
        )


def _json_default(o: Any) -> Any:
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    return str(o)


def gnss_solve(
    obs: str | os.PathLike[str],
    nav: str | os.PathLike[str],
    *,
    systems: Sequence[str] | str = "G",
    mask_deg: float = 10.0,
    alpha: float = 0.01,
    k: float | None = None,
    exclude: bool = True,
    noise: tuple[float, float] = (0.3, 0.3),
    weighting: str = "auto",
    cn0_reference: float = 45.0,
    ionosphere: bool = True,
    troposphere: bool = True,
    faults: Iterable[GnssFault | str] = (),
    codes: dict[str, str] | None = None,
    noise_factors: dict[str, float] | None = None,
    sprt: tuple[float, float] = (1e-3, 1e-3),
    aime: tuple[float, int] = (1e-3, 10),
    cusum: tuple[float, float, float, int, float] = (1.0, 5.0, 60.0, 20, 0.02),
    truth: np.ndarray | Sequence[float] | str | None = None,
    progress: bool = False,
    chunk: int = 500,
    integrity: str | os.PathLike[str] | IntegritySettings | None = None,
    doppler_noise: tuple[float, float] = (0.05, 0.05),
    noise_scale: float | str = "auto",
    test: str = "global",
    power: float = 0.8,
    cn0_slope: float | str = "auto",
) -> GnssSolution:
    """Single-point positioning with satellite FDE over every epoch of a RINEX 3 file.

    A navigation file that does not cover the observations is named: ``ValueError`` with both
    files' time spans when not one satellite-epoch has an ephemeris (another day's file), a
    :class:`navfdi.PartialLogWarning` per system whose satellite-epochs lack one more than
    half the time.

    Parameters
    ----------
    obs, nav : path
        Observation and navigation files (RINEX 3, plain or ``.gz``).
    systems : str or sequence of str
        Letters of the systems to use: ``G`` GPS, ``E`` Galileo, ``C`` BeiDou, ``J`` QZSS
        (``"G,E"`` or ``["G", "E"]``); one receiver clock per system.
    mask_deg : float
        Elevation mask (deg).
    alpha, k : float
        False-alarm probability of the global χ² test and the w-test critical value
        (default: the two-sided normal quantile of ``alpha``).
    exclude : bool
        Run the exclusion loop (False: weighted least squares, test reported only).
    noise : (a, b)
        Code noise (m): ``σ² = a² + b²/sin² el`` (``weighting="elevation"``), RTKLIB's
        ``pntpos`` variance with these a, b (``weighting="rtklib"``), or for low-cost receivers
        and phones the elevation model times ``10^(cn0_slope (cn0_reference − C/N0)/10)`` with the
        recorded C/N0 (``weighting="cn0"``; ``S1C`` beside ``C1C``, a satellite without one
        keeps the elevation model), or ``weighting="auto"`` (default): the one of
        ``"elevation"`` and ``"cn0"`` whose fault-free global statistics have the shape of a
        fitting model's (the 90th- and 50th-percentile σ factors nearest each other; elevation
        on a tie, as on a file without C/N0); ``config["weighting_auto"]`` holds the choice and
        both ratios. ``weighting="elevation", noise_scale=1.0`` is the model as given.
    cn0_reference : float
        The C/N0 (dB-Hz) at which ``weighting="cn0"`` gives the elevation model (default 45).
    cn0_slope : float or "auto"
        The C/N0 model's variance decades per 10 dB-Hz (in ``[0, 3]``; 1 is the σ–ε model's
        ``σ² ∝ 10^(−C/N0/10)``, 0 the elevation model). ``"auto"`` (default; used with
        ``weighting="cn0"`` or ``"auto"``, nothing to estimate with the other models) estimates
        it from the file, without the injected faults: solved without exclusion, the clean w's robust spread per 2.5 dB-Hz
        bin regressed on the C/N0, the slope moved by the misfit until it settles
        (:func:`navfdi._gnss_noise.estimate_cn0_slope`), and the estimate used where it is
        above the σ–ε model's 1 (:data:`navfdi._gnss_noise.CN0_SLOPE_FLOOR`: tracking noise falls
        no faster than that; a file whose w call for less carries errors that do not follow
        C/N0, and a smaller slope costs FDE power there); a file whose C/N0 spans less than
        5 dB-Hz keeps 1. ``config["cn0_slope_auto"]`` holds the estimate and its path; the
        noise scale (``noise_scale="auto"``) is estimated after it, at the slope used.
    ionosphere, troposphere : bool
        Apply the broadcast Klobuchar and the Saastamoinen models.
    faults : GnssFault or str
        Faults to inject (``"G13:step:20m:100s:200s"``; times from the first epoch).
    codes : dict
        Pseudorange code per system letter, to force one (``{"E": "C1X"}``). By default each
        system's first code with pseudoranges in the file, in the order GPS C1C > C1W > C1X >
        C1L > C1S > C1P > C1Y, Galileo C1C > C1X > C1B > C1A > C1Z, BeiDou C2I > C2X > C2Q,
        QZSS C1C > C1X > C1L > C1S > C1Z (first band: the broadcast group delays refer to it).
        A system with none of them is an error naming the codes the file holds.
    noise_factors : dict
        Factor on σ per system letter (default 1), e.g. ``{"C": 3.0}`` where a system's
        broadcast biases exceed the code noise.
    sprt : (P_f, P_m)
        Improved SPRT on each satellite's whitened residual stream (known unit variance).
    aime : (P_f, window)
        AIME (:class:`navfdi.Aime`) on each satellite's whitened residual stream.
    cusum : (drift, threshold, tau, warmup, floor)
        The whitening in front of the three sequential detectors and the CUSUM on its output:
        drift ν and threshold h of Page's CUSUM (in units of the whitened residual), the
        whitening's time constant (epochs) for each satellite's bias, variance and lag-1
        correlation, epochs without output after a restart, floor of the innovation's σ (m).
        See ``navfdi_core::gnss::sequential``.
    truth : (3,) ECEF m, ``"LAT,LON,H"`` or None
        Reference position; adds ``east, north, up`` error columns and RMS to the summary.
    progress : bool
        Show a tqdm progress bar.
    chunk : int
        Epochs solved per call into Rust (progress granularity).
    noise_scale : float or "auto"
        Factor on every system's σ (on top of ``noise_factors``). ``"auto"`` (default)
        estimates it from the file, without the injected faults; with fewer than 20 epochs
        that can be tested it stays 1 (a warning says so), and a factor above
        :data:`navfdi._gnss_auto.IMPLAUSIBLE_NOISE_SCALE` (30) is warned about (residuals that
        are not code noise). The estimates of the ``"auto"`` settings solve the file several
        times on one reading of it; ``config["estimation_solves"]`` counts the solves. The *whole file's* factor: a pass without
        exclusion, then the 90th percentile over the epochs of ``T / χ²₀.₉(dof)`` (the global
        statistic against its 90 % quantile; 1 when the model fits) gives the factor's square.
        It is robust to faults in up to about 10 % of the epochs but drowns them beyond
        (multipath on a phone), and on heavy-tailed residuals the tests still exceed α (the
        percentile does not see the tail they work in; docs/gnss_real.md). The factor *with the
        faults excluded*: the same percentile of the statistic left after the global test's
        exclusions (whatever ``test`` is: the factor is the receiver's), iterated (solve with
        the factor, rescale by the percentile) from below — the smaller of the residuals'
        median-absolute-w scale and 1 — until it changes by < 1 %. The whole
        file's factor is used unless it is more than
        :data:`navfdi._gnss_noise.AUTO_NOISE_CONTAMINATION_RATIO` (2)
        times the other (then the file's statistic is set by its faults, not by its noise:
        on the bundled receivers the two differ by ≤ 1.3×). The run is then solved with it;
        ``config["noise_scale"]`` holds the factor, ``config["noise_scale_auto"]`` both
        estimates, the solves taken and the one used.
    doppler_noise : (a, b)
        Pseudorange-rate noise (m/s) of the Doppler velocity, ``σ² = a² + b²/sin² el``.
    test : str
        What opens the exclusion loop: ``"global"`` (the χ² test at ``alpha``, default),
        ``"wtest"`` (data snooping: the largest |w| above ``k0 = z(1 − α0/2)`` with ``α0 = 1 −
        (1 − α)^(1/n)`` over the n satellites tested, which also identifies; the more powerful
        with many satellites, the less with few), ``"both"`` (each at α/2, either opens) or
        ``"auto"`` (per epoch, the one of the two whose minimal detectable bias is the smaller).
        The epoch table has ``k0``, ``alpha0`` and ``lambda0`` and the satellite table each
        satellite's minimal detectable bias ``mdb`` (m).
    power : float
        The power β0 (in (alpha, 1)) at which the minimal detectable biases are computed.
    integrity : str or path or IntegritySettings, optional
        An allocation — a name (``"lpv200"``) or the path of an allocation file (TOML; see
        :func:`navfdi.gnss_integrity.load_allocation_file`), checked before solving: add
        ARAIM and snapshot-RAIM protection levels and the
        integrity state per epoch (:mod:`navfdi.gnss_integrity`); the summary then has an
        ``integrity`` block (availability, misleading and hazardously misleading epochs
        against the truth) and ``write`` adds the Stanford diagrams.
    """
    if isinstance(systems, str):
        systems = [s for s in re.split(r"[,\s]+", systems.strip()) if s]
    systems = [s.upper() for s in systems]
    if not systems:
        raise ValueError("systems: give at least one of G, E, C, J")
    for p, name in ((obs, "obs"), (nav, "nav")):
        check_input_file(p, name)
    if integrity is not None:
        from navfdi.gnss_integrity import check_systems, resolve_integrity

        integrity = resolve_integrity(integrity)
        check_systems(integrity, systems)
    # The solver's settings other than the ones the "auto" estimates choose.
    common: dict[str, Any] = dict(systems=systems, mask_deg=mask_deg, alpha=alpha, k=k, noise=noise, cn0_reference=cn0_reference, ionosphere=ionosphere, troposphere=troposphere, codes=codes, noise_factors=noise_factors, sprt=sprt, aime=aime, cusum=cusum, chunk=chunk, doppler_noise=doppler_noise, test=test, power=power)
    if weighting not in ("elevation", "rtklib", "cn0", "auto"):
        raise ValueError(f"weighting: {weighting!r} is not 'elevation', 'rtklib', 'cn0' or 'auto'")
    if isinstance(cn0_slope, str):
        if cn0_slope != "auto":
            raise ValueError(f"cn0_slope = {cn0_slope!r}: a slope in [0, {_core.CN0_SLOPE_MAX:g}] or 'auto'")
    elif isinstance(cn0_slope, bool) or not (isinstance(cn0_slope, numbers.Real) and 0.0 <= cn0_slope <= _core.CN0_SLOPE_MAX):
        raise ValueError(f"cn0_slope = {cn0_slope!r}: a slope in [0, {_core.CN0_SLOPE_MAX:g}] (variance decades per 10 dB-Hz) or 'auto'")
    elif cn0_slope != 1.0 and weighting not in ("cn0", "auto"):
        raise ValueError(f"cn0_slope = {cn0_slope!r} is the C/N0 model's; weighting = {weighting!r} has none: give weighting='cn0' or 'auto'")
    if noise_scale != "auto" and (isinstance(noise_scale, (bool, str)) or not (isinstance(noise_scale, (int, float)) and 0 < noise_scale < MAX_NOISE_SCALE)):
        raise ValueError(f"noise_scale = {noise_scale!r}: a positive factor or 'auto'")
    if isinstance(faults, (str, GnssFault)):
        faults = [faults]  # one fault given alone, not a sequence of characters
    parsed = [f if isinstance(f, GnssFault) else GnssFault.parse(f, f"faults[{i}]") for i, f in enumerate(faults)]
    if isinstance(mask_deg, bool) or not (isinstance(mask_deg, (int, float)) and math.isfinite(mask_deg) and 0 <= mask_deg < 90):
        raise ValueError(f"mask: {mask_deg} deg; the elevation mask must be in [0, 90) deg")
    if chunk < 1:
        raise ValueError(f"chunk = {chunk}: must be >= 1")
    if isinstance(truth, str):
        truth = parse_truth(truth)
    t_ecef = None if truth is None else np.asarray(truth, dtype=float).reshape(-1)
    if t_ecef is not None:
        check_ecef_truth(t_ecef)
    # The "auto" settings, estimated on one reading of the files without the injected faults.
    weighting, cn0_slope, noise_scale, estimated = resolve_auto(obs, nav, common, weighting, cn0_slope, noise_scale)
    if estimated.get("estimation_solves"):
        _release_freed_memory()
    factors = scaled_factors(noise_factors, noise_scale)
    if noise_scale != 1.0:
        noise_factors = factors  # what the run used, as the config records it
    run = new_run(obs, nav, common, exclude=exclude, weighting=weighting, cn0_slope=cn0_slope, factors=factors,
                  faults=[(f.satellite, f.shape, f.magnitude, f.start, min(f.end, 1e15)) for f in parsed])
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=run.n_epochs, unit="epoch", desc="gnss")
    try:
        while run.done < run.n_epochs:
            n = run.advance(chunk)
            if bar is not None:
                bar.update(n)
    finally:
        if bar is not None:
            bar.close()
    ep = run.epoch_table()
    # Receiver velocity from Doppler, the satellite table and the run's facts: everything is
    # taken from the run, which is then freed (the file's observations) before pandas is
    # imported and the tables are built (peak memory).
    vel = run.velocity((float(doppler_noise[0]), float(doppler_noise[1])))
    st = run.satellite_table()
    used_codes, dropped, receiver, in_files = dict(run.codes), run.dropped, run.receiver, run.systems_in_files
    del run
    _release_freed_memory()
    import pandas as pd

    sol = pd.DataFrame({"time": gps_time(ep["time"]).strftime("%Y-%m-%dT%H:%M:%S.%f").str[:-3], "gps_seconds": ep["time"]})
    xyz = np.column_stack([ep["x"], ep["y"], ep["z"]])
    lla = ecef_to_lla(xyz) if len(xyz) else np.zeros((0, 3))
    for c, col in (("x", 0), ("y", 1), ("z", 2)):
        sol[c] = xyz[:, col]
    sol["lat"], sol["lon"], sol["height"] = lla[:, 0], lla[:, 1], lla[:, 2]
    for c in ("dof", "statistic", "threshold", "first_statistic", "first_threshold", "first_dof"):
        sol[c] = ep[c]
    sol["dof"] = sol["dof"].astype("int64")
    sol["first_dof"] = sol["first_dof"].astype("int64")
    sol["excluded"] = ep["excluded"]
    sol["status"] = ep["status"]
    sol["used"] = ep["used"].astype("int64")
    sol["k0"], sol["alpha0"], sol["lambda0"] = ep["k0"], ep["alpha0"], ep["lambda0"]
    sol["faulty"] = ep["faulty"]
    for s in ("G", "E", "C", "J"):
        if s in systems:
            sol[f"clock_{s}"] = ep[f"clock_{s}"]
    if t_ecef is not None:
        t_lla = ecef_to_lla(t_ecef[None, :])[0]
        enu = (xyz - t_ecef) @ enu_rotation(t_lla[0], t_lla[1]).T
        sol["east"], sol["north"], sol["up"] = enu[:, 0], enu[:, 1], enu[:, 2]
    sol["reason"] = ep["reason"]
    # Receiver velocity (ECEF and east/north/up at each epoch's position).
    v = np.column_stack([vel["vx"], vel["vy"], vel["vz"]])
    sol["vx"], sol["vy"], sol["vz"], sol["clock_drift"] = v[:, 0], v[:, 1], v[:, 2], vel["clock_drift"]
    venu = np.full_like(v, np.nan)
    ok = np.flatnonzero(np.isfinite(v[:, 0]) & np.isfinite(lla[:, 0]))
    if len(ok):
        venu[ok] = np.einsum("kij,kj->ki", enu_rotation(lla[ok, 0], lla[ok, 1]), v[ok])
    sol["vel_e"], sol["vel_n"], sol["vel_u"] = venu[:, 0], venu[:, 1], venu[:, 2]
    sol["vel_statistic"], sol["vel_threshold"] = vel["statistic"], vel["threshold"]
    sol["vel_used"] = vel["used"]
    sol["vel_excluded"] = vel["excluded"]
    # Column by column, each taken out of the run's table as it goes in: one column in flight
    # at a time rather than the whole table twice (a day file has ~10^5 satellite rows).
    n_rows = len(next(iter(st.values()))) if st else 0
    sats = pd.DataFrame(index=pd.RangeIndex(n_rows))
    for key in list(st):
        sats[key] = st.pop(key)
    del st
    sats["epoch"] = sats["epoch"].astype("int64")
    sats.insert(1, "time", gps_time(ep["time"][sats["epoch"].to_numpy()]) if len(sats) else pd.DatetimeIndex([]))
    sats["satellite"] = sats["satellite"].astype("category")
    if len(sol):
        solved = int((sol["status"] != "no_solution").sum())
        check_ephemeris_coverage(sats, solved, obs, nav, tuple(gps_time(ep["time"][[0, -1]])), read_rinex)
        raise_if_nothing_solved(sats, len(sol), solved, obs, systems, in_files)
    sd = enu_sigma(sats, len(sol))
    at = sol.columns.get_loc("height") + 1
    for j, c in enumerate(("sd_e", "sd_n", "sd_u")):
        sol.insert(at + j, c, sd[:, j])
    config = {
        "obs": os.fspath(obs),
        "nav": os.fspath(nav),
        "systems": systems,
        "mask_deg": float(mask_deg),
        "alpha": float(alpha),
        "k": k,
        "exclude": bool(exclude),
        "noise": list(noise),
        "weighting": weighting,
        "cn0_reference": float(cn0_reference),
        "cn0_slope": float(cn0_slope),
        "ionosphere": bool(ionosphere),
        "troposphere": bool(troposphere),
        "codes": used_codes,
        "codes_given": dict(codes or {}),
        "noise_factors": dict(noise_factors or {}),
        "sprt": list(sprt),
        "aime": list(aime),
        "cusum": list(cusum),
        "faults": [f.__dict__ for f in parsed],
        "doppler_noise": list(doppler_noise),
        "noise_scale": float(noise_scale),
        "test": test,
        "power": float(power),
        "dropped_observation_types": dropped,
        "receiver": receiver,
        "systems_in_files": list(in_files),
        **estimated,
    }
    out = GnssSolution(sol, sats, t_ecef, config, parsed)
    if integrity is not None:
        from navfdi.gnss_integrity import add_integrity

        add_integrity(out, integrity)
    for f in parsed:
        note = out.fault_note(f)
        if note:
            warnings.warn(f"fault {f.label()}: never applied: {note}; it is left out of the detection statistics", NeverAppliedWarning, stacklevel=2)
    return out

