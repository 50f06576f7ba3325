//! Integrity bindings: ARAIM protection levels of one epoch (`navfdi_core::integrity::araim`).

use crate::convert::to_numpy;
use crate::errors::IntoPyResult;
use navfdi_core::integrity::araim::{araim, Allocation, FaultMode, Ism};
use navfdi_core::integrity::araim_fde::araim_fde;
use navfdi_core::integrity::araim_model as model;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// ARAIM (ADD v3.0 multiple-hypothesis solution separation) on one epoch. `rows` (n, 3): ENU
/// geometry rows (minus the unit lines of sight); `constellation` (n): index of each
/// satellite's constellation; `c_int`, `c_acc` (n, m²); `b_nom`, `p_sat` (n); `p_const` (one per
/// constellation); `allocation`: (P_HMI,VERT, P_HMI,HOR, P_FA,VERT, P_FA,HOR, P_THRES, P_EMT,
/// TOL_PL (m));
/// `residuals` (n, m, optional): fault detection and exclusion on them
/// (`navfdi_core::integrity::araim_fde::araim_fde`). Returns a dict of the all-in-view results,
/// the fault modes as columns (`modes`: `prior` (N,), `sigma`, `sigma_ss`, `bias`,
/// `threshold`, `separation` (N, 3), `satellites` and `constellations` flattened with their
/// per-mode counts), and with residuals `fde` (`detected`, `test_ratio`, `excluded`, `tried`,
/// `passed`, `vpl`, `hpl`, `vpl_any`, `hpl_any`, `correction` (east, north, up, m), `alarm`,
/// `available`); the GIL is released.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (rows, constellation, c_int, c_acc, b_nom, p_sat, p_const, allocation, residuals=None))]
pub fn araim_epoch<'py>(
    py: Python<'py>,
    rows: Vec<[f64; 3]>,
    constellation: Vec<usize>,
    c_int: Vec<f64>,
    c_acc: Vec<f64>,
    b_nom: Vec<f64>,
    p_sat: Vec<f64>,
    p_const: Vec<f64>,
    allocation: (f64, f64, f64, f64, f64, f64, f64),
    residuals: Option<Vec<f64>>,
) -> PyResult<Bound<'py, PyDict>> {
    finite_rows(&rows)?;
    let ism = Ism {
        c_int,
        c_acc,
        b_nom,
        p_sat,
        p_const,
    };
    run_araim(py, rows, constellation, ism, allocation, residuals)
}

/// [`araim_epoch`] from unit lines of sight `los_enu` (n, 3; east, north, up; any array-like)
/// with the ADD's default variances where `c_int` / `c_acc` are None
/// (`navfdi_core::integrity::araim_model`: `σ_URA² (σ_URE²) + σ_tropo² + σ_user²` at each
/// satellite's elevation). `sigma_ura`, `sigma_ure`, `b_nom`, `p_sat`, `c_int`, `c_acc`: one
/// value for every satellite or n. The same dict as [`araim_epoch`]; ValueError naming the
/// argument for a wrong shape, a non-finite or non-unit line of sight.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (los_enu, constellation, sigma_ura, sigma_ure, c_int, c_acc, b_nom, p_sat, p_const, allocation, residuals=None))]
pub fn araim_los<'py>(
    py: Python<'py>,
    los_enu: &Bound<'py, PyAny>,
    constellation: Vec<usize>,
    sigma_ura: Vec<f64>,
    sigma_ure: Vec<f64>,
    c_int: Option<Vec<f64>>,
    c_acc: Option<Vec<f64>>,
    b_nom: Vec<f64>,
    p_sat: Vec<f64>,
    p_const: Vec<f64>,
    allocation: (f64, f64, f64, f64, f64, f64, f64),
    residuals: Option<Vec<f64>>,
) -> PyResult<Bound<'py, PyDict>> {
    let a = crate::convert::read("los_enu", los_enu)?;
    if a.shape.len() != 2 || a.shape[1] != 3 || a.shape[0] == 0 {
        return Err(PyValueError::new_err(format!(
            "los_enu: expected shape (n, 3), got {:?}",
            a.shape
        )));
    }
    let n = a.shape[0];
    let los: Vec<[f64; 3]> = a.data.chunks_exact(3).map(|r| [r[0], r[1], r[2]]).collect();
    let each = |name: &str, v: Vec<f64>| model::per_satellite(name, v, n).py();
    let (ura, ure) = (
        each("ism.sigma_ura", sigma_ura)?,
        each("ism.sigma_ure", sigma_ure)?,
    );
    let m = model::los_rows_and_variances(&los, &ura, &ure).py()?;
    let ism = Ism {
        c_int: match c_int {
            Some(v) => each("c_int", v)?,
            None => m.c_int,
        },
        c_acc: match c_acc {
            Some(v) => each("c_acc", v)?,
            None => m.c_acc,
        },
        b_nom: each("ism.b_nom", b_nom)?,
        p_sat: each("ism.p_sat", p_sat)?,
        p_const,
    };
    run_araim(py, m.rows, constellation, ism, allocation, residuals)
}

