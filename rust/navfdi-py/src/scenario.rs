//! Scenario bindings: validation, truth trajectory and federated runs (JSON spec in SI units,
//! produced by `navfdi.scenario`).

use crate::convert::to_numpy;
use crate::errors::IntoPyResult;
use navfdi_core::arch::run_architecture;
use navfdi_core::record::{RunRecord, ERROR_COLUMNS};
use navfdi_core::sim::noise::simulate;
use navfdi_core::sim::prepare::Prepared;
use navfdi_core::sim::trajectory::generate;
use navfdi_core::spec::ScenarioSpec;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// Validate a scenario given as JSON (SI units); raises ValueError naming the field.
#[pyfunction]
pub fn validate_scenario(spec_json: &str) -> PyResult<()> {
    ScenarioSpec::from_json(spec_json).py().map(|_| ())
}

/// Truth trajectory of a scenario: dict of arrays (t, lat, lon, h, v (T,3), euler (T,3),
/// f_b (T,3), w_b (T,3)).
#[pyfunction]
pub fn scenario_trajectory<'py>(py: Python<'py>, spec_json: &str) -> PyResult<Bound<'py, PyDict>> {
    let spec = ScenarioSpec::from_json(spec_json).py()?;
    let traj = spec.trajectory().py()?.clone();
    let tr = py.detach(|| generate(&traj, spec.dt, spec.epochs()));
    let t = tr.len();
    let d = PyDict::new(py);
    d.set_item("t", to_numpy(py, tr.iter().map(|e| e.t).collect(), &[t])?)?;
    d.set_item(
        "lat",
        to_numpy(py, tr.iter().map(|e| e.lat).collect(), &[t])?,
    )?;
    d.set_item(
        "lon",
        to_numpy(py, tr.iter().map(|e| e.lon).collect(), &[t])?,
    )?;
    d.set_item("h", to_numpy(py, tr.iter().map(|e| e.h).collect(), &[t])?)?;
    let v3 = |f: &dyn Fn(&navfdi_core::sim::trajectory::TruthEpoch) -> [f64; 3]| -> Vec<f64> {
        tr.iter().flat_map(f).collect()
    };
    d.set_item("v", to_numpy(py, v3(&|e| [e.v.x, e.v.y, e.v.z]), &[t, 3])?)?;
    d.set_item(
        "euler",
        to_numpy(py, v3(&|e| [e.euler.x, e.euler.y, e.euler.z]), &[t, 3])?,
    )?;
    d.set_item(
        "f_b",
        to_numpy(py, v3(&|e| [e.f_b.x, e.f_b.y, e.f_b.z]), &[t, 3])?,
    )?;
    d.set_item(
        "w_b",
        to_numpy(py, v3(&|e| [e.w_b.x, e.w_b.y, e.w_b.z]), &[t, 3])?,
    )?;
    Ok(d)
}

