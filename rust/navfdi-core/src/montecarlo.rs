//! Monte-Carlo runs of a prepared scenario, reduced to per-run metrics (METHODS §12).
//!
//! Run `i` draws its noise from `(seed, stream = i)` ([`crate::sim::noise::simulate`]) and is
//! filtered with isolation active, so its metrics depend on nothing but `(seed, i)`: the
//! results are bit-identical whatever the number of threads, the chunking of runs or the
//! machine that executes a chunk.
//!
//! Metrics per run and *cell* (sub-filter × detector × fault, plus one cell per sub-filter ×
//! detector for the epochs outside every fault, fault id `none`):
//!
//! Every per-epoch count is over the epochs at which the detector tested
//! ([`crate::metrics::tested`]): on a multi-rate record a 1 Hz sensor's detectors count one
//! epoch per second, whatever the record's interval.
//!
//! * fault cells: `detected` (an alarm onset inside the window or up to
//!   [`crate::metrics::GRACE`] s after it, [`crate::metrics`]'s rule), `delay` = onset − fault
//!   start, `clear_delay` = end of the last such interval (its first passing test) − fault end
//!   (NaN if never cleared), `at_onset` (already in alarm when the fault began: reported, not
//!   a detection) and `alarm_fraction` (share of the fault's tests in alarm);
//! * `none` cells: `false_alarm_epochs` and `outside_epochs`: tests with an alarm, and all
//!   tests, outside every fault window of the sub-filter's sensor and outside the
//!   [`SETTLE`] seconds after each fault ends (the clearing transient);
//! * the isolating detector's cells: `wrong_isolations`, isolation intervals of the sub-filter
//!   that overlap no fault window of its sensor (counted on the `none` cell);
//! * per run: master attitude error RMS and maximum (rad, all axes) and position error RMS and
//!   maximum (m, horizontal and vertical together).

use crate::arch::run_architecture;
use crate::cancel::Cancel;
use crate::error::{Error, Result};
use crate::metrics::{match_interval, test_intervals, tested, window_alarm, Interval};
use crate::record::RunRecord;
use crate::sim::noise::simulate;
use crate::sim::prepare::Prepared;
use crate::spec::ScenarioSpec;
use rayon::prelude::*;

/// Seconds after a fault's end excluded from false-alarm counting.
pub const SETTLE: f64 = 10.0;

/// One cell: which sub-filter, detector and fault (None: outside faults).
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    /// Sub-filter (sensor) index in the federated configuration.
    pub subfilter: usize,
    /// Detector index in that sub-filter.
    pub detector: usize,
    /// Fault index in the scenario, or None for the `none` cell.
    pub fault: Option<usize>,
}

/// Metrics of one run and cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellMetrics {
    /// Fault detected (fault cells).
    pub detected: bool,
    /// Detection delay (s), NaN if missed or a `none` cell.
    pub delay: f64,
    /// Clear delay (s), NaN if not detected or never cleared.
    pub clear_delay: f64,
    /// Alarmed epochs outside faults (`none` cells).
    pub false_alarm_epochs: u32,
    /// Epochs outside faults (`none` cells).
    pub outside_epochs: u32,
    /// Isolation intervals overlapping no fault (`none` cell of the isolating detector).
    pub wrong_isolations: u32,
    /// Fault cells: the detector was already in alarm at the fault's first epoch (raised
    /// before the fault began; not a detection).
    pub at_onset: bool,
    /// Fault cells: fraction of the fault's epochs in alarm (NaN for `none` cells).
    pub alarm_fraction: f64,
    /// Fault cells: the fault reached a measurement the filter processed
    /// ([`RunRecord::faults_applied`]); a fault that did not (outside the navigated span of a
    /// partial log, or its sensor not measuring) is left out of the detection figures.
    /// Always true for `none` cells.
    pub applied: bool,
    /// Satellite-FDE counts (tight architecture; all zero otherwise): for a fault cell the
    /// fault's, for the `none` cell the outside epochs' ([`crate::metrics::SatFaultMetrics`]).
    pub sat: crate::metrics::SatFaultMetrics,
}

