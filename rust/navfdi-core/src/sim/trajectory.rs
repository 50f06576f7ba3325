//! Truth trajectory from flight segments.
//!
//! Kinematic model: ground speed `s`, heading `ψ` (clockwise from north) and vertical speed
//! `v_U` evolve per segment; ENU velocity `v = (s sin ψ, s cos ψ, v_U)`; position integrates on
//! the WGS-84 ellipsoid (`L̇ = v_N/(R_M+h)`, `λ̇ = v_E/((R_N+h) cos L)`, `ḣ = v_U`). Attitude:
//! yaw = heading, pitch = flight-path angle `atan2(v_U, s)`, roll = coordinated-turn bank
//! `atan(s ψ̇ / g)`. Specific force in ENU `f^n = v̇ − g^n + (2ω_ie + ω_en) × v`; in body
//! (x right, y forward, z up) `f^b = C_n^b f^n`. Body angular rate
//! `ω_ib^b = C_n^b(ω_ie + ω_en) + ω_nb^b`, with `ω_nb^b` from the attitude change over the epoch.
//! Transitions between segments are instantaneous.

use crate::ins::earth;
use crate::ins::error_model::Kinematics;
use crate::spec::{SegmentSpec, TrajectorySpec};
use nalgebra::{Matrix3, Rotation3, Vector3};

/// Truth at one epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthEpoch {
    /// Time (s).
    pub t: f64,
    /// Latitude (rad).
    pub lat: f64,
    /// Longitude (rad).
    pub lon: f64,
    /// Height (m).
    pub h: f64,
    /// ENU velocity (m/s).
    pub v: Vector3<f64>,
    /// Roll, pitch, yaw (heading, clockwise from north) (rad).
    pub euler: Vector3<f64>,
    /// Specific force in body axes (m/s²).
    pub f_b: Vector3<f64>,
    /// Angular rate ω_ib in body axes (rad/s).
    pub w_b: Vector3<f64>,
    /// Specific force in ENU (m/s²).
    pub f_n: Vector3<f64>,
    /// Body-to-ENU rotation.
    pub c_bn: Matrix3<f64>,
}

impl TruthEpoch {
    /// What the error model needs.
    pub fn kinematics(&self) -> Kinematics {
        Kinematics {
            lat: self.lat,
            h: self.h,
            v: self.v,
            f_n: self.f_n,
            c_bn: self.c_bn,
        }
    }
}

/// Body (x right, y forward, z up) to ENU rotation for roll, pitch, heading.
pub fn c_bn(roll: f64, pitch: f64, heading: f64) -> Matrix3<f64> {
    let rz = Rotation3::from_axis_angle(&Vector3::z_axis(), -heading);
    let rx = Rotation3::from_axis_angle(&Vector3::x_axis(), pitch);
    let ry = Rotation3::from_axis_angle(&Vector3::y_axis(), roll);
    (rz * rx * ry).into_inner()
}

#[derive(Debug, Clone, Copy)]
struct Motion {
    speed: f64,
    heading: f64,
    vu: f64,
    accel: f64,
    turn: f64,
}

fn motion_at(spec: &TrajectorySpec, t: f64) -> Motion {
    // Replay segments up to time t (closed form within each segment).
    let mut m = Motion {
        speed: spec.speed,
        heading: spec.heading,
        vu: 0.0,
        accel: 0.0,
        turn: 0.0,
    };
    let mut t0 = 0.0;
    let n = spec.segments.len();
    for (i, seg) in spec.segments.iter().enumerate() {
        let d = seg.duration();
        let last = i + 1 == n;
        let tau = if last { t - t0 } else { (t - t0).min(d) };
        if tau < 0.0 {
            break;
        }
        m.accel = 0.0;
        m.turn = 0.0;
        m.vu = 0.0;
        match *seg {
            SegmentSpec::Stationary { .. } => {}
            SegmentSpec::Accelerate { acceleration, .. } => {
                let dur = if last { tau.min(d) } else { tau };
                m.speed = (m.speed + acceleration * dur).max(0.0);
                if tau < d {
                    m.accel = acceleration;
                }
            }
            SegmentSpec::Climb { rate, .. } => m.vu = rate,
            SegmentSpec::Descent { rate, .. } => m.vu = -rate,
            SegmentSpec::Level { .. } => {}
            SegmentSpec::Turn { rate, .. } => {
                let dur = if last { tau.min(d) } else { tau };
                m.heading += rate * dur;
                if tau < d {
                    m.turn = rate;
                }
            }
        }
        if t - t0 < d || last {
            break;
        }
        t0 += d;
    }
    m
}

/// Truth at epochs `t_k = k·dt`, `k = 0..epochs` (an aircraft: coordinated turns bank).
pub fn generate(spec: &TrajectorySpec, dt: f64, epochs: usize) -> Vec<TruthEpoch> {
    generate_vehicle(spec, dt, epochs, true)
}

