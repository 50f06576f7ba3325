"""Behaviour unchanged by refactoring, proven: every bundled scenario's run (records of every
variant and its printed tables) and a small Monte-Carlo campaign (summary table and per-run
metrics) hash to the values stored in ``tests/data/golden_outputs.json``.

The stored hashes were taken on the code before the measurement-stream refactor.
They are bit-level: any change of arithmetic order shows. They depend on the floating-point
code paths chosen at run time (the tight filter's AVX2+FMA row loop), so the test runs only
on a processor with the same features as the one the hashes were taken on.

A change that is *meant* to alter numbers regenerates the file with
``python tests/test_bit_identity.py --write`` and says so in its commit.
"""

from __future__ import annotations

import hashlib
import json
import struct
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import navfdi

GOLDEN = Path(__file__).parent / "data" / "golden_outputs.json"
SEED = 1
MC_RUNS = 3
MC_SEED = 7


def cpu_features() -> str:
    """The x86 features that select the numeric code paths ("avx2 fma", or what is there)."""
    try:
        flags = next(line for line in Path("/proc/cpuinfo").read_text().splitlines() if line.startswith("flags")).split()
    except (OSError, StopIteration):
        return "unknown"
    return " ".join(f for f in ("avx2", "fma") if f in flags)


def _feed(h: Any, obj: Any) -> None:
    if isinstance(obj, dict):
        h.update(b"{")
        for k in sorted(obj):
            h.update(repr(k).encode())
            _feed(h, obj[k])
        h.update(b"}")
    elif isinstance(obj, (list, tuple)):
        h.update(b"[")
        for v in obj:
            _feed(h, v)
        h.update(b"]")
    elif isinstance(obj, np.ndarray):
        a = np.ascontiguousarray(obj)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        if a.dtype == object:
            _feed(h, a.tolist())
        else:
            h.update(a.tobytes())
    elif isinstance(obj, (bool, np.bool_)):
        h.update(b"T" if obj else b"F")
    elif isinstance(obj, (float, np.floating)):
        h.update(struct.pack("<d", float(obj)))
    elif isinstance(obj, (int, np.integer)):
        h.update(str(int(obj)).encode())
    elif obj is None:
        h.update(b"None")
    else:
        h.update(repr(obj).encode())


def digest(obj: Any) -> str:
    """SHA-256 of a nested structure of dicts, lists, numpy arrays and scalars (bit-exact)."""
    h = hashlib.sha256()
    _feed(h, obj)
    return h.hexdigest()


def run_hashes(name: str) -> dict[str, str]:
    """Hashes of one bundled scenario's run at ``SEED``: each variant's record (and the
    no-isolation baseline) and the printed tables."""
    r = navfdi.run_scenario(name, seed=SEED)
    out: dict[str, str] = {"tables": hashlib.sha256(r.format_tables().encode()).hexdigest()}
    runs = r.runs if isinstance(r, navfdi.VariantRuns) else {"base": r}
    for vname, run in runs.items():
        out[f"record.{vname}"] = digest(run.record)
        if run.baseline is not None:
            out[f"baseline.{vname}"] = digest(run.baseline)
    return out


def campaign_hashes(name: str) -> dict[str, str]:
    """Hashes of a small campaign: summary table, printed table and per-run metrics."""
    c = navfdi.montecarlo(name, runs=MC_RUNS, seed=MC_SEED, workers=2, progress=False)
    return {
        "summary": hashlib.sha256(c.summary().to_csv(index=False).encode()).hexdigest(),
        "table": hashlib.sha256(c.format_table().encode()).hexdigest(),
        "runs": hashlib.sha256(c.runs.to_csv(index=False).encode()).hexdigest(),
    }


def bundled() -> list[str]:
    return sorted(navfdi.bundled_scenarios())


def compute() -> dict[str, Any]:
    return {
        "cpu": cpu_features(),
        "run": {n: run_hashes(n) for n in bundled()},
        "montecarlo": {n: campaign_hashes(n) for n in bundled()},
    }


def _golden() -> dict[str, Any]:
    g = json.loads(GOLDEN.read_text())
    if g["cpu"] != cpu_features():
        pytest.skip(f"hashes taken on a CPU with {g['cpu']!r}, this one has {cpu_features()!r}")
    return g


@pytest.mark.parametrize("name", bundled())
def test_run_outputs_bit_identical(name: str) -> None:
    assert run_hashes(name) == _golden()["run"][name]


@pytest.mark.parametrize("name", bundled())
def test_montecarlo_outputs_bit_identical(name: str) -> None:
    assert campaign_hashes(name) == _golden()["montecarlo"][name]


def test_digest_sees_one_bit() -> None:
    a = np.linspace(0.0, 1.0, 7)
    b = a.copy()
    b[3] = np.nextafter(b[3], 2.0)
    assert digest({"x": a}) != digest({"x": b})
    assert digest({"x": a, "y": [1, True]}) == digest({"y": [1, True], "x": a.copy()})


if __name__ == "__main__":
    if "--write" in sys.argv:
        GOLDEN.write_text(json.dumps(compute(), indent=1, sort_keys=True) + "\n")
        print(f"wrote {GOLDEN}")
