"""The scenario reference is generated from the one schema the validators check keys against:
``docs/reference/scenario.md`` is what ``docs/scripts/scenario_reference.py`` writes, every
``_check_keys`` call names a schema section, the code's own per-key tables agree with it,
and a key the schema does not list is refused in every section that is validated."""

from __future__ import annotations

import ast
import copy
import subprocess
import sys
from pathlib import Path

import pytest

import navfdi
from navfdi import _schema
from navfdi._lc_schema import _INTEGRITY_KEYS
from navfdi.logs import IMU_KEYS
from navfdi.scenario import _CLOCK, _INS, _SEGMENTS, ScenarioError, from_dict, load_scenario

ROOT = Path(__file__).resolve().parent.parent


def test_reference_is_generated_from_the_schema() -> None:
    r = subprocess.run([sys.executable, str(ROOT / "docs" / "scripts" / "scenario_reference.py"), "--check"], capture_output=True)
    assert r.returncode == 0, "docs/reference/scenario.md is stale: run python docs/scripts/scenario_reference.py"
    doc = (ROOT / "docs" / "reference" / "scenario.md").read_text(encoding="utf-8")
    for sec in _schema.SECTIONS.values():
        assert f"## {sec.title}" in doc
        for key, k in sec.keys.items():
            assert k.type and k.default and k.meaning, (sec.title, key)
            assert f"| `{key}` |" in doc


def test_every_key_check_names_a_schema_section() -> None:
    """No validator keeps its own list of keys: each ``_check_keys`` call passes a section of
    the schema (an f-string only for the trajectory segments, one section per kind)."""
    calls = 0
    for f in sorted((ROOT / "python" / "navfdi").glob("*.py")):
        for node in ast.walk(ast.parse(f.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "_check_keys":
                calls += 1
                arg = node.args[1]
                if isinstance(arg, ast.JoinedStr):
                    assert f.name == "scenario.py"
                    assert {f"segment.{k}" for k in _SEGMENTS} <= set(_schema.SECTIONS)
                else:
                    assert isinstance(arg, ast.Constant) and isinstance(arg.value, str), f"{f.name}:{node.lineno}"
                    _schema.keys(arg.value)  # a known section
    assert calls >= 30


def test_code_tables_agree_with_the_schema() -> None:
    assert set(_INS) == _schema.keys("ins")
    assert set(_CLOCK) == _schema.keys("sensors.ranges.clock")
    assert {*_INTEGRITY_KEYS, "range_errors"} == _schema.keys("tight.integrity")
    for kind, dims in _SEGMENTS.items():
        assert {"kind", *dims} == _schema.keys(f"segment.{kind}")
    assert set(IMU_KEYS) == _schema.keys("source.imu")


def _with(raw: dict, path: list, key: str) -> dict:
    out = copy.deepcopy(raw)
    t = out
    for p in path:
        t = t[p]
    t[key] = 1
    return out


@pytest.mark.parametrize(("scenario", "path", "section"), [
    ("yang2013", [], ""), ("yang2013", ["ins"], "ins"), ("yang2013", ["trajectory"], "trajectory"),
    ("yang2013", ["sensors", 0], "sensors"), ("yang2013", ["federated"], "federated"),
    ("gao_fading", ["centralized"], "centralized"), ("gao_fading", ["faults", 0], "faults"),
    ("shao2018", ["tight"], "tight"), ("shao2018", ["sensors", 0, "ranges"], "sensors.ranges"),
    ("liu2022", ["ultra_tight"], "ultra_tight"), ("drive_lc", ["loosely_coupled"], "loosely_coupled"),
    ("drive_lc", ["loosely_coupled", "imu"], "strapdown.imu"), ("drive_lc", ["loosely_coupled", "alignment"], "strapdown.alignment"),
    ("drive_lc", ["loosely_coupled", "nhc"], "constraint"), ("drive_lc", ["source"], "source.loosely_coupled"),
    ("walk_tc", ["tight", "strapdown"], "tight.strapdown"), ("walk_tc", ["source"], "source.tight"),
])
def test_an_unlisted_key_is_refused_with_the_schema_keys(scenario: str, path: list, section: str) -> None:
    raw = load_scenario(scenario).raw
    with pytest.raises(ScenarioError, match="unknown field") as e:
        from_dict(_with(raw, path, "no_such_key"), source=scenario)
    assert all(k in str(e.value) for k in _schema.keys(section))
    assert navfdi  # the package imports with the schema
