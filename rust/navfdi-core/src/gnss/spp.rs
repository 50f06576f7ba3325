//! Single-point positioning (SPP) with satellite fault detection and exclusion on real
//! pseudoranges (RINEX), epoch by epoch.
//!
//! Per epoch and satellite with a pseudorange ρ of the chosen code (first band: GPS/QZSS/
//! Galileo `C1x`, BeiDou `C2x`):
//!
//! * ephemeris: `broadcast::select` (nearest healthy t_oe within the system's maximum age;
//!   Galileo I/NAV first); none → `no_ephemeris`, only unhealthy ones → `unhealthy`;
//! * transmission time `t_rx − ρ/c − δt_s`, satellite position at that time, satellite clock
//!   δt_s with the relativistic term, group delay: `ρ_c = ρ + c δt_s − c TGD`;
//! * model `ρ_c = |r_s − r| + ω_e (x_s y − y_s x)/c + c δt_r,sys + I + T + ε`: Earth rotation
//!   during the signal's travel (Sagnac term), one receiver clock per system (columns in the
//!   order GPS, Galileo, BeiDou, QZSS, only systems present), Klobuchar ionosphere `I` scaled
//!   from L1 by `(f_L1/f)²`, Saastamoinen troposphere `T` (relative humidity 0.7) — both
//!   recomputed at each Gauss-Newton iterate, as RTKLIB's `pntpos` does;
//! * variance (RTKLIB's `pntpos` model, so solutions compare): `σ² = a² + b²/sin el + URA² +
//!   0.3² + (0.5 I)² + (0.3 / (sin el + 0.1))²` with `a = b = 0.3 m` by default;
//!   (the default is the measurement noise only, `σ² = a² + b²/sin² el`; see [`Weighting`]),
//!   times a per-system factor;
//! * elevation mask applied at the start position (the previous epoch's solution, or for the
//!   first epoch an uncorrected least-squares fix from the Earth's centre);
//! * the exclusion loop `snapshot::fde` (global χ² test + w-test, METHODS §10) on every
//!   epoch, or plain weighted least squares when exclusion is off.
//!
//! Injected faults ([`InjectedFault`]) are added to the chosen satellites' pseudoranges before
//! all of this, so detectors are scored on real noise with known faults.

use super::atmosphere::{klobuchar, klobuchar_residual_sigma, saastamoinen, Klobuchar};
use super::broadcast::{select, EphProblem, GpsTime, Sat, Sys};
use super::geodesy::{ecef_to_lla, elevation_azimuth};
use super::rinex::{NavData, ObsData};
use super::sequential::{SatDetectors, SeqConfig, SeqOutput};
use super::snapshot::{fde, gauss_newton, FdeConfig, FdeModel, FdeOutcome, ObsCov};
use super::C;

/// Travel distance (m) of a medium-orbit satellite's signal, for a pseudorange outside
/// 1e7 … 1e8 m (no receiver measures one there).
pub const NOMINAL_RANGE: f64 = 2.3e7;
use crate::cancel::Cancel;
use crate::error::{Error, Result};
use nalgebra::{DMatrix, DVector, Vector3};
use std::collections::btree_map::{BTreeMap, Entry};

/// Earth rotation rate used for the Sagnac term (rad/s, WGS-84).
const OMEGA_E: f64 = 7.292_115_146_7e-5;
/// GPS L1 frequency (Hz).
pub const F_L1: f64 = 1_575.42e6;

/// Carrier frequency (Hz) of a first-band code of `sys` (`C1C` → L1/E1, `C2I` → B1I).
pub fn frequency(sys: Sys, code: &str) -> Option<f64> {
    let band = code.chars().nth(1)?;
    match (sys, band) {
        (Sys::Gps | Sys::Qzss | Sys::Galileo, '1') => Some(F_L1),
        (Sys::BeiDou, '2') => Some(1_561.098e6),
        _ => None,
    }
}

/// The shape of an injected fault.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FaultShape {
    /// Constant offset (m).
    Step,
    /// Offset growing at a constant rate (m/s) from the start.
    Ramp,
    /// Offset `a (t − start)²` (a in m/s²).
    Quadratic,
}

