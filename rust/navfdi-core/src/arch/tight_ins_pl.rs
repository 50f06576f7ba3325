//! Filter protection levels of the tight filter on recorded logs ([`super::tight_ins`]): the
//! bank of [`crate::integrity::filter_ss`] for a closed-loop strapdown filter.
//!
//! Each sub-filter is a whole strapdown navigator — its own mechanised state, error filter and
//! mechanisation — born as a copy of the filter's (after the mechanisation to the epoch, before
//! the update) at the first epoch its satellite is in view, kept through the satellite's
//! absences of up to [`HOLD_ABSENT`] s, mechanised from the same IMU
//! samples, and updated at every epoch with the rows the filter uses (predicted from its own
//! state, through the closure the filter builds its own rows with) but those of its satellite,
//! the estimate fed back into its own state. The separation
//! is the difference of the mechanised (IMU) positions, east, north, up; its variance is taken
//! as `P_s − P₀` of the position error states, which holds to first order in the closed-loop
//! filters' linearisation (the Kalman-filter identity is exact only for a linear filter on
//! nested data: [`crate::integrity::filter_ss`]). The levels are the same equation's
//! ([`crate::integrity::filter_ss::separation_levels`]). Under the filter's own placement
//! (`innovation`, `ls_precheck`, `none`) the test reports and the sub-filters follow the
//! filter's exclusions; under `separation` the bank names the satellite to exclude
//! ([`StrapdownBank::identify`]), its sub-filter's navigator must pass its own check of the
//! epoch ([`StrapdownBank::explains`]), and the filter then takes that navigator over
//! ([`StrapdownBank::exclude`]).

use super::inertial::{BodyImu, Mechaniser};
use crate::error::Result;
use crate::ins::earth;
use crate::ins::error_filter::{ErrorFilter, N_CLOCK, R};
use crate::ins::range_states::{self as rs, RangeStates};
use crate::ins::strapdown::NavState;
use crate::integrity::araim::Allocation;
use crate::integrity::filter_ss::{
    most_separated, separation_levels, separation_score, SsEpoch, SsMode,
};
use nalgebra::{DMatrix, DVector, Vector3};

/// One epoch's rows at a navigator's state: residuals `ẑ − z`, the rows of `H`, their σ and the
/// satellite (stream index) of each row.
/// The first `ranges` rows are pseudoranges (the rest range rates).
pub(super) type EpochRows = (DVector<f64>, DMatrix<f64>, Vec<f64>, Vec<usize>, usize);

/// How long (s) a sub-filter outlives its satellite's absence: a handheld receiver loses and
/// regains satellites every few seconds, and a sub-filter reborn from the filter at each return
/// would inherit whatever the satellite's fault had put into the filter — the one clean
/// reference against it lost (a fault left unexcluded then went unflagged). A sub-filter
/// without satellite g stays exact while g is away (it never used g); after this long away it
/// is dropped, so the bank does not grow with every satellite ever seen.
pub(super) const HOLD_ABSENT: f64 = 60.0;

/// One sub-filter: a strapdown navigator without one satellite.
#[derive(Clone)]
struct Sub {
    s: NavState,
    kf: ErrorFilter<N_CLOCK>,
    /// Its own range-error states, when the filter has them.
    gm: Option<RangeStates>,
    mech: Mechaniser,
    /// Last epoch time its satellite was in view (s).
    seen: f64,
}

/// The sub-filters of one logged tight run, one per satellite in view (index into the
/// stream's names).
pub(super) struct StrapdownBank {
    subs: Vec<Option<Sub>>,
    p_sat: f64,
    alloc: Allocation,
}

impl StrapdownBank {
    /// A bank for `satellites` satellites, the satellite prior `p_sat` and allocation `alloc`.
    pub(super) fn new(satellites: usize, p_sat: f64, alloc: Allocation) -> Self {
        StrapdownBank {
            subs: (0..satellites).map(|_| None).collect(),
            p_sat,
            alloc,
        }
    }

    /// The prior and allocation (for the snapshot levels beside).
    pub(super) fn allocation(&self) -> (f64, Allocation) {
        (self.p_sat, self.alloc)
    }

