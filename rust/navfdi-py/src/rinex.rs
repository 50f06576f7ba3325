//! RINEX reading and single-point positioning with FDE on real data: conversion only.

use crate::convert::to_numpy;
use crate::errors::IntoPyResult;
use navfdi_core::gnss::broadcast::{Sat, Sys};
use navfdi_core::gnss::rinex::{self, NavData, ObsData};
use navfdi_core::gnss::snapshot::{Detection, FdeConfig};
use navfdi_core::gnss::spp::{
    self, FaultShape, InjectedFault, SppConfig, SppRun, SppState, Weighting, CN0_SLOPE_MAX,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::BTreeMap;

fn sat_names(sats: impl Iterator<Item = Sat>) -> (Vec<u32>, Vec<String>) {
    let mut table: BTreeMap<Sat, u32> = BTreeMap::new();
    let ids: Vec<Sat> = sats.collect();
    for s in &ids {
        let n = table.len() as u32;
        table.entry(*s).or_insert(n);
    }
    let mut names = vec![String::new(); table.len()];
    for (s, i) in &table {
        names[*i as usize] = s.name();
    }
    (ids.iter().map(|s| table[s]).collect(), names)
}

/// Read a RINEX 3 or 4 observation file (plain, .gz or Hatanaka .crx) into columns: ``epoch`` (int, index of the
/// epoch), ``time`` (GPS seconds since 1980-01-06, GPST), ``sat`` (int code into
/// ``satellites``), ``code`` (int code into ``observables``), ``value`` (float64); plus
/// ``satellites``, ``observables``, ``flags`` (per epoch), ``epoch_times``, ``dropped``
/// (observation types dropped, e.g. ``G:X1``), ``version``, ``receiver``,
/// ``approx_position`` (3 floats or None).
#[pyfunction]
pub fn read_rinex_obs<'py>(py: Python<'py>, path: String) -> PyResult<Bound<'py, PyDict>> {
    let data = crate::interrupt::run(py, move |_| rinex::read_obs(&path))?;
    obs_dict(py, &data)
}

fn obs_dict<'py>(py: Python<'py>, data: &ObsData) -> PyResult<Bound<'py, PyDict>> {
    let n: usize = data.epochs.iter().map(|e| e.obs.len()).sum();
    let mut epoch = Vec::with_capacity(n);
    let mut time = Vec::with_capacity(n);
    let mut code = Vec::with_capacity(n);
    let mut value = Vec::with_capacity(n);
    for (i, e) in data.epochs.iter().enumerate() {
        let t = e.time.seconds();
        for o in &e.obs {
            epoch.push(i as u32);
            time.push(t);
            code.push(o.code as u32);
            value.push(o.value);
        }
    }
    let (sat, satellites) = sat_names(data.epochs.iter().flat_map(|e| e.obs.iter().map(|o| o.sat)));
    let d = PyDict::new(py);
    d.set_item("epoch", to_numpy(py, epoch, &[n])?)?;
    d.set_item("time", to_numpy(py, time, &[n])?)?;
    d.set_item("sat", to_numpy(py, sat, &[n])?)?;
    d.set_item("code", to_numpy(py, code, &[n])?)?;
    d.set_item("value", to_numpy(py, value, &[n])?)?;
    d.set_item("satellites", satellites)?;
    d.set_item("observables", data.codes.clone())?;
    let ne = data.epochs.len();
    d.set_item(
        "epoch_times",
        to_numpy(
            py,
            data.epochs.iter().map(|e| e.time.seconds()).collect(),
            &[ne],
        )?,
    )?;
    d.set_item(
        "flags",
        to_numpy(
            py,
            data.epochs.iter().map(|e| e.flag as u32).collect(),
            &[ne],
        )?,
    )?;
    d.set_item("dropped", data.dropped_codes.clone())?;
    d.set_item("version", data.version.clone())?;
    d.set_item("receiver", data.receiver.clone())?;
    d.set_item(
        "approx_position",
        data.approx_position.map(|p| vec![p.x, p.y, p.z]),
    )?;
    Ok(d)
}

