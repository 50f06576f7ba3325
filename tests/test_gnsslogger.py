"""Android GnssLogger files (what phones, GPSTest and the Smartphone Decimeter Challenge write):
the ``Fix`` records of one provider as the GNSS log, the accelerometer and gyro records as the
IMU log, put on GPS time by the clock pairs the file carries. The bundled drive written as
such a file (its IMU on a phone's boot clock that runs 20 ppm fast, its RTK fixes as ``GPS``
fixes, a fused ``FLP`` provider beside them) reads back as the drive's own logs and runs as
they do."""

from __future__ import annotations

import math
import warnings
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi import LeftOutFixesWarning, ScenarioError
from navfdi._errors import ScenarioWarning
from navfdi.gnss_logs import read_gnss, read_gnsslogger_fixes, read_reference
from navfdi.gnsslogger import _resample, read_gnsslogger_imu
from navfdi.logs import read_imu, read_pos
from navfdi.scenario import from_dict, load_scenario

PKG = Path(str(resources.files("navfdi")))
SCENARIOS = PKG / "scenarios"
DRIVE = PKG / "data" / "drive_0708"
UNIX_GPS = 315964800  # the GPS epoch in Unix seconds
LEAP = 18
WALL_ERROR = 0.37  # s: the phone's wall clock against UTC in the written file
HEADER = [
    "# Version: v3.0.6.4 Platform: 14 Manufacturer: Test Model: Drive",
    "# Raw,utcTimeMillis,TimeNanos,LeapSecond,TimeUncertaintyNanos,FullBiasNanos,BiasNanos,BiasUncertaintyNanos,DriftNanosPerSecond,"
    "DriftUncertaintyNanosPerSecond,HardwareClockDiscontinuityCount,Svid,TimeOffsetNanos,State,ReceivedSvTimeNanos,"
    "ReceivedSvTimeUncertaintyNanos,Cn0DbHz,PseudorangeRateMetersPerSecond,PseudorangeRateUncertaintyMetersPerSecond,"
    "AccumulatedDeltaRangeState,AccumulatedDeltaRangeMeters,AccumulatedDeltaRangeUncertaintyMeters,CarrierFrequencyHz,CarrierCycles,"
    "CarrierPhase,CarrierPhaseUncertainty,MultipathIndicator,SnrInDb,ConstellationType,AgcDb,BasebandCn0DbHz,FullInterSignalBiasNanos,"
    "FullInterSignalBiasUncertaintyNanos,SatelliteInterSignalBiasNanos,SatelliteInterSignalBiasUncertaintyNanos,CodeType,"
    "ChipsetElapsedRealtimeNanos",
    "# UncalAccel,utcTimeMillis,elapsedRealtimeNanos,UncalAccelXMps2,UncalAccelYMps2,UncalAccelZMps2,BiasXMps2,BiasYMps2,BiasZMps2",
    "# UncalGyro,utcTimeMillis,elapsedRealtimeNanos,UncalGyroXRadPerSec,UncalGyroYRadPerSec,UncalGyroZRadPerSec,DriftXRadPerSec,"
    "DriftYRadPerSec,DriftZRadPerSec",
    "# Fix,Provider,LatitudeDegrees,LongitudeDegrees,AltitudeMeters,SpeedMps,AccuracyMeters,BearingDegrees,UnixTimeMillis,"
    "SpeedAccuracyMps,BearingAccuracyDegrees,elapsedRealtimeNanos,VerticalAccuracyMeters,MockLocation",
    "# Status,UnixTimeMillis,SignalCount,SignalIndex,ConstellationType,Svid,CarrierFrequencyHz,Cn0DbHz,AzimuthDegrees,ElevationDegrees,"
    "UsedInFix,HasAlmanacData,HasEphemerisData,BasebandCn0DbHz",
]


def drive_imu():
    return read_imu(DRIVE / "imu_1934_gpst.csv.gz", dict(load_scenario("drive_lc").raw["source"]["imu"]))


