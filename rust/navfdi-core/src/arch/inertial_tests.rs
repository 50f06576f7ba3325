//! Tests of [`super`] (the strapdown INS's shared parts): the velocities differenced from
//! positions, the alignment and the IMU's own rest check.

use super::{imu_gaps, velocity_from_positions};
use nalgebra::Vector3;

#[test]
fn velocities_from_positions_difference_about_two_seconds_and_skip_gaps() {
    // Fixes at 4 Hz on record epochs of 8 Hz, moving (3, −2, 0.5) m/s, with a gap of 3 s.
    let t: Vec<f64> = (0..160).map(|k| f64::from(k) * 0.125).collect();
    let v = Vector3::new(3.0, -2.0, 0.5);
    let gap = |x: f64| (10.0..13.0).contains(&x);
    let pos = |k: usize| (k.is_multiple_of(2) && !gap(t[k])).then(|| v * t[k]);
    let out = velocity_from_positions(&t, pos, |_| 2.0, |_| false, 1.0, 0.25);
    for (k, o) in out.iter().enumerate() {
        let tk = t[k];
        let inside = k.is_multiple_of(2)
            && tk >= 1.0
            && tk <= t[159] - 1.0
            && !gap(tk)
            && !(9.0 < tk && tk < 10.0 || (13.0..14.0).contains(&tk));
        match o {
            Some((dv, sig)) => {
                assert!(inside, "a velocity at {tk}");
                assert!((dv - v).norm() < 1e-9, "{dv} at {tk}");
                // Two fixes of σ 2 m, 2 s apart.
                assert!((sig - 8f64.sqrt() / 2.0).abs() < 1e-9, "{sig}");
            }
            None => assert!(!inside || (9.0..=10.0).contains(&tk), "none at {tk}"),
        }
    }
    assert!(out.iter().filter(|o| o.is_some()).count() > 50);
}

#[test]
fn no_velocity_is_differenced_across_a_jump_of_the_fixes() {
    // 1 Hz fixes of a car at 5 m/s north; a 30 m burst east from 20 s to 27 s: the fixes jump
    // at 20 s and back at 28 s.
    let t: Vec<f64> = (0..40).map(f64::from).collect();
    let burst = |k: usize| if (20..28).contains(&k) { 30.0 } else { 0.0 };
    let pos = |k: usize| Some(Vector3::new(burst(k), 5.0 * t[k], 0.0));
    let jumped = |k: usize| k == 20 || k == 28;
    let out = velocity_from_positions(&t, pos, |_| 2.0, jumped, 1.0, 1.0);
    for (k, o) in out.iter().enumerate().skip(1).take(38) {
        // Differences from k − 1 to k + 1 spanning the fix at 20 s or 28 s give none.
        let spans = [19, 20, 27, 28].contains(&k);
        match o {
            None => assert!(spans, "none at {k}"),
            Some((v, _)) => {
                assert!(!spans, "{v} at {k}");
                assert!(
                    (v - Vector3::new(0.0, 5.0, 0.0)).norm() < 1e-9,
                    "{v} at {k}"
                );
            }
        }
    }
    // Without the jumps marked, those epochs take 15 m/s east from the burst.
    let blind = velocity_from_positions(&t, pos, |_| 2.0, |_| false, 1.0, 1.0);
    assert!((blind[19].unwrap().0.x - 15.0).abs() < 1e-9);
}

#[test]
fn a_held_position_gives_no_velocity_where_it_catches_up() {
    // 1 Hz fixes of a car at rest to 10 s, then at 5 m/s north; the receiver repeats its
    // fix at 12-14 s (a stale spell) and at rest (a static hold).
    let t: Vec<f64> = (0..30).map(f64::from).collect();
    let truth = |x: f64| Vector3::new(0.0, 5.0 * (x - 10.0).max(0.0), 0.0);
    let pos = |k: usize| Some(truth(if (12..15).contains(&k) { t[11] } else { t[k] }));
    let out = velocity_from_positions(&t, pos, |_| 2.0, |_| false, 1.0, 1.0);
    for (k, o) in out.iter().enumerate().skip(1).take(28) {
        match o {
            // Differences spanning a repeated fix and a move give none: the stale spell's
            // start and end (11, 14, 15 s), and moving off from the held rest (10 s).
            None => assert!([10, 11, 14, 15].contains(&k), "none at {k}"),
            Some((v, _)) => {
                assert!(![10, 11, 14, 15].contains(&k), "{v} at {k}");
                // Inside the spell two repeated fixes say what a standing vehicle's do.
                let want = if k <= 9 || k == 12 || k == 13 {
                    0.0
                } else {
                    5.0
                };
                assert!((v.y - want).abs() < 1e-9, "{v} at {k}");
            }
        }
    }
}

