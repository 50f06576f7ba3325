//! The one event-matching engine: alarm intervals and the fault each detects. `navfdi run`
//! (events and per-fault tables), `navfdi montecarlo` (per-run metrics, [`crate::montecarlo`])
//! and `navfdi demo` all use it.
//!
//! **Tested epochs are the unit.** A detector tests only at the epochs its sensor measures (a
//! 1 Hz GNSS on a 4 Hz record is tested at one epoch in four); at the others its statistic is
//! NaN ([`tested`]) and whatever alarm flag it carries there is ignored. Every per-epoch
//! figure counts tests: the share of a fault's epochs in alarm, false alarms per epoch, the
//! share of epochs excluded. An alarm interval runs from the first alarmed test to the first
//! passing test after it; untested epochs between them do not end it.
//!
//! Rule: a fault with window `[f_start, f_end)` is **detected** by an alarm interval whose
//! **onset** (its first test) lies in `[f_start, f_end + GRACE]` ([`GRACE`] seconds after the
//! fault's end still count: a detector's latency). When several faults' windows hold the
//! onset, it belongs to the one that started last (the most recent change). An alarm raised
//! before the fault began and still running at its start is *not* a detection: it is
//! reported separately ("in alarm at onset"), and the share of the fault's tests in alarm is
//! reported beside the detection. Delay = onset − `f_start` (never negative).

/// One alarm interval: epoch indices `[start, end)`; `end = None` if still in alarm at the
/// last test. `start` is the first alarmed test, `end` the first passing test after it.
pub type Interval = (usize, Option<usize>);

/// The epochs at which a detector tested: its statistic is not NaN there (an untested epoch
/// records NaN; a gross fault's statistic is `inf`, which is a test).
pub fn tested(statistic: &[f64]) -> Vec<bool> {
    statistic.iter().map(|s| !s.is_nan()).collect()
}

/// Alarm intervals of a per-epoch alarm sequence in which every epoch is a test.
pub fn intervals(alarm: &[bool]) -> Vec<Interval> {
    test_intervals(alarm, None)
        .into_iter()
        .map(|(iv, _)| iv)
        .collect()
}

/// Alarm intervals of `alarm` over the epochs `tested` (None: every epoch), each with the
/// number of tests it spans (alarmed tests: every test inside an interval alarmed). Alarm
/// flags at untested epochs are ignored.
pub fn test_intervals(alarm: &[bool], tested: Option<&[bool]>) -> Vec<(Interval, u32)> {
    let mut out = Vec::new();
    let mut open: Option<(usize, u32)> = None;
    for (k, &a) in alarm.iter().enumerate() {
        if !tested.is_none_or(|t| t.get(k).copied().unwrap_or(false)) {
            continue;
        }
        match (a, open.as_mut()) {
            (true, None) => open = Some((k, 1)),
            (true, Some((_, n))) => *n += 1,
            (false, Some(&mut (s, n))) => {
                out.push(((s, Some(k)), n));
                open = None;
            }
            (false, None) => {}
        }
    }
    if let Some((s, n)) = open {
        out.push(((s, None), n));
    }
    out
}

/// Seconds after a fault's end within which an alarm onset still detects it: one epoch at
/// 1 Hz, the latency of a detector that tests the fault's last measurement. Later onsets are
/// the clearing transient, not detections (and fall in the [`crate::montecarlo::SETTLE`]
/// seconds left out of the false-alarm count).
pub const GRACE: f64 = 1.0;

/// The fault (index into `windows`, `(start, end)` in s) that an alarm interval with onset at
/// time `onset` detects, by the module's rule: the latest-starting window with
/// `w_start ≤ onset ≤ w_end + GRACE` (the interval's end plays no part).
pub fn match_interval(onset: f64, windows: &[(f64, f64)]) -> Option<usize> {
    let start = onset;
    windows
        .iter()
        .enumerate()
        .filter(|(_, &(ws, we))| ws <= start && start <= we + GRACE)
        .max_by(|a, b| a.1 .0.total_cmp(&b.1 .0).then(b.0.cmp(&a.0)))
        .map(|(i, _)| i)
}

