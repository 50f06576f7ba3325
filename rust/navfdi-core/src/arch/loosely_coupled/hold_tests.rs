//! Unit tests of the position hold ([`super::PositionHold`]).

use super::*;
use crate::arch::loosely_coupled::blame::VelocityBlame;

fn v(x: f64) -> Vector3<f64> {
    Vector3::new(0.0, x, 0.0)
}

const THR: f64 = 28.37; // χ²₁ at pf 1e-7

/// The receiver's consistency on north: `e`, σ_e and the window's sum of earlier `e` (m), no
/// ramp flagged.
fn north(e: f64, sigma: f64, window: f64) -> Consistency {
    Consistency {
        e: Vector3::new(0.0, e, 0.0),
        sigma: Vector3::repeat(sigma),
        ramp: [false; 3],
        onset: [None; 3],
        window: Vector3::new(0.0, window, 0.0),
        excursion: [[(0.0, 0.0); crate::arch::loosely_coupled::window::LAGS.len()]; 3],
        structure: [[f64::NAN; crate::arch::loosely_coupled::window::LAGS.len()]; 3],
        ins_referenced: false,
    }
}

/// One converged fix on north with innovation `d`, innovation variance `s` (every
/// component) and the receiver's consistency `c`: the north component's use.
fn decide_north(h: &mut PositionHold, t: f64, d: f64, s: f64, alarm: bool, c: &Consistency) -> Use {
    h.decide(
        t,
        &v(d),
        &Vector3::repeat(s),
        alarm,
        &[1],
        THR,
        Some(c),
        false,
        true,
        false,
        true,
        None,
    )[1]
}

fn step(h: &mut PositionHold, t: f64, d: f64, alarm: bool, ramp: bool) -> Use {
    step_e(h, t, d, alarm, ramp.then_some((-1.0, -11.0)))
}

/// One fix: `recv` the receiver's `e` on north and, where the CUSUM fires, the sum since
/// its onset (σ_e 1 m); None: no velocity channel.
fn step_e(h: &mut PositionHold, t: f64, d: f64, alarm: bool, recv: Option<(f64, f64)>) -> Use {
    step_with(h, t, d, alarm, recv, false)
}

/// [`step_e`] with the consistency read against the receiver's velocity or, `ins_referenced`,
/// against the INS's displacement (a receiver without velocities).
fn step_with(
    h: &mut PositionHold,
    t: f64,
    d: f64,
    alarm: bool,
    recv: Option<(f64, f64)>,
    ins_referenced: bool,
) -> Use {
    let s = Vector3::repeat(4.5);
    let c = recv.map(|(e, sum)| Consistency {
        e: Vector3::new(0.0, e, 0.0),
        sigma: Vector3::repeat(1.0),
        ramp: [false, sum != 0.0, false],
        onset: [None, (sum != 0.0).then_some((sum, 11.0)), None],
        window: Vector3::zeros(),
        excursion: [[(0.0, 0.0); crate::arch::loosely_coupled::window::LAGS.len()]; 3],
        structure: [[f64::NAN; crate::arch::loosely_coupled::window::LAGS.len()]; 3],
        ins_referenced,
    });
    h.decide(
        t,
        &v(d),
        &s,
        alarm,
        &[1],
        THR,
        c.as_ref(),
        c.is_none(),
        true,
        false,
        true,
        None,
    )[1]
}

/// A hold after five clean fixes on north (the receiver consistent), all used as measured.
fn settled() -> PositionHold {
    let mut h = PositionHold::default();
    for k in 0..5 {
        assert_eq!(
            step_e(&mut h, k as f64, 0.1, false, Some((0.1, 0.0))),
            Use::Raw
        );
    }
    h
}

/// [`settled`], then a 20 m north step from 5 s held (a relative fix) for five fixes.
fn held_step() -> PositionHold {
    let mut h = settled();
    assert!(matches!(
        step_e(&mut h, 5.0, -20.0, true, Some((20.0, 0.0))),
        Use::Relative(..)
    ));
    for k in 6..10 {
        step_e(&mut h, k as f64, -20.0, true, Some((0.1, 0.0)));
    }
    h
}

