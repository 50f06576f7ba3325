//! Strapdown mechanisation for real IMUs: attitude quaternion, velocity and position
//! integrated from angle and velocity increments in the local-level north-east-down frame,
//! with Earth rotation, transport rate, normal gravity and Coriolis, two-sample coning and
//! sculling corrections (as in Shin's and KF-GINS's mechanisation, first order in the frame
//! rotation over one sample).
//!
//! Frames: body `b` forward-right-down; navigation `n` north-east-down at the current
//! position; the IMU's own axes are rotated into the body by the mounting matrix
//! ([`mounting`]). Units: rad, m, s, m/s, rad/s, m/s².

use super::earth;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// Navigation state of a strapdown INS.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NavState {
    /// Latitude (rad).
    pub lat: f64,
    /// Longitude (rad).
    pub lon: f64,
    /// Height (m; in the datum of the position fixes the INS is aided with).
    pub h: f64,
    /// Velocity north, east, down (m/s).
    pub v: Vector3<f64>,
    /// Body-to-navigation rotation `q_b^n`.
    pub q: UnitQuaternion<f64>,
}

/// One IMU interval: angle increment (rad) and velocity increment (m/s) in body axes over
/// `dt` seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Increment {
    /// Angle increment Δθ (rad), body axes.
    pub dtheta: Vector3<f64>,
    /// Velocity increment Δv (m/s), body axes.
    pub dvel: Vector3<f64>,
    /// Length of the interval (s).
    pub dt: f64,
}

impl Increment {
    /// A zero increment (no rotation, no specific force) over `dt` s.
    pub fn zero(dt: f64) -> Self {
        Increment {
            dtheta: Vector3::zeros(),
            dvel: Vector3::zeros(),
            dt,
        }
    }
}