/// Per fault window and alarm sequence over the epochs `tested` (None: every epoch): whether
/// the detector was already in alarm at the window's first test (an alarm raised at an earlier
/// test, before the fault), and the share of the window's tests in alarm (NaN when no test
/// lies in the window).
pub fn window_alarm(
    t: &[f64],
    alarm: &[bool],
    tested: Option<&[bool]>,
    window: (f64, f64),
) -> (bool, f64) {
    let (ws, we) = window;
    let is_test = |k: usize| tested.is_none_or(|m| m.get(k).copied().unwrap_or(false));
    let first = (0..t.len()).find(|&k| is_test(k) && t[k] >= ws && t[k] < we);
    // In alarm at its first test with the alarm raised at the test before (before the fault).
    let at_onset = first
        .is_some_and(|k| alarm[k] && (0..k).rev().find(|&j| is_test(j)).is_some_and(|j| alarm[j]));
    let (mut n, mut a) = (0u32, 0u32);
    for (k, &tk) in t.iter().enumerate() {
        if is_test(k) && tk >= ws && tk < we {
            n += 1;
            a += u32::from(alarm[k]);
        }
    }
    (at_onset, if n > 0 { a as f64 / n as f64 } else { f64::NAN })
}

/// Every alarm interval of `alarm` (times `t`, tests `tested`) with the tests it spans and
/// the fault it detects.
pub fn events(
    t: &[f64],
    alarm: &[bool],
    tested: Option<&[bool]>,
    windows: &[(f64, f64)],
) -> Vec<(Interval, u32, Option<usize>)> {
    test_intervals(alarm, tested)
        .into_iter()
        .map(|(iv, n)| {
            let m = match_interval(t[iv.0], windows);
            (iv, n, m)
        })
        .collect()
}

/// Measured epochs after a fault's end over which alarms count as its after-effect.
pub const AFTER_EPOCHS: usize = 50;

/// Satellite-FDE counts of one run for one fault on a `gnss_ranges` sensor (`fault = Some`)
/// or for the epochs outside every fault and its after-window (`fault = None`). Only epochs
/// in which the sensor measured count. Rates (pooled over runs by summing numerators and
/// denominators):
///
/// * detection rate = `detected_epochs / faulty_epochs` (faulty epochs: in the fault window
///   with the faulty satellite in view; detected: it was excluded);
/// * identification rate = `exact_epochs / exclusion_epochs` (epochs in the window with any
///   exclusion; exact: exactly the faulty satellite excluded);
/// * after-fault alarm rate = `after_alarm_epochs / after_epochs` (the first
///   [`AFTER_EPOCHS`] measured epochs from the fault's end, stopping at the next fault on the
///   sensor; alarm: any satellite excluded);
/// * false-exclusion rate = `false_exclusions / outside_epochs` (satellites excluded per epoch
///   outside every fault window and after-window).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SatFaultMetrics {
    /// Fault index in the scenario, or None for the outside epochs.
    pub fault: Option<usize>,
    /// Epochs in the window with the faulty satellite in view.
    pub faulty_epochs: u32,
    /// Of those, epochs in which it was excluded.
    pub detected_epochs: u32,
    /// Epochs in the window with any exclusion.
    pub exclusion_epochs: u32,
    /// Epochs in the window in which exactly the faulty satellite was excluded.
    pub exact_epochs: u32,
    /// Epochs in the after-window.
    pub after_epochs: u32,
    /// Of those, epochs with any exclusion.
    pub after_alarm_epochs: u32,
    /// Epochs outside every window and after-window (`fault = None`).
    pub outside_epochs: u32,
    /// Satellites excluded in those epochs (`fault = None`).
    pub false_exclusions: u32,
}

/// A fault on a satellite for [`satellite_metrics`]: scenario fault index, satellite index,
/// window `[start, end)` (s).
pub type SatFault = (usize, usize, f64, f64);

