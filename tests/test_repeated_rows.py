"""Rows a logger wrote twice — the same time and the same values — are left out and said
(nothing is lost), in the IMU CSV, the ``.pos`` and the other GNSS formats; the same time
with other values is still refused with its line."""

from __future__ import annotations

import gzip
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from navfdi import ImuGapWarning, LeftOutFixesWarning, LeftOutSamplesWarning, ScenarioError
from navfdi.gnss_logs import read_gnss
from navfdi.logs import read_imu, read_pos
from navfdi.scenario import load_scenario

DRIVE = Path(str(resources.files("navfdi"))) / "data" / "drive_0708"


def lines(name: str) -> list[str]:
    return gzip.open(DRIVE / name, "rt").read().splitlines()


def test_an_imu_row_written_twice_is_left_out(tmp_path: Path):
    cols = load_scenario("drive_lc").raw["source"]["imu"]
    rows = lines("imu_1934_gpst.csv.gz")
    (tmp_path / "imu.csv").write_text("\n".join(rows[:20001] + [rows[20000], rows[20000]] + rows[20001:]) + "\n")
    with pytest.warns(LeftOutSamplesWarning, match=r"2 row\(s\) repeating the row before them exactly .*the first at line 20002\) left out"):
        got = read_imu(tmp_path / "imu.csv", cols)
    want = read_imu(DRIVE / "imu_1934_gpst.csv.gz", cols)
    np.testing.assert_array_equal(got.t, want.t)
    np.testing.assert_array_equal(got.accel, want.accel)
    other = rows[20000].rsplit(",", 2)[0] + ",0.5,999999"
    (tmp_path / "bad.csv").write_text("\n".join(rows[:20001] + [other] + rows[20001:]) + "\n")
    with pytest.raises(ScenarioError, match=r"line 20002, column 'gps_sow_s': time does not increase"):
        read_imu(tmp_path / "bad.csv", cols)


def test_a_pos_epoch_written_twice_is_left_out(tmp_path: Path):
    rows = lines("gnss_1934_sf.pos.gz")
    k = next(i for i, r in enumerate(rows) if not r.startswith("%")) + 500
    (tmp_path / "a.pos").write_text("\n".join(rows[: k + 1] + [rows[k]] + rows[k + 1:]) + "\n")
    with pytest.warns(LeftOutFixesWarning, match=rf"1 fix\(es\) repeating the epoch before them exactly \(the first at line {k + 2}\)"):
        got = read_pos(tmp_path / "a.pos")
    want = read_pos(DRIVE / "gnss_1934_sf.pos.gz")
    np.testing.assert_array_equal(got.t, want.t)
    np.testing.assert_array_equal(got.lat, want.lat)
    np.testing.assert_array_equal(got.vel, want.vel)
    swapped = rows[:k] + [rows[k + 1], rows[k]] + rows[k + 2:]
    (tmp_path / "b.pos").write_text("\n".join(swapped) + "\n")
    with pytest.raises(ScenarioError, match=rf"b\.pos, line {k + 2}: epoch .* does not come after the one before it"):
        read_pos(tmp_path / "b.pos")


def test_a_csv_epoch_written_twice_is_left_out(tmp_path: Path):
    cfg = {"format": "csv", "columns": {"time": "t", "lat": "lat", "lon": "lon", "height": "h"}}
    body = ["t,lat,lon,h", "1436038700.0,40.1,-105.1,1601.0", "1436038701.0,40.1,-105.1,1601.5"]
    (tmp_path / "a.csv").write_text("\n".join(body + [body[2]]) + "\n")
    with pytest.warns(LeftOutFixesWarning, match=r"1 fix\(es\) repeating the epoch before them exactly left out"):
        got = read_gnss({**cfg, "file": "a.csv"}, tmp_path)
    assert list(got.t) == [1436038700.0, 1436038701.0]
    (tmp_path / "b.csv").write_text("\n".join(body + ["1436038701.0,40.1,-105.1,1609.5"]) + "\n")
    with pytest.raises(ScenarioError, match=r"two different epochs at 1436038701\.000 GPS s"):
        read_gnss({**cfg, "file": "b.csv"}, tmp_path)


