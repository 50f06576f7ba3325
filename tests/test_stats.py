"""Thresholds, non-centrality and MDB against scipy (a test-only dependency)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

import navfdi

PF = [1e-9, 1e-6, 1e-4, 1e-3, 0.005, 0.01, 0.05, 0.1, 0.2, 0.5, 0.9]
DOF = [1, 2, 3, 5, 6, 10, 15, 40]


@pytest.mark.parametrize("dof", DOF)
@pytest.mark.parametrize("pf", PF)
def test_chi2_threshold_matches_scipy(pf, dof):
    assert navfdi.chi2_threshold(pf, dof) == pytest.approx(stats.chi2.isf(pf, dof), rel=1e-10)


@pytest.mark.parametrize(
    ("pf", "dof", "paper"),
    [(0.1, 3, 6.251), (0.005, 6, 18.548), (0.05, 5, 11.0705)],
)
def test_papers_chi2_thresholds(pf, dof, paper):
    # Papers 000, 002 and 001 report these to the digits shown.
    assert navfdi.chi2_threshold(pf, dof) == pytest.approx(paper, abs=0.5 * 10 ** -(len(str(paper).split(".")[1])))


@pytest.mark.parametrize(("pf", "pm", "paper"), [(0.1, 0.1, 2.197), (0.005, 0.005, 5.293)])
def test_papers_sprt_thresholds(pf, pm, paper):
    assert navfdi.sprt_threshold(pf, pm) == pytest.approx(paper, abs=5e-4)
    assert navfdi.sprt_threshold(pf, pm) == pytest.approx(math.log((1 - pm) / pf), rel=1e-15)


@pytest.mark.parametrize("dof", [1, 3, 6, 12])
@pytest.mark.parametrize(("pf", "pm"), [(0.1, 0.05), (0.005, 0.005), (0.01, 0.1), (1e-5, 1e-3), (0.2, 0.5)])
def test_noncentrality_matches_scipy(pf, pm, dof):
    lam = navfdi.noncentrality(pf, pm, dof)
    td = stats.chi2.isf(pf, dof)
    assert stats.ncx2.cdf(td, dof, lam) == pytest.approx(pm, rel=1e-7)


def test_noncentrality_values_of_methods_section_6():
    # METHODS §6: 17.87 is what m=6, Pf=0.1, Pm=0.05 gives; Pf=Pm=0.005 gives 41.04 (m=6), 28.98 (m=1).
    assert navfdi.noncentrality(0.1, 0.05, 6) == pytest.approx(17.87, abs=0.01)
    assert navfdi.noncentrality(0.005, 0.005, 6) == pytest.approx(41.04, abs=0.01)
    assert navfdi.noncentrality(0.005, 0.005, 1) == pytest.approx(28.98, abs=0.01)


@pytest.mark.parametrize("x", [0.1, 1.0, 5.0, 20.0, 80.0])
@pytest.mark.parametrize("nc", [0.0, 0.5, 5.0, 40.0, 200.0])
def test_ncx2_cdf_matches_scipy(x, nc):
    expected = stats.chi2.cdf(x, 4) if nc == 0 else stats.ncx2.cdf(x, 4, nc)
    assert navfdi.ncx2_cdf(x, 4, nc) == pytest.approx(expected, rel=1e-9, abs=1e-15)


def test_mdb_matches_definition():
    rng = np.random.default_rng(0)
    B = rng.standard_normal((6, 6))
    A = B @ B.T + 6 * np.eye(6)
    lam0 = navfdi.noncentrality(0.005, 0.005, 6)
    expected = np.sqrt(lam0 / np.diag(np.linalg.inv(A)))
    np.testing.assert_allclose(navfdi.mdb(A, 0.005, 0.005), expected, rtol=1e-10)


def test_mdb_paper_002_scale():
    """GNSS position noise 10 m, velocity 0.1 m/s (paper 002): MDB = σ·sqrt(λ0) for a diagonal A."""
    A = np.diag([100.0] * 3 + [0.01] * 3)
    mdb = navfdi.mdb(A, 0.1, 0.05)  # λ0 = 17.87, the value paper 002 reports
    np.testing.assert_allclose(mdb[:3], 10 * np.sqrt(17.872), rtol=1e-3)  # ≈ 42.3 m (paper: ≈ 42.5 m)
    np.testing.assert_allclose(mdb[3:], 0.1 * np.sqrt(17.872), rtol=1e-3)  # ≈ 0.42 m/s


@pytest.mark.parametrize(
    ("call", "needle"),
    [
        (lambda: navfdi.chi2_threshold(0.0, 3), "pf"),
        (lambda: navfdi.chi2_threshold(1.0, 3), "pf"),
        (lambda: navfdi.chi2_threshold(float("nan"), 3), "pf"),
        (lambda: navfdi.chi2_threshold(0.1, 0), "dof"),
        (lambda: navfdi.chi2_threshold(0.1, -2), "dof"),
        (lambda: navfdi.sprt_threshold(0.1, 1.5), "pm"),
        (lambda: navfdi.sprt_threshold(0.6, 0.5), "pf + pm"),
        (lambda: navfdi.noncentrality(0.5, 0.6, 3), "pf + pm"),
        (lambda: navfdi.mdb(np.eye(2)[:1], 0.1, 0.1), "A"),
        (lambda: navfdi.mdb([[1.0, 2.0], [2.0, 1.0]], 0.1, 0.1), "A"),
        (lambda: navfdi.ncx2_cdf(1.0, 3, -1.0), "lambda"),
    ],
)
def test_bad_parameters_raise_value_error(call, needle):
    with pytest.raises(ValueError, match=needle.replace("+", r"\+")):
        call()
