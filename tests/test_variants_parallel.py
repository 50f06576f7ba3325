"""Variants run in parallel (rayon, inside one Rust call): each variant's record is the same
to the bit as the variant run alone, on simulated and on recorded measurements."""

from __future__ import annotations

import numpy as np
import pytest

from navfdi import load_scenario, run_scenario


def _same(a: object, b: object, path: str = "record") -> None:
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), path
        for k in a:
            _same(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape, path
        assert a.tobytes() == b.tobytes(), path
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _same(x, y, f"{path}[{i}]")
    elif isinstance(a, float) and np.isnan(a):
        assert isinstance(b, float) and np.isnan(b), path
    else:
        assert a == b, path


@pytest.mark.parametrize("name", ["yang2013", "shao2018", "drive_lc"])
def test_each_variant_as_run_alone(name: str) -> None:
    sc = load_scenario(name)
    together = run_scenario(sc, seed=3)
    assert len(together.runs) >= 2
    for vname, variant in sc.variants():
        alone = run_scenario(variant, seed=3, compare_isolation=False)
        _same(together[vname].record, alone.record)
