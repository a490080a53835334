//! The pipelines a scenario file can name. Each reads its own `[params]`, runs with the
//! scenario's seeded generator, and returns metrics plus a report section.

use anyhow::Result;
use indicatif::ProgressBar;

use crate::scenario::{PipelineOutput, Scenario};

mod gdt;
mod hmm;
mod kalman;
mod mcmcda;
mod mot_eval;
mod mot_track;
mod phd;
mod simulator;

/// A pipeline: scenario in, metrics and report section out; ticks `progress` as it goes.
pub type PipelineFn = fn(&Scenario, &ProgressBar) -> Result<PipelineOutput>;

/// Every pipeline by name.
const PIPELINES: &[(&str, PipelineFn)] = &[
    ("gdt-gaps", gdt::run),
    ("hmm-tracking", hmm::run),
    ("kalman-crossing", kalman::run),
    ("mcmcda-batch", mcmcda::batch),
    ("mcmcda-online", mcmcda::online),
    ("mcmcda-sweep", mcmcda::sweep),
    ("mot-eval", mot_eval::run),
    ("mot-track", mot_track::run),
    ("phd-pedestrians", phd::run),
    ("simulator-poisson", simulator::run),
];

/// The pipeline called `name`.
pub fn find(name: &str) -> Option<PipelineFn> {
    PIPELINES.iter().find(|(n, _)| *n == name).map(|(_, f)| *f)
}

/// All pipeline names, for error messages.
pub fn names() -> Vec<&'static str> {
    PIPELINES.iter().map(|(n, _)| *n).collect()
}
