//! Unit tests of where a fix lands when it jumps back: the end of a held step lands the fix on
//! the INS, or across it by at most what the INS followed — never further across than the held
//! offset itself.

use super::*;

/// A held 20 m north step (offset −20) whose end comes with a 40 m fault the other way at the
/// same fix (traced: a multipath burst held as a step gave way, at one fix, to a 40 m step; the
/// jump "back" was taken for the burst's end and the step used as measured for ten fixes,
/// 20.6 m RMS through it). The fix lands 40 m across the INS, beyond the held offset: a new
/// offset, held, whose own end is then the end — with the receiver's velocities or without.
#[test]
fn a_jump_back_past_the_held_offset_is_a_new_fault() {
    let mut h = held_step();
    let u = step_e(&mut h, 10.0, 40.0, true, Some((-60.0, 0.0)));
    assert!(
        matches!(u, Use::Relative(b, _) if (b - 40.0).abs() < 1e-9),
        "{u:?}"
    );
    assert!(matches!(h.comps[1], Comp::Step { .. }), "{:?}", h.comps[1]);
    for k in 11..15 {
        assert!(matches!(
            step_e(&mut h, k as f64, 40.0, true, Some((0.1, 0.0))),
            Use::Relative(..)
        ));
    }
    // The new fault's end: back on the INS — or across it by 12 m (the INS followed part of
    // it), nearer the old offset than zero: the old fault is over, nothing to go back to.
    let mut other = h.clone();
    assert_eq!(
        step_e(&mut h, 15.0, 0.2, false, Some((40.0, 0.0))),
        Use::Raw
    );
    assert_eq!(
        step_e(&mut other, 15.0, -12.0, true, Some((52.0, 0.0))),
        Use::Raw
    );
    // Landing across by less than the held offset (the INS followed part of it): the end.
    let mut h = held_step();
    assert_eq!(
        step_e(&mut h, 10.0, 15.0, true, Some((-35.0, 0.0))),
        Use::Raw
    );
    // Against the INS's displacement (no receiver velocity) too, where the copies of the filter
    // carried without GNSS side with the INS (traced: a 40 m step starting inside a 30 m burst,
    // across the INS from it, was taken for the burst's end and used as measured, 42 m of error
    // through the step): the fix held at the old offset just before, so the jump past it is a
    // new fault, held at its own offset.
    let mut h = settled();
    h.copies_with_ins = true;
    step_with(&mut h, 5.0, -20.0, true, Some((20.0, 0.0)), true);
    step_with(&mut h, 6.0, -20.0, true, Some((0.1, 0.0)), true);
    assert!(matches!(h.comps[1], Comp::Step { .. }), "{:?}", h.comps[1]);
    let u = step_with(&mut h, 7.0, 40.0, true, Some((-60.0, 0.0)), true);
    assert_ne!(u, Use::Raw);
    assert!(
        matches!(h.comps[1], Comp::Step { b, .. } if (b - 40.0).abs() < 1e-9),
        "{u:?} {:?}",
        h.comps[1]
    );
    // Its end on the INS is the end.
    assert_eq!(
        step_with(&mut h, 8.0, 0.2, false, Some((40.0, 0.0)), true),
        Use::Raw
    );
    // A jump back that lands across the INS by less than the held offset: with the copies on
    // the INS (it followed none of the fault, so an end lands on it) a new fault too; without
    // them the end, as with the receiver's velocities.
    for with_ins in [true, false] {
        let mut h = settled();
        h.copies_with_ins = with_ins;
        step_with(&mut h, 5.0, -20.0, true, Some((20.0, 0.0)), true);
        step_with(&mut h, 6.0, -20.0, true, Some((0.1, 0.0)), true);
        let u = step_with(&mut h, 7.0, 15.0, true, Some((-35.0, 0.0)), true);
        assert_eq!(
            u == Use::Raw,
            !with_ins,
            "{with_ins}: {u:?} {:?}",
            h.comps[1]
        );
        assert_eq!(
            matches!(h.comps[1], Comp::Step { b, .. } if (b - 15.0).abs() < 1e-9),
            with_ins
        );
    }
}

/// Positions alone: the relative fixes of a held step (or a return, or a move onto the fixes)
/// can take the INS along a ramp taken for a step, whose end then lands across the INS past the
/// held offset. Only where the copies of the filter carried without GNSS side with the INS (it
/// followed none of the fault) is that landing a new fault; otherwise the end.
#[test]
fn a_landing_past_the_offset_is_a_new_fault_where_the_copies_side_with_the_ins() {
    for with_ins in [true, false] {
        let mut h = settled();
        h.copies_with_ins = with_ins;
        step_with(&mut h, 5.0, -20.0, true, Some((20.0, 0.0)), true);
        for k in 6..16 {
            step_with(&mut h, k as f64, -20.0, true, Some((0.1, 0.0)), true);
        }
        assert!(matches!(h.comps[1], Comp::Step { .. }), "{:?}", h.comps[1]);
        // The fix jumps 50 m back, landing 30 m across the INS.
        let u = step_with(&mut h, 16.0, 30.0, true, Some((-50.0, 0.0)), true);
        assert_eq!(
            matches!(h.comps[1], Comp::Step { b, .. } if (b - 30.0).abs() < 1e-9),
            with_ins,
            "{with_ins}: {u:?} {:?}",
            h.comps[1]
        );
    }
}