/// A ramp taken for a step (its size followed by the receiver's inconsistency) that the
/// INS partly followed: when the receiver jumps back to where its velocity says it is, the
/// fix is used as measured at once (it corrects the INS), not held as a new offset equal
/// to the INS's error.
#[test]
fn the_receivers_jump_back_ends_a_hold_the_ins_partly_followed() {
    let mut h = settled();
    // The fix jumps by 5 m (a step to the receiver: e = 5 m against σ_e 1 m), then keeps
    // moving 2 m per fix; the INS ends 3 m off by the ramp's end.
    assert!(matches!(
        step_e(&mut h, 5.0, -5.0, true, Some((5.0, 0.0))),
        Use::Relative(..)
    ));
    let mut d = -5.0;
    for k in 6..20 {
        d -= 1.8;
        assert!(
            matches!(
                step_e(&mut h, k as f64, d, true, Some((2.0, 0.0))),
                Use::Relative(..) | Use::Out(STEP)
            ),
            "{k}"
        );
    }
    // The receiver returns by the whole accumulated 33 m; the INS is 3 m off. Its fixes
    // are used as measured while the receiver stays consistent, even though the test
    // still alarms, until one agrees with the INS.
    assert_eq!(
        step_e(&mut h, 20.0, 3.0, true, Some((-33.0, 0.0))),
        Use::Raw
    );
    assert_eq!(h.comps[1], Comp::Return { fixes: 1 });
    assert_eq!(step_e(&mut h, 21.0, 2.5, true, Some((0.1, 0.0))), Use::Raw);
    assert_eq!(step_e(&mut h, 22.0, 0.2, false, Some((0.1, 0.0))), Use::Raw);
    assert_eq!(h.comps[1], Comp::Normal);
}

/// A multipath burst on top of a held step, the same way (the offset follows it through the
/// receiver's consistency): its end takes the offset back to the step's, which is not the
/// fault's end — the step stays held; the step's own end is.
#[test]
fn a_burst_on_a_held_step_ends_back_on_the_step() {
    let mut h = held_step();
    // A 25 m burst on it, the same way, for five fixes.
    step_e(&mut h, 10.0, -45.0, true, Some((25.0, 0.0)));
    for k in 11..15 {
        assert!(matches!(
            step_e(&mut h, k as f64, -45.0, true, Some((0.1, 0.0))),
            Use::Relative(..)
        ));
    }
    // The burst ends: the fix jumps back 25 m (more than half of the 45 m offset), to the step.
    assert!(matches!(
        step_e(&mut h, 15.0, -20.0, true, Some((-25.0, 0.0))),
        Use::Relative(..)
    ));
    assert!(
        matches!(h.comps[1], Comp::Step { b, .. } if (b + 20.0).abs() < 0.5),
        "{:?}",
        h.comps[1]
    );
    for k in 16..20 {
        step_e(&mut h, k as f64, -20.0, true, Some((0.1, 0.0)));
    }
    // The step ends.
    assert_eq!(
        step_e(&mut h, 20.0, 0.0, false, Some((-20.0, 0.0))),
        Use::Raw
    );
    assert_eq!(h.comps[1], Comp::Return { fixes: 1 });
}

/// A multipath burst against a held step: its start reads as the step's end (a return,
/// the fixes used as measured — right, the burst cancels the step), and its end, a jump back
/// to the step's offset that also cancels the window's record of the burst's start, resumes
/// the step instead of reading as a second return.
#[test]
fn a_burst_against_a_held_step_ends_by_resuming_it() {
    let mut h = held_step();
    // The burst: the fix back near the truth.
    assert_eq!(
        step_e(&mut h, 10.0, -1.0, false, Some((-19.0, 0.0))),
        Use::Raw
    );
    for k in 11..16 {
        assert_eq!(
            step_e(&mut h, k as f64, -1.0, false, Some((0.1, 0.0))),
            Use::Raw
        );
    }
    // Its end: back to the step's offset, the window holding the burst's −19 m.
    let u = decide_north(&mut h, 16.0, -20.0, 4.5, true, &north(19.0, 1.0, -19.0));
    assert!(matches!(u, Use::Relative(..)), "{u:?}");
    assert!(matches!(h.comps[1], Comp::Step { .. }), "{:?}", h.comps[1]);
}

/// A fault the filter followed unseen (no alarm during it): at its end the receiver
/// returns; its fixes correct the INS though the test alarms at them, and a new jump
/// while returning is tested again.
#[test]
fn a_return_is_used_until_the_ins_agrees() {
    let mut h = PositionHold::default();
    let mk = |e: f64, w: f64| north(e, 0.7, w);
    let go = |h: &mut PositionHold, t: f64, d: f64, alarm: bool, c: Consistency| {
        decide_north(h, t, d, 8.0, alarm, &c)
    };
    // 27 m of drift, 25 m of it in the window: a return, not a new step.
    assert_eq!(go(&mut h, 0.0, 16.5, true, mk(-26.7, 25.0)), Use::Raw);
    assert!(matches!(h.comps[1], Comp::Return { .. }));
    // The test still alarms (|d|² / s above 28.4): used as measured while returning.
    for (k, d) in [(1.0, 16.3), (2.0, 15.8)] {
        assert_eq!(go(&mut h, k, d, true, mk(0.2, -8.0)), Use::Raw, "{k}");
    }
    // A new jump of the receiver while returning: tested as any fix.
    assert_eq!(go(&mut h, 3.0, 20.0, true, mk(15.0, -8.0)), Use::Out(TEST));
    assert_eq!(h.comps[1], Comp::Normal);
}

