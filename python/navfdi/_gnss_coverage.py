"""Does the navigation file cover the observations? Checked after a single-point run from
the satellite table's statuses, so that a navigation file of another day, or one without a
selected system's records, is named as such instead of giving an empty solution."""

from __future__ import annotations

import os
import warnings
from typing import TYPE_CHECKING, Any, Callable, Sequence

import numpy as np

from navfdi._errors import PartialLogWarning

if TYPE_CHECKING:
    import pandas as pd

# A system whose satellite-epochs lack an ephemeris more often than this is reported.
UNCOVERED_SHARE = 0.5

_NAMES = {"G": "GPS", "E": "Galileo", "C": "BeiDou", "J": "QZSS"}


def check_ephemeris_coverage(sats: pd.DataFrame, solved: int, obs: str | os.PathLike[str], nav: str | os.PathLike[str], obs_span: tuple[Any, Any],
                             read_nav: Callable[[str | os.PathLike[str]], pd.DataFrame]) -> None:
    """Raise or warn when the navigation file ``nav`` does not cover the observations.

    ``sats``: the run's satellite table (one row per satellite-epoch of the selected
    systems, columns ``satellite`` and ``status``); ``solved``: epochs with a solution;
    ``obs_span``: the first and last observation epochs (GPST timestamps); ``read_nav``:
    :func:`navfdi.gnss.read_rinex` (its ``satellite`` and ``toe`` columns give the spans; read
    only when something is reported).

    * No epoch solved and not one satellite-epoch with an ephemeris: ``ValueError`` naming
      both files' time spans (a navigation file of another day).
    * Otherwise a :class:`navfdi.PartialLogWarning` for each system whose satellite-epochs
      lack an ephemeris more than half the time (``UNCOVERED_SHARE``), with the spans.
    """
    if len(sats) == 0:
        return
    sat = sats["satellite"].astype("category")  # per category, not per row: day files have ~10^5 rows
    system = np.array([str(c)[:1] for c in sat.cat.categories] + [""])[sat.cat.codes.to_numpy()]
    missing = (sats["status"] == "no_ephemeris").to_numpy()
    share = {s: float(missing[system == s].mean()) for s in np.unique(system)}
    short = {s: v for s, v in share.items() if v > UNCOVERED_SHARE}
    if not short:
        return
    spans = _nav_spans(read_nav(nav))
    first, last = (t.strftime("%Y-%m-%d %H:%M:%S") for t in obs_span)
    obs_text = f"the observations of {os.fspath(obs)} span {first} to {last} GPST"

    def covered(s: str) -> str:
        if s not in spans:
            return f"{os.fspath(nav)} has no {_NAMES.get(s, s)} records"
        a, b = spans[s]
        return f"its {_NAMES.get(s, s)} ephemerides (t_oe) span {a} to {b} GPST"

    if solved == 0 and bool(missing.all()):
        raise ValueError(f"no epoch solved: not one of the {len(sats)} satellite-epochs has a broadcast ephemeris in {os.fspath(nav)}: " + "; ".join(covered(s) for s in sorted(share)) + f"; {obs_text}. Give the navigation file of the observations' day(s)")
    for s in sorted(short):
        warnings.warn(f"{_NAMES.get(s, s)}: {short[s]:.0%} of its satellite-epochs have no broadcast ephemeris ({covered(s)}; {obs_text}); they are left out of the solution", PartialLogWarning, stacklevel=3)


def _nav_spans(records: pd.DataFrame) -> dict[str, tuple[str, str]]:
    """First and last t_oe per system of a navigation file's records, as text (GPST)."""
    toe = records.groupby(records["satellite"].astype(str).str[0])["toe"]
    lo, hi = toe.min(), toe.max()
    return {str(s): (lo[s].strftime("%Y-%m-%d %H:%M:%S"), hi[s].strftime("%Y-%m-%d %H:%M:%S")) for s in lo.index}


def left_out_systems(systems: Sequence[str], in_files: Sequence[str]) -> tuple[list[str], str]:
    """The systems of ``in_files`` (those both files let a solution use) not in ``systems``,
    as letters and as names for messages (``"Galileo, BeiDou"``; empty when none)."""
    others = [s for s in in_files if s not in systems]
    return others, ", ".join(_NAMES.get(s, s) for s in others)


def raise_if_nothing_solved(sats: pd.DataFrame, n_epochs: int, solved: int, obs: str | os.PathLike[str], systems: Sequence[str], in_files: Sequence[str] = ()) -> None:
    """``ValueError`` when not one of the ``n_epochs`` epochs of ``obs`` has a solution: the
    satellite-epochs per status (``sats``: the run's satellite table) and the most satellites
    any epoch had that could enter a solution, against the ``4 + len(systems)`` a solution
    and its test need (position, one clock per system and one more), and the systems of
    ``in_files`` (those both files let a solution use) that were not asked for — rather than
    a run of NaN rates."""
    if solved or not n_epochs:
        return
    counts = list(sats["status"].value_counts().items()) if len(sats) else []
    usable = sats[sats["status"].isin(["used", "excluded", "unsolved"])] if len(sats) else sats
    most = int(usable.groupby("epoch").size().max()) if len(usable) else 0
    need = 4 + len(systems)
    text = ", ".join(f"{k} {int(v)}" for k, v in counts) or "none observed on the systems and codes asked for"
    others, names = left_out_systems(systems, in_files)
    hint = (f"; the files also have {names}: ask for {','.join([*systems, *others])} "
            "(--systems, systems=, or source.gnss.systems in a scenario)") if others else ""
    raise ValueError(f"no epoch solved in {os.fspath(obs)} ({n_epochs} epochs): satellite-epochs {text}; at most {most} satellite(s) with a "
                     f"usable ephemeris above the mask at any epoch, {need} needed (position, one clock per system and one more to test){hint}")
