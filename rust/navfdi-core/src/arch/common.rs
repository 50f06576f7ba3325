//! Helpers shared by the architectures: detectors built from their specs, the sensor of each
//! detection channel, which measurement matrices change along the run.

use crate::detect::{Detector, ImprovedSprt, JointChi2Sprt, ResidualChi2, SprtVariance};
use crate::error::Result;
use crate::spec::{DetectorKind, ScenarioSpec, SensorKind};

/// Build a detector from its spec (validated by the scenario). `min_samples` (SPRT and joint)
/// overrides the default minimum sample count of the SPRT.
pub fn make_detector(
    kind: DetectorKind,
    pf: f64,
    pm: Option<f64>,
    variance: Option<&str>,
    min_samples: Option<u64>,
) -> Result<Detector> {
    let var = if variance == Some("sample") {
        SprtVariance::Sample
    } else {
        SprtVariance::Known
    };
    let pm = pm.unwrap_or(pf);
    Ok(match kind {
        DetectorKind::Chi2 => Detector::Chi2(ResidualChi2::new(pf)?),
        DetectorKind::Sprt => {
            let d = ImprovedSprt::new(pf, pm, var)?;
            Detector::Sprt(match min_samples {
                Some(n) => d.with_min_samples(n)?,
                None => d,
            })
        }
        DetectorKind::Joint => {
            let d = JointChi2Sprt::new(pf, pm, var)?;
            Detector::Joint(match min_samples {
                Some(n) => d.with_min_samples(n)?,
                None => d,
            })
        }
        DetectorKind::StateChi2 => {
            return Err(crate::error::Error::Invalid(
                "a state_chi2 detector tests sub-filter states, not innovations (centralized architecture only)".into(),
            ))
        }
    })
}

/// Sensor index of each detection channel.
pub fn channel_sensors(spec: &ScenarioSpec) -> Vec<usize> {
    spec.channels()
        .iter()
        .map(|ch| spec.sensor_index(ch.sensor).unwrap_or(0))
        .collect()
}

/// Whether each channel's measurement matrix changes along the trajectory (position sensors).
pub fn varying_h(spec: &ScenarioSpec, sensor_idx: &[usize]) -> Vec<bool> {
    sensor_idx
        .iter()
        .map(|&si| {
            !matches!(
                spec.sensors[si].kind,
                SensorKind::Cns
                    | SensorKind::GnssVelocity
                    | SensorKind::Baro
                    | SensorKind::RadioAltimeter
                    | SensorKind::GnssRanges
            )
        })
        .collect()
}