    /// Mechanise every sub-filter to time `tk` (s) from the IMU samples.
    pub(super) fn advance(&mut self, imu: &BodyImu, tk: f64) {
        for sub in self.subs.iter_mut().flatten() {
            sub.mech.advance(imu, &mut sub.s, &mut sub.kf, tk);
        }
    }

    /// At epoch time `tk` (s): a sub-filter (a copy of the filter's navigator, mechanised to
    /// the epoch and not yet updated) for each satellite of `sats` without one; a satellite
    /// out of view keeps its sub-filter (still a monitored mode: the filter may hold what the
    /// satellite gave it) until it has been away longer than [`HOLD_ABSENT`].
    pub(super) fn sync_view(
        &mut self,
        s: &NavState,
        kf: &ErrorFilter<N_CLOCK>,
        gm: Option<&RangeStates>,
        mech: &Mechaniser,
        sats: &[usize],
        tk: f64,
    ) {
        for (g, sub) in self.subs.iter_mut().enumerate() {
            if sats.contains(&g) {
                match sub {
                    Some(sub) => sub.seen = tk,
                    None => {
                        *sub = Some(Sub {
                            s: *s,
                            kf: kf.clone(),
                            gm: gm.cloned(),
                            mech: mech.clone(),
                            seen: tk,
                        })
                    }
                }
            } else if sub.as_ref().is_some_and(|x| tk - x.seen > HOLD_ABSENT) {
                *sub = None;
            }
        }
    }

    /// Update each sub-filter at epoch time `tk` (s) with the epoch's rows at its own state
    /// (`rows_of(state, filter, last angular rate)`), without its satellite and the satellites
    /// the filter excluded (`excluded`, stream indices), and feed back; its range-error states
    /// (if any) propagated to the epoch and predicting the pseudoranges as the filter's do.
    pub(super) fn update(
        &mut self,
        rows_of: impl Fn(&NavState, &ErrorFilter<N_CLOCK>, &Vector3<f64>) -> Option<EpochRows>,
        excluded: &[usize],
        tk: f64,
    ) -> Result<()> {
        for (g, sub) in self.subs.iter_mut().enumerate() {
            let Some(sub) = sub.as_mut() else { continue };
            let Some((mut res, h, sigma, sats, ranges)) =
                rows_of(&sub.s, &sub.kf, &sub.mech.w_last)
            else {
                continue;
            };
            if let Some(gm) = sub.gm.as_mut() {
                gm.propagate(&mut sub.kf, tk, &sats[..ranges], &sigma[..ranges]);
                gm.correct(&mut res, &sats, ranges);
            }
            let keep: Vec<usize> = (0..res.len())
                .filter(|&i| sats[i] != g && !excluded.contains(&sats[i]))
                .collect();
            if keep.is_empty() {
                continue;
            }
            let rk: Vec<f64> = keep.iter().map(|&i| sigma[i] * sigma[i]).collect();
            let ks: Vec<usize> = keep.iter().map(|&i| sats[i]).collect();
            let kr = keep.iter().filter(|&&i| i < ranges).count();
            let (up, _) = rs::sequential(
                &sub.kf,
                sub.gm.as_ref(),
                &res.select_rows(&keep),
                &h.select_rows(&keep),
                &rk,
                &ks,
                kr,
            )?;
            rs::commit(&mut sub.kf, sub.gm.as_mut(), &mut sub.s, up)?;
        }
        Ok(())
    }

    /// The satellite whose sub-filter separates most from the filter (`s`, `kf`) by the χ²
    /// tail of its normalised position separation (east, north, up; covariance `P_s − P₀`),
    /// if the runner-up is at least [`crate::integrity::filter_ss::AMBIGUITY`] times less likely;
    /// None otherwise.
    pub(super) fn identify(&self, s: &NavState, kf: &ErrorFilter<N_CLOCK>) -> Option<usize> {
        let rm = earth::r_meridian(s.lat) + s.h;
        let rn = (earth::r_normal(s.lat) + s.h) * s.lat.cos();
        let scores = self.subs.iter().enumerate().filter_map(|(g, sub)| {
            let sub = sub.as_ref()?;
            // North, east, down separation, in the position error states' axes.
            let d = DVector::from_column_slice(&[
                (sub.s.lat - s.lat) * rm,
                (sub.s.lon - s.lon) * rn,
                -(sub.s.h - s.h),
            ]);
            let c = sub.kf.p.fixed_view::<3, 3>(R, R) - kf.p.fixed_view::<3, 3>(R, R);
            let c = DMatrix::from_column_slice(3, 3, c.as_slice());
            separation_score(&d, &c).map(|v| (v, g))
        });
        most_separated(scores.collect())
    }