/// Satellite-FDE counts (see [`SatFaultMetrics`]) from per-epoch flags: `t` (T) epoch times,
/// `measured` (T), `in_view` and `excluded` (T × S row-major), `faults` on the sensor. One
/// entry per fault (in the order given), then the outside entry.
pub fn satellite_metrics(
    t: &[f64],
    measured: &[bool],
    in_view: &[bool],
    excluded: &[bool],
    sats: usize,
    faults: &[SatFault],
) -> Vec<SatFaultMetrics> {
    let epochs = t.len();
    let row = |k: usize| k * sats..(k + 1) * sats;
    let n_excluded = |k: usize| excluded[row(k)].iter().filter(|e| **e).count() as u32;
    let mut after_mask = vec![false; epochs];
    let mut out = Vec::with_capacity(faults.len() + 1);
    for &(fi, sat, start, end) in faults {
        let mut m = SatFaultMetrics {
            fault: Some(fi),
            ..Default::default()
        };
        let next = faults
            .iter()
            .map(|f| f.2)
            .filter(|&s| s >= end)
            .fold(f64::INFINITY, f64::min);
        let mut after_left = AFTER_EPOCHS;
        for k in 0..epochs {
            if !measured[k] {
                continue;
            }
            let tk = t[k];
            let nx = n_excluded(k);
            if tk >= start && tk < end {
                if in_view[k * sats + sat] {
                    m.faulty_epochs += 1;
                    if excluded[k * sats + sat] {
                        m.detected_epochs += 1;
                    }
                }
                if nx > 0 {
                    m.exclusion_epochs += 1;
                    if nx == 1 && excluded[k * sats + sat] {
                        m.exact_epochs += 1;
                    }
                }
            } else if tk >= end && tk < next && after_left > 0 {
                after_left -= 1;
                after_mask[k] = true;
                m.after_epochs += 1;
                if nx > 0 {
                    m.after_alarm_epochs += 1;
                }
            }
        }
        out.push(m);
    }
    let mut none = SatFaultMetrics::default();
    for k in 0..epochs {
        let inside = faults.iter().any(|f| t[k] >= f.2 && t[k] < f.3);
        if measured[k] && !inside && !after_mask[k] {
            none.outside_epochs += 1;
            none.false_exclusions += n_excluded(k);
        }
    }
    out.push(none);
    out
}

#[cfg(test)]
mod sat_tests {
    use super::*;

