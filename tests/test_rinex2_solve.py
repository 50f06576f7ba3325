"""A RINEX 2.11 observation file solved with its RINEX 2 navigation file.

The shared RINEX 2 pair (delf0010.21o with cbw10010.21n) cannot be solved: the navigation file
holds ephemerides for only two of the satellites in view in the observations' hour (its other
records begin at 02:00 or later; RTKLIB solves none of its epochs either). So the bundled
RINEX 3 pair is written out as RINEX 2.11 (GPS: C1, L1, D1, S1; GPS navigation records with
``ION ALPHA``/``ION BETA``), the values copied digit for digit, and both pairs are solved:
the positions, velocities and satellite sets must be the same.
"""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np

import navfdi

DATA = Path(__file__).parent / "data" / "rinex"
TYPES = (("C1", "C1C"), ("L1", "L1C"), ("D1", "D1C"), ("S1", "S1C"))


def _hdr(text: str, label: str) -> str:
    return f"{text:<60}{label:<20}\n"


def write_obs_v2(path: Path) -> int:
    """RINEX 2.11 GPS observations of the bundled rover file; returns the epochs written."""
    obs = navfdi.read_rinex(DATA / "rover.obs.gz")
    gps = obs[obs["satellite"].astype(str).str.startswith("G") & obs["observable"].astype(str).isin([t for _, t in TYPES])]
    table = gps.pivot_table(index=["epoch", "time", "satellite"], columns="observable", values="value", observed=True, aggfunc="first")
    t0 = table.index.get_level_values("time")[0]
    out = [
        _hdr("     2.11           OBSERVATION DATA    G (GPS)", "RINEX VERSION / TYPE"),
        _hdr("navfdi test           navfdi", "PGM / RUN BY / DATE"),
        _hdr("SEPT", "MARKER NAME"),
        _hdr(" -3817680.9841  3562840.0688  3650158.4543", "APPROX POSITION XYZ"),
        _hdr("        0.0000        0.0000        0.0000", "ANTENNA: DELTA H/E/N"),
        _hdr("     1     1", "WAVELENGTH FACT L1/2"),
        _hdr(f"{len(TYPES):6d}" + "".join(f"{t2:>6}" for t2, _ in TYPES), "# / TYPES OF OBSERV"),
        _hdr("     1.000", "INTERVAL"),
        _hdr(f"{t0.year:6d}{t0.month:6d}{t0.day:6d}{t0.hour:6d}{t0.minute:6d}{t0.second:13.7f}     GPS", "TIME OF FIRST OBS"),
        _hdr("", "END OF HEADER"),
    ]
    epochs = 0
    for (_, t), rows in table.groupby(level=["epoch", "time"], sort=True):
        sats = [str(s) for s in rows.index.get_level_values("satellite")]
        head = f" {t.year % 100:02d} {t.month:2d} {t.day:2d} {t.hour:2d} {t.minute:2d}{t.second + t.microsecond / 1e6:11.7f}  0{len(sats):3d}"
        for i in range(0, len(sats), 12):
            chunk = "".join(sats[i : i + 12])
            out.append((head if i == 0 else " " * 32) + chunk + "\n")
        for _, row in rows.iterrows():
            fields = ["" if not np.isfinite(row.get(t3, np.nan)) else f"{row[t3]:14.3f}  " for _, t3 in TYPES]
            out.append("".join(f"{f:16}" for f in fields).rstrip() + "\n")
        epochs += 1
    path.write_text("".join(out))
    return epochs


def write_nav_v2(path: Path) -> None:
    """RINEX 2 GPS navigation of the bundled base.nav's GPS records, values copied."""
    lines = (DATA / "base.nav").read_text().splitlines()
    end = next(i for i, line in enumerate(lines) if "END OF HEADER" in line)
    ion = {line[:4]: line[5:53] for line in lines[:end] if "IONOSPHERIC CORR" in line}
    out = [
        _hdr("     2.11           N: GPS NAV DATA", "RINEX VERSION / TYPE"),
        _hdr("navfdi test           navfdi", "PGM / RUN BY / DATE"),
        _hdr("  " + "".join(f"{float(v):12.4E}".replace("E", "D") for v in ion["GPSA"].split()), "ION ALPHA"),
        _hdr("  " + "".join(f"{float(v):12.4E}".replace("E", "D") for v in ion["GPSB"].split()), "ION BETA"),
        _hdr("    18", "LEAP SECONDS"),
        _hdr("", "END OF HEADER"),
    ]
    body = lines[end + 1 :]
    i = 0
    while i < len(body):
        line = body[i]
        if line.startswith("G"):
            prn, y, mo, d, h, mi, s = int(line[1:3]), int(line[4:8]), int(line[9:11]), int(line[12:14]), int(line[15:17]), int(line[18:20]), int(line[21:23])
            out.append(f"{prn:2d} {y % 100:02d} {mo:2d} {d:2d} {h:2d} {mi:2d}{float(s):5.1f}" + line[23:].replace("E", "D") + "\n")
            for cont in body[i + 1 : i + 8]:
                out.append("   " + cont[4:].replace("E", "D") + "\n")
            i += 8
        else:
            i += 1
    path.write_text("".join(out))


def test_a_rinex2_pair_solves_as_its_rinex3_original(tmp_path: Path) -> None:
    obs2, nav2 = tmp_path / "sept1760.24o", tmp_path / "sept1760.24n"
    n = write_obs_v2(obs2)
    write_nav_v2(nav2)
    assert n == 301
    v2 = navfdi.gnss_solve(obs2, nav2, systems="G")
    v3 = navfdi.gnss_solve(DATA / "rover.obs.gz", DATA / "base.nav", systems="G")
    a, b = v2.solution, v3.solution
    assert len(a) == len(b) == 301
    assert (a["status"] == b["status"]).all()
    assert int((a["status"] == "passed").sum()) >= 290
    for c in ("x", "y", "z"):
        assert np.nanmax(np.abs(a[c].to_numpy() - b[c].to_numpy())) < 1e-6, c
    for c in ("vx", "vy", "vz"):
        assert np.nanmax(np.abs(a[c].to_numpy() - b[c].to_numpy())) < 1e-9, c
    assert (a["used"] == b["used"]).all()
    assert v2.config["codes"]["G"] == "C1C"