    /// Whether the sub-filter without satellite `g` explains the epoch: at its own state
    /// (`rows_of` as in [`StrapdownBank::update`], after the update) every row of the other
    /// satellites not in `excluded` agrees within `k` of its innovation σ, and a row of `g`
    /// does not. False when `g` has no sub-filter or no rows.
    pub(super) fn explains(
        &self,
        g: usize,
        rows_of: impl Fn(&NavState, &ErrorFilter<N_CLOCK>, &Vector3<f64>) -> Option<EpochRows>,
        excluded: &[usize],
        k: f64,
    ) -> bool {
        let Some(sub) = self.subs.get(g).and_then(Option::as_ref) else {
            return false;
        };
        let Some((mut res, h, sigma, sats, ranges)) = rows_of(&sub.s, &sub.kf, &sub.mech.w_last)
        else {
            return false;
        };
        if let Some(gm) = sub.gm.as_ref() {
            gm.correct(&mut res, &sats, ranges);
        }
        let (mut others_agree, mut own_disagrees) = (true, false);
        for i in 0..res.len() {
            if excluded.contains(&sats[i]) {
                continue;
            }
            let r = sigma[i] * sigma[i];
            let var = rs::row_variance(&sub.kf, sub.gm.as_ref(), &h, i, r, sats[i], i < ranges);
            let z = res[i] / var.max(f64::MIN_POSITIVE).sqrt();
            if sats[i] == g {
                own_disagrees |= z.abs() > k;
            } else {
                others_agree &= z.abs() <= k;
            }
        }
        others_agree && own_disagrees
    }

    /// Exclude satellite `g`: the filter (`s`, `kf`, `gm`, `mech`) takes its sub-filter's
    /// navigator, and the other sub-filters restart as copies of it. False (nothing changed)
    /// when `g` has no sub-filter.
    pub(super) fn exclude(
        &mut self,
        g: usize,
        s: &mut NavState,
        kf: &mut ErrorFilter<N_CLOCK>,
        gm: &mut Option<RangeStates>,
        mech: &mut Mechaniser,
    ) -> bool {
        let Some(sub) = self.subs.get_mut(g).and_then(Option::take) else {
            return false;
        };
        (*s, *kf, *gm, *mech) = (sub.s, sub.kf, sub.gm, sub.mech);
        for other in self.subs.iter_mut().flatten() {
            other.s = *s;
            other.kf = kf.clone();
            other.gm = gm.clone();
            other.mech = mech.clone();
        }
        true
    }

    /// The separation test and protection levels of the filter (`s`, `kf`, after its update).
    pub(super) fn levels(&self, s: &NavState, kf: &ErrorFilter<N_CLOCK>) -> SsEpoch {
        let rm = earth::r_meridian(s.lat) + s.h;
        let rn = (earth::r_normal(s.lat) + s.h) * s.lat.cos();
        // Position error states are north, east, down (m): east, north, up variances.
        let enu_var = |f: &ErrorFilter<N_CLOCK>| {
            [
                f.p[(R + 1, R + 1)].max(0.0),
                f.p[(R, R)].max(0.0),
                f.p[(R + 2, R + 2)].max(0.0),
            ]
        };
        let modes: Vec<SsMode> = self
            .subs
            .iter()
            .enumerate()
            .filter_map(|(g, sub)| {
                let sub = sub.as_ref()?;
                Some(SsMode {
                    satellite: g,
                    var: enu_var(&sub.kf),
                    separation: [
                        (sub.s.lon - s.lon) * rn,
                        (sub.s.lat - s.lat) * rm,
                        sub.s.h - s.h,
                    ],
                })
            })
            .collect();
        separation_levels(enu_var(kf), &modes, self.p_sat, &self.alloc)
    }
}
