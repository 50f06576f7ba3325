"""Logs stamped in Unix time (phones, ROS, data loggers): an IMU CSV with a Unix time column
in nanoseconds and a receiver CSV in Unix milliseconds read as the same log in GPS time, and
the loosely coupled run on them as on the original files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi import ScenarioError
from navfdi._logtime import unix_to_gps
from navfdi.gnss_logs import read_gnss
from navfdi.logs import read_imu, read_pos
from navfdi.scenario import from_dict, load_scenario
from navfdi.simlog import simulate_log

UNIX_GPS = 315_964_800.0
IMU_COLS = {"week": "gps_week", "seconds": "gps_sow_s", "gyro": ["gyro_x_dps", "gyro_y_dps", "gyro_z_dps"],
            "accel": ["acc_x_mps2", "acc_y_mps2", "acc_z_mps2"], "gyro_unit": "deg/s", "accel_unit": "m/s^2"}


def test_unix_to_gps_counts_the_leap_seconds_of_the_date():
    # 2017-01-01 00:00:00 UTC: 18 leap seconds from that instant, 17 the second before.
    t = np.array([1_483_228_799.0, 1_483_228_800.0, 1_136_073_599.0])
    np.testing.assert_array_equal(unix_to_gps(t) - (t - UNIX_GPS), [17.0, 18.0, 13.0])


@pytest.fixture(scope="module")
def unix_log(tmp_path_factory: pytest.TempPathFactory):
    """A simulated drive, and its IMU (ns) and GNSS (ms) files in Unix time beside it."""
    log = simulate_log(tmp_path_factory.mktemp("unix"), duration=240, seed=3, gnss_rate=1.0, gnss_sigma=1.0)
    folder = Path(log.folder)
    imu = np.genfromtxt(log.imu, delimiter=",", names=True)
    gps = imu["gps_week"] * 604800.0 + imu["gps_sow_s"]
    with open(folder / "imu_unix.csv", "w") as f:
        f.write("stamp_ns,gx,gy,gz,ax,ay,az\n")
        for k in range(len(gps)):
            ns = int(round((gps[k] - 18.0 + UNIX_GPS) * 1e9))
            vals = [float(imu[c][k]) for c in ("gyro_x_dps", "gyro_y_dps", "gyro_z_dps", "acc_x_mps2", "acc_y_mps2", "acc_z_mps2")]
            f.write(f"{ns}," + ",".join(repr(v) for v in vals) + "\n")
    p = read_pos(log.gnss)
    with open(folder / "fix_unix.csv", "w") as f:
        f.write("unix_ms,lat,lon,h,se,sn,su,ve,vn,vu,sve,svn,svu\n")
        for k in range(len(p.t)):
            ms = (p.t[k] - 18.0 + UNIX_GPS) * 1e3
            vals = [p.lat[k], p.lon[k], p.height[k], *p.sd_pos[k], *p.vel[k], *p.sd_vel[k]]
            f.write(f"{ms:.3f}," + ",".join(repr(float(v)) for v in vals) + "\n")
    return log


IMU_UNIX = {"time": "stamp_ns", "time_scale": "unix", "time_unit": "ns", "gyro": ["gx", "gy", "gz"], "accel": ["ax", "ay", "az"],
            "gyro_unit": "deg/s", "accel_unit": "m/s^2"}
GNSS_UNIX = {"file": "fix_unix.csv", "format": "csv", "time_scale": "unix", "time_unit": "ms",
             "columns": {"time": "unix_ms", "lat": "lat", "lon": "lon", "height": "h", "sd": ["se", "sn", "su"],
                         "vel": ["ve", "vn", "vu"], "sd_vel": ["sve", "svn", "svu"]}}


def test_unix_time_files_read_as_the_gps_time_files(unix_log):
    folder = Path(unix_log.folder)
    a, b = read_imu(unix_log.imu, IMU_COLS), read_imu(folder / "imu_unix.csv", IMU_UNIX)
    # Nanoseconds as float64 near 1.7e18 keep ~0.25 µs.
    np.testing.assert_allclose(b.t, a.t, rtol=0, atol=1e-6)
    np.testing.assert_array_equal(b.gyro, a.gyro)
    np.testing.assert_array_equal(b.accel, a.accel)
    g, h = read_pos(unix_log.gnss), read_gnss(GNSS_UNIX, folder)
    np.testing.assert_allclose(h.t, g.t, rtol=0, atol=1e-6)
    np.testing.assert_allclose(h.lat, g.lat, rtol=0, atol=1e-12)
    np.testing.assert_allclose(h.vel, g.vel, rtol=0, atol=1e-12)


def test_the_filter_runs_on_unix_time_logs(unix_log):
    raw = dict(load_scenario(str(unix_log.scenario)).raw)
    base = navfdi.run_scenario(from_dict(raw, source=str(unix_log.scenario))).runs["fde"].errors()
    raw["source"] = {**raw["source"], "gnss": GNSS_UNIX, "imu": {"file": "imu_unix.csv", **IMU_UNIX}}
    e = navfdi.run_scenario(from_dict(raw, source=str(unix_log.scenario))).runs["fde"].errors()
    assert e["scored"] == base["scored"] > 150
    assert abs(e["hor_rms"] - base["hor_rms"]) < 1e-3 * base["hor_rms"]


@pytest.mark.parametrize(
    "cols, match",
    [
        ({"time_scale": "tai"}, r"source.imu.time_scale = 'tai': 'gpst' \(GPS seconds or ISO date-times in GPS time\), 'unix' \(Unix time, UTC\), 'utc' \(ISO date-times in UTC\) or 'boot'"),
        ({"time_unit": "min"}, r"source.imu.time_unit = 'min': one of s, ms, us, ns"),
        ({"time": None, "week": "w", "seconds": "s"}, r"time_scale and time_unit are for a single time column"),
    ],
)
def test_bad_imu_time_settings_are_named(tmp_path, cols, match):
    spec = {**IMU_UNIX, **cols}
    spec = {k: v for k, v in spec.items() if v is not None}
    (tmp_path / "i.csv").write_text("stamp_ns,gx,gy,gz,ax,ay,az\n1,0,0,0,0,0,9.8\n")
    with pytest.raises(ScenarioError, match=match):
        read_imu(tmp_path / "i.csv", spec)


def test_bad_gnss_time_settings_are_named(tmp_path):
    (tmp_path / "f.csv").write_text("t,lat,lon,h\n2025-07-08T10:00:00,40,-105,1600\n")
    cols = {"time": "t", "lat": "lat", "lon": "lon", "height": "h"}
    with pytest.raises(ScenarioError, match=r"time_scale = 'unix' needs numbers \(Unix time in s\)"):
        read_gnss({"file": "f.csv", "format": "csv", "time_scale": "unix", "columns": cols}, tmp_path)
    with pytest.raises(ScenarioError, match=r"source.gnss.time_unit = 'h': one of s, ms, us, ns"):
        read_gnss({"file": "f.csv", "format": "csv", "time_unit": "h", "columns": cols}, tmp_path)
    with pytest.raises(ScenarioError, match=r"'gpst', 'utc' \(ISO date-times\) or 'unix'"):
        read_gnss({"file": "f.csv", "format": "csv", "time_scale": "local", "columns": cols}, tmp_path)


def test_a_reference_in_another_format_scores_as_the_pos(unix_log, tmp_path):
    """``[source] reference`` in any solution format: the simulated truth as a CSV (columns
    mapped; no quality column: every epoch is the reference) scores the run as the ``.pos``
    reference does."""
    ref = read_pos(unix_log.reference)
    csv = Path(unix_log.folder) / "truth_ref.csv"
    with open(csv, "w") as f:
        f.write("gps_s,lat,lon,h,ve,vn,vu\n")
        for k in range(len(ref.t)):
            f.write(f"{float(ref.t[k])!r},{float(ref.lat[k])!r},{float(ref.lon[k])!r},{float(ref.height[k])!r},"
                    f"{float(ref.vel[k, 0])!r},{float(ref.vel[k, 1])!r},{float(ref.vel[k, 2])!r}\n")
    raw = dict(load_scenario(str(unix_log.scenario)).raw)
    base = navfdi.run_scenario(from_dict(raw, source=str(unix_log.scenario))).runs["fde"].errors()
    raw["source"] = {**raw["source"], "reference": {"file": "truth_ref.csv", "format": "csv",
                                                    "columns": {"time": "gps_s", "lat": "lat", "lon": "lon", "height": "h", "vel": ["ve", "vn", "vu"]}}}
    e = navfdi.run_scenario(from_dict(raw, source=str(unix_log.scenario))).runs["fde"].errors()
    assert e["scored"] == base["scored"] > 150
    assert e["hor_rms"] == pytest.approx(base["hor_rms"], rel=1e-9)
    raw["source"]["reference_quality"] = [1]
    with pytest.raises(ScenarioError, match="source.reference_quality: the reference has no solution quality \\(a CSV"):
        navfdi.run_scenario(from_dict(raw, source=str(unix_log.scenario)))
    raw["source"] = {**raw["source"], "reference": {"file": "nope.csv", "format": "csv", "columns": {}}}
    del raw["source"]["reference_quality"]
    with pytest.raises(ScenarioError, match="source.reference"):
        navfdi.run_scenario(from_dict(raw, source=str(unix_log.scenario)))
