//! The simulator as a source of *recorded-style* logs: IMU samples (specific force and
//! angular rate from the truth trajectory plus white noise and a constant bias per run) and a
//! GNSS solution (truth positions and velocities plus errors, with their σ), and the truth as
//! the reference — so that the loosely coupled architecture's strapdown INS and filter, which
//! run on recorded logs, can be checked where the truth is known (NEES), and so that FDE and
//! calibration can be measured against known errors.
//!
//! The GNSS errors can be what a receiver's own single-point fix has ([`LogNoise`]): white
//! noise, a first-order Gauss-Markov error per axis (time-correlated, metres), multipath
//! bursts (an offset held for seconds) and stale fixes (the last fix repeated while the
//! vehicle moves). The IMU can sit in any orientation (`mounting`, its axes in the vehicle's
//! forward-right-down body frame), with a boresight error and a time-stamp offset.
//!
//! By default the IMU axes are the trajectory's right-forward-up body axes: the IMU is
//! "mounted" with roll 180°, pitch 0, yaw 90° in the filter's forward-right-down body frame
//! ([`crate::ins::strapdown::mounting`]).

use super::trajectory::generate_vehicle;
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

/// Stream offset of the Gauss-Markov biases' driving noise.
const BIAS_DRIVE_STREAM: u64 = 0x0B1A_5D21_7E00;

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
    /// Correlation time (s) of the GNSS position errors: a first-order Gauss-Markov process
    /// per axis of stationary σ `gnss_pos` (0: white).
    pub gnss_tau: f64,
    /// σ of the white GNSS position noise (m per axis) added to the Gauss-Markov error.
    pub gnss_white: f64,
    /// Multipath bursts: expected bursts per second, each an offset (horizontal σ
    /// `burst_size` m per axis) held for `burst_duration` s.
    pub burst_rate: f64,
    /// See [`LogNoise::burst_rate`].
    pub burst_size: f64,
    /// See [`LogNoise::burst_rate`].
    pub burst_duration: f64,
    /// Stale fixes: expected stale spells per second while moving, each repeating the last
    /// fix (position and velocity) for `stale_duration` s.
    pub stale_rate: f64,
    /// See [`LogNoise::stale_rate`].
    pub stale_duration: f64,
    /// The σ the receiver reports with each fix (m, m/s per axis); 0: `gnss_pos`, `gnss_vel`.
    pub reported_pos: f64,
    /// See [`LogNoise::reported_pos`].
    pub reported_vel: f64,
    /// The IMU's orientation in the vehicle's forward-right-down body frame: roll, pitch, yaw
    /// (rad, the convention of [`crate::ins::strapdown::mounting`]).
    pub mounting: [f64; 3],
    /// Seconds the IMU's time stamps lag the truth (`t_imu = t − lag`): the filter's
    /// `imu_time_offset` that undoes it is `+lag`.
    pub time_lag: f64,
    /// A ground vehicle (no bank in turns) rather than an aircraft.
    pub ground: bool,
    /// The GNSS antenna from the IMU in the vehicle's forward-right-down body frame (m; the
    /// scenario's `lever_arm`): the fixes and their velocities are the antenna's, and so is
    /// the reference's position (the filters record the antenna's); its velocity the IMU's.
    pub lever_arm: [f64; 3],
    /// Correlation time (s) of the gyro and accelerometer biases: first-order Gauss-Markov
    /// processes of stationary σ `gyro_bias`, `accel_bias` (the filters' bias model), driven
    /// from their own random stream; 0: constant per run.
    pub bias_tau: f64,
}

impl Default for LogNoise {
    /// A consumer IMU at 100 Hz and a 4 Hz white-noise GNSS of 0.5 m, IMU axes
    /// right-forward-up ([`MOUNTING`]), an aircraft.
    fn default() -> Self {
        LogNoise {
            imu_rate: 100.0,
            gyro_noise: 0.01f64.to_radians(),
            accel_noise: 100e-6 * 9.80665,
            gyro_bias: (10.0f64 / 3600.0).to_radians(),
            accel_bias: 1e-3 * 9.80665,
            gyro_scale: 0.0,
            accel_scale: 0.0,
            gnss_dt: 0.25,
            gnss_pos: 0.5,
            gnss_vel: 0.05,
            gnss_tau: 0.0,
            gnss_white: 0.0,
            burst_rate: 0.0,
            burst_size: 0.0,
            burst_duration: 0.0,
            stale_rate: 0.0,
            stale_duration: 0.0,
            reported_pos: 0.0,
            reported_vel: 0.0,
            mounting: MOUNTING,
            time_lag: 0.0,
            ground: false,
            bias_tau: 0.0,
            lever_arm: [0.0; 3],
        }
    }
}