/// Metrics of one run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunMetrics {
    /// Run index.
    pub run: u64,
    /// Per cell, in [`cells`] order.
    pub cells: Vec<CellMetrics>,
    /// Master attitude error RMS (rad).
    pub att_rms: f64,
    /// Master attitude error maximum |φ| component (rad).
    pub att_max: f64,
    /// Master position error RMS (m).
    pub pos_rms: f64,
    /// Master position error maximum |component| (m).
    pub pos_max: f64,
    /// Latitude (north position) error RMS (m).
    pub lat_rms: f64,
    /// Latitude (north position) error maximum |error| (m).
    pub lat_max: f64,
    /// Fused-altitude error RMS over the epochs it existed (m; NaN without altitude fusion or
    /// when it never existed).
    pub fused_alt_rms: f64,
    /// Fused-altitude error maximum |error| (m; NaN likewise).
    pub fused_alt_max: f64,
    /// Runs on recorded logs: horizontal error RMS and maximum (m) over the scored epochs,
    /// and the maximum inside the fault windows (NaN without faults); NaN for simulated runs.
    pub hor_rms: f64,
    /// See [`RunMetrics::hor_rms`].
    pub hor_max: f64,
    /// See [`RunMetrics::hor_rms`].
    pub fault_hor_max: f64,
    /// [`RunMetrics::hor_rms`] and [`RunMetrics::fault_hor_max`] with the run's mean east and
    /// north offset to the reference removed (the mean over the scored epochs outside the
    /// fault windows): for a reference with an offset of its own (m; NaN likewise).
    pub hor_rel_rms: f64,
    /// See [`RunMetrics::hor_rel_rms`].
    pub fault_hor_rel_max: f64,
    /// The run's faults as drawn (campaigns on recorded logs; empty otherwise).
    pub drawn: Vec<crate::spec::FaultSpec>,
    /// Filter protection levels against the true error (tight filter with
    /// `[tight.integrity]`; None otherwise).
    pub integrity: Option<IntegrityMetrics>,
    /// Optional full record of the run (kept for chosen runs).
    pub record: Option<RunRecord>,
    /// The run failed (its error: a numerical failure on this draw's measurements, with the
    /// epoch); every figure is NaN and it is left out of the campaign's statistics, which
    /// go on with the other runs.
    pub failed: Option<String>,
}

impl CellMetrics {
    /// A cell before scoring (nothing detected, every figure NaN); `applied`: its fault
    /// reached a measurement.
    fn unscored(applied: bool) -> Self {
        CellMetrics {
            detected: false,
            delay: f64::NAN,
            clear_delay: f64::NAN,
            false_alarm_epochs: 0,
            outside_epochs: 0,
            wrong_isolations: 0,
            at_onset: false,
            alarm_fraction: f64::NAN,
            applied,
            sat: Default::default(),
        }
    }
}

impl RunMetrics {
    /// The metrics of run `run` that failed with `error`: `cells` cells, every figure NaN.
    pub fn failed(run: u64, cells: usize, error: String) -> Self {
        let cell = CellMetrics::unscored(false);
        RunMetrics {
            run,
            cells: vec![cell; cells],
            att_rms: f64::NAN,
            att_max: f64::NAN,
            pos_rms: f64::NAN,
            pos_max: f64::NAN,
            lat_rms: f64::NAN,
            lat_max: f64::NAN,
            fused_alt_rms: f64::NAN,
            fused_alt_max: f64::NAN,
            hor_rms: f64::NAN,
            hor_max: f64::NAN,
            fault_hor_max: f64::NAN,
            hor_rel_rms: f64::NAN,
            fault_hor_rel_max: f64::NAN,
            drawn: Vec::new(),
            integrity: None,
            record: None,
            failed: Some(error),
        }
    }
}