/// The ADD's `(σ_tropo², σ_user²)` (m²) at elevations `elevation` (rad, any shape), each an
/// array of that shape (`navfdi_core::integrity::araim_model::elevation_variances`).
#[pyfunction]
pub fn araim_variances<'py>(
    py: Python<'py>,
    elevation: &Bound<'py, PyAny>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let a = crate::convert::read("elevation", elevation)?;
    let (t, u): (Vec<f64>, Vec<f64>) = a
        .data
        .iter()
        .map(|&e| model::elevation_variances(e))
        .unzip();
    Ok((
        to_numpy(py, t, &a.shape)?.into_any(),
        to_numpy(py, u, &a.shape)?.into_any(),
    ))
}

/// ARAIM (or, with residuals, its FDE) on the GIL-free side, and the result dict.
fn run_araim<'py>(
    py: Python<'py>,
    rows: Vec<[f64; 3]>,
    constellation: Vec<usize>,
    ism: Ism,
    allocation: (f64, f64, f64, f64, f64, f64, f64),
    residuals: Option<Vec<f64>>,
) -> PyResult<Bound<'py, PyDict>> {
    let (p_hmi_vert, p_hmi_hor, p_fa_vert, p_fa_hor, p_thres, p_emt, tol_pl) = allocation;
    let alloc = Allocation {
        p_hmi_vert,
        p_hmi_hor,
        p_fa_vert,
        p_fa_hor,
        p_thres,
        p_emt,
        tol_pl,
    };
    let (r, fde) = py
        .detach(move || match residuals {
            None => araim(&rows, &constellation, &ism, &alloc).map(|r| (r, None)),
            Some(y) => araim_fde(&rows, &constellation, &ism, &alloc, &y).map(|f| {
                let r = f.all_in_view.clone();
                (r, Some(f))
            }),
        })
        .py()?;
    let d = PyDict::new(py);
    d.set_item("vpl", r.vpl)?;
    d.set_item("hpl", r.hpl)?;
    d.set_item("emt", r.emt)?;
    d.set_item("sigma_acc", r.sigma_acc.to_vec())?;
    d.set_item("sigma0", r.sigma0.to_vec())?;
    d.set_item("bias0", r.bias0.to_vec())?;
    d.set_item("k_fa", r.k_fa.to_vec())?;
    d.set_item("p_unmonitored", r.p_unmonitored)?;
    d.set_item("n_max", r.n_max)?;
    d.set_item("available", r.available)?;
    let n_modes = r.modes.len();
    let table =
        |f: &dyn Fn(&FaultMode) -> [f64; 3]| -> Vec<f64> { r.modes.iter().flat_map(f).collect() };
    let modes = PyDict::new(py);
    modes.set_item(
        "prior",
        to_numpy(py, r.modes.iter().map(|m| m.prior).collect(), &[n_modes])?,
    )?;
    for (name, col) in [
        ("sigma", table(&|m| m.sigma)),
        ("sigma_ss", table(&|m| m.sigma_ss)),
        ("bias", table(&|m| m.bias)),
        ("threshold", table(&|m| m.threshold)),
        ("separation", table(&|m| m.separation)),
    ] {
        modes.set_item(name, to_numpy(py, col, &[n_modes, 3])?)?;
    }
    for (name, lists) in [
        (
            "satellites",
            r.modes.iter().map(|m| &m.satellites).collect::<Vec<_>>(),
        ),
        (
            "constellations",
            r.modes
                .iter()
                .map(|m| &m.constellations)
                .collect::<Vec<_>>(),
        ),
    ] {
        let flat: Vec<i64> = lists
            .iter()
            .flat_map(|v| v.iter().map(|&i| i as i64))
            .collect();
        let counts: Vec<i64> = lists.iter().map(|v| v.len() as i64).collect();
        let n_flat = flat.len();
        modes.set_item(name, to_numpy(py, flat, &[n_flat])?)?;
        modes.set_item(format!("{name}_count"), to_numpy(py, counts, &[n_modes])?)?;
    }
    d.set_item("modes", modes)?;
    if let Some(f) = fde {
        let e = PyDict::new(py);
        e.set_item("detected", f.detected)?;
        e.set_item("test_ratio", f.test_ratio)?;
        e.set_item("excluded", f.excluded)?;
        e.set_item("tried", f.tried)?;
        e.set_item("passed", f.passed)?;
        e.set_item("vpl", f.vpl)?;
        e.set_item("hpl", f.hpl)?;
        e.set_item("vpl_any", f.vpl_any)?;
        e.set_item("hpl_any", f.hpl_any)?;
        e.set_item("correction", f.correction.to_vec())?;
        e.set_item("alarm", f.alarm)?;
        e.set_item("available", f.available)?;
        d.set_item("fde", e)?;
    }
    Ok(d)
}

