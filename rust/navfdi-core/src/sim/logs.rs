//! The simulator as a source of *recorded-style* logs: IMU samples (specific force and
//! angular rate from the truth trajectory plus white noise and a constant bias per run) and a
//! GNSS solution (truth positions and velocities plus white noise, with their σ), and the
//! truth as the reference — so that the loosely coupled architecture's strapdown INS and
//! filter, which run on recorded logs, can be checked where the truth is known (NEES).
//!
//! The trajectory's body axes are right-forward-up: the IMU is "mounted" with roll 180°,
//! pitch 0, yaw 90° in the filter's forward-right-down body frame
//! ([`crate::ins::strapdown::mounting`]).

use super::trajectory::generate;
use crate::error::{Error, Result};
use crate::logs::GnssLog;
use crate::spec::TrajectorySpec;
use crate::stream::{ImuSamples, Nominal};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// IMU mounting (roll, pitch, yaw; rad) of the simulator's right-forward-up body axes in the
/// filter's forward-right-down body frame.
pub const MOUNTING: [f64; 3] = [std::f64::consts::PI, 0.0, std::f64::consts::FRAC_PI_2];

/// Errors of the simulated IMU and GNSS.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogNoise {
    /// IMU sample rate (Hz).
    pub imu_rate: f64,
    /// Gyro white-noise density per axis (rad/s/√Hz).
    pub gyro_noise: f64,
    /// Accelerometer white-noise density per axis (m/s²/√Hz).
    pub accel_noise: f64,
    /// σ of the constant gyro bias drawn per run and axis (rad/s).
    pub gyro_bias: f64,
    /// σ of the constant accelerometer bias drawn per run and axis (m/s²).
    pub accel_bias: f64,
    /// σ of the constant gyro and accelerometer scale-factor errors drawn per run and axis
    /// (dimensionless): the IMU outputs `(1 + s) · truth + bias + noise`.
    pub gyro_scale: f64,
    /// See [`LogNoise::gyro_scale`].
    pub accel_scale: f64,
    /// GNSS epoch interval (s).
    pub gnss_dt: f64,
    /// GNSS position σ per axis (m) and velocity σ per axis (m/s).
    pub gnss_pos: f64,
    /// See [`LogNoise::gnss_pos`].
    pub gnss_vel: f64,
}

/// One simulated run's logs and truth.
#[derive(Debug, Clone)]
pub struct SimulatedLogs {
    /// IMU samples (time from 0, IMU axes = the trajectory's right-forward-up body axes).
    pub imu: ImuSamples,
    /// GNSS solution with its σ.
    pub gnss: GnssLog,
    /// The truth at the GNSS epochs (σ zero).
    pub reference: GnssLog,
    /// True body (forward-right-down) to north-east-down attitude at the GNSS epochs.
    pub attitude: Vec<UnitQuaternion<f64>>,
}

fn normal3(rng: &mut ChaCha8Rng) -> Vector3<f64> {
    Vector3::new(
        StandardNormal.sample(rng),
        StandardNormal.sample(rng),
        StandardNormal.sample(rng),
    )
}

/// Simulate `duration` seconds of logs along `trajectory` with the errors `noise`, from
/// ChaCha8 `(seed, stream = run)`.
pub fn simulate_logs(
    trajectory: &TrajectorySpec,
    duration: f64,
    noise: &LogNoise,
    seed: u64,
    run: u64,
) -> Result<SimulatedLogs> {
    if !(noise.imu_rate > 0.0 && noise.gnss_dt > 0.0 && duration > 0.0) {
        return Err(Error::Invalid(
            "simulated logs: rates, interval and duration must be positive".into(),
        ));
    }
    let dt = 1.0 / noise.imu_rate;
    let n = (duration / dt).floor() as usize + 1;
    let truth = generate(trajectory, dt, n);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(run);
    let bg = normal3(&mut rng) * noise.gyro_bias;
    let ba = normal3(&mut rng) * noise.accel_bias;
    let sg = Vector3::repeat(1.0) + normal3(&mut rng) * noise.gyro_scale;
    let sa = Vector3::repeat(1.0) + normal3(&mut rng) * noise.accel_scale;
    let sgn = noise.gyro_noise * noise.imu_rate.sqrt();
    let san = noise.accel_noise * noise.imu_rate.sqrt();
    let mut imu = ImuSamples::default();
    for e in &truth {
        imu.t.push(e.t);
        imu.gyro
            .push(e.w_b.component_mul(&sg) + bg + normal3(&mut rng) * sgn);
        imu.accel
            .push(e.f_b.component_mul(&sa) + ba + normal3(&mut rng) * san);
    }
    // ENU (right-forward-up body) to NED (forward-right-down body).
    let enu_ned = Matrix3::new(0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0);
    let step = (noise.gnss_dt / dt).round().max(1.0) as usize;
    let mut gnss = GnssLog::default();
    let mut reference = GnssLog::default();
    let mut attitude = Vec::new();
    for e in truth.iter().step_by(step) {
        let p = Nominal {
            lat: e.lat,
            lon: e.lon,
            h: e.h,
        };
        let d = normal3(&mut rng) * noise.gnss_pos;
        let rm = crate::ins::earth::r_meridian(e.lat) + e.h;
        let rn = crate::ins::earth::r_normal(e.lat) + e.h;
        let noisy = Nominal {
            lat: e.lat + d.y / rm,
            lon: e.lon + d.x / (rn * e.lat.cos()),
            h: e.h + d.z,
        };
        let dv = normal3(&mut rng) * noise.gnss_vel;
        for (log, pos, vel, sp, sv) in [
            (&mut gnss, noisy, e.v + dv, noise.gnss_pos, noise.gnss_vel),
            (&mut reference, p, e.v, 0.0, 0.0),
        ] {
            log.t.push(e.t);
            log.pos.push(pos);
            log.vel.push(vel);
            log.sd_pos.push(Vector3::repeat(sp));
            log.sd_vel.push(Vector3::repeat(sv));
        }
        let c_ned = enu_ned * e.c_bn * enu_ned;
        attitude.push(UnitQuaternion::from_matrix(&c_ned));
    }
    Ok(SimulatedLogs {
        imu,
        gnss,
        reference,
        attitude,
    })
}
