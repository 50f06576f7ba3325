"""File formats (issue 23, item 4): Compact RINEX (Hatanaka) read directly — CRINEX 3 gives
exactly the observations of its plain RINEX 3 pair, CRINEX 1 expands to RINEX 2.11, which is
then refused with what to do, a damaged compressed file names its line; RINEX 4 navigation
files (their `> EPH` records, the GPS Klobuchar `> ION` record) and RINEX 4 observation files.
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


def test_crinex1_expands_and_rinex2_is_refused_with_what_to_do() -> None:
    with pytest.raises(navfdi.FileFormatError, match=r"delf0010\.21d\.gz, line 1: RINEX version '2\.11' is not supported.*convert"):
        _core.read_rinex_obs(str(D / "delf0010.21d.gz"))


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