pub fn record_to_py<'py>(py: Python<'py>, rec: RunRecord) -> PyResult<Bound<'py, PyDict>> {
    let t = rec.t.len();
    // The metrics engine's integrity counts (the same function Monte-Carlo uses).
    let integrity_metrics = navfdi_core::montecarlo::integrity_metrics(&rec);
    let d = PyDict::new(py);
    d.set_item("t", to_numpy(py, rec.t, &[t])?)?;
    d.set_item("faults_applied", rec.faults_applied)?;
    if !rec.reanchored.is_empty() {
        d.set_item("reanchored", rec.reanchored.clone())?;
    }
    if let Some(c) = rec.converged_at {
        d.set_item("converged_at", c)?;
    }
    if let Some(m) = rec.position_errors {
        d.set_item("position_errors", m.to_vec())?;
    }
    if let Some(m) = rec.position_wander {
        d.set_item("position_wander", m.to_vec())?;
    }
    d.set_item("error", to_numpy(py, rec.error, &[t, 9])?)?;
    d.set_item("sigma", to_numpy(py, rec.sigma, &[t, 9])?)?;
    d.set_item("error_columns", ERROR_COLUMNS.to_vec())?;
    d.set_item("sources", to_numpy(py, rec.sources, &[t])?)?;
    let subs = PyList::empty(py);
    for s in rec.subs {
        let sd = PyDict::new(py);
        sd.set_item("sensor", s.sensor)?;
        sd.set_item("statistic", to_numpy(py, s.statistic, &[t])?)?;
        sd.set_item("dof", to_numpy(py, s.dof, &[t])?)?;
        sd.set_item("isolated", to_numpy(py, s.isolated, &[t])?)?;
        sd.set_item("reinstated", to_numpy(py, s.reinstated, &[t])?)?;
        sd.set_item("fused", to_numpy(py, s.fused, &[t])?)?;
        if !s.mdb.is_empty() && t > 0 {
            let m = s.mdb.len() / t;
            sd.set_item("mdb", to_numpy(py, s.mdb, &[t, m])?)?;
        }
        if !s.noise_scale.is_empty() {
            sd.set_item("noise_scale", to_numpy(py, s.noise_scale, &[t])?)?;
        }
        if !s.reason.is_empty() {
            sd.set_item("reason", to_numpy(py, s.reason, &[t])?)?;
            sd.set_item(
                "reason_names",
                navfdi_core::record::EXCLUSION_REASONS.to_vec(),
            )?;
        }
        if !s.whitened.is_empty() && t > 0 {
            let m = s.whitened.len() / t;
            sd.set_item("whitened", to_numpy(py, s.whitened, &[t, m])?)?;
        }
        let dets = PyList::empty(py);
        for dr in s.detectors {
            let dd = PyDict::new(py);
            dd.set_item("name", dr.name)?;
            dd.set_item("statistic", to_numpy(py, dr.statistic, &[t])?)?;
            dd.set_item("threshold", to_numpy(py, dr.threshold, &[t])?)?;
            dd.set_item("alarm", to_numpy(py, dr.alarm, &[t])?)?;
            dets.append(dd)?;
        }
        sd.set_item("detectors", dets)?;
        subs.append(sd)?;
    }
    d.set_item("subfilters", subs)?;
    if !rec.nav.is_empty() {
        let c = navfdi_core::record::NAV_COLUMNS.len();
        d.set_item("nav", to_numpy(py, rec.nav, &[t, c])?)?;
        d.set_item("nav_columns", navfdi_core::record::NAV_COLUMNS.to_vec())?;
    }
    if !rec.fused_alt.is_empty() {
        d.set_item("fused_alt", to_numpy(py, rec.fused_alt, &[t])?)?;
    }
    if let Some(fr) = rec.fusion {
        let n = fr.sensors.len();
        let fd = PyDict::new(py);
        fd.set_item("sensors", fr.sensors)?;
        fd.set_item("error", to_numpy(py, fr.error, &[t, n])?)?;
        fd.set_item("weight", to_numpy(py, fr.weight, &[t, n])?)?;
        d.set_item("fusion", fd)?;
    }
    if !rec.mode.is_empty() {
        d.set_item("mode", to_numpy(py, rec.mode, &[t])?)?;
    }
    if let Some(st) = rec.state {
        let sd = PyDict::new(py);
        sd.set_item("states", st.detector.states().to_vec())?;
        sd.set_item("pf", st.detector.pf())?;
        sd.set_item("statistic", to_numpy(py, st.statistic, &[t])?)?;
        sd.set_item("threshold", to_numpy(py, st.threshold, &[t])?)?;
        sd.set_item("alarm", to_numpy(py, st.alarm, &[t])?)?;
        sd.set_item("ready", to_numpy(py, st.ready, &[t])?)?;
        sd.set_item("ill_conditioned", to_numpy(py, st.ill_conditioned, &[t])?)?;
        d.set_item("state_chi2", sd)?;
    }
    if let Some(ir) = rec.integrity {
        let id = PyDict::new(py);
        id.set_item("hpl", to_numpy(py, ir.hpl, &[t])?)?;
        id.set_item("vpl", to_numpy(py, ir.vpl, &[t])?)?;
        id.set_item("hpl_snapshot", to_numpy(py, ir.hpl_snapshot, &[t])?)?;
        id.set_item("vpl_snapshot", to_numpy(py, ir.vpl_snapshot, &[t])?)?;
        id.set_item("statistic", to_numpy(py, ir.statistic, &[t])?)?;
        id.set_item("alarm", to_numpy(py, ir.alarm, &[t])?)?;
        id.set_item("modes", to_numpy(py, ir.modes, &[t])?)?;
        if let Some(m) = integrity_metrics {
            let md = PyDict::new(py);
            md.set_item("epochs", m.epochs)?;
            md.set_item("mi_h_epochs", m.mi_h)?;
            md.set_item("mi_v_epochs", m.mi_v)?;
            md.set_item("hmi_h_epochs", m.hmi_h)?;
            md.set_item("hmi_v_epochs", m.hmi_v)?;
            md.set_item("alarm_epochs", m.alarms)?;
            md.set_item("error_over_hpl_max", m.max_ratio_h)?;
            md.set_item("error_over_vpl_max", m.max_ratio_v)?;
            md.set_item("compared_epochs", m.compared)?;
            md.set_item("hpl_ratio_sum", m.sum_pl_ratio_h)?;
            md.set_item("vpl_ratio_sum", m.sum_pl_ratio_v)?;
            md.set_item("hpl_sum", m.sum_hpl)?;
            md.set_item("vpl_sum", m.sum_vpl)?;
            id.set_item("metrics", md)?;
        }
        d.set_item("integrity", id)?;
    }
    if let Some(sr) = rec.sats {
        let n = sr.names.len();
        let sd = PyDict::new(py);
        sd.set_item("names", sr.names)?;
        sd.set_item("in_view", to_numpy(py, sr.in_view, &[t, n])?)?;
        sd.set_item("excluded", to_numpy(py, sr.excluded, &[t, n])?)?;
        sd.set_item("w", to_numpy(py, sr.w, &[t, n])?)?;
        sd.set_item("status", to_numpy(py, sr.status, &[t])?)?;
        sd.set_item("status_names", navfdi_core::record::SAT_STATUS.to_vec())?;
        sd.set_item("used", to_numpy(py, sr.used, &[t])?)?;
        let ms = PyList::empty(py);
        for m in sr.metrics {
            let md = PyDict::new(py);
            md.set_item("fault", m.fault)?;
            md.set_item("faulty_epochs", m.faulty_epochs)?;
            md.set_item("detected_epochs", m.detected_epochs)?;
            md.set_item("exclusion_epochs", m.exclusion_epochs)?;
            md.set_item("exact_epochs", m.exact_epochs)?;
            md.set_item("after_epochs", m.after_epochs)?;
            md.set_item("after_alarm_epochs", m.after_alarm_epochs)?;
            md.set_item("outside_epochs", m.outside_epochs)?;
            md.set_item("false_exclusions", m.false_exclusions)?;
            ms.append(md)?;
        }
        sd.set_item("metrics", ms)?;
        d.set_item("satellites", sd)?;
    }
    Ok(d)
}

