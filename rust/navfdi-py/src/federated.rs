//! `FederatedFilter`: the per-epoch step API of the federated filter (online use).

use crate::convert::{matrix, matrix_to_numpy, vector, vector_to_numpy};
use crate::detect::PyDecision;
use crate::errors::IntoPyResult;
use navfdi_core::arch::common::make_detector;
use navfdi_core::fusion::{FederatedFilter, StepReport, SubFilterConfig};
use navfdi_core::spec::{DetectorKind, FusionMode, IsolatedMode};
use numpy::{IxDyn, PyArray};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

fn get<'py>(d: &Bound<'py, PyDict>, key: &str, path: &str) -> PyResult<Bound<'py, PyAny>> {
    d.get_item(key)?
        .ok_or_else(|| PyValueError::new_err(format!("{path}.{key}: missing")))
}

/// Refuse keys that are not in `allowed` (a typo such as "isolaton" would otherwise silently
/// disable what it meant to set).
fn check_keys(d: &Bound<'_, PyDict>, allowed: &[&str], path: &str) -> PyResult<()> {
    for k in d.keys() {
        let key: String = k.str()?.extract()?;
        if !k.is_instance_of::<pyo3::types::PyString>() || !allowed.contains(&key.as_str()) {
            return Err(PyValueError::new_err(format!(
                "{path}: unknown key {key:?} (allowed: {})",
                allowed.join(", ")
            )));
        }
    }
    Ok(())
}

fn type_name(v: &Bound<'_, PyAny>) -> String {
    v.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into())
}

fn as_str(v: &Bound<'_, PyAny>, path: &str) -> PyResult<String> {
    if !v.is_instance_of::<pyo3::types::PyString>() {
        return Err(PyValueError::new_err(format!(
            "{path}: expected a string, got {} {}",
            type_name(v),
            v.repr()?
        )));
    }
    v.extract()
}

fn as_f64(v: &Bound<'_, PyAny>, path: &str) -> PyResult<f64> {
    let is_bool = v.is_instance_of::<pyo3::types::PyBool>();
    let is_num = v.is_instance_of::<pyo3::types::PyFloat>()
        || v.is_instance_of::<pyo3::types::PyInt>()
        || v.hasattr("__float__")? && !v.is_instance_of::<pyo3::types::PyString>();
    if is_bool || !is_num {
        return Err(PyValueError::new_err(format!(
            "{path}: expected a number, got {} {}",
            type_name(v),
            v.repr()?
        )));
    }
    v.extract()
}

fn as_u64(v: &Bound<'_, PyAny>, path: &str) -> PyResult<u64> {
    if v.is_instance_of::<pyo3::types::PyBool>() || !v.is_instance_of::<pyo3::types::PyInt>() {
        return Err(PyValueError::new_err(format!(
            "{path}: expected a positive integer, got {} {}",
            type_name(v),
            v.repr()?
        )));
    }
    v.extract().map_err(|_| {
        PyValueError::new_err(format!("{path}: expected a positive integer, got {}", v))
    })
}

const SUB_KEYS: [&str; 6] = ["name", "H", "R", "share", "detectors", "isolation"];
const DETECTOR_KEYS: [&str; 6] = ["name", "kind", "pf", "pm", "variance", "min_samples"];