/// The end of a slow ramp the filter partly followed, traced on a σ 2 m Gauss-Markov drive
/// (0.45 m/s from 300 s, not flagged): the fix 6.2 m ahead of the INS, the receiver 8.8 m
/// (3.6 σ of its 30 s window sums) drifted that way, then a jump of −17.5 m back across the
/// INS — a return (before, held as an 11.6 m step for the rest of the fault's window). The
/// same jump with the INS on the fix a moment before, or without a significant drift, is a
/// step.
#[test]
fn a_jump_back_across_a_lagging_ins_after_a_drift_is_a_return() {
    let drifted = |e: f64| {
        let mut c = north(e, 0.74, 9.8);
        c.excursion[1][1] = (8.8, 3.6);
        c
    };
    let run = |d_before: f64, c: Consistency| {
        let mut h = PositionHold::default();
        assert_eq!(
            decide_north(&mut h, 339.0, d_before, 9.36, false, &north(1.1, 0.74, 9.8)),
            Use::Raw
        );
        let u = decide_north(&mut h, 340.0, 11.57, 9.36, false, &c);
        (u, h.comps[1])
    };
    let (u, comp) = run(-6.16, drifted(-17.46));
    assert_eq!((u, comp), (Use::Raw, Comp::Return { fixes: 1 }));
    // The INS on the fix before the jump: a step's onset.
    let (_, comp) = run(-0.5, drifted(-17.46));
    assert!(matches!(comp, Comp::Step { .. }), "{comp:?}");
    // No significant drift of the receiver before it (2.5 σ): a step.
    let mut weak = drifted(-17.46);
    weak.excursion[1][1] = (6.0, 2.5);
    let (_, comp) = run(-6.16, weak);
    assert!(matches!(comp, Comp::Step { .. }), "{comp:?}");
}

/// The same jump back across the INS where the receiver's windows were restarted by a stop
/// (no drift to read) but the fixes had been off the INS that way (|w| > 2) for
/// [`LAG_RUN`] s: a return, the run's mean standing for the lag where larger than its last
/// fix's (which may dip below |w| 2). After a shorter run, with the INS on the fix at the fix before, or with the jump
/// landing beyond [`LAG_RATIO`] times the lag, a step.
#[test]
fn a_jump_back_across_an_ins_lagging_for_seconds_is_a_return() {
    let run = |lagging: usize, d_before: f64, d_after: f64| {
        let mut h = PositionHold::default();
        let quiet = north(0.3, 0.74, 0.0);
        for k in 0..5 {
            decide_north(&mut h, 300.0 + k as f64, 0.5, 9.36, false, &quiet);
        }
        // The fixes run ahead of the INS (d = INS − fix < 0, |w| 2.6–3.3) for `lagging` fixes.
        for k in 0..lagging {
            let d = if k + 1 == lagging {
                d_before
            } else {
                -8.0 - 0.2 * k as f64
            };
            decide_north(&mut h, 305.0 + k as f64, d, 9.36, false, &quiet);
        }
        let t = 305.0 + lagging as f64;
        let jump = north(d_before - d_after, 0.74, 0.0);
        let u = decide_north(&mut h, t, d_after, 9.36, true, &jump);
        (u, h.comps[1])
    };
    assert_eq!(run(6, -10.0, 9.9), (Use::Raw, Comp::Return { fixes: 1 }));
    let (_, comp) = run(4, -10.0, 9.9);
    assert!(matches!(comp, Comp::Step { .. }), "{comp:?}");
    let (_, comp) = run(6, -0.5, 9.9);
    assert!(matches!(comp, Comp::Step { .. }), "{comp:?}");
    // A jump far beyond the lag (a burst starting: 45 m against a mean lag of 8 m): a step.
    let (_, comp) = run(6, -7.0, 45.0);
    assert!(matches!(comp, Comp::Step { .. }), "{comp:?}");
    assert_eq!(run(6, -7.0, 20.0).0, Use::Raw);
    // The run's last fix dipped to |w| 1.3: its mean lag stands, a return.
    assert_eq!(run(6, -4.0, 9.9).0, Use::Raw);
}

