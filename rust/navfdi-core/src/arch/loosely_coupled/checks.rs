//! The loosely coupled architecture's measurements and checks: a measurement and its rows,
//! component isolation by the w-test.

pub(super) use super::super::inertial::{antenna, shift};
use crate::error::Result;
use nalgebra::{DMatrix, DVector};

/// A measurement ready for the filter, components in the channel's order.
pub(super) struct Meas {
    /// `ẑ − z`: INS prediction minus measurement.
    pub res: DVector<f64>,
    pub h: DMatrix<f64>,
    pub r: DMatrix<f64>,
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
