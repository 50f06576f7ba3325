//! Monte-Carlo bindings: a prepared scenario that runs chunks of runs in Rust (rayon, GIL
//! released) and returns per-run metrics as arrays.

use crate::convert::to_numpy;
use crate::errors::IntoPyResult;
use navfdi_core::montecarlo::{cells, run_chunk, Cell};
use navfdi_core::sim::prepare::Prepared;
use navfdi_core::spec::ScenarioSpec;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::Arc;

/// A scenario prepared once (truth, Φ_k, Q_k, measurement models) for many runs.
#[pyclass(name = "PreparedScenario", module = "navfdi._core", frozen)]
pub struct PyPreparedScenario {
    prep: Arc<Prepared>,
    cells: Vec<Cell>,
}

#[pymethods]
impl PyPreparedScenario {
    /// Per fault of the scenario: whether it ever reaches a measurement (its sensor measures
    /// inside the window and, for a satellite fault, the satellite is in view then). Seed-free.
    #[getter]
    fn faults_applied(&self) -> Vec<bool> {
        navfdi_core::stream::faults_applied(&self.prep.spec, &self.prep.models)
    }

    #[new]
    fn new(py: Python<'_>, spec_json: &str) -> PyResult<Self> {
        let spec = ScenarioSpec::from_json(spec_json).py()?;
        let prep = crate::interrupt::run(py, move |_| Prepared::new(spec))?;
        let cells = cells(&prep);
        Ok(PyPreparedScenario {
            prep: Arc::new(prep),
            cells,
        })
    }

    /// Number of epochs per run.
    #[getter]
    fn epochs(&self) -> usize {
        self.prep.epochs()
    }

    /// The metric cells: list of ``(subfilter, detector, fault_id or "none", pf)``.
    #[getter]
    fn cells(&self) -> Vec<(String, String, String, f64)> {
        cell_names(&self.prep.spec, &self.cells)
    }

    /// Runs ``start .. start + count`` (noise from ``(seed, run index)``) on ``threads`` threads
    /// (0: all cores), with the GIL released. Returns a dict of arrays: ``run`` (count,),
    /// ``detected``, ``delay``, ``clear_delay``, ``false_alarm_epochs``, ``outside_epochs``,
    /// ``wrong_isolations`` (count, cells), ``att_rms``, ``att_max``, ``pos_rms``, ``pos_max``,
    /// ``lat_rms``, ``lat_max``, ``fused_alt_rms``, ``fused_alt_max`` (count,), and ``records`` ({run: record dict} for the runs listed in ``keep``).
    #[pyo3(signature = (seed, start, count, threads = 0, keep = None))]
    fn run_chunk<'py>(
        &self,
        py: Python<'py>,
        seed: u64,
        start: u64,
        count: u64,
        threads: usize,
        keep: Option<Vec<u64>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        if count == 0 {
            return Err(PyValueError::new_err("count: must be at least 1"));
        }
        let keep = keep.unwrap_or_default();
        let prep = Arc::clone(&self.prep);
        let rows = crate::interrupt::run(py, move |cancel| {
            run_chunk(&prep, seed, start, count, threads, &keep, cancel)
        })?;
        rows_to_py(py, rows, self.cells.len())
    }
}

/// Refuse (MemoryError) a campaign of `runs` runs × `points` sweep points whose per-run table
/// (`row_bytes` per row, one row per metric cell) and `kept` kept series per point would not
/// fit in memory; checked from the scenario alone, before anything is prepared.
#[pyfunction]
pub fn check_campaign_memory(
    spec_json: &str,
    runs: f64,
    points: f64,
    kept: f64,
    row_bytes: f64,
) -> PyResult<()> {
    let spec = ScenarioSpec::from_json(spec_json).py()?;
    navfdi_core::montecarlo::check_campaign_memory(&spec, runs, points, kept, row_bytes).py()
}