/// Read a RINEX 3 or 4 navigation file (plain or .gz): one row per GPS/Galileo/BeiDou/QZSS
/// ephemeris as columns (``satellite`` str; ``toc``, ``toe`` GPS seconds; ``af0`` s, ``af1``
/// s/s, ``af2`` s/s²; ``sqrt_a`` √m; ``e``; ``i0``, ``omega0``, ``omega``, ``m0`` rad;
/// ``delta_n``, ``idot``, ``omega_dot`` rad/s; ``tgd`` s; ``health`` int; ``unhealthy``
/// bool; ``accuracy`` m; ``fnav`` bool; ``iod``), plus ``klobuchar`` (8 floats or None),
/// ``records`` (records per system letter, all systems) and ``version``.
#[pyfunction]
pub fn read_rinex_nav<'py>(py: Python<'py>, path: String) -> PyResult<Bound<'py, PyDict>> {
    let nav = crate::interrupt::run(py, move |_| rinex::read_nav(&path))?;
    let ephs: Vec<_> = nav.ephemerides.values().flatten().collect();
    let n = ephs.len();
    let d = PyDict::new(py);
    d.set_item(
        "satellite",
        ephs.iter().map(|e| e.sat.name()).collect::<Vec<_>>(),
    )?;
    let col = |f: &dyn Fn(&navfdi_core::gnss::broadcast::Ephemeris) -> f64| -> Vec<f64> {
        ephs.iter().map(|e| f(e)).collect()
    };
    let cols: [(&str, Vec<f64>); 18] = [
        ("toc", col(&|e| e.toc.seconds())),
        ("toe", col(&|e| e.toe.seconds())),
        ("af0", col(&|e| e.af[0])),
        ("af1", col(&|e| e.af[1])),
        ("af2", col(&|e| e.af[2])),
        ("sqrt_a", col(&|e| e.sqrt_a)),
        ("e", col(&|e| e.e)),
        ("i0", col(&|e| e.i0)),
        ("omega0", col(&|e| e.omega0)),
        ("omega", col(&|e| e.omega)),
        ("m0", col(&|e| e.m0)),
        ("delta_n", col(&|e| e.delta_n)),
        ("idot", col(&|e| e.idot)),
        ("omega_dot", col(&|e| e.omega_dot)),
        ("tgd", col(&|e| e.tgd)),
        ("health", col(&|e| e.health as f64)),
        ("accuracy", col(&|e| e.accuracy)),
        ("iod", col(&|e| e.iod)),
    ];
    for (name, v) in cols {
        d.set_item(name, to_numpy(py, v, &[n])?)?;
    }
    d.set_item(
        "unhealthy",
        ephs.iter().map(|e| e.unhealthy).collect::<Vec<_>>(),
    )?;
    d.set_item("fnav", ephs.iter().map(|e| e.fnav).collect::<Vec<_>>())?;
    d.set_item("klobuchar", nav.klobuchar.map(|k| k.to_vec()))?;
    d.set_item(
        "records",
        nav.records
            .iter()
            .map(|(k, v)| (k.to_string(), *v))
            .collect::<BTreeMap<_, _>>(),
    )?;
    d.set_item("version", nav.version.clone())?;
    Ok(d)
}

/// A single-point solution with FDE over a RINEX observation file, solved in chunks of
/// epochs (so a caller can show progress). Internal: use ``navfdi.gnss_solve``.
#[pyclass(name = "GnssRun", module = "navfdi._core")]
pub struct PyGnssRun {
    obs: ObsData,
    nav: NavData,
    cfg: SppConfig,
    faults: Vec<InjectedFault>,
    state: SppState,
    out: SppRun,
    next: usize,
    /// C/N0 (dB-Hz) at which the C/N0 model gives the elevation model's σ (for `restart`).
    cn0_reference: f64,
    /// Solve every `every`-th epoch only (1: all; set by `restart`).
    every: usize,
}

