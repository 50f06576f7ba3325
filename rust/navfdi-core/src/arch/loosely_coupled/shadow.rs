//! The INS without GNSS from a state kept before a hold began: the witness that tells the
//! INS's error from the fixes' on a receiver of positions alone.
//!
//! Without the receiver's velocity the filter follows a slow ramp through its own velocity;
//! where the ramp ends, the fixes jump back across the INS — in the innovations the same
//! picture as a step's onset — and the jump was held as a step for the rest of the log; or the
//! end was taken in, the INS kept the velocity it had followed, and the fixes it then drifted
//! from were held as a ramp while it ran away at under the runaway rate (simulated σ 1 m
//! positions at 1 Hz: after 0.5 m/s ramps over 40 s, 4–55 m off for minutes, every run). What
//! tells the INS's error from the fixes' is where the vehicle really is, and the IMU with the
//! vehicle's constraints (zero velocity, non-holonomic) knows that for a while without a fix.
//! Every [`SHADOW_EVERY`] s of fixes used as measured a copy of the filter is started, and
//! carried on the IMU samples and the constraints alone, with its own covariance; a copy
//! [`SHADOW_AGE`] s old is dropped when the next one starts, so during a hold (when none
//! starts) the copies carried when it began stay to its end (dropping them at that age
//! whatever happens raised the simulated ramps' false exclusions, 0.045 → 0.051 per epoch).
//! A hold (step or ramp) that began [`SHADOW_LEAD`] s or more after a copy started has that
//! copy as a witness: where the fix is on it (within [`FIX_CHI2`]) and the INS off it
//! (beyond [`INS_CHI2`], and [`LR_CHI2`] more than the fix: the INS's error a thousand times
//! likelier than the fix's), the INS is the one that is wrong and the younger witness replaces
//! it ([`Witness`]: its state, covariance and mechaniser), and the fix updates it. Moving the
//! INS onto the fix instead (the re-anchoring of [`super::diverge`]) kept the velocity it had
//! followed the fault with, its variance reopened: where a multipath burst began as a
//! followed step ended, the burst's end gave it a 2 m/s error that ran it away for minutes
//! with the fixes held out (simulated positions-only logs, a tactical-grade IMU: 61–117 m of
//! error 20–60 s after the step). A step's onset takes the fix off the copy and leaves the INS on it; a fault ramp held drifts
//! the fix away from both. A copy whose covariance has grown to the jump's size (a MEMS IMU, a
//! minute or more of a poorly known velocity) decides nothing, and the hold stays.

use super::checks::{nhc_applies, nhc_meas, update, zupt_meas};
use super::noise_scale::Rolling;
use crate::arch::inertial::{BodyImu, Mechaniser};
use crate::ins::error_filter::{ErrorFilter, R};
use crate::ins::strapdown::NavState;
use crate::spec::ConstraintSpec;
use nalgebra::{Matrix2, Vector2};
use std::collections::VecDeque;

/// Seconds between the starts of two copies.
pub const SHADOW_EVERY: f64 = 20.0;
/// A copy this many seconds old is dropped when the next one starts.
pub const SHADOW_AGE: f64 = 100.0;
/// A copy witnesses a hold that began at least this many seconds after its start.
pub const SHADOW_LEAD: f64 = 5.0;
/// The fix is on the copy: its horizontal distance within χ²(2) at 1 % (9.21).
pub const FIX_CHI2: f64 = 9.21;
/// The INS is off the copy: its horizontal distance beyond χ²(2) at 3.4 · 10⁻⁴ (16.0).
pub const INS_CHI2: f64 = 16.0;
/// And the fix on it by this much more (twice the log-likelihood ratio of the two causes, the
/// INS's error against the fix's: 13.8 is 1 000 to 1).
pub const LR_CHI2: f64 = 13.8;