/// A fault added to one satellite's pseudoranges over `[start, end)` (s from the first epoch).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InjectedFault {
    /// Satellite.
    pub sat: Sat,
    /// Shape.
    pub shape: FaultShape,
    /// Size: m (step), m/s (ramp), m/s² (quadratic).
    pub magnitude: f64,
    /// Start (s after the first epoch, inclusive).
    pub start: f64,
    /// End (s after the first epoch, exclusive).
    pub end: f64,
}

impl InjectedFault {
    /// Offset (m) at `tau` seconds after the first epoch (0 outside the window).
    pub fn offset(&self, tau: f64) -> f64 {
        if tau < self.start || tau >= self.end {
            return 0.0;
        }
        let d = tau - self.start;
        match self.shape {
            FaultShape::Step => self.magnitude,
            FaultShape::Ramp => self.magnitude * d,
            FaultShape::Quadratic => self.magnitude * d * d,
        }
    }

    /// Check the numbers (finite magnitude, 0 ≤ start < end).
    pub fn validate(&self) -> Result<()> {
        if !self.magnitude.is_finite() {
            return Err(Error::InvalidParameter {
                name: format!("fault on {}: magnitude", self.sat.name()),
                value: self.magnitude,
                requirement: "must be finite".into(),
            });
        }
        if !(self.start >= 0.0 && self.end > self.start && self.start.is_finite()) {
            return Err(Error::Invalid(format!(
                "fault on {}: the window {}–{} s must satisfy 0 ≤ start < end",
                self.sat.name(),
                self.start,
                self.end
            )));
        }
        Ok(())
    }
}

/// Settings of a single-point solution.
#[derive(Debug, Clone)]
pub struct SppConfig {
    /// Systems used (others are read and skipped).
    pub systems: Vec<Sys>,
    /// Pseudorange code per system (`C1C`, `C2I`, …).
    pub codes: Vec<(Sys, String)>,
    /// Elevation mask (rad).
    pub mask: f64,
    /// Exclusion-loop settings (α, K).
    pub fde: FdeConfig,
    /// Run the exclusion loop (false: weighted least squares with the global test reported).
    pub exclude: bool,
    /// Code noise `a`, `b` (m) of the variance model.
    pub noise: (f64, f64),
    /// Variance model.
    pub weighting: Weighting,
    /// Per-system factor on σ (RTKLIB's EFACT), default 1 for every system.
    pub factors: Vec<(Sys, f64)>,
    /// Sequential detectors on each satellite's residual stream.
    pub sequential: SeqConfig,
    /// Apply the Klobuchar ionosphere.
    pub ionosphere: bool,
    /// Apply the Saastamoinen troposphere.
    pub troposphere: bool,
}

impl SppConfig {
    /// Defaults: GPS `C1C`, 10° mask, the given FDE settings, RTKLIB noise, both models.
    pub fn new(fde: FdeConfig) -> Self {
        SppConfig {
            systems: vec![Sys::Gps],
            codes: vec![
                (Sys::Gps, "C1C".into()),
                (Sys::Galileo, "C1C".into()),
                (Sys::BeiDou, "C2I".into()),
                (Sys::Qzss, "C1C".into()),
            ],
            mask: 10f64.to_radians(),
            fde,
            exclude: true,
            noise: (0.3, 0.3),
            weighting: Weighting::Elevation,
            factors: Vec::new(),
            sequential: SeqConfig::default(),
            ionosphere: true,
            troposphere: true,
        }
    }