/// Protection levels of one run against its true position error (see [`integrity_metrics`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct IntegrityMetrics {
    /// Epochs with finite filter protection levels.
    pub epochs: u32,
    /// Epochs whose horizontal (vertical) error exceeds the HPL (VPL): misleading.
    pub mi_h: u32,
    /// See [`IntegrityMetrics::mi_h`].
    pub mi_v: u32,
    /// Of those, epochs without an alarm of the separation test: hazardously misleading.
    pub hmi_h: u32,
    /// See [`IntegrityMetrics::hmi_h`].
    pub hmi_v: u32,
    /// Epochs in which the separation test alarmed.
    pub alarms: u32,
    /// Largest horizontal error / HPL and vertical error / VPL over the run.
    pub max_ratio_h: f64,
    /// See [`IntegrityMetrics::max_ratio_h`].
    pub max_ratio_v: f64,
    /// Epochs with both filter and snapshot levels finite, and the sums over them of
    /// filter HPL / snapshot HPL and filter VPL / snapshot VPL.
    pub compared: u32,
    /// See [`IntegrityMetrics::compared`].
    pub sum_pl_ratio_h: f64,
    /// See [`IntegrityMetrics::compared`].
    pub sum_pl_ratio_v: f64,
    /// Sums of the filter HPL and VPL over [`IntegrityMetrics::epochs`] (m).
    pub sum_hpl: f64,
    /// See [`IntegrityMetrics::sum_hpl`].
    pub sum_vpl: f64,
}

/// Whether epoch `k` of `rec` (error row `row`) is scored against the protection levels: both
/// levels and the position error are finite.
fn is_scored(ir: &crate::record::IntegrityRecord, k: usize, row: &[f64]) -> bool {
    ir.hpl[k].is_finite() && ir.vpl[k].is_finite() && row[6..9].iter().all(|v| v.is_finite())
}

/// The mean position error (east, north, up, m) of `rec` over its scored epochs; `None`
/// without protection levels or scored epochs.
fn mean_position_error(rec: &RunRecord) -> Option<[f64; 3]> {
    let ir = rec.integrity.as_ref()?;
    let (mut sum, mut n) = ([0.0; 3], 0usize);
    for (k, row) in rec.error.chunks(9).enumerate() {
        if is_scored(ir, k, row) {
            for q in 0..3 {
                sum[q] += row[6 + q];
            }
            n += 1;
        }
    }
    (n > 0).then(|| sum.map(|v| v / n as f64))
}

/// The protection levels of `rec` (when it has them) against its position error (m,
/// columns pos_e, pos_n, pos_u of [`RunRecord::error`]; on recorded logs about the
/// reference's datum: [`RunRecord::datum`], else the run's own mean offset): counts of
/// misleading and hazardously misleading epochs, the worst error-to-level ratios, and the
/// filter levels beside the snapshot levels of the same epochs.
pub fn integrity_metrics(rec: &RunRecord) -> Option<IntegrityMetrics> {
    let ir = rec.integrity.as_ref()?;
    let mut m = IntegrityMetrics::default();
    // On recorded logs the reference has a datum of its own (walk_tc's is 8 m off): the errors
    // are taken about it — the fault-free pass's mean offset a logged run with faults carries
    // ([`logged_datum`]), else (no fault to move it) the run's own.
    let offset = match rec.datum {
        Some(d) => d,
        None if !rec.nav.is_empty() => mean_position_error(rec).unwrap_or([0.0; 3]),
        None => [0.0; 3],
    };
    for (k, row) in rec.error.chunks(9).enumerate() {
        let (hpl, vpl) = (ir.hpl[k], ir.vpl[k]);
        if !is_scored(ir, k, row) {
            continue;
        }
        let hor = (row[6] - offset[0]).hypot(row[7] - offset[1]);
        let up = (row[8] - offset[2]).abs();
        if !(hor.is_finite() && up.is_finite()) {
            continue;
        }
        m.epochs += 1;
        m.sum_hpl += hpl;
        m.sum_vpl += vpl;
        let alarm = ir.alarm[k];
        m.alarms += u32::from(alarm);
        if hor > hpl {
            m.mi_h += 1;
            m.hmi_h += u32::from(!alarm);
        }
        if up > vpl {
            m.mi_v += 1;
            m.hmi_v += u32::from(!alarm);
        }
        m.max_ratio_h = m.max_ratio_h.max(hor / hpl);
        m.max_ratio_v = m.max_ratio_v.max(up / vpl);
        let (hs, vs) = (ir.hpl_snapshot[k], ir.vpl_snapshot[k]);
        if hs.is_finite() && vs.is_finite() && hs > 0.0 && vs > 0.0 {
            m.compared += 1;
            m.sum_pl_ratio_h += hpl / hs;
            m.sum_pl_ratio_v += vpl / vs;
        }
    }
    Some(m)
}