    #[test]
    fn satellite_counts() {
        // 2 satellites, 8 epochs at 1 s; fault on satellite 1 over [2, 5).
        let t: Vec<f64> = (0..8).map(|k| k as f64).collect();
        let measured = [true, true, true, true, true, true, false, true];
        let in_view = [true; 16];
        let mut excluded = [false; 16];
        excluded[2 * 2 + 1] = true; // k=2: exactly sat 1
        excluded[3 * 2] = true; // k=3: both
        excluded[3 * 2 + 1] = true;
        excluded[5 * 2] = true; // k=5: after, sat 0
        excluded[2] = true; // k=1: outside, sat 0
        let m = satellite_metrics(&t, &measured, &in_view, &excluded, 2, &[(0, 1, 2.0, 5.0)]);
        assert_eq!(m.len(), 2);
        let f = m[0];
        assert_eq!((f.faulty_epochs, f.detected_epochs), (3, 2));
        assert_eq!((f.exclusion_epochs, f.exact_epochs), (2, 1));
        // after: measured epochs 5 and 7 (6 not measured), alarm at 5
        assert_eq!((f.after_epochs, f.after_alarm_epochs), (2, 1));
        let o = m[1];
        assert_eq!((o.outside_epochs, o.false_exclusions), (2, 1));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interval_extraction() {
        let a = [false, true, true, false, true];
        assert_eq!(intervals(&a), vec![(1, Some(3)), (4, None)]);
        assert!(intervals(&[false, false]).is_empty());
    }

    #[test]
    fn matching_rule() {
        let w = [(300.0, 500.0), (800.0, 850.0)];
        assert_eq!(match_interval(310.0, &w), Some(0)); // onset inside
        assert_eq!(match_interval(300.0, &w), Some(0)); // onset at the first epoch
                                                        // An alarm raised before the fault and still running detects nothing.
        assert_eq!(match_interval(290.0, &w), None);
        assert_eq!(match_interval(290.0, &w), None);
        assert_eq!(match_interval(600.0, &w), None); // raised between faults
        assert_eq!(match_interval(805.0, &w), Some(1));
        assert_eq!(match_interval(501.0, &w), Some(0)); // within the 1 s grace
        assert_eq!(match_interval(502.0, &w), None); // after the grace
        assert_eq!(match_interval(100.0, &w), None);
        // Overlapping windows: the latest-starting fault that holds the onset.
        let w = [(100.0, 200.0), (150.0, 160.0)];
        assert_eq!(match_interval(155.0, &w), Some(1));
        assert_eq!(match_interval(160.5, &w), Some(1)); // in 1's grace, 0's window
        assert_eq!(match_interval(175.0, &w), Some(0));
    }

    #[test]
    fn alarm_at_onset_and_fraction() {
        let t: Vec<f64> = (0..10).map(|k| k as f64).collect();
        let a = [
            false, false, true, true, true, false, false, true, false, false,
        ];
        // Window [3, 7): in alarm at 3 since 2 (before the fault); 2 of 4 epochs in alarm.
        assert_eq!(window_alarm(&t, &a, None, (3.0, 7.0)), (true, 0.5));
        // Window [2, 4): the alarm begins with it: a detection, not "at onset".
        assert_eq!(window_alarm(&t, &a, None, (2.0, 4.0)), (false, 1.0));
        assert_eq!(window_alarm(&t, &a, None, (5.0, 7.0)), (false, 0.0));
        let (at, f) = window_alarm(&t, &a, None, (20.0, 30.0));
        assert!(!at && f.is_nan());
    }

    #[test]
    fn untested_epochs_neither_end_nor_count() {
        // A 1 Hz test on a 4 Hz record: tests at 0, 4, 8, ...; the untested epochs carry
        // `false` (loosely coupled) - they must not split the alarm or dilute its share.
        let t: Vec<f64> = (0..24).map(|k| k as f64 * 0.25).collect();
        let tested: Vec<bool> = (0..24).map(|k| k % 4 == 0).collect();
        let alarm: Vec<bool> = (0..24)
            .map(|k| k % 4 == 0 && (8..20).contains(&k))
            .collect();
        let ivs = test_intervals(&alarm, Some(&tested));
        assert_eq!(ivs, vec![((8, Some(20)), 3)]);
        // Held alarm flags at untested epochs (federated) give the same interval.
        let held: Vec<bool> = (0..24).map(|k| (8..20).contains(&k)).collect();
        assert_eq!(test_intervals(&held, Some(&tested)), ivs);
        // Every test of [2, 5) s (epochs 8, 12, 16) alarmed: share 1, not 1/4.
        assert_eq!(
            window_alarm(&t, &alarm, Some(&tested), (2.0, 5.0)),
            (false, 1.0)
        );
        assert_eq!(window_alarm(&t, &alarm, None, (2.0, 5.0)), (false, 0.25));
        // In alarm at onset: the test before the window alarmed (untested epochs skipped).
        assert_eq!(
            window_alarm(&t, &alarm, Some(&tested), (3.0, 5.0)),
            (true, 1.0)
        );
        // Still open at the end.
        let open: Vec<bool> = (0..24).map(|k| k >= 16).collect();
        assert_eq!(test_intervals(&open, Some(&tested)), vec![((16, None), 2)]);
        assert_eq!(tested_of_nan(), vec![true, false, true]);
    }

    fn tested_of_nan() -> Vec<bool> {
        tested(&[1.0, f64::NAN, f64::INFINITY])
    }
}