def write(path: Path, clock: str = "raw", accel_every: int = 1, mock: int | None = None, end: float | None = None) -> Path:
    """The drive as a GnssLogger file: ``clock`` "raw" (Raw records with chipset boot times),
    "fix" (the fixes' boot times only) or "wall" (neither); accelerometer records on every
    ``accel_every``-th sample; fix number ``mock`` marked MockLocation; up to ``end`` s."""
    imu, pos = drive_imu(), read_pos(DRIVE / "gnss_1934_sf.pos.gz")
    t0 = float(pos.t[0])
    last = pos.t[-1] if end is None else t0 + end

    def boot(g: float) -> int:  # the phone's boot clock (ns), 20 ppm fast against GPS time
        return int(round((1234.5 + (g - t0) * (1 + 20e-6)) * 1e9))

    ev: list[tuple[int, str]] = []
    for k in np.flatnonzero((imu.t >= t0 - 1) & (imu.t <= last + 1)):
        g, w, a = float(imu.t[k]), imu.gyro[k].tolist(), imu.accel[k].tolist()
        utc = int(round((g - LEAP + UNIX_GPS + WALL_ERROR) * 1e3))
        ev.append((boot(g), f"UncalGyro,{utc},{boot(g)},{w[0]!r},{w[1]!r},{w[2]!r},0.0,0.0,0.0"))
        if k % accel_every == 0:
            ev.append((boot(g), f"UncalAccel,{utc},{boot(g)},{a[0]!r},{a[1]!r},{a[2]!r},0.1,0.1,0.1"))
    for j in np.flatnonzero(pos.t <= last):
        g, sd = float(pos.t[j]), pos.sd_pos[j].tolist()
        um = int(round((g - LEAP + UNIX_GPS) * 1e3))
        fb = boot(g) if clock == "fix" else ""
        acc, vacc = float(sd[0]) * math.sqrt(-2 * math.log(0.32)), float(sd[2]) * 0.9945
        for prov, dlat in (("GPS", 0.0), ("FLP", 1e-4)):
            ev.append((boot(g) + 1, f"Fix,{prov},{float(pos.lat[j]) + dlat!r},{float(pos.lon[j])!r},{float(pos.height[j])!r},3.0,{acc!r},90.0,{um},,,{fb},"
                                    f"{vacc!r},{int(j == mock)}"))
        if clock in ("raw", "millis"):
            full_bias = -1_345_000_000_000_000_000
            for sv in (3, 7):
                head = um if clock == "raw" else (boot(g) + 2_000_000) // 1_000_000  # delivered 2 ms late, in ms
                tail = f",,,,,,,C,{boot(g)}" if clock == "raw" else ""
                ev.append((boot(g), f"Raw,{head},{int(round(g * 1e9)) + full_bias},18,,{full_bias},0.0,1.0,0,0,0,{sv},0.0,16431,0,10,30.0,0,0,0,0,0,"
                                    f"1575420030,,,,0,,1{tail}"))
        ev.append((boot(g) + 2, f"Status,{um},2,0,1,3,,30.0,100.0,45.0,1,1,1,"))
    ev.sort(key=lambda e: e[0])
    header = HEADER if clock != "millis" else [  # GnssLogger 2's Raw layout: the boot time in ms first, no chipset time
        "# Raw,ElapsedRealtimeMillis," + HEADER[1].split(",", 2)[2].rsplit(",AgcDb", 1)[0] if h.startswith("# Raw") else h for h in HEADER]
    path.write_text("\n".join(header + [e[1] for e in ev]) + "\n")
    return path


