"""A time-of-week column in milliseconds (u-blox's ``iTOW``) with ``gps_week`` and
``time_unit = "ms"``, in the IMU log and in a GNSS CSV: read as the same times as seconds of
week."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from navfdi.gnss_logs import read_gnss
from navfdi.logs import read_imu

WEEK = 2374
TOW = 243261.85


def test_imu_itow_in_ms(tmp_path: Path):
    rows = [f"{round((TOW + k * 0.01) * 1000)},0.001,0.002,-0.003,0.1,0.2,-9.8" for k in range(300)]
    (tmp_path / "imu.csv").write_text("itow,gx,gy,gz,ax,ay,az\n" + "\n".join(rows) + "\n")
    cols = {"seconds": "itow", "gps_week": WEEK, "time_unit": "ms", "gyro": ["gx", "gy", "gz"], "accel": ["ax", "ay", "az"]}
    got = read_imu(tmp_path / "imu.csv", cols)
    np.testing.assert_allclose(got.t, WEEK * 604800.0 + TOW + np.arange(300) * 0.01, rtol=0, atol=1e-6)


def test_gnss_csv_itow_in_ms(tmp_path: Path):
    rows = [f"{round((TOW + k) * 1000)},40.1,-105.1,1601.0" for k in range(5)]
    (tmp_path / "fix.csv").write_text("itow,lat,lon,h\n" + "\n".join(rows) + "\n")
    cfg = {"file": "fix.csv", "format": "csv", "gps_week": WEEK, "time_unit": "ms",
           "columns": {"time": "itow", "lat": "lat", "lon": "lon", "height": "h"}}
    got = read_gnss(cfg, tmp_path)
    np.testing.assert_allclose(got.t, WEEK * 604800.0 + TOW + np.arange(5), rtol=0, atol=1e-6)
