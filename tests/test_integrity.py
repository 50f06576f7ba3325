"""ARAIM: the ADD v3.0 Appendix D example through the Python API, the ADD's
elevation models, a 30-satellite two-constellation geometry, fault detection and exclusion on
residuals, and bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi.integrity import elevation_variances

DATA = json.loads((Path(__file__).parent / "data" / "araim" / "add_v3_appendix_d.json").read_text())
ROWS = np.array([r[1] for r in DATA["rows"]])
SYSTEMS = [r[0][0] for r in DATA["rows"]]
C_INT = np.array([r[2] for r in DATA["rows"]])
C_ACC = np.array([r[3] for r in DATA["rows"]])
EXP = DATA["expected"]


def test_add_appendix_d_example():
    r = navfdi.araim(-ROWS, SYSTEMS, c_int=C_INT, c_acc=C_ACC, allocation=navfdi.lpv200())
    assert len(r.modes) == EXP["n_fault_modes_excl_fault_free"]
    assert r.k_fa_v == pytest.approx(EXP["K_fa_vert"], abs=5e-4)
    for key, c in (("const_out_GPS", 0), ("const_out_GAL", 1)):
        m = next(m for m in r.modes if m["constellations"] == [c])
        assert m["sigma"][2] == pytest.approx(EXP[key]["sigma_v_m"], abs=5e-4)
        assert m["sigma_ss"][2] == pytest.approx(EXP[key]["sigma_ss_v_m"], abs=5e-4)
        assert m["bias"][2] == pytest.approx(EXP[key]["b_v_m"], abs=5e-4)
    assert r.vpl == pytest.approx(EXP["VPL_m"], abs=0.05)
    assert r.emt == pytest.approx(EXP["EMT_m"], abs=0.05)
    assert r.sigma_acc_v == pytest.approx(EXP["sigma_acc_v_m"], abs=0.05)
    assert r.available and r.p_unmonitored < 8e-8


def test_add_appendix_d_hpl():
    """The ADD's levels come from its half-interval search, stopped when the bracket is TOL_PL
    (5 cm) wide, upper end returned: HPL 14.464 m (published 14.5); the exact roots of the PL
    equations are 14.416 m and VPL 19.217 m (tol_pl=0)."""
    r = navfdi.araim(-ROWS, SYSTEMS, c_int=C_INT, c_acc=C_ACC)
    assert r.hpl == pytest.approx(EXP["HPL_m"], abs=0.05)
    assert r.vpl == pytest.approx(EXP["VPL_m"], abs=0.05)
    exact = navfdi.araim(-ROWS, SYSTEMS, c_int=C_INT, c_acc=C_ACC, allocation=navfdi.Allocation(**{**navfdi.lpv200().__dict__, "tol_pl": 0.0}))
    assert exact.hpl == pytest.approx(14.4158, abs=1e-3)
    assert exact.vpl == pytest.approx(19.2171, abs=1e-3)
    # The search's result is a bound: at or above the root, within TOL_PL per axis.
    assert exact.vpl <= r.vpl <= exact.vpl + 0.05
    assert exact.hpl <= r.hpl <= exact.hpl + 0.05 * np.sqrt(2)


@pytest.mark.parametrize("field,value", [("p_hmi_vert", float("nan")), ("p_fa_vert", 0.0), ("p_thres", 1.5), ("tol_pl", -1.0), ("tol_pl", float("inf"))])
def test_a_bad_allocation_is_named(field, value):
    # Refused where it is made (the dataclass checks its fields) ...
    with pytest.raises(ValueError, match=f"Allocation.{field}"):
        navfdi.Allocation(**{**navfdi.lpv200().__dict__, field: value})
    # ... and by the core past it (the binding called directly).
    a = {**navfdi.lpv200().__dict__, field: value}
    order = ("p_hmi_vert", "p_hmi_hor", "p_fa_vert", "p_fa_hor", "p_thres", "p_emt", "tol_pl")
    los = -ROWS
    with pytest.raises(ValueError, match=f"allocation.{field}"):
        navfdi._core.araim_epoch((-los).tolist(), [0 if s == "G" else 1 for s in SYSTEMS], list(C_INT), list(C_ACC), [0.5] * len(SYSTEMS), [1e-5] * len(SYSTEMS), [1e-4, 1e-4], tuple(a[k] for k in order))


def test_the_adds_elevation_models_give_the_published_variances():
    """σ_URA² + σ_tropo² + σ_user² from the rows' elevations equals the example's C_int to the
    rows' 4-digit rounding, and the protection levels follow."""
    tropo, user = elevation_variances(np.arcsin(-ROWS[:, 2]))
    np.testing.assert_allclose(0.75**2 + tropo + user, C_INT, atol=2e-4)
    np.testing.assert_allclose(0.5**2 + tropo + user, C_ACC, atol=2e-4)
    r = navfdi.araim(-ROWS, SYSTEMS)
    assert r.vpl == pytest.approx(EXP["VPL_m"], abs=0.05)


