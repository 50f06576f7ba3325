"""GNSS log epochs that are not GNSS measurements are left out as the log is read, and said:
NMEA ``GGA`` fixes of quality 6–8 (dead reckoning, manual, simulator) and fixes from fewer
than four satellites (``.pos`` ``ns``, ``GGA``, a CSV's ``satellites`` column). ``GGA``
qualities are read on RTKLIB's scale (1 fixed, 2 float, 4 DGPS, 5 single)."""

from __future__ import annotations

import dataclasses
import datetime as dt
import warnings
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi._logtime import GPS_EPOCH
from navfdi.gnss_logs import read_gnss, read_nmea
from navfdi.logs import PosLog, read_pos
from navfdi.scenario import ScenarioError, from_dict, load_scenario
from navfdi.simlog import simulate_log

from loglib import horizontal_error, nmea, nmea_lines

GGA = "GPGGA,120000.00,4000.0000000,N,10500.0000000,W,{q},{ns},0.8,1600.0,M,-20.0,M,,"
RMC = "GPRMC,120000.00,A,4000.0000000,N,10500.0000000,W,0.0,0.0,080725,,,A"


def _gga(hms: str, q: int, ns: int | str = 12) -> str:
    return nmea(GGA.format(q=q, ns=ns).replace("120000.00", hms))


def test_gga_qualities_are_read_on_rtklib_scale_and_non_measurements_left_out(tmp_path: Path) -> None:
    """Qualities 1, 2, 4, 5, 9 → 5, 4, 1, 2, 3; 6, 7 and 8 left out with one warning each
    naming the count; the satellite count is read."""
    qs = [1, 2, 4, 5, 9, 6, 6, 7, 8, 1]
    lines = [nmea(RMC.replace("120000.00", "120000.00"))]
    lines += [_gga(f"1200{k:02d}.00", q, 5 + k) for k, q in enumerate(qs)]
    f = tmp_path / "q.nmea"
    f.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.warns(navfdi.LeftOutFixesWarning) as rec:
        p = read_nmea(f)
    msgs = [str(w.message) for w in rec]
    assert any("2 fix(es) of GGA quality 6 or GNS mode E (estimated, dead reckoning" in m for m in msgs), msgs
    assert any("1 fix(es) of GGA quality 7 or GNS mode M (manual input" in m for m in msgs)
    assert any("1 fix(es) of GGA quality 8 or GNS mode S (simulator" in m for m in msgs)
    assert p.q.tolist() == [5, 4, 1, 2, 3, 5]
    assert p.ns is not None and p.ns.tolist() == [5, 6, 7, 8, 9, 14]


def test_an_unknown_gga_quality_is_refused_with_its_line(tmp_path: Path) -> None:
    f = tmp_path / "bad.nmea"
    f.write_text("\n".join([nmea(RMC), _gga("120000.00", 1), _gga("120001.00", 12)]) + "\n", encoding="utf-8")
    with pytest.raises(ScenarioError, match=r"bad.nmea, line 3: GGA fix quality 12 is none of NMEA 0183's"):
        read_nmea(f)


def test_a_log_of_dead_reckoning_only_is_refused(tmp_path: Path) -> None:
    f = tmp_path / "dr.nmea"
    f.write_text("\n".join([nmea(RMC), _gga("120000.00", 6, 0), _gga("120001.00", 6, 0)]) + "\n", encoding="utf-8")
    with pytest.raises(ScenarioError, match=r"no GGA fix of a GNSS quality \(every one is estimated, dead reckoning\)"), \
            pytest.warns(navfdi.LeftOutFixesWarning):
        read_nmea(f)


def _pos_with_ns(tmp_path: Path, ns: list[int]) -> Path:
    path = simulate_log(tmp_path / "sim", duration=60, seed=2).scenario
    lines = (path.parent / "gnss.pos").read_text(encoding="utf-8").splitlines()
    head = [ln for ln in lines if ln.startswith("%")]
    body = [ln for ln in lines if not ln.startswith("%")][: len(ns)]
    out = []
    for ln, n in zip(body, ns):
        tok = ln.split()
        tok[6] = str(n)  # week, seconds, lat, lon, height, Q, ns
        out.append(" ".join(tok))
    f = tmp_path / "ns.pos"
    f.write_text("\n".join(head + out) + "\n", encoding="utf-8")
    return f


def test_pos_fixes_from_fewer_than_four_satellites_are_left_out(tmp_path: Path) -> None:
    """``.pos`` ``ns`` of 1–3 left out (warned, with the count), 0 read as no count (converters
    write it), 4 and more kept; ``read_pos`` itself (references) keeps every epoch."""
    ns = [9, 9, 3, 2, 9, 0, 4, 1, 9, 9]
    f = _pos_with_ns(tmp_path, ns)
    assert len(read_pos(f).t) == 10
    with pytest.warns(navfdi.LeftOutFixesWarning, match=r"ns.pos: 3 fix\(es\) from fewer than 4 satellites"):
        p = read_gnss(str(f), tmp_path)
    assert p.ns is not None and p.ns.tolist() == [9, 9, 9, 0, 4, 9, 9]
    assert len(p.t) == len(p.lat) == len(p.vel) == 7


def test_pos_fixes_all_below_four_satellites_are_refused(tmp_path: Path) -> None:
    f = _pos_with_ns(tmp_path, [3, 3, 2])
    with pytest.raises(ScenarioError, match=r"every fix is from fewer than 4 satellites"):
        read_gnss(str(f), tmp_path)