/// [`super::align`] on 60 s of an IMU at 100 Hz whose x rate is `gyro_x(t)` (rad/s, level,
/// gravity on z) and GNSS epochs every 0.25 s moving east at `speed(t)` (m/s; positions at
/// 5 m/s) with velocity σ `sig_v` (m/s), by the loosely coupled alignment's defaults
/// (`alignment.speed` 1 m/s, static speed 0.05 m/s); with the time of its epoch (s).
fn align_east(
    gyro_x: impl Fn(f64) -> f64,
    speed: impl Fn(f64) -> f64,
    sig_v: f64,
) -> crate::error::Result<(super::Aligned, f64)> {
    use super::{align, BodyImu};
    use crate::spec::AlignmentSpec;
    use crate::stream::Nominal;
    let ti: Vec<f64> = (0..6001).map(|i| i as f64 * 0.01).collect();
    let gyro = ti
        .iter()
        .map(|&x| Vector3::new(gyro_x(x), 0.0, 0.0))
        .collect();
    let acc = ti.iter().map(|_| Vector3::new(0.0, 0.0, -9.8)).collect();
    let imu = BodyImu {
        t: ti,
        gyro,
        acc,
        gaps: Vec::new(),
    };
    let t: Vec<f64> = (0..240).map(|k| f64::from(k) * 0.25).collect();
    let a = AlignmentSpec {
        speed: 1.0,
        heading: None,
        static_speed: 0.05,
        gyro_bias: true,
        sigma_level: 0.02,
        sigma_heading: 0.1,
        sigma_position: 2.0,
        sigma_velocity: 1.0,
    };
    let origin = Nominal {
        lat: 0.7,
        lon: 0.2,
        h: 100.0,
    };
    let al = align(
        &a,
        "loosely_coupled",
        &imu,
        &t,
        &origin,
        |k| Some(Vector3::new(speed(t[k]), 0.0, 0.0)),
        |k| Some(Vector3::new(5.0 * t[k], 0.0, 0.0)),
        |_| sig_v,
        true,
    )?;
    let at = t[al.epoch];
    Ok((al, at))
}

/// Speeds differenced from meter-level fixes (σ 1.4 m/s) dip below 2.5σ in motion: a
/// single slow epoch before the heading's speed is no static start (it held one IMU sample,
/// and the alignment failed); the search goes on to the rest before it, whose mean rate is
/// the gyro bias.
#[test]
fn a_slow_moment_in_motion_is_no_static_start() {
    // At rest to 30 s (gyro bias 0.01 rad/s on x), turning and shaking after; 5 m/s from 30 s
    // with a dip to 0.5 m/s at 35 s, 8 m/s (above 5σ) from 40 s.
    let gyro = |x: f64| if x <= 30.0 { 0.01 } else { 0.3 };
    let speed = |x: f64| match x {
        x if x <= 30.0 => 0.0,
        35.0 => 0.5,
        x if x < 40.0 => 5.0,
        _ => 8.0,
    };
    let (al, at) =
        align_east(gyro, speed, 1.4).expect("aligned on the rest before the slow moment");
    assert_eq!(at, 40.0);
    assert!((al.bg0.x - 0.01).abs() < 1e-4, "{:?}", al.bg0);
}

/// A log whose speed never reaches 5σ of its velocity (σ 4 m/s, 8 m/s at most): the heading
/// is read at half the most σ it reaches (4 m/s), not at a drift of the fixes at rest that
/// passes `alignment.speed` (2 m/s at 20 s while the car stands).
#[test]
fn a_log_never_5_sigma_fast_is_not_aligned_on_a_drift_at_rest() {
    let speed = |x: f64| match x {
        20.0 => 2.0,
        x if x <= 30.0 => 0.0,
        x if x < 40.0 => 3.0,
        _ => 8.0,
    };
    let (_, at) = align_east(|_| 0.01, speed, 4.0).expect("aligned");
    assert_eq!(at, 40.0);
}

/// The IMU's own rest check cuts a static start where the vehicle moves off (three
/// seconds in a row turning), not at a bump at rest (a door shut: one second).
#[test]
fn the_imu_says_where_the_rest_ends() {
    use super::{imu_rest, BodyImu};
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let mut noise = |s: f64| -> f64 {
        let n: f64 = StandardNormal.sample(&mut rng);
        s * n
    };
    let t: Vec<f64> = (0..5000).map(|i| i as f64 * 0.01).collect();
    // At rest to 40 s with a bump at 20.3–20.8 s; turning at 10°/s and accelerating after.
    let gyro = t
        .iter()
        .map(|&x| {
            let turn = if x >= 40.0 { 10f64.to_radians() } else { 0.0 };
            let bump = if (20.3..20.8).contains(&x) { 0.2 } else { 0.0 };
            Vector3::new(0.002 + noise(0.02) + bump, noise(0.04), turn + noise(0.002))
        })
        .collect();
    let acc = t
        .iter()
        .map(|&x| {
            let a = if x >= 40.0 { 1.0 } else { 0.0 };
            Vector3::new(a + noise(0.05), noise(0.05), -9.8 + noise(0.13))
        })
        .collect();
    let imu = BodyImu {
        t,
        gyro,
        acc,
        gaps: Vec::new(),
    };
    let idx: Vec<usize> = (0..5000).collect();
    let rest = imu_rest(&imu, &idx);
    let end = imu.t[*rest.last().unwrap()];
    assert!(rest[0] == 0 && (39.0..40.0).contains(&end), "{end}");
    // At rest throughout: every sample.
    let idx: Vec<usize> = (0..4000).collect();
    assert_eq!(imu_rest(&imu, &idx), idx);
    // Rocked for 4 s at 5–9 s (luggage loaded): the longer rest after it.
    let mut rocked = BodyImu {
        t: imu.t.clone(),
        gyro: imu.gyro.clone(),
        acc: imu.acc.clone(),
        gaps: Vec::new(),
    };
    for i in 500..900 {
        rocked.acc[i].x += 0.3;
    }
    let rest = imu_rest(&rocked, &idx);
    let (a, b) = (rocked.t[rest[0]], rocked.t[*rest.last().unwrap()]);
    assert!((9.0..10.0).contains(&a) && b > 39.9, "{a} {b}");
}