/// A held step's offset follows the receiver's own jump where the INS agrees the fix moved,
/// or where the jump is beyond any noise ([`MOVE_ALONE`] σ_e): one noisy fix (white σ 1 m
/// fixes: 2.5 m one way, then 2.5 m the other) is a 5 m jump of the receiver's consistency
/// (σ_e 1.4 m) the INS does not see, and the offset stays (before, it moved 5 m for the rest
/// of the fault); a ramp the INS follows (8σ_e per fix) moves it.
#[test]
fn a_held_offset_moves_with_a_jump_the_ins_confirms_or_beyond_noise() {
    let offset = |h: &PositionHold| match h.comps[1] {
        Comp::Step { b, .. } => b,
        c => panic!("{c:?}"),
    };
    let fix = |h: &mut PositionHold, t: f64, d: f64, e: f64| {
        decide_north(h, t, d, 4.5, true, &north(e, 1.4, 0.0))
    };
    let held = || {
        let mut h = PositionHold::default();
        for k in 0..5 {
            fix(&mut h, k as f64, 0.1, 0.1);
        }
        assert!(matches!(fix(&mut h, 5.0, -20.0, 20.0), Use::Relative(..)));
        h
    };
    // Noise: +2.5 m (within 3σ_e), −2.5 m (a 5 m jump), back.
    let mut h = held();
    fix(&mut h, 6.0, -22.5, 2.5);
    fix(&mut h, 7.0, -17.5, -5.0);
    assert_eq!(offset(&h), -20.0);
    let u = fix(&mut h, 8.0, -20.0, 2.5);
    assert!(matches!(u, Use::Relative(b, _) if b == -20.0), "{u:?}");
    // A move the INS confirms (the fix 5 m further off it): taken.
    let mut h = held();
    fix(&mut h, 6.0, -24.8, 5.0);
    assert_eq!(offset(&h), -25.0);
    // A ramp the INS follows (the innovation unchanged), 8σ_e per fix: taken.
    let mut h = held();
    fix(&mut h, 6.0, -20.0, 11.2);
    assert!((offset(&h) + 31.2).abs() < 1e-9, "{}", offset(&h));
}

/// A held ramp on a receiver whose drift windows saturate (white errors: their sums do not
/// grow with the window): the size's variance stops at its onset's plus the receiver's
/// measured drift spread, so a ramp still growing stays held. Grown as a random walk's instead
/// (the spread not yet measured), the 10 m ramp's size sinks into it within five fixes and the
/// hold ends ten fixes later, mid-ramp.
#[test]
fn a_held_ramps_variance_stops_at_the_receivers_drift_spread() {
    let run = |spread: f64| {
        let mut h = PositionHold::default();
        for k in 0..10 {
            decide_north(&mut h, k as f64, 0.0, 4.5, false, &north(0.0, 2.0, 0.0));
        }
        let fix = |e: f64, onset: Option<(f64, f64)>| {
            let mut c = north(e, 2.0, 0.0);
            c.onset[1] = onset;
            c.ramp[1] = onset.is_some();
            c.structure[1] = [spread; crate::arch::loosely_coupled::window::LAGS.len()];
            c
        };
        let u = decide_north(
            &mut h,
            10.0,
            10.0,
            4.5,
            true,
            &fix(-0.5, Some((-10.0, 4.0))),
        );
        assert_eq!(u, Use::Out(RAMP));
        for k in 1..=25 {
            let d = 10.0 + 0.5 * k as f64;
            decide_north(&mut h, 10.0 + k as f64, d, 4.5, true, &fix(-0.5, None));
        }
        h.comps[1]
    };
    assert!(matches!(run(8.0), Comp::Drift { .. }), "{:?}", run(8.0));
    assert!(
        matches!(run(f64::NAN), Comp::Return { .. } | Comp::Normal),
        "{:?}",
        run(f64::NAN)
    );
}

/// A ramp's first increment on RTK fixes (σ_e 4 cm) beside a window of latency residuals
/// the other way is not a return: the jump does not stand out of the window's own noise.
#[test]
fn a_small_jump_against_window_noise_is_not_a_return() {
    let mut h = PositionHold::default();
    let u = decide_north(&mut h, 0.0, -0.4, 0.003, true, &north(0.4, 0.04, -0.8));
    assert!(matches!(h.comps[1], Comp::Step { .. }), "{:?}", h.comps[1]);
    assert!(matches!(u, Use::Relative(..)));
}

/// A 20 m step on north at σ 2 m: held from its first fix to its last (used as a relative
/// fix), re-admitted two fixes after it ends.
#[test]
fn steps_are_held_to_their_end() {
    let mut h = PositionHold::default();
    for k in 0..5 {
        assert_eq!(step(&mut h, k as f64, 0.5, false, false), Use::Raw);
    }
    assert_eq!(
        step(&mut h, 5.0, 20.0, true, false),
        Use::Relative(20.0, 4.5)
    );
    for k in 6..30 {
        // The raw fix stays 19.5 m off the INS: never re-admitted while it lasts.
        assert_eq!(
            step(&mut h, k as f64, 19.5, true, false),
            Use::Relative(20.0, 4.5),
            "{k}"
        );
    }
    assert_eq!(step(&mut h, 30.0, 0.3, false, false), Use::Out(STEP));
    assert_eq!(step(&mut h, 31.0, 0.3, false, false), Use::Raw);
}

