"""An IMU CSV whose time column holds ISO 8601 date-times (as data loggers write them), told
from its first row: in GPS time by default, in UTC with ``time_scale = "utc"`` (the leap
seconds added); the drive's IMU written so reads as its GPS seconds."""

from __future__ import annotations

import datetime as dt
import gzip
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from navfdi import ScenarioError
from navfdi.logs import read_imu
from navfdi.scenario import load_scenario

DRIVE = Path(str(resources.files("navfdi"))) / "data" / "drive_0708"
GPS0 = dt.datetime(1980, 1, 6)


def write(path: Path, shift: float) -> Path:
    """The drive's IMU with its time as ISO date-times ``shift`` s before GPS time."""
    rows = gzip.open(DRIVE / "imu_1934_gpst.csv.gz", "rt").read().splitlines()
    out = ["time," + rows[0].split(",", 2)[2]]
    for r in rows[1:3000]:
        week, sow, rest = r.split(",", 2)
        t = GPS0 + dt.timedelta(seconds=int(week) * 604800 + float(sow) - shift)
        out.append(t.isoformat(timespec="microseconds") + "Z," + rest)
    path.write_text("\n".join(out) + "\n")
    return path


def cols(**more):
    c = dict(load_scenario("drive_lc").raw["source"]["imu"])
    for k in ("week", "seconds"):
        c.pop(k)
    return {**c, "time": "time", **more}


def test_iso_times_in_gps_time_and_utc(tmp_path: Path):
    want = read_imu(DRIVE / "imu_1934_gpst.csv.gz", dict(load_scenario("drive_lc").raw["source"]["imu"]))
    gpst = read_imu(write(tmp_path / "gpst.csv", 0.0), cols())
    np.testing.assert_allclose(gpst.t, want.t[:2999], rtol=0, atol=1e-6)
    utc = read_imu(write(tmp_path / "utc.csv", 18.0), cols(time_scale="utc"))
    np.testing.assert_allclose(utc.t, want.t[:2999], rtol=0, atol=1e-6)
    np.testing.assert_array_equal(utc.gyro, want.gyro[:2999])


def test_iso_settings_that_do_not_fit_are_named(tmp_path: Path):
    path = write(tmp_path / "gpst.csv", 0.0)
    with pytest.raises(ScenarioError, match=r"time_unit: .*holds ISO date-times \(no unit\)"):
        read_imu(path, cols(time_unit="ms"))
    with pytest.raises(ScenarioError, match=r"time_scale = 'utc': for ISO date-times; .*holds numbers"):
        read_imu(DRIVE / "imu_1934_gpst.csv.gz", cols(time="gps_sow_s", time_scale="utc"))