def test_the_elevation_models_equal_the_adds_formulas():
    """The models (in Rust) against the ADD's formulas written out in numpy, from below the
    horizon to the zenith, on arrays of any shape and on a scalar."""
    el = np.linspace(-0.1, np.pi / 2, 2001).reshape(23, 87)
    d = np.degrees(el)
    k = (1575.42**4 + 1176.45**4) / (1575.42**2 - 1176.45**2) ** 2
    tropo, user = elevation_variances(el)
    assert tropo.shape == user.shape == el.shape
    np.testing.assert_allclose(tropo, (0.12 * 1.001 / np.sqrt(0.002001 + np.sin(el) ** 2)) ** 2, rtol=4e-15, atol=0)
    np.testing.assert_allclose(user, k * ((0.13 + 0.53 * np.exp(-d / 10)) ** 2 + (0.15 + 0.43 * np.exp(-d / 6.9)) ** 2), rtol=4e-15, atol=0)
    t0, u0 = elevation_variances(0.3)
    t1, u1 = elevation_variances(np.array([0.3]))
    assert np.ndim(t0) == np.ndim(u0) == 0 and (t0, u0) == (t1[0], u1[0])


def test_default_variances_equal_the_same_variances_given():
    """``araim`` with the ISM's σ and the elevation models (computed in Rust) gives the bits of
    the same call with ``c_int`` / ``c_acc`` given from :func:`elevation_variances`; per-satellite
    ISM arrays equal their scalar."""
    los = -ROWS
    tropo, user = elevation_variances(np.arcsin(los[:, 2]))
    a = navfdi.araim(los, SYSTEMS)
    b = navfdi.araim(los, SYSTEMS, c_int=0.75**2 + tropo + user, c_acc=0.5**2 + tropo + user)
    c = navfdi.araim(los, SYSTEMS, ism=navfdi.integrity.Ism(sigma_ura=[0.75] * 10, b_nom=np.full(10, 0.5), p_sat=[1e-5] * 10))
    for r in (b, c):
        assert (r.vpl, r.hpl, r.emt, r.sigma_acc_v) == (a.vpl, a.hpl, a.emt, a.sigma_acc_v)
        np.testing.assert_array_equal(r.mode_table["sigma"], a.mode_table["sigma"])
    # Lines of sight in Fortran order or as lists read the same.
    d = navfdi.araim(np.asfortranarray(los), SYSTEMS)
    e = navfdi.araim(los.tolist(), SYSTEMS)
    assert (d.vpl, d.hpl) == (e.vpl, e.hpl) == (a.vpl, a.hpl)