@pytest.fixture(scope="module")
def logfile(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write(tmp_path_factory.mktemp("gnsslogger") / "gnss_log.txt")


@pytest.mark.parametrize("clock, tol", [("raw", 5e-6), ("fix", 2e-5), ("millis", 2.6e-3)])
def test_the_imu_reads_on_gps_time_through_the_files_clock_pairs(tmp_path: Path, logfile: Path, clock: str, tol: float):
    path = logfile if clock == "raw" else write(tmp_path / "fix.txt", clock=clock, end=120.0)
    got, want = read_gnsslogger_imu(path), drive_imu()
    i = int(np.searchsorted(want.t, got.t[0] - 1e-3))
    n = len(got.t)
    # The boot clock ran 20 ppm fast: over the 9-minute drive 11 ms, taken out by the fit.
    np.testing.assert_allclose(got.t, want.t[i:i + n], rtol=0, atol=tol)
    np.testing.assert_array_equal(got.gyro, want.gyro[i:i + n])
    np.testing.assert_array_equal(got.accel, want.accel[i:i + n])


def test_without_clock_pairs_the_wall_clock_places_the_imu_and_says_so(tmp_path: Path):
    path = write(tmp_path / "wall.txt", clock="wall", end=60.0)
    with pytest.warns(ScenarioWarning, match=r"placed on GPS time by the phone's wall clock"):
        got = read_gnsslogger_imu(path)
    want = drive_imu()
    i = int(np.searchsorted(want.t, got.t[0] - WALL_ERROR - 1e-3))
    np.testing.assert_allclose(got.t - want.t[i:i + len(got.t)], WALL_ERROR, atol=1e-3)


def test_a_faster_sensor_is_averaged_over_the_slower_ones_intervals():
    t = np.arange(0, 2, 1 / 400)
    v = np.column_stack([3 + 2 * t, np.sin(2 * np.pi * 150 * t), np.zeros_like(t)])
    at = np.arange(0.1, 1.9, 1 / 100)
    out = _resample(t, v, at)
    np.testing.assert_allclose(out[:, 0], 3 + 2 * at, atol=1e-12)  # a linear signal's mean is its middle value
    # A 150 Hz vibration sampled at 400 Hz: averaged over 10 ms it is a tenth of its amplitude;
    # interpolated it would alias into the 100 Hz log at up to its whole amplitude.
    assert np.abs(out[:, 1]).max() < 0.12
    same = _resample(t, v, t[40:60] + 1e-3)  # as fast: interpolated
    np.testing.assert_allclose(same[:, 0], 3 + 2 * (t[40:60] + 1e-3), atol=1e-12)


def test_fixes_of_one_provider_read_as_the_receivers(logfile: Path, tmp_path: Path):
    want = read_pos(DRIVE / "gnss_1934_sf.pos.gz")
    got = read_gnss({"file": str(logfile)}, tmp_path)  # told from the file
    np.testing.assert_allclose(got.t, want.t, rtol=0, atol=1e-6)
    np.testing.assert_array_equal(got.lat, want.lat)
    np.testing.assert_array_equal(got.height, want.height)
    np.testing.assert_allclose(got.sd_pos[:, [0, 2]], want.sd_pos[:, [0, 2]], rtol=1e-12)
    assert np.isnan(got.vel).all()  # a fix has no vertical speed: positions only
    flp = read_gnsslogger_fixes(logfile, "FLP")
    np.testing.assert_allclose(flp.lat - want.lat, 1e-4, atol=1e-12)
    with pytest.raises(ScenarioError, match=r"no Fix of provider 'fused'; the file has FLP, GPS"):
        read_gnsslogger_fixes(logfile, "fused")
    with pytest.raises(ScenarioError, match=r"source.gnss.provider = 3: a provider's name"):
        read_gnsslogger_fixes(logfile, 3)  # type: ignore[arg-type]
    with pytest.raises(ScenarioError, match=r"no Fix of provider 'NLP'; the file has FLP, GPS \(source.gnss.provider\)"):
        read_gnsslogger_fixes(logfile, "NLP")


def test_mock_locations_are_left_out_and_said(tmp_path: Path):
    path = write(tmp_path / "mock.txt", mock=5, end=30.0)
    with pytest.warns(LeftOutFixesWarning, match=r"1 fix\(es\) marked as mock locations"):
        got = read_gnsslogger_fixes(path)
    want = read_pos(DRIVE / "gnss_1934_sf.pos.gz").t
    want = want[want <= want[0] + 30.0]
    assert len(got.t) == len(want) - 1
    np.testing.assert_allclose(got.t, np.delete(want, 5), rtol=0, atol=1e-6)


def run(source: dict) -> navfdi.VariantRuns:
    """``drive_lc`` on positions alone with ``source`` in place of its logs."""
    raw = dict(load_scenario("drive_lc").raw)
    ref = str((SCENARIOS / raw["source"]["reference"]).resolve())
    raw["source"] = {"reference": ref, "reference_quality": [1], **source}
    raw["sensors"] = [s for s in raw["sensors"] if s["name"] != "gnss_vel"]
    raw["loosely_coupled"] = dict(raw["loosely_coupled"], sensors=[s for s in raw["loosely_coupled"]["sensors"] if s["sensor"] != "gnss_vel"])
    return navfdi.run_scenario(from_dict(raw, source=str(SCENARIOS / "drive_lc.toml")))


def test_the_drive_from_a_gnsslogger_file_runs_as_from_its_own_logs(logfile: Path, tmp_path: Path):
    # The same fixes as a CSV (no solution quality, as a phone's) and the drive's IMU CSV.
    pos = read_pos(DRIVE / "gnss_1934_sf.pos.gz")
    csv = tmp_path / "fixes.csv"
    rows = [",".join(repr(float(x)) for x in (t, a, b, h, *s)) for t, a, b, h, s in zip(pos.t, pos.lat, pos.lon, pos.height, pos.sd_pos)]
    csv.write_text("t,lat,lon,h,se,sn,su\n" + "\n".join(rows) + "\n")
    imu = dict(load_scenario("drive_lc").raw["source"]["imu"])
    imu["file"] = str((SCENARIOS / imu["file"]).resolve())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ScenarioWarning)
        a = run({"gnss": {"file": str(csv), "format": "csv", "columns": {"time": "t", "lat": "lat", "lon": "lon", "height": "h",
                                                                          "sd": ["se", "sn", "su"]}}, "imu": imu})
        b = run({"gnss": {"file": str(logfile), "format": "gnsslogger"}, "imu": {"file": str(logfile), "format": "gnsslogger", "max_gap": 0.1}})
    for v in ("fde", "no_fde"):
        ea, eb = a.runs[v].errors(), b.runs[v].errors()
        for k in ("hor_rms", "hor_max", "ver_rms"):
            assert eb[k] == pytest.approx(ea[k], rel=1e-4), (v, k, ea[k], eb[k])
    assert a.runs["fde"].errors()["hor_rms"] < 0.1  # the 20 m step held out


