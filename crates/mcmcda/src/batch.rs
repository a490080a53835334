//! Batch multi-scan MCMCDA over a whole problem in one call: the greedy nearest-neighbour
//! start of Oh, Russell & Sastry 2009 §V, then independent chains of Algorithm 3.

use serde::{Deserialize, Serialize};

use crate::config::Model;
use crate::error::{Result, ensure_chains, ensure_samples};
use crate::nearest::greedy_initial_partition;
use crate::problem::Problem;
use crate::sampler::{McmcdaRun, run_chains};

/// Settings of a batch run ([`batch_mcmcda`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BatchConfig {
    /// Independent chains, run in parallel; the MAP is the best over all of them
    /// (default 1).
    pub chains: usize,
    /// MCMC steps per chain (default 50,000, as in the batch experiments of Oh, Russell &
    /// Sastry 2009).
    pub samples: u64,
    /// Seed of the generators: chain i draws from ChaCha8(seed) stream i, so the result does
    /// not depend on the thread count (default 0).
    pub seed: u64,
}

impl Default for BatchConfig {
    fn default() -> Self {
        Self {
            chains: 1,
            samples: 50_000,
            seed: 0,
        }
    }
}

impl BatchConfig {
    /// Checks the chain count (1 to [`crate::MAX_CHAINS`]) and the steps per chain (at most
    /// [`crate::MAX_SAMPLES`]). [`batch_mcmcda`] calls this.
    pub fn check(&self) -> Result<()> {
        ensure_chains(self.chains)?;
        ensure_samples(self.samples, "samples")
    }
}

/// Multi-scan MCMCDA over every scan of `problem`: the chains start from the greedy
/// nearest-neighbour partition ([`greedy_initial_partition`]) and the result is their MAP
/// ([`run_chains`]). Fails on a problem without scans ([`crate::Error::EmptyProblem`]).
pub fn batch_mcmcda(model: &Model, problem: &Problem, config: &BatchConfig) -> Result<McmcdaRun> {
    config.check()?;
    let start = greedy_initial_partition(model, problem, problem.all_scans()?)?;
    run_chains(&start, config.chains, config.samples, config.seed)
}
