//! Unit tests of where a fix lands when it jumps back: the end of a held step lands the fix on
//! the INS, or across it by at most what the INS followed — never further across than the held
//! offset itself.

use super::*;

/// A held 20 m north step (offset −20) whose end comes with a 40 m fault the other way at the
/// same fix (traced: a multipath burst held as a step gave way, at one fix, to a 40 m step; the
/// jump "back" was taken for the burst's end and the step used as measured for ten fixes,
/// 20.6 m RMS through it). The fix lands 40 m across the INS, beyond the held offset: a new
/// offset, held, whose own end is then the end.
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
    // Against the INS's displacement (no receiver velocity) the offset does not follow the
    // receiver, so it bounds nothing: the jump back is the end, as before.
    let mut h = settled();
    step_with(&mut h, 5.0, -20.0, true, Some((20.0, 0.0)), true);
    assert!(matches!(h.comps[1], Comp::Step { .. }), "{:?}", h.comps[1]);
    let u = step_with(&mut h, 6.0, 40.0, true, Some((-60.0, 0.0)), true);
    assert!(
        !matches!(h.comps[1], Comp::Step { .. }),
        "{u:?} {:?}",
        h.comps[1]
    );
}
