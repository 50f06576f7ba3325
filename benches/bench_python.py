"""pytest-benchmark: navfdi's Python API beside filterpy on the same problem, in the same run.

``python -m pytest benches --benchmark-enable`` times them (plain ``pytest`` only smoke-runs
them once, with ``--benchmark-disable`` from pyproject). ``python benches/compare.py`` prints
the per-epoch ratios for benches/README.md.
"""

from __future__ import annotations

import numpy as np
import pytest

from problem import filterpy_loop, problem, run_filter, step_api

pytest.importorskip("filterpy")

T_SMALL = 2_000  # epochs per benchmark round (per-epoch cost is what is compared)


@pytest.fixture(scope="module")
def prob():
    return problem(T_SMALL)


def test_all_three_agree(prob):
    """Same problem, same answer (filterpy uses an explicit inverse, hence the tolerance)."""
    a, b, c = run_filter(*prob), step_api(*prob), filterpy_loop(*prob)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(a, c.ravel(), rtol=1e-6, atol=1e-9)


@pytest.mark.benchmark(group="kalman n=15 m=6")
def test_bench_run_filter(benchmark, prob):
    benchmark(run_filter, *prob)


@pytest.mark.benchmark(group="kalman n=15 m=6")
def test_bench_step_api(benchmark, prob):
    benchmark(step_api, *prob)


@pytest.mark.benchmark(group="kalman n=15 m=6")
def test_bench_filterpy(benchmark, prob):
    benchmark.pedantic(filterpy_loop, args=prob, rounds=3, iterations=1)
