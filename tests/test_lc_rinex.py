"""The loosely coupled filter straight from RINEX observation and navigation files
(``[source] gnss = { format = "rinex", … }``): navfdi's own single-point solution with FDE as
the log is read, the same fixes and σ as ``navfdi gnss``'s ``solution.csv``, and a step held
out on the recorded walk."""

from __future__ import annotations

import subprocess
import sys
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi._gnss_geometry import enu_sigma
from navfdi.gnss import gnss_solve
from navfdi.gnss_logs import read_gnss
from navfdi.scenario import ScenarioError, load_scenario

WALK = Path(str(resources.files("navfdi") / "data" / "walk_0827"))
OBS, NAV = WALK / "gnss_1730.obs.gz", WALK / "gnss_1730.nav"


def _scenario(folder: Path, gnss: str, fault: bool = True) -> Path:
    text = f'''name = "walk_lc"
architecture = "loosely_coupled"

[source]
gnss = {gnss}
reference = "{WALK / 'gnss_1730_sf_ellh.pos.gz'}"
reference_quality = [1, 2]

[source.imu]
file = "{WALK / 'imu_1730_gpst.csv.gz'}"
week = "gps_week"
seconds = "gps_sow_s"
gyro = ["gyro_x_dps", "gyro_y_dps", "gyro_z_dps"]
accel = ["acc_x_g", "acc_y_g", "acc_z_g"]
gyro_unit = "deg/s"
accel_unit = "g"
max_gap = 0.1

[[sensors]]
name = "gnss_pos"
kind = "gnss_position"
noise = "3 m"
rate = "4 Hz"

[[sensors]]
name = "gnss_vel"
kind = "gnss_velocity"
noise = "0.2 m/s"
rate = "4 Hz"

[loosely_coupled]
mounting = ["180 deg", "0 deg", "-90 deg"]
lever_arm = ["0 m", "-0.05 m", "0 m"]
imu = {{ gyro_noise = "0.05 deg/s/sqrt(Hz)", accel_noise = "0.5 mg/sqrt(Hz)", gyro_bias = "0.01 deg/s", accel_bias = "0.01 m/s2", bias_tau = "300 s" }}
alignment = {{ speed = "0.5 m/s", static_speed = "0.2 m/s", sigma_level = "2 deg", sigma_heading = "20 deg", sigma_position = "3 m", sigma_velocity = "0.2 m/s" }}
sensors = [
  {{ sensor = "gnss_pos", detectors = [{{ name = "chi2", kind = "chi2", pf = 1e-4 }}, {{ name = "exclude", kind = "chi2", pf = 1e-5 }}], decision = "exclude" }},
  {{ sensor = "gnss_vel", detectors = [{{ name = "chi2", kind = "chi2", pf = 1e-4 }}, {{ name = "exclude", kind = "chi2", pf = 1e-7 }}], decision = "exclude" }},
]
'''
    if fault:
        text += '''
[[faults]]
id = "step"
sensor = "gnss_pos"
components = ["pos_n"]
kind = "step"
magnitude = "20 m"
start = "50 s"
end = "90 s"

[[variants]]
name = "fde"

[[variants]]
name = "no_fde"
set = { "loosely_coupled.isolate" = false }
'''
    p = folder / "walk_lc.toml"
    p.write_text(text, encoding="utf-8")
    return p


RINEX = f'{{ format = "rinex", obs = "{OBS}", nav = "{NAV}", systems = ["G", "E"], weighting = "cn0" }}'


