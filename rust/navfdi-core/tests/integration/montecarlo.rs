//! Monte-Carlo determinism: results depend only on (seed, run index).

use navfdi_core::cancel::NEVER;
use navfdi_core::montecarlo::{cells, run_chunk, RunMetrics};
use navfdi_core::sim::prepare::Prepared;
use navfdi_core::spec::ScenarioSpec;

fn prep() -> Prepared {
    let mut spec =
        ScenarioSpec::from_json(include_str!("../../../../benches/yang2013.json")).unwrap();
    spec.duration = 200.0; // shorter runs for the test; faults moved inside
    spec.faults[0].start = 50.0;
    spec.faults[0].end = 100.0;
    spec.faults[1].start = 150.0;
    spec.faults[1].end = 160.0;
    Prepared::new(spec).unwrap()
}

fn bits(v: &[RunMetrics]) -> Vec<u64> {
    v.iter()
        .flat_map(|m| {
            let mut b = vec![
                m.run,
                m.att_rms.to_bits(),
                m.att_max.to_bits(),
                m.pos_rms.to_bits(),
                m.pos_max.to_bits(),
            ];
            for c in &m.cells {
                b.extend([
                    c.detected as u64,
                    c.delay.to_bits(),
                    c.clear_delay.to_bits(),
                    c.false_alarm_epochs as u64,
                    c.outside_epochs as u64,
                    c.wrong_isolations as u64,
                ]);
            }
            b
        })
        .collect()
}

#[test]
fn identical_across_threads_and_chunking() {
    let p = prep();
    let one = run_chunk(&p, 7, 0, 8, 1, &[], &NEVER).unwrap();
    let two = run_chunk(&p, 7, 0, 8, 2, &[], &NEVER).unwrap();
    let mut chunked = run_chunk(&p, 7, 0, 3, 2, &[], &NEVER).unwrap();
    chunked.extend(run_chunk(&p, 7, 3, 5, 1, &[], &NEVER).unwrap());
    assert_eq!(bits(&one), bits(&two));
    assert_eq!(bits(&one), bits(&chunked));
    assert_eq!(
        one.iter().map(|m| m.run).collect::<Vec<_>>(),
        (0..8).collect::<Vec<_>>()
    );
    // Different seeds give different runs.
    let other = run_chunk(&p, 8, 0, 8, 2, &[], &NEVER).unwrap();
    assert_ne!(bits(&one), bits(&other));
}

#[test]
fn cells_cover_faults_and_outside() {
    let p = prep();
    let c = cells(&p);
    // CNS: 3 detectors × (2 faults + none); GNSS: 1 detector × none.
    assert_eq!(c.len(), 3 * 3 + 1);
    let m = run_chunk(&p, 1, 0, 2, 1, &[1], &NEVER).unwrap();
    assert!(m[0].record.is_none() && m[1].record.is_some());
    // The step (20 σ) is found by the joint detector (cells: [ramp, step, none] per detector).
    let joint_step = &m[0].cells[2 * 3 + 1];
    assert!(joint_step.detected && joint_step.delay <= 1.0);
    // The SPRT without reset misses it (still in alarm from the ramp).
    assert!(!m[0].cells[3 + 1].detected);
    let none = &m[0].cells[2];
    assert!(none.outside_epochs > 0 && none.outside_epochs < 200);
}