/// An alarm that grew into the test (no jump) leaves that fix out and holds nothing; a
/// ramp flagged by the sequential test is held, its size followed by the receiver's
/// inconsistency (used as a relative fix once the fix leaves the INS), until the receiver
/// jumps back and the fix agrees with the INS.
#[test]
fn ramps_are_held_until_the_receiver_returns() {
    let mut h = PositionHold::default();
    for k in 0..10 {
        step(&mut h, k as f64, 0.0, false, false);
    }
    let mut d = 0.0;
    for k in 10..20 {
        d += 1.0;
        let alarm = d * d / 4.5 > THR;
        let u = step(&mut h, k as f64, d, alarm, false);
        assert_eq!(u, if alarm { Use::Out(TEST) } else { Use::Raw }, "{k}");
    }
    // Flagged at the 11th fix of the ramp (fix 11 m off, receiver −11 m since onset).
    d += 1.0;
    assert_eq!(
        step_e(&mut h, 20.0, d, true, Some((-1.0, -11.0))),
        Use::Out(RAMP)
    );
    for k in 21..40 {
        d += 1.0;
        let u = step_e(&mut h, k as f64, d, true, Some((-1.0, 0.0)));
        // b = 11 + (k − 20) follows the fix exactly: used relative to it.
        assert_eq!(u, Use::Relative(d, 11.0 + (k - 20) as f64), "{k}");
    }
    // The ramp's end: the receiver jumps back by its size (b ≈ −1 m, σ 5.6 m: used
    // relative to it); re-admitted on the second agreement.
    assert_eq!(
        step_e(&mut h, 40.0, 0.2, false, Some((31.0, 0.0))),
        Use::Relative(-1.0, 31.0)
    );
    assert_eq!(step_e(&mut h, 41.0, 0.2, false, Some((0.0, 0.0))), Use::Raw);
}

/// On positions only (the consistency against the INS's displacement) a jump of the fix on
/// a held step — a multipath burst on top of it — is a new offset: the fixes of the burst are
/// used relative to it, not relative to the step's offset (a 33 m relative innovation passed
/// the gate at pf 1e-12 as the INS's variance grew, and pulled a simulated log 536 m RMS off).
#[test]
fn a_jump_on_a_held_step_against_the_ins_displacement_is_a_new_offset() {
    let mut h = PositionHold::default();
    for k in 0..10 {
        step_with(&mut h, k as f64, 0.0, false, Some((0.0, 0.0)), true);
    }
    // A 30 m step (the fix +30 m: innovation −30), held and used relative to its offset.
    assert!(matches!(
        step_with(&mut h, 10.0, -30.0, true, Some((30.0, 0.0)), true),
        Use::Relative(b, _) if b == -30.0
    ));
    assert!(matches!(
        step_with(&mut h, 11.0, -30.0, true, Some((0.0, 0.0)), true),
        Use::Relative(b, _) if b == -30.0
    ));
    // A burst moves the fix 40 m further: left out, its offset taken as the new one, and its
    // next fix used relative to that (not left out against the step's −30 m).
    assert_eq!(
        step_with(&mut h, 12.0, -70.0, true, Some((40.0, 0.0)), true),
        Use::Out(STEP)
    );
    assert!(matches!(
        step_with(&mut h, 13.0, -70.0, true, Some((0.0, 0.0)), true),
        Use::Relative(b, _) if b == -70.0
    ));
}

/// On positions only, the end of that burst — the fix jumping back to the step's offset, by
/// more than half the burst's — is no fault's end: the step stays held, and its own end is
/// (on a simulated positions-only route with stops, a 37.5 m step was followed for its last
/// 20 s from a burst's end, the jump back read as the step's end).
#[test]
fn a_bursts_end_on_a_held_step_against_the_ins_displacement_keeps_the_step() {
    let mut h = PositionHold::default();
    for k in 0..10 {
        step_with(&mut h, k as f64, 0.0, false, Some((0.0, 0.0)), true);
    }
    step_with(&mut h, 10.0, -30.0, true, Some((30.0, 0.0)), true);
    step_with(&mut h, 11.0, -30.0, true, Some((0.0, 0.0)), true);
    assert_eq!(
        step_with(&mut h, 12.0, -70.0, true, Some((40.0, 0.0)), true),
        Use::Out(STEP)
    );
    step_with(&mut h, 13.0, -70.0, true, Some((0.0, 0.0)), true);
    // The burst ends: the fix jumps back 40 m, onto the step.
    let u = step_with(&mut h, 14.0, -30.0, true, Some((-40.0, 0.0)), true);
    assert_eq!(u, Use::Out(STEP));
    assert!(
        matches!(h.comps[1], Comp::Step { b, .. } if b == -30.0),
        "{:?}",
        h.comps[1]
    );
    assert!(matches!(
        step_with(&mut h, 15.0, -30.0, true, Some((0.0, 0.0)), true),
        Use::Relative(b, _) if b == -30.0
    ));
    // The step ends: the fix back on the INS.
    assert_eq!(
        step_with(&mut h, 16.0, 0.0, false, Some((-30.0, 0.0)), true),
        Use::Raw
    );
    assert_eq!(h.comps[1], Comp::Return { fixes: 1 });
}

