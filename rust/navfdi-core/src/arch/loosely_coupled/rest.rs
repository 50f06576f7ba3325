//! Whether a receiver of positions only agrees that the vehicle has stopped.
//!
//! The zero-velocity update starts where the IMU shows rest, and its own test compares the
//! INS's velocity with zero at the INS's velocity σ. With receiver velocities that σ is a few
//! cm/s and a vehicle still rolling fails the test; on positions alone it is tenths of a m/s,
//! and a car rolling smoothly to a stop (its IMU as quiet as at rest) passes: on the bundled
//! drive without its velocity channel, the update at 530 s stopped the INS while the car still
//! rolled at 0.5 m/s, 0.4 m short of where it stopped — and the fixes there, right, were held
//! out as a step to the end of the log (18 s). The fixes say it: two fixes 1 s apart 0.5 m
//! apart at RTK σ. So on positions alone a spell of rest starts only when the last two fixes
//! agree with standing still ([`FixRest::moving`]); once started it lasts as long as the IMU
//! shows rest (a fault starting during a stop does not end it).

use super::diverge::SecondDifferences;
use nalgebra::Vector3;

/// Displacements between consecutive fixes whose spread sets the test's noise.
const SPREAD_WINDOW: usize = 60;

/// A displacement beyond this many σ of standing still is motion.
const REST_SIGMAS: f64 = 3.0;

/// The INS's horizontal speed (m/s) at or below which the fixes are not asked: a ramp of the
/// receiver while the car stops moves the fixes, not the INS, which the IMU brings to rest
/// (the update then holds it); a car still rolling carries the INS along (0.3 m/s at 530 s).
const INS_ROLLING: f64 = 0.2;

/// The last fixes of a receiver of positions only, and the spread of their motion.
#[derive(Debug, Clone, Default)]
pub struct FixRest {
    /// The last two fixes and the sizes of their second differences.
    steps: SecondDifferences<SPREAD_WINDOW>,
    /// The last two fixes' horizontal σ as recorded (m).
    sigma: [f64; 2],
}

impl FixRest {
    /// The fix `p` (east, north, up, m) at `t` (s) with its horizontal σ `sigma` (m, as
    /// recorded), the fixes `interval` s apart: kept as the last, and its second difference,
    /// with the two before it at most 1.5 intervals apart, added to the spread.
    pub fn push(&mut self, t: f64, p: Vector3<f64>, sigma: f64, interval: f64) {
        if let Some(d) = self.steps.push(t, [p.x, p.y], interval) {
            let size = d[0].hypot(d[1]);
            if size.is_finite() {
                self.steps.record(size);
            }
        }
        self.sigma = [sigma, self.sigma[0]];
    }

    /// Whether the INS still rolls (`ins_speed`, m/s, above [`INS_ROLLING`]) and the last two
    /// fixes, the later at most 1.5 `interval`s before `t` (s) and the two at most 1.5
    /// intervals apart, say the vehicle moves: their horizontal displacement
    /// beyond [`REST_SIGMAS`] σ of a still receiver — σ the larger of the two fixes' recorded
    /// σ combined and the fixes' own noise, from the median size of their last second
    /// differences (for white errors a first difference's σ is a second difference's over √3,
    /// and the size's median 1.1774 σ per component; a receiver whose recorded σ is optimistic
    /// still passes at rest). False
    /// without two such fixes: no evidence.
    pub fn moving(&self, t: f64, interval: f64, ins_speed: f64) -> bool {
        if !(ins_speed > INS_ROLLING) {
            return false;
        }
        let gap = 1.5 * interval;
        let [Some((t1, p1)), Some((t0, p0))] = self.steps.last() else {
            return false;
        };
        if t - t1 > gap || t1 - t0 > gap {
            return false;
        }
        let recorded = self.sigma[0].hypot(self.sigma[1]);
        let own = self.steps.sigma(10).map_or(0.0, |s| s / 3f64.sqrt());
        (p1[0] - p0[0]).hypot(p1[1] - p0[1]) > REST_SIGMAS * recorded.max(own)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_car_rolling_to_a_stop_moves_until_its_fixes_stand() {
        let mut r = FixRest::default();
        // RTK fixes (σ 1 cm, 5 mm of noise) of a car at 0.5 m/s north, then stopped.
        let noise = |k: u32| 0.005 * (((k * 37) % 11) as f64 / 5.0 - 1.0);
        for k in 0..40u32 {
            let north = if k < 30 { 0.5 * k as f64 } else { 15.0 };
            r.push(
                k as f64,
                Vector3::new(noise(k), north + noise(k + 3), 0.0),
                0.01,
                1.0,
            );
            // One fix is no evidence; at k = 30 the last displacement is still 0.5 m; from 31
            // the car stands.
            assert_eq!(
                r.moving(k as f64 + 0.25, 1.0, 0.5),
                (1..31).contains(&k),
                "at {k}"
            );
        }
        // No recent pair of fixes: no evidence.
        assert!(!r.moving(45.0, 1.0, 0.5));
    }

    #[test]
    fn optimistic_sigma_still_passes_at_rest() {
        // A receiver that says 0.3 m but scatters by 2 m (white): its own spread decides.
        let mut r = FixRest::default();
        let mut seed = 3_u64;
        let mut gauss = || {
            let mut u = || {
                seed = seed
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                ((seed >> 11) as f64 + 0.5) / (1u64 << 53) as f64
            };
            (-2.0 * u().ln()).sqrt() * (std::f64::consts::TAU * u()).cos()
        };
        let mut moving = 0;
        for k in 0..300 {
            let p = Vector3::new(2.0 * gauss(), 2.0 * gauss(), 0.0);
            r.push(k as f64, p, 0.3, 1.0);
            if k >= 60 && r.moving(k as f64, 1.0, 0.5) {
                moving += 1;
            }
        }
        // 3σ of a 2D Gaussian displacement: exp(−4.5) = 1.1 % of the fixes.
        assert!(moving <= 8, "{moving} of 240 at rest called moving");
        // With the recorded σ alone, most would be.
        let recorded_only = (0..240).filter(|_| {
            let d = Vector3::new(2.0 * gauss(), 2.0 * gauss(), 0.0) * 2f64.sqrt();
            d.x.hypot(d.y) > 3.0 * 0.3 * 2f64.sqrt()
        });
        assert!(recorded_only.count() > 200);
    }
}
