//! Nominal constellations on circular orbits.
//!
//! GPS is modelled as a Walker delta pattern 24/6/1 (24 satellites in 6 planes, phasing 1) at
//! 55° inclination and 26 560 km orbit radius; Galileo as Walker 24/3/1 at 56° and 29 600 km.
//! These are the nominal shapes of both systems, not their broadcast ephemerides (real
//! ephemerides come from RINEX navigation files). Satellites are named `G01`–`G24` and
//! `E01`–`E24`, plane by plane.
//!
//! Orbit: argument of latitude `u(t) = u₀ + n t` with mean motion `n = sqrt(μ / a³)`, node
//! longitude in the Earth-fixed frame `Ω(t) = Ω₀ − ω_ie t`; position
//! `r = a [cos u cos Ω − sin u cos i sin Ω, cos u sin Ω + sin u cos i cos Ω, sin u sin i]` and
//! velocity `ṙ = ∂r/∂u · n − ∂r/∂Ω · ω_ie` (ECEF, so the velocity includes the Earth's
//! rotation).

use crate::ins::earth::OMEGA_IE;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// Earth's gravitational constant μ (m³/s², WGS-84 / IS-GPS-200).
pub const MU: f64 = 3.986_004_418e14;

/// A satellite system.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum System {
    /// GPS (names `Gnn`).
    Gps,
    /// Galileo (names `Enn`).
    Galileo,
}

/// One satellite on a circular orbit.
#[derive(Debug, Clone, PartialEq)]
pub struct Orbit {
    /// Name, e.g. `G03`.
    pub name: String,
    /// System.
    pub system: System,
    /// Orbit radius a (m).
    pub radius: f64,
    /// Inclination i (rad).
    pub inclination: f64,
    /// Longitude of the ascending node at t = 0 in the Earth-fixed frame Ω₀ (rad).
    pub node: f64,
    /// Argument of latitude at t = 0, u₀ (rad).
    pub arg_lat: f64,
}

impl Orbit {
    /// Mean motion n (rad/s).
    pub fn mean_motion(&self) -> f64 {
        (MU / self.radius.powi(3)).sqrt()
    }

    /// ECEF position (m) and velocity (m/s) at time `t` (s).
    pub fn ecef(&self, t: f64) -> (Vector3<f64>, Vector3<f64>) {
        let n = self.mean_motion();
        let u = self.arg_lat + n * t;
        let om = self.node - OMEGA_IE * t;
        let (su, cu) = u.sin_cos();
        let (so, co) = om.sin_cos();
        let (si, ci) = self.inclination.sin_cos();
        let a = self.radius;
        let r = a * Vector3::new(cu * co - su * ci * so, cu * so + su * ci * co, su * si);
        let dr_du = a * Vector3::new(-su * co - cu * ci * so, -su * so + cu * ci * co, cu * si);
        let dr_dom = a * Vector3::new(-cu * so - su * ci * co, cu * co - su * ci * so, 0.0);
        (r, dr_du * n - dr_dom * OMEGA_IE)
    }
}

/// A Walker delta pattern `total/planes/phasing` at `inclination` (rad) and `radius` (m); names
/// `{prefix}01…`. Plane j has node `j·2π/planes`; satellite k of plane j has argument of
/// latitude `k·2π/(total/planes) + j·phasing·2π/total`.
pub fn walker(
    system: System,
    prefix: char,
    total: usize,
    planes: usize,
    phasing: usize,
    inclination: f64,
    radius: f64,
) -> Vec<Orbit> {
    let per = total / planes;
    let tau = std::f64::consts::TAU;
    let mut out = Vec::with_capacity(total);
    for j in 0..planes {
        for k in 0..per {
            out.push(Orbit {
                name: format!("{prefix}{:02}", out.len() + 1),
                system,
                radius,
                inclination,
                node: j as f64 * tau / planes as f64,
                arg_lat: k as f64 * tau / per as f64
                    + j as f64 * phasing as f64 * tau / total as f64,
            });
        }
    }
    out
}

/// Nominal GPS: Walker 24/6/1, 55°, 26 560 km.
pub fn gps() -> Vec<Orbit> {
    walker(System::Gps, 'G', 24, 6, 1, 55f64.to_radians(), 26_560_000.0)
}

/// Nominal Galileo: Walker 24/3/1, 56°, 29 600 km.
pub fn galileo() -> Vec<Orbit> {
    walker(
        System::Galileo,
        'E',
        24,
        3,
        1,
        56f64.to_radians(),
        29_600_000.0,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gps_orbits() {
        let c = gps();
        assert_eq!(c.len(), 24);
        assert_eq!(c[2].name, "G03");
        // Half a sidereal day period: 11 h 58 min.
        let period = std::f64::consts::TAU / c[0].mean_motion();
        assert!((period - 43_082.0).abs() < 60.0, "{period}");
        // Velocity is the derivative of position (central differences).
        for s in &c[..5] {
            for &t in &[0.0, 1234.5, 40_000.0] {
                let (r, v) = s.ecef(t);
                assert!((r.norm() - s.radius).abs() < 1e-6);
                let dt = 1e-3;
                let fd = (s.ecef(t + dt).0 - s.ecef(t - dt).0) / (2.0 * dt);
                assert!((fd - v).norm() < 1e-4, "{}", (fd - v).norm());
            }
        }
        let e = galileo();
        assert_eq!(e[23].name, "E24");
    }
}
