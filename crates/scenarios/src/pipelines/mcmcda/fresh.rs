//! The fresh scenarios of `mcmcda-batch` and `mcmcda-sweep`: `runs` more per setting, drawn
//! from `fresh_seed` (generated once after GNN's tuning and the reported results were
//! frozen, never used for a choice). Every claim is made there: per setting (and model
//! variant), MCMCDA against the tuned GNN by a paired 95 % t interval of F1 and of GOSPA
//! ([`crate::fresh`]).

use std::collections::BTreeMap;

use super::{RunScores, Scores};
use crate::Table;
use crate::fresh::{self, Comparison, negated};
use crate::stats::Verdict;

/// Variant `v` of one setting's fresh runs `group`: MCMCDA's F1 and GOSPA against the tuned
/// GNN's, keyed `<key>_f1` and `<key>_gospa` and stated for `label` ("K = 10, true model").
pub(crate) fn comparisons(
    label: &str,
    key: &str,
    group: &[RunScores],
    v: usize,
) -> [Comparison; 2] {
    let pick = |f: fn(&Scores) -> f64, mcmcda: bool| -> Vec<f64> {
        group
            .iter()
            .map(|r| f(if mcmcda { &r.mcmcda[v] } else { &r.gnn[v] }))
            .collect()
    };
    [
        Comparison {
            key: format!("{key}_f1"),
            statement: format!("{label}: MCMCDA's F1 ≥ the tuned GNN's"),
            units: "scenarios",
            ours: pick(|s| s.f1, true),
            theirs: pick(|s| s.f1, false),
        },
        Comparison {
            key: format!("{key}_gospa"),
            statement: format!("{label}: MCMCDA's GOSPA ≤ the tuned GNN's"),
            units: "scenarios",
            ours: negated(&pick(|s| s.gospa, true)),
            theirs: negated(&pick(|s| s.gospa, false)),
        },
    ]
}

/// The fresh comparisons' table of an experiment whose fresh scenarios come from `seed`.
pub(crate) fn table(
    comparisons: &[Comparison],
    verdicts: &BTreeMap<String, Verdict>,
    seed: u64,
) -> Table {
    fresh::table(
        &format!(
            "Fresh scenarios (seed {seed}; never used to choose anything): MCMCDA − tuned GNN \
             per scenario (GOSPA negated so that higher is better)"
        ),
        comparisons,
        verdicts,
    )
}
