"""u-blox binary logs (``.ubx``): the receiver's NAV-PVT solutions read as a GNSS log. The
walk's NAV-PVT messages (``tests/data/ubx``: the 536 NAV-PVT packets of the walk's raw u-blox
log and its first 30 other packets) against the bundled ``.pos`` that the data's author made
from the same messages with their own converter."""

from __future__ import annotations

import gzip
import warnings
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi import LeftOutFixesWarning, ScenarioError
from navfdi.gnss_logs import read_gnss, read_ubx
from navfdi.logs import read_pos

UBX = Path(__file__).parent / "data" / "ubx" / "walk_1730_pvt.ubx.gz"
WALK = Path(str(resources.files("navfdi") / "data" / "walk_0827"))


def test_nav_pvt_reads_as_the_authors_conversion():
    u = read_ubx(UBX)
    p = read_pos(WALK / "gnss_1730_sf_ellh.pos.gz")
    assert len(u.t) == len(p.t) == 536
    # The author's times are the UTC time truncated to the millisecond; ours keep the
    # receiver's nanoseconds.
    assert np.all((u.t - p.t >= 0) & (u.t - p.t < 1e-3))
    np.testing.assert_allclose(u.lat, p.lat, rtol=0, atol=1e-12)
    np.testing.assert_allclose(u.lon, p.lon, rtol=0, atol=1e-12)
    # The bundled file's height is hMSL minus a fixed geoid separation (21.387 m); NAV-PVT's own
    # height above the ellipsoid agrees to the millimetre.
    assert np.abs(u.height - p.height).max() <= 1e-3 + 1e-9
    np.testing.assert_array_equal(u.q, p.q)
    np.testing.assert_array_equal(u.ns, p.ns)
    np.testing.assert_allclose(u.vel, p.vel, rtol=0, atol=1e-9)
    np.testing.assert_allclose(u.sd_pos, p.sd_pos, rtol=0, atol=1e-6)


def test_the_format_is_told_from_the_name_and_the_bytes(tmp_path: Path):
    a = read_gnss(str(UBX), Path("."))
    plain = tmp_path / "receiver_log"
    plain.write_bytes(gzip.open(UBX).read())
    b = read_gnss(str(plain), Path("."))
    np.testing.assert_array_equal(a.t, b.t)
    c = read_gnss({"file": str(plain), "format": "ubx"}, Path("."))
    np.testing.assert_array_equal(a.lat, c.lat)


def test_invalid_fixes_and_corrupt_packets_are_left_out_and_said(tmp_path: Path):
    raw = bytearray(gzip.open(UBX).read())
    # The first NAV-PVT: its fix flags cleared (gnssFixOK off), checksum recomputed; the second:
    # one payload byte changed without its checksum (corrupt).
    starts = [i for i in range(len(raw) - 3) if raw[i:i + 4] == b"\xb5\x62\x01\x07"]
    first, second = starts[0], starts[1]
    raw[first + 6 + 21] = 0  # flags
    a = b = 0
    for x in raw[first + 2:first + 6 + 92]:
        a = (a + x) & 255
        b = (b + a) & 255
    raw[first + 6 + 92], raw[first + 6 + 93] = a, b
    raw[second + 6 + 30] ^= 0xFF
    f = tmp_path / "edited.ubx"
    f.write_bytes(bytes(raw))
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        u = read_ubx(f)
    said = [str(x.message) for x in w if issubclass(x.category, LeftOutFixesWarning)]
    assert any("1 UBX packet(s) with a bad checksum" in m for m in said), said
    assert any("1 fix(es) not marked valid by the receiver" in m for m in said), said
    assert len(u.t) == 534


@pytest.mark.parametrize(
    "content, match",
    [
        (b"$GPGGA,hello\n", r"no UBX packet .* not a u-blox binary log"),
        (b"\xb5\x62\x05\x01\x02\x00\x06\x01\x0f\x38", r"1 UBX packets but no NAV-PVT"),
    ],
)
def test_files_that_are_not_usable_are_named(tmp_path: Path, content: bytes, match: str):
    f = tmp_path / "x.ubx"
    f.write_bytes(content)
    with pytest.raises(ScenarioError, match=match):
        read_ubx(f)


def test_the_walk_runs_loosely_coupled_from_the_ubx(tmp_path: Path):
    """The walk's filter fed the NAV-PVT log gives what it gives on the author's .pos of the
    same messages."""
    from test_lc_rinex import _scenario

    runs = {}
    for name, gnss in (("pos", f'"{WALK / "gnss_1730_sf_ellh.pos.gz"}"'), ("ubx", f'"{UBX}"')):
        (tmp_path / name).mkdir()
        runs[name] = navfdi.run_scenario(_scenario(tmp_path / name, gnss)).runs["fde"].errors()
    assert runs["ubx"]["scored"] == runs["pos"]["scored"] > 300
    assert abs(runs["ubx"]["hor_rms"] - runs["pos"]["hor_rms"]) < 0.01


def test_a_log_that_cannot_be_read_says_why_when_the_duration_is_taken_from_it(tmp_path: Path):
    """``duration`` and ``dt`` left to the log: the reader's own reason, not only that the
    epochs could not be read."""
    from test_lc_rinex import _scenario

    (tmp_path / "bad.ubx").write_text("hello\n")
    sc = _scenario(tmp_path, '"bad.ubx"')
    with pytest.raises(ScenarioError, match=r"could not be read to take them from .*: source.gnss: .*bad.ubx: no UBX packet"):
        navfdi.run_scenario(sc)


@pytest.mark.parametrize("key, value", [("header", False), ("columns", {"time": 1}), ("date", "2025-08-28")])
def test_a_key_another_format_reads_is_refused_not_ignored(key, value):
    with pytest.raises(ScenarioError, match=rf"source.gnss.{key}: read for format = .* only; this log is read as ubx"):
        read_gnss({"file": str(UBX), key: value}, Path("."))
