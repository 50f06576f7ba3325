//! The one event-matching engine: alarm intervals and the fault each belongs to. `navfdi run`
//! (events and per-fault tables), `navfdi montecarlo` (per-run metrics, [`crate::montecarlo`])
//! and `navfdi demo` all use it.
//!
//! Rule: an alarm interval `[start, end)` (end = first epoch without alarm, or never) belongs
//! to the first fault, in start order, whose window `[f_start, f_end]` it overlaps
//! (`start ≤ f_end` and `end > f_start`) and that began at or after the previous fault's window
//! ended (`start ≥ previous f_end`): an alarm still raised from an earlier fault is not a new
//! detection. Delay = `max(start − f_start, 0)`.

/// One alarm interval: epoch indices `[start, end)`; `end = None` if still in alarm at the
/// last epoch.
pub type Interval = (usize, Option<usize>);

/// Alarm intervals of a per-epoch alarm sequence.
pub fn intervals(alarm: &[bool]) -> Vec<Interval> {
    let mut out = Vec::new();
    let mut start = None;
    for (k, &a) in alarm.iter().enumerate() {
        match (a, start) {
            (true, None) => start = Some(k),
            (false, Some(s)) => {
                out.push((s, Some(k)));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s, None));
    }
    out
}

/// The fault (index into `windows`, which must be sorted by start) that the interval from time
/// `start` to time `end` (`None`: never ended) detects, by the module's rule.
pub fn match_interval(start: f64, end: Option<f64>, windows: &[(f64, f64)]) -> Option<usize> {
    let end = end.unwrap_or(f64::INFINITY);
    let mut prev_end = f64::NEG_INFINITY;
    for (i, &(fs, fe)) in windows.iter().enumerate() {
        if start <= fe && end > fs && start >= prev_end {
            return Some(i);
        }
        prev_end = fe;
    }
    None
}

/// Every alarm interval of `alarm` (times `t`) with the fault it detects.
pub fn events(t: &[f64], alarm: &[bool], windows: &[(f64, f64)]) -> Vec<(Interval, Option<usize>)> {
    intervals(alarm)
        .into_iter()
        .map(|iv| {
            let m = match_interval(t[iv.0], iv.1.map(|e| t[e]), windows);
            (iv, m)
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
        assert_eq!(match_interval(310.0, Some(520.0), &w), Some(0));
        assert_eq!(match_interval(290.0, Some(301.0), &w), Some(0)); // false alarm running into it
        assert_eq!(match_interval(290.0, Some(300.0), &w), None); // ended as the fault began
        assert_eq!(match_interval(310.0, None, &w), Some(0)); // never cleared: only the first
        assert_eq!(match_interval(600.0, Some(810.0), &w), Some(1));
        assert_eq!(match_interval(499.0, Some(900.0), &w), Some(0)); // not a new detection of 1
        assert_eq!(match_interval(503.0, Some(505.0), &w), None); // after the fault
        assert_eq!(match_interval(100.0, Some(120.0), &w), None);
    }
}