def test_bad_files_and_settings_are_named(tmp_path: Path, logfile: Path):
    bad = tmp_path / "bad.txt"
    lines = logfile.read_text().splitlines()[:400]
    k = next(i for i, ln in enumerate(lines) if ln.startswith("UncalGyro,"))
    parts = lines[k].split(",")
    parts[3] = "fast"
    lines[k] = ",".join(parts)
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(ScenarioError, match=rf"line {k + 1}: UncalGyro field UncalGyroXRadPerSec = 'fast' is not a number"):
        read_gnsslogger_imu(bad)
    lines[k] = lines[k].replace("fast", "0.1") + ",0.5"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(ScenarioError, match=rf"line {k + 1}: a UncalGyro record with 10 fields; the file's '# UncalGyro,…' line names 9"):
        read_gnsslogger_imu(bad)
    noacc = tmp_path / "noacc.txt"
    noacc.write_text("\n".join(ln for ln in logfile.read_text().splitlines()[:400] if not ln.startswith("UncalAccel")) + "\n")
    with pytest.raises(ScenarioError, match=r"no accelerometer records \(UncalAccel or Accel\)"):
        read_gnsslogger_imu(noacc)
    with pytest.raises(ScenarioError, match=r"source.imu: gyro: not read with format = \"gnsslogger\""):
        read_imu(logfile, {"file": str(logfile), "format": "gnsslogger", "gyro": ["a", "b", "c"]})
    with pytest.raises(ScenarioError, match=r"source.imu.clock: read with format = \"gnsslogger\" only"):
        read_imu(DRIVE / "imu_1934_gpst.csv.gz", {**load_scenario("drive_lc").raw["source"]["imu"], "clock": str(logfile)})
    with pytest.raises(ScenarioError, match=r"source.imu.format = 'phone'"):
        read_imu(logfile, {"file": str(logfile), "format": "phone"})
    with pytest.raises(ScenarioError, match=r"not a GnssLogger file"):
        read_gnsslogger_fixes(DRIVE / "gnss_1934_sf.pos.gz")
    with pytest.raises(ScenarioError, match=r"source.gnss.provider: read for format = \"gnsslogger\" only"):
        read_gnss({"file": str(DRIVE / "gnss_1934_sf.pos.gz"), "provider": "GPS"}, tmp_path)