def test_csv_satellites_column(tmp_path: Path) -> None:
    f = tmp_path / "fix.csv"
    rows = ["t,la,lo,h,n"] + [f"{1.4e9 + k},40.0,-105.0,1600.0,{n}" for k, n in enumerate([8, 3, 8])]
    f.write_text("\n".join(rows) + "\n", encoding="utf-8")
    cols = {"time": "t", "lat": "la", "lon": "lo", "height": "h", "satellites": "n"}
    with pytest.warns(navfdi.LeftOutFixesWarning, match=r"1 fix\(es\) from fewer than 4"):
        p = read_gnss({"file": "fix.csv", "format": "csv", "columns": cols}, tmp_path)
    assert p.ns is not None and p.ns.tolist() == [8, 8]
    with pytest.raises(ScenarioError, match=r"columns.satellites = 'm': no such column"):
        read_gnss({"file": "fix.csv", "format": "csv", "columns": {**cols, "satellites": "m"}}, tmp_path)


def test_dead_reckoned_fixes_do_not_pull_the_filter(tmp_path: Path) -> None:
    """A receiver that dead-reckons for a minute (GGA quality 6, drifting north at 0.5 m/s):
    its fixes are left out (60 fewer tested epochs, a warning) and the filter coasts on the INS
    (error within the fault-free run's largest); the same fixes written as quality 1 are used
    and pull it further."""
    path = simulate_log(tmp_path / "sim", duration=600, seed=1, gnss_sigma=2.0, gnss_tau=30.0, gnss_white=0.3,
                        gnss_velocity_sigma=0.1).scenario
    p = read_pos(path.parent / "gnss.pos")
    t = p.t - p.t[0]
    dr = (t >= 200) & (t < 260)
    lat = p.lat.copy()
    lat[dr] += np.degrees((t[dr] - 200) * 0.5 / 6.371e6)
    moved = dataclasses.replace(p, lat=lat)
    date = (GPS_EPOCH + dt.timedelta(seconds=float(p.t[0]) - 18.0)).date().isoformat()

    def run(code: str | None) -> navfdi.RunRecordView:
        lines, k = [], -1
        for ln in nmea_lines(moved if code else p, 12.5):
            if "GGA" in ln:
                k += 1
                if code and dr[k]:
                    f = ln[1:].split("*")[0].split(",")
                    f[6] = code
                    ln = nmea(",".join(f))
            lines.append(ln)
        nm = path.parent / f"receiver{code}.nmea"
        nm.write_text("\n".join(lines) + "\n", encoding="utf-8")
        raw = dict(load_scenario(str(path)).raw)
        raw["source"] = {**raw["source"], "gnss": {"file": nm.name, "date": date}}
        del raw["duration"], raw["dt"]
        return navfdi.run_scenario(from_dict(raw, source=str(path))).runs["fde"]

    clean = run(None)
    with pytest.warns(navfdi.LeftOutFixesWarning, match=r"fix\(es\) of GGA quality 6 or GNS mode E \(estimated, dead reckoning"):
        held = run("6")
    with warnings.catch_warnings():
        warnings.simplefilter("error", navfdi.LeftOutFixesWarning)
        used = run("1")
    # The run's epochs are the log's: none in the minute left out, the coasting shows after it.
    def worst(x: navfdi.RunRecordView) -> float:
        return float(np.nanmax(horizontal_error(x)[(x.t >= 200) & (x.t < 280)]))

    tested = lambda x: x.exclusion_counts()["gnss_pos"]["tested"]  # noqa: E731
    assert tested(held) == tested(clean) - 60
    assert worst(held) <= float(np.nanmax(horizontal_error(clean)))
    assert worst(used) > 1.5 * worst(held), (worst(used), worst(held))


GNS = "GNGNS,{hms},4000.0000000,N,10500.0000000,W,{mode},{ns},0.8,1600.0,-20.0,,,V"


def test_gns_sentences_are_read_where_an_epoch_has_no_gga(tmp_path: Path) -> None:
    """``GNS`` (the multi-constellation fix, which some receivers write instead of ``GGA``):
    the best system's mode is the fix's (``RA`` → RTK fixed), ``N`` systems are skipped, ``E``
    alone is dead reckoning (left out, warned), a ``GGA`` of the same epoch is read instead,
    the position and height are those of the ``GGA`` it stands for, an unknown letter is
    refused with its line."""
    lines = [nmea(RMC), _gga("120000.00", 1, 9)]
    lines += [nmea(GNS.format(hms=h, mode=m, ns=n)) for h, m, n in
              (("120000.00", "RR", 14), ("120001.00", "AN", 9), ("120002.00", "RA", 15), ("120003.00", "NE", 6), ("120004.00", "DAN", 11))]
    f = tmp_path / "gns.nmea"
    f.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.warns(navfdi.LeftOutFixesWarning, match=r"1 fix\(es\) of GGA quality 6 or GNS mode E"):
        p = read_nmea(f)
    assert p.q.tolist() == [5, 5, 1, 4]  # GGA (not the GNS "RR"), A, R, D
    assert p.ns is not None and p.ns.tolist() == [9, 9, 15, 11]
    gga = read_nmea_text(tmp_path, [nmea(RMC), _gga("120000.00", 1, 9)])
    assert np.allclose([p.lat[1], p.lon[1], p.height[1]], [gga.lat[0], gga.lon[0], gga.height[0]])
    bad = tmp_path / "bad_gns.nmea"
    bad.write_text("\n".join([nmea(RMC), nmea(GNS.format(hms="120000.00", mode="AX", ns=9))]) + "\n", encoding="utf-8")
    with pytest.raises(ScenarioError, match=r"bad_gns.nmea, line 2: GNS mode indicator 'AX'"):
        read_nmea(bad)


def read_nmea_text(folder: Path, lines: list[str]) -> PosLog:
    """``lines`` written to a file in ``folder`` and read."""
    f = folder / "one.nmea"
    f.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return read_nmea(f)
