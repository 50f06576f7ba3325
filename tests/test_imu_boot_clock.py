"""IMU logs stamped on the IMU's own clock (seconds since power-up): ``[source.imu]
time_scale = "boot"`` places them on the GNSS log's GPS time by matching the IMU's turn rate
to the GNSS track's (:func:`navfdi.frames.imu_clock_offset`). The drive's IMU restamped on a
boot clock is placed back within the 0.1 s search step; logs whose turns do not say it are
refused with the reason."""

from __future__ import annotations

import gzip
import warnings
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi import ScenarioError
from navfdi._errors import ScenarioWarning
from navfdi.scenario import from_dict, load_scenario
from navfdi.simlog import simulate_log

PKG = Path(str(resources.files("navfdi")))
TRUE_OFFSET = 2374 * 604800 + 243000.0 - 12.345  # GPS seconds of the boot clock's 0


@pytest.fixture(scope="module")
def boot_imu(tmp_path_factory: pytest.TempPathFactory) -> Path:
    rows = gzip.open(PKG / "data" / "drive_0708" / "imu_1934_gpst.csv.gz", "rt").read().splitlines()
    out = tmp_path_factory.mktemp("boot") / "imu_boot.csv"
    with open(out, "w") as f:
        f.write("t_boot,acc_x_g,acc_y_g,acc_z_g,gyro_x_dps,gyro_y_dps,gyro_z_dps\n")
        for r in rows[1:]:
            v = r.split(",")
            f.write(f"{float(v[0]) * 604800 + float(v[1]) - TRUE_OFFSET:.4f}," + ",".join(v[2:8]) + "\n")
    return out


def _drive_with(imu_file: Path) -> dict:
    raw = dict(load_scenario("drive_lc").raw)
    imu = {k: v for k, v in raw["source"]["imu"].items() if k not in ("week", "seconds")}
    imu.update({"file": str(imu_file), "time": "t_boot", "time_scale": "boot"})
    src = {**raw["source"], "imu": imu}
    for k in ("gnss", "reference"):
        src[k] = str(PKG / "scenarios" / src[k])
    raw["source"] = src
    return raw


def test_the_drive_on_a_boot_clock_is_placed_by_its_turns(boot_imu: Path):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        run = navfdi.run_scenario(from_dict(_drive_with(boot_imu), source=str(boot_imu.parent / "s.toml")))
    said = [str(x.message) for x in w if issubclass(x.category, ScenarioWarning) and "boot" in str(x.message)]
    assert len(said) == 1, said
    off = float(said[0].split("turns, ")[1].split(" s added")[0])
    # The search's step is 0.1 s (the filter's imu_time_offset refines within it).
    assert abs(off - TRUE_OFFSET) <= 0.1
    base = navfdi.run_scenario("drive_lc")
    e, b = run.runs["no_fde"].errors(), base.runs["no_fde"].errors()
    assert e["scored"] == b["scored"]
    assert abs(e["hor_rms"] - b["hor_rms"]) < 0.01 * b["hor_rms"]


def test_a_drive_without_turns_is_refused(tmp_path: Path):
    straight = {"latitude": "40 deg", "longitude": "-105 deg", "height": "1600 m", "heading": "30 deg", "speed": "0 m/s",
                "segments": [{"kind": "stationary", "duration": "20 s"}, {"kind": "accelerate", "duration": "10 s", "acceleration": "1.5 m/s2"},
                             {"kind": "level", "duration": "170 s"}]}
    log = simulate_log(tmp_path, duration=200, seed=1, trajectory=straight, gnss_rate=1.0)
    raw = dict(load_scenario(str(log.scenario)).raw)
    imu = {k: v for k, v in raw["source"]["imu"].items() if k not in ("week", "seconds")}
    rows = Path(log.imu).read_text().splitlines()
    with open(tmp_path / "imu_boot.csv", "w") as f:
        f.write("t_boot," + ",".join(rows[0].split(",")[2:]) + "\n")
        for r in rows[1:]:
            v = r.split(",")
            f.write(f"{float(v[1]) - 240000.0 + 5.0:.6f}," + ",".join(v[2:]) + "\n")
    imu.update({"file": "imu_boot.csv", "time": "t_boot", "time_scale": "boot"})
    raw["source"] = {**raw["source"], "imu": imu}
    with pytest.raises(ScenarioError, match=r"time_scale = \"boot\": the IMU's clock cannot be placed .* too few turns"):
        navfdi.run_scenario(from_dict(raw, source=str(log.scenario)))


def test_boot_time_needs_a_gnss_log_and_a_single_time_column(boot_imu: Path, tmp_path: Path):
    from navfdi.logs import load_source

    imu = {"file": str(boot_imu), "time": "t_boot", "time_scale": "boot", "gyro": ["gyro_x_dps", "gyro_y_dps", "gyro_z_dps"],
           "accel": ["acc_x_g", "acc_y_g", "acc_z_g"], "gyro_unit": "deg/s", "accel_unit": "g"}
    with pytest.raises(ScenarioError, match=r"a tight scenario's RINEX has none"):
        load_source({"imu": imu, "rinex_obs": "x.obs", "rinex_nav": "x.nav"}, tmp_path)
    bad = {**{k: v for k, v in imu.items() if k != "time"}, "week": "w", "seconds": "s"}
    with pytest.raises(ScenarioError, match=r"time_scale and time_unit are for a single time column"):
        load_source({"imu": bad, "gnss": "g.pos"}, tmp_path)


def test_a_boot_clock_that_runs_fast_is_placed_with_its_rate(boot_imu: Path, tmp_path: Path):
    # The same log on a clock 1500 ppm fast (0.8 s over the drive; a ceramic resonator's
    # error, where a crystal's is tens of ppm): one offset leaves the ends 0.4 s off.
    rows = boot_imu.read_text().splitlines()
    t = np.array([float(r.split(",", 1)[0]) for r in rows[1:]])
    fast = tmp_path / "imu_fast.csv"
    fast.write_text("\n".join([rows[0]] + [f"{(v - t[0]) * 1.0015 + t[0]:.6f}," + r.split(",", 1)[1] for v, r in zip(t, rows[1:])]) + "\n")

    def run(path: Path) -> tuple[navfdi.VariantRuns, str]:
        from navfdi import logs

        logs._BOOT_OFFSETS.clear()  # said once per process: say it again
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            r = navfdi.run_scenario(from_dict(_drive_with(path), source=str(path.parent / "s.toml")))
        return r, next(str(x.message) for x in w if "time_scale = \"boot\"" in str(x.message))

    steady, said_steady = run(boot_imu)
    drifting, said = run(fast)
    assert "its clock runs" not in said_steady  # the bundled stamps' own rate is not significant
    rate, se = (float(x) for x in said.split("its clock runs ")[1].split(" ppm")[0].split(" ± "))
    # The estimate holds the bundled stamps' own rate against the turns (about +370 ± 200 ppm
    # on the drive, below three standard errors) beside the 1500 ppm added.
    assert abs(rate - 1500) < 3 * se + 400, said
    a, b = steady.runs["fde"].errors(), drifting.runs["fde"].errors()
    # Placed by one offset: 0.27 m RMS and 2.7 m at worst at 1000 ppm (0.066 / 0.30 m steady).
    assert b["hor_rms"] <= 1.2 * a["hor_rms"] and b["hor_max"] <= 1.2 * a["hor_max"], (a, b)
