//! Recorded-data runs: the IMU and GNSS logs (read and checked by `navfdi.logs`) as arrays,
//! turned into measurement streams by `navfdi_core::logs` and run by the scenario's
//! architecture with the GIL released.

use crate::convert::{matrix, read};
use crate::errors::IntoPyResult;
use crate::scenario::record_to_py;
use nalgebra::{DMatrix, Vector3};
use navfdi_core::arch::run_variants;
use navfdi_core::logs::{GnssLog, LoggedSource};
use navfdi_core::record::RunRecord;
use navfdi_core::spec::ScenarioSpec;
use navfdi_core::stream::{ImuSamples, Nominal, Streams};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyList;
use std::sync::OnceLock;

fn gnss_log(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<GnssLog> {
    let m = columns(name, obj, &[13, 14])?;
    let rows = m.nrows();
    let v3 = |r: usize, c: usize| Vector3::new(m[(r, c)], m[(r, c + 1)], m[(r, c + 2)]);
    let q = if m.ncols() == 14 {
        (0..rows)
            .map(|r| {
                let v = m[(r, 13)];
                if v == v.trunc() && (0.0..=255.0).contains(&v) {
                    Ok(v as u8)
                } else {
                    Err(PyValueError::new_err(format!(
                        "{name}: row {r}, column 13 (solution quality): {v} is not an integer code 0-255"
                    )))
                }
            })
            .collect::<PyResult<Vec<u8>>>()?
    } else {
        Vec::new()
    };
    Ok(GnssLog {
        q,
        t: (0..rows).map(|r| m[(r, 0)]).collect(),
        pos: (0..rows)
            .map(|r| Nominal {
                lat: m[(r, 1)],
                lon: m[(r, 2)],
                h: m[(r, 3)],
            })
            .collect(),
        vel: (0..rows).map(|r| v3(r, 4)).collect(),
        sd_pos: (0..rows).map(|r| v3(r, 7)).collect(),
        sd_vel: (0..rows).map(|r| v3(r, 10)).collect(),
    })
}

/// `obj` as a matrix of one of the column counts `cols` (ValueError naming `name` otherwise).
fn columns(name: &str, obj: &Bound<'_, PyAny>, cols: &[usize]) -> PyResult<DMatrix<f64>> {
    let a = read(name, obj)?;
    if a.shape.len() != 2 || !cols.contains(&a.shape[1]) {
        let want: Vec<String> = cols.iter().map(|c| format!("(n, {c})")).collect();
        return Err(PyValueError::new_err(format!(
            "{name}: expected shape {}, got {:?}",
            want.join(" or "),
            a.shape
        )));
    }
    matrix(name, obj)
}

/// Recorded logs prepared for a scenario:
/// ``LoggedSource(spec_json, imu, gnss=None, reference=None, rinex=None)``.
///
/// ``imu``: (N, 7) float array, columns time (s from the run's time 0), angular rate x, y, z
/// (rad/s) and specific force x, y, z (m/s²) in the IMU's axes. ``gnss`` and ``reference``:
/// (M, 13) or (M, 14) arrays, columns time (s), latitude, longitude (rad), height (m), velocity
/// east, north, up (m/s), σ of position east, north, up (m) and of velocity east, north, up
/// (m/s), and (14th, optional) the solution quality in RTKLIB's codes (1 fixed, 2 float, 3
/// SBAS, 4 DGPS, 5 single, 6 PPP; 0 unknown).
/// The record epochs are ``gnss``'s; the reference is scored where no GNSS measurement was an
/// input. Or, for a tight scenario (``tight.strapdown``), ``rinex`` = (observation path,
/// navigation path) instead of ``gnss``: the record epochs are the observation epochs, time 0
/// the first of them, and ``imu`` and ``reference`` times are GPS seconds (since 1980-01-06,
/// GPST); the reference is scored at every epoch it has. Raises ValueError naming the array
/// and row of bad input, FileFormatError for a malformed RINEX file.
#[pyclass(name = "LoggedSource", module = "navfdi._core", frozen)]
pub struct PyLoggedSource {
    src: LoggedSource,
    spec: ScenarioSpec,
    spec_json: String,
    time0: f64,
    /// The fault-free datum of protection-level scoring, computed at the first chunk (or
    /// decoded with the source) and reused by every later one.
    datum: OnceLock<Option<[f64; 3]>>,
}

impl PyLoggedSource {
    fn datum(&self, cancel: &navfdi_core::cancel::Cancel) -> navfdi_core::Result<Option<[f64; 3]>> {
        if let Some(d) = self.datum.get() {
            return Ok(*d);
        }
        let d = navfdi_core::montecarlo::logged_datum(&self.src, &self.spec, cancel)?;
        // A concurrent first call computed the same value: either is kept.
        let _ = self.datum.set(d);
        Ok(d)
    }
}

#[pymethods]
impl PyLoggedSource {
    #[new]
    #[pyo3(signature = (spec_json, imu, gnss=None, reference=None, rinex=None, score_inputs=false))]
    fn new(
        py: Python<'_>,
        spec_json: &str,
        imu: &Bound<'_, PyAny>,
        gnss: Option<&Bound<'_, PyAny>>,
        reference: Option<&Bound<'_, PyAny>>,
        rinex: Option<(String, String)>,
        score_inputs: bool,
    ) -> PyResult<Self> {
        let spec = ScenarioSpec::from_json(spec_json).py()?;
        let m = columns("imu", imu, &[7])?;
        let n = m.nrows();
        let mut imu = ImuSamples {
            t: (0..n).map(|r| m[(r, 0)]).collect(),
            gyro: (0..n)
                .map(|r| Vector3::new(m[(r, 1)], m[(r, 2)], m[(r, 3)]))
                .collect(),
            accel: (0..n)
                .map(|r| Vector3::new(m[(r, 4)], m[(r, 5)], m[(r, 6)]))
                .collect(),
        };
        let mut reference = reference.map(|r| gnss_log("reference", r)).transpose()?;
        let sp = spec.clone();
        let (src, time0) = match (gnss, rinex) {
            (Some(g), None) => {
                let gnss = gnss_log("gnss", g)?;
                let src = py
                    .detach(move || {
                        LoggedSource::with_scoring(&sp, imu, &gnss, reference.as_ref(), score_inputs)
                    })
                    .py()?;
                (src, 0.0)
            }
            (None, Some((obs_path, nav_path))) => crate::interrupt::run(py, move |_| {
                let obs = navfdi_core::gnss::rinex::read_obs(&obs_path)?;
                let nav = navfdi_core::gnss::rinex::read_nav(&nav_path)?;
                // Times in GPS seconds; time 0 is the first observation epoch.
                let t0 = obs.epochs.first().map_or(0.0, |e| e.time.seconds());
                imu.t.iter_mut().for_each(|t| *t -= t0);
                if let Some(r) = reference.as_mut() {
                    r.t.iter_mut().for_each(|t| *t -= t0);
                }
                let src = LoggedSource::from_rinex(&sp, imu, &obs, &nav, reference.as_ref())?;
                Ok((src, t0))
            })?,
            _ => {
                return Err(PyValueError::new_err(
                    "give either gnss (a GNSS solution log) or rinex (observation and navigation files), not both or neither",
                ))
            }
        };
        Ok(PyLoggedSource {
            src,
            spec,
            spec_json: spec_json.to_owned(),
            time0,
            datum: OnceLock::new(),
        })
    }

    /// The prepared source as bytes (``bytes``; see ``LoggedSource.from_bytes``): the
    /// scenario, time 0, the prepared streams and — computed now if the scenario scores
    /// protection levels and not yet done — the fault-free datum, so that a process that
    /// decodes it runs chunks without reading or preparing the logs again. GIL released;
    /// Ctrl-C stops the datum's run.
    fn to_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyBytes>> {
        let bytes = crate::interrupt::run(py, |cancel| {
            let datum = self.datum(cancel)?;
            navfdi_core::logs::shipped::encode(&self.spec_json, self.time0, Some(datum), &self.src)
        })?;
        Ok(pyo3::types::PyBytes::new(py, &bytes))
    }

    /// A source from ``LoggedSource.to_bytes``'s bytes (``data``: bytes-like). Raises
    /// FileFormatError naming what is wrong: not a prepared source, written by another navfdi
    /// version, truncated or corrupted.
    #[staticmethod]
    fn from_bytes(py: Python<'_>, data: &[u8]) -> PyResult<Self> {
        let owned = data.to_vec();
        let shipped = py
            .detach(move || navfdi_core::logs::shipped::decode(&owned))
            .py()?;
        let spec = ScenarioSpec::from_json(&shipped.spec_json).py()?;
        let datum = OnceLock::new();
        if let Some(d) = shipped.datum {
            let _ = datum.set(d);
        }
        Ok(PyLoggedSource {
            src: shipped.source,
            spec,
            spec_json: shipped.spec_json,
            time0: shipped.time0,
            datum,
        })
    }

    /// Pickle support: the source travels as ``to_bytes()`` (Dask scatters it this way).
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, pyo3::types::PyBytes>,))> {
        let ctor = py.get_type::<PyLoggedSource>().getattr("from_bytes")?;
        Ok((ctor, (self.to_bytes(py)?,)))
    }

    /// GPS seconds (since 1980-01-06, GPST) of time 0 for a source read from RINEX files (its
    /// first observation epoch); 0 for one built from a GNSS solution log (whose times are
    /// already relative).
    #[getter]
    fn time0(&self) -> f64 {
        self.time0
    }

    /// Record epochs at which the reference is scored (it has a matched epoch there).
    #[getter]
    fn scored(&self) -> usize {
        self.src
            .reference
            .enu
            .iter()
            .filter(|e| e[0].is_finite())
            .count()
    }

    /// Record epoch times (s from time 0), shape (T,).
    #[getter]
    fn times<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let t = self.src.models.t.clone();
        let n = t.len();
        Ok(crate::convert::to_numpy(py, t, &[n])?.into_any())
    }

    /// Satellite names of a source read from RINEX files (every satellite in view at some
    /// epoch, above the mask with an ephemeris); empty otherwise.
    #[getter]
    fn satellites(&self) -> Vec<String> {
        self.src
            .models
            .ranges
            .as_ref()
            .map_or_else(Vec::new, |r| r.names.clone())
    }

    /// Number of record epochs.
    #[getter]
    fn epochs(&self) -> usize {
        self.src.models.epochs()
    }

    /// Per fault of the scenario (as given, before any draw): whether it reaches a
    /// measurement (its sensor measures inside the window).
    #[getter]
    fn faults_applied(&self) -> Vec<bool> {
        navfdi_core::stream::faults_applied(&self.spec, &self.src.models)
    }

    /// The metric cells: list of ``(channel, detector, fault_id or "none", pf)``.
    #[getter]
    fn cells(&self) -> Vec<(String, String, String, f64)> {
        crate::montecarlo::cell_names(&self.spec, &navfdi_core::montecarlo::spec_cells(&self.spec))
    }

    /// Monte-Carlo runs ``start .. start + count`` on the recorded data: run ``i`` draws its
    /// faults' ``draw`` ranges from ``(seed, i)``; on ``threads`` threads (0: all cores), GIL
    /// released. Returns the dict of arrays of ``PreparedScenario.run_chunk`` (plus
    /// ``hor_rms``, ``hor_max``, ``fault_hor_max``, and ``hor_rel_rms``, ``fault_hor_rel_max`` with the
    /// run's mean horizontal offset to the reference removed, in m).
    #[pyo3(signature = (seed, start, count, threads = 0, keep = None))]
    fn run_chunk<'py>(
        &self,
        py: Python<'py>,
        seed: u64,
        start: u64,
        count: u64,
        threads: usize,
        keep: Option<Vec<u64>>,
    ) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        if count == 0 {
            return Err(PyValueError::new_err("count: must be at least 1"));
        }
        let keep = keep.unwrap_or_default();
        let (src, spec) = (&self.src, &self.spec);
        let rows = crate::interrupt::run(py, move |cancel| {
            let datum = self.datum(cancel)?;
            navfdi_core::montecarlo::run_logged_chunk(
                src, spec, datum, seed, start, count, threads, &keep, cancel,
            )
        })?;
        let c = navfdi_core::montecarlo::spec_cells(&self.spec).len();
        crate::montecarlo::rows_to_py(py, rows, c)
    }

    /// Run each scenario of ``spec_jsons`` (the prepared one and its variants: only the
    /// filter may differ) on the recorded measurements with the prepared scenario's faults
    /// injected; ``isolation`` False makes every detector report only. Returns one record dict
    /// per scenario (as ``run_scenario``'s, plus ``nav`` (T, 21) and ``nav_columns``), run in
    /// parallel; the GIL is released and Ctrl-C stops the run.
    #[pyo3(signature = (spec_jsons, isolation=true))]
    fn run<'py>(
        &self,
        py: Python<'py>,
        spec_jsons: Vec<String>,
        isolation: bool,
    ) -> PyResult<Bound<'py, PyList>> {
        let specs = spec_jsons
            .iter()
            .map(|j| ScenarioSpec::from_json(j))
            .collect::<navfdi_core::Result<Vec<_>>>()
            .py()?;
        let base = &self.spec;
        let src = &self.src;
        let records =
            crate::interrupt::run(py, move |cancel| -> navfdi_core::Result<Vec<RunRecord>> {
                let meas = src.measurements(base);
                let streams = Streams {
                    models: &src.models,
                    meas: &meas,
                    reference: Some(&src.reference),
                    seed: 0,
                    stream: 0,
                };
                let datum = |s: &ScenarioSpec, rec: RunRecord| {
                    let datum = navfdi_core::montecarlo::logged_datum(src, s, cancel)?;
                    Ok(RunRecord { datum, ..rec })
                };
                run_variants(base, &specs, &streams, isolation, cancel, datum)
            })?;
        let out = PyList::empty(py);
        for r in records {
            out.append(record_to_py(py, r)?)?;
        }
        Ok(out)
    }
}

