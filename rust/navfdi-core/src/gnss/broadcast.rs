//! Broadcast ephemerides: GPS time, Keplerian satellite positions and clocks (GPS, Galileo,
//! BeiDou, QZSS), ephemeris selection and health.
//!
//! Equations (IS-GPS-200 §20.3.3.4.3; Galileo OS-SIS-ICD §5.1.1; BeiDou ICD B1I §5.2.4, with
//! the GEO rotation for C01–C05 and C59–C63), constants per system as RTKLIB's `eph2pos`, so
//! positions compare with RTKLIB to well under a millimetre:
//!
//! * `tₖ = t − t_oe`, `n = √(μ/A³) + Δn`, `M = M₀ + n tₖ`, Kepler `E − e sin E = M` (Newton),
//!   `ν = atan2(√(1−e²) sin E, cos E − e)`, `Φ = ν + ω`, harmonic corrections
//!   `δu, δr, δi` from `C_us, C_uc, C_rs, C_rc, C_is, C_ic` at `2Φ`;
//! * `Ω = Ω₀ + (Ω̇ − ω_e) tₖ − ω_e t_oe,sow` (GEO: `Ω₀ + Ω̇ tₖ − ω_e t_oe,sow`, then the
//!   rotation by `ω_e tₖ` about z and by −5° about x);
//! * clock `δt = a₀ + a₁ (t − t_oc) + a₂ (t − t_oc)²` (computed here for t before t_oc too)
//!   plus the relativistic term `−2 √(μ A) e sin E / c²`.
//!
//! Times are [`GpsTime`] (GPS week and seconds of week, GPST). BeiDou ephemerides are in BDT
//! (= GPST − 14 s); their `t_oe,sow` stays in BDT for the `ω_e t_oe` term, as in the ICD.

use super::C;
use nalgebra::Vector3;

/// Seconds in a week.
pub const WEEK: f64 = 604_800.0;

/// A time in GPST: week number and seconds of week (exact to ~1e-10 s over a week, unlike one
/// f64 of seconds since 1980).
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct GpsTime {
    /// GPS week (weeks since 1980-01-06, no roll-over).
    pub week: i64,
    /// Seconds of week, in [0, 604800).
    pub sow: f64,
}

impl GpsTime {
    /// A normalised time (sow folded into [0, 604800)).
    pub fn new(week: i64, sow: f64) -> Self {
        let w = (sow / WEEK).floor();
        GpsTime {
            week: week + w as i64,
            sow: sow - w * WEEK,
        }
    }

    /// `self − other` (s).
    pub fn diff(&self, other: &GpsTime) -> f64 {
        (self.week - other.week) as f64 * WEEK + (self.sow - other.sow)
    }

    /// `self + dt` (s).
    pub fn add(&self, dt: f64) -> GpsTime {
        GpsTime::new(self.week, self.sow + dt)
    }

    /// Seconds since 1980-01-06 00:00:00 GPST (one f64, ~0.2 µs resolution: for output).
    pub fn seconds(&self) -> f64 {
        self.week as f64 * WEEK + self.sow
    }
}

/// A satellite system of real data.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Sys {
    /// GPS (`G`).
    Gps,
    /// Galileo (`E`).
    Galileo,
    /// BeiDou (`C`).
    BeiDou,
    /// QZSS (`J`).
    Qzss,
    /// GLONASS (`R`): read, not positioned (FDMA ephemerides are not Keplerian).
    Glonass,
    /// SBAS (`S`), IRNSS/NavIC (`I`) and anything else: read, not positioned.
    Other,
}

impl Sys {
    /// The systems a single-point solution can use, in column order.
    pub const POSITIONING: [Sys; 4] = [Sys::Gps, Sys::Galileo, Sys::BeiDou, Sys::Qzss];

    /// RINEX letter.
    pub fn letter(self) -> char {
        match self {
            Sys::Gps => 'G',
            Sys::Galileo => 'E',
            Sys::BeiDou => 'C',
            Sys::Qzss => 'J',
            Sys::Glonass => 'R',
            Sys::Other => '?',
        }
    }

    /// From a RINEX letter (None for letters that are not satellite systems).
    pub fn from_letter(c: char) -> Option<Sys> {
        Some(match c.to_ascii_uppercase() {
            'G' => Sys::Gps,
            'E' => Sys::Galileo,
            'C' => Sys::BeiDou,
            'J' => Sys::Qzss,
            'R' => Sys::Glonass,
            'S' | 'I' => Sys::Other,
            _ => return None,
        })
    }

