//! GNSS bindings: snapshot least squares with fault detection and exclusion.

use crate::convert::{read, to_numpy};
use crate::errors::IntoPyResult;
use nalgebra::Vector3;
use navfdi_core::gnss::snapshot::{self, Detection, FdeConfig, ObsCov};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// Result of :func:`snapshot_fde` (one epoch).
#[pyclass(name = "SnapshotFde", module = "navfdi._core", frozen)]
pub struct PySnapshotFde {
    inner: snapshot::SnapshotResult,
    /// The inputs (copies), so that pickling can recompute the identical result.
    args: SnapshotArgs,
}

/// Inputs of one [`snapshot_fde`] call: `sat_pos` row-major (n × 3), pseudoranges, σ (n) or
/// covariance (n × n, row-major) with its shape, α, k, x0.
#[derive(Clone)]
struct SnapshotArgs {
    sat_pos: Vec<f64>,
    rho: Vec<f64>,
    sigma: Vec<f64>,
    sigma_shape: Vec<usize>,
    alpha: f64,
    k: Option<f64>,
    x0: Option<[f64; 4]>,
    test: &'static str,
    power: f64,
}

#[pymethods]
impl PySnapshotFde {
    /// Pickle as the call that made it (the computation is deterministic): `(snapshot_fde,
    /// (sat_pos, pseudoranges, sigma, alpha, k, x0, test, power))`.
    #[allow(clippy::type_complexity)]
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(
        Bound<'py, PyAny>,
        (
            Bound<'py, PyAny>,
            Bound<'py, PyAny>,
            Bound<'py, PyAny>,
            f64,
            Option<f64>,
            Option<Bound<'py, PyAny>>,
            &'static str,
            f64,
        ),
    )> {
        let a = &self.args;
        let n = a.rho.len();
        let f = py.import("navfdi._core")?.getattr("snapshot_fde")?;
        Ok((
            f,
            (
                to_numpy(py, a.sat_pos.clone(), &[n, 3])?.into_any(),
                to_numpy(py, a.rho.clone(), &[n])?.into_any(),
                to_numpy(py, a.sigma.clone(), &a.sigma_shape)?.into_any(),
                a.alpha,
                a.k,
                a.x0.map(|x| to_numpy(py, x.to_vec(), &[4]))
                    .transpose()?
                    .map(|x| x.into_any()),
                a.test,
                a.power,
            ),
        ))
    }

    /// ECEF position (3,) in m, or None when there is no solution (``status == "no_solution"``).
    #[getter]
    fn position<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.inner
            .position
            .map(|p| to_numpy(py, vec![p.x, p.y, p.z], &[3]).map(|a| a.into_any()))
            .transpose()
    }

    /// Receiver clock bias c·δt in m, or None without a solution.
    #[getter]
    fn clock(&self) -> Option<f64> {
        self.inner.clock
    }

    /// Global-test statistic VᵀD⁻¹V of the final set of satellites (NaN without a solution).
    #[getter]
    fn statistic(&self) -> f64 {
        self.inner.fde.statistic
    }

    /// Its threshold: the 1 − alpha quantile of χ²(dof) (NaN without a solution).
    #[getter]
    fn threshold(&self) -> f64 {
        self.inner.fde.threshold
    }

    /// Degrees of freedom n − 4 of the final set (0 without a solution).
    #[getter]
    fn dof(&self) -> usize {
        self.inner.fde.dof
    }

    /// ``(statistic, threshold, dof)`` of the first global test, on all satellites.
    #[getter]
    fn first_test(&self) -> (f64, f64, usize) {
        self.inner.fde.first
    }

    /// w-test statistic per input satellite (n,) from the final set; NaN for excluded
    /// satellites, satellites without redundancy and without a solution.
    #[getter]
    fn w<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let n = self.inner.fde.w.len();
        Ok(to_numpy(py, self.inner.fde.w.clone(), &[n])?.into_any())
    }

    /// Minimal detectable bias per input satellite (n,) in m at the final test: the bias the
    /// tests find with the allocation's power (``power``) at ``alpha``, ``√(λ0 / q_i)``;
    /// NaN for excluded satellites, satellites without redundancy and without a solution.
    #[getter]
    fn mdb<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let n = self.inner.fde.mdb.len();
        Ok(to_numpy(py, self.inner.fde.mdb.clone(), &[n])?.into_any())
    }

    /// The final set's allocation ``(k0, alpha0, lambda0)``: the w-test's critical value, its
    /// per-satellite false-alarm probability and the non-centrality behind ``mdb`` (the
    /// deciding test's at ``alpha`` and ``power``); NaN without a solution.
    #[getter]
    fn allocation(&self) -> (f64, f64, f64) {
        self.inner
            .fde
            .snooping
            .map_or((f64::NAN, f64::NAN, f64::NAN), |s| {
                (s.k0, s.alpha0, s.lambda0)
            })
    }

    /// Excluded satellites: indices into the inputs, in exclusion order.
    #[getter]
    fn excluded(&self) -> Vec<usize> {
        self.inner.fde.excluded.clone()
    }

    /// |w| of each excluded satellite when it was excluded (same order as ``excluded``).
    #[getter]
    fn excluded_w(&self) -> Vec<f64> {
        self.inner.fde.excluded_w.clone()
    }

    /// ``"passed"``, ``"excluded"``, ``"unidentified"`` (the global test fails but no |w|
    /// exceeds k) or ``"no_solution"``.
    #[getter]
    fn status(&self) -> &'static str {
        self.inner.fde.status.as_str()
    }

    /// Why the exclusion loop stopped, in words.
    #[getter]
    fn reason(&self) -> String {
        self.inner.fde.reason.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "SnapshotFde(status='{}', excluded={:?}, statistic={}, threshold={}, dof={})",
            self.status(),
            self.inner.fde.excluded,
            crate::convert::py_float(self.inner.fde.statistic),
            crate::convert::py_float(self.inner.fde.threshold),
            self.inner.fde.dof
        )
    }
}

