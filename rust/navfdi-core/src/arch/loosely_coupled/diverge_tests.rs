//! Unit tests of the INS watch ([`super::InsWatch`]): runaways, outlasting holds and the
//! fixes' jumps.

use super::*;

/// An INS running away at 5 m/s east from held fixes is caught within the window; a held
/// 20 m step (constant offset), a 2 m/s ramp and a 30 m burst's jump are not.
#[test]
fn a_runaway_is_a_rate_a_step_ramp_or_burst_is_not() {
    let mut m = Divergence::default();
    let hit = (0..20).find_map(|k| {
        m.push(k as f64, [5.0 * k as f64, 1.0], true, false)
            .map(|r| (k, r))
    });
    let (k, r) = hit.expect("caught");
    assert!((8..=10).contains(&k), "{k}");
    assert!((r[0] - 5.0).abs() < 1e-9 && r[1].abs() < 1e-9, "{r:?}");
    for d in [
        |k: f64| [20.0 + 0.5 * (k * 1.7).sin(), -3.0],
        |k: f64| [2.0 * k, 0.0],
        |k: f64| [if k < 6.0 { 0.0 } else { 30.0 }, 0.0],
        |k: f64| {
            [
                40.0 * f64::from(u8::from(k >= 13.0)) + 15.0 * f64::from(u8::from(k >= 17.0)),
                0.0,
            ]
        },
    ] {
        let mut m = Divergence::default();
        assert!((0..40).all(|k| m.push(k as f64, d(k as f64), true, true).is_none()));
    }
    // A fix used as measured starts the window again.
    let mut m = Divergence::default();
    let caught = (0..20).any(|k| {
        m.push(k as f64, [5.0 * k as f64, 0.0], k % 7 != 6, false)
            .is_some()
    });
    assert!(!caught);
}

/// A ramp held for more than [`HOLD_LONGEST`] s while the INS drifts from the fixes at 0.8 m/s
/// (below the runaway rate) is the INS's drift: caught once the spell is that long, at the
/// drift's rate, and not onto a burst's fix (a 30 m burst at 118–127 s delays it until the
/// fixes are back on the line). Not a held step (its offset is constant, or it is the
/// outlasting rule's), nor a drift slower than [`DRIFT_RATE`], nor a spell a fix used as
/// measured broke.
#[test]
fn a_ramp_held_longer_than_any_evidence_while_the_ins_drifts_is_the_ins() {
    let noise = |k: usize| 0.7 * ((k as f64) * 2.3).sin();
    let burst = |t: f64| {
        if (118.0..128.0).contains(&t) {
            30.0
        } else {
            0.0
        }
    };
    let run = |rate: f64, ramp: bool, used_at: Option<usize>| {
        let mut m = Divergence::default();
        (0..300).find_map(|k| {
            let t = k as f64;
            let d = [rate * t + noise(k) + burst(t), 2.0 + noise(k + 7)];
            m.push(t, d, used_at != Some(k), ramp).map(|r| (t, r))
        })
    };
    let (t, r) = run(0.8, true, None).expect("caught");
    assert!((128.0..=130.0).contains(&t), "{t}");
    assert!((r[0] - 0.8).abs() < 0.05 && r[1].abs() < 0.05, "{r:?}");
    assert!(run(0.8, false, None).is_none());
    assert!(run(0.05, true, None).is_none());
    // A fix used as measured at 100 s: the spell starts again, and is long enough at 221 s.
    let (t, _) = run(0.8, true, Some(100)).expect("caught later");
    assert!((221.0..=222.0).contains(&t), "{t}");
}

#[test]
fn a_held_step_that_outlasts_the_fixes_before_it_is_the_ins() {
    // First fix at 2 s, fixes agree until a hold at 60 s: held out more than 60 − 2 + 30
    // s (at 149 s, not at 148 s) it is the INS's error, once; the fixes since the hold's
    // onset are then the spell.
    let push = |o: &mut Outlast, t: u32, held: bool, step: bool| {
        o.push(
            t as f64,
            Some([10.0 * t as f64, 0.0]),
            None,
            [0.0; 2],
            held,
            step,
            true,
            false,
        )
    };
    let mut o = Outlast::new(2.0, 1.0);
    assert!((30..60).all(|t| !push(&mut o, t, false, false)));
    let fired: Vec<u32> = (60..400).filter(|&t| push(&mut o, t, true, true)).collect();
    assert_eq!(fired[0], 149, "{fired:?}");
    // After firing the held fixes since 60 s are the spell: a hold again from 150 s must
    // outlast 150 − 60 + 30 s.
    assert_eq!(fired[1], 150 + 120 + 1, "{fired:?}");
    // A hold that ends before that is forgotten; a held ramp never fires.
    let mut o = Outlast::new(0.0, 1.0);
    assert!((100..129).all(|t| !push(&mut o, t, true, true)));
    assert!(!push(&mut o, 129, false, false));
    assert!((130..400).all(|t| !push(&mut o, t, true, false)));
}