fn parse_sys(s: &str) -> PyResult<Sys> {
    let mut ch = s.trim().chars();
    match (ch.next().and_then(Sys::from_letter), ch.next()) {
        (Some(sys), None) if Sys::POSITIONING.contains(&sys) => Ok(sys),
        _ => Err(PyValueError::new_err(format!(
            "systems: '{s}' is not a system that can be positioned; use G (GPS), E (Galileo), C (BeiDou) or J (QZSS)"
        ))),
    }
}

/// The variance model named `weighting` (``"elevation"``, ``"rtklib"``, ``"cn0"``; the last with
/// its reference C/N0 in dB-Hz and slope in decades per 10 dB-Hz).
fn parse_weighting(weighting: &str, cn0_reference: f64, cn0_slope: f64) -> PyResult<Weighting> {
    Ok(match weighting {
        "elevation" => Weighting::Elevation,
        "rtklib" => Weighting::Rtklib,
        "cn0" if !(cn0_reference > 10.0 && cn0_reference < 70.0) => {
            return Err(PyValueError::new_err(format!(
                "cn0_reference: {cn0_reference} dB-Hz; expected a carrier-to-noise density in (10, 70) dB-Hz"
            )))
        }
        "cn0" if !(0.0..=CN0_SLOPE_MAX).contains(&cn0_slope) => {
            return Err(PyValueError::new_err(format!(
                "cn0_slope: {cn0_slope}; expected the variance's decades per 10 dB-Hz in [0, {CN0_SLOPE_MAX}] (1: the σ–ε model, 0: no C/N0 term)"
            )))
        }
        "cn0" => Weighting::Cn0 {
            reference: cn0_reference,
            slope: cn0_slope,
        },
        other => {
            return Err(PyValueError::new_err(format!(
                "weighting: '{other}' is not 'elevation', 'rtklib' or 'cn0'"
            )))
        }
    })
}

/// The global test's columns of the epochs `e` into `d`: ``statistic``, ``dof`` of the final
/// set and ``first_statistic``, ``first_dof`` of the first test (float64).
fn test_columns(py: Python<'_>, d: &Bound<'_, PyDict>, e: &[spp::EpochSolution]) -> PyResult<()> {
    let n = e.len();
    let f = |g: &dyn Fn(&spp::EpochSolution) -> f64| -> Vec<f64> { e.iter().map(g).collect() };
    d.set_item("dof", to_numpy(py, f(&|s| s.fde.dof as f64), &[n])?)?;
    d.set_item("statistic", to_numpy(py, f(&|s| s.fde.statistic), &[n])?)?;
    d.set_item(
        "first_statistic",
        to_numpy(py, f(&|s| s.fde.first.0), &[n])?,
    )?;
    d.set_item(
        "first_dof",
        to_numpy(py, f(&|s| s.fde.first.2 as f64), &[n])?,
    )?;
    Ok(())
}

/// Per-system σ factors from their letters.
fn parse_factors(factors: &BTreeMap<String, f64>) -> PyResult<Vec<(Sys, f64)>> {
    factors
        .iter()
        .map(|(letter, f)| Ok((parse_sys(letter)?, *f)))
        .collect()
}

