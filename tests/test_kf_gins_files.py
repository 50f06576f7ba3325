"""The drive in KF-GINS's own file formats — the IMU as column-aligned text without a header
(seconds of week, angle and velocity increments in rad and m/s) and the GNSS positions as
column-aligned text (seconds of week, latitude, longitude, height, σ north, east, up) — read
with ``[source.imu] header = false, delimiter = "whitespace", gps_week, kind = "increments"``
and a ``csv`` GNSS source with the same keys: the same samples and fixes, and the same run."""

from __future__ import annotations

import gzip
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi import ScenarioError
from navfdi.gnss_logs import read_gnss
from navfdi.logs import read_imu, read_pos
from navfdi.scenario import from_dict, load_scenario

PKG = Path(str(resources.files("navfdi")))
DRIVE = PKG / "data" / "drive_0708"
WEEK = 2374
IMU_KF = {"file": "imu_kf.txt", "header": False, "delimiter": "whitespace", "gps_week": WEEK, "seconds": 1,
          "gyro": [2, 3, 4], "accel": [5, 6, 7], "kind": "increments", "gyro_unit": "rad/s", "accel_unit": "m/s^2"}
GNSS_KF = {"file": "gnss_kf.txt", "format": "csv", "header": False, "delimiter": "whitespace", "gps_week": WEEK,
           "columns": {"time": 1, "lat": 2, "lon": 3, "height": 4, "sd": [6, 5, 7]}}


@pytest.fixture(scope="module")
def kf_files(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("kf")
    sc = load_scenario("drive_lc")
    cols = sc.raw["source"]["imu"]
    imu = read_imu(DRIVE / "imu_1934_gpst.csv.gz", cols)
    # Increments over each sample's interval (the first: the next one's), in the seconds of
    # week the file holds.
    sow = np.round(imu.t - WEEK * 604800.0, 6)
    dt = np.diff(sow, prepend=sow[0] - (sow[1] - sow[0]))
    with open(d / "imu_kf.txt", "w") as f:
        for k in range(len(sow)):
            inc = [*(imu.gyro[k] * dt[k]), *(imu.accel[k] * dt[k])]
            f.write(f"  {sow[k]:.6f}" + "".join(f"  {v:22.15e}" for v in inc) + "\n")
    pos = read_pos(DRIVE / "gnss_1934_sf.pos.gz")
    with open(d / "gnss_kf.txt", "w") as f:
        for k in range(len(pos.t)):
            vals = [pos.lat[k], pos.lon[k], pos.height[k], pos.sd_pos[k, 1], pos.sd_pos[k, 0], pos.sd_pos[k, 2]]
            f.write(f"{pos.t[k] - WEEK * 604800.0:12.3f}" + "".join(f" {float(v)!r:>18}" for v in vals) + "\n")
    return d


def test_the_files_read_as_the_originals(kf_files: Path):
    sc = load_scenario("drive_lc")
    a = read_imu(DRIVE / "imu_1934_gpst.csv.gz", sc.raw["source"]["imu"])
    b = read_imu(kf_files / "imu_kf.txt", IMU_KF)
    np.testing.assert_allclose(b.t, a.t, rtol=0, atol=1e-6)
    np.testing.assert_allclose(b.gyro, a.gyro, rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(b.accel, a.accel, rtol=1e-6, atol=1e-12)
    g, h = read_pos(DRIVE / "gnss_1934_sf.pos.gz"), read_gnss(GNSS_KF, kf_files)
    np.testing.assert_allclose(h.t, g.t, rtol=0, atol=1e-6)
    np.testing.assert_array_equal(h.lat, g.lat)
    np.testing.assert_array_equal(h.sd_pos, g.sd_pos)


def test_the_drive_runs_on_them(kf_files: Path):
    raw = dict(load_scenario("drive_lc").raw)
    base = navfdi.run_scenario(from_dict(raw, source=str(PKG / "scenarios" / "drive_lc.toml"))).runs["no_fde"].errors()
    raw["source"] = {**raw["source"], "imu": {**IMU_KF, "file": str(kf_files / "imu_kf.txt")},
                     "reference": str(DRIVE / "gnss_1934_sf.pos.gz")}
    e = navfdi.run_scenario(from_dict(raw, source=str(PKG / "scenarios" / "drive_lc.toml"))).runs["no_fde"].errors()
    assert e["scored"] == base["scored"]
    assert e["hor_rms"] == pytest.approx(base["hor_rms"], rel=1e-4)


@pytest.mark.parametrize(
    "imu, match",
    [
        ({"gps_week": "2374"}, r"gps_week = '2374': the GPS week number"),
        ({"week": 9}, r"gps_week: with a seconds-of-week column \(seconds = …\) alone"),
        ({"delimiter": "spaces"}, r"delimiter = 'spaces'.*\"whitespace\""),
    ],
)
def test_bad_week_and_separator_settings_are_named(kf_files: Path, imu, match):
    with pytest.raises(ScenarioError, match=match):
        read_imu(kf_files / "imu_kf.txt", {**IMU_KF, **imu})


def test_bad_gnss_settings_are_named(kf_files: Path):
    with pytest.raises(ScenarioError, match=r"gps_week = -1"):
        read_gnss({**GNSS_KF, "gps_week": -1}, kf_files)
    with pytest.raises(ScenarioError, match=r"no such column .*the first line has 7 columns, numbered from 1"):
        read_gnss({**GNSS_KF, "columns": {**GNSS_KF["columns"], "lat": 9}}, kf_files)
