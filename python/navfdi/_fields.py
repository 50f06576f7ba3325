"""Scenario field readers shared by the schema modules: each checks one field's type or unit
and raises :class:`~navfdi.ScenarioError` naming its path."""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from typing import Any

from navfdi._errors import ScenarioError
from navfdi._schema import keys
from navfdi.units import UnitError, parse


def _need(d: Mapping[str, Any], key: str, path: str) -> Any:
    if not isinstance(d, Mapping):
        raise ScenarioError(f"{path}: expected a table, got {type(d).__name__}")
    if key not in d:
        raise ScenarioError(f"{path + '.' if path else ''}{key}: missing")
    return d[key]


def _check_keys(d: Mapping[str, Any], section: str, path: str) -> None:
    """Refuse keys of table ``d`` (at field ``path``) that the schema's ``section``
    (:data:`navfdi._schema.SECTIONS`) does not list."""
    allowed = keys(section)
    if not isinstance(d, Mapping):
        raise ScenarioError(f"{path or 'scenario'} = {d!r}: expected a table")
    extra = sorted(str(k) for k in set(d) - allowed)
    if extra:
        where = path or "scenario"
        raise ScenarioError(f"{where}: unknown field(s) {', '.join(extra)} (allowed: {', '.join(sorted(allowed))})")


def _list(v: Any, path: str) -> list[Any]:
    if not isinstance(v, list):
        raise ScenarioError(f"{path}: expected a list, got {type(v).__name__}")
    return v


def _str(v: Any, path: str) -> str:
    if not isinstance(v, str):
        raise ScenarioError(f"{path} = {v!r}: expected a string")
    return v


#: What a name (sensor, detector, fault id, variant) may hold: names become parts of file
#: names (``{variant}_detector_{sensor}_{detector}.png``), so no path separator, no leading dot.
NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.+-]{0,63}")


def _name(v: Any, path: str) -> str:
    """A name: 1–64 letters, digits, ``_ . + -``, starting with a letter or digit (names are
    parts of output file names: ``../x`` or ``a/b`` would write outside ``--out``)."""
    s = _str(v, path)
    if not s.strip():
        raise ScenarioError(f"{path} = {v!r}: must not be empty")
    if s != s.strip():
        raise ScenarioError(f"{path} = {v!r}: must not start or end with white space")
    if not NAME_PATTERN.fullmatch(s):
        raise ScenarioError(
            f"{path} = {v!r}: a name may hold only letters, digits and _ . + - (up to 64, starting with a "
            "letter or digit): it becomes part of output file names")
    return s


def _number(v: Any, path: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ScenarioError(f"{path} = {v!r}: expected a finite number")
    return float(v)


def _count(v: Any, path: str) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or v < 1:
        raise ScenarioError(f"{path} = {v!r}: expected an integer >= 1")
    return v


def _bool(v: Any, path: str) -> bool:
    """A TOML boolean; anything else names the field."""
    if not isinstance(v, bool):
        raise ScenarioError(f"{path} = {v!r}: expected true or false")
    return v


def _unit(v: Any, dim: str, path: str) -> float:
    try:
        return parse(v, dim, path)
    except UnitError as e:
        raise ScenarioError(str(e)) from None


def _detectors(value: Any, p: str) -> list[dict[str, Any]]:
    """The ``detectors`` list of a sub-filter or centralized sensor at path ``p``."""
    dets = []
    for j, d in enumerate(_list(value, f"{p}.detectors")):
        dp = f"{p}.detectors[{j}]"
        _check_keys(d, "detectors", dp)
        kind = _str(_need(d, "kind", dp), f"{dp}.kind")
        if kind not in ("chi2", "sprt", "joint", "state_chi2"):
            raise ScenarioError(f"{dp}.kind = {kind!r}: use chi2, sprt, joint or state_chi2")
        dets.append(
            {
                "name": _name(d.get("name", kind), f"{dp}.name"),
                "kind": kind,
                "pf": _number(_need(d, "pf", dp), f"{dp}.pf"),
                "pm": None if "pm" not in d else _number(d["pm"], f"{dp}.pm"),
                "variance": None if "variance" not in d else _str(d["variance"], f"{dp}.variance"),
                "min_samples": None if "min_samples" not in d else _count(d["min_samples"], f"{dp}.min_samples"),
            }
        )
    return dets