/// Seconds after a held step's onset within which the copies may call it the INS's error: a
/// ramp's end lands the fix on them at once; a copy that drifts onto a step's fixes later is
/// no evidence (the recorded drive's consumer IMU on positions alone: 3 of 116 steps of 5–20 m
/// moved onto 24–54 s into the step without this bound).
pub const STEP_WINDOW: f64 = 5.0;

/// Copies that must agree: one copy that started with the filter's velocity off drifts
/// beyond its covariance, and may drift onto a stepped fix (simulated 10 Hz positions, one
/// 20 m step in 18 taken for the INS's error with one witness).
pub const WITNESSES: usize = 2;

/// Ages (s) that split the copies' consistency into bins: below 30 s, 30–60 s, older.
const AGE_BINS: [f64; 2] = [30.0, 60.0];
/// The fewest comparisons with fixes used as measured before a bin's copies may witness.
const MIN_FIT: usize = 30;
/// The median of χ²(2): a consistent copy's comparisons have it as theirs.
const CHI2_2_MEDIAN: f64 = 1.386;
/// Seconds between two comparisons of one copy (they are correlated from fix to fix).
const FIT_EVERY: f64 = 1.0;

/// One copy of the filter, carried without GNSS from `start` (s).
#[derive(Debug, Clone)]
struct Shadow<const NS: usize> {
    start: f64,
    s: NavState,
    kf: ErrorFilter<NS>,
    mech: Mechaniser,
    /// When it was last compared with a fix (s).
    seen: f64,
}

/// A copy that called a hold the INS's error ([`Shadows::returned`]): its state, its
/// covariance scaled by its age bin's inflation, and its mechaniser — what replaces the INS.
#[derive(Debug, Clone)]
pub struct Witness<const NS: usize> {
    pub s: NavState,
    pub kf: ErrorFilter<NS>,
    pub mech: Mechaniser,
}

/// The copies of the filter carried without GNSS (positions-only receivers).
#[derive(Debug, Clone, Default)]
pub struct Shadows<const NS: usize> {
    list: VecDeque<Shadow<NS>>,
    /// Per age bin, the copies' χ² against fixes the filter used as measured: how far their
    /// covariance understates their error on this log (the IMU's errors beyond the filter's
    /// model, which aided operation hides).
    fit: [Rolling<1024>; 3],
}

/// The age bin of a copy `age` s old.
fn bin(age: f64) -> usize {
    AGE_BINS.iter().filter(|&&a| age >= a).count()
}

/// χ² of a horizontal difference `d` (m) with covariance `v` (m²); NaN where singular.
fn chi2(d: Vector2<f64>, v: Matrix2<f64>) -> f64 {
    v.try_inverse()
        .map_or(f64::NAN, |vi| (d.transpose() * vi * d)[0])
}

impl<const NS: usize> Shadows<NS> {
    /// At `t` (s), after the epoch's updates: start a copy of the filter (`s`, `kf`, its
    /// mechaniser `mech`) where the last started [`SHADOW_EVERY`] s ago or more, and drop the
    /// copies older than [`SHADOW_AGE`].
    pub fn start(&mut self, t: f64, s: &NavState, kf: &ErrorFilter<NS>, mech: &Mechaniser) {
        self.list.retain(|c| t - c.start <= SHADOW_AGE);
        if self.list.back().is_none_or(|c| t - c.start >= SHADOW_EVERY) {
            self.list.push_back(Shadow {
                start: t,
                s: *s,
                kf: kf.clone(),
                mech: mech.clone(),
                seen: f64::NEG_INFINITY,
            });
        }
    }

