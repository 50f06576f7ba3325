//! A model fixed once for a filter that runs it epoch after epoch: `Φ`, `Q`, `H` and `R`
//! validated when set, then [`KalmanFilter::step`] takes only the measurement — the per-epoch
//! API of a filter whose matrices do not change (what filterpy's `KalmanFilter` keeps as
//! attributes), without converting and re-checking four matrices at every epoch.

use super::{Innovation, KalmanFilter};
use crate::error::{Error, Result};
use crate::validate::{check_len, check_no_inf};
use nalgebra::{DMatrix, DVector};

/// `Φ` and `Q` (n × n), `H` (m × n) and `R` (m × m) of [`KalmanFilter::step`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FixedModel {
    /// State transition (n × n).
    pub phi: DMatrix<f64>,
    /// Process-noise covariance mapped to the state (n × n, symmetric PSD).
    pub q: DMatrix<f64>,
    /// Measurement matrix (m × n).
    pub h: DMatrix<f64>,
    /// Measurement-noise covariance (m × m, symmetric PSD).
    pub r: DMatrix<f64>,
}

impl KalmanFilter {
    /// Fix the model [`KalmanFilter::step`] runs: `phi`, `q` (n × n), `h` (m × n), `r` (m × m),
    /// validated as [`KalmanFilter::predict`] and [`KalmanFilter::update`] validate theirs.
    /// On error the filter (and any model it had) is unchanged.
    pub fn set_model(
        &mut self,
        phi: DMatrix<f64>,
        q: DMatrix<f64>,
        h: DMatrix<f64>,
        r: DMatrix<f64>,
    ) -> Result<()> {
        self.check_predict(&phi, &q, 1.0)?;
        let probe = DVector::zeros(h.nrows());
        self.check_update(&probe, &h, &r)?;
        self.model = Some(Box::new(FixedModel { phi, q, h, r }));
        Ok(())
    }

    /// The model set by [`KalmanFilter::set_model`], if any.
    pub fn model(&self) -> Option<&FixedModel> {
        self.model.as_deref()
    }

    /// One epoch of the fixed model: [`KalmanFilter::predict`] then [`KalmanFilter::update`]
    /// with `z` (m; NaN marks a missing component), the same arithmetic as the two calls. Only
    /// `z` is checked (its length, no infinity). On error the filter is unchanged.
    pub fn step(&mut self, z: &DVector<f64>) -> Result<Innovation> {
        let Some(model) = self.model.take() else {
            return Err(Error::Invalid(
                "step: no model; call set_model(Phi, Q, H, R) first".into(),
            ));
        };
        let out = self.step_with(&model, z);
        self.model = Some(model);
        out
    }

    fn step_with(&mut self, m: &FixedModel, z: &DVector<f64>) -> Result<Innovation> {
        check_len("z", z, m.h.nrows())?;
        check_no_inf("z", z)?;
        // The state before the epoch, for a failed update: the prediction leaves it in its
        // workspace (it computes into `ws` and swaps), from where it is swapped into `saved`
        // — buffers the filter owns, no copy or allocation per epoch once they have the size.
        if self.saved.1.shape() != self.p.shape() {
            self.saved = (self.x.clone(), self.p.clone());
        }
        // A failed prediction leaves the filter as it was.
        self.predict_trusted(&m.phi, &m.q, 1.0)?;
        std::mem::swap(&mut self.saved.0, &mut self.ws.x);
        std::mem::swap(&mut self.saved.1, &mut self.ws.nn_c);
        let out = self.update_trusted(z, &m.h, &m.r);
        if out.is_err() {
            self.x.copy_from(&self.saved.0);
            self.p.copy_from(&self.saved.1);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn filter() -> KalmanFilter {
        KalmanFilter::new(DVector::from_vec(vec![1.0, -1.0]), DMatrix::identity(2, 2)).unwrap()
    }

    fn model() -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
        let phi = DMatrix::from_row_slice(2, 2, &[1.0, 0.1, 0.0, 1.0]);
        let q = DMatrix::from_diagonal_element(2, 2, 0.01);
        let h = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
        let r = DMatrix::from_element(1, 1, 0.5);
        (phi, q, h, r)
    }

    /// A filter with the model fixed and its twin stepped by hand.
    fn twins() -> (KalmanFilter, KalmanFilter) {
        let (phi, q, h, r) = model();
        let mut a = filter();
        a.set_model(phi, q, h, r).unwrap();
        (a, filter())
    }

    /// `a.step(z)` beside `b.predict` + `b.update` with the same model: the same state and
    /// statistic to the bit.
    fn step_both(a: &mut KalmanFilter, b: &mut KalmanFilter, z: f64) {
        let (phi, q, h, r) = model();
        let z = DVector::from_element(1, z);
        let ia = a.step(&z).unwrap();
        b.predict(&phi, &q, 1.0).unwrap();
        let ib = b.update(&z, &h, &r).unwrap();
        assert_eq!((a.x(), a.p()), (b.x(), b.p()));
        assert_eq!(ia.statistic.to_bits(), ib.statistic.to_bits());
    }

    #[test]
    fn a_step_is_predict_then_update_to_the_bit() {
        let (mut a, mut b) = twins();
        for k in 0..20 {
            step_both(&mut a, &mut b, (k as f64).sin());
        }
    }

    #[test]
    fn bad_input_leaves_the_filter_as_it_was() {
        let (phi, q, h, r) = model();
        let mut kf = filter();
        assert!(kf.step(&DVector::from_element(1, 0.0)).is_err()); // no model
        assert!(kf
            .set_model(phi.clone(), -q.clone(), h.clone(), r.clone())
            .is_err());
        assert!(kf.model().is_none());
        kf.set_model(phi, q, h, r).unwrap();
        let (x, p) = (kf.x().clone(), kf.p().clone());
        assert!(kf.step(&DVector::from_element(2, 0.0)).is_err()); // wrong length
        assert!(kf.step(&DVector::from_element(1, f64::INFINITY)).is_err());
        assert_eq!((kf.x(), kf.p()), (&x, &p));
        // A missing component: predict only.
        assert!(kf.step(&DVector::from_element(1, f64::NAN)).is_ok());
        assert_ne!(kf.p(), &p);
    }

    /// An update that fails after the prediction (a finite `z` whose statistic overflows)
    /// restores the state before the epoch from the swapped buffers, and the next steps are
    /// still predict + update to the bit.
    #[test]
    fn a_failed_update_restores_the_epoch_before() {
        let (mut a, mut b) = twins();
        for k in 0..3 {
            step_both(&mut a, &mut b, k as f64);
        }
        let (x, p) = (a.x().clone(), a.p().clone());
        assert!(a.step(&DVector::from_element(1, 1e300)).is_err());
        assert_eq!((a.x(), a.p()), (&x, &p));
        for k in 0..3 {
            step_both(&mut a, &mut b, -(k as f64));
        }
    }

    #[test]
    fn the_model_survives_serialisation() {
        let (phi, q, h, r) = model();
        let mut kf = filter();
        kf.set_model(phi, q, h, r).unwrap();
        let back: KalmanFilter =
            serde_json::from_str(&serde_json::to_string(&kf).unwrap()).unwrap();
        assert_eq!(back.model(), kf.model());
        let plain: KalmanFilter =
            serde_json::from_str(&serde_json::to_string(&filter()).unwrap()).unwrap();
        assert!(plain.model().is_none());
    }
}