    /// Name for messages.
    pub fn name(self) -> &'static str {
        match self {
            Sys::Gps => "GPS",
            Sys::Galileo => "Galileo",
            Sys::BeiDou => "BeiDou",
            Sys::Qzss => "QZSS",
            Sys::Glonass => "GLONASS",
            Sys::Other => "other",
        }
    }

    /// (μ (m³/s²), ω_e (rad/s)) as the system's ICD (and RTKLIB) use them.
    pub fn constants(self) -> (f64, f64) {
        match self {
            Sys::Gps | Sys::Qzss => (3.986_005_0e14, 7.292_115_146_7e-5),
            Sys::Galileo => (3.986_004_418e14, 7.292_115_146_7e-5),
            Sys::BeiDou => (3.986_004_418e14, 7.292_115e-5),
            Sys::Glonass | Sys::Other => (3.986_004_418e14, 7.292_115e-5),
        }
    }

    /// Longest |t − t_oe| (s) for which an ephemeris is used (RTKLIB's MAXDTOE values).
    pub fn max_age(self) -> f64 {
        match self {
            Sys::Galileo => 14_400.0,
            Sys::BeiDou => 21_600.0,
            _ => 7_200.0,
        }
    }
}

/// A satellite: system and PRN (`G05`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Sat {
    /// System.
    pub sys: Sys,
    /// PRN (the number in the name).
    pub prn: u8,
    /// The RINEX letter (kept for systems grouped as [`Sys::Other`]).
    pub letter: char,
}

impl Sat {
    /// A satellite from its RINEX letter and PRN (None for an unknown letter).
    pub fn new(letter: char, prn: u8) -> Option<Sat> {
        Sys::from_letter(letter).map(|sys| Sat {
            sys,
            prn,
            letter: letter.to_ascii_uppercase(),
        })
    }

    /// Parse `G05` / `G5` / `E11`.
    pub fn parse(s: &str) -> Option<Sat> {
        let s = s.trim();
        let mut ch = s.chars();
        let letter = ch.next()?;
        let prn: u8 = ch.as_str().trim().parse().ok()?;
        Sat::new(letter, prn)
    }

    /// Name as in RINEX (`G05`).
    pub fn name(&self) -> String {
        format!("{}{:02}", self.letter, self.prn)
    }

    /// A BeiDou geostationary satellite (C01–C05, C59–C63).
    pub fn is_bds_geo(&self) -> bool {
        self.sys == Sys::BeiDou && (self.prn <= 5 || self.prn >= 59)
    }
}

/// A broadcast Keplerian ephemeris (one RINEX navigation record).
#[derive(Debug, Clone, PartialEq)]
pub struct Ephemeris {
    /// Satellite.
    pub sat: Sat,
    /// Time of clock (GPST).
    pub toc: GpsTime,
    /// Time of ephemeris (GPST).
    pub toe: GpsTime,
    /// t_oe as seconds of week in the system's own time (BDT for BeiDou), for `ω_e t_oe`.
    pub toe_sow: f64,
    /// Clock polynomial a₀ (s), a₁ (s/s), a₂ (s/s²).
    pub af: [f64; 3],
    /// √A (√m).
    pub sqrt_a: f64,
    /// Eccentricity.
    pub e: f64,
    /// Inclination at t_oe (rad).
    pub i0: f64,
    /// Longitude of the ascending node at the week epoch (rad).
    pub omega0: f64,
    /// Argument of perigee (rad).
    pub omega: f64,
    /// Mean anomaly at t_oe (rad).
    pub m0: f64,
    /// Mean motion difference (rad/s).
    pub delta_n: f64,
    /// Rate of inclination (rad/s).
    pub idot: f64,
    /// Rate of right ascension (rad/s).
    pub omega_dot: f64,
    /// Harmonic corrections `[cuc, cus, crc, crs, cic, cis]` (rad, rad, m, m, rad, rad).
    pub harmonics: [f64; 6],
    /// Group delay used with the first-frequency code (s): TGD (GPS, QZSS), BGD E5b/E1
    /// (Galileo I/NAV; E5a/E1 for F/NAV), TGD1 (BeiDou B1I).
    pub tgd: f64,
    /// Raw health word of the record.
    pub health: u32,
    /// Whether the health word marks the signal used (E1/L1/B1I) unusable.
    pub unhealthy: bool,
    /// User range accuracy (m): GPS/QZSS URA, Galileo SISA, BeiDou URA; NaN when unknown.
    pub accuracy: f64,
    /// Galileo: true for an F/NAV record (I/NAV is preferred for E1).
    pub fnav: bool,
    /// Issue of data (IODE / IODnav / AODE), for reference.
    pub iod: f64,
}