/// One multipath burst giving way to a smaller one the same way: the fix jumps back by more
/// than half the held offset but stays off the INS beyond the deciding test. That is the fault
/// changing, not ending: its fixes are held at the new offset, not used as measured (a
/// simulated positions-only log, a 33 m burst followed by a 13 m one: the jump back was taken
/// for the end, the second burst's fixes pulled the INS 30 m off and it ran away, 24.5 m RMS
/// against 0.35 m with them held).
#[test]
fn a_burst_giving_way_to_a_smaller_one_is_no_end() {
    for ins_referenced in [true, false] {
        let mut h = PositionHold::default();
        for k in 0..10 {
            step_with(
                &mut h,
                k as f64,
                0.0,
                false,
                Some((0.0, 0.0)),
                ins_referenced,
            );
        }
        // The fix 40 m north (innovation −40), held.
        step_with(&mut h, 10.0, -40.0, true, Some((40.0, 0.0)), ins_referenced);
        step_with(&mut h, 11.0, -40.0, true, Some((0.0, 0.0)), ins_referenced);
        // Back by 25 m of 40: the fix still 15 m off (w² 50 against THR 28.4).
        let u = step_with(
            &mut h,
            12.0,
            -15.0,
            true,
            Some((-25.0, 0.0)),
            ins_referenced,
        );
        assert_ne!(u, Use::Raw, "{ins_referenced}");
        assert!(
            matches!(h.comps[1], Comp::Step { .. }),
            "{ins_referenced}: {:?}",
            h.comps[1]
        );
        assert!(
            matches!(
                step_with(&mut h, 13.0, -15.0, true, Some((0.0, 0.0)), ins_referenced),
                Use::Relative(b, _) if b == -15.0
            ),
            "{ins_referenced}"
        );
        // Its end, the fix back on the INS, is the end.
        assert_eq!(
            step_with(&mut h, 14.0, 0.0, false, Some((-15.0, 0.0)), ins_referenced),
            Use::Raw,
            "{ins_referenced}"
        );
    }
}

/// The same jump back where another held component of the fix lands on the INS at once: the
/// burst has ended, and what the first component is left off by is the INS's own drift — the
/// end, used as measured (a ramp the INS had followed, with a burst on top, kept the INS's
/// 14 m drift held as a new step otherwise, 79 m off after the ramp).
#[test]
fn a_jump_back_beside_a_component_back_on_the_ins_is_the_end() {
    let mut h = PositionHold::default();
    let s = Vector3::repeat(4.5);
    let fix = |h: &mut PositionHold, t: f64, d: Vector3<f64>, e: Vector3<f64>, alarm: bool| {
        let c = Consistency {
            e,
            ins_referenced: true,
            ..north(0.0, 1.0, 0.0)
        };
        h.decide(
            t,
            &d,
            &s,
            alarm,
            &[1, 2],
            THR,
            Some(&c),
            false,
            true,
            false,
            true,
            None,
        )
    };
    for k in 0..10 {
        fix(&mut h, k as f64, Vector3::zeros(), Vector3::zeros(), false);
    }
    // A burst: the fix 40 m north and 20 m up, both held.
    let burst = Vector3::new(0.0, -40.0, -20.0);
    fix(&mut h, 10.0, burst, -burst, true);
    fix(&mut h, 11.0, burst, Vector3::zeros(), true);
    assert!(matches!(h.comps[1], Comp::Step { .. }) && matches!(h.comps[2], Comp::Step { .. }));
    // Its end: up back on the INS, north left 15 m off by the INS's drift during the hold.
    let u = fix(
        &mut h,
        12.0,
        Vector3::new(0.0, -15.0, 0.0),
        Vector3::new(0.0, -25.0, 20.0),
        true,
    );
    assert_eq!(u[1], Use::Raw);
    assert_eq!(h.comps[1], Comp::Return { fixes: 1 });
}

