//! The developer tools behind the scenario's peak-score tables and its diagnostics (never run
//! by the suite), started by developer options that `cargo xtask scenarios` reads from
//! environment variables of the same names; their lines go to the developer as they are
//! measured. All run on seeds other than the reported one. The one configuration's search is
//! `cargo xtask tune av-fusion-road`.

use anyhow::Result;
use av_fusion::scene::{Params, RunSpec, Settings};
use av_fusion::tuning;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::Developer;
use crate::seeds::check_disjoint;

/// `AV_FUSION_FIT_SCORES=<approaches>` (`all`, or comma-separated approach indices or keys
/// such as `5,audio_product`; `av_fusion::tuning::approaches_in`): learns the peak-score
/// tables of `[params.scene.multi_peak_scores]` with `[params.scene.score_fit]` and prints
/// them as TOML.
const FIT_SCORES_ENV: &str = "AV_FUSION_FIT_SCORES";

/// `AV_FUSION_DIAG=1,2,3`: where the multi-vehicle runs' MOTA errors come from under the one
/// configuration, on these seeds.
const DIAG_ENV: &str = "AV_FUSION_DIAG";

/// Runs the developer tools the developer asked for, in the order above, before the
/// reported runs (which they do not change). The diagnostics refuse the reported `seed` and
/// the fresh seeds, as the fit's seeds are refused by `av_fusion::scene::check_params`.
pub(super) fn run_tools(
    dev: &dyn Developer,
    p: &Params,
    one: &Settings,
    runs: &[RunSpec],
    seed: u64,
) -> Result<()> {
    let log = |text: &str| dev.say(text);
    if let Some(which) = dev.option(FIT_SCORES_ENV) {
        let which = tuning::approaches_in(&which)?;
        tuning::fit_peak_scores(p, runs, &seeded(&p.score_fit.seeds), &which, &log)?;
    }
    if let Some(seeds) = dev.option(DIAG_ENV) {
        let seeds: Vec<u64> = seeds
            .split(',')
            .filter_map(|s| s.trim().parse().ok())
            .collect();
        check_disjoint(&[
            ("diagnostic", &seeds),
            ("reported", &[seed]),
            ("fresh", &p.fresh_seeds),
        ])?;
        tuning::diagnose(p, one, runs, &seeded(&seeds), &log)?;
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
