"""A navigation file that does not cover the observations is named as such: an error when
not one satellite-epoch has an ephemeris (another day's file), a warning per system when
most of its satellite-epochs lack one."""

from __future__ import annotations

import warnings
from pathlib import Path

import pandas as pd
import pytest

import navfdi
from navfdi._gnss_coverage import check_ephemeris_coverage
from navfdi.cli import main

DATA = Path(__file__).parent / "data"
OBS = DATA / "rinex" / "rover.obs.gz"
NAV = DATA / "rinex" / "base.nav"
OTHER_DAY = DATA / "rinex_formats" / "KMS300DNK_R_20221591000_01H_MN.rnx.gz"  # 2022-06-08; the rover is 2024-06-24


def test_a_navigation_file_of_another_day_is_an_error_naming_both_spans():
    with pytest.raises(ValueError, match=r"no epoch solved: not one of the \d+ satellite-epochs has a broadcast ephemeris") as e:
        navfdi.gnss_solve(OBS, OTHER_DAY, systems="G,E")
    text = str(e.value)
    assert "GPS ephemerides (t_oe) span 2022-06-08" in text
    assert "Galileo ephemerides (t_oe) span 2022-06-08" in text
    assert "span 2024-06-24 08:20:00 to 2024-06-24 08:25:00 GPST" in text


def test_the_command_line_exits_2_on_it(capsys):
    assert main(["gnss", str(OBS), str(OTHER_DAY), "--systems", "G"]) == 2
    assert "navigation file of the observations' day" in capsys.readouterr().err


def test_a_covered_file_says_nothing():
    with warnings.catch_warnings():
        warnings.simplefilter("error", navfdi.PartialLogWarning)
        s = navfdi.gnss_solve(OBS, NAV, systems="G,E")
    assert s.summary()["solved"] == 301


def _sats(rows: dict[str, tuple[int, int]]) -> pd.DataFrame:
    """A satellite table: per satellite (covered, uncovered) satellite-epochs."""
    sat, status = [], []
    for name, (ok, missing) in rows.items():
        sat += [name] * (ok + missing)
        status += ["used"] * ok + ["no_ephemeris"] * missing
    return pd.DataFrame({"satellite": sat, "status": status})


SPAN = tuple(pd.to_datetime(["2024-06-24 08:20:00", "2024-06-24 08:25:00"]))


def test_a_system_mostly_without_ephemerides_is_warned_with_its_span():
    sats = _sats({"G05": (10, 0), "E07": (3, 7), "E08": (2, 8)})
    with pytest.warns(navfdi.PartialLogWarning, match=r"Galileo: 75% of its satellite-epochs have no broadcast ephemeris \(its Galileo ephemerides \(t_oe\) span 2024-06-24"):
        check_ephemeris_coverage(sats, 10, OBS, NAV, SPAN, navfdi.read_rinex)
    # Half or less is not reported, nor a system that has all of its ephemerides.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_ephemeris_coverage(_sats({"G05": (10, 0), "E07": (5, 5)}), 10, OBS, NAV, SPAN, navfdi.read_rinex)


def test_solved_epochs_turn_the_error_into_a_warning():
    # Every satellite-epoch of the table lacks an ephemeris but an epoch is solved (the
    # table given is only part of the run): a warning, not an error.
    with pytest.warns(navfdi.PartialLogWarning, match="GPS: 100%"):
        check_ephemeris_coverage(_sats({"G05": (0, 4)}), 1, OBS, NAV, SPAN, navfdi.read_rinex)
    with pytest.raises(ValueError, match="no epoch solved"):
        check_ephemeris_coverage(_sats({"G05": (0, 4)}), 0, OBS, NAV, SPAN, navfdi.read_rinex)


def test_a_file_with_no_epoch_solved_says_why():
    """The shared RINEX 2 pair: its navigation file covers two or three of the satellites in
    view in the observations' hour, so no epoch has four. The run says so — satellite-epochs
    per status, the most any epoch had against the five needed — instead of NaN rates; the
    σ model's estimate adds no warning of its own (nothing could be tested)."""
    obs, nav = DATA / "rinex_formats" / "delf0010.21o.gz", DATA / "rinex_formats" / "cbw10010.21n.gz"
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        with pytest.raises(ValueError, match=r"no epoch solved in .*delf0010\.21o\.gz \(105 epochs\): satellite-epochs no_ephemeris 1030, "
                                             r"unsolved 217; at most 3 satellite\(s\) with a usable ephemeris above the mask at any epoch, 5 needed \(position, "
                                             r"one clock per system and one more to test\)$"):
            navfdi.gnss_solve(obs, nav, systems="G")
    assert [type(w.message) for w in seen] == [navfdi.PartialLogWarning]
    assert main(["gnss", str(obs), str(nav), "--systems", "G", "--no-figures"]) == 2


def test_no_epoch_solved_names_the_systems_left_out():
    """The walk's u-blox file with GPS alone: four GPS satellites with ephemerides, one short
    of a solution and its test; the error says so and that the files also have Galileo (the
    systems option to use; BeiDou is observed only on B2/B3 codes, so it is not offered),
    where a new user's first run would otherwise end at the count."""
    d = Path(navfdi.__file__).parent / "data" / "walk_0827"
    obs, nav = d / "gnss_1730.obs.gz", d / "gnss_1730.nav"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ValueError, match=r"at most 4 satellite\(s\) .* 5 needed .*; the files also have Galileo: ask for G,E "
                                             r"\(--systems, systems=, or source\.gnss\.systems in a scenario\)$"):
            navfdi.gnss_solve(obs, nav, systems="G")
        assert len(navfdi.gnss_solve(obs, nav, systems="G,E").solution)


def test_console_names_systems_left_out(capsys):
    """The static rover file solved on GPS alone: the console and the summary say which
    systems the files also have (G + E + C + J there), and the option that adds them."""
    assert main(["gnss", str(OBS), str(NAV), "--systems", "G", "--no-figures"]) == 0
    out = capsys.readouterr().out
    assert "the files also have Galileo, BeiDou, QZSS, not used: --systems G,E,C,J uses them" in out
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = navfdi.gnss_solve(OBS, NAV, systems="G,E,C,J")
    assert s.config["systems_in_files"] == ["G", "E", "C", "J"]
    assert "the files also have" not in s.format_summary()