    /// Carry every copy to `t` (s) on the IMU samples, then the constraints the filter applies:
    /// zero velocity where the filter found the IMU at rest (`at_rest`), the non-holonomic
    /// constraint on the copy's own velocity and turn rate. A copy whose update fails is dropped.
    pub fn advance(
        &mut self,
        imu: &BodyImu,
        t: f64,
        at_rest: bool,
        zupt: Option<&ConstraintSpec>,
        nhc: Option<&ConstraintSpec>,
    ) {
        self.list.retain_mut(|c| {
            c.mech.advance(imu, &mut c.s, &mut c.kf, t);
            let rest = match (at_rest, zupt) {
                (true, Some(z)) => {
                    let meas = zupt_meas::<NS>(&c.s, z);
                    update(&mut c.kf, &mut c.s, &meas).is_ok()
                }
                _ => true,
            };
            let side = match nhc {
                Some(n) if nhc_applies(&c.s, &c.mech.w_last, at_rest, n) => {
                    let meas = nhc_meas::<NS>(&c.s, n);
                    update(&mut c.kf, &mut c.s, &meas).is_ok()
                }
                _ => true,
            };
            rest && side
        });
    }

    /// Forget every copy (the INS was moved: they carry what it was).
    pub fn clear(&mut self) {
        self.list.clear();
    }

    /// At `t` (s), a fix the filter used as measured, `fix` (east, north, m) with horizontal
    /// covariance `fix_var` (m²): each copy's χ² against it, for its age bin's consistency.
    /// `antenna` gives a state's antenna east and north (m).
    pub fn observe(
        &mut self,
        t: f64,
        antenna: impl Fn(&NavState) -> Vector2<f64>,
        (fix, fix_var): (Vector2<f64>, Matrix2<f64>),
    ) {
        for c in self.list.iter_mut().filter(|c| t - c.seen >= FIT_EVERY) {
            let x = chi2(antenna(&c.s) - fix, horizontal(&c.kf) + fix_var);
            if x.is_finite() {
                self.fit[bin(t - c.start)].push(x);
                c.seen = t;
            }
        }
    }

    /// How far the copies of age `age` (s) understate their error: the median of their χ²
    /// against used fixes over χ²(2)'s, at least 1; None before [`MIN_FIT`] comparisons.
    fn inflation(&self, age: f64) -> Option<f64> {
        let f = &self.fit[bin(age)];
        (f.len() >= MIN_FIT).then(|| (f.median() / CHI2_2_MEDIAN).max(1.0))
    }

    /// Which side the copies take between the fix and the INS on a hold that began at `onset`
    /// (s): `Some(true)` where every copy started [`SHADOW_LEAD`] s or more before it,
    /// [`WITNESSES`] at least, is nearer the fix than the INS (χ² with its covariance and the
    /// fix's, or the INS's; the age bin's inflation scales both alike), `Some(false)` where
    /// every one is nearer the INS, None otherwise (no hold, no fix, too few copies, or copies
    /// on both sides). With the fix: what a ramp held for minutes needs to be the INS's drift
    /// ([`super::diverge::HOLD_LONGEST`]; on a real ramp the INS, aided by the held offset,
    /// stays with the copies). With the INS: the INS followed none of the held fault, so a
    /// jump of the fix past the held offset is a new fault
    /// ([`super::hold::PositionHold::copies_with_ins`]). Arguments as for
    /// [`Shadows::returned`] (`fix` None: no fix).
    pub fn side(
        &self,
        onset: Option<f64>,
        antenna: impl Fn(&NavState) -> Vector2<f64>,
        fix: Option<(Vector2<f64>, Matrix2<f64>)>,
        (ins, ins_var): (&NavState, Matrix2<f64>),
    ) -> Option<bool> {
        let (onset, (fix, fix_var)) = (onset?, fix?);
        let at_ins = antenna(ins);
        // The copies started before the hold, and how many of them are nearer the fix.
        let (n, near) = self
            .list
            .iter()
            .filter(|c| c.start <= onset - SHADOW_LEAD)
            .fold((0, 0), |(n, near), c| {
                let (p, a) = (horizontal(&c.kf), antenna(&c.s));
                let nearer = chi2(a - fix, p + fix_var) < chi2(a - at_ins, p + ins_var);
                (n + 1, near + usize::from(nearer))
            });
        match near {
            _ if n < WITNESSES => None,
            k if k == n => Some(true),
            0 => Some(false),
            _ => None,
        }
    }