/// Snapshot least-squares position and clock from pseudoranges with fault detection and
/// exclusion (global chi-square test + Baarda w-test, iterative exclusion; METHODS §10).
///
/// `sat_pos` (n, 3) ECEF in m; `pseudoranges` (n,) m; `sigma` (n,) standard deviations in m
/// or a full (n, n) covariance in m²; `alpha` false-alarm probability of the global test;
/// `k` w-test critical value (default: the two-sided normal quantile of `alpha`);
/// `x0` start value `[x, y, z]` or `[x, y, z, clock]` in m (default: the Earth's centre);
/// `test` what opens the exclusion loop: ``"global"`` (the χ² test), ``"wtest"`` (data
/// snooping: the largest |w| above k0, α shared over the satellites), ``"both"`` (each at
/// α/2) or ``"auto"`` (the one of the two with the smaller MDB); `power` the β0 of the
/// reported minimal detectable biases.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (sat_pos, pseudoranges, sigma, alpha = 0.05, k = None, x0 = None, test = "global", power = 0.8))]
pub fn snapshot_fde(
    py: Python<'_>,
    sat_pos: &Bound<'_, PyAny>,
    pseudoranges: &Bound<'_, PyAny>,
    sigma: &Bound<'_, PyAny>,
    alpha: f64,
    k: Option<f64>,
    x0: Option<&Bound<'_, PyAny>>,
    test: &str,
    power: f64,
) -> PyResult<PySnapshotFde> {
    let detection = Detection::parse(test).py()?;
    let sp = read("sat_pos", sat_pos)?;
    if sp.shape.len() != 2 || sp.shape[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "sat_pos: expected shape (n, 3) (ECEF x, y, z in m), got {}",
            navfdi_core::validate::shape_str(&sp.shape)
        )));
    }
    let n = sp.shape[0];
    if n == 0 {
        return Err(PyValueError::new_err("sat_pos: no satellites given"));
    }
    let sats: Vec<Vector3<f64>> = sp
        .data
        .chunks(3)
        .map(|c| Vector3::new(c[0], c[1], c[2]))
        .collect();
    let rho = crate::convert::vector("pseudoranges", pseudoranges, Some(n))?;
    let s = read("sigma", sigma)?;
    let (sigma_copy, sigma_shape) = (s.data.clone(), s.shape.clone());
    let cov = match s.shape.len() {
        1 if s.shape[0] == n => ObsCov::Sigma(s.data),
        2 if s.shape == [n, n] => ObsCov::Full(navfdi_core::linalg::from_row_major(n, n, &s.data)),
        _ => {
            return Err(PyValueError::new_err(format!(
                "sigma: expected shape ({n},) (standard deviations, m) or ({n}, {n}) (covariance, m²), got {}",
                navfdi_core::validate::shape_str(&s.shape)
            )))
        }
    };
    let x0 = match x0 {
        None => None,
        Some(o) => {
            let v = read("x0", o)?;
            match v.data.len() {
                3 if v.shape.len() == 1 => Some([v.data[0], v.data[1], v.data[2], 0.0]),
                4 if v.shape.len() == 1 => Some([v.data[0], v.data[1], v.data[2], v.data[3]]),
                _ => {
                    return Err(PyValueError::new_err(format!(
                    "x0: expected shape (3,) or (4,) ([x, y, z] or [x, y, z, clock] in m), got {}",
                    navfdi_core::validate::shape_str(&v.shape)
                )))
                }
            }
        }
    };
    let cfg = FdeConfig::new(alpha, k)
        .and_then(|c| c.with_test(detection, power))
        .py()?;
    let rho = rho.as_slice().to_vec();
    let args = SnapshotArgs {
        sat_pos: sp.data.clone(),
        rho: rho.clone(),
        sigma: sigma_copy,
        sigma_shape,
        alpha,
        k,
        x0,
        test: detection.as_str(),
        power,
    };
    let inner = py
        .detach(move || snapshot::snapshot_fde(&sats, &rho, &cov, &cfg, x0))
        .py()?;
    Ok(PySnapshotFde { inner, args })
}