/// The cells of a scenario, in the order metrics are reported.
pub fn cells(prep: &Prepared) -> Vec<Cell> {
    spec_cells(&prep.spec)
}

/// [`cells`] from the scenario alone (no preparation needed).
pub fn spec_cells(spec: &ScenarioSpec) -> Vec<Cell> {
    let mut out = Vec::new();
    for (si, sf) in spec.channels().iter().enumerate() {
        let faults: Vec<usize> = (0..spec.faults.len())
            .filter(|&f| sf.sees(&spec.faults[f]))
            .collect();
        for di in 0..sf.detectors.len() {
            for &f in &faults {
                out.push(Cell {
                    subfilter: si,
                    detector: di,
                    fault: Some(f),
                });
            }
            out.push(Cell {
                subfilter: si,
                detector: di,
                fault: None,
            });
        }
    }
    out
}

/// Reduce one run's record to metrics.
pub fn metrics(prep: &Prepared, run: u64, rec: &RunRecord, cells: &[Cell]) -> RunMetrics {
    metrics_of(&prep.spec, run, rec, cells)
}

/// Reduce one run's record of scenario `spec` to metrics (any source). Every per-epoch
/// figure counts the epochs the detector tested ([`crate::metrics`]); on recorded logs (a
/// record with a navigation solution) the errors are taken over the epochs the reference
/// scores.
pub fn metrics_of(spec: &ScenarioSpec, run: u64, rec: &RunRecord, cells: &[Cell]) -> RunMetrics {
    let logged = !rec.nav.is_empty();
    let t = &rec.t;
    let mut out = Vec::with_capacity(cells.len());
    for c in cells {
        let sub = &rec.subs[c.subfilter];
        let det = &sub.detectors[c.detector];
        let channels = spec.channels();
        let channel = &channels[c.subfilter];
        let mut faults: Vec<&crate::spec::FaultSpec> =
            spec.faults.iter().filter(|f| channel.sees(f)).collect();
        faults.sort_by(|a, b| a.start.total_cmp(&b.start));
        let det_tested = tested(&det.statistic);
        let ivs: Vec<Interval> = test_intervals(&det.alarm, Some(&det_tested))
            .into_iter()
            .map(|(iv, _)| iv)
            .collect();
        let mut m = CellMetrics::unscored(
            c.fault
                .is_none_or(|fi| rec.faults_applied.get(fi).copied().unwrap_or(true)),
        );
        if let Some(sr) = &rec.sats {
            if let Some(sm) = sr.metrics.iter().find(|m| m.fault == c.fault) {
                m.sat = *sm;
            }
        } else if !sub.reason.is_empty() {
            // A loosely coupled channel's exclusions, whatever their reason (the test, a held
            // step, a stale fix, a ramp), counted as satellite FDE counts them, the channel
            // being the one "satellite": epochs it measured (tested or left out), epochs it
            // was left out in each fault window, and outside them.
            let out_k = |k: usize| sub.reason.get(k).is_some_and(|r| *r != 0);
            let measured: Vec<bool> = (0..t.len()).map(|k| det_tested[k] || out_k(k)).collect();
            let excluded: Vec<bool> = (0..t.len()).map(out_k).collect();
            let fl: Vec<crate::metrics::SatFault> = spec
                .faults
                .iter()
                .enumerate()
                .filter(|(_, f)| channel.sees(f))
                .map(|(i, f)| (i, 0, f.start, f.end))
                .collect();
            let all = crate::metrics::satellite_metrics(t, &measured, &measured, &excluded, 1, &fl);
            if let Some(sm) = all.iter().find(|m| m.fault == c.fault) {
                m.sat = *sm;
            }
        }
        match c.fault {
            Some(fi) => {
                let f = &spec.faults[fi];
                let windows: Vec<(f64, f64)> = faults.iter().map(|g| (g.start, g.end)).collect();
                let me = faults.iter().position(|g| std::ptr::eq(*g, f));
                let matched: Vec<&Interval> = ivs
                    .iter()
                    .filter(|(s, _)| me.is_some() && match_interval(t[*s], &windows) == me)
                    .collect();
                if let (Some(first), Some(last)) = (matched.first(), matched.last()) {
                    m.detected = true;
                    m.delay = (t[first.0] - f.start).max(0.0);
                    m.clear_delay = last.1.map_or(f64::NAN, |e| t[e] - f.end);
                }
                (m.at_onset, m.alarm_fraction) =
                    window_alarm(t, &det.alarm, Some(&det_tested), (f.start, f.end));
            }
            None => {
                for (k, &tk) in t.iter().enumerate() {
                    let inside = faults.iter().any(|f| tk >= f.start && tk < f.end + SETTLE);
                    if !inside && det_tested[k] {
                        m.outside_epochs += 1;
                        if det.alarm[k] {
                            m.false_alarm_epochs += 1;
                        }
                    }
                }
                let isolating = channels[c.subfilter].decision == Some(det.name.as_str());
                if isolating {
                    let sub_tested: Vec<bool> = sub.dof.iter().map(|&d| d > 0).collect();
                    for ((s, e), _) in test_intervals(&sub.isolated, Some(&sub_tested)) {
                        let ts = t[s];
                        let te = e.map_or(f64::INFINITY, |e| t[e]);
                        if !faults.iter().any(|f| ts <= f.end && te > f.start) {
                            m.wrong_isolations += 1;
                        }
                    }
                }
            }
        }
        out.push(m);
    }
    if logged {
        return logged_errors(spec, run, rec, out);
    }
    let epochs = t.len().max(1) as f64;
    let (mut a2, mut amax, mut p2, mut pmax) = (0.0, 0.0f64, 0.0, 0.0f64);
    let (mut l2, mut lmax) = (0.0, 0.0f64);
    for row in rec.error.chunks(9) {
        l2 += row[7] * row[7];
        lmax = lmax.max(row[7].abs());
        for v in &row[0..3] {
            a2 += v * v;
            amax = amax.max(v.abs());
        }
        for v in &row[6..9] {
            p2 += v * v;
            pmax = pmax.max(v.abs());
        }
    }
    // NaN.max(x) = x: the maximum stays NaN only when no epoch had a fused altitude.
    let (mut f2, mut fmax, mut fn_) = (0.0, f64::NAN, 0usize);
    for v in rec.fused_alt.iter().filter(|v| v.is_finite()) {
        f2 += v * v;
        fmax = fmax.max(v.abs());
        fn_ += 1;
    }
    RunMetrics {
        run,
        cells: out,
        fused_alt_rms: if fn_ > 0 {
            (f2 / fn_ as f64).sqrt()
        } else {
            f64::NAN
        },
        fused_alt_max: fmax,
        att_rms: (a2 / (3.0 * epochs)).sqrt(),
        att_max: amax,
        pos_rms: (p2 / (3.0 * epochs)).sqrt(),
        pos_max: pmax,
        lat_rms: (l2 / epochs).sqrt(),
        lat_max: lmax,
        hor_rms: f64::NAN,
        hor_max: f64::NAN,
        fault_hor_max: f64::NAN,
        hor_rel_rms: f64::NAN,
        fault_hor_rel_max: f64::NAN,
        drawn: Vec::new(),
        integrity: integrity_metrics(rec),
        record: None,
        failed: None,
    }
}