fn parse_sub(i: usize, obj: &Bound<'_, PyAny>) -> PyResult<SubFilterConfig> {
    let path = format!("subfilters[{i}]");
    let d = obj
        .cast::<PyDict>()
        .map_err(|_| PyValueError::new_err(format!("{path}: expected a dict")))?;
    check_keys(d, &SUB_KEYS, &path)?;
    let name = as_str(&get(d, "name", &path)?, &format!("{path}.name"))?;
    if name.is_empty() {
        return Err(PyValueError::new_err(format!(
            "{path}.name: must not be empty"
        )));
    }
    let h = matrix(&format!("{path}.H"), &get(d, "H", &path)?)?;
    let r = matrix(&format!("{path}.R"), &get(d, "R", &path)?)?;
    let share = as_f64(&get(d, "share", &path)?, &format!("{path}.share"))?;
    let mut detectors: Vec<(String, navfdi_core::detect::Detector)> = Vec::new();
    if let Some(list) = d.get_item("detectors")? {
        let list = list
            .cast::<PyList>()
            .map_err(|_| PyValueError::new_err(format!("{path}.detectors: expected a list")))?;
        for (j, item) in list.iter().enumerate() {
            let dp = format!("{path}.detectors[{j}]");
            let dd = item
                .cast::<PyDict>()
                .map_err(|_| PyValueError::new_err(format!("{dp}: expected a dict")))?;
            check_keys(dd, &DETECTOR_KEYS, &dp)?;
            let kind = as_str(&get(dd, "kind", &dp)?, &format!("{dp}.kind"))?;
            let kind = match kind.as_str() {
                "chi2" => DetectorKind::Chi2,
                "sprt" => DetectorKind::Sprt,
                "joint" => DetectorKind::Joint,
                other => {
                    return Err(PyValueError::new_err(format!(
                        "{dp}.kind = {other:?}: use chi2, sprt or joint"
                    )))
                }
            };
            let dname: String = match dd.get_item("name")? {
                Some(v) => as_str(&v, &format!("{dp}.name"))?,
                None => format!("{kind:?}").to_lowercase(),
            };
            if dname.is_empty() {
                return Err(PyValueError::new_err(format!(
                    "{dp}.name: must not be empty"
                )));
            }
            if detectors.iter().any(|(n, _)| *n == dname) {
                return Err(PyValueError::new_err(format!(
                    "{dp}.name = {dname:?}: used by an earlier detector of this sub-filter (decisions are keyed by name)"
                )));
            }
            let pf = as_f64(&get(dd, "pf", &dp)?, &format!("{dp}.pf"))?;
            let pm = dd
                .get_item("pm")?
                .map(|v| as_f64(&v, &format!("{dp}.pm")))
                .transpose()?;
            if kind != DetectorKind::Chi2 && pm.is_none() {
                return Err(PyValueError::new_err(format!(
                    "{dp}.pm: required for sprt and joint detectors"
                )));
            }
            let variance = dd
                .get_item("variance")?
                .map(|v| as_str(&v, &format!("{dp}.variance")))
                .transpose()?;
            if let Some(v) = &variance {
                if v != "known" && v != "sample" {
                    return Err(PyValueError::new_err(format!(
                        "{dp}.variance = {v:?}: must be \"known\" or \"sample\""
                    )));
                }
            }
            let min_samples = dd
                .get_item("min_samples")?
                .map(|v| as_u64(&v, &format!("{dp}.min_samples")))
                .transpose()?;
            let det = make_detector(kind, pf, pm, variance.as_deref(), min_samples)
                .map_err(|e| PyValueError::new_err(format!("{dp}: {e}")))?;
            detectors.push((dname, det));
        }
    }
    let isolation = match d.get_item("isolation")? {
        None => None,
        Some(v) if v.is_none() => None,
        Some(v) => {
            let n = as_str(&v, &format!("{path}.isolation"))?;
            Some(
                detectors
                    .iter()
                    .position(|(dn, _)| *dn == n)
                    .ok_or_else(|| {
                        PyValueError::new_err(format!(
                            "{path}.isolation = {n:?}: not one of this sub-filter's detectors"
                        ))
                    })?,
            )
        }
    };
    Ok(SubFilterConfig {
        name,
        h,
        r,
        share,
        detectors,
        isolation,
    })
}

/// One epoch of the federated filter.
#[pyclass(name = "FederatedStep", module = "navfdi._core", frozen)]
pub struct PyFederatedStep {
    report: StepReport,
    names: Vec<String>,
    det_names: Vec<Vec<String>>,
    x: nalgebra::DVector<f64>,
    p: nalgebra::DMatrix<f64>,
}

#[pymethods]
impl PyFederatedStep {
    /// Global estimate after fusion, shape (n,).
    #[getter]
    fn x<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray<f64, IxDyn>>> {
        vector_to_numpy(py, &self.x)
    }
    /// Global covariance, shape (n, n).
    #[getter(P)]
    fn p<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray<f64, IxDyn>>> {
        matrix_to_numpy(py, &self.p)
    }
    /// Number of sources fused (0: the global solution was propagated).
    #[getter]
    fn sources(&self) -> usize {
        self.report.sources
    }
    /// Isolation flag per sub-filter.
    #[getter]
    fn isolated(&self) -> Vec<bool> {
        self.report.subs.iter().map(|s| s.isolated).collect()
    }
    /// Sub-filters reinstated (reset from the global solution) this epoch.
    #[getter]
    fn reinstated(&self) -> Vec<bool> {
        self.report.subs.iter().map(|s| s.reinstated).collect()
    }
    /// Sub-filters that fed this epoch's fusion.
    #[getter]
    fn fused(&self) -> Vec<bool> {
        self.report.subs.iter().map(|s| s.fused).collect()
    }
    /// Innovation statistic λ per sub-filter (NaN without measurement).
    #[getter]
    fn statistic(&self) -> Vec<f64> {
        self.report.subs.iter().map(|s| s.statistic).collect()
    }
    /// Decisions: ``{sub-filter name: {detector name: Decision}}``.
    #[getter]
    fn decisions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        for (i, s) in self.report.subs.iter().enumerate() {
            let d = PyDict::new(py);
            for (j, dec) in s.decisions.iter().enumerate() {
                d.set_item(
                    &self.det_names[i][j],
                    Py::new(py, PyDecision::from_decision(dec.clone()))?,
                )?;
            }
            out.set_item(&self.names[i], d)?;
        }
        Ok(out)
    }
}

/// Federated filter with per-sub-filter detectors, isolation and reinstatement.
#[pyclass(name = "FederatedFilter", module = "navfdi._core")]
pub struct PyFederatedFilter {
    inner: FederatedFilter,
}

impl PyFederatedFilter {
    /// Wrap a core object (used when unpickling).
    pub fn from_inner(inner: FederatedFilter) -> Self {
        PyFederatedFilter { inner }
    }
}