/// Simulate one run of a scenario (noise from `(seed, stream)`) and filter it once per entry
/// of `isolation` (default `[True]`) (True: isolation active; False: detectors only report). Returns one record
/// dict per entry; all share the same truth and measurements. Runs with the GIL released.
#[pyfunction]
#[pyo3(signature = (spec_json, seed, stream = 0, isolation = None))]
pub fn run_scenario<'py>(
    py: Python<'py>,
    spec_json: &str,
    seed: u64,
    stream: u64,
    isolation: Option<Vec<bool>>,
) -> PyResult<Bound<'py, PyList>> {
    let isolation = isolation.unwrap_or_else(|| vec![true]);
    let spec = ScenarioSpec::from_json(spec_json).py()?;
    let records =
        crate::interrupt::run(py, move |cancel| -> navfdi_core::Result<Vec<RunRecord>> {
            spec.check_memory(isolation.len() as f64)?;
            let prep = Prepared::new(spec)?;
            cancel.check()?;
            let sim = simulate(&prep, seed, stream);
            let src = sim.streams(&prep);
            isolation
                .iter()
                .map(|&iso| run_architecture(&prep.spec, &src, iso, true, cancel))
                .collect()
        })?;
    let out = PyList::empty(py);
    for r in records {
        out.append(record_to_py(py, r)?)?;
    }
    Ok(out)
}