def test_rinex_source_is_navfdi_gnss_solution(tmp_path: Path) -> None:
    """The fixes, σ and velocities read from RINEX are those of ``navfdi gnss``'s
    solution.csv with the same settings (one solve, two routes)."""
    out = tmp_path / "g"
    r = subprocess.run([sys.executable, "-m", "navfdi", "gnss", str(OBS), str(NAV), "--systems", "G,E", "--weighting", "cn0", "--out", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    a = read_gnss({"file": str(out / "solution.csv")}, tmp_path)
    b = read_gnss({"format": "rinex", "obs": str(OBS), "nav": str(NAV), "systems": ["G", "E"], "weighting": "cn0"}, tmp_path)
    assert len(a.t) == len(b.t) > 500
    for x, y in ((a.t, b.t), (a.lat, b.lat), (a.lon, b.lon), (a.height, b.height), (a.vel, b.vel), (a.sd_pos, b.sd_pos)):
        np.testing.assert_allclose(x, y, rtol=1e-12, atol=1e-9)
    assert np.isfinite(b.sd_pos).all() and (b.sd_pos[:, 2] > b.sd_pos[:, :2].max(axis=1)).mean() > 0.9


def test_enu_sigma_is_the_weighted_geometry() -> None:
    """σ east, north, up of an epoch from the used satellites' lines of sight, one clock per
    system and 1/σ² weights, computed here term by term; NaN with fewer satellites than
    unknowns."""
    sol = gnss_solve(OBS, NAV, systems=["G", "E"], weighting="cn0")
    sats = sol.satellites
    k = int(sol.solution["used"].to_numpy().argmax())
    u = sats[(sats["epoch"] == k) & (sats["status"] == "used")]
    el, az = np.radians(u["elevation"].to_numpy(float)), np.radians(u["azimuth"].to_numpy(float))
    sys_ = u["satellite"].astype(str).str[0].to_numpy()
    h = np.column_stack([-np.cos(el) * np.sin(az), -np.cos(el) * np.cos(az), -np.sin(el), sys_ == "E", sys_ == "G"]).astype(float)
    c = np.linalg.inv(h.T @ np.diag(1.0 / u["sigma"].to_numpy(float) ** 2) @ h)
    np.testing.assert_allclose(sol.solution.loc[k, ["sd_e", "sd_n", "sd_u"]].to_numpy(float), np.sqrt(np.diag(c)[:3]), rtol=1e-9)
    few = sats[(sats["epoch"] == k)].copy()
    few.loc[few.index[4:], "status"] = "excluded"
    assert np.isnan(enu_sigma(few, k + 1)[k]).all()


def test_walk_loosely_coupled_from_rinex_holds_a_step_out(tmp_path: Path) -> None:
    """The walk's RINEX straight into the loosely coupled filter: a 20 m north step is left
    out at every fix of its 40 s (4 Hz) and the error in it stays at the fault-free level
    (the reference's steady base offset removed), while without FDE the filter follows it."""
    run = navfdi.run_scenario(load_scenario(_scenario(tmp_path, RINEX)))
    fde, none = run.runs["fde"], run.runs["no_fde"]
    assert fde.exclusion_counts()["gnss_pos"]["step"] >= 159
    off = fde.reference_offset()
    t = fde.t
    m = (t >= 50) & (t < 90) & np.isfinite(fde.record["error"][:, 6])
    err = fde.record["error"][m, 6:8] - off[:2]
    assert np.hypot(err[:, 0], err[:, 1]).max() < 2.5
    err0 = none.record["error"][m, 6:8] - off[:2]
    assert np.hypot(err0[:, 0], err0[:, 1]).max() > 10.0


def test_bad_rinex_sources_are_named(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError, match=r"source.gnss.nav: the RINEX navigation file's path is required"):
        read_gnss({"format": "rinex", "obs": str(OBS)}, tmp_path)
    with pytest.raises(ScenarioError, match="no such file"):
        read_gnss({"format": "rinex", "obs": str(OBS), "nav": str(tmp_path / "x.nav")}, tmp_path)
    with pytest.raises(ScenarioError, match="unknown key.*mask"):
        read_gnss({"format": "rinex", "obs": str(OBS), "nav": str(NAV), "mask": "5 deg"}, tmp_path)
    with pytest.raises(ScenarioError, match="systems"):
        read_gnss({"format": "rinex", "obs": str(OBS), "nav": str(NAV), "systems": [1]}, tmp_path)
    with pytest.raises(ScenarioError, match="elevation_mask"):
        read_gnss({"format": "rinex", "obs": str(OBS), "nav": str(NAV), "elevation_mask": "5 m"}, tmp_path)
    for bad in (-1.0, 0, "loud", True, float("nan")):
        with pytest.raises(ScenarioError, match=r"source.gnss.noise = .*\"auto\" or a positive factor"):
            read_gnss({"format": "rinex", "obs": str(OBS), "nav": str(NAV), "noise": bad}, tmp_path)


def test_the_rinex_source_takes_a_noise_factor(tmp_path: Path) -> None:
    """``noise = 2.0`` is ``navfdi gnss --noise 2`` (the σ of the fixes from that solve); the
    default estimates it from the file, as ``navfdi gnss`` does."""
    cfg = {"format": "rinex", "obs": str(OBS), "nav": str(NAV), "systems": ["G", "E"], "weighting": "elevation"}
    two = read_gnss({**cfg, "noise": 2.0}, tmp_path)
    sol = gnss_solve(OBS, NAV, systems=["G", "E"], weighting="elevation", noise_scale=2.0).solution
    sol = sol[sol["status"] != "no_solution"]
    np.testing.assert_allclose(two.sd_pos[:, 0], sol["sd_e"].to_numpy(float), rtol=1e-12)
    auto = read_gnss(cfg, tmp_path)
    est = gnss_solve(OBS, NAV, systems=["G", "E"], weighting="elevation").config["noise_scale"]
    assert est > 2.0  # the walk's u-blox: 2.35 on the elevation model
    assert np.median(auto.sd_pos[:, 0] / two.sd_pos[:, 0]) == pytest.approx(est / 2.0, rel=1e-9)