    /// Check systems, codes, mask and noise.
    pub fn validate(&self) -> Result<()> {
        if self.systems.is_empty() {
            return Err(Error::Invalid(
                "systems: at least one system is needed".into(),
            ));
        }
        for s in &self.systems {
            if !Sys::POSITIONING.contains(s) {
                return Err(Error::Invalid(format!(
                    "systems: {} cannot be positioned (GPS 'G', Galileo 'E', BeiDou 'C', QZSS 'J' can)",
                    s.name()
                )));
            }
            let code = self.code(*s).ok_or_else(|| {
                Error::Invalid(format!("codes: no pseudorange code given for {}", s.name()))
            })?;
            if !code.starts_with('C') || code.len() != 3 || frequency(*s, code).is_none() {
                return Err(Error::Invalid(format!(
                    "codes: '{code}' for {} is not supported; single-frequency first-band pseudoranges only (GPS/Galileo/QZSS 'C1x', BeiDou 'C2x'), as the broadcast group delays refer to them",
                    s.name()
                )));
            }
        }
        if !(self.mask >= 0.0 && self.mask < std::f64::consts::FRAC_PI_2) {
            return Err(Error::InvalidParameter {
                name: "mask".into(),
                value: self.mask.to_degrees(),
                requirement: "the elevation mask must be in [0, 90) degrees".into(),
            });
        }
        for (name, v) in [("noise a", self.noise.0), ("noise b", self.noise.1)] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(Error::InvalidParameter {
                    name: name.into(),
                    value: v,
                    requirement: "must be finite and ≥ 0 (m)".into(),
                });
            }
        }
        for (sys, f) in &self.factors {
            if !(*f > 0.0 && f.is_finite()) {
                return Err(Error::InvalidParameter {
                    name: format!("noise factor of {}", sys.name()),
                    value: *f,
                    requirement: "must be positive and finite".into(),
                });
            }
        }
        self.sequential.validate()?;
        if self.noise.0 == 0.0 && self.noise.1 == 0.0 {
            return Err(Error::Invalid(
                "noise: a and b are both 0; the code noise must be positive".into(),
            ));
        }
        Ok(())
    }

    fn code(&self, s: Sys) -> Option<&str> {
        self.codes
            .iter()
            .find(|(c, _)| *c == s)
            .map(|(_, n)| n.as_str())
    }
}

/// The largest [`Weighting::Cn0`] slope accepted: 30 dB of variance per 10 dB-Hz of C/N0.
pub const CN0_SLOPE_MAX: f64 = 3.0;

/// Pseudorange variance model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Weighting {
    /// `σ² = a² + b²/sin² el`: the measurement noise only, so the χ² and w tests are scaled
    /// by what the residuals scatter by.
    Elevation,
    /// RTKLIB `pntpos`: `σ² = a² + b²/sin el + URA² + 0.3² + (0.5 I)² + (0.3/(sin el + 0.1))²`,
    /// which adds bounds on the broadcast-model errors (ephemeris, ionosphere, troposphere);
    /// positions compare with RTKLIB, tests are far from their nominal α (the model errors are
    /// common to all satellites and mostly absorbed by the clock).
    Rtklib,
    /// C/N0 weighting for low-cost receivers and phones: the elevation model scaled by
    /// `10^(slope (C/N0_ref − C/N0)/10)` with the recorded C/N0 (`S1C` beside `C1C`, dB-Hz;
    /// slope 1 is the σ–ε model's `σ² ∝ 10^(−C/N0/10)`, Hartinger and Brunner 1999, slope 0
    /// the elevation model), `a`, `b` being the noise at the reference C/N0 (dB-Hz); a
    /// satellite without a recorded C/N0 keeps the elevation model.
    Cn0 {
        /// The C/N0 (dB-Hz) at which the variance is the elevation model's.
        reference: f64,
        /// The variance's decades per 10 dB-Hz below the reference (dimensionless, ≥ 0).
        slope: f64,
    },
}

/// What happened to a satellite at an epoch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SatStatus {
    /// Used in the final solution.
    Used,
    /// Excluded by the w-test.
    Excluded,
    /// Below the elevation mask.
    BelowMask,
    /// No ephemeris within the maximum age.
    NoEphemeris,
    /// Only unhealthy ephemerides.
    Unhealthy,
    /// Every ephemeris in range has an implausible orbit or clock
    /// ([`super::broadcast::Ephemeris::plausible`]), or the selected one gives an impossible
    /// position or clock (corrupt records).
    BadEphemeris,
    /// No solution at this epoch (satellite above the mask with an ephemeris).
    Unsolved,
}

impl SatStatus {
    /// Lower-case name.
    pub fn as_str(self) -> &'static str {
        match self {
            SatStatus::Used => "used",
            SatStatus::Excluded => "excluded",
            SatStatus::BelowMask => "below_mask",
            SatStatus::NoEphemeris => "no_ephemeris",
            SatStatus::Unhealthy => "unhealthy",
            SatStatus::BadEphemeris => "bad_ephemeris",
            SatStatus::Unsolved => "unsolved",
        }
    }
}