/// On positions only a held ramp's size follows the fixes' displacement against the INS's
/// velocity for its first [`AGREE_LONG`] fixes, then the line they drew: an INS velocity
/// error that shows in the displacement afterwards is not taken into the size (the relative
/// fixes then see it), and a fix off the line beyond the test starts a new line.
#[test]
fn a_ramp_against_the_ins_displacement_follows_its_line() {
    let mut h = PositionHold::default();
    for k in 0..10 {
        step_with(&mut h, k as f64, 0.0, false, Some((0.0, 0.0)), true);
    }
    let mut d = 11.0;
    assert_eq!(
        step_with(&mut h, 10.0, d, true, Some((-1.0, -11.0)), true),
        Use::Out(RAMP)
    );
    // A 1 m/s ramp: the size follows the displacement, then its line (1 m/s from 11 m at 10 s).
    for k in 11..25 {
        d += 1.0;
        let u = step_with(&mut h, k as f64, d, true, Some((-1.0, 0.0)), true);
        assert_eq!(u, Use::Relative(d, 1.0 + k as f64), "{k}");
    }
    // The INS's velocity drifts 0.5 m/s off: the displacement says −1.5 m per fix, the size
    // stays on the line, and the fix (the INS 0.5 m further off each second) is used relative
    // to it until it leaves the test.
    for k in 25..30 {
        d += 1.5;
        let u = step_with(&mut h, k as f64, d, true, Some((-1.5, 0.0)), true);
        assert!(
            matches!(u, Use::Relative(b, _) if b == 1.0 + k as f64),
            "{k}: {u:?}"
        );
    }
}

/// A sequential-test alarm whose fix never leaves the INS is a false one: held for
/// [`PROBATION`] fixes only.
#[test]
fn a_false_ramp_alarm_is_over_after_probation() {
    let mut h = PositionHold::default();
    assert_eq!(
        step_e(&mut h, 0.0, 0.5, false, Some((0.3, -12.0))),
        Use::Out(RAMP)
    );
    for k in 1..PROBATION {
        assert_eq!(
            step_e(&mut h, k as f64, 0.5, false, Some((0.3, 0.0))),
            Use::Out(RAMP)
        );
    }
    assert_eq!(step_e(&mut h, 9.0, 0.5, false, Some((0.3, 0.0))), Use::Raw);
}

/// A receiver jump that cancels its earlier drift (a ramp the filter followed, ending) is
/// used as measured, not held as a new step.
#[test]
fn a_return_to_consistency_is_not_a_step() {
    let mut h = PositionHold::default();
    assert_eq!(
        decide_north(&mut h, 0.0, -4.0, 0.01, true, &north(4.0, 0.05, -3.9)),
        Use::Raw
    );
    // The same jump without an earlier drift is a step.
    let mut h = PositionHold::default();
    assert_eq!(
        decide_north(&mut h, 0.0, -4.0, 0.01, true, &north(4.0, 0.05, 0.0)),
        Use::Relative(-4.0, 0.01)
    );
}

#[test]
fn a_stale_fix_is_one_repeated_while_the_ins_moves() {
    let mut h = PositionHold::default();
    let f = Vector3::new(1.0, 2.0, 3.0);
    assert!(!h.stale(&f, &Vector3::zeros()));
    assert!(h.stale(&f, &Vector3::new(10.0, 0.0, 0.0)));
    assert!(!h.stale(&f, &Vector3::new(0.1, 0.0, 0.0)));
    assert!(!h.stale(&(f + Vector3::repeat(0.01)), &Vector3::new(20.0, 0.0, 0.0)));
}

/// The receiver's consistency does not take a stale fix in: a spell of repeated fixes while
/// moving at 10 m/s north gives no consistency, and the first fresh fix after it is measured
/// across the spell (a gap: no jump, the sequential tests restarted) instead of reading as a
/// 40 m jump back. Only with the receiver's own velocity.
#[test]
fn the_receiver_consistency_skips_stale_fixes() {
    let mut r = ReceiverConsistency::default();
    let vel = v(10.0);
    let at = |t: f64| Vector3::new(0.0, 10.0 * t, 0.0);
    let mut got = None;
    for k in 0..40 {
        let t = k as f64;
        got = r.step(t, &at(t), &vel, 2.5, true);
    }
    let c = got.expect("moving fixes give a consistency once σ_e is known");
    assert!(c.e.amax() < 1e-6);
    for k in 40..44 {
        assert!(
            r.step(k as f64, &at(39.0), &vel, 2.5, true).is_none(),
            "stale fix at {k} s"
        );
    }
    assert!(r.step(44.0, &at(44.0), &vel, 2.5, true).is_none());
    let c = r
        .step(45.0, &at(45.0), &vel, 2.5, true)
        .expect("fresh fixes again");
    assert!(c.e.amax() < 1e-6 && c.onset.iter().all(|o| o.is_none()));
    // Against the INS's displacement (positions only) it is taken in, as before.
    let mut r = ReceiverConsistency::default();
    for k in 0..40 {
        r.step(k as f64, &at(k as f64), &vel, 2.5, false);
    }
    assert!(r
        .step(40.0, &at(39.0), &vel, 2.5, false)
        .is_some_and(|c| c.e[1] < -5.0));
}

