//! The developer searches behind the scenario's settings (never run by the suite), started
//! by developer options that `cargo xtask scenarios` reads from environment variables of the
//! same names; their lines go to the developer as they are measured. All run on their own
//! tuning seeds; the reported seed is only simulated by the normal run.

use anyhow::Result;
use av_fusion::scene::{Params, RunSpec};
use av_fusion::tuning;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::Developer;
use crate::seeds::check_disjoint;

/// `AV_FUSION_TUNE=1`: the single-vehicle grid search of `[params.tuning]`
/// (`av_fusion::tuning::tune`), each line as it is measured and then the whole table.
const TUNE_ENV: &str = "AV_FUSION_TUNE";

/// `AV_FUSION_FIT_SCORES=<approaches>` (`all`, or comma-separated approach indices or keys
/// such as `5,audio_product`; `av_fusion::tuning::approaches_in`): learns the peak-score
/// tables of `[params.multi_peak_scores]` with `[params.score_fit]` and prints them as TOML.
/// The tables are fitted with the multi-vehicle settings as configured, and the search of
/// `AV_FUSION_TUNE_MULTI` uses the tables as configured (not those just printed): fit, paste,
/// search, paste, and fit again until neither moves.
const FIT_SCORES_ENV: &str = "AV_FUSION_FIT_SCORES";

/// `AV_FUSION_TUNE_MULTI=<approaches>` (as for `AV_FUSION_FIT_SCORES`): the coordinate search of
/// `[params.multi_tuning]` behind `[params.multi_settings]`.
const TUNE_MULTI_ENV: &str = "AV_FUSION_TUNE_MULTI";

/// `AV_FUSION_DIAG=1,2,3`: where the multi-vehicle runs' MOTA errors come from, on these seeds.
const DIAG_ENV: &str = "AV_FUSION_DIAG";

/// Runs the developer tools the developer asked for, in the order above, before the
/// reported runs (which they do not change). The diagnostics refuse the reported `seed`, as
/// the searches' seed lists are refused by `av_fusion::scene::check_params`.
pub(super) fn run_tools(
    dev: &dyn Developer,
    p: &Params,
    runs: &[RunSpec],
    seed: u64,
) -> Result<()> {
    let log = |text: &str| dev.say(text);
    if dev.option(TUNE_ENV).is_some() {
        let table = tuning::tune(p, runs, &seeded(&p.tuning.seeds), &log)?;
        dev.say(&table);
    }
    if let Some(which) = dev.option(FIT_SCORES_ENV) {
        let which = tuning::approaches_in(&which)?;
        tuning::fit_peak_scores(p, runs, &seeded(&p.score_fit.seeds), &which, &log)?;
    }
    if let Some(which) = dev.option(TUNE_MULTI_ENV) {
        let which = tuning::approaches_in(&which)?;
        tuning::tune_multi(p, runs, &seeded(&p.multi_tuning.seeds), &which, &log)?;
    }
    if let Some(seeds) = dev.option(DIAG_ENV) {
        let seeds: Vec<u64> = seeds
            .split(',')
            .filter_map(|s| s.trim().parse().ok())
            .collect();
        check_disjoint(&[("diagnostic", &seeds), ("reported", &[seed])])?;
        tuning::diagnose(p, runs, &seeded(&seeds), &log)?;
    }
    Ok(())
}

/// Each seed with its generator, as the scenario seeds the reported runs' generator.
fn seeded(seeds: &[u64]) -> Vec<(u64, ChaCha8Rng)> {
    seeds
        .iter()
        .map(|&seed| (seed, ChaCha8Rng::seed_from_u64(seed)))
        .collect()
}