def test_thirty_satellites_in_two_constellations_are_available():
    i = np.arange(30)
    az = i * 2.399963
    el = np.radians(10 + 75 * ((i * 7) % 30) / 29)
    los = np.column_stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)])
    r = navfdi.araim(los, ["G" if k % 2 == 0 else "E" for k in i])
    assert r.available and r.p_unmonitored < 8e-8
    # Pairs of events are monitored: a constellation with a satellite of the other among them.
    assert any(len(m["constellations"]) == 1 and len(m["satellites"]) == 16 for m in r.modes)
    assert r.vpl < 35.0 and r.hpl < 40.0


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"los_enu": np.zeros((3, 2))}, r"los_enu: expected shape \(n, 3\)"),
        ({"los_enu": -ROWS * 2}, r"los_enu\[\d\]: norm .* unit vectors"),
        ({"systems": SYSTEMS[:-1]}, "systems: 9 letters for 10 satellites"),
        ({"systems": ["G"] * 5 + ["C"] * 5}, r"no constellation prior for system\(s\) C"),
        ({"c_int": -C_INT}, r"c_int\[0\] = -3.8865: a variance must be positive"),
        ({"c_acc": C_ACC[:3]}, r"c_acc: expected a scalar or \(10,\) values"),
        ({"los_enu": np.where(np.arange(30).reshape(10, 3) == 7, np.nan, -ROWS)}, r"los_enu: element \[2, 1\] is NaN; only finite"),
        ({"los_enu": np.where(np.arange(30).reshape(10, 3) == 2, np.inf, -ROWS)}, r"los_enu: element \[0, 2\] is inf"),
        ({"ism": navfdi.integrity.Ism(b_nom=[0.5] * 4)}, r"ism.b_nom: expected a scalar or \(10,\) values"),
    ],
)
def test_bad_input_is_named(kwargs, match):
    args = {"los_enu": -ROWS, "systems": SYSTEMS, **kwargs}
    with pytest.raises(ValueError, match=match):
        navfdi.araim(args.pop("los_enu"), args.pop("systems"), **args)


# ---- fault detection and exclusion (residuals) ---------------------------------------------
def _residuals(bias: dict[int, float]) -> np.ndarray:
    """Residuals of the ADD geometry for a receiver offset and clocks (which no test may see)
    plus ``bias`` (m) on some satellites."""
    clocks = np.where(np.array(SYSTEMS) == "G", 40.0, -25.0)
    y = ROWS @ np.array([3.0, -2.0, 5.0]) + clocks
    for i, b in bias.items():
        y[i] += b
    return y


def test_consistent_residuals_pass_and_keep_the_levels():
    plain = navfdi.araim(-ROWS, SYSTEMS, c_int=C_INT, c_acc=C_ACC)
    r = navfdi.araim(-ROWS, SYSTEMS, c_int=C_INT, c_acc=C_ACC, residuals=_residuals({}))
    assert not r.detected and not r.alarm and r.excluded == ()
    assert r.test_ratio < 1e-9 and (r.vpl, r.hpl) == (plain.vpl, plain.hpl)
    # each mode's separation is recorded, and |separation| ≤ threshold everywhere
    sep = r.mode_table["separation"]
    assert sep.shape == (len(r.modes), 3) and np.all(np.abs(sep) <= r.mode_table["threshold"])
    assert np.isnan(plain.mode_table["separation"]).all() and np.isnan(plain.test_ratio)


@pytest.mark.parametrize("faulty", range(10))
def test_a_biased_satellite_is_excluded_and_the_levels_recomputed(faulty):
    r = navfdi.araim(-ROWS, SYSTEMS, c_int=C_INT, c_acc=C_ACC, residuals=_residuals({faulty: 60.0}))
    assert r.detected and r.test_ratio > 1 and not r.alarm
    assert r.excluded == (faulty,)
    keep = [i for i in range(10) if i != faulty]
    sub = navfdi.araim(-ROWS[keep], [SYSTEMS[i] for i in keep], c_int=C_INT[keep], c_acc=C_ACC[keep])
    assert (r.vpl, r.hpl) == (sub.vpl, sub.hpl) and r.available == sub.available
    assert r.vpl_any >= r.vpl and r.hpl_any >= r.hpl


def test_residuals_are_checked():
    with pytest.raises(ValueError, match=r"residuals: expected shape \(10,\)"):
        navfdi.araim(-ROWS, SYSTEMS, residuals=np.zeros(9))
    y = _residuals({})
    y[3] = np.nan
    with pytest.raises(ValueError, match=r"residuals\[3\]"):
        navfdi.araim(-ROWS, SYSTEMS, residuals=y)


def test_modes_are_built_from_the_columns():
    r = navfdi.araim(-ROWS, SYSTEMS, c_int=C_INT, c_acc=C_ACC)
    t = r.mode_table
    assert len(r.modes) == len(t["prior"]) == 12
    for k, m in enumerate(r.modes):
        assert m["prior"] == t["prior"][k] and m["sigma"] == list(t["sigma"][k])
        assert len(m["satellites"]) == t["satellites_count"][k]