type ImuArrays<'py> = (
    Bound<'py, numpy::PyArray<f64, numpy::IxDyn>>,
    Bound<'py, numpy::PyArray<f64, numpy::IxDyn>>,
    Bound<'py, numpy::PyArray<f64, numpy::IxDyn>>,
    (usize, u64, usize, u64, bool),
);

/// Read an IMU CSV log (`navfdi_core::logs::imu_csv::read_imu_csv`, GIL released): `time` is
/// one column name (GPS seconds) or `(week, seconds)`; `gyro`, `accel` three column names
/// each; `gyro_scale` to rad/s and `accel_scale` to m/s²; `increments`: per-sample increments;
/// `max_gap` (s); `unit_fields`: the unit fields' names for messages; `time_unit`: seconds per
/// unit of a single time column (default 1); `header`: the first line names the columns (else
/// they are `"1"`, `"2"`, … by position); `delimiter`: one ASCII character, or `"whitespace"`
/// (runs of spaces and tabs); `spread_times`: samples sharing a stamp spread evenly to the next
/// one. Returns `t` (N,) in seconds of that column's count,
/// `gyro` (N, 3) rad/s, `accel` (N, 3) m/s² and `(repeated, line, zeroed, line, iso)`: rows
/// left out as exact repeats of the row before them, and as placeholders (specific force
/// exactly zero), each with the first one's line (0: none); `iso`: the time column held ISO
/// date-times (`t` calendar seconds since 1980-01-06 as written). FileFormatError names
/// the file, line and column of bad input; OSError an unreadable path.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (path, time, gyro, accel, gyro_scale, accel_scale, increments, max_gap, unit_fields, time_unit = 1.0, header = true, delimiter = ",", spread_times = false))]
pub fn read_imu_csv<'py>(
    py: Python<'py>,
    path: String,
    time: Vec<String>,
    gyro: [String; 3],
    accel: [String; 3],
    gyro_scale: f64,
    accel_scale: f64,
    increments: bool,
    max_gap: f64,
    unit_fields: [String; 2],
    time_unit: f64,
    header: bool,
    delimiter: &str,
    spread_times: bool,
) -> PyResult<ImuArrays<'py>> {
    use navfdi_core::logs::imu_csv::Delimiter;
    let delimiter = match delimiter.as_bytes() {
        b"whitespace" => Delimiter::Whitespace,
        [b] if b.is_ascii() && !matches!(b, b'"' | b'\n' | b'\r') => Delimiter::Byte(*b),
        _ => {
            return Err(PyValueError::new_err(format!(
                "source.imu.delimiter = {delimiter:?}: one ASCII character other than a quote or a line end, or \"whitespace\""
            )))
        }
    };
    use navfdi_core::logs::imu_csv::{read_imu_csv as read, ImuCsvSpec, TimeColumns};
    let time = match time.as_slice() {
        [s] => TimeColumns::Seconds(s.clone()),
        [w, s] => TimeColumns::WeekSeconds(w.clone(), s.clone()),
        _ => {
            return Err(PyValueError::new_err(
                "time: one column (GPS seconds) or two (GPS week, seconds of week)",
            ))
        }
    };
    let spec = ImuCsvSpec {
        time,
        gyro,
        accel,
        gyro_scale,
        accel_scale,
        increments,
        max_gap,
        time_unit,
        header,
        delimiter,
        unit_fields,
        spread_times,
    };
    let table = crate::interrupt::run(py, move |_| read(&path, &spec))?;
    let n = table.t.len();
    let flat = |v: Vec<[f64; 3]>| -> Vec<f64> { v.into_iter().flatten().collect() };
    Ok((
        crate::convert::to_numpy(py, table.t, &[n])?,
        crate::convert::to_numpy(py, flat(table.gyro), &[n, 3])?,
        crate::convert::to_numpy(py, flat(table.accel), &[n, 3])?,
        (
            table.repeated,
            table.first_repeated_line,
            table.zeroed,
            table.first_zeroed_line,
            table.iso,
        ),
    ))
}