/// Errors of a run on recorded logs, over the epochs its reference scores (finite errors).
fn logged_errors(
    spec: &ScenarioSpec,
    run: u64,
    rec: &RunRecord,
    cells: Vec<CellMetrics>,
) -> RunMetrics {
    let (mut n, mut p2, mut pmax, mut l2, mut lmax, mut h2, mut hmax) =
        (0usize, 0.0, 0.0f64, 0.0, 0.0f64, 0.0, 0.0f64);
    let mut fmax = f64::NAN;
    for (k, row) in rec.error.chunks(9).enumerate() {
        if !(row[6].is_finite() && row[7].is_finite() && row[8].is_finite()) {
            continue;
        }
        n += 1;
        l2 += row[7] * row[7];
        lmax = lmax.max(row[7].abs());
        for v in &row[6..9] {
            p2 += v * v;
            pmax = pmax.max(v.abs());
        }
        let h = row[6].hypot(row[7]);
        h2 += h * h;
        hmax = hmax.max(h);
        let tk = rec.t[k];
        if spec.faults.iter().any(|f| tk >= f.start && tk < f.end) {
            fmax = fmax.max(h);
        }
    }
    let nn = n.max(1) as f64;
    let none = |v: f64| if n == 0 { f64::NAN } else { v };
    // The run's mean horizontal offset outside the fault windows, and the errors without it.
    let in_fault = |k: usize| {
        spec.faults
            .iter()
            .any(|f| rec.t[k] >= f.start && rec.t[k] < f.end)
    };
    let scored = |row: &[f64]| row[6].is_finite() && row[7].is_finite() && row[8].is_finite();
    let (mut se, mut sn, mut m) = (0.0, 0.0, 0usize);
    for (k, row) in rec.error.chunks(9).enumerate() {
        if scored(row) && !in_fault(k) {
            se += row[6];
            sn += row[7];
            m += 1;
        }
    }
    let (oe, on) = if m > 0 {
        (se / m as f64, sn / m as f64)
    } else {
        (f64::NAN, f64::NAN)
    };
    let (mut r2, mut rmax) = (0.0, f64::NAN);
    for (k, row) in rec.error.chunks(9).enumerate() {
        if scored(row) {
            let h = (row[6] - oe).hypot(row[7] - on);
            r2 += h * h;
            if in_fault(k) {
                rmax = f64::max(rmax, h);
            }
        }
    }
    RunMetrics {
        run,
        cells,
        att_rms: f64::NAN,
        att_max: f64::NAN,
        pos_rms: none((p2 / (3.0 * nn)).sqrt()),
        pos_max: none(pmax),
        lat_rms: none((l2 / nn).sqrt()),
        lat_max: none(lmax),
        fused_alt_rms: f64::NAN,
        fused_alt_max: f64::NAN,
        hor_rms: none((h2 / nn).sqrt()),
        hor_max: none(hmax),
        fault_hor_max: fmax,
        hor_rel_rms: none((r2 / nn).sqrt()),
        fault_hor_rel_max: rmax,
        drawn: spec.faults.clone(),
        integrity: integrity_metrics(rec),
        record: None,
        failed: None,
    }
}

