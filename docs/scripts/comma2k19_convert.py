"""Convert the comma2k19 segment (../shared/data/comma2k19_segment, MIT, comma.ai) into the
files the bundled ``comma_lc`` scenario reads (python/navfdi/data/comma2k19/): the phone IMU
as a CSV in GPS seconds (boot time + 357 697.849502 s, week 2012; axes forward, right, down),
the u-blox fixes decimated to the first fix of each GPS second as a CSV (GPS seconds from UTC
ms + 18 s; velocity east/north from speed and bearing, vertical 0), and comma's pose (camera,
ECEF, 20 Hz: a smooth trajectory, not independent of the GNSS) as an RTKLIB-style .pos.
Run: python docs/scripts/comma2k19_convert.py SEGMENT_DIR OUT_DIR"""

from __future__ import annotations

import gzip
import math
import shutil
import sys
from pathlib import Path

import numpy as np

from navfdi.gnss import ecef_to_lla

WEEK, BOOT_TO_TOW = 2012, 357_697.849502


def main(src: str, out: str) -> None:
    d, o = Path(src), Path(out)
    o.mkdir(parents=True, exist_ok=True)
    L = lambda p: np.load(d / p)  # noqa: E731
    t = L("processed_log/IMU/accelerometer/t")
    acc, gyr = L("processed_log/IMU/accelerometer/value"), L("processed_log/IMU/gyro/value")
    assert np.array_equal(t, L("processed_log/IMU/gyro/t"))
    with gzip.open(o / "imu.csv.gz", "wt", encoding="utf-8") as f:
        f.write("gps_week,gps_tow_s,gyro_x_rads,gyro_y_rads,gyro_z_rads,acc_x_mps2,acc_y_mps2,acc_z_mps2\n")
        for k in range(len(t)):
            f.write(f"{WEEK},{t[k] + BOOT_TO_TOW:.6f},{gyr[k, 0]:.7f},{gyr[k, 1]:.7f},{gyr[k, 2]:.7f},{acc[k, 0]:.6f},{acc[k, 1]:.6f},{acc[k, 2]:.6f}\n")
    u = L("processed_log/GNSS/live_gnss_ublox/value")
    gps = u[:, 3] / 1000.0 + 18.0 - 315964800.0  # UTC ms since 1970 → GPS seconds since 1980-01-06
    sec = np.floor(gps)
    first = np.flatnonzero(np.r_[True, np.diff(sec) > 0])
    with open(o / "ublox.csv", "w", encoding="utf-8") as f:
        f.write("gps_seconds,lat_deg,lon_deg,height_m,vel_e,vel_n,vel_u\n")
        for k in first:
            sp, brg = u[k, 2], math.radians(u[k, 5])
            f.write(f"{gps[k]:.3f},{u[k, 0]:.9f},{u[k, 1]:.9f},{u[k, 4]:.3f},{sp * math.sin(brg):.4f},{sp * math.cos(brg):.4f},0\n")
    pt = L("global_pose/frame_gps_times")
    lla = ecef_to_lla(L("global_pose/frame_positions"))
    with gzip.open(o / "pose.pos.gz", "wt", encoding="utf-8") as f:
        f.write("% comma2k19 global_pose (camera; post-processed INS/GNSS/vision fit, not independent of the GNSS)\n")
        f.write("%  GPST                  latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)\n")
        for k in range(len(pt)):
            f.write(f"{int(pt[k, 0])} {pt[k, 1]:.3f} {lla[k, 0]:.9f} {lla[k, 1]:.9f} {lla[k, 2]:.4f} 1 0 1.0 1.0 1.0\n")
    shutil.copy(d / "LICENSE", o / "LICENSE")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