/// One satellite at one epoch.
#[derive(Debug, Clone, PartialEq)]
pub struct SatRow {
    /// Epoch index.
    pub epoch: usize,
    /// Satellite.
    pub sat: Sat,
    /// Elevation and azimuth (rad; NaN without ephemeris or start position).
    pub elevation: f64,
    /// Azimuth (rad, clockwise from north).
    pub azimuth: f64,
    /// Corrected pseudorange minus the model at the final solution (m; NaN without one).
    pub residual: f64,
    /// w of the final test (|w| at exclusion for excluded satellites; NaN when untested).
    pub w: f64,
    /// Minimal detectable bias of the final test (m, at α and the allocation's power β0; NaN
    /// for excluded or untested satellites).
    pub mdb: f64,
    /// σ used (m; NaN when not used).
    pub sigma: f64,
    /// Ionospheric and tropospheric delays at the final solution (m).
    pub iono: f64,
    /// σ of the ionospheric delay left after the broadcast correction at the final solution
    /// (m, DO-229's single-frequency model on this signal's frequency:
    /// [`super::atmosphere::klobuchar_residual_sigma`]; NaN without a solution).
    pub iono_sigma: f64,
    /// Tropospheric delay (m).
    pub tropo: f64,
    /// Carrier-to-noise density of the signal as recorded (dB-Hz; NaN where the file has none
    /// for it, or no ephemeris let the satellite be solved).
    pub cn0: f64,
    /// Injected fault (m; 0 when none).
    pub fault: f64,
    /// Satellite ECEF position at transmission (m; NaN without an ephemeris).
    pub sat_pos: Vector3<f64>,
    /// Satellite clock offset incl. the relativistic term (s; NaN without an ephemeris).
    pub sat_clock: f64,
    /// Sequential detectors on this satellite's residual stream (NaN statistics without a
    /// residual).
    pub seq: SeqOutput,
    /// Status.
    pub status: SatStatus,
}

/// One epoch's solution.
#[derive(Debug, Clone, PartialEq)]
pub struct EpochSolution {
    /// Receiver time (GPST).
    pub time: GpsTime,
    /// ECEF position (m), None without a solution.
    pub position: Option<Vector3<f64>>,
    /// Receiver clock per system (m), for the systems of this epoch's solution.
    pub clocks: Vec<(Sys, f64)>,
    /// The exclusion loop's outcome.
    pub fde: FdeOutcome,
    /// Satellites excluded, in exclusion order.
    pub excluded: Vec<Sat>,
    /// Satellites with an injected fault at this epoch.
    pub faulty: Vec<Sat>,
    /// Satellites used in the final solution.
    pub used: usize,
}

/// Everything a run produces.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SppRun {
    /// Per epoch.
    pub epochs: Vec<EpochSolution>,
    /// Per epoch and satellite.
    pub sats: Vec<SatRow>,
}

/// Gauss-Newton convergence of a fix: step norm below this (m).
const SPP_TOLERANCE: f64 = 1e-4;

/// The measurement model of one epoch (see the module docs), apart from its unknowns.
struct SppGeometry<'a> {
    sat: &'a [Vector3<f64>],
    rho: &'a [f64],
    col: &'a [usize],
    iono_scale: &'a [f64],
    n_clk: usize,
    klob: Option<&'a Klobuchar>,
    sow: f64,
    trop: bool,
}

impl SppGeometry<'_> {
    /// The receiver's geodetic position at `x` where the atmosphere and elevation are modelled
    /// (more than 6 000 km from the centre; None before the first iterations get there).
    fn receiver_lla(x: &[f64]) -> Option<(f64, f64, f64)> {
        let r = Vector3::new(x[0], x[1], x[2]);
        (r.norm() > 6.0e6).then(|| ecef_to_lla(&r))
    }

    /// Predicted ρ_c, unit vector to the satellite and (I, T, el, az) at `x`, with the
    /// receiver's geodetic position `lla` of `x` ([`SppGeometry::receiver_lla`]: one
    /// conversion per iteration, not one per satellite).
    fn predict(
        &self,
        x: &[f64],
        i: usize,
        lla: Option<(f64, f64, f64)>,
    ) -> (f64, Vector3<f64>, [f64; 4]) {
        let r = Vector3::new(x[0], x[1], x[2]);
        let s = self.sat[i];
        let d = s - r;
        let range = d.norm();
        let geo = range + OMEGA_E * (s.x * r.y - s.y * r.x) / C;
        let mut extra = [0.0, 0.0, f64::NAN, f64::NAN];
        if let Some((lat, lon, h)) = lla {
            let (el, az) = elevation_azimuth(&r, lat, lon, &s);
            extra[2] = el;
            extra[3] = az;
            if let Some(k) = self.klob {
                extra[0] = klobuchar(k, self.sow, lat, lon, h, az, el) * self.iono_scale[i];
            }
            if self.trop {
                extra[1] = saastamoinen(lat, h, el, 0.7);
            }
        }
        let pred = geo + x[3 + self.col[i]] + extra[0] + extra[1];
        (pred, d / range, extra)
    }

    fn linearise(&self, x: &[f64], idx: &[usize]) -> (DMatrix<f64>, DVector<f64>) {
        let u = 3 + self.n_clk;
        let mut b = DMatrix::zeros(idx.len(), u);
        let mut l = DVector::zeros(idx.len());
        let lla = Self::receiver_lla(x);
        for (j, &i) in idx.iter().enumerate() {
            let (pred, e, _) = self.predict(x, i, lla);
            for c in 0..3 {
                b[(j, c)] = -e[c];
            }
            b[(j, 3 + self.col[i])] = 1.0;
            l[j] = self.rho[i] - pred;
        }
        (b, l)
    }
}

