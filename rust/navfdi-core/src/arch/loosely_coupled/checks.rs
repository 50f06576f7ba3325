//! The loosely coupled architecture's measurements and checks: a measurement and its rows,
//! moving a state, the GNSS exclusion bookkeeping (a position channel's previous measurement,
//! component isolation by the w-test) and the normalised estimation error squared against a
//! reference with the true attitude.

use crate::error::Result;
use crate::ins::earth;
use crate::ins::error_filter::{ErrorFilter, PHI, R, V};
use crate::ins::strapdown::{skew, NavState};
use crate::stream::{Nominal, Streams};
use nalgebra::{DMatrix, DVector, Vector3};

/// A measurement ready for the filter, components in the channel's order.
pub(super) struct Meas {
    /// `ẑ − z`: INS prediction minus measurement.
    pub res: DVector<f64>,
    pub h: DMatrix<f64>,
    pub r: DMatrix<f64>,
}

/// Move the state's position by `d` metres north, east, down.
pub(super) fn shift(s: &mut NavState, d: &Vector3<f64>) {
    let rm = earth::r_meridian(s.lat) + s.h;
    let rn = earth::r_normal(s.lat) + s.h;
    s.lat += d.x / rm;
    s.lon += d.y / (rn * s.lat.cos());
    s.h -= d.z;
}

/// A position channel's previous measurement: time, fix, the INS antenna position then, the
/// fix's variances (east, north, up), whether it was excluded and, while excluded, how the fix
/// had moved against the INS.
pub(super) struct Track {
    pub t: f64,
    pub fix: Nominal,
    pub ins: NavState,
    pub var: DVector<f64>,
    pub excluded: bool,
    /// While excluded: how the fix moved against the INS since the measurement before.
    pub drift: Option<Vector3<f64>>,
    /// Size of the position innovation (m).
    pub innovation: f64,
}

/// North, east, down (m) of `p` from `q` (at `q`'s radii).
pub(super) fn ned(p: &impl Point, q: &impl Point) -> Vector3<f64> {
    let (la, lo, h) = q.llh();
    let (pa, po, ph) = p.llh();
    let rm = earth::r_meridian(la) + h;
    let rn = earth::r_normal(la) + h;
    Vector3::new((pa - la) * rm, (po - lo) * rn * la.cos(), -(ph - h))
}

/// A point with latitude, longitude (rad) and height (m).
pub(super) trait Point {
    fn llh(&self) -> (f64, f64, f64);
}

impl Point for Nominal {
    fn llh(&self) -> (f64, f64, f64) {
        (self.lat, self.lon, self.h)
    }
}

impl Point for NavState {
    fn llh(&self) -> (f64, f64, f64) {
        (self.lat, self.lon, self.h)
    }
}

/// Components to keep of an alarming innovation `r` with covariance `s`: the component with
/// the largest Baarda w (`(S⁻¹r)_i / √(S⁻¹)_ii`) is left out, again, until the χ² test of the
/// rest at `pf` passes (all left out when it never does).
pub(super) fn isolate(r: &DVector<f64>, s: &DMatrix<f64>, pf: f64) -> Result<Vec<usize>> {
    let mut keep: Vec<usize> = (0..r.len()).collect();
    while !keep.is_empty() {
        let rk = DVector::from_iterator(keep.len(), keep.iter().map(|&i| r[i]));
        let sk = s.select_rows(&keep).select_columns(&keep);
        let Some(inv) = sk.clone().try_inverse() else {
            return Ok(Vec::new());
        };
        let u = &inv * &rk;
        if rk.dot(&u) <= crate::stats::chi2_threshold(pf, keep.len())? {
            break;
        }
        let worst = (0..keep.len())
            .max_by(|&a, &b| {
                let wa = u[a].abs() / inv[(a, a)].max(1e-300).sqrt();
                let wb = u[b].abs() / inv[(b, b)].max(1e-300).sqrt();
                wa.total_cmp(&wb)
            })
            .unwrap_or(0);
        keep.remove(worst);
    }
    Ok(keep)
}

/// The rows `keep` of a measurement.
pub(super) fn rows(m: &Meas, keep: &[usize]) -> Meas {
    Meas {
        res: DVector::from_iterator(keep.len(), keep.iter().map(|&i| m.res[i])),
        h: m.h.select_rows(keep),
        r: m.r.select_rows(keep).select_columns(keep),
    }
}

/// The state moved from the IMU to the antenna at `lever` (m, body forward-right-down).
pub(super) fn antenna(s: &NavState, lever: &Vector3<f64>) -> NavState {
    let mut ant = *s;
    shift(&mut ant, &(s.q * lever));
    ant
}

/// Normalised estimation error squared of antenna position, velocity and attitude at epoch
/// `k` against a reference that has the true attitude (NaN otherwise).
pub(super) fn nees<const NS: usize>(
    s: &NavState,
    kf: &ErrorFilter<NS>,
    lever: &Vector3<f64>,
    origin: &Nominal,
    src: &Streams,
    k: usize,
) -> f64 {
    let Some(r) = src.reference else {
        return f64::NAN;
    };
    let (Some(q_true), Some(e)) = (r.attitude.get(k), r.enu.get(k)) else {
        return f64::NAN;
    };
    if !e.iter().all(|v| v.is_finite()) {
        return f64::NAN;
    }
    let ant = antenna(s, lever);
    let truth = origin.from_enu(&Vector3::new(e[0], e[1], e[2]));
    let dr = ned(&ant, &truth);
    let dv = s.v - Vector3::new(e[4], e[3], -e[5]);
    let phi = (q_true * s.q.inverse()).scaled_axis();
    let mut err = nalgebra::SVector::<f64, 9>::zeros();
    err.fixed_rows_mut::<3>(0).copy_from(&dr);
    err.fixed_rows_mut::<3>(3).copy_from(&dv);
    err.fixed_rows_mut::<3>(6).copy_from(&phi);
    // Antenna position error = δr + [(C l)×] φ.
    let mut t = nalgebra::SMatrix::<f64, 9, NS>::zeros();
    for j in 0..3 {
        t[(j, R + j)] = 1.0;
        t[(3 + j, V + j)] = 1.0;
        t[(6 + j, PHI + j)] = 1.0;
    }
    t.fixed_view_mut::<3, 3>(0, PHI)
        .copy_from(&skew(&(s.q * lever)));
    let cov = t * kf.p * t.transpose();
    match cov.cholesky() {
        Some(ch) => err.dot(&ch.solve(&err)),
        None => f64::NAN,
    }
}
