//! The one event-matching engine: alarm intervals and the fault each belongs to. `navfdi run`
//! (events and per-fault tables), `navfdi montecarlo` (per-run metrics, [`super::montecarlo`])
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