/// [`generate`] for an aircraft (`banked`: coordinated turns roll the body) or a ground
/// vehicle (`banked = false`: the body stays level in turns and the centripetal acceleration
/// is a lateral specific force, as in a car).
pub fn generate_vehicle(
    spec: &TrajectorySpec,
    dt: f64,
    epochs: usize,
    banked: bool,
) -> Vec<TruthEpoch> {
    let bank = |speed: f64, turn: f64, g: f64| {
        if banked {
            (speed * turn / g).atan()
        } else {
            0.0
        }
    };
    let (mut lat, mut lon, mut h) = (spec.latitude, spec.longitude, spec.height);
    let mut out: Vec<TruthEpoch> = Vec::with_capacity(epochs);
    let w = earth::OMEGA_IE;
    let sub = 10; // integration sub-steps per epoch
    for k in 0..epochs {
        let t = k as f64 * dt;
        let m = motion_at(spec, t);
        let v = Vector3::new(m.speed * m.heading.sin(), m.speed * m.heading.cos(), m.vu);
        let g = earth::gravity(lat, h);
        let roll = bank(m.speed, m.turn, g);
        let pitch = m.vu.atan2(m.speed.max(1e-9));
        let pitch = if m.speed < 1e-9 && m.vu == 0.0 {
            0.0
        } else {
            pitch
        };
        let c = c_bn(roll, pitch, m.heading);
        let rm = earth::r_meridian(lat) + h;
        let rn = earth::r_normal(lat) + h;
        let w_ie = Vector3::new(0.0, w * lat.cos(), w * lat.sin());
        let w_en = Vector3::new(-v.y / rm, v.x / rn, v.x * lat.tan() / rn);
        // v̇ in ENU: along-track acceleration and turn (centripetal); vertical speed is constant.
        let vdot = Vector3::new(
            m.accel * m.heading.sin() + m.speed * m.heading.cos() * m.turn,
            m.accel * m.heading.cos() - m.speed * m.heading.sin() * m.turn,
            0.0,
        );
        let f_n = vdot + Vector3::new(0.0, 0.0, g) + (2.0 * w_ie + w_en).cross(&v);
        let f_b = c.transpose() * f_n;
        // ω_nb^b from the attitude one small step ahead (finite difference).
        let eps = 1e-3;
        let m2 = motion_at(spec, t + eps);
        let roll2 = bank(m2.speed, m2.turn, g);
        let pitch2 = if m2.speed < 1e-9 && m2.vu == 0.0 {
            0.0
        } else {
            m2.vu.atan2(m2.speed.max(1e-9))
        };
        let c2 = c_bn(roll2, pitch2, m2.heading);
        let d = c.transpose() * c2; // ≈ I + [ω_nb^b ×] eps
        let w_nb = Vector3::new(
            d[(2, 1)] - d[(1, 2)],
            d[(0, 2)] - d[(2, 0)],
            d[(1, 0)] - d[(0, 1)],
        ) / (2.0 * eps);
        let w_b = c.transpose() * (w_ie + w_en) + w_nb;
        out.push(TruthEpoch {
            t,
            lat,
            lon,
            h,
            v,
            euler: Vector3::new(roll, pitch, m.heading),
            f_b,
            w_b,
            f_n,
            c_bn: c,
        });
        // Integrate position to the next epoch (sub-steps, velocity from the motion model).
        let hs = dt / sub as f64;
        for s in 0..sub {
            let ts = t + (s as f64 + 0.5) * hs;
            let ms = motion_at(spec, ts);
            let vs = Vector3::new(
                ms.speed * ms.heading.sin(),
                ms.speed * ms.heading.cos(),
                ms.vu,
            );
            let rm = earth::r_meridian(lat) + h;
            let rn = earth::r_normal(lat) + h;
            lat += vs.y / rm * hs;
            lon += vs.x / (rn * lat.cos()) * hs;
            h += vs.z * hs;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(segments: Vec<SegmentSpec>) -> TrajectorySpec {
        TrajectorySpec {
            latitude: 20f64.to_radians(),
            longitude: 110f64.to_radians(),
            height: 500.0,
            heading: 0.0,
            speed: 0.0,
            segments,
        }
    }

    #[test]
    fn segments_change_speed_height_and_heading() {
        let s = spec(vec![
            SegmentSpec::Stationary { duration: 10.0 },
            SegmentSpec::Accelerate {
                duration: 20.0,
                acceleration: 5.0,
            },
            SegmentSpec::Climb {
                duration: 50.0,
                rate: 10.0,
            },
            SegmentSpec::Turn {
                duration: 90.0,
                rate: 1f64.to_radians(),
            },
            SegmentSpec::Level { duration: 10.0 },
        ]);
        let tr = generate(&s, 1.0, 200);
        // At rest: specific force is g up, no velocity.
        assert!(tr[5].v.norm() < 1e-12);
        assert!((tr[5].f_b.z - earth::gravity(s.latitude, 500.0)).abs() < 1e-3);
        // Take-off: 100 m/s after 20 s at 5 m/s², along-track force ≈ 5 m/s².
        assert!((tr[30].v.y - 100.0).abs() < 1e-9);
        assert!((tr[20].f_b.y - 5.0).abs() < 0.01);
        // Climb: 500 m higher after 50 s at 10 m/s.
        assert!((tr[80].h - 1000.0).abs() < 1e-6);
        // Turn: heading 90° after 90 s at 1°/s, banked while turning.
        assert!((tr[170].euler.z - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        assert!(tr[120].euler.x > 0.1);
        // Angular rate in ENU: a right (clockwise) turn is −ψ̇ about up; earth and transport
        // rates add less than 1e-4 rad/s here.
        let w_n = tr[120].c_bn * tr[120].w_b;
        assert!((w_n.z + 1f64.to_radians()).abs() < 1e-4, "{w_n}");
        assert!(w_n.x.abs() < 1e-4 && w_n.y.abs() < 1e-4, "{w_n}");
        // Moving north, latitude increases.
        assert!(tr[80].lat > tr[10].lat);
    }
}