def write_gsdc(folder: Path, end: float = 60.0) -> Path:
    """The drive's first ``end`` s in the Smartphone Decimeter Challenge's CSV layout: ``device_imu.csv``
    (one header, a MessageType per row, Measurement X/Y/Z), ``device_gnss.csv`` (Raw rows with the
    chipset's boot times) and ``ground_truth.csv`` (Fix rows of provider GT)."""
    imu, pos = drive_imu(), read_pos(DRIVE / "gnss_1934_sf.pos.gz")
    t0 = float(pos.t[0])

    def boot(g: float) -> int:
        return int(round((99.0 + (g - t0) * (1 - 35e-6)) * 1e9))

    rows = ["MessageType,utcTimeMillis,elapsedRealtimeNanos,MeasurementX,MeasurementY,MeasurementZ,BiasX,BiasY,BiasZ"]
    for k in np.flatnonzero((imu.t >= t0) & (imu.t <= t0 + end)):
        g = float(imu.t[k])
        utc = int(round((g - LEAP + UNIX_GPS) * 1e3))
        for kind, v in (("UncalAccel", imu.accel[k]), ("UncalGyro", imu.gyro[k]), ("UncalMag", np.array([20.0, 5.0, -40.0]))):
            rows.append(f"{kind},{utc},{boot(g)}," + ",".join(repr(float(x)) for x in v) + ",0.0,0.0,0.0")
    (folder / "device_imu.csv").write_text("\n".join(rows) + "\n")
    rows = ["MessageType,utcTimeMillis,TimeNanos,LeapSecond,FullBiasNanos,BiasNanos,Svid,Cn0DbHz,ChipsetElapsedRealtimeNanos,"
            "WlsPositionXEcefMeters,WlsPositionYEcefMeters,WlsPositionZEcefMeters"]
    truth = ["MessageType,Provider,LatitudeDegrees,LongitudeDegrees,AltitudeMeters,SpeedMps,AccuracyMeters,BearingDegrees,UnixTimeMillis"]
    for j in np.flatnonzero(pos.t <= t0 + end):
        g = float(pos.t[j])
        um = int(round((g - LEAP + UNIX_GPS) * 1e3))
        fb = -1_300_000_000_000_000_000
        lat, lon, h = math.radians(float(pos.lat[j])), math.radians(float(pos.lon[j])), float(pos.height[j])
        n = 6378137.0 / math.sqrt(1 - 6.69437999014e-3 * math.sin(lat) ** 2)  # WGS 84
        xyz = ((n + h) * math.cos(lat) * math.cos(lon), (n + h) * math.cos(lat) * math.sin(lon), (n * (1 - 6.69437999014e-3) + h) * math.sin(lat))
        # One row per satellite, each with the epoch's weighted-least-squares position.
        rows += [f"Raw,{um},{int(round(g * 1e9)) + fb},18,{fb},0.0,{sv},30.0,{boot(g)}," + ",".join(repr(x) for x in xyz) for sv in (5, 9)]
        truth.append(f"Fix,GT,{float(pos.lat[j])!r},{float(pos.lon[j])!r},{float(pos.height[j])!r},3.0,0.1,90.0,{um}")
    (folder / "device_gnss.csv").write_text("\n".join(rows) + "\n")
    (folder / "ground_truth.csv").write_text("\n".join(truth) + "\n")
    return folder