/// The geometry with its unknowns `[x, y, z, clocks…]`, as the exclusion loop solves it.
struct SppModel<'a> {
    geo: SppGeometry<'a>,
    x: Vec<f64>,
    x0: Vec<f64>,
}

impl FdeModel for SppModel<'_> {
    fn unknowns(&self) -> usize {
        3 + self.geo.n_clk
    }

    fn solve(
        &mut self,
        idx: &[usize],
        dinv: &DMatrix<f64>,
        cfg: &FdeConfig,
    ) -> Option<(DMatrix<f64>, DVector<f64>)> {
        self.x.clone_from(&self.x0);
        let geo = &self.geo;
        gauss_newton(
            &mut self.x,
            |x| geo.linearise(x, idx),
            dinv,
            cfg.max_iterations,
            SPP_TOLERANCE,
        )
    }

    fn solution(&self) -> DVector<f64> {
        DVector::from_vec(self.x.clone())
    }
}

/// A solution's position (ECEF, m) and clocks per system (m).
type LastFix = (Vector3<f64>, Vec<(Sys, f64)>);

/// Carries the last solution from one chunk of epochs to the next.
#[derive(Debug, Clone, Default)]
pub struct SppState {
    last: Option<LastFix>,
    detectors: BTreeMap<Sat, SatDetectors>,
}

struct Candidate {
    /// Recorded C/N0 (dB-Hz; NaN without one).
    cn0: f64,
    sat: Sat,
    pos: Vector3<f64>,
    rho_c: f64,
    ura: f64,
    iono_scale: f64,
    row: usize,
}

/// The systems both files let a solution use, whether asked for or not: with pseudoranges
/// on a first-band code ([`super::signals::priority`]) in the observation file and with
/// ephemerides in the navigation file, in column order.
pub fn systems_in_files(obs: &ObsData, nav: &NavData) -> Vec<Sys> {
    let n = super::signals::counts(obs);
    Sys::POSITIONING
        .into_iter()
        .filter(|s| {
            super::signals::priority(*s)
                .iter()
                .any(|c| n.contains_key(&(s.letter(), c.to_string())))
        })
        .filter(|s| nav.ephemerides.keys().any(|sat| sat.sys == *s))
        .collect()
}