/// Satellite state from an ephemeris.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SatState {
    /// ECEF position at transmission, in the Earth-fixed frame of that instant (m).
    pub pos: Vector3<f64>,
    /// Satellite clock offset incl. the relativistic term (s).
    pub clock: f64,
}

/// Solve Kepler's equation `E − e sin E = M` by Newton's method.
fn eccentric_anomaly(m: f64, e: f64) -> f64 {
    let mut ek = m;
    for _ in 0..30 {
        let step = (ek - e * ek.sin() - m) / (1.0 - e * ek.cos());
        ek -= step;
        if step.abs() < 1e-14 {
            break;
        }
    }
    ek
}

const SIN_M5: f64 = -0.087_155_742_747_658_2; // sin(−5°)
const COS_M5: f64 = 0.996_194_698_091_745_6; // cos(−5°)

impl Ephemeris {
    /// Clock polynomial at `t` (s), without the relativistic term.
    pub fn clock_poly(&self, t: &GpsTime) -> f64 {
        let dt = t.diff(&self.toc);
        self.af[0] + self.af[1] * dt + self.af[2] * dt * dt
    }

    /// Position and clock at transmission time `t` (GPST).
    pub fn state(&self, t: &GpsTime) -> SatState {
        let (mu, we) = self.sat.sys.constants();
        let a = self.sqrt_a * self.sqrt_a;
        let tk = t.diff(&self.toe);
        let n = (mu / (a * a * a)).sqrt() + self.delta_n;
        let m = self.m0 + n * tk;
        let ek = eccentric_anomaly(m, self.e);
        let (sin_e, cos_e) = ek.sin_cos();
        let nu = ((1.0 - self.e * self.e).sqrt() * sin_e).atan2(cos_e - self.e);
        let phi = nu + self.omega;
        let (s2, c2) = (2.0 * phi).sin_cos();
        let [cuc, cus, crc, crs, cic, cis] = self.harmonics;
        let u = phi + cus * s2 + cuc * c2;
        let r = a * (1.0 - self.e * cos_e) + crs * s2 + crc * c2;
        let i = self.i0 + cis * s2 + cic * c2 + self.idot * tk;
        let (x, y) = (r * u.cos(), r * u.sin());
        let (sin_i, cos_i) = i.sin_cos();
        let pos = if self.sat.is_bds_geo() {
            let o = self.omega0 + self.omega_dot * tk - we * self.toe_sow;
            let (so, co) = o.sin_cos();
            let xg = x * co - y * cos_i * so;
            let yg = x * so + y * cos_i * co;
            let zg = y * sin_i;
            let (sino, coso) = (we * tk).sin_cos();
            Vector3::new(
                xg * coso + yg * sino * COS_M5 + zg * sino * SIN_M5,
                -xg * sino + yg * coso * COS_M5 + zg * coso * SIN_M5,
                -yg * SIN_M5 + zg * COS_M5,
            )
        } else {
            let o = self.omega0 + (self.omega_dot - we) * tk - we * self.toe_sow;
            let (so, co) = o.sin_cos();
            Vector3::new(x * co - y * cos_i * so, x * so + y * cos_i * co, y * sin_i)
        };
        let rel = -2.0 * (mu * a).sqrt() * self.e * sin_e / (C * C);
        SatState {
            pos,
            clock: self.clock_poly(t) + rel,
        }
    }

    /// Velocity (ECEF, m/s) and clock drift (s/s) at `t`: central differences of
    /// [`Ephemeris::state`] over ±0.5 s.
    pub fn rates(&self, t: &GpsTime) -> (Vector3<f64>, f64) {
        let (a, b) = (self.state(&t.add(-0.5)), self.state(&t.add(0.5)));
        (b.pos - a.pos, b.clock - a.clock)
    }

    /// Transmission time for a signal received at `t_rx` with pseudorange `rho` (m):
    /// `t_rx − ρ/c`, then corrected by the satellite clock polynomial (two fixed-point
    /// iterations, as RTKLIB's `eph2clk`).
    pub fn transmission_time(&self, t_rx: &GpsTime, rho: f64) -> GpsTime {
        let t0 = t_rx.add(-rho / C);
        let ts = t0.diff(&self.toc);
        let mut t = ts;
        for _ in 0..2 {
            t = ts - (self.af[0] + self.af[1] * t + self.af[2] * t * t);
        }
        let dt = self.af[0] + self.af[1] * t + self.af[2] * t * t;
        t0.add(-dt)
    }
}

