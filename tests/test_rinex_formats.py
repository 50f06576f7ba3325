"""File formats: Compact RINEX (Hatanaka) read directly — CRINEX 3 gives
exactly the observations of its plain RINEX 3 pair, CRINEX 1 expands to RINEX 2.11, which is
then refused with what to do, a damaged compressed file names its line; RINEX 4 navigation
files (their `> EPH` records, the GPS Klobuchar `> ION` record) and RINEX 4 observation files;
RINEX 2.11 observation and GPS navigation files.
The RINEX 4 navigation converter is also tested against a RINEX 3 file written as RINEX 4 in
the Rust tests (same ephemerides, errors on the original lines)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi import _core

D = Path(__file__).parent / "data" / "rinex_formats"
ACOR = "ACOR00ESP_R_20213550000_01D_30S_MO"


def test_crinex3_reads_as_its_plain_pair() -> None:
    a = _core.read_rinex_obs(str(D / f"{ACOR}.crx"))
    b = _core.read_rinex_obs(str(D / f"{ACOR}.rnx.gz"))
    assert len(a["epoch_times"]) == 25 and len(a["value"]) == 9036
    for k in ("epoch", "time", "sat", "code", "value"):
        assert np.array_equal(a[k], b[k], equal_nan=True), k
    assert a["satellites"] == b["satellites"] and a["observables"] == b["observables"]
    # The public reader and its table.
    df = navfdi.read_rinex(D / f"{ACOR}.crx")
    assert df.attrs["kind"] == "observation" and len(df) == 9036 and df["satellite"].nunique() == len(a["satellites"])


def test_rinex2_observations_and_their_crinex1_form_read() -> None:
    """RINEX 2.11 (converted to the RINEX 3 text the reader checks, RINEX 3 codes for the
    RINEX 2 types) and its Compact RINEX 1 form give the same observations; spot values of
    the file's first epoch."""
    a = _core.read_rinex_obs(str(D / "delf0010.21o.gz"))
    b = _core.read_rinex_obs(str(D / "delf0010.21d.gz"))
    for k in ("epoch", "time", "sat", "code", "value"):
        assert np.array_equal(a[k], b[k], equal_nan=True), k
    assert a["version"] == "2.11" and len(a["epoch_times"]) == 105
    df = navfdi.read_rinex(D / "delf0010.21o.gz")
    e0 = df[df["epoch"] == 0]
    g07 = e0[e0["satellite"] == "G07"].set_index("observable")["value"].to_dict()
    assert g07 == {"L1C": 126298057.858, "L2W": 98414080.647, "C1C": 24033720.416, "C2W": 24033721.351, "C1W": 24033719.353, "S1C": 40.0, "S2W": 22.0}
    r24 = e0[e0["satellite"] == "R24"].set_index("observable")["value"].to_dict()
    assert r24["C1P"] == 23125836.244 and r24["C2P"] == 23125839.071 and r24["C1C"] == 23125836.575
    assert e0["satellite"].nunique() == 20


def test_rinex2_gps_navigation_reads() -> None:
    df = navfdi.read_rinex(D / "cbw10010.21n.gz")
    assert df.attrs["version"] == "2.11" and len(df) == 187 and set(df["satellite"].str[0]) == {"G"}
    assert np.allclose(df.attrs["klobuchar"], [0.7451e-08, -0.1490e-07, -0.5960e-07, 0.1192e-06, 0.9011e05, -0.6554e05, -0.1311e06, 0.4588e06])
    g01 = df[df["satellite"] == "G01"].iloc[0]
    assert str(g01["toc"]) == "2021-01-01 02:00:00" and abs(g01["sqrt_a"] - 5153.69373131) < 1e-8
    assert abs(g01["af0"] - 7.874774746600e-04) < 1e-18


def test_a_malformed_rinex2_epoch_names_its_line(tmp_path) -> None:
    import gzip

    lines = gzip.open(D / "delf0010.21o.gz", "rt").read().splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith(" 21  1  1  0  0 30.0"))
    lines[k] = " 21  1  1  0  0 30.0000000  0 xxG07"
    p = tmp_path / "bad.21o"
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(navfdi.FileFormatError, match=rf"bad\.21o, line {k + 1}: the epoch line has no satellite count"):
        _core.read_rinex_obs(str(p))


def test_a_damaged_compact_file_names_its_line(tmp_path) -> None:
    raw = (D / f"{ACOR}.crx").read_text().splitlines()
    k = next(i for i, line in enumerate(raw) if line.startswith(">")) + 2
    raw[k] = "3&x&&y 3&not numbers"
    p = tmp_path / "bad.crx"
    p.write_text("\n".join(raw) + "\n")
    with pytest.raises(navfdi.FileFormatError, match=rf"bad\.crx, line {k + 1}: not Compact RINEX data.*damaged"):
        _core.read_rinex_obs(str(p))


def test_rinex4_navigation_file_reads() -> None:
    df = navfdi.read_rinex(D / "KMS300DNK_R_20221591000_01H_MN.rnx.gz")
    assert df.attrs["kind"] == "navigation" and df.attrs["version"] == "4.00"
    counts = df["satellite"].str[0].value_counts().to_dict()
    # 30 GPS and 1 QZSS LNAV, 108 Galileo INAV/FNAV, 36 BeiDou D1/D2 records in the file.
    assert counts == {"E": 108, "C": 36, "G": 30, "J": 1}
    assert np.allclose(df.attrs["klobuchar"], [1.024454832077e-08, 2.235174179077e-08, -5.960464477539e-08, -1.192092895508e-07, 9.6256e04, 1.31072e05, -6.5536e04, -5.89824e05])
    assert (df["sqrt_a"].between(5e3, 6.5e3)).all()


def test_rinex4_observation_file_reads_as_rinex3(tmp_path) -> None:
    import gzip

    lines = gzip.open(D / f"{ACOR}.rnx.gz", "rt").read().splitlines()
    lines[0] = "     4.00" + lines[0][9:]
    p = tmp_path / "acor4.rnx"
    p.write_text("\n".join(lines) + "\n")
    a = _core.read_rinex_obs(str(p))
    b = _core.read_rinex_obs(str(D / f"{ACOR}.rnx.gz"))
    assert a["version"] == "4.00"
    for k in ("epoch", "time", "sat", "code", "value"):
        assert np.array_equal(a[k], b[k], equal_nan=True), k

