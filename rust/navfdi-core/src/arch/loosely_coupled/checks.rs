//! The loosely coupled architecture's measurements and checks: a measurement and its rows,
//! component isolation by the w-test.

pub(super) use super::super::inertial::{antenna, shift};
use crate::error::Result;
use crate::ins::earth;
use crate::ins::error_filter::{ErrorFilter, PHI, R, V};
use crate::ins::strapdown::{skew, NavState};
use crate::spec::ConstraintSpec;
use crate::stream::{Logged, Nominal};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// A measurement ready for the filter, components in the channel's order.
pub(super) struct Meas {
    /// `ẑ − z`: INS prediction minus measurement.
    pub res: DVector<f64>,
    pub h: DMatrix<f64>,
    pub r: DMatrix<f64>,
}

/// Update the filter with a measurement and feed the correction back into the state.
pub(super) fn update<const NS: usize>(
    kf: &mut ErrorFilter<NS>,
    s: &mut NavState,
    meas: &Meas,
) -> Result<()> {
    let inn = kf.innovation(&meas.res, &meas.h, &meas.r)?;
    let dx = kf.update(&inn, &meas.h, &meas.r)?;
    kf.feedback(s, &dx);
    Ok(())
}

/// The zero-velocity measurement: the INS velocity (north, east, down; m/s) against zero, σ
/// `c.noise`.
pub(super) fn zupt_meas<const NS: usize>(s: &NavState, c: &ConstraintSpec) -> Meas {
    Meas {
        res: DVector::from_column_slice(s.v.as_slice()),
        h: DMatrix::from_fn(3, NS, |i, j| if j == V + i { 1.0 } else { 0.0 }),
        r: diag(&c.noise),
    }
}

/// Whether the non-holonomic constraint applies: not at rest, the INS at least `c.threshold`
/// m/s and turning at most `c.rate_threshold` rad/s about the body's down axis (`w`, the last
/// compensated angular rate).
pub(super) fn nhc_applies(
    s: &NavState,
    w: &Vector3<f64>,
    at_rest: bool,
    c: &ConstraintSpec,
) -> bool {
    !at_rest && s.v.norm() >= c.threshold && w.z.abs() <= c.rate_threshold
}

