"""A GNSS CSV in ECEF coordinates (``columns.ecef``, ``vel_ecef``, ``sd_ecef``, ``sd_vel_ecef``):
read as the same fixes as their latitude/longitude/height and east/north/up form, without a
hand conversion; rows of zeros (no fix) left out and said."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi import LeftOutFixesWarning, ScenarioError
from navfdi.gnss import enu_rotation, lla_to_ecef
from navfdi.gnss_logs import read_gnss
from navfdi.logs import read_pos
from navfdi.scenario import from_dict, load_scenario

PKG = Path(str(resources.files("navfdi")))
POS = PKG / "data" / "drive_0708" / "gnss_1934_sf.pos.gz"
ECEF = {"time": "t", "ecef": ["x", "y", "z"], "vel_ecef": ["vx", "vy", "vz"], "sd_ecef": ["sx", "sy", "sz"]}


def write(path: Path, zeros: tuple[int, ...] = ()) -> Path:
    """The drive's fixes as ECEF x, y, z with ECEF velocities and a σ of 0.02 m on every axis."""
    g = read_pos(POS)
    r = enu_rotation(g.lat, g.lon)
    lines = ["t,x,y,z,vx,vy,vz,sx,sy,sz"]
    for k in range(len(g.t)):
        x = [0.0] * 3 if k in zeros else [float(c) for c in lla_to_ecef(g.lat[k], g.lon[k], g.height[k])]
        v = [float(c) for c in r[k].T @ g.vel[k]]
        lines.append(",".join(repr(c) for c in [float(g.t[k]), *x, *v]) + ",0.02,0.02,0.02")
    path.write_text("\n".join(lines) + "\n")
    return path


def test_ecef_columns_read_as_the_geodetic_fixes(tmp_path: Path):
    g = read_pos(POS)
    e = read_gnss({"file": str(write(tmp_path / "ecef.csv")), "format": "csv", "columns": ECEF}, tmp_path)
    np.testing.assert_array_equal(e.t, g.t)
    np.testing.assert_allclose(e.lat, g.lat, rtol=0, atol=1e-11)
    np.testing.assert_allclose(e.lon, g.lon, rtol=0, atol=1e-11)
    np.testing.assert_allclose(e.height, g.height, rtol=0, atol=1e-6)
    np.testing.assert_allclose(e.vel, g.vel, rtol=0, atol=1e-9)
    # An isotropic σ is the same on every axis in any frame.
    np.testing.assert_allclose(e.sd_pos, 0.02, rtol=1e-12)


def test_a_row_of_zeros_is_no_fix_and_said(tmp_path: Path):
    path = write(tmp_path / "ecef.csv", zeros=(5, 6, 7))
    with pytest.warns(LeftOutFixesWarning, match=r"3 fix\(es\) without a position \(empty, or ECEF zeros: no fix\) left out"):
        e = read_gnss({"file": str(path), "format": "csv", "columns": ECEF}, tmp_path)
    assert len(e.t) == len(read_pos(POS).t) - 3


def test_an_anisotropic_sigma_turns_with_the_axes(tmp_path: Path):
    # σ only along ECEF z at latitude φ: up gets sin φ of it, north cos φ, east none.
    (tmp_path / "one.csv").write_text("t,x,y,z,sx,sy,sz\n1e9,4517590.878,0,4487348.409,0,0,2\n1.1e9,4517590.878,0,4487348.409,0,0,2\n")
    e = read_gnss({"file": str(tmp_path / "one.csv"), "format": "csv",
                   "columns": {"time": "t", "ecef": ["x", "y", "z"], "sd_ecef": ["sx", "sy", "sz"]}}, tmp_path)
    phi = np.radians(e.lat[0])
    np.testing.assert_allclose(e.sd_pos[0], [0.0, 2 * np.cos(phi), 2 * np.sin(phi)], atol=1e-12)


@pytest.mark.parametrize("columns, match", [
    ({**ECEF, "lat": "x"}, r"ecef \(x, y, z\) or lat, lon and height, not both \(also given: lat\)"),
    ({**ECEF, "ecef": ["x", "y"]}, r"columns.ecef: three column names \(x, y, z\)"),
    ({**ECEF, "vel": ["vx", "vy", "vz"]}, r"vel \(east, north, up\) or vel_ecef \(x, y, z\), not both"),
    ({"time": "t", "vel_ecef": ["vx", "vy", "vz"]}, r"columns.lat: the column name is required \(or ecef"),
])
def test_bad_ecef_mappings_are_named(tmp_path: Path, columns, match):
    with pytest.raises(ScenarioError, match=match):
        read_gnss({"file": str(write(tmp_path / "ecef.csv")), "format": "csv", "columns": columns}, tmp_path)


def test_the_drive_runs_on_ecef_fixes(tmp_path: Path):
    raw = dict(load_scenario("drive_lc").raw)
    src = PKG / "scenarios" / "drive_lc.toml"
    base = navfdi.run_scenario(from_dict(raw, source=str(src))).runs["fde"].errors()
    gnss = {"file": str(write(tmp_path / "ecef.csv")), "format": "csv", "columns": {**ECEF, "sd_ecef": ["sx", "sy", "sz"]}}
    raw["source"] = {**raw["source"], "gnss": gnss, "reference": str(POS),
                     "imu": {**raw["source"]["imu"], "file": str(PKG / "data" / "drive_0708" / "imu_1934_gpst.csv.gz")}}
    e = navfdi.run_scenario(from_dict(raw, source=str(src))).runs["fde"].errors()
    assert e["scored"] == base["scored"]
    # The .pos σ (1 cm) are floored at the scenario's 2 cm, as the CSV's are: the same run.
    assert e["hor_rms"] == pytest.approx(base["hor_rms"], rel=1e-3)
