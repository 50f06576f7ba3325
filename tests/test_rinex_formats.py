"""Compact RINEX (Hatanaka) files read directly (issue 23, item 4): CRINEX 3 gives exactly the
observations of its plain RINEX 3 pair; CRINEX 1 expands to RINEX 2.11, which is then refused
with what to do; a damaged compressed file names its line."""

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