/// What the simulated GNSS did at one epoch: its position error (east, north, up, m) and
/// whether the fix was a stale repeat or inside a multipath burst.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GnssTruthError {
    /// Position error east, north, up (m).
    pub error: Vector3<f64>,
    /// The fix repeats the previous one (the receiver had none).
    pub stale: bool,
    /// A multipath burst was active.
    pub burst: bool,
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
    /// The GNSS errors at its epochs.
    pub gnss_errors: Vec<GnssTruthError>,
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
    for (name, v) in [
        ("gnss_tau", noise.gnss_tau),
        ("gnss_white", noise.gnss_white),
        ("burst_rate", noise.burst_rate),
        ("burst_size", noise.burst_size),
        ("burst_duration", noise.burst_duration),
        ("stale_rate", noise.stale_rate),
        ("stale_duration", noise.stale_duration),
        ("reported_pos", noise.reported_pos),
        ("reported_vel", noise.reported_vel),
        ("bias_tau", noise.bias_tau),
    ] {
        if !(v >= 0.0 && v.is_finite()) {
            return Err(Error::Invalid(format!(
                "simulated logs: {name} = {v} must be finite and non-negative"
            )));
        }
    }
    if !(noise.time_lag.abs() <= 10.0 && noise.mounting.iter().all(|v| v.is_finite())) {
        return Err(Error::Invalid(
            "simulated logs: time_lag within ±10 s and finite mounting angles".into(),
        ));
    }
    if !noise
        .lever_arm
        .iter()
        .all(|v| v.is_finite() && v.abs() <= 100.0)
    {
        return Err(Error::Invalid(format!(
            "simulated logs: lever_arm = {:?} m must be finite and within ±100 m",
            noise.lever_arm
        )));
    }
    let dt = 1.0 / noise.imu_rate;
    let n = (duration / dt).floor() as usize + 1;
    crate::memory::check(
        "simulated logs",
        n as f64 * 200.0,
        &format!("{n} IMU samples"),
        "shorten the duration or lower the IMU rate",
    )?;
    let truth = generate_vehicle(trajectory, dt, n, !noise.ground);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(run);
    let bg = normal3(&mut rng) * noise.gyro_bias;
    let ba = normal3(&mut rng) * noise.accel_bias;
    let sg = Vector3::repeat(1.0) + normal3(&mut rng) * noise.gyro_scale;
    let sa = Vector3::repeat(1.0) + normal3(&mut rng) * noise.accel_scale;
    let sgn = noise.gyro_noise * noise.imu_rate.sqrt();
    let san = noise.accel_noise * noise.imu_rate.sqrt();
    // ENU (right-forward-up body) to NED (forward-right-down body), and the IMU's axes.
    let enu_ned = Matrix3::new(0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0);
    let to_imu =
        crate::ins::strapdown::mounting(noise.mounting[0], noise.mounting[1], noise.mounting[2])
            .transpose()
            * enu_ned;
    let mut imu = ImuSamples::default();
    // Gauss-Markov biases: driven from their own stream, so constant biases draw as before.
    let mut bias_rng = ChaCha8Rng::seed_from_u64(seed);
    bias_rng.set_stream(run ^ BIAS_DRIVE_STREAM);
    let bias_phi = if noise.bias_tau > 0.0 {
        (-dt / noise.bias_tau).exp()
    } else {
        1.0
    };
    let bias_q = (1.0 - bias_phi * bias_phi).sqrt();
    let (mut bg, mut ba) = (bg, ba);
    for e in &truth {
        if bias_phi < 1.0 {
            bg = bg * bias_phi + normal3(&mut bias_rng) * (noise.gyro_bias * bias_q);
            ba = ba * bias_phi + normal3(&mut bias_rng) * (noise.accel_bias * bias_q);
        }
        imu.t.push(e.t - noise.time_lag);
        let w = to_imu * e.w_b;
        let f = to_imu * e.f_b;
        imu.gyro
            .push(w.component_mul(&sg) + bg + normal3(&mut rng) * sgn);
        imu.accel
            .push(f.component_mul(&sa) + ba + normal3(&mut rng) * san);
    }
    let step = (noise.gnss_dt / dt).round().max(1.0) as usize;
    let gdt = step as f64 * dt;
    let phi = if noise.gnss_tau > 0.0 {
        (-gdt / noise.gnss_tau).exp()
    } else {
        0.0
    };
    let mut gm = normal3(&mut rng) * noise.gnss_pos;
    let mut burst = (0.0f64, Vector3::zeros());
    let mut stale_left = 0.0f64;
    let mut gnss = GnssLog::default();
    let mut reference = GnssLog::default();
    let mut attitude = Vec::new();
    let mut gnss_errors = Vec::new();
    let uniform = |rng: &mut ChaCha8Rng| -> f64 { rand::RngExt::random::<f64>(rng) };
    let lever_rfu = enu_ned * Vector3::from(noise.lever_arm);
    for (k, e) in truth.iter().step_by(step).enumerate() {
        // The antenna: the lever arm turned into ENU, and its velocity ω × l (ω_ib: the earth's
        // rate in it moves a 1 m arm by 7e-5 m/s).
        let lever = e.c_bn * lever_rfu;
        let v_ant = e.v + e.c_bn * e.w_b.cross(&lever_rfu);
        if k > 0 {
            gm = gm * phi + normal3(&mut rng) * (noise.gnss_pos * (1.0 - phi * phi).sqrt());
        }
        // Multipath burst: started at random, an offset held for its duration.
        if burst.0 <= 0.0 && uniform(&mut rng) < noise.burst_rate * gdt {
            let d = normal3(&mut rng) * noise.burst_size;
            burst = (noise.burst_duration, Vector3::new(d.x, d.y, 0.5 * d.z));
        }
        let in_burst = burst.0 > 0.0;
        let b = if in_burst { burst.1 } else { Vector3::zeros() };
        burst.0 -= gdt;
        let d = gm + normal3(&mut rng) * noise.gnss_white + b;
        let rm = crate::ins::earth::r_meridian(e.lat) + e.h;
        let rn = crate::ins::earth::r_normal(e.lat) + e.h;
        let antenna = Nominal {
            lat: e.lat + lever.y / rm,
            lon: e.lon + lever.x / (rn * e.lat.cos()),
            h: e.h + lever.z,
        };
        let noisy = Nominal {
            lat: antenna.lat + d.y / rm,
            lon: antenna.lon + d.x / (rn * e.lat.cos()),
            h: antenna.h + d.z,
        };
        let dv = normal3(&mut rng) * noise.gnss_vel;
        let moving = e.v.xy().norm() > 1.0;
        if stale_left <= 0.0 && moving && k > 0 && uniform(&mut rng) < noise.stale_rate * gdt {
            stale_left = noise.stale_duration;
        }
        let stale = stale_left > 0.0 && k > 0;
        stale_left -= gdt;
        let (sp, sv) = (
            if noise.reported_pos > 0.0 {
                noise.reported_pos
            } else {
                noise.gnss_pos.hypot(noise.gnss_white)
            },
            if noise.reported_vel > 0.0 {
                noise.reported_vel
            } else {
                noise.gnss_vel
            },
        );
        let (pos, vel) = if stale {
            (gnss.pos[k - 1], gnss.vel[k - 1])
        } else {
            (noisy, v_ant + dv)
        };
        gnss.t.push(e.t);
        gnss.pos.push(pos);
        gnss.vel.push(vel);
        gnss.sd_pos.push(Vector3::repeat(sp));
        gnss.sd_vel.push(Vector3::repeat(sv));
        reference.t.push(e.t);
        reference.pos.push(antenna);
        reference.vel.push(e.v);
        reference.sd_pos.push(Vector3::zeros());
        reference.sd_vel.push(Vector3::zeros());
        let err = crate::stream::Nominal::to_enu(&antenna, &pos);
        gnss_errors.push(GnssTruthError {
            error: err,
            stale,
            burst: in_burst,
        });
        let c_ned = enu_ned * e.c_bn * enu_ned;
        attitude.push(UnitQuaternion::from_matrix(&c_ned));
    }
    Ok(SimulatedLogs {
        imu,
        gnss,
        reference,
        attitude,
        gnss_errors,
    })
}