/// A faulty velocity (the receiver's displacement off by −δv·Δt per fix, its velocity's
/// innovation −δv) is blamed from the second fix and while it lasts; a position ramp (the
/// velocity's innovation near 0) and a one-fix blip of the velocity's noise are not.
#[test]
fn a_velocity_is_blamed_where_its_innovation_says_what_the_receiver_does() {
    let s_dv = Vector3::repeat(0.01); // σ 0.1 m/s
    let quiet = Vector3::repeat(1.0);
    // Velocity 0.5 m/s north too large: e = −0.5 m, dv = −0.5 m/s (5σ).
    let mut b = VelocityBlame::default();
    let c = north(-0.5, 0.02, 0.0);
    assert_eq!(b.step(&c, &v(-0.5), &s_dv, &quiet, 1.0), [false; 3]);
    for _ in 0..10 {
        assert_eq!(
            b.step(&c, &v(-0.5), &s_dv, &quiet, 1.0),
            [false, true, false]
        );
    }
    // It ends: the receiver consistent again.
    assert_eq!(
        b.step(&north(0.0, 0.02, 0.0), &v(-0.05), &s_dv, &quiet, 1.0),
        [false; 3]
    );
    // A position ramp of 0.5 m/s: e = +0.5 m, the velocity right (dv 0.02).
    let mut b = VelocityBlame::default();
    let ramp = north(0.5, 0.02, 0.0);
    for _ in 0..10 {
        assert_eq!(b.step(&ramp, &v(0.02), &s_dv, &quiet, 1.0), [false; 3]);
    }
    // Its start meeting one large velocity-noise value: not blamed (one fix), nor later when
    // the filter, following the ramp, has the INS velocity on the ramp's rate.
    let mut b = VelocityBlame::default();
    assert_eq!(b.step(&ramp, &v(0.4), &s_dv, &quiet, 1.0), [false; 3]);
    for _ in 0..3 {
        assert_eq!(b.step(&ramp, &v(0.02), &s_dv, &quiet, 1.0), [false; 3]);
    }
    for _ in 0..5 {
        assert_eq!(b.step(&ramp, &v(0.45), &s_dv, &quiet, 1.0), [false; 3]);
    }
    // Against the INS (a receiver without velocities) nothing is blamed.
    let mut b = VelocityBlame::default();
    let ins = Consistency {
        ins_referenced: true,
        ..north(-0.5, 0.02, 0.0)
    };
    for _ in 0..3 {
        assert_eq!(b.step(&ins, &v(-0.5), &s_dv, &quiet, 1.0), [false; 3]);
    }
}

/// A held ramp whose end comes at rest, where the receiver's consistency is not read: the
/// fix jumps back across an INS the GNSS updates had pulled the ramp's way (16 m of position
/// corrections, as a filter that weighs the fixes too much follows a ramp while ZUPT holds the
/// velocity), which ends the hold, and the fixes after it are used as measured while they
/// correct the INS — before, the ramp was held for the rest of the run.
#[test]
fn a_ramps_end_at_rest_across_a_pull_is_a_return() {
    let mut pull = crate::arch::loosely_coupled::pull::PullHistory::default();
    for k in 0..41 {
        pull.add(k as f64, &v(0.4), &Vector3::zeros());
    }
    let mut h = settled();
    // The ramp flagged by the receiver (11 m since its onset), the fix 4 m north of the INS.
    assert!(matches!(
        step_e(&mut h, 30.0, -4.0, true, Some((1.0, 11.0))),
        Use::Out(RAMP) | Use::Relative(..)
    ));
    assert!(matches!(h.comps[1], Comp::Drift { .. }), "{:?}", h.comps[1]);
    let at_rest = |h: &mut PositionHold, t: f64, d: f64, pull| {
        h.decide(
            t,
            &v(d),
            &Vector3::repeat(4.5),
            d * d / 4.5 > THR,
            &[1],
            THR,
            None,
            true,
            true,
            false,
            true,
            pull,
        )[1]
    };
    assert!(matches!(
        at_rest(&mut h, 31.0, -4.2, Some(&pull)),
        Use::Out(RAMP) | Use::Relative(..)
    ));
    // Without the pull the jump back is not told from a new fault: still held.
    let mut other = h.clone();
    assert!(matches!(
        at_rest(&mut other, 32.0, 16.0, None),
        Use::Out(_) | Use::Relative(..)
    ));
    // With it: a return, and the fixes that follow correct the INS.
    assert_eq!(at_rest(&mut h, 32.0, 16.0, Some(&pull)), Use::Raw);
    assert_eq!(at_rest(&mut h, 33.0, 12.0, Some(&pull)), Use::Raw);
    assert_eq!(at_rest(&mut h, 34.0, 8.0, Some(&pull)), Use::Raw);
}

#[path = "hold_landing_tests.rs"]
mod landing;