/// Why a satellite has no usable ephemeris at a time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EphProblem {
    /// No record for this satellite (or none within the system's maximum age).
    Missing,
    /// The nearest usable record marks the satellite unhealthy.
    Unhealthy,
    /// Every record in range has an implausible orbit or clock ([`Ephemeris::plausible`]).
    Implausible,
}

/// Pick the ephemeris of `sat` for time `t` from `ephs` (all of that satellite, any order):
/// the healthy record with the nearest t_oe within the system's maximum age, Galileo I/NAV
/// before F/NAV. When only unhealthy records are in range: [`EphProblem::Unhealthy`].
pub fn select<'a>(ephs: &'a [Ephemeris], t: &GpsTime) -> Result<&'a Ephemeris, EphProblem> {
    let in_range = |e: &&Ephemeris| t.diff(&e.toe).abs() <= e.sat.sys.max_age() + 1.0;
    let best = |healthy: bool, fnav: bool| {
        ephs.iter()
            .filter(in_range)
            .filter(|e| e.plausible())
            .filter(|e| e.unhealthy != healthy && e.fnav == fnav)
            .min_by(|a, b| t.diff(&a.toe).abs().total_cmp(&t.diff(&b.toe).abs()))
    };
    if let Some(e) = best(true, false).or_else(|| best(true, true)) {
        return Ok(e);
    }
    if ephs.iter().any(|e| in_range(&e) && e.plausible()) {
        Err(EphProblem::Unhealthy)
    } else if ephs.iter().any(|e| in_range(&e)) {
        Err(EphProblem::Implausible)
    } else {
        Err(EphProblem::Missing)
    }
}

/// Largest broadcast clock bias accepted (s): twice the GPS and BeiDou `af0` field range
/// (±2⁻¹⁰ s); a corrupt record (1 s: 3·10⁸ m) would otherwise defeat the first fix of every
/// epoch, while a bias within it (1 ms: 300 km) is left to the FDE, which excludes it.
pub const MAX_CLOCK_BIAS: f64 = 2e-3;

impl Ephemeris {
    /// Whether the record's orbit and clock could be a navigation satellite's: every field
    /// finite, `√A` in [4000, 8000] √m (GPS 5154, Galileo 5440, BeiDou MEO 5282, GEO/IGSO and
    /// QZSS 6493), eccentricity in [0, 0.1), `|af0|` ≤ [`MAX_CLOCK_BIAS`], `|af1|` ≤ 1e-7 s/s.
    /// Implausible records are never selected (the satellite is reported `bad_ephemeris`).
    pub fn plausible(&self) -> bool {
        let finite = self.af.iter().all(|v| v.is_finite())
            && [
                self.sqrt_a,
                self.e,
                self.i0,
                self.omega0,
                self.omega,
                self.m0,
                self.delta_n,
                self.idot,
                self.omega_dot,
                self.toe_sow,
            ]
            .iter()
            .all(|v| v.is_finite())
            && self.harmonics.iter().all(|v| v.is_finite());
        finite
            && (4000.0..=8000.0).contains(&self.sqrt_a)
            && (0.0..0.1).contains(&self.e)
            && self.af[0].abs() <= MAX_CLOCK_BIAS
            && self.af[1].abs() <= 1e-7
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_and_names() {
        let t = GpsTime::new(2320, 604_799.5).add(1.0);
        assert_eq!(t.week, 2321);
        assert!((t.sow - 0.5).abs() < 1e-12);
        assert!((t.diff(&GpsTime::new(2320, 0.0)) - 604_800.5).abs() < 1e-9);
        assert_eq!(Sat::parse("G5").unwrap().name(), "G05");
        assert!(Sat::parse("C60").unwrap().is_bds_geo());
        assert!(Sat::parse("X01").is_none() && Sat::parse("G").is_none());
    }

    #[test]
    fn kepler_solution_satisfies_the_equation() {
        for &(m, e) in &[(0.1, 0.01), (3.0, 0.2), (-2.0, 0.7)] {
            let ek = eccentric_anomaly(m, e);
            assert!((ek - e * ek.sin() - m).abs() < 1e-13);
        }
    }
}