/// Samples missing from a 100 Hz log are found as gaps, with the samples' scatter either side;
/// the jitter of a logger's clock (intervals up to 1.8× the median) is not a gap.
#[test]
fn imu_gaps_are_missing_samples_with_their_scatter() {
    let mut t: Vec<f64> = Vec::new();
    let mut k = 0.0;
    for i in 0..1000 {
        // Every third interval 1.8× (jitter); 30 samples missing after sample 500.
        k += if i % 3 == 0 { 0.018 } else { 0.01 };
        if i == 500 {
            k += 0.30;
        }
        t.push(k);
    }
    // Samples alternating ±a about a level: a scatter known exactly.
    let sgn = |i: usize| if i.is_multiple_of(2) { 1.0 } else { -1.0 };
    let acc: Vec<Vector3<f64>> = (0..1000)
        .map(|i| Vector3::new(0.5 * sgn(i), 0.0, -9.8 + 0.1 * sgn(i)))
        .collect();
    let gyro: Vec<Vector3<f64>> = (0..1000)
        .map(|i| Vector3::new(0.0, 0.02 * sgn(i), 0.0))
        .collect();
    let gaps = imu_gaps(&t, &gyro, &acc, &[]);
    assert_eq!(gaps.len(), 1, "{gaps:?}");
    let g = gaps[0];
    assert_eq!(g.i, 500);
    let span = t[500] - t[499];
    assert!(span > 0.3);
    // 20 samples, ten of each sign: variance a² · 20/19.
    let v = |a: f64| a * a * 20.0 / 19.0 * span / 2.0;
    assert!(
        (g.acc_rate - Vector3::new(v(0.5), 0.0, v(0.1))).norm() < 1e-12,
        "{g:?}"
    );
    assert!(
        (g.gyro_rate - Vector3::new(0.0, v(0.02), 0.0)).norm() < 1e-15,
        "{g:?}"
    );
    // Too short a log has none.
    assert!(imu_gaps(&t[..2], &gyro[..2], &acc[..2], &[]).is_empty());
}

/// Samples at the sensor's full scale are kept, and every interval from the sample before the
/// run to the one after it takes the noise of one gap spanning them, from the samples around.
#[test]
fn clipped_samples_take_the_noise_of_a_gap_over_their_run() {
    let t: Vec<f64> = (0..200).map(|i| i as f64 * 0.01).collect();
    let sgn = |i: usize| if i.is_multiple_of(2) { 1.0 } else { -1.0 };
    let acc: Vec<Vector3<f64>> = (0..200)
        .map(|i| Vector3::new(0.3 * sgn(i), 0.0, 9.8))
        .collect();
    let gyro = vec![Vector3::new(0.0, 0.0, 0.01); 200];
    let mut clipped = vec![false; 200];
    clipped[100..103].iter_mut().for_each(|c| *c = true);
    let gaps = imu_gaps(&t, &gyro, &acc, &clipped);
    assert_eq!(
        gaps.iter().map(|g| g.i).collect::<Vec<_>>(),
        vec![100, 101, 102, 103]
    );
    // The run's span, from sample 99 to 103; the scatter of samples 90 to 112 (23: twelve of
    // one sign, eleven of the other).
    let span = t[103] - t[99];
    let mean: f64 = 0.3 / 23.0;
    let var = (12.0 * (0.3_f64 - mean).powi(2) + 11.0 * (0.3_f64 + mean).powi(2)) / 22.0;
    for g in &gaps {
        assert!((g.acc_rate.x - var * span / 2.0).abs() < 1e-15, "{g:?}");
        assert!(g.gyro_rate.norm() < 1e-30, "{g:?}"); // a steady rate: no scatter
    }
    // No clipping and no gap: nothing.
    assert!(imu_gaps(&t, &gyro, &acc, &[false; 200]).is_empty());
}