/// Solve the epochs `epochs` (ascending indices; those past the file's end are ignored) of
/// `obs` with `nav`, appending to `out`. `t0` is the first epoch's
/// time (faults count from it); `state` carries the start position across calls.
#[allow(clippy::too_many_arguments)]
pub fn solve(
    obs: &ObsData,
    nav: &NavData,
    cfg: &SppConfig,
    faults: &[InjectedFault],
    epochs: impl Iterator<Item = usize>,
    state: &mut SppState,
    out: &mut SppRun,
    cancel: &Cancel,
) -> Result<()> {
    cfg.validate()?;
    for f in faults {
        f.validate()?;
    }
    let Some(first) = obs.epochs.first() else {
        return Ok(());
    };
    let t0 = first.time;
    let codes: Vec<(Sys, Option<u16>, f64, Option<u16>)> = cfg
        .systems
        .iter()
        .map(|&s| {
            let code = cfg.code(s).unwrap_or("C1C");
            let f = frequency(s, code).unwrap_or(F_L1);
            let snr = obs.code_index(&format!("S{}", code.get(1..).unwrap_or("")));
            (s, obs.code_index(code), (F_L1 / f).powi(2), snr)
        })
        .collect();
    let klob = if cfg.ionosphere {
        Some(nav.klobuchar.unwrap_or([0.0; 8]))
    } else {
        None
    };
    let n_epochs = obs.epochs.len();
    // Without exclusion the loop still reports the global test, with a w-test that never fires.
    let no_exclusion;
    let fde_cfg = if cfg.exclude {
        &cfg.fde
    } else {
        no_exclusion = FdeConfig::new(cfg.fde.alpha, Some(f64::MAX))?;
        &no_exclusion
    };
    for ei in epochs.take_while(|&e| e < n_epochs) {
        cancel.check()?;
        let ep = &obs.epochs[ei];
        let tau = ep.time.diff(&t0);
        let mut cands: Vec<Candidate> = Vec::new();
        let mut faulty = Vec::new();
        let first_row = out.sats.len();
        for o in &ep.obs {
            let Some(&(_, _, scale, snr)) = codes
                .iter()
                .find(|(s, c, _, _)| *s == o.sat.sys && *c == Some(o.code))
            else {
                continue;
            };
            // A blank (zero) or unreadable pseudorange is no observation. Any other value, however
            // gross (negative, 9e9 m), is one: it is tested and excluded by the FDE like an
            // injected fault (its satellite placed at a nominal travel time), so it is recorded
            // in the satellite rows and counted among the exclusions, never dropped unseen.
            if o.value == 0.0 || !o.value.is_finite() {
                continue;
            }
            let fault: f64 = faults
                .iter()
                .filter(|f| f.sat == o.sat)
                .map(|f| f.offset(tau))
                .sum();
            if faults
                .iter()
                .any(|f| f.sat == o.sat && tau >= f.start && tau < f.end)
            {
                faulty.push(o.sat);
            }
            let rho = o.value + fault;
            let row = out.sats.len();
            let mut sr = SatRow {
                epoch: ei,
                sat: o.sat,
                elevation: f64::NAN,
                azimuth: f64::NAN,
                residual: f64::NAN,
                w: f64::NAN,
                mdb: f64::NAN,
                sigma: f64::NAN,
                iono: f64::NAN,
                iono_sigma: f64::NAN,
                tropo: f64::NAN,
                cn0: f64::NAN,
                fault,
                sat_pos: Vector3::repeat(f64::NAN),
                sat_clock: f64::NAN,
                seq: SeqOutput::NONE,
                status: SatStatus::Unsolved,
            };
            let ephs = nav
                .ephemerides
                .get(&o.sat)
                .map(Vec::as_slice)
                .unwrap_or(&[]);
            match select(ephs, &ep.time) {
                Err(p) => {
                    sr.status = match p {
                        EphProblem::Missing => SatStatus::NoEphemeris,
                        EphProblem::Unhealthy => SatStatus::Unhealthy,
                        EphProblem::Implausible => SatStatus::BadEphemeris,
                    };
                    out.sats.push(sr);
                }
                Ok(eph) => {
                    // A pseudorange no receiver can measure (a tracking glitch, an injected
                    // gross fault) would put the satellite at a meaningless transmission
                    // time; its position is taken at a nominal travel time instead and the
                    // observation is left to the FDE, which excludes it.
                    let rho_tx = if (1e7..=1e8).contains(&rho) {
                        rho
                    } else {
                        NOMINAL_RANGE
                    };
                    let ttx = eph.transmission_time(&ep.time, rho_tx);
                    let st = eph.state(&ttx);
                    let r = st.pos.norm();
                    if !(r > 1e7 && r < 6e7 && st.clock.is_finite() && st.clock.abs() < 1.0) {
                        // A record that parses but gives no usable orbit or clock.
                        sr.status = SatStatus::BadEphemeris;
                        out.sats.push(sr);
                        continue;
                    }
                    sr.sat_pos = st.pos;
                    sr.sat_clock = st.clock;
                    out.sats.push(sr);
                    let cn0 = snr
                        .and_then(|c| ep.obs.iter().find(|x| x.sat == o.sat && x.code == c))
                        .map(|x| x.value)
                        .filter(|v| v.is_finite() && *v > 0.0)
                        .unwrap_or(f64::NAN);
                    out.sats[row].cn0 = cn0;
                    cands.push(Candidate {
                        cn0,
                        sat: o.sat,
                        pos: st.pos,
                        rho_c: rho + C * st.clock - C * eph.tgd,
                        ura: eph.accuracy,
                        iono_scale: scale,
                        row,
                    });
                }
            }
        }
        let mut sol = solve_epoch(cfg, fde_cfg, klob.as_ref(), ep.time, &cands, state, out)?;
        sol.faulty = faulty;
        out.epochs.push(sol);
        // Sequential detectors: satellites with a residual step theirs; the others restart.
        let mut seen = Vec::new();
        for row in &mut out.sats[first_row..] {
            if !row.residual.is_finite() || !(row.sigma > 0.0) {
                continue;
            }
            let det = match state.detectors.entry(row.sat) {
                Entry::Occupied(e) => e.into_mut(),
                Entry::Vacant(v) => v.insert(SatDetectors::new(&cfg.sequential)?),
            };
            row.seq = det.step(row.residual, &cfg.sequential);
            seen.push(row.sat);
        }
        state.detectors.retain(|s, _| seen.contains(s));
    }
    Ok(())
}

