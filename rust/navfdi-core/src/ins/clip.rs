//! IMU samples at the sensor's full scale (clipped). A MEMS accelerometer at ±2 g or a gyro at
//! ±250 deg/s — the power-on ranges of common consumer parts — reads its range's end, not the
//! motion, through a pothole, a kerb or a fast turn, and the mechanisation integrates the part
//! beyond it as if it had not happened.
//!
//! A channel is clipped where the log holds its largest (or smallest) value, exactly, on at
//! least [`MIN_RUN`] consecutive samples, and that value is within [`RANGE_TOLERANCE`] of a
//! full scale such sensors are built with ([`ACCEL_RANGES_G`], [`GYRO_RANGES_DPS`]): a
//! converter at its end code writes the same number again and again, and a real peak neither
//! stays on one value that long nor falls on a range's end by chance.

use nalgebra::Vector3;

/// Accelerometer full scales (g) of MEMS and tactical IMUs.
pub const ACCEL_RANGES_G: [f64; 14] = [
    2.0, 4.0, 5.0, 6.0, 8.0, 10.0, 16.0, 18.0, 20.0, 24.0, 30.0, 32.0, 40.0, 50.0,
];
/// Gyro full scales (deg/s).
pub const GYRO_RANGES_DPS: [f64; 12] = [
    125.0, 150.0, 245.0, 250.0, 300.0, 400.0, 450.0, 490.0, 500.0, 1000.0, 2000.0, 4000.0,
];
/// The shortest run of samples at the extreme value that is clipping.
pub const MIN_RUN: usize = 3;
/// How near a full scale the extreme value must be (relative): scale factors differ from the
/// nominal range by a few per cent (32 767 codes for 2 g; a g of 9.80665 or 9.81 m/s²).
pub const RANGE_TOLERANCE: f64 = 0.05;
const G: f64 = 9.80665;

/// A clipped channel: `sensor` 0 accelerometer, 1 gyro; `axis` 0–2 (the IMU's x, y, z);
/// `value` the full-scale reading (m/s² or rad/s, signed); `samples` how many sit on it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClippedChannel {
    /// 0: accelerometer, 1: gyro.
    pub sensor: usize,
    /// The IMU axis (0, 1, 2: x, y, z).
    pub axis: usize,
    /// The value the samples sit on (m/s² or rad/s).
    pub value: f64,
    /// Samples on it.
    pub samples: usize,
}

/// The samples (one flag each) at a channel's full scale, and the clipped channels. `gyro`
/// (rad/s) and `acc` (m/s²) in the IMU's own axes, one per sample.
pub fn clipped_samples(
    gyro: &[Vector3<f64>],
    acc: &[Vector3<f64>],
) -> (Vec<bool>, Vec<ClippedChannel>) {
    let n = gyro.len().min(acc.len());
    let mut mask = vec![false; n];
    let mut channels = Vec::new();
    for (sensor, data, ranges, unit) in [
        (0, acc, &ACCEL_RANGES_G[..], G),
        (1, gyro, &GYRO_RANGES_DPS[..], 1f64.to_radians()),
    ] {
        for axis in 0..3 {
            let col: Vec<f64> = data.iter().take(n).map(|x| x[axis]).collect();
            let v = |k: usize| col[k];
            let (mut hi, mut lo) = (f64::NEG_INFINITY, f64::INFINITY);
            for k in 0..n {
                hi = hi.max(v(k));
                lo = lo.min(v(k));
            }
            for value in [hi, lo] {
                let near = ranges
                    .iter()
                    .map(|r| (value.abs() / unit / r - 1.0).abs())
                    .fold(f64::INFINITY, f64::min);
                if !(near <= RANGE_TOLERANCE) {
                    continue;
                }
                let (mut run, mut longest, mut count) = (0, 0, 0);
                for k in 0..n {
                    if v(k) == value {
                        run += 1;
                        count += 1;
                        longest = longest.max(run);
                    } else {
                        run = 0;
                    }
                }
                if longest >= MIN_RUN
                    && !channels.iter().any(|c: &ClippedChannel| {
                        c.sensor == sensor && c.axis == axis && c.value == value
                    })
                {
                    for (k, m) in mask.iter_mut().enumerate() {
                        *m |= v(k) == value;
                    }
                    channels.push(ClippedChannel {
                        sensor,
                        axis,
                        value,
                        samples: count,
                    });
                }
            }
        }
    }
    (mask, channels)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn log(z: &[f64]) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
        let acc = z.iter().map(|&g| Vector3::new(0.1, -0.2, g * G)).collect();
        let gyro = z.iter().map(|_| Vector3::new(0.01, 0.0, -0.02)).collect();
        (gyro, acc)
    }

    #[test]
    fn a_run_at_a_full_scale_is_clipped_and_a_peak_is_not() {
        // Vertical specific force held at 2 g for three samples, twice.
        let z = [
            1.0, 1.5, 2.0, 2.0, 2.0, 1.2, 1.0, 0.4, 1.0, 2.0, 2.0, 2.0, 1.1,
        ];
        let (gyro, acc) = log(&z);
        let (mask, ch) = clipped_samples(&gyro, &acc);
        assert_eq!(ch.len(), 1);
        assert_eq!((ch[0].sensor, ch[0].axis, ch[0].samples), (0, 2, 6));
        assert_eq!(mask.iter().filter(|&&m| m).count(), 6);
        assert!(mask[2] && mask[4] && !mask[5] && mask[9]);
        // Two samples on it: a peak held, not a converter at its end code.
        let (_, ch) = clipped_samples(&gyro[..4], &acc[..4]);
        assert!(ch.is_empty());
        // Three samples on a value that is no full scale (1.7 g).
        let z = [1.0, 1.7, 1.7, 1.7, 1.0];
        let (gyro, acc) = log(&z);
        assert!(clipped_samples(&gyro, &acc).1.is_empty());
    }

    #[test]
    fn a_gyro_at_minus_250_deg_per_s_is_clipped() {
        let r = -250f64.to_radians() * 1.01;
        let gyro: Vec<_> = [0.1, r, r, r, r, 0.2]
            .iter()
            .map(|&w| Vector3::new(0.0, w, 0.0))
            .collect();
        let acc = vec![Vector3::new(0.0, 0.0, G); 6];
        let (mask, ch) = clipped_samples(&gyro, &acc);
        assert_eq!(
            ch,
            vec![ClippedChannel {
                sensor: 1,
                axis: 1,
                value: r,
                samples: 4
            }]
        );
        assert_eq!(mask, vec![false, true, true, true, true, false]);
    }
}
