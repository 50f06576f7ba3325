"""IMU CSV logs without a header line and with other separators (semicolon, tab, space, runs
of whitespace as column-aligned text such as KF-GINS's), as loggers write them: columns
numbered from 1, the same samples as the headed comma file."""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np
import pytest

from navfdi import ScenarioError
from navfdi.logs import read_imu

DRIVE = Path(__file__).parent.parent / "python" / "navfdi" / "data" / "drive_0708" / "imu_1934_gpst.csv.gz"
HEADED = {"week": "gps_week", "seconds": "gps_sow_s", "gyro": ["gyro_x_dps", "gyro_y_dps", "gyro_z_dps"],
          "accel": ["acc_x_g", "acc_y_g", "acc_z_g"], "gyro_unit": "deg/s", "accel_unit": "g"}
# The same columns by number: week 1, seconds 2, accel 3-5, gyro 6-8, counter 9.
NUMBERED = {"header": False, "week": 1, "seconds": "2", "gyro": [6, 7, 8], "accel": [3, 4, 5], "gyro_unit": "deg/s", "accel_unit": "g"}


@pytest.fixture(scope="module")
def drive_rows() -> list[str]:
    lines = gzip.open(DRIVE, "rt").read().splitlines()
    return lines[1:2001]


@pytest.mark.parametrize("delimiter, sep", [(",", ","), (";", ";"), ("tab", "\t"), (" ", " "), ("whitespace", "   \t ")])
def test_headerless_files_read_as_the_headed_one(tmp_path: Path, drive_rows, delimiter, sep):
    headed = tmp_path / "headed.csv"
    headed.write_text(",".join(["gps_week", "gps_sow_s", "acc_x_g", "acc_y_g", "acc_z_g", "gyro_x_dps", "gyro_y_dps", "gyro_z_dps", "imu_counter_ms"]) + "\n"
                      + "\n".join(drive_rows) + "\n")
    bare = tmp_path / "bare.txt"
    # Column-aligned text (the whitespace case) also starts and ends its lines with spaces.
    pad = "  " if delimiter == "whitespace" else ""
    bare.write_text("\n".join(pad + r.replace(",", sep) + pad for r in drive_rows) + "\n")
    a = read_imu(headed, HEADED)
    b = read_imu(bare, {**NUMBERED, "delimiter": delimiter})
    assert len(b.t) == len(drive_rows)
    np.testing.assert_array_equal(b.t, a.t)
    np.testing.assert_array_equal(b.gyro, a.gyro)
    np.testing.assert_array_equal(b.accel, a.accel)


@pytest.mark.parametrize(
    "cols, text, match",
    [
        ({"gyro": [6, 7, 0]}, None, r"gyro: three column numbers \(from 1; header = false\)"),
        ({"time": 2, "week": None, "seconds": None, "gyro": [6, 7, 10]}, None, r"line 1: no column '10' \(the first line has 9 columns, numbered from 1\)"),
        ({"delimiter": "::"}, None, r"delimiter = '::': one ASCII character"),
        ({"header": "no"}, None, r"header = 'no': true .* or false"),
        ({"week": None, "seconds": None}, None, r"without a header line the time column's number is required"),
        ({}, "2374,1.0,0,0,1,0,0,0,5\n2374,1.01,0,0,1,0,0,0\n", r"line 2: 8 fields, the first line has 9"),
        ({"header": True}, None, r"three column names"),
    ],
)
def test_bad_headerless_settings_are_named(tmp_path: Path, drive_rows, cols, text, match):
    f = tmp_path / "bare.csv"
    f.write_text(text if text is not None else "\n".join(drive_rows[:50]) + "\n")
    spec = {k: v for k, v in {**NUMBERED, **cols}.items() if v is not None}
    with pytest.raises(ScenarioError, match=match):
        read_imu(f, spec)