/// Runs `start..start + count` of a campaign on recorded logs: run `i` draws its faults from
/// `(seed, i)` ([`ScenarioSpec::drawn`]), injects them into the recorded measurements and runs
/// the architecture; on `threads` threads (0: rayon's default), in run order. The cells are
/// `spec`'s (drawn faults keep their ids). `datum`: what every run's errors are scored
/// against for its protection levels ([`logged_datum`] of `src` and `spec`, computed once by
/// the caller and reused for every chunk).
#[allow(clippy::too_many_arguments)]
pub fn run_logged_chunk(
    src: &crate::logs::LoggedSource,
    spec: &ScenarioSpec,
    datum: Option<[f64; 3]>,
    seed: u64,
    start: u64,
    count: u64,
    threads: usize,
    keep: &[u64],
    cancel: &Cancel,
) -> Result<Vec<RunMetrics>> {
    check_range(start, count)?;
    let cells = spec_cells(spec);
    let one = |i: u64| -> Result<RunMetrics> {
        cancel.check()?;
        let run_spec = spec.drawn(seed, i);
        // A run that fails is recorded as failed; the campaign goes on.
        let rec = match run_logged(src, &run_spec, seed, i, keep.contains(&i), cancel) {
            Ok(rec) => rec,
            Err(Error::Cancelled) => return Err(Error::Cancelled),
            Err(e @ Error::TooLarge(_)) => return Err(e),
            Err(e) => {
                let mut m = RunMetrics::failed(i, cells.len(), e.to_string());
                m.drawn = run_spec.faults.clone();
                return Ok(m);
            }
        };
        let rec = RunRecord { datum, ..rec };
        let mut m = metrics_of(&run_spec, i, &rec, &cells);
        if keep.contains(&i) {
            m.record = Some(rec);
        }
        Ok(m)
    };
    in_pool(threads, start, count, one)
}