/// Simulate one run of the first scenario (noise from `(seed, stream)`) and filter it with each
/// scenario of `spec_jsons` (variants: only the filter may differ), isolation active. Returns
/// one record per variant, in order (run in parallel); the GIL is released and Ctrl-C stops
/// the run.
#[pyfunction]
#[pyo3(signature = (spec_jsons, seed, stream = 0))]
pub fn run_variants<'py>(
    py: Python<'py>,
    spec_jsons: Vec<String>,
    seed: u64,
    stream: u64,
) -> PyResult<Bound<'py, PyList>> {
    if spec_jsons.is_empty() {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "spec_jsons: at least one scenario is required",
        ));
    }
    let specs = spec_jsons
        .iter()
        .map(|j| ScenarioSpec::from_json(j))
        .collect::<navfdi_core::Result<Vec<_>>>()
        .py()?;
    let records =
        crate::interrupt::run(py, move |cancel| -> navfdi_core::Result<Vec<RunRecord>> {
            let mut specs = specs.into_iter();
            let Some(first) = specs.next() else {
                return Ok(Vec::new());
            };
            first.check_memory(1.0 + specs.len() as f64)?;
            let prep = Prepared::new(first)?;
            cancel.check()?;
            let sim = simulate(&prep, seed, stream);
            let src = sim.streams(&prep);
            let all: Vec<ScenarioSpec> = std::iter::once(prep.spec.clone()).chain(specs).collect();
            navfdi_core::arch::run_variants(&prep.spec, &all, &src, true, cancel, |_, rec| Ok(rec))
        })?;
    let out = PyList::empty(py);
    for r in records {
        out.append(record_to_py(py, r)?)?;
    }
    Ok(out)
}

type Matched<'py> = (
    Bound<'py, numpy::PyArray<i64, numpy::IxDyn>>,
    Bound<'py, numpy::PyArray<i64, numpy::IxDyn>>,
    Bound<'py, numpy::PyArray<i64, numpy::IxDyn>>,
    Bound<'py, numpy::PyArray<i64, numpy::IxDyn>>,
);

/// `tested` checked against the length of `alarm`.
fn tested_mask(tested: Option<Vec<bool>>, n: usize) -> PyResult<Option<Vec<bool>>> {
    match tested {
        Some(m) if m.len() != n => Err(pyo3::exceptions::PyValueError::new_err(format!(
            "tested: expected length {n} to match alarm, got {}",
            m.len()
        ))),
        other => Ok(other),
    }
}

/// Alarm intervals of `alarm` (times `t`, tests `tested`: None = every epoch) and the fault
/// each detects, by the one matching rule (`navfdi_core::metrics`). `windows`: fault windows
/// `(start, end)` in s, sorted by start. Returns `(start_index, end_index, tests,
/// fault_index)` arrays; `-1` for "never ended" / "no fault".
#[pyfunction]
#[pyo3(signature = (t, alarm, windows, tested=None))]
pub fn match_alarms<'py>(
    py: Python<'py>,
    t: &Bound<'py, PyAny>,
    alarm: Vec<bool>,
    windows: Vec<(f64, f64)>,
    tested: Option<Vec<bool>>,
) -> PyResult<Matched<'py>> {
    let t = crate::convert::vector("t", t, Some(alarm.len()))?;
    let tested = tested_mask(tested, alarm.len())?;
    if windows.windows(2).any(|w| w[1].0 < w[0].0) {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "windows: must be sorted by start",
        ));
    }
    let ev = navfdi_core::metrics::events(t.as_slice(), &alarm, tested.as_deref(), &windows);
    let n = ev.len();
    let starts = ev.iter().map(|((s, _), _, _)| *s as i64).collect();
    let ends = ev
        .iter()
        .map(|((_, e), _, _)| e.map_or(-1, |e| e as i64))
        .collect();
    let tests = ev.iter().map(|(_, c, _)| *c as i64).collect();
    let faults = ev
        .iter()
        .map(|(_, _, f)| f.map_or(-1, |f| f as i64))
        .collect();
    Ok((
        to_numpy(py, starts, &[n])?,
        to_numpy(py, ends, &[n])?,
        to_numpy(py, tests, &[n])?,
        to_numpy(py, faults, &[n])?,
    ))
}

/// Whether `alarm` (over times `t`, tests `tested`: None = every epoch) was already raised at
/// the first test of the window `[start, end)` (an alarm from before the fault: not a
/// detection), and the share of the window's tests in alarm (NaN when none lies in it); the
/// rule of `navfdi_core::metrics::window_alarm`.
#[pyfunction]
#[pyo3(signature = (t, alarm, start, end, tested=None))]
pub fn window_alarm(
    t: &Bound<'_, PyAny>,
    alarm: Vec<bool>,
    start: f64,
    end: f64,
    tested: Option<Vec<bool>>,
) -> PyResult<(bool, f64)> {
    let t = crate::convert::vector("t", t, Some(alarm.len()))?;
    let tested = tested_mask(tested, alarm.len())?;
    Ok(navfdi_core::metrics::window_alarm(
        t.as_slice(),
        &alarm,
        tested.as_deref(),
        (start, end),
    ))
}
