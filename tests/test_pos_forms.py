"""RTKLIB solution files in the forms ``rnx2rtkp`` writes besides latitude/longitude in GPST
(``tests/data/pos_forms``: the same 30 solutions as ECEF x/y/z, in degrees-minutes-seconds, in
UTC and JST, with and without velocities) read as the latitude/longitude file reads."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from navfdi import ScenarioError
from navfdi.logs import read_pos

DATA = Path(__file__).parent / "data" / "pos_forms"
REF = read_pos(DATA / "llh_v.pos")


def test_the_reference_has_what_is_compared():
    assert len(REF.t) == 30 and np.isfinite(REF.vel).all() and np.isfinite(REF.sd_vel).all()


@pytest.mark.parametrize("name, velocity", [("xyz_v", True), ("dms_vu", True), ("xyz_jst", False), ("dms_w", False)])
def test_every_form_reads_as_latitude_longitude_in_gpst(name, velocity):
    p = read_pos(DATA / f"{name}.pos")
    # Times: UTC and JST become GPST (18 leap seconds in 2024); a week and seconds form too.
    np.testing.assert_array_equal(p.t, REF.t)
    # Positions: the files' rounding (1e-9 deg, 1e-5 arcsec, 0.1 mm) — about 0.1 mm.
    m_per_deg = 111_000.0
    assert np.abs(p.lat - REF.lat).max() * m_per_deg < 3e-4
    assert np.abs(p.lon - REF.lon).max() * m_per_deg < 3e-4
    assert np.abs(p.height - REF.height).max() < 3e-4
    np.testing.assert_array_equal(p.q, REF.q)
    np.testing.assert_array_equal(p.ns, REF.ns)
    # σ east, north, up: ECEF covariances (signed square roots) rotated; 0.1 mm rounding.
    np.testing.assert_allclose(p.sd_pos, REF.sd_pos, atol=3e-4)
    if velocity:
        np.testing.assert_allclose(p.vel, REF.vel, atol=3e-5)
        np.testing.assert_allclose(p.sd_vel, REF.sd_vel, atol=3e-5)
    else:
        assert np.isnan(p.vel).all()


def _edit(tmp_path: Path, name: str, old: str, new: str, count: int = 1) -> Path:
    text = (DATA / f"{name}.pos").read_text()
    assert old in text
    out = tmp_path / f"{name}.pos"
    out.write_text(text.replace(old, new, count))
    return out


def test_a_southern_western_dms_angle_below_one_degree_keeps_its_sign(tmp_path):
    """RTKLIB puts the sign on the degrees, so -0.5° is written ``-0 30 00.00000``."""
    text = (DATA / "dms_w.pos").read_text().splitlines()
    rows = [i for i, ln in enumerate(text) if not ln.startswith("%")]
    tok = text[rows[0]].split()
    tok[2:5] = ["-0", "30", "00.00000"]
    tok[5:8] = ["-0", "15", "36.00000"]
    text[rows[0]] = " ".join(tok)
    (tmp_path / "s.pos").write_text("\n".join(text) + "\n")
    p = read_pos(tmp_path / "s.pos")
    assert p.lat[0] == -0.5 and p.lon[0] == pytest.approx(-0.26, abs=1e-12)


@pytest.mark.parametrize(
    "name, old, new, match",
    [
        ("dms_w", " 35 08 05.02276 ", " 35 61 05.02276 ", r"line \d+, column 'latitude': arcmin 61.0 is outside \[0, 60\)"),
        ("llh_v", "%  GPST  ", "%  TAI   ", r"time column 'TAI'; GPST, UTC or JST expected"),
        ("xyz_jst", "x-ecef(m)", "e-baseline(m)", r"baselines .* out-solformat = llh or xyz"),
        ("xyz_v", "-3817694.8070", "-3817694.8070e20", r"line \d+, column 'latitude\(deg\)': not a number|line \d+, column 'height\(m\)'"),
        ("dms_vu", "08 05.02276", "08 05.0x276", r"line \d+, column 'latitude\(arcsec\)': '05.0x276' is not a number"),
    ],
)
def test_bad_forms_and_values_are_named(tmp_path, name, old, new, match):
    with pytest.raises(ScenarioError, match=match):
        read_pos(_edit(tmp_path, name, old, new))