#[test]
fn a_hold_that_undoes_a_jump_taken_in_moves_the_ins_at_once() {
    // A car at 10 m/s east with 0.3 m of noise; a 15 m north burst over 38–45 s that the
    // filter took in (the alignment at 36 s, not converged yet): at 46 s the fix jumps
    // back, and the INS is 14 m north of it.
    let noise = |k: u32| 0.3 * ((k * 7919 % 13) as f64 / 6.0 - 1.0);
    let fix = |k: u32, burst: f64| Some([10.0 * k as f64 + noise(k), noise(k + 5) + burst]);
    let run_with = |d: [f64; 2], back: f64, off: f64, converged: bool| {
        let mut o = Outlast::new(0.0, 1.0);
        for k in 0..46 {
            let burst = if (38..46).contains(&k) { 15.0 } else { 0.0 };
            // At its jump the fix is `off` m off the INS (INS − fix), then followed.
            let d = if k == 38 { [0.0, off] } else { [0.0; 2] };
            assert!(!o.push(
                k as f64,
                fix(k, burst),
                None,
                d,
                false,
                false,
                converged,
                false
            ));
        }
        (46..200).find(|&k| {
            o.push(
                k as f64,
                fix(k, 15.0 - back),
                None,
                d,
                true,
                true,
                false,
                false,
            )
        })
    };
    let run = |d: [f64; 2], back: f64| run_with(d, back, -15.0, false);
    // Moved after 5 s of hold, not after 46 + 30.
    assert_eq!(run([0.5, 14.0], 15.0), Some(52));
    // The INS that followed part of it (8 m) too.
    assert_eq!(run([0.5, 8.0], 15.0), Some(52));
    // The INS that coasted past it on the velocity the burst gave it too.
    assert_eq!(run([0.5, 25.0], 15.0), Some(52));
    // An INS off further, or the other way, or a fix that did not jump back, is not that
    // burst's end: the spell rule (46 + 30 s from 46 s) decides.
    assert_eq!(run([0.5, 40.0], 15.0), Some(123));
    assert_eq!(run([12.0, 0.0], 15.0), Some(123));
    assert_eq!(run([0.5, -14.0], 15.0), Some(123));
    assert_eq!(run([0.5, 14.0], 0.0), Some(123));
    // A jump onto the INS (a held fault's end, taken in) is not a fault's start.
    assert_eq!(run_with([0.5, 14.0], 15.0, 0.0, false), Some(123));
    // Nor is a jump a converged filter took in (its tests, not gross innovations, decide).
    assert_eq!(run_with([0.5, 14.0], 15.0, -15.0, true), Some(123));
    // The filter converged inside the burst, whose fixes were then held from 40 s: the jump
    // back at 46 s, in the hold, ends it as well (moved at 52 s, not 40 + 70).
    let mut o = Outlast::new(0.0, 1.0);
    for k in 0..40 {
        let burst = if k >= 38 { 15.0 } else { 0.0 };
        let d = if k == 38 { [0.0, -15.0] } else { [0.0; 2] };
        assert!(!o.push(k as f64, fix(k, burst), None, d, false, false, false, false));
    }
    let moved = (40..200).find(|&k| {
        let (burst, d) = if k < 46 {
            (15.0, [0.0, 1.0])
        } else {
            (0.0, [0.5, 16.0])
        };
        o.push(k as f64, fix(k, burst), None, d, true, true, true, false)
    });
    assert_eq!(moved, Some(52));
    // Smooth driving with braking at 6 m/s² is no jump.
    let mut o = Outlast::new(0.0, 1.0);
    for k in 0..20u32 {
        let t = k as f64;
        let x = if k < 10 {
            20.0 * t
        } else {
            200.0 + 20.0 * (t - 10.0) - 3.0 * (t - 10.0).powi(2)
        };
        o.taken(t, [x, 0.0], None, None);
    }
    assert!(o.open.is_empty());
}