def test_placeholder_rows_are_left_out_as_missing_samples(tmp_path: Path):
    # Three rows of zeros every 50 s (a logger's placeholder for samples it did not get):
    # mechanised, each is 0.01 s of free fall; left out, the interval is a gap.
    import navfdi
    from navfdi.scenario import from_dict

    rows = lines("imu_1934_gpst.csv.gz")
    out = [rows[0]]
    for i, r in enumerate(rows[1:], 1):
        if any(s <= i < s + 3 for s in range(5000, 54000, 5000)):
            f = r.split(",")
            r = ",".join(f[:2] + ["0"] * 6 + f[8:])
        out.append(r)
    (tmp_path / "imu.csv").write_text("\n".join(out) + "\n")
    raw = dict(load_scenario("drive_lc").raw)
    src = Path(str(resources.files("navfdi"))) / "scenarios" / "drive_lc.toml"
    intact = navfdi.run_scenario(from_dict(raw, source=str(src))).runs["fde"].errors()
    raw["source"] = {**raw["source"], "imu": {**raw["source"]["imu"], "file": str(tmp_path / "imu.csv")}}
    with pytest.warns(ImuGapWarning, match=r"has 10 gap\(s\)"), \
            pytest.warns(LeftOutSamplesWarning, match=r"30 row\(s\) with a specific force of exactly zero .*the first at line 5001\) left out"):
        got = navfdi.run_scenario(from_dict(raw, source=str(src))).runs["fde"].errors()
    # Mechanised as read, the vertical RMS went 0.043 → 0.075 m.
    assert got["ver_rms"] <= 1.1 * intact["ver_rms"], (intact, got)
    assert got["hor_rms"] <= 1.1 * intact["hor_rms"], (intact, got)


def test_batch_stamps_are_refused_or_spread(tmp_path: Path):
    # Samples stamped in batches of ten with the first one's time, as some loggers write them.
    import navfdi
    from navfdi.scenario import from_dict

    rows = lines("imu_1934_gpst.csv.gz")
    out = [rows[0]]
    for i, r in enumerate(rows[1:]):
        f = r.split(",")
        f[1] = rows[1 + i - i % 10].split(",")[1]
        out.append(",".join(f))
    (tmp_path / "imu.csv").write_text("\n".join(out) + "\n")
    raw = dict(load_scenario("drive_lc").raw)
    src = Path(str(resources.files("navfdi"))) / "scenarios" / "drive_lc.toml"
    cols = {**raw["source"]["imu"], "file": str(tmp_path / "imu.csv"), "max_gap": 1.0}
    with pytest.raises(ScenarioError, match=r"line 3, column 'gps_sow_s': time does not increase .*time_repeats = \"spread\""):
        read_imu(tmp_path / "imu.csv", cols)
    with pytest.raises(ScenarioError, match=r"time_repeats = 'keep': \"refuse\" \(default\) or \"spread\""):
        read_imu(tmp_path / "imu.csv", {**cols, "time_repeats": "keep"})
    spread = read_imu(tmp_path / "imu.csv", {**cols, "time_repeats": "spread"})
    assert np.abs(spread.t - read_imu(DRIVE / "imu_1934_gpst.csv.gz", cols).t).max() < 0.003
    intact = navfdi.run_scenario(from_dict(raw, source=str(src))).runs["fde"].errors()
    raw["source"] = {**raw["source"], "imu": {**cols, "time_repeats": "spread"}}
    got = navfdi.run_scenario(from_dict(raw, source=str(src))).runs["fde"].errors()
    assert got["hor_rms"] <= 1.05 * intact["hor_rms"], (intact, got)