/// Slope-based protection levels of the snapshot least-squares global test (one epoch).
/// `los_enu` (n, 3): unit lines of sight receiver → satellite (east, north, up); `clock` (n):
/// 0-based clock group per satellite; `sigma2` (n, m²); `threshold`: the χ² quantile the test
/// compares `rᵀWr` with; `k_md`: the missed-detection quantile. Returns a dict: `hpl`, `vpl`,
/// `sigma_h`, `sigma_v` (m), `hslope`, `vslope`, `critical` (index of the satellite with the
/// largest vertical slope). `overbound` (optional): ``(variances m², nominal biases m)`` per
/// satellite of an overbounding error model, for the fault-free terms (the slopes keep the
/// test's σ). ValueError for too few satellites or a singular geometry.
#[pyfunction]
#[pyo3(signature = (los_enu, clock, sigma2, threshold, k_md, overbound = None))]
pub fn snapshot_pl<'py>(
    py: Python<'py>,
    los_enu: Vec<[f64; 3]>,
    clock: Vec<usize>,
    sigma2: Vec<f64>,
    threshold: f64,
    k_md: f64,
    overbound: Option<(Vec<f64>, Vec<f64>)>,
) -> PyResult<Bound<'py, PyDict>> {
    finite_rows(&los_enu)?;
    let los: Vec<nalgebra::Vector3<f64>> = los_enu
        .iter()
        .map(|r| nalgebra::Vector3::from(*r))
        .collect();
    let ob = overbound
        .as_ref()
        .map(|(c, b)| (c.as_slice(), b.as_slice()));
    let pl = navfdi_core::integrity::snapshot::snapshot_pl_overbound(
        &los, &clock, &sigma2, threshold, k_md, ob,
    )
    .py()?;
    let d = PyDict::new(py);
    d.set_item("hpl", pl.hpl)?;
    d.set_item("vpl", pl.vpl)?;
    d.set_item("sigma_h", pl.sigma_h)?;
    d.set_item("sigma_v", pl.sigma_v)?;
    d.set_item("hslope", pl.hslope)?;
    d.set_item("vslope", pl.vslope)?;
    d.set_item("critical", pl.critical)?;
    Ok(d)
}

/// Every line of sight finite, else a ValueError naming the first bad row of `los_enu`.
fn finite_rows(rows: &[[f64; 3]]) -> PyResult<()> {
    match rows
        .iter()
        .enumerate()
        .find(|(_, r)| !r.iter().all(|v| v.is_finite()))
    {
        Some((i, r)) => Err(PyValueError::new_err(format!(
            "los_enu[{i}]: {r:?} is not finite"
        ))),
        None => Ok(()),
    }
}
