"""The `.pos` reader's one-pass Rust path (`_core.pos_rows`) against its line-by-line Python
reader: the same numbers to the bit on every bundled solution file and on both time forms,
and the Python reader (with its worded errors) wherever the text is irregular."""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np
import pytest

from navfdi import ScenarioError, _core
from navfdi.logs import _pos_rows, _read_text, read_pos

DATA = Path(__file__).resolve().parents[1] / "python" / "navfdi" / "data"
HEADER = "%  GPST                  latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)\n"


def _fields(text: str) -> list[str]:
    return next(ln[1:].split() for ln in text.splitlines() if ln.startswith("%") and "latitude" in ln)[1:]


@pytest.mark.parametrize("path", sorted(DATA.glob("*/*.pos*")), ids=lambda p: p.name)
def test_bundled_files_read_the_same_both_ways(path: Path) -> None:
    text = _read_text(path)
    fields = _fields(text)
    fast = _core.pos_rows(text, len(fields))
    assert fast is not None
    slow = _pos_rows(path, text.splitlines(), fields)
    assert fast[0].tobytes() == slow[0].tobytes()
    assert fast[1].tolist() == slow[1]


def test_week_seconds_and_dates_agree(tmp_path: Path) -> None:
    """The same epochs written as dates and as GPS week / seconds (CRLF line ends, a blank
    line): the same times to the bit, and the line numbers count the blank line."""
    rows = [("2025/07/08 19:34:18.499", "2374 243258.499"), ("2025/07/08 23:59:59.9", "2374 259199.9"), ("2025/07/09 00:00:00.1", "2374 259200.1")]
    for k, form in enumerate(("date", "week")):
        body = "".join(f"{r[k]} 40.1 -105.1 1601.5 1 12 0.5 0.5 1.2\r\n" + ("\r\n" if i == 0 else "") for i, r in enumerate(rows))
        (tmp_path / f"{form}.pos").write_text(HEADER.replace("\n", "\r\n") + body, newline="")
    a, b = read_pos(tmp_path / "date.pos"), read_pos(tmp_path / "week.pos")
    assert a.t.tobytes() == b.t.tobytes()
    text = _read_text(tmp_path / "date.pos")
    assert _core.pos_rows(text, len(_fields(text)))[1].tolist() == [2, 4, 5]


def test_irregular_text_takes_the_worded_reader(tmp_path: Path) -> None:
    good = "2025/07/08 19:34:18.499 40.1 -105.1 1601.5 1 12 0.5 0.5 1.2\n"
    # A number Python reads and Rust's parser does not: read, by the line-by-line reader.
    p = tmp_path / "underscore.pos"
    p.write_text(HEADER + good + good.replace("18.499", "19.499").replace("1601.5", "1_601.5"))
    text = _read_text(p)
    assert _core.pos_rows(text, len(_fields(text))) is None
    assert read_pos(p).height[1] == 1601.5
    # Errors keep their words: the line and column named.
    with gzip.open(tmp_path / "bad.pos.gz", "wt") as f:
        f.write(HEADER + good + good.replace("18.499", "19.499").replace("40.1", "forty"))
    bad = tmp_path / "bad.pos.gz"
    with pytest.raises(ScenarioError, match=r"line 3, column 'latitude\(deg\)': 'forty' is not a number"):
        read_pos(bad)
    short = tmp_path / "short.pos"
    short.write_text(HEADER + good + "2025/07/08 19:34:19.499 40.1\n")
    with pytest.raises(ScenarioError, match=r"line 3: 3 fields, the header names 10"):
        read_pos(short)
    late = tmp_path / "late.pos"
    late.write_text(HEADER + good + good.replace("19:34:18", "25:34:18"))
    with pytest.raises(ScenarioError, match=r"line 3, column 'GPST'"):
        read_pos(late)
    assert np.isfinite(read_pos(tmp_path / "underscore.pos").t).all()