/// The non-holonomic measurement: the body's right and down velocity (m/s) against zero, σ
/// `c.noise`.
pub(super) fn nhc_meas<const NS: usize>(s: &NavState, c: &ConstraintSpec) -> Meas {
    let ct = s.q.to_rotation_matrix().into_inner().transpose();
    let vb = ct * s.v;
    let hphi = -ct * skew(&s.v);
    let mut h = DMatrix::zeros(2, NS);
    for (row, b) in [1usize, 2].iter().enumerate() {
        for j in 0..3 {
            h[(row, V + j)] = ct[(*b, j)];
            h[(row, PHI + j)] = hphi[(*b, j)];
        }
    }
    Meas {
        res: DVector::from_vec(vec![vb.y, vb.z]),
        h,
        r: diag(&c.noise),
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

/// Three components from `off` of an innovation `r` and the diagonal of its covariance `sv`
/// (east, north, up of a position or velocity).
pub(super) fn three(
    r: &DVector<f64>,
    sv: &DMatrix<f64>,
    off: usize,
) -> (Vector3<f64>, Vector3<f64>) {
    (
        Vector3::new(r[off], r[off + 1], r[off + 2]),
        Vector3::new(
            sv[(off, off)],
            sv[(off + 1, off + 1)],
            sv[(off + 2, off + 2)],
        ),
    )
}

/// A diagonal covariance with the squares of the σ `sig` on its diagonal.
pub(super) fn diag(sig: &[f64]) -> DMatrix<f64> {
    DMatrix::from_diagonal(&DVector::from_iterator(
        sig.len(),
        sig.iter().map(|s| s * s),
    ))
}

/// The factor on a fix's position variance in the update for Gauss-Markov errors of
/// correlation time `tau` (s) sampled every `dt` (s): `(1 + ρ)/(1 − ρ)` with `ρ = e^(−dt/τ)`,
/// the variance ratio of the mean of many such fixes to the mean of as many independent ones;
/// 1 for `tau = 0` (white).
pub(super) fn correlation_weight(dt: f64, tau: f64) -> f64 {
    if !(tau > 0.0 && dt > 0.0) {
        return 1.0;
    }
    let x = dt / tau;
    // (1 + e^(−x))/(1 − e^(−x)) = coth(x/2), written without cancellation for small x.
    1.0 / (0.5 * x).tanh()
}

/// The larger horizontal σ (m) of the position fix of `aid` at epoch `k` as recorded, floored
/// at the sensor's `noise` (the floor alone where none is recorded).
pub(super) fn sigma_h(logged: &Logged, aid: &super::Aid, k: usize) -> f64 {
    let rec = aid
        .sensor
        .and_then(|si| logged.sigma.get(si))
        .and_then(|s| s.get(k))
        .zip(aid.pos)
        .map(|(s, o)| s[o].max(s[o + 1]))
        .filter(|x| x.is_finite() && *x > 0.0);
    rec.unwrap_or(0.0).max(aid.floor[0].max(aid.floor[1]))
}

/// The GNSS measurement of channel `aid` at the INS state `s`: the innovation `INS − fix`
/// (position: the fix `z` east, north, up from `origin`, m, lever arm `lever` applied; velocity:
/// m/s, with the lever arm's rotation at the body rate `w`, rad/s) in the sensor's east, north,
/// up order, its rows of H in the `NS` error states, and R from the recorded σ `sig` floored
/// at the sensor's noise.
#[allow(clippy::too_many_arguments)]
pub(super) fn gnss_measurement<const NS: usize>(
    s: &NavState,
    aid: &super::Aid,
    z: &DVector<f64>,
    sig: Option<&DVector<f64>>,
    origin: &Nominal,
    lever: &Vector3<f64>,
    w: &Vector3<f64>,
) -> Meas {
    let dim = z.len();
    let c = s.q.to_rotation_matrix().into_inner();
    let cl = c * lever;
    let mut res = DVector::zeros(dim);
    let mut h = DMatrix::zeros(dim, NS);
    // NED rows into the sensor's east, north, up order.
    let mut put = |off: usize,
                   d_ned: &Vector3<f64>,
                   rows: &nalgebra::Matrix3x6<f64>,
                   col0: usize,
                   blk: &Matrix3<f64>| {
        let order = [(1usize, 1.0), (0, 1.0), (2, -1.0)];
        for (j, (src_row, sign)) in order.iter().enumerate() {
            res[off + j] = sign * d_ned[*src_row];
            for q in 0..3 {
                h[(off + j, col0 + q)] = sign * rows[(*src_row, q)];
                h[(off + j, PHI + q)] = sign * blk[(*src_row, q)];
            }
        }
    };
    let ident = nalgebra::Matrix3x6::<f64>::from_fn(|r, c| if r == c { 1.0 } else { 0.0 });
    if let Some(o) = aid.pos {
        let g = origin.from_enu(&Vector3::new(z[o], z[o + 1], z[o + 2]));
        let rm = earth::r_meridian(s.lat) + s.h;
        let rn = earth::r_normal(s.lat) + s.h;
        let d = Vector3::new(
            (s.lat - g.lat) * rm,
            (s.lon - g.lon) * rn * s.lat.cos(),
            -(s.h - g.h),
        ) + cl;
        put(o, &d, &ident, R, &skew(&cl));
    }
    if let Some(o) = aid.vel {
        let vl = c * w.cross(lever);
        let v_g = Vector3::new(z[o + 1], z[o], -z[o + 2]);
        let d = s.v + vl - v_g;
        put(o, &d, &ident, V, &skew(&vl));
    }
    let sd: Vec<f64> = (0..dim)
        .map(|j| {
            let rec = sig
                .and_then(|v| v.get(j).copied())
                .filter(|x| x.is_finite() && *x > 0.0);
            rec.unwrap_or(0.0).max(aid.floor[j])
        })
        .collect();
    Meas {
        res,
        h,
        r: diag(&sd),
    }
}

/// Rest over the window before `tk`: σ of the specific-force magnitude and mean
/// bias-corrected rate magnitude under their thresholds.
pub(super) fn still(
    t: &[f64],
    acc: &[Vector3<f64>],
    gyro: &[Vector3<f64>],
    bg: &Vector3<f64>,
    i: usize,
    tk: f64,
    c: &ConstraintSpec,
) -> bool {
    let hi = i.min(t.len());
    let lo = t[..hi].partition_point(|&x| x < tk - c.window);
    let n = hi - lo;
    if n < 5 {
        return false;
    }
    let mags: Vec<f64> = acc[lo..hi].iter().map(|f| f.norm()).collect();
    let mean = mags.iter().sum::<f64>() / n as f64;
    let var = mags.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    let rate = gyro[lo..hi].iter().map(|w| (w - bg).norm()).sum::<f64>() / n as f64;
    var.sqrt() < c.threshold && rate < c.rate_threshold
}

/// A north, east, down vector as east, north, up.
pub(super) fn enu(v: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(v.y, v.x, -v.z)
}

#[cfg(test)]
mod tests {
    use super::correlation_weight;

    #[test]
    fn correlation_weight_is_the_worth_of_correlated_fixes() {
        assert_eq!(correlation_weight(1.0, 0.0), 1.0);
        for (dt, tau) in [(1.0, 30.0), (0.25, 30.0), (1.0, 1.0), (0.2, 1e5)] {
            let rho = f64::exp(-dt / tau);
            let want = (1.0 + rho) / (1.0 - rho);
            let got = correlation_weight(dt, tau);
            assert!(
                (got - want).abs() <= 1e-9 * want,
                "{dt} {tau}: {got} {want}"
            );
        }
        // σ 2 m fixes at 1 Hz with τ 30 s count as about 1/60 of an independent fix each.
        assert!((correlation_weight(1.0, 30.0) - 60.0).abs() < 0.01);
    }
}