/// The data rows of an RTKLIB `.pos` file's text (`navfdi_core::logs::pos_text::pos_rows`, GIL
/// released): `n_fields` numbers after the GPST time. Returns `(values, lines)` — `values`
/// (N, 1 + n_fields): GPS seconds, then the numbers; `lines` (N,) their 1-based line numbers
/// — or None where the text is not in the regular form (the caller's reader then decides).
#[pyfunction]
pub fn pos_rows<'py>(
    py: Python<'py>,
    text: &str,
    n_fields: usize,
) -> PyResult<Option<PosRows<'py>>> {
    let Some((values, lines)) = py.detach(|| navfdi_core::logs::pos_text::pos_rows(text, n_fields))
    else {
        return Ok(None);
    };
    let n = lines.len();
    Ok(Some((
        crate::convert::to_numpy(py, values, &[n, 1 + n_fields])?,
        crate::convert::to_numpy(py, lines, &[n])?,
    )))
}

/// The NAV-PVT solutions of a u-blox binary log (`navfdi_core::logs::ubx::read_ubx_pvt`, GIL
/// released): a dict of numpy columns, one row per message — `t` (N,) GPS s, `llh` (N, 4)
/// latitude, longitude (deg), height above the ellipsoid and mean sea level (m), `acc` (N, 3)
/// horizontal, vertical (m) and speed (m/s) accuracy estimates, `vel_ned` (N, 3) m/s, `status`
/// (N, 3) satellites, fix type, fix flags; and `corrupt`, the packets skipped. FileFormatError
/// for a file that is not a UBX log or has no NAV-PVT; OSError for an unreadable path.
#[pyfunction]
pub fn read_ubx<'py>(py: Python<'py>, path: String) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
    let tab = crate::interrupt::run(py, move |_| navfdi_core::logs::ubx::read_ubx_pvt(&path))?;
    let n = tab.t.len();
    let d = pyo3::types::PyDict::new(py);
    d.set_item("t", crate::convert::to_numpy(py, tab.t, &[n])?)?;
    for (name, col, width) in [
        ("llh", tab.llh.concat(), 4),
        ("acc", tab.acc.concat(), 3),
        ("vel_ned", tab.vel_ned.concat(), 3),
    ] {
        d.set_item(name, crate::convert::to_numpy(py, col, &[n, width])?)?;
    }
    d.set_item(
        "status",
        crate::convert::to_numpy(py, tab.status.concat(), &[n, 3])?,
    )?;
    d.set_item("corrupt", tab.corrupt)?;
    Ok(d)
}