/// The reference datum of a logged run with filter protection levels: the mean position error
/// (east, north, up, m) over the epochs with levels of `spec` run on `src` **without its
/// faults** — what the errors of the faulted runs are scored against
/// ([`integrity_metrics`]), so that a fault's own error, or what is left of it after the
/// fault window when nothing excludes it, does not move the datum. `None` when the scenario
/// has no faults or no `[tight.integrity]`, or no epoch has levels.
pub fn logged_datum(
    src: &crate::logs::LoggedSource,
    spec: &ScenarioSpec,
    cancel: &Cancel,
) -> Result<Option<[f64; 3]>> {
    let integrity = spec.tight.as_ref().is_some_and(|t| t.integrity.is_some());
    if !integrity || spec.faults.is_empty() {
        return Ok(None);
    }
    let mut clean = spec.clone();
    clean.faults.clear();
    let rec = run_logged(src, &clean, 0, 0, false, cancel)?;
    Ok(mean_position_error(&rec))
}

/// `spec` (its faults injected) on the recorded measurements of `src`, with isolation; the
/// noise stream `(seed, stream)`; `keep`: record every series.
fn run_logged(
    src: &crate::logs::LoggedSource,
    spec: &ScenarioSpec,
    seed: u64,
    stream: u64,
    keep: bool,
    cancel: &Cancel,
) -> Result<RunRecord> {
    let meas = src.measurements(spec);
    let streams = crate::stream::Streams {
        models: &src.models,
        meas: &meas,
        reference: Some(&src.reference),
        seed,
        stream,
    };
    run_architecture(spec, &streams, true, keep, cancel)
}

/// One run: simulate, filter with isolation, reduce.
pub fn one_run(
    prep: &Prepared,
    seed: u64,
    run: u64,
    cells: &[Cell],
    keep: bool,
    cancel: &Cancel,
) -> Result<RunMetrics> {
    cancel.check()?;
    let sim = simulate(prep, seed, run);
    // A run that fails is recorded as failed; the campaign goes on.
    let rec = match run_architecture(&prep.spec, &sim.streams(prep), true, keep, cancel) {
        Ok(rec) => rec,
        Err(Error::Cancelled) => return Err(Error::Cancelled),
        Err(e @ Error::TooLarge(_)) => return Err(e),
        Err(e) => return Ok(RunMetrics::failed(run, cells.len(), e.to_string())),
    };
    let mut m = metrics(prep, run, &rec, cells);
    if keep {
        m.record = Some(rec);
    }
    Ok(m)
}

/// Refuse a campaign whose per-run metric table (`runs × points × cells` rows of `row_bytes`
/// each, held by the caller) and kept series (`kept × points` full records) would not fit in
/// memory, before anything is prepared ([`crate::memory::check`]).
pub fn check_campaign_memory(
    spec: &ScenarioSpec,
    runs: f64,
    points: f64,
    kept: f64,
    row_bytes: f64,
) -> Result<()> {
    let cells = spec_cells(spec).len().max(1) as f64;
    let table = runs * points * cells * row_bytes;
    let series = kept * points * (spec.memory_estimate(1.0) - spec.memory_estimate(0.0));
    crate::memory::check(
        "montecarlo",
        table + series,
        &format!(
            "{runs} runs × {points} point(s) × {cells} metric cells = {} of per-run metrics, {kept} kept series × {points} point(s) = {}",
            crate::memory::human(table),
            crate::memory::human(series)
        ),
        "use fewer runs or sweep points, or keep fewer series",
    )
}

