"""The loosely coupled filter fed GNSS solutions in the formats receivers and tools write:
navfdi's solution.csv, NMEA (GGA/RMC/GST), and any CSV through a column mapping — each the
same positions as an RTKLIB .pos, so each run matches the .pos run."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi._logtime import GPS_EPOCH
from navfdi.gnss_logs import read_gnss
from navfdi.logs import read_pos
from navfdi.scenario import ScenarioError, from_dict, load_scenario
from navfdi.simlog import simulate_log

from loglib import nmea, nmea_lines


@pytest.fixture(scope="module")
def log(tmp_path_factory: pytest.TempPathFactory):
    return simulate_log(tmp_path_factory.mktemp("fmt"), duration=240, seed=5, gnss_rate=1.0, gnss_sigma=1.0)


def _write_formats(log) -> dict[str, Path]:
    p = read_pos(log.gnss)
    folder = Path(log.folder)
    # navfdi solution.csv columns.
    sol = folder / "solution.csv"
    with open(sol, "w") as f:
        f.write("time,gps_seconds,lat,lon,height,vel_e,vel_n,vel_u,status\n")
        for k in range(len(p.t)):
            f.write(f"x,{p.t[k]:.3f},{p.lat[k]:.10f},{p.lon[k]:.10f},{p.height[k]:.4f},{p.vel[k, 0]:.5f},{p.vel[k, 1]:.5f},{p.vel[k, 2]:.5f},passed\n")
    # A CSV with its own names, heights above sea level and UTC ISO times.
    csvp = folder / "receiver.csv"
    und = 12.5
    with open(csvp, "w") as f:
        f.write("utc,latitude_deg,longitude_deg,alt_msl,sig_e,sig_n,sig_u\n")
        for k in range(len(p.t)):
            utc = GPS_EPOCH + dt.timedelta(seconds=float(p.t[k]) - 18.0)
            f.write(f"{utc.isoformat()},{p.lat[k]:.10f},{p.lon[k]:.10f},{p.height[k] - und:.4f},{p.sd_pos[k, 0]:.4f},{p.sd_pos[k, 1]:.4f},{p.sd_pos[k, 2]:.4f}\n")
    # NMEA: GGA (MSL altitude + geoid separation), RMC (date, speed, course), GST (σ).
    nm = folder / "receiver.nmea"
    lines = nmea_lines(p, und)
    nm.write_text("\n".join(lines) + "\n")
    return {"solution": sol, "csv": csvp, "nmea": nm}


def test_every_format_reads_the_same_positions(log) -> None:
    files = _write_formats(log)
    ref = read_pos(log.gnss)
    sol = read_gnss(str(files["solution"]), Path("."))
    csvl = read_gnss({"file": str(files["csv"]), "format": "csv", "time_scale": "utc", "undulation": 12.5,
                      "columns": {"time": "utc", "lat": "latitude_deg", "lon": "longitude_deg", "height_msl": "alt_msl", "sd": ["sig_e", "sig_n", "sig_u"]}}, Path("."))
    nm = read_gnss(str(files["nmea"]), Path("."))
    for g in (sol, csvl, nm):
        np.testing.assert_allclose(g.t, ref.t, atol=0.011)
        np.testing.assert_allclose(g.lat, ref.lat, atol=1e-8)
        np.testing.assert_allclose(g.lon, ref.lon, atol=1e-8)
        np.testing.assert_allclose(g.height, ref.height, atol=1e-3)
    np.testing.assert_allclose(nm.vel[:, :2], ref.vel[:, :2], atol=2e-3)
    np.testing.assert_allclose(nm.sd_pos, ref.sd_pos, atol=1e-3)
    np.testing.assert_allclose(csvl.sd_pos, ref.sd_pos, atol=1e-3)


@pytest.mark.parametrize("fmt", ["solution", "nmea"])
def test_the_filter_runs_on_each_format(log, fmt: str) -> None:
    files = _write_formats(log)
    raw = dict(load_scenario(str(log.scenario)).raw)
    base = navfdi.run_scenario(from_dict(raw, source=str(log.scenario))).runs["fde"].errors()["hor_rms"]
    raw["source"] = {**raw["source"], "gnss": files[fmt].name}
    del raw["duration"], raw["dt"]  # taken from the log
    e = navfdi.run_scenario(from_dict(raw, source=str(log.scenario))).runs["fde"].errors()
    assert e["scored"] > 150
    assert abs(e["hor_rms"] - base) < 0.1 * base + 0.02


def test_bad_gnss_logs_are_named(log, tmp_path: Path) -> None:
    bad = tmp_path / "bad.nmea"
    bad.write_text("$GNGGA,120000.00,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*00\n")
    with pytest.raises(ScenarioError, match="line 1: NMEA checksum"):
        read_gnss(str(bad), Path("."))
    nodate = tmp_path / "nodate.nmea"
    nodate.write_text(nmea("GNGGA,120000.00,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,") + "\n")
    with pytest.raises(ScenarioError, match='date = "YYYY-MM-DD"'):
        read_gnss(str(nodate), Path("."))
    assert read_gnss({"file": str(nodate), "date": "2025-07-08"}, Path(".")).height[0] == pytest.approx(545.4 + 46.9)
    with pytest.raises(ScenarioError, match="no such column"):
        read_gnss({"file": str(log.truth), "format": "csv", "columns": {"time": "nope", "lat": "a", "lon": "b", "height": "c"}}, Path("."))
    with pytest.raises(ScenarioError, match="format not recognised"):
        read_gnss(str(log.truth), Path("."))