/// Skew-symmetric matrix `[v×]`.
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Direction cosine matrix of the Euler angles roll `r`, pitch `p`, yaw `y` (rad; the z-y-x
/// sequence): the matrix taking vectors of the rotated frame into the reference frame,
/// `C = R_z(y) R_y(p) R_x(r)`.
pub fn euler_to_dcm(r: f64, p: f64, y: f64) -> Matrix3<f64> {
    *UnitQuaternion::from_euler_angles(r, p, y)
        .to_rotation_matrix()
        .matrix()
}

/// The IMU-to-body rotation `C_imu^b` of an IMU whose axes have roll, pitch, yaw (rad) in
/// the body frame, i.e. `C_b^imu = R_z(y) R_y(p) R_x(r)` (the convention of rtklibexplorer's
/// GNSS_IMU configuration files): body = `C_b^imuᵀ` · imu.
pub fn mounting(roll: f64, pitch: f64, yaw: f64) -> Matrix3<f64> {
    euler_to_dcm(roll, pitch, yaw).transpose()
}

/// Earth-rate `ω_ie^n` and transport-rate `ω_en^n` (rad/s) in north-east-down at `s`.
pub fn frame_rates(s: &NavState) -> (Vector3<f64>, Vector3<f64>) {
    let (sl, cl) = s.lat.sin_cos();
    let rm = earth::r_meridian(s.lat) + s.h;
    let rn = earth::r_normal(s.lat) + s.h;
    let w_ie = Vector3::new(earth::OMEGA_IE * cl, 0.0, -earth::OMEGA_IE * sl);
    let w_en = Vector3::new(s.v.y / rn, -s.v.x / rm, -s.v.y * sl / (cl * rn));
    (w_ie, w_en)
}

/// Advance `s` over one IMU interval `inc`, with `prev` the previous interval's increment
/// (for the coning and sculling corrections; pass a zero increment at the start).
pub fn mechanise(s: &mut NavState, prev: &Increment, inc: &Increment) {
    let dt = inc.dt;
    if dt <= 0.0 {
        return;
    }
    let (w_ie, w_en) = frame_rates(s);
    let g = Vector3::new(0.0, 0.0, earth::gravity(s.lat, s.h));
    // Velocity: sculling-corrected Δv rotated to n, minus the n frame's rotation over dt.
    let scul = 0.5 * inc.dtheta.cross(&inc.dvel)
        + (prev.dtheta.cross(&inc.dvel) + prev.dvel.cross(&inc.dtheta)) / 12.0;
    let dv_b = inc.dvel + scul;
    let zeta = (w_ie + w_en) * dt;
    let c_bn = s.q.to_rotation_matrix();
    let dv_n = (Matrix3::identity() - 0.5 * skew(&zeta)) * (c_bn * dv_b);
    let cor = g - (2.0 * w_ie + w_en).cross(&s.v);
    let v_old = s.v;
    s.v = v_old + dv_n + cor * dt;
    // Position by the mean velocity over the interval.
    let vm = 0.5 * (v_old + s.v);
    let rm = earth::r_meridian(s.lat) + s.h;
    let h_mid = s.h - 0.5 * vm.z * dt;
    let lat_mid = s.lat + 0.5 * vm.x / rm * dt;
    let rm = earth::r_meridian(lat_mid) + h_mid;
    let rn = earth::r_normal(lat_mid) + h_mid;
    s.lat += vm.x / rm * dt;
    s.lon += vm.y / (rn * lat_mid.cos()) * dt;
    s.h -= vm.z * dt;
    // Attitude: body rotation with coning, navigation-frame rotation.
    let phi = inc.dtheta + prev.dtheta.cross(&inc.dtheta) / 12.0;
    let q_bb = UnitQuaternion::from_scaled_axis(phi);
    let q_nn = UnitQuaternion::from_scaled_axis(-zeta);
    s.q = q_nn * s.q * q_bb;
}

/// Roll and pitch (rad) of a body at rest from its mean specific force `f` (m/s², body
/// forward-right-down; at rest about (0, 0, −g)).
pub fn level(f: &Vector3<f64>) -> (f64, f64) {
    let roll = (-f.y).atan2(-f.z);
    let pitch = f.x.atan2((f.y * f.y + f.z * f.z).sqrt());
    (roll, pitch)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rest(lat: f64) -> (NavState, Increment) {
        let s = NavState {
            lat,
            lon: 0.3,
            h: 100.0,
            v: Vector3::zeros(),
            q: UnitQuaternion::identity(),
        };
        // At rest the IMU senses the Earth's rate and the reaction to gravity.
        let g = earth::gravity(lat, 100.0);
        let w_ie = Vector3::new(
            earth::OMEGA_IE * lat.cos(),
            0.0,
            -earth::OMEGA_IE * lat.sin(),
        );
        let dt = 0.01;
        (
            s,
            Increment {
                dtheta: w_ie * dt,
                dvel: Vector3::new(0.0, 0.0, -g) * dt,
                dt,
            },
        )
    }

    #[test]
    fn stays_at_rest() {
        let (mut s, inc) = rest(0.7);
        let s0 = s;
        let mut prev = Increment::zero(inc.dt);
        for _ in 0..60_000 {
            mechanise(&mut s, &prev, &inc);
            prev = inc;
        }
        // Ten minutes at rest: no velocity, position or attitude drift beyond rounding.
        assert!(s.v.norm() < 1e-6, "{:?}", s.v);
        assert!(((s.lat - s0.lat) * 6.4e6).abs() < 1e-3);
        assert!((s.h - s0.h).abs() < 1e-3);
        assert!(s.q.angle_to(&s0.q) < 1e-9);
    }

    #[test]
    fn level_and_mounting() {
        let (r, p) = (0.1, -0.2);
        let c = euler_to_dcm(r, p, 0.7);
        // Specific force at rest in n is (0, 0, -g); in b it is Cᵀ f_n.
        let f_b = c.transpose() * Vector3::new(0.0, 0.0, -9.8);
        let (rr, pp) = level(&f_b);
        assert!((rr - r).abs() < 1e-12 && (pp - p).abs() < 1e-12);
        let m = mounting(std::f64::consts::PI, 0.0, std::f64::consts::PI);
        let d = m - Matrix3::from_diagonal(&Vector3::new(-1.0, 1.0, -1.0));
        assert!(d.norm() < 1e-12);
    }

    #[test]
    fn constant_acceleration_north() {
        // Level body, accelerating north at 1 m/s² for 10 s: v = 10 m/s, 50 m travelled.
        let (mut s, mut inc) = rest(0.0);
        inc.dvel.x = 1.0 * inc.dt;
        let lat0 = s.lat;
        let mut prev = Increment::zero(inc.dt);
        for _ in 0..1000 {
            mechanise(&mut s, &prev, &inc);
            prev = inc;
        }
        assert!((s.v.x - 10.0).abs() < 1e-3, "{}", s.v.x);
        let north = (s.lat - lat0) * (earth::r_meridian(0.0) + 100.0);
        assert!((north - 50.0).abs() < 0.01, "{north}");
    }
}