/// The positioning systems among the candidates `i` with `keep(i)` (their clock columns, in
/// the order GPS, Galileo, BeiDou, QZSS) and each candidate's column (0 for a system not kept).
fn clock_columns(cands: &[Candidate], keep: impl Fn(usize) -> bool) -> (Vec<Sys>, Vec<usize>) {
    let systems: Vec<Sys> = Sys::POSITIONING
        .iter()
        .copied()
        .filter(|s| (0..cands.len()).any(|i| keep(i) && cands[i].sat.sys == *s))
        .collect();
    let col = cands
        .iter()
        .map(|c| systems.iter().position(|s| *s == c.sat.sys).unwrap_or(0))
        .collect();
    (systems, col)
}

fn solve_epoch(
    cfg: &SppConfig,
    fde_cfg: &FdeConfig,
    klob: Option<&Klobuchar>,
    time: GpsTime,
    cands: &[Candidate],
    state: &mut SppState,
    out: &mut SppRun,
) -> Result<EpochSolution> {
    let n = cands.len();
    let sat: Vec<Vector3<f64>> = cands.iter().map(|c| c.pos).collect();
    let rho: Vec<f64> = cands.iter().map(|c| c.rho_c).collect();
    let iono_scale: Vec<f64> = cands.iter().map(|c| c.iono_scale).collect();
    let mut empty = EpochSolution {
        time,
        position: None,
        clocks: Vec::new(),
        fde: FdeOutcome::empty(n),
        excluded: Vec::new(),
        faulty: Vec::new(),
        used: 0,
    };
    // The model without atmosphere; each use below sets its clock columns.
    let uncorrected = SppGeometry {
        sat: &sat,
        rho: &rho,
        col: &[],
        iono_scale: &iono_scale,
        n_clk: 0,
        klob: None,
        sow: time.sow,
        trop: false,
    };
    // Start position: the last solution, else an uncorrected fix from the Earth's centre.
    let r0 = match &state.last {
        Some((p, _)) => *p,
        None => {
            // The coarse fix uses the pseudoranges a receiver can measure (1e7 … 1e8 m); a gross
            // one (negative, 9e9 m) would stop it, and is left to the FDE at the fine fix.
            let measurable = |i: usize| (1e7..=1e8).contains(&cands[i].rho_c);
            let (systems, col) = clock_columns(cands, measurable);
            let u = 3 + systems.len();
            if n < u {
                empty.fde.reason = format!(
                    "{n} satellites with ephemerides; at least {u} are needed for a first fix"
                );
                return Ok(empty);
            }
            let geo = SppGeometry {
                col: &col,
                n_clk: systems.len(),
                ..uncorrected
            };
            let mut coarse = SppModel {
                geo,
                x: vec![0.0; u],
                x0: vec![0.0; u],
            };
            let idx: Vec<usize> = (0..n).filter(|&i| measurable(i)).collect();
            let m = idx.len();
            if m < u
                || coarse
                    .solve(&idx, &DMatrix::identity(m, m), &cfg.fde)
                    .is_none()
            {
                empty.fde.reason = "no first fix (singular geometry or no convergence)".into();
                return Ok(empty);
            }
            Vector3::new(coarse.x[0], coarse.x[1], coarse.x[2])
        }
    };
    // Elevation mask and weights at the start position.
    let (lat, lon, h) = ecef_to_lla(&r0);
    let mut usable = vec![false; n];
    let mut sigma = vec![1.0; n];
    for (i, c) in cands.iter().enumerate() {
        let (el, az) = elevation_azimuth(&r0, lat, lon, &c.pos);
        let row = &mut out.sats[c.row];
        row.elevation = el;
        row.azimuth = az;
        if el < cfg.mask {
            row.status = SatStatus::BelowMask;
            continue;
        }
        usable[i] = true;
        let s = el.sin();
        let iono = klob.map_or(0.0, |k| {
            klobuchar(k, time.sow, lat, lon, h, az, el) * c.iono_scale
        });
        let (a, b) = cfg.noise;
        let ura = if c.ura.is_finite() { c.ura } else { 0.0 };
        let var = match cfg.weighting {
            Weighting::Elevation => a * a + b * b / (s * s),
            Weighting::Cn0 { reference, slope } => {
                let f = if c.cn0.is_finite() {
                    10f64.powf(slope * (reference - c.cn0) / 10.0)
                } else {
                    1.0
                };
                (a * a + b * b / (s * s)) * f
            }
            Weighting::Rtklib => {
                let mut v = a * a + b * b / s + ura * ura + 0.09 + (0.5 * iono).powi(2);
                if cfg.troposphere {
                    v += (0.3 / (s + 0.1)).powi(2);
                }
                v
            }
        };
        let factor = cfg
            .factors
            .iter()
            .find(|(s, _)| *s == c.sat.sys)
            .map_or(1.0, |f| f.1);
        sigma[i] = factor * var.sqrt();
        row.sigma = sigma[i];
    }
    // Clock columns of the systems with a usable satellite; clocks start from the last fix.
    let (systems, col) = clock_columns(cands, |i| usable[i]);
    let mut x0 = r0.as_slice().to_vec();
    x0.extend(systems.iter().map(|s| {
        state
            .last
            .as_ref()
            .and_then(|(_, c)| c.iter().find(|(cs, _)| cs == s).map(|c| c.1))
            .unwrap_or(0.0)
    }));
    let geo = SppGeometry {
        col: &col,
        n_clk: systems.len(),
        klob,
        trop: cfg.troposphere,
        ..uncorrected
    };
    let mut model = SppModel {
        geo,
        x: x0.clone(),
        x0,
    };
    let cov = ObsCov::Sigma(sigma);
    let outcome = fde(&mut model, &cov, &usable, None, fde_cfg)?;
    let mut sol = empty;
    sol.excluded = outcome.excluded.iter().map(|&i| cands[i].sat).collect();
    if let Some(x) = &outcome.solution {
        let p = Vector3::new(x[0], x[1], x[2]);
        let clocks: Vec<(Sys, f64)> = systems
            .iter()
            .enumerate()
            .map(|(j, s)| (*s, x[3 + j]))
            .collect();
        let w = outcome.w_with_excluded();
        let (lat, lon, _) = ecef_to_lla(&p);
        let lla = SppGeometry::receiver_lla(x.as_slice());
        for (i, c) in cands.iter().enumerate() {
            let row = &mut out.sats[c.row];
            if !usable[i] {
                continue;
            }
            let (pred, _, extra) = model.geo.predict(x.as_slice(), i, lla);
            row.residual = rho[i] - pred;
            row.iono = extra[0];
            row.iono_sigma = klobuchar_residual_sigma(lat, lon, extra[3], extra[2]) * c.iono_scale;
            row.tropo = extra[1];
            row.w = w[i];
            row.mdb = outcome.mdb[i];
            row.status = if outcome.excluded.contains(&i) {
                SatStatus::Excluded
            } else {
                SatStatus::Used
            };
        }
        sol.used = (0..n)
            .filter(|&i| usable[i] && !outcome.excluded.contains(&i))
            .count();
        sol.position = Some(p);
        sol.clocks = clocks.clone();
        state.last = Some((p, clocks));
    }
    sol.fde = outcome;
    Ok(sol)
}

#[cfg(test)]
#[path = "spp_tests.rs"]
mod tests;