    /// Whether, at `t` (s), a hold that began at `onset` (s) is the INS's error (a held step
    /// only within [`STEP_WINDOW`] s of its onset, `step`): [`WITNESSES`] copies started
    /// [`SHADOW_LEAD`] s before it or earlier have the fix on them and the INS off them, their
    /// χ² divided by their age bin's inflation ([`Shadows::observe`]; a bin without
    /// [`MIN_FIT`] comparisons decides nothing). `antenna` gives a state's antenna east and
    /// north (m); `fix` is the fix's (m), `fix_var` its horizontal covariance (m², east and
    /// north); `ins` the INS's state and `ins_var` its antenna's horizontal covariance (m²).
    pub fn returned(
        &self,
        (t, onset, step): (f64, f64, bool),
        antenna: impl Fn(&NavState) -> Vector2<f64>,
        (fix, fix_var): (Vector2<f64>, Matrix2<f64>),
        (ins, ins_var): (&NavState, Matrix2<f64>),
    ) -> Option<Witness<NS>> {
        if step && t - onset > STEP_WINDOW {
            return None;
        }
        let at_ins = antenna(ins);
        let agree: Vec<(&Shadow<NS>, f64)> = self
            .list
            .iter()
            .filter(|c| c.start <= onset - SHADOW_LEAD)
            .filter_map(|c| {
                let k = self.inflation(t - c.start)?;
                let (p, a) = (horizontal(&c.kf), antenna(&c.s));
                let cf = chi2(a - fix, p + fix_var) / k;
                let ci = chi2(a - at_ins, p + ins_var) / k;
                (cf <= FIX_CHI2 && ci >= INS_CHI2 && ci - cf >= LR_CHI2).then_some((c, k))
            })
            .collect();
        if agree.len() < WITNESSES {
            return None;
        }
        // The youngest witness: the least carried without fixes.
        let (c, k) = agree
            .iter()
            .max_by(|a, b| a.0.start.total_cmp(&b.0.start))?;
        let mut kf = c.kf.clone();
        kf.p *= *k;
        Some(Witness {
            s: c.s,
            kf,
            mech: c.mech.clone(),
        })
    }
}

/// The horizontal position covariance (m², east and north) of an error filter.
pub fn horizontal<const NS: usize>(kf: &ErrorFilter<NS>) -> Matrix2<f64> {
    // The filter's position errors are north, east, down at R.
    let (n, e) = (R, R + 1);
    Matrix2::new(kf.p[(e, e)], kf.p[(e, n)], kf.p[(n, e)], kf.p[(n, n)])
}