/// Per-run metric rows as the dict of arrays ``run_chunk`` returns (``c`` cells per run).
pub fn rows_to_py<'py>(
    py: Python<'py>,
    rows: Vec<navfdi_core::montecarlo::RunMetrics>,
    c: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let n = rows.len();
    let d = PyDict::new(py);
    d.set_item(
        "run",
        to_numpy(py, rows.iter().map(|r| r.run as i64).collect(), &[n])?,
    )?;
    d.set_item(
        "failed",
        rows.iter()
            .map(|r| r.failed.clone().unwrap_or_default())
            .collect::<Vec<String>>(),
    )?;
    let grid = |f: &dyn Fn(&navfdi_core::montecarlo::CellMetrics) -> f64| -> Vec<f64> {
        rows.iter().flat_map(|r| r.cells.iter().map(f)).collect()
    };
    let grid_i = |f: &dyn Fn(&navfdi_core::montecarlo::CellMetrics) -> i64| -> Vec<i64> {
        rows.iter().flat_map(|r| r.cells.iter().map(f)).collect()
    };
    d.set_item(
        "detected",
        to_numpy(
            py,
            rows.iter()
                .flat_map(|r| r.cells.iter().map(|m| m.detected))
                .collect::<Vec<bool>>(),
            &[n, c],
        )?,
    )?;
    d.set_item("delay", to_numpy(py, grid(&|m| m.delay), &[n, c])?)?;
    d.set_item(
        "applied",
        to_numpy(
            py,
            rows.iter()
                .flat_map(|r| r.cells.iter().map(|m| m.applied))
                .collect::<Vec<bool>>(),
            &[n, c],
        )?,
    )?;
    d.set_item(
        "at_onset",
        to_numpy(
            py,
            rows.iter()
                .flat_map(|r| r.cells.iter().map(|m| m.at_onset))
                .collect::<Vec<bool>>(),
            &[n, c],
        )?,
    )?;
    d.set_item(
        "alarm_fraction",
        to_numpy(py, grid(&|m| m.alarm_fraction), &[n, c])?,
    )?;
    d.set_item(
        "clear_delay",
        to_numpy(py, grid(&|m| m.clear_delay), &[n, c])?,
    )?;
    d.set_item(
        "false_alarm_epochs",
        to_numpy(py, grid_i(&|m| m.false_alarm_epochs as i64), &[n, c])?,
    )?;
    d.set_item(
        "outside_epochs",
        to_numpy(py, grid_i(&|m| m.outside_epochs as i64), &[n, c])?,
    )?;
    d.set_item(
        "wrong_isolations",
        to_numpy(py, grid_i(&|m| m.wrong_isolations as i64), &[n, c])?,
    )?;
    for (key, f) in [
        (
            "fde_faulty_epochs",
            (|m| m.sat.faulty_epochs) as fn(&navfdi_core::montecarlo::CellMetrics) -> u32,
        ),
        ("fde_detected_epochs", |m| m.sat.detected_epochs),
        ("fde_exclusion_epochs", |m| m.sat.exclusion_epochs),
        ("fde_exact_epochs", |m| m.sat.exact_epochs),
        ("fde_after_epochs", |m| m.sat.after_epochs),
        ("fde_after_alarm_epochs", |m| m.sat.after_alarm_epochs),
        ("fde_outside_epochs", |m| m.sat.outside_epochs),
        ("fde_false_exclusions", |m| m.sat.false_exclusions),
    ] {
        d.set_item(key, to_numpy(py, grid_i(&|m| f(m) as i64), &[n, c])?)?;
    }
    for (key, f) in [
        (
            "att_rms",
            (|r| r.att_rms) as fn(&navfdi_core::montecarlo::RunMetrics) -> f64,
        ),
        ("att_max", |r| r.att_max),
        ("pos_rms", |r| r.pos_rms),
        ("pos_max", |r| r.pos_max),
        ("lat_rms", |r| r.lat_rms),
        ("lat_max", |r| r.lat_max),
        ("fused_alt_rms", |r| r.fused_alt_rms),
        ("fused_alt_max", |r| r.fused_alt_max),
        ("hor_rms", |r| r.hor_rms),
        ("hor_max", |r| r.hor_max),
        ("fault_hor_max", |r| r.fault_hor_max),
        ("hor_rel_rms", |r| r.hor_rel_rms),
        ("fault_hor_rel_max", |r| r.fault_hor_rel_max),
    ] {
        d.set_item(key, to_numpy(py, rows.iter().map(f).collect(), &[n])?)?;
    }
    // Filter protection levels against the true error (tight filter with [tight.integrity]).
    if n > 0 && rows.iter().all(|r| r.integrity.is_some()) {
        let im: Vec<navfdi_core::montecarlo::IntegrityMetrics> =
            rows.iter().filter_map(|r| r.integrity).collect();
        for (key, f) in [
            (
                "pl_epochs",
                (|m| m.epochs) as fn(&navfdi_core::montecarlo::IntegrityMetrics) -> u32,
            ),
            ("mi_h_epochs", |m| m.mi_h),
            ("mi_v_epochs", |m| m.mi_v),
            ("hmi_h_epochs", |m| m.hmi_h),
            ("hmi_v_epochs", |m| m.hmi_v),
            ("pl_alarm_epochs", |m| m.alarms),
            ("pl_compared_epochs", |m| m.compared),
        ] {
            d.set_item(
                key,
                to_numpy(py, im.iter().map(|m| f(m) as i64).collect(), &[n])?,
            )?;
        }
        for (key, f) in [
            (
                "error_over_hpl_max",
                (|m| m.max_ratio_h) as fn(&navfdi_core::montecarlo::IntegrityMetrics) -> f64,
            ),
            ("error_over_vpl_max", |m| m.max_ratio_v),
            ("hpl_sum", |m| m.sum_hpl),
            ("vpl_sum", |m| m.sum_vpl),
            ("hpl_ratio_sum", |m| m.sum_pl_ratio_h),
            ("vpl_ratio_sum", |m| m.sum_pl_ratio_v),
        ] {
            d.set_item(key, to_numpy(py, im.iter().map(f).collect(), &[n])?)?;
        }
    }
    // The faults each run drew (campaigns on recorded logs): start (s), magnitude (SI), kind,
    // components (comma-separated indices) and satellite ("" for none), (runs, faults).
    let nf = rows.first().map_or(0, |r| r.drawn.len());
    if nf > 0 && rows.iter().all(|r| r.drawn.len() == nf) {
        let f = |g: &dyn Fn(&navfdi_core::spec::FaultSpec) -> f64| -> Vec<f64> {
            rows.iter().flat_map(|r| r.drawn.iter().map(g)).collect()
        };
        d.set_item("fault_start", to_numpy(py, f(&|x| x.start), &[n, nf])?)?;
        d.set_item(
            "fault_magnitude",
            to_numpy(py, f(&|x| x.magnitude), &[n, nf])?,
        )?;
        let kinds: Vec<String> = rows
            .iter()
            .flat_map(|r| {
                r.drawn.iter().map(|x| {
                    match x.kind {
                        navfdi_core::spec::FaultKind::Step => "step",
                        navfdi_core::spec::FaultKind::Ramp => "ramp",
                        navfdi_core::spec::FaultKind::Quadratic => "quadratic",
                    }
                    .to_string()
                })
            })
            .collect();
        let comps: Vec<String> = rows
            .iter()
            .flat_map(|r| {
                r.drawn.iter().map(|x| {
                    x.components
                        .iter()
                        .map(|c| c.to_string())
                        .collect::<Vec<_>>()
                        .join(",")
                })
            })
            .collect();
        let sats: Vec<String> = rows
            .iter()
            .flat_map(|r| {
                r.drawn
                    .iter()
                    .map(|x| x.satellite.clone().unwrap_or_default())
            })
            .collect();
        d.set_item("fault_kind", kinds)?;
        d.set_item("fault_components", comps)?;
        d.set_item("fault_satellite", sats)?;
    }
    let recs = PyDict::new(py);
    for r in rows {
        if let Some(rec) = r.record {
            recs.set_item(r.run, crate::scenario::record_to_py(py, rec)?)?;
        }
    }
    d.set_item("records", recs)?;
    Ok(d)
}

/// The metric cells of `spec` as ``(channel, detector, fault_id or "none", pf)``.
pub fn cell_names(
    spec: &navfdi_core::spec::ScenarioSpec,
    cells: &[Cell],
) -> Vec<(String, String, String, f64)> {
    let channels = spec.channels();
    cells
        .iter()
        .map(|c| {
            let ch = &channels[c.subfilter];
            let d = &ch.detectors[c.detector];
            let f = c
                .fault
                .map_or_else(|| "none".to_string(), |i| spec.faults[i].id.clone());
            (ch.name().to_string(), d.name.clone(), f, d.pf)
        })
        .collect()
}
