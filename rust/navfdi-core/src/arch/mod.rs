//! One epoch loop per integration architecture, one file each. Each drives its filters,
//! detectors and fault-handling policy over one run's measurement streams
//! ([`crate::stream::Streams`]: whatever source produced them) and fills the same
//! [`crate::record::RunRecord`] (one channel per tested sensor), so metrics, Monte-Carlo,
//! outputs and plots serve every architecture. No architecture imports the simulator.
//!
//! This module is the dispatcher above them: [`run_architecture`] picks the loop the scenario
//! names. Shared helpers are in [`common`].

pub mod centralized;
pub mod common;
pub mod federated;
pub mod inertial;
pub mod loosely_coupled;
pub mod tight;
pub mod tight_ins;
mod tight_ins_pl;
pub mod ultra_tight;

use crate::cancel::Cancel;
use crate::error::Result;
use crate::record::RunRecord;
use crate::spec::{Architecture, ScenarioSpec};
use crate::stream::Streams;

/// Run the architecture of scenario `spec` over one run's streams (`isolation = false`:
/// detectors report but never act). `full`: record everything, including quantities only
/// figures and time series use (the MDB); Monte-Carlo runs that keep no series pass false.
pub fn run_architecture(
    spec: &ScenarioSpec,
    src: &Streams,
    isolation: bool,
    full: bool,
    cancel: &Cancel,
) -> Result<RunRecord> {
    match spec.architecture {
        Architecture::Federated => {
            let isolate = spec.federated.as_ref().is_none_or(|f| f.isolate);
            federated::run_federated(spec, src, isolation && isolate, cancel)
        }
        Architecture::Centralized => {
            let isolate = spec.centralized.as_ref().is_none_or(|c| c.isolate);
            centralized::run_centralized(spec, src, isolation && isolate, full, cancel)
        }
        Architecture::Tight if spec.runs_on_logs() => {
            tight_ins::run_tight_ins(spec, src, isolation, full, cancel)
        }
        Architecture::Tight => tight::run_tight(spec, src, isolation, full, cancel),
        Architecture::UltraTight => {
            ultra_tight::run_ultra_tight(spec, src, isolation, full, cancel)
        }
        Architecture::LooselyCoupled => {
            let isolate = spec.loosely_coupled.as_ref().is_none_or(|l| l.isolate);
            loosely_coupled::run_loosely_coupled(spec, src, isolation && isolate, cancel)
        }
    }
}

/// Run every scenario of `specs` over the same streams, everything recorded (`isolation` as
/// in [`run_architecture`]): the variants of one run. Only the filter may differ from `base`,
/// which made the streams; each is checked by [`ScenarioSpec::check_variant`] before any runs.
/// `then` finishes each record (e.g. a logged run's datum). The variants run in parallel on
/// rayon's pool; each is the same computation as alone, so the records (returned in `specs`'
/// order) are the same to the bit whatever the number of threads. With several failures, the
/// error of the first failing variant in order is returned.
pub fn run_variants<F>(
    base: &ScenarioSpec,
    specs: &[ScenarioSpec],
    src: &Streams,
    isolation: bool,
    cancel: &Cancel,
    then: F,
) -> Result<Vec<RunRecord>>
where
    F: Fn(&ScenarioSpec, RunRecord) -> Result<RunRecord> + Sync,
{
    use rayon::prelude::*;
    for s in specs {
        base.check_variant(s)?;
    }
    let each: Vec<Result<RunRecord>> = specs
        .par_iter()
        .map(|s| then(s, run_architecture(s, src, isolation, true, cancel)?))
        .collect();
    each.into_iter().collect()
}