#[test]
fn with_velocities_a_burst_is_a_jump_the_second_differences_miss() {
    // A car at 10 m/s east, fixes of 2 m white noise with the receiver's velocities, an
    // 18 m burst north over 23–35 s under way at the alignment: its start and end are
    // within the second differences' 5σ (about 26 m) but beyond the displacement against
    // the velocities' (about 15 m).
    let mut gauss = {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12345);
        move || -> f64 { StandardNormal.sample(&mut rng) }
    };
    let fixes: Vec<[f64; 2]> = (0..60)
        .map(|k| {
            let burst = if (23..36).contains(&k) { -18.0 } else { 0.0 };
            [10.0 * k as f64 + 2.0 * gauss(), burst + 2.0 * gauss()]
        })
        .collect();
    let run = |vel: bool| {
        let mut j = Jumps::new(1.0);
        (0..60)
            .filter(|&k| {
                let v = vel.then_some([10.0, 0.0]);
                j.push_with(k as f64, fixes[k], v).is_some()
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(run(true), vec![23, 36]);
    assert!(!run(false).contains(&23), "{:?}", run(false));
    // Velocities at one fix in two: the second differences decide where a pair lacks them.
    let mut j = Jumps::new(1.0);
    let half: Vec<usize> = (0..60)
        .filter(|&k| {
            let v = (k % 2 == 0).then_some([10.0, 0.0]);
            j.push_with(k as f64, fixes[k], v).is_some()
        })
        .collect();
    assert!(!half.contains(&23), "{half:?}");
    // Under way at the alignment (taken in before it), the jump back that starts the hold
    // moves the INS 5 s later instead of after the spell (36 + 30 s).
    let hold = |vel: bool| {
        let v = vel.then_some([10.0, 0.0]);
        let mut o = Outlast::new(0.0, 1.0);
        for (k, &p) in fixes.iter().enumerate().take(32) {
            o.taken(k as f64, p, v, None);
        }
        for (k, &p) in fixes.iter().enumerate().take(36).skip(32) {
            let d = [0.0; 2];
            assert!(!o.push(k as f64, Some(p), v, d, false, false, false, false));
        }
        (36..200).find(|&k| {
            let p = if k < 60 {
                fixes[k]
            } else {
                [10.0 * k as f64, 0.0]
            };
            o.push(k as f64, Some(p), v, [0.0, -17.0], true, true, true, false)
        })
    };
    assert_eq!(hold(true), Some(42));
    assert_eq!(hold(false), Some(103));
}

#[test]
fn a_jump_taken_in_is_forgotten_once_the_converged_filter_uses_the_fixes_for_30_s() {
    // A 10 m jump south-west taken in before the alignment (its end in steps too small to
    // be read), then fixes the converged filter used from 50 s; at `onset` a burst jumps
    // 8.5 m north-east — the other way — and is held, the INS 14 m south-west of it. With
    // less than 30 s of used fixes (50-79 s) the jump is that burst's "end" (moved 5 s
    // later); after 30 s the burst is a hold like any other (the spell rule).
    let run = |onset: u32| {
        let mut o = Outlast::new(0.0, 1.0);
        let fix = |k: u32, off: [f64; 2]| [10.0 * k as f64 + off[0], off[1]];
        for k in 0..30u32 {
            let off = if k >= 29 { [-7.0, -7.0] } else { [0.0; 2] };
            o.taken(k as f64, fix(k, off), Some([10.0, 0.0]), None);
        }
        let v = Some([10.0, 0.0]);
        for k in 30..onset {
            // The INS pulled back onto the fixes by the updates, without a jump.
            let off = match k {
                ..45 => [-7.0, -7.0],
                45..48 => [-4.0, -4.0],
                _ => [-1.0, -1.0],
            };
            let p = Some(fix(k, off));
            assert!(!o.push(k as f64, p, v, [0.0; 2], false, false, k >= 50, false));
        }
        (onset..onset + 200).find(|&k| {
            let p = Some(fix(k, [6.0, 6.0]));
            o.push(k as f64, p, v, [-10.0, -10.0], true, true, true, false)
        })
    };
    assert_eq!(run(70), Some(76));
    assert_eq!(run(80), Some(86));
    assert_eq!(run(81), Some(81 + 81 + 30 + 1));
}

/// The INS is put on the fix, its velocity moved by the rate and its heading turned by
/// the change of course; the position and horizontal velocity variances reopened with
/// their correlations dropped, the heading's raised to (5°)².
#[test]
fn reanchoring_puts_the_ins_on_the_fix() {
    use crate::ins::error_filter::tests::noise;
    use crate::ins::error_filter::N;
    let lat = 0.7_f64;
    let q0 = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.3);
    let mut s = NavState {
        lat,
        lon: 0.2,
        h: 100.0,
        v: Vector3::new(10.0, 0.0, 0.0),
        q: q0,
    };
    let mut kf = ErrorFilter::<N>::new(1.0, 0.1, Vector3::repeat(0.001), Vector3::zeros(), noise());
    kf.p[(R, PHI)] = 0.5;
    kf.p[(PHI, R)] = 0.5;
    let before = s;
    // INS − fix: 30 m east, −40 m north, 2 m up; the INS running 10 m/s east of the fixes.
    let d = Vector3::new(30.0, -40.0, 2.0);
    reanchor(
        &mut s,
        &mut kf,
        &d,
        &Vector3::new(4.0, 5.0, 9.0),
        [10.0, 0.0],
    );
    let rm = crate::ins::earth::r_meridian(lat) + before.h;
    assert!(
        ((s.lat - before.lat) * rm - 40.0).abs() < 1e-6,
        "north moved by +40 m"
    );
    assert!((s.h - 98.0).abs() < 1e-9);
    // Velocity 10 north → 10 north − 10 east: the course turns by −45°, so does the heading.
    assert!((s.v.x - 10.0).abs() < 1e-12 && (s.v.y + 10.0).abs() < 1e-12);
    let turned = (s.q * before.q.inverse()).scaled_axis();
    assert!(
        (turned.z + std::f64::consts::FRAC_PI_4).abs() < 1e-9 && turned.xy().norm() < 1e-9,
        "{turned:?}"
    );
    assert_eq!(
        (kf.p[(R, R)], kf.p[(R + 1, R + 1)], kf.p[(R + 2, R + 2)]),
        (5.0, 4.0, 9.0)
    );
    assert_eq!((kf.p[(V, V)], kf.p[(V + 1, V + 1)]), (1.0, 101.0));
    assert_eq!((kf.p[(R, PHI)], kf.p[(PHI, R)]), (0.0, 0.0));
    assert!((kf.p[(PHI + 2, PHI + 2)] - REANCHOR_HEADING_VAR).abs() < 1e-15);
}

/// A held up step is watched as a horizontal one: it is the INS's height when it outlasts
/// the fixes before it by 30 s; the re-anchoring then moves the height alone.
#[test]
fn an_up_step_that_outlasts_the_fixes_before_it_moves_the_height_alone() {
    use crate::ins::error_filter::tests::noise;
    use crate::ins::error_filter::N;
    let mut w = InsWatch::new(Some(0.0), 1.0, std::iter::empty());
    assert!((0..44).all(|t| !w.vertical(t as f64, false, (true, false))));
    // Held from 44 s: it must outlast 44 − 0 + 30 s (fires at 119 s, not at 118 s).
    let fired: Vec<u32> = (44..200)
        .filter(|&t| w.vertical(t as f64, true, (true, false)))
        .collect();
    assert_eq!(fired.first(), Some(&119), "{fired:?}");
    // A hold that ends in time is forgotten.
    let mut w = InsWatch::new(Some(0.0), 1.0, std::iter::empty());
    assert!((44..100).all(|t| !w.vertical(t as f64, true, (true, false))));
    assert!(!w.vertical(100.0, false, (true, false)));
    // Holds of under a minute from 101 s on: each would have to outlast 131 s.
    assert!((101..400).all(|t| !w.vertical(t as f64, t % 60 != 0, (true, false))));
    // Held from the receiver's return to fixed fixes (after the filter
    // used float fixes): the return, moved after 5 s (at 50 s), not 75 s; the same for a
    // hold that started on a float fix and meets the return at 45 s (moved at 51 s).
    for (start, back, at) in [(44, 44, 50), (44, 45, 51)] {
        let mut w = InsWatch::new(Some(0.0), 1.0, std::iter::empty());
        assert!((0..start).all(|t| !w.vertical(t as f64, false, (true, false))));
        let fired: Vec<u32> = (start..200)
            .filter(|&t| w.vertical(t as f64, true, (true, t >= back && t < back + 10)))
            .collect();
        assert_eq!(fired.first(), Some(&at), "{fired:?}");
    }

    let mut s = NavState {
        lat: 0.7,
        lon: 0.2,
        h: 100.0,
        v: Vector3::new(10.0, 0.0, 0.3),
        q: UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.3),
    };
    let mut kf = ErrorFilter::<N>::new(1.0, 0.1, Vector3::repeat(0.001), Vector3::zeros(), noise());
    kf.p[(R + 2, V + 2)] = 0.01;
    kf.p[(V + 2, R + 2)] = 0.01;
    let (before, p0) = (s, kf.p);
    // INS − fix 0.4 m up: the INS comes down 0.4 m.
    let mut hold = super::super::hold::PositionHold::default();
    hold.comps[2] = super::super::hold::Comp::Step {
        b: 0.4,
        var: 0.01,
        back: false,
        agree: 0,
        quiet: 0,
        base: None,
        moved: false,
    };
    reanchor_up(&mut s, &mut kf, 0.4, 0.003, &mut hold);
    assert!(!hold.up_step());
    assert!((s.h - 99.6).abs() < 1e-12);
    assert_eq!(
        (s.lat, s.lon, s.v, s.q),
        (before.lat, before.lon, before.v, before.q)
    );
    assert_eq!(kf.p[(R + 2, R + 2)], 0.003);
    assert_eq!((kf.p[(R + 2, V + 2)], kf.p[(V + 2, R + 2)]), (0.0, 0.0));
    for i in (0..kf.p.nrows()).filter(|&i| i != R + 2) {
        for j in (0..kf.p.ncols()).filter(|&j| j != R + 2) {
            assert_eq!(kf.p[(i, j)], p0[(i, j)]);
        }
    }
}