/// The linear test of METHODS §10 on a given model `l = B x + ε`, `ε ~ N(0, D)`: `B` (n, u),
/// `l` (n,), `D` (n, n) symmetric positive definite (or (n,) standard deviations). Returns a
/// dict: ``x`` (u,) estimate, ``v`` (n,) residuals `B x̂ − l`, ``dv`` (n, n) their covariance
/// `D − B(BᵀD⁻¹B)⁻¹Bᵀ`, ``statistic`` `VᵀD⁻¹V`, ``dof`` n − u and ``w`` (n,) the general w-test
/// `e_iᵀD⁻¹V / sqrt(e_iᵀD⁻¹D_VD⁻¹e_i)` (NaN where an observation has no redundancy).
#[pyfunction]
#[pyo3(name = "ls_test")]
pub fn py_ls_test<'py>(
    py: Python<'py>,
    b: &Bound<'py, PyAny>,
    l: &Bound<'py, PyAny>,
    d: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
    let bm = crate::convert::matrix("B", b)?;
    let (n, u) = bm.shape();
    if n <= u || u == 0 {
        return Err(PyValueError::new_err(format!(
            "B: expected shape (n, u) with n > u >= 1 (more observations than unknowns), got ({n}, {u})"
        )));
    }
    navfdi_core::gnss::snapshot::check_size("ls_test", n).py()?;
    navfdi_core::validate::check_finite_matrix("B", &bm).py()?;
    let lv = crate::convert::vector("l", l, Some(n))?;
    navfdi_core::validate::check_finite_vector("l", &lv).py()?;
    let s = read("D", d)?;
    let cov = match s.shape.len() {
        1 if s.shape[0] == n => ObsCov::Sigma(s.data),
        2 if s.shape == [n, n] => ObsCov::Full(navfdi_core::linalg::from_row_major(n, n, &s.data)),
        _ => {
            return Err(PyValueError::new_err(format!(
                "D: expected shape ({n}, {n}) (covariance) or ({n},) (standard deviations), got {}",
                navfdi_core::validate::shape_str(&s.shape)
            )))
        }
    };
    cov.validate("D", n).py()?;
    let t = snapshot::ls_test_cov(&bm, &lv, &cov).py()?;
    let out = pyo3::types::PyDict::new(py);
    out.set_item("x", crate::convert::vector_to_numpy(py, &t.x)?)?;
    out.set_item("v", crate::convert::vector_to_numpy(py, &t.v)?)?;
    out.set_item("dv", crate::convert::matrix_to_numpy(py, &t.dv)?)?;
    out.set_item("statistic", t.statistic)?;
    out.set_item("dof", n - u)?;
    out.set_item("w", crate::convert::vector_to_numpy(py, &t.w)?)?;
    Ok(out)
}