/// Runs `start..start + count` on `threads` threads (0: rayon's default), in run order. Runs
/// whose index is in `keep` also return their full record. The memory of the runs held at
/// once (one per thread, plus the kept records) is checked before anything runs; `cancel` is
/// checked every epoch of every run.
pub fn run_chunk(
    prep: &Prepared,
    seed: u64,
    start: u64,
    count: u64,
    threads: usize,
    keep: &[u64],
    cancel: &Cancel,
) -> Result<Vec<RunMetrics>> {
    check_range(start, count)?;
    let workers = if threads == 0 {
        rayon::current_num_threads()
    } else {
        threads
    };
    let kept = keep
        .iter()
        .filter(|&&k| k >= start && k < start + count)
        .count();
    let held = (workers.min(count as usize) + kept) as f64;
    let run_bytes = prep.spec.memory_estimate(held) - prep.spec.memory_estimate(0.0);
    crate::memory::check(
        "Monte-Carlo chunk",
        run_bytes,
        &format!(
            "{held} runs of {} epochs held at once ({kept} kept series)",
            prep.epochs()
        ),
        "keep fewer series, use fewer workers, or shorten the scenario",
    )?;
    let cells = cells(prep);
    in_pool(threads, start, count, |i| {
        one_run(prep, seed, i, &cells, keep.contains(&i), cancel)
    })
}

/// Refuse a chunk whose run indices would overflow.
fn check_range(start: u64, count: u64) -> Result<()> {
    if start.checked_add(count).is_none() {
        return Err(Error::Invalid(format!(
            "runs {start} + {count}: the run index would overflow"
        )));
    }
    Ok(())
}

/// Run `one` over `start..start + count` on `threads` threads (0: rayon's default pool), in
/// run order.
fn in_pool<F>(threads: usize, start: u64, count: u64, one: F) -> Result<Vec<RunMetrics>>
where
    F: Fn(u64) -> Result<RunMetrics> + Sync + Send,
{
    let work = || -> Result<Vec<RunMetrics>> {
        (start..start + count).into_par_iter().map(&one).collect()
    };
    if threads == 0 {
        return work();
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| {
            Error::Invalid(format!(
                "workers = {threads}: cannot start a thread pool: {e}"
            ))
        })?
        .install(work)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::{IntegrityRecord, RunRecord};

    /// A logged run's record: 100 epochs at 1 s, a constant reference datum offset of
    /// (6, −4, 2) m, plus `fault` m east inside [40, 80) s; levels HPL 3 m, VPL 4 m; `datum`
    /// as a fault-free pass would give it.
    fn logged(fault: f64, datum: Option<[f64; 3]>) -> RunRecord {
        let t: Vec<f64> = (0..100).map(f64::from).collect();
        let mut error = Vec::new();
        for &tk in &t {
            let f = if (40.0..80.0).contains(&tk) {
                fault
            } else {
                0.0
            };
            error.extend([0.0; 6]);
            error.extend([6.0 + f, -4.0, 2.0]);
        }
        RunRecord {
            t,
            error,
            nav: vec![0.0; 100],
            datum,
            integrity: Some(IntegrityRecord {
                hpl: vec![3.0; 100],
                vpl: vec![4.0; 100],
                hpl_snapshot: vec![30.0; 100],
                vpl_snapshot: vec![40.0; 100],
                statistic: vec![0.5; 100],
                alarm: vec![false; 100],
                modes: vec![10; 100],
            }),
            ..RunRecord::default()
        }
    }

    #[test]
    fn a_logged_run_is_scored_about_the_fault_free_datum() {
        // The fault's 10 m east error is misleading at its 40 epochs and nowhere else: the
        // datum is the fault-free pass's.
        let m = integrity_metrics(&logged(10.0, Some([6.0, -4.0, 2.0]))).unwrap();
        assert_eq!((m.epochs, m.mi_h, m.mi_v, m.hmi_h), (100, 40, 0, 40));
        assert!(
            (m.max_ratio_h - 10.0 / 3.0).abs() < 1e-12,
            "{}",
            m.max_ratio_h
        );
        // Taken from the faulted run itself (as before), the fault would move the datum 4 m
        // east and make the 60 clean epochs misleading too.
        let all = integrity_metrics(&logged(10.0, None)).unwrap();
        assert_eq!(all.mi_h, 100);
        // No fault (and so no datum carried): the run's own mean removed, nothing misleading.
        let clean = integrity_metrics(&logged(0.0, None)).unwrap();
        assert_eq!((clean.mi_h, clean.mi_v), (0, 0));
        assert!(clean.max_ratio_h < 1e-12 && clean.max_ratio_v < 1e-12);
    }
}