def test_the_decimeter_challenges_csv_layout_reads_with_its_clock_file(tmp_path: Path):
    folder = write_gsdc(tmp_path)
    want, pos = drive_imu(), read_pos(DRIVE / "gnss_1934_sf.pos.gz")
    got = read_imu(folder / "device_imu.csv", {"file": "device_imu.csv", "format": "gnsslogger", "clock": str(folder / "device_gnss.csv")})
    i = int(np.searchsorted(want.t, got.t[0] - 1e-3))
    np.testing.assert_allclose(got.t, want.t[i:i + len(got.t)], rtol=0, atol=5e-6)  # a boot clock 35 ppm slow, fitted
    np.testing.assert_array_equal(got.accel, want.accel[i:i + len(got.t)])
    np.testing.assert_array_equal(got.gyro, want.gyro[i:i + len(got.t)])
    ref, has_quality = read_reference({"file": "ground_truth.csv", "provider": "GT"}, folder)  # told from the file
    assert not has_quality  # a phone log's reference has no solution quality: every epoch is the reference
    np.testing.assert_array_equal(ref.lat, pos.lat[: len(ref.t)])
    np.testing.assert_allclose(ref.t, pos.t[: len(ref.t)], rtol=0, atol=1e-6)
    with pytest.raises(ScenarioError, match=r"no Fix of provider 'GPS'; the file has GT"):
        read_gnsslogger_fixes(folder / "ground_truth.csv")
    with pytest.warns(ScenarioWarning, match=r"wall clock"):  # without its clock file
        read_imu(folder / "device_imu.csv", {"file": "device_imu.csv", "format": "gnsslogger"})
    # Its baseline positions (Google's weighted least squares, ECEF, on every Raw row) read as a CSV.
    with pytest.warns(LeftOutFixesWarning, match=r"repeating the epoch before them exactly"):
        wls = read_gnss({"file": "device_gnss.csv", "format": "csv", "time_scale": "unix", "time_unit": "ms",
                         "columns": {"time": "utcTimeMillis", "ecef": ["WlsPositionXEcefMeters", "WlsPositionYEcefMeters", "WlsPositionZEcefMeters"]}},
                        folder)
    np.testing.assert_allclose(wls.lat, ref.lat, rtol=0, atol=1e-9)
    np.testing.assert_allclose(wls.height, ref.height, rtol=0, atol=1e-4)


def test_a_file_without_its_field_lines_reads_with_gnsslogger_3s_layout(logfile: Path, tmp_path: Path):
    bare = tmp_path / "bare.txt"
    bare.write_text("\n".join(ln for ln in logfile.read_text().splitlines()[:6000] if not ln.startswith("#")) + "\n")
    got = read_gnsslogger_imu(bare)  # its clock from the Raw records' chipset times, by position
    want = drive_imu()
    i = int(np.searchsorted(want.t, got.t[0] - 1e-3))
    np.testing.assert_allclose(got.t, want.t[i:i + len(got.t)], rtol=0, atol=5e-6)
    assert len(read_gnsslogger_fixes(bare).t) > 10