type PosRows<'py> = (
    Bound<'py, numpy::PyArray<f64, numpy::IxDyn>>,
    Bound<'py, numpy::PyArray<u64, numpy::IxDyn>>,
);

/// `log` as a (M, 13) table of the column layout [`gnss_log`] reads: time (s), latitude,
/// longitude (rad), height (m), velocity east, north, up (m/s), σ position, σ velocity.
fn gnss_table(log: &GnssLog) -> Vec<f64> {
    let mut out = Vec::with_capacity(log.t.len() * 13);
    for k in 0..log.t.len() {
        let p = &log.pos[k];
        out.extend([log.t[k], p.lat, p.lon, p.h]);
        out.extend(log.vel[k].iter());
        out.extend(log.sd_pos[k].iter());
        out.extend(log.sd_vel[k].iter());
    }
    out
}

/// Simulate recorded-style logs (`navfdi_core::sim::logs::simulate_logs`, GIL released):
/// `trajectory_json` the SI trajectory, `duration` (s), `noise` a dict of the `LogNoise`
/// fields (SI; `mounting` three angles in rad, `lever_arm` the antenna from the IMU in m
/// (forward-right-down), `ground` a bool; absent fields keep their
/// defaults), `seed`, `run`. Returns `imu` (N, 7: time, gyro rad/s, accel m/s², in the IMU's
/// axes), `gnss` and `reference` (M, 13 in the layout of `LoggedSource`), `attitude` (M, 4:
/// body-to-NED quaternion w, x, y, z), `gnss_error` (M, 3: east, north, up, m), `stale` and
/// `burst` (M, bool).
#[pyfunction]
pub fn simulate_logs<'py>(
    py: Python<'py>,
    trajectory_json: &str,
    duration: f64,
    noise: &Bound<'py, pyo3::types::PyDict>,
    seed: u64,
    run: u64,
) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
    use navfdi_core::sim::logs::{simulate_logs as simulate, LogNoise};
    let trajectory: navfdi_core::spec::TrajectorySpec = serde_json::from_str(trajectory_json)
        .map_err(|e| PyValueError::new_err(format!("trajectory: {e}")))?;
    let mut n = LogNoise::default();
    for (k, v) in noise.iter() {
        let key: String = k.extract()?;
        let f = |v: &Bound<'py, PyAny>| -> PyResult<f64> { v.extract::<f64>() };
        match key.as_str() {
            "imu_rate" => n.imu_rate = f(&v)?,
            "gyro_noise" => n.gyro_noise = f(&v)?,
            "accel_noise" => n.accel_noise = f(&v)?,
            "gyro_bias" => n.gyro_bias = f(&v)?,
            "accel_bias" => n.accel_bias = f(&v)?,
            "gyro_scale" => n.gyro_scale = f(&v)?,
            "accel_scale" => n.accel_scale = f(&v)?,
            "gnss_dt" => n.gnss_dt = f(&v)?,
            "gnss_pos" => n.gnss_pos = f(&v)?,
            "gnss_vel" => n.gnss_vel = f(&v)?,
            "gnss_tau" => n.gnss_tau = f(&v)?,
            "gnss_white" => n.gnss_white = f(&v)?,
            "burst_rate" => n.burst_rate = f(&v)?,
            "burst_size" => n.burst_size = f(&v)?,
            "burst_duration" => n.burst_duration = f(&v)?,
            "stale_rate" => n.stale_rate = f(&v)?,
            "stale_duration" => n.stale_duration = f(&v)?,
            "reported_pos" => n.reported_pos = f(&v)?,
            "reported_vel" => n.reported_vel = f(&v)?,
            "time_lag" => n.time_lag = f(&v)?,
            "ground" => n.ground = v.extract::<bool>()?,
            "bias_tau" => n.bias_tau = f(&v)?,
            "mounting" => n.mounting = v.extract::<[f64; 3]>()?,
            "lever_arm" => n.lever_arm = v.extract::<[f64; 3]>()?,
            other => {
                return Err(PyValueError::new_err(format!(
                    "noise: unknown field {other:?}"
                )))
            }
        }
    }
    if !(duration > 0.0 && duration <= 86_400.0) {
        return Err(PyValueError::new_err(format!(
            "duration = {duration}: must be in (0, 86400] s"
        )));
    }
    let sim = py
        .detach(move || simulate(&trajectory, duration, &n, seed, run))
        .py()?;
    let d = pyo3::types::PyDict::new(py);
    let ni = sim.imu.t.len();
    let mut imu = Vec::with_capacity(ni * 7);
    for i in 0..ni {
        imu.push(sim.imu.t[i]);
        imu.extend(sim.imu.gyro[i].iter());
        imu.extend(sim.imu.accel[i].iter());
    }
    let m = sim.gnss.t.len();
    d.set_item("imu", crate::convert::to_numpy(py, imu, &[ni, 7])?)?;
    d.set_item(
        "gnss",
        crate::convert::to_numpy(py, gnss_table(&sim.gnss), &[m, 13])?,
    )?;
    d.set_item(
        "reference",
        crate::convert::to_numpy(py, gnss_table(&sim.reference), &[m, 13])?,
    )?;
    let att: Vec<f64> = sim
        .attitude
        .iter()
        .flat_map(|q| [q.w, q.i, q.j, q.k])
        .collect();
    d.set_item("attitude", crate::convert::to_numpy(py, att, &[m, 4])?)?;
    let err: Vec<f64> = sim
        .gnss_errors
        .iter()
        .flat_map(|e| e.error.iter().copied().collect::<Vec<_>>())
        .collect();
    d.set_item("gnss_error", crate::convert::to_numpy(py, err, &[m, 3])?)?;
    d.set_item(
        "stale",
        crate::convert::to_numpy(
            py,
            sim.gnss_errors.iter().map(|e| e.stale).collect::<Vec<_>>(),
            &[m],
        )?,
    )?;
    d.set_item(
        "burst",
        crate::convert::to_numpy(
            py,
            sim.gnss_errors.iter().map(|e| e.burst).collect::<Vec<_>>(),
            &[m],
        )?,
    )?;
    Ok(d)
}

