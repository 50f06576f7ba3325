"""Derive ``navfdi/data/walk_0827/imu_1730_gpst.csv.gz`` from the walk's raw IMU log and its
RTKLIB time-tag file (rtklibexplorer/GNSS_IMU, BSD-3), the same mapping as the drive's
``imu_1934_gpst.csv`` (see that data's README) and as the repository's
``src/convert_imu_file.py`` **without** its zero-phase low-pass filter: only the time column is
made; no value is filtered, resampled or rescaled.

1. ``start`` = ``time + sec`` of the tag file's header (GPST seconds since 1970, GPS scale);
   ``end`` = ``start`` + (ms of the last tag record) / 1000.
2. The raw CSV without its first (partial) and last (truncated) line; with ``c`` the ms
   counter, ``t = start + (c − c[0])/1000 · (end − start) / ((c[−1] − c[0])/1000)``.
3. GPS week and seconds of week from ``t − 315964800``.

Usage: ``python docs/scripts/walk_imu_gpst.py RAW.csv RAW.csv.tag OUT.csv.gz``.
"""

from __future__ import annotations

import gzip
import struct
import sys

WEEK = 604800.0
GPS_EPOCH_UNIX = 315964800.0


def main(raw: str, tag: str, out: str) -> None:
    b = open(tag, "rb").read()
    if not b.startswith(b"TIMETAG RTKLIB"):
        raise SystemExit(f"{tag}: not an RTKLIB time-tag file")
    tm, = struct.unpack("<I", b[64:68])
    sec, = struct.unpack("<d", b[68:76])
    last_ms, = struct.unpack("<I", b[len(b) - 8:len(b) - 4])
    start = tm + sec
    end = start + last_ms / 1000.0
    lines = open(raw, encoding="ascii").read().splitlines()[1:-1]
    rows = [ln.split(",") for ln in lines]
    c = [int(r[6]) for r in rows]
    stretch = (end - start) / ((c[-1] - c[0]) / 1000.0)
    with gzip.open(out, "wt", encoding="ascii", newline="\n") as f:
        f.write("gps_week,gps_sow_s,acc_x_g,acc_y_g,acc_z_g,gyro_x_dps,gyro_y_dps,gyro_z_dps,imu_counter_ms\n")
        for r, ci in zip(rows, c):
            t = start + (ci - c[0]) / 1000.0 * stretch - GPS_EPOCH_UNIX
            week = int(t // WEEK)
            f.write(f"{week},{t - week * WEEK:.4f},{','.join(x.strip() for x in r[:6])},{ci}\n")
    print(f"{out}: {len(rows)} samples, stretch {stretch:.6f}, {start - GPS_EPOCH_UNIX:.3f}–{end - GPS_EPOCH_UNIX:.3f} GPS s")


if __name__ == "__main__":
    main(*sys.argv[1:4])
