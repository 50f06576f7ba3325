//! Integrity bindings: ARAIM protection levels of one epoch (`navfdi_core::integrity::araim`).

use crate::errors::IntoPyResult;
use navfdi_core::integrity::araim::{araim, Allocation, Ism};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// ARAIM (ADD v3.0 multiple-hypothesis solution separation) on one epoch. `rows` (n, 3): ENU
/// geometry rows (minus the unit lines of sight); `constellation` (n): index of each
/// satellite's constellation; `c_int`, `c_acc` (n, m²); `b_nom`, `p_sat` (n); `p_const` (one per
/// constellation); `allocation`: (P_HMI,VERT, P_HMI,HOR, P_FA,VERT, P_FA,HOR, P_THRES, P_EMT).
/// Returns a dict of the results and the fault modes; the GIL is released.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn araim_epoch<'py>(
    py: Python<'py>,
    rows: Vec<[f64; 3]>,
    constellation: Vec<usize>,
    c_int: Vec<f64>,
    c_acc: Vec<f64>,
    b_nom: Vec<f64>,
    p_sat: Vec<f64>,
    p_const: Vec<f64>,
    allocation: (f64, f64, f64, f64, f64, f64),
) -> PyResult<Bound<'py, PyDict>> {
    finite_rows(&rows)?;
    let (p_hmi_vert, p_hmi_hor, p_fa_vert, p_fa_hor, p_thres, p_emt) = allocation;
    let alloc = Allocation {
        p_hmi_vert,
        p_hmi_hor,
        p_fa_vert,
        p_fa_hor,
        p_thres,
        p_emt,
    };
    let ism = Ism {
        c_int,
        c_acc,
        b_nom,
        p_sat,
        p_const,
    };
    let r = py
        .detach(move || araim(&rows, &constellation, &ism, &alloc))
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
    let modes = PyList::empty(py);
    for m in r.modes {
        let md = PyDict::new(py);
        md.set_item("satellites", m.satellites)?;
        md.set_item("constellations", m.constellations)?;
        md.set_item("prior", m.prior)?;
        md.set_item("sigma", m.sigma.to_vec())?;
        md.set_item("sigma_ss", m.sigma_ss.to_vec())?;
        md.set_item("bias", m.bias.to_vec())?;
        md.set_item("threshold", m.threshold.to_vec())?;
        modes.append(md)?;
    }
    d.set_item("modes", modes)?;
    Ok(d)
}

/// Slope-based protection levels of the snapshot least-squares global test (one epoch).
/// `los_enu` (n, 3): unit lines of sight receiver → satellite (east, north, up); `clock` (n):
/// 0-based clock group per satellite; `sigma2` (n, m²); `threshold`: the χ² quantile the test
/// compares `rᵀWr` with; `k_md`: the missed-detection quantile. Returns a dict: `hpl`, `vpl`,
/// `sigma_h`, `sigma_v` (m), `hslope`, `vslope`, `critical` (index of the satellite with the
/// largest vertical slope). ValueError for too few satellites or a singular geometry.
#[pyfunction]
pub fn snapshot_pl<'py>(
    py: Python<'py>,
    los_enu: Vec<[f64; 3]>,
    clock: Vec<usize>,
    sigma2: Vec<f64>,
    threshold: f64,
    k_md: f64,
) -> PyResult<Bound<'py, PyDict>> {
    finite_rows(&los_enu)?;
    let los: Vec<nalgebra::Vector3<f64>> = los_enu
        .iter()
        .map(|r| nalgebra::Vector3::from(*r))
        .collect();
    let pl = navfdi_core::integrity::snapshot::snapshot_pl(&los, &clock, &sigma2, threshold, k_md)
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