/// The IMU samples at a channel's full scale (clipped; ``navfdi_core::ins::clip``):
/// ``imu_clipped(gyro, accel)`` with ``gyro`` (N, 3) rad/s and ``accel`` (N, 3) m/s² in the
/// IMU's axes. Returns ``(mask, channels)``: a bool list (N,) and per clipped channel
/// ``(sensor, axis, value, samples)`` — ``"accel"`` or ``"gyro"``, 0–2 for x, y, z, the
/// full-scale reading (m/s² or rad/s) and the samples on it. ValueError for other shapes.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn imu_clipped(
    py: Python<'_>,
    gyro: &Bound<'_, PyAny>,
    accel: &Bound<'_, PyAny>,
) -> PyResult<(Vec<bool>, Vec<(&'static str, usize, f64, usize)>)> {
    let g = columns("gyro", gyro, &[3])?;
    let a = columns("accel", accel, &[3])?;
    if g.nrows() != a.nrows() {
        return Err(PyValueError::new_err(format!(
            "gyro and accel: {} and {} samples; one row each per sample",
            g.nrows(),
            a.nrows()
        )));
    }
    let v3 = |m: &DMatrix<f64>| -> Vec<Vector3<f64>> {
        (0..m.nrows())
            .map(|r| Vector3::new(m[(r, 0)], m[(r, 1)], m[(r, 2)]))
            .collect()
    };
    let (gv, av) = (v3(&g), v3(&a));
    let (mask, ch) = py.detach(|| navfdi_core::ins::clip::clipped_samples(&gv, &av));
    Ok((
        mask,
        ch.into_iter()
            .map(|c| {
                (
                    if c.sensor == 0 { "accel" } else { "gyro" },
                    c.axis,
                    c.value,
                    c.samples,
                )
            })
            .collect(),
    ))
}