#[pymethods]
impl PyFederatedFilter {
    #[new]
    #[pyo3(signature = (x0, P0, subfilters, mode = "reset", master_share = 0.0, isolation = true, isolated = "track"))]
    #[allow(non_snake_case, clippy::too_many_arguments)]
    fn new(
        x0: &Bound<'_, PyAny>,
        P0: &Bound<'_, PyAny>,
        subfilters: &Bound<'_, PyAny>,
        mode: &str,
        master_share: f64,
        isolation: bool,
        isolated: &str,
    ) -> PyResult<Self> {
        let x0 = vector("x0", x0, None)?;
        let p0 = matrix("P0", P0)?;
        let mode = match mode {
            "reset" => FusionMode::Reset,
            "no_reset" => FusionMode::NoReset,
            other => {
                return Err(PyValueError::new_err(format!(
                    "mode = {other:?}: use \"reset\" or \"no_reset\""
                )))
            }
        };
        let list = subfilters
            .cast::<PyList>()
            .map_err(|_| PyValueError::new_err("subfilters: expected a list of dicts"))?;
        let subs = list
            .iter()
            .enumerate()
            .map(|(i, o)| parse_sub(i, &o))
            .collect::<PyResult<Vec<_>>>()?;
        for (i, s) in subs.iter().enumerate() {
            if subs[..i].iter().any(|o| o.name == s.name) {
                return Err(PyValueError::new_err(format!(
                    "subfilters[{i}].name = {:?}: used by an earlier sub-filter (decisions are keyed by name)",
                    s.name
                )));
            }
        }
        let isolated = match isolated {
            "track" => IsolatedMode::Track,
            "predict" => IsolatedMode::Predict,
            "update" => IsolatedMode::Update,
            other => {
                return Err(PyValueError::new_err(format!(
                    "isolated = {other:?}: use \"track\", \"predict\" or \"update\""
                )))
            }
        };
        let mut inner = FederatedFilter::new(x0, p0, subs, mode, master_share, isolation).py()?;
        inner.set_isolated_mode(isolated);
        Ok(PyFederatedFilter { inner })
    }

    /// One epoch: predict with Phi, Q; one measurement per sub-filter (NaN = missing).
    #[pyo3(signature = (Phi, Q, measurements))]
    #[allow(non_snake_case)]
    fn step(
        &mut self,
        Phi: &Bound<'_, PyAny>,
        Q: &Bound<'_, PyAny>,
        measurements: &Bound<'_, PyAny>,
    ) -> PyResult<PyFederatedStep> {
        let phi = matrix("Phi", Phi)?;
        let q = matrix("Q", Q)?;
        let list = measurements.cast::<PyList>().map_err(|_| {
            PyValueError::new_err("measurements: expected a list with one array per sub-filter")
        })?;
        let names = self.inner.names();
        let zs = list
            .iter()
            .enumerate()
            .map(|(i, z)| {
                vector(
                    &format!("measurements[{}]", names.get(i).map_or("?", |s| s.as_str())),
                    &z,
                    None,
                )
            })
            .collect::<PyResult<Vec<_>>>()?;
        let report = self.inner.step(&phi, &q, &zs).py()?;
        let det_names = (0..names.len())
            .map(|i| self.inner.detector_names(i))
            .collect();
        Ok(PyFederatedStep {
            report,
            names,
            det_names,
            x: self.inner.x().clone(),
            p: self.inner.p().clone(),
        })
    }

    /// Replace the measurement model (H, R) of the sub-filter named `name`.
    #[pyo3(signature = (name, H, R))]
    #[allow(non_snake_case)]
    fn set_model(
        &mut self,
        name: &str,
        H: &Bound<'_, PyAny>,
        R: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let names = self.inner.names();
        let i = names.iter().position(|n| n == name).ok_or_else(|| {
            PyValueError::new_err(format!(
                "name = {name:?}: no such sub-filter (known: {})",
                names.join(", ")
            ))
        })?;
        let h = matrix("H", H)?;
        let r = matrix("R", R)?;
        self.inner.set_model(i, h, r).py()
    }
    /// Global estimate, shape (n,).
    #[getter]
    fn x<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray<f64, IxDyn>>> {
        vector_to_numpy(py, self.inner.x())
    }
    /// Global covariance, shape (n, n).
    #[getter(P)]
    fn p<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray<f64, IxDyn>>> {
        matrix_to_numpy(py, self.inner.p())
    }
    /// Sub-filter names.
    #[getter]
    fn names(&self) -> Vec<String> {
        self.inner.names()
    }
    /// Pickle support: ``(navfdi._core._restore, ("FederatedFilter", state))``.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String, String))> {
        crate::pickling::reduce(
            py,
            "FederatedFilter",
            crate::pickling::state("FederatedFilter", &self.inner)?,
        )
    }
    /// Current isolation flags.
    #[getter]
    fn isolated(&self) -> Vec<bool> {
        self.inner.isolated()
    }
}