#[test]
fn a_jump_at_the_alignments_own_fix_is_a_faults_start() {
    // A car at 10 m/s east, clean fixes to 31 s, the alignment at 32 s on a fix a 56 m burst
    // moved (the INS put on it: no innovation), the burst's end at 36 s held. The jump at 32 s
    // is read as before the alignment (not "onto the INS"): the INS is moved 5 s after the hold's
    // onset instead of after the spell (36 + 30 s).
    let v = Some([10.0, 0.0]);
    let fix = |k: u32| {
        let burst = if (32..36).contains(&k) {
            [21.6, -51.8]
        } else {
            [0.0; 2]
        };
        [10.0 * k as f64 + burst[0], burst[1]]
    };
    let mut o = Outlast::new(0.0, 1.0);
    for k in 0..32 {
        o.taken(k as f64, fix(k), v, None);
    }
    for k in 32..36 {
        assert!(!o.push(
            k as f64,
            Some(fix(k)),
            v,
            [0.0; 2],
            false,
            false,
            false,
            false
        ));
    }
    let d = [21.6, -51.8];
    let moved = (36..200).find(|&k| o.push(k as f64, Some(fix(k)), v, d, true, true, true, false));
    assert_eq!(moved, Some(42));
}

#[test]
fn a_stale_spells_catch_up_is_motion_not_a_jump() {
    // A car at 10 m/s east with the receiver's velocities; the receiver repeats its fix (and
    // velocity) over 31-34 s. Its first fresh fix is read from the last fresh one against the
    // velocities at both ends: the catch-up (40 m) is no jump, and a 20 m burst north that
    // began in the spell is that burst alone.
    let run = |burst_from: u32| {
        let mut j = Jumps::new(1.0);
        (0..60u32)
            .filter_map(|k| {
                let fresh = !(31..35).contains(&k);
                let at = if fresh { k } else { 30 };
                let burst = if (burst_from..45).contains(&at) {
                    20.0
                } else {
                    0.0
                };
                let p = [10.0 * at as f64, burst];
                j.push_with(k as f64, p, Some([10.0, 0.0]))
                    .map(|(e, _)| (k, e))
            })
            .collect::<Vec<_>>()
    };
    assert!(run(100).is_empty(), "{:?}", run(100));
    let jumps = run(33);
    assert_eq!(jumps.len(), 2, "{jumps:?}");
    let ((k0, e0), (k1, e1)) = (jumps[0], jumps[1]);
    assert_eq!((k0, k1), (35, 45));
    assert!(e0[0].abs() < 1e-9 && (e0[1] - 20.0).abs() < 1e-9, "{e0:?}");
    assert!(e1[0].abs() < 1e-9 && (e1[1] + 20.0).abs() < 1e-9, "{e1:?}");
}