/// The 2 × 2 block of `m` at `(off, off)`: a measurement's horizontal covariance (m², east
/// and north, where its position is east, north, up from `off`).
pub fn block(m: &nalgebra::DMatrix<f64>, off: usize) -> Matrix2<f64> {
    m.fixed_view::<2, 2>(off, off).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ins::earth::{gravity, r_meridian, r_normal, OMEGA_IE};
    use crate::ins::error_filter::{tests::noise, N};
    use nalgebra::{UnitQuaternion, Vector3};

    /// A vehicle standing level, its body axes north, east, down, at 100 Hz for `secs` s (the
    /// IMU reads the Earth's rotation and gravity).
    fn standing(secs: f64, lat: f64) -> BodyImu {
        let n = (secs * 100.0) as usize + 1;
        BodyImu {
            t: (0..n).map(|i| i as f64 * 0.01).collect(),
            gyro: vec![Vector3::new(OMEGA_IE * lat.cos(), 0.0, -OMEGA_IE * lat.sin()); n],
            acc: vec![Vector3::new(0.0, 0.0, -gravity(lat, 0.0)); n],
            gaps: Vec::new(),
        }
    }

    /// Copies started at 0 and 20 s from a standing INS, carried to 62 s (the IMU's
    /// mechanisation keeps them on the start), compared with fixes there; the antenna as east
    /// and north metres from the start.
    fn witnesses() -> (
        Shadows<N>,
        NavState,
        impl Fn(&NavState) -> Vector2<f64> + Copy,
    ) {
        let lat = 0.7;
        let s0 = NavState {
            lat,
            lon: 0.2,
            h: 0.0,
            v: Vector3::zeros(),
            q: UnitQuaternion::identity(),
        };
        let kf =
            ErrorFilter::<N>::new(1.0, 0.05, Vector3::repeat(0.001), Vector3::zeros(), noise());
        let imu = standing(60.0, lat);
        let en = move |s: &NavState| {
            Vector2::new(
                (s.lon - 0.2) * (r_normal(lat) * lat.cos()),
                (s.lat - lat) * r_meridian(lat),
            )
        };
        let mut sh = Shadows::<N>::default();
        let mech = Mechaniser::new(&imu, 0.0, &Vector3::zeros());
        sh.start(0.0, &s0, &kf, &mech);
        for k in 1..=62 {
            let t = k as f64;
            sh.advance(&imu, t, false, None, None);
            if k == 20 {
                let mech = Mechaniser::new(&imu, t, &Vector3::zeros());
                sh.start(t, &s0, &kf, &mech);
            }
            sh.observe(t, en, (Vector2::zeros(), Matrix2::identity()));
        }
        // The copies' horizontal σ set to 2 m (what carrying them gives depends on the IMU
        // model; the decision is what is tested here), every age bin fitted as consistent.
        for c in sh.list.iter_mut() {
            for j in [R, R + 1] {
                c.kf.p[(j, j)] = 4.0;
            }
        }
        for f in sh.fit.iter_mut() {
            (0..MIN_FIT).for_each(|_| f.push(CHI2_2_MEDIAN));
        }
        (sh, s0, en)
    }

    /// `s` moved `m` metres north.
    fn north_of(mut s: NavState, m: f64) -> NavState {
        s.lat += m / r_meridian(s.lat);
        s
    }

    /// A ramp held for minutes is the INS's drift only where every copy started before the
    /// hold is nearer the fix than the INS: not where the INS stays with them (a real ramp,
    /// held; they side with the INS), nor with one copy only, nor without a hold or a fix.
    #[test]
    fn the_copies_side_with_the_fix_or_the_ins() {
        let (sh, s0, en) = witnesses();
        let m = Matrix2::identity();
        // The fix 30 m north of the copies, the INS 150 m south: the copies side with the fix.
        let (fix, ins) = (Some((Vector2::new(0.0, 30.0), m)), north_of(s0, -150.0));
        assert_eq!(sh.side(Some(62.0), en, fix, (&ins, m)), Some(true));
        // The INS 5 m from the copies, the fix 30 m off them: a real ramp.
        assert_eq!(
            sh.side(Some(62.0), en, fix, (&north_of(s0, -5.0), m)),
            Some(false)
        );
        // One copy started before the hold (at 0 s; the other at 20 s): not enough.
        assert_eq!(sh.side(Some(24.0), en, fix, (&ins, m)), None);
        assert_eq!(sh.side(None, en, fix, (&ins, m)), None);
        assert_eq!(sh.side(Some(62.0), en, None, (&ins, m)), None);
    }

    #[test]
    fn the_ins_off_the_copies_and_the_fix_on_them_is_the_ins_error() {
        let (sh, s0, en) = witnesses();
        assert_eq!(sh.list.len(), 2);
        let fix = (Vector2::zeros(), Matrix2::identity());
        // The INS 20 m north of the copies (it followed a ramp), the fix back on them.
        let ins = north_of(s0, 20.0);
        let ins = (&ins, Matrix2::identity() * 0.01);
        assert!(sh.returned((62.0, 59.0, true), en, fix, ins).is_some());
        // A held step later than the window after its onset: no longer.
        assert!(sh.returned((62.0, 50.0, true), en, fix, ins).is_none());
        // A held ramp: at any time.
        assert!(sh.returned((62.0, 50.0, false), en, fix, ins).is_some());
        // A hold that began before the second copy started has one witness only.
        assert!(sh.returned((21.0, 18.0, false), en, fix, ins).is_none());
    }

    #[test]
    fn the_witness_is_the_youngest_copy_with_its_covariance_inflated() {
        let (mut sh, s0, en) = witnesses();
        // At 62 s the copies are 62 s (bin 2) and 42 s old (bin 1): the younger's bin
        // understates its error 4× (in variance), the older's not at all.
        sh.fit[1] = Default::default();
        (0..MIN_FIT).for_each(|_| sh.fit[1].push(4.0 * CHI2_2_MEDIAN));
        sh.list[1].s.v = Vector3::new(0.5, 0.0, 0.0);
        let ins = north_of(s0, 30.0);
        let w = sh
            .returned(
                (62.0, 59.0, true),
                en,
                (Vector2::zeros(), Matrix2::identity()),
                (&ins, Matrix2::identity() * 0.01),
            )
            .expect("both copies witness");
        // The copy started at 20 s: its state and mechaniser, its covariance times 4.
        assert_eq!(w.s.v, Vector3::new(0.5, 0.0, 0.0));
        assert_eq!(w.kf.p, sh.list[1].kf.p * 4.0);
        assert_eq!(w.mech.i, sh.list[1].mech.i);
    }

    #[test]
    fn a_steps_onset_leaves_the_ins_on_the_copies() {
        let (sh, s0, en) = witnesses();
        // The fix 20 m north, the INS on the copies: the fix's error, not the INS's.
        let fix = (Vector2::new(0.0, 20.0), Matrix2::identity());
        assert!(sh
            .returned(
                (62.0, 59.0, true),
                en,
                fix,
                (&s0, Matrix2::identity() * 0.01)
            )
            .is_none());
    }

    #[test]
    fn copies_without_enough_comparisons_decide_nothing() {
        let (mut sh, s0, en) = witnesses();
        sh.fit = Default::default();
        let ins = north_of(s0, 20.0);
        let fix = (Vector2::zeros(), Matrix2::identity());
        assert!(sh
            .returned(
                (62.0, 59.0, true),
                en,
                fix,
                (&ins, Matrix2::identity() * 0.01)
            )
            .is_none());
    }

    #[test]
    fn copies_past_their_age_stay_until_the_next_start() {
        let (mut sh, s0, _) = witnesses();
        let imu = standing(200.0, s0.lat);
        // No start during a hold: the copies from 0 and 20 s are carried past 100 s old.
        for k in 63..=150 {
            sh.advance(&imu, k as f64, false, None, None);
        }
        assert_eq!(sh.list.len(), 2);
        // The next start drops both (150 and 130 s old) and keeps the new one alone.
        let kf = sh.list[0].kf.clone();
        let mech = Mechaniser::new(&imu, 150.0, &Vector3::zeros());
        sh.start(150.0, &s0, &kf, &mech);
        assert_eq!(sh.list.len(), 1);
        assert_eq!(sh.list[0].start, 150.0);
    }

    #[test]
    fn the_inflation_is_the_copies_median_over_chi2s() {
        let mut f = Shadows::<N>::default();
        for _ in 0..MIN_FIT - 1 {
            f.fit[0].push(4.0 * CHI2_2_MEDIAN);
        }
        assert_eq!(f.inflation(10.0), None);
        f.fit[0].push(4.0 * CHI2_2_MEDIAN);
        assert!((f.inflation(10.0).unwrap() - 4.0).abs() < 1e-12);
        assert_eq!(f.inflation(45.0), None);
        assert_eq!((bin(29.9), bin(30.0), bin(60.0)), (0, 1, 2));
    }
}