#[pymethods]
impl PyGnssRun {
    /// Read `obs_path` and `nav_path` and set up the solution. `systems` letters (G, E, C,
    /// J); `mask_deg` elevation mask (deg); `alpha`, `k` of the tests; `exclude` runs the
    /// exclusion loop; `noise` (a, b) in m; `weighting` ``"elevation"``, ``"rtklib"`` or
    /// ``"cn0"`` (with `cn0_reference`, dB-Hz: the C/N0 at which σ is the elevation model's,
    /// and `cn0_slope`: the variance's decades per 10 dB-Hz below it, 1 the σ–ε model's);
    /// `faults` tuples ``(satellite, shape, magnitude, start_s, end_s)`` with shape ``step``
    /// (m), ``ramp`` (m/s) or ``quadratic`` (m/s²); `codes` per system letter; `factors`
    /// per-system σ factors; `sprt` (P_f, P_m), `aime` (P_f, window epochs) and `cusum` (drift, threshold, tau epochs,
    /// warm-up epochs, floor m) of the sequential detectors; `test` what opens the exclusion
    /// loop (``"global"``, ``"wtest"``: data snooping, ``"both"``, ``"auto"``) and `power` the
    /// β0 of the reported minimal detectable biases.
    #[new]
    #[pyo3(signature = (obs_path, nav_path, systems, mask_deg, alpha, k, exclude, noise, weighting, ionosphere, troposphere, faults, codes, factors, sprt, aime, cusum, cn0_reference = 45.0, test = "global", power = 0.8, cn0_slope = 1.0))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        obs_path: String,
        nav_path: String,
        systems: Vec<String>,
        mask_deg: f64,
        alpha: f64,
        k: Option<f64>,
        exclude: bool,
        noise: (f64, f64),
        weighting: &str,
        ionosphere: bool,
        troposphere: bool,
        faults: Vec<(String, String, f64, f64, f64)>,
        codes: BTreeMap<String, String>,
        factors: BTreeMap<String, f64>,
        sprt: (f64, f64),
        aime: (f64, usize),
        cusum: (f64, f64, f64, usize, f64),
        cn0_reference: f64,
        test: &str,
        power: f64,
        cn0_slope: f64,
    ) -> PyResult<Self> {
        let fde = FdeConfig::new(alpha, k)
            .and_then(|c| c.with_test(Detection::parse(test)?, power))
            .py()?;
        let mut cfg = SppConfig::new(fde);
        cfg.systems = systems
            .iter()
            .map(|s| parse_sys(s))
            .collect::<PyResult<_>>()?;
        for (letter, code) in &codes {
            let sys = parse_sys(letter)?;
            match cfg.codes.iter_mut().find(|(s, _)| *s == sys) {
                Some(c) => c.1 = code.clone(),
                None => cfg.codes.push((sys, code.clone())),
            }
        }
        cfg.factors.extend(parse_factors(&factors)?);
        if !mask_deg.is_finite() {
            return Err(PyValueError::new_err(format!(
                "mask: {mask_deg} is not a finite elevation (deg)"
            )));
        }
        cfg.mask = mask_deg.to_radians();
        cfg.exclude = exclude;
        cfg.noise = noise;
        cfg.weighting = parse_weighting(weighting, cn0_reference, cn0_slope)?;
        cfg.sequential = navfdi_core::gnss::sequential::SeqConfig {
            sprt,
            aime,
            cusum: navfdi_core::gnss::sequential::CusumConfig {
                drift: cusum.0,
                threshold: cusum.1,
                tau: cusum.2,
                warmup: cusum.3,
                floor: cusum.4,
            },
        };
        cfg.ionosphere = ionosphere;
        cfg.troposphere = troposphere;
        cfg.validate().py()?;
        let faults = faults
            .into_iter()
            .map(|(sat, shape, magnitude, start, end)| {
                let s = Sat::parse(&sat)
                    .filter(|s| Sys::POSITIONING.contains(&s.sys))
                    .ok_or_else(|| {
                        PyValueError::new_err(format!(
                            "fault: '{sat}' is not a satellite name such as G13 (GPS, Galileo, BeiDou or QZSS)"
                        ))
                    })?;
                let shape = match shape.as_str() {
                    "step" => FaultShape::Step,
                    "ramp" => FaultShape::Ramp,
                    "quadratic" => FaultShape::Quadratic,
                    o => {
                        return Err(PyValueError::new_err(format!(
                            "fault on {sat}: shape '{o}' is not step, ramp or quadratic"
                        )))
                    }
                };
                let f = InjectedFault {
                    sat: s,
                    shape,
                    magnitude,
                    start,
                    end,
                };
                f.validate().py()?;
                Ok(f)
            })
            .collect::<PyResult<Vec<_>>>()?;
        let (obs, nav) = crate::interrupt::run(py, move |_| {
            let nav = rinex::read_nav(&nav_path)?;
            let obs = rinex::read_obs(&obs_path)?;
            Ok((obs, nav))
        })?;
        // Codes: the user's where given, else the first of the priority list the file holds.
        let forced: Vec<(Sys, String)> = codes
            .iter()
            .map(|(l, c)| parse_sys(l).map(|s| (s, c.clone())))
            .collect::<PyResult<_>>()?;
        cfg.codes = navfdi_core::gnss::signals::select_codes(&obs, &cfg.systems, &forced).py()?;
        cfg.validate().py()?;
        for s in &cfg.systems {
            if !nav.ephemerides.keys().any(|k| k.sys == *s) {
                return Err(navfdi_core::Error::Format(format!(
                    "the navigation file has no {} ephemerides, but {} was asked for (systems)",
                    s.name(),
                    s.name()
                )))
                .py();
            }
        }
        Ok(PyGnssRun {
            obs,
            nav,
            cfg,
            faults,
            state: SppState::default(),
            out: SppRun::default(),
            next: 0,
            cn0_reference,
            every: 1,
        })
    }

    /// Start again from the first epoch on the observations already read, with another
    /// variance model (`weighting`, `cn0_slope` as in the constructor; the reference C/N0 is
    /// kept), per-system σ `factors` (replacing the constructor's), `exclude` and `test` (the
    /// allocation's α, k and power kept), solving every `every`-th epoch only (1: all): what
    /// ``navfdi.gnss_solve``'s ``"auto"`` estimates solve a file with, several times, without
    /// reading it again. Everything solved so far is dropped; on an error nothing changes.
    #[pyo3(signature = (weighting, cn0_slope, factors, exclude, test, every = 1))]
    fn restart(
        &mut self,
        weighting: &str,
        cn0_slope: f64,
        factors: BTreeMap<String, f64>,
        exclude: bool,
        test: &str,
        every: usize,
    ) -> PyResult<()> {
        if every == 0 {
            return Err(PyValueError::new_err(
                "every = 0: solve every k-th epoch with k >= 1",
            ));
        }
        let mut cfg = self.cfg.clone();
        cfg.weighting = parse_weighting(weighting, self.cn0_reference, cn0_slope)?;
        cfg.factors = parse_factors(&factors)?;
        cfg.exclude = exclude;
        let power = cfg.fde.power;
        cfg.fde = cfg
            .fde
            .clone()
            .with_test(Detection::parse(test).py()?, power)
            .py()?;
        cfg.validate().py()?;
        self.cfg = cfg;
        self.state = SppState::default();
        self.out = SppRun::default();
        self.next = 0;
        self.every = every;
        Ok(())
    }

    /// The pseudorange code used per system letter (chosen by priority or given).
    #[getter]
    fn codes(&self) -> BTreeMap<String, String> {
        self.cfg
            .codes
            .iter()
            .filter(|(s, _)| self.cfg.systems.contains(s))
            .map(|(s, c)| (s.letter().to_string(), c.clone()))
            .collect()
    }

    /// Number of epochs in the observation file.
    #[getter]
    fn n_epochs(&self) -> usize {
        self.obs.epochs.len()
    }

    /// Epochs solved so far.
    #[getter]
    fn done(&self) -> usize {
        self.next
    }

    /// Solve up to `n` more epochs (GIL released, Ctrl-C stops within one epoch); returns how
    /// many were solved (of every `every`-th epoch after a `restart` with it: `done` then
    /// counts the file's epochs passed).
    fn advance(&mut self, py: Python<'_>, n: usize) -> PyResult<usize> {
        let start = self.next;
        let every = self.every;
        let end = start
            .saturating_add(n.saturating_mul(every))
            .min(self.obs.epochs.len());
        let (obs, nav, cfg, faults) = (&self.obs, &self.nav, &self.cfg, &self.faults);
        let mut state = self.state.clone();
        let mut out = std::mem::take(&mut self.out);
        let solved_before = out.epochs.len();
        let res = crate::interrupt::run(py, |cancel| {
            spp::solve(
                obs,
                nav,
                cfg,
                faults,
                (start..end).step_by(every),
                &mut state,
                &mut out,
                cancel,
            )
        });
        // On an error (e.g. Ctrl-C) the epochs of this chunk are dropped so that the run
        // stays consistent: everything before `start` is kept.
        if res.is_err() {
            out.epochs.truncate(solved_before);
            out.sats.retain(|r| r.epoch < start);
            self.out = out;
            res?;
            return Ok(0);
        }
        self.out = out;
        self.state = state;
        self.next = end;
        Ok((end - start).div_ceil(every))
    }

    /// Receiver velocity from Doppler for the epochs solved so far (`navfdi_core::gnss::doppler`),
    /// rate noise `(a, b)` m/s in `σ² = a² + b²/sin² el`: dict of arrays `vx, vy, vz,
    /// clock_drift` (m/s, ECEF; NaN without a solution), `statistic, threshold` of the rate
    /// test, `dof`, `used` (satellites), `excluded` (names, space separated). GIL released.
    #[pyo3(signature = (noise = (0.05, 0.05)))]
    fn velocity<'py>(&self, py: Python<'py>, noise: (f64, f64)) -> PyResult<Bound<'py, PyDict>> {
        if !(noise.0 >= 0.0
            && noise.1 >= 0.0
            && noise.0 + noise.1 > 0.0
            && (noise.0 + noise.1).is_finite())
        {
            return Err(PyValueError::new_err(format!(
                "doppler noise {noise:?}: give non-negative finite (a, b) m/s, not both 0"
            )));
        }
        let (obs, nav, cfg, out) = (&self.obs, &self.nav, &self.cfg, &self.out);
        let rows = crate::interrupt::run(py, move |_| {
            navfdi_core::gnss::doppler::doppler_velocity(obs, nav, cfg, out, noise, &cfg.fde)
        })?;
        let n = rows.len();
        let d = PyDict::new(py);
        let f = |g: &dyn Fn(&navfdi_core::gnss::doppler::EpochVelocity) -> f64| -> Vec<f64> {
            rows.iter().map(g).collect()
        };
        for (c, name) in ["vx", "vy", "vz"].iter().enumerate() {
            d.set_item(
                *name,
                to_numpy(py, f(&|r| r.velocity.map_or(f64::NAN, |v| v.0[c])), &[n])?,
            )?;
        }
        d.set_item(
            "clock_drift",
            to_numpy(py, f(&|r| r.velocity.map_or(f64::NAN, |v| v.1)), &[n])?,
        )?;
        d.set_item("statistic", to_numpy(py, f(&|r| r.fde.statistic), &[n])?)?;
        d.set_item("threshold", to_numpy(py, f(&|r| r.fde.threshold), &[n])?)?;
        d.set_item(
            "dof",
            to_numpy(py, rows.iter().map(|r| r.fde.dof as i64).collect(), &[n])?,
        )?;
        d.set_item(
            "used",
            to_numpy(
                py,
                rows.iter()
                    .map(|r| (r.sats.len() - r.fde.excluded.len()) as i64)
                    .collect(),
                &[n],
            )?,
        )?;
        d.set_item(
            "excluded",
            rows.iter()
                .map(|r| {
                    r.fde
                        .excluded
                        .iter()
                        .map(|&i| r.sats[i].name())
                        .collect::<Vec<_>>()
                        .join(" ")
                })
                .collect::<Vec<_>>(),
        )?;
        Ok(d)
    }

    /// Per-epoch columns of the epochs solved so far: ``time`` (GPS s), ``x, y, z`` (ECEF m,
    /// NaN without a solution), ``status`` (str), ``dof``, ``statistic``, ``threshold``,
    /// ``first_statistic``, ``first_threshold``, ``first_dof``, ``k0``, ``alpha0``,
    /// ``lambda0`` (the final set's allocation: the w-test's critical value, its per-satellite
    /// false-alarm probability and the non-centrality behind the MDB), ``excluded`` (space-separated
    /// names), ``faulty`` (names with an injected fault), ``used`` (int), ``reason`` (str),
    /// ``clock_G``/``clock_E``/``clock_C``/``clock_J`` (m, NaN when the system is not solved).
    fn epoch_table<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let e = &self.out.epochs;
        let n = e.len();
        let d = PyDict::new(py);
        let f = |g: &dyn Fn(&spp::EpochSolution) -> f64| -> Vec<f64> { e.iter().map(g).collect() };
        d.set_item("time", to_numpy(py, f(&|s| s.time.seconds()), &[n])?)?;
        for (c, name) in ["x", "y", "z"].iter().enumerate() {
            d.set_item(
                *name,
                to_numpy(py, f(&|s| s.position.map_or(f64::NAN, |p| p[c])), &[n])?,
            )?;
        }
        for sys in Sys::POSITIONING {
            d.set_item(
                format!("clock_{}", sys.letter()),
                to_numpy(
                    py,
                    f(&|s| {
                        s.clocks
                            .iter()
                            .find(|(c, _)| *c == sys)
                            .map_or(f64::NAN, |c| c.1)
                    }),
                    &[n],
                )?,
            )?;
        }
        test_columns(py, &d, e)?;
        d.set_item("threshold", to_numpy(py, f(&|s| s.fde.threshold), &[n])?)?;
        d.set_item(
            "first_threshold",
            to_numpy(py, f(&|s| s.fde.first.1), &[n])?,
        )?;
        let sn = |g: &dyn Fn(&navfdi_core::gnss::snapshot::Snooping) -> f64| {
            f(&|s: &spp::EpochSolution| s.fde.snooping.as_ref().map_or(f64::NAN, g))
        };
        d.set_item("k0", to_numpy(py, sn(&|x| x.k0), &[n])?)?;
        d.set_item("alpha0", to_numpy(py, sn(&|x| x.alpha0), &[n])?)?;
        d.set_item("lambda0", to_numpy(py, sn(&|x| x.lambda0), &[n])?)?;
        d.set_item("used", to_numpy(py, f(&|s| s.used as f64), &[n])?)?;
        let names = |v: &[Sat]| v.iter().map(Sat::name).collect::<Vec<_>>().join(" ");
        d.set_item(
            "excluded",
            e.iter().map(|s| names(&s.excluded)).collect::<Vec<_>>(),
        )?;
        d.set_item(
            "faulty",
            e.iter().map(|s| names(&s.faulty)).collect::<Vec<_>>(),
        )?;
        d.set_item(
            "status",
            e.iter().map(|s| s.fde.status.as_str()).collect::<Vec<_>>(),
        )?;
        d.set_item(
            "reason",
            e.iter().map(|s| s.fde.reason.clone()).collect::<Vec<_>>(),
        )?;
        Ok(d)
    }

    /// What the ``"auto"`` estimates of ``navfdi.gnss_solve`` read of the epochs solved so
    /// far, without the full tables' strings: per epoch ``statistic``, ``dof``,
    /// ``first_statistic``, ``first_dof`` (as in :meth:`epoch_table`); per satellite-epoch
    /// row ``w``, ``cn0`` (dB-Hz, NaN where none) and ``used`` (bool: status ``used``).
    fn estimation_table<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = &self.out.sats;
        let m = r.len();
        let d = PyDict::new(py);
        test_columns(py, &d, &self.out.epochs)?;
        d.set_item("w", to_numpy(py, r.iter().map(|x| x.w).collect(), &[m])?)?;
        d.set_item(
            "cn0",
            to_numpy(py, r.iter().map(|x| x.cn0).collect(), &[m])?,
        )?;
        d.set_item(
            "used",
            to_numpy(
                py,
                r.iter().map(|x| x.status.as_str() == "used").collect(),
                &[m],
            )?,
        )?;
        Ok(d)
    }

    /// Per epoch and satellite columns of the epochs solved so far: ``epoch`` (int),
    /// ``satellite`` (str), ``elevation``, ``azimuth`` (deg), ``residual`` (m), ``w``, ``mdb``
    /// (minimal detectable bias, m), ``sigma`` (m), ``iono``, ``tropo`` (m), ``iono_sigma`` (σ of the delay left after
    /// the broadcast correction, DO-229's single-frequency model, m), ``cn0`` (recorded C/N0,
    /// dB-Hz; NaN where none), ``fault`` (injected, m), ``sat_x, sat_y,
    /// sat_z`` (satellite ECEF at transmission, m), ``sat_clock`` (s), ``sprt``, ``aime``,
    /// ``cusum`` (sequential statistics), ``sprt_alarm``, ``aime_alarm``, ``cusum_alarm``
    /// (bool), ``status`` (``used``,
    /// ``excluded``, ``below_mask``, ``no_ephemeris``, ``unhealthy``, ``bad_ephemeris``, ``unsolved``).
    fn satellite_table<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = &self.out.sats;
        let n = r.len();
        let d = PyDict::new(py);
        let f = |g: &dyn Fn(&spp::SatRow) -> f64| -> Vec<f64> { r.iter().map(g).collect() };
        d.set_item(
            "epoch",
            to_numpy(py, r.iter().map(|x| x.epoch as u32).collect(), &[n])?,
        )?;
        d.set_item(
            "satellite",
            r.iter().map(|x| x.sat.name()).collect::<Vec<_>>(),
        )?;
        d.set_item(
            "elevation",
            to_numpy(py, f(&|x| x.elevation.to_degrees()), &[n])?,
        )?;
        d.set_item(
            "azimuth",
            to_numpy(py, f(&|x| x.azimuth.to_degrees()), &[n])?,
        )?;
        d.set_item("residual", to_numpy(py, f(&|x| x.residual), &[n])?)?;
        d.set_item("w", to_numpy(py, f(&|x| x.w), &[n])?)?;
        d.set_item("mdb", to_numpy(py, f(&|x| x.mdb), &[n])?)?;
        d.set_item("sigma", to_numpy(py, f(&|x| x.sigma), &[n])?)?;
        d.set_item("iono", to_numpy(py, f(&|x| x.iono), &[n])?)?;
        d.set_item("iono_sigma", to_numpy(py, f(&|x| x.iono_sigma), &[n])?)?;
        d.set_item("tropo", to_numpy(py, f(&|x| x.tropo), &[n])?)?;
        d.set_item("cn0", to_numpy(py, f(&|x| x.cn0), &[n])?)?;
        d.set_item("fault", to_numpy(py, f(&|x| x.fault), &[n])?)?;
        for (c, name) in ["sat_x", "sat_y", "sat_z"].iter().enumerate() {
            d.set_item(*name, to_numpy(py, f(&|x| x.sat_pos[c]), &[n])?)?;
        }
        d.set_item("sat_clock", to_numpy(py, f(&|x| x.sat_clock), &[n])?)?;
        d.set_item("sprt", to_numpy(py, f(&|x| x.seq.sprt), &[n])?)?;
        d.set_item("cusum", to_numpy(py, f(&|x| x.seq.cusum), &[n])?)?;
        d.set_item("aime", to_numpy(py, f(&|x| x.seq.aime), &[n])?)?;
        d.set_item(
            "aime_alarm",
            r.iter().map(|x| x.seq.aime_alarm).collect::<Vec<_>>(),
        )?;
        d.set_item(
            "sprt_alarm",
            r.iter().map(|x| x.seq.sprt_alarm).collect::<Vec<_>>(),
        )?;
        d.set_item(
            "cusum_alarm",
            r.iter().map(|x| x.seq.cusum_alarm).collect::<Vec<_>>(),
        )?;
        d.set_item(
            "status",
            r.iter().map(|x| x.status.as_str()).collect::<Vec<_>>(),
        )?;
        Ok(d)
    }

    /// Letters of the systems both files let a solution use, asked for or not.
    #[getter]
    fn systems_in_files(&self) -> Vec<String> {
        navfdi_core::gnss::spp::systems_in_files(&self.obs, &self.nav)
            .into_iter()
            .map(|s| s.letter().to_string())
            .collect()
    }

    /// Observation types dropped while reading (e.g. ``G:X1``).
    #[getter]
    fn dropped(&self) -> Vec<String> {
        self.obs.dropped_codes.clone()
    }

    /// Receiver type from the observation header.
    #[getter]
    fn receiver(&self) -> String {
        self.obs.receiver.clone()
    }
}
