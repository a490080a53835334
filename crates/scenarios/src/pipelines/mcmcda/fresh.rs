//! The fresh scenarios of `mcmcda-batch` and `mcmcda-sweep`: `runs` more per setting, drawn
//! from `fresh_seed` (generated once after GNN's tuning and the reported results were
//! frozen, never used for a choice). Every claim is made there: per setting (and model
//! variant), MCMCDA against the tuned GNN by a paired 95 % t interval of F1 and of GOSPA,
//! against a margin of 0, each verdict recorded from the first run (`fresh_verdicts`).

use std::collections::BTreeMap;

use anyhow::{Result, bail};

use super::RunScores;
use crate::pipelines::mot_realistic::verdict_claim;
use crate::stats::{Paired, Verdict};
use crate::{Claim, Metrics, Table};

/// One setting's fresh runs under one model variant: MCMCDA's and GNN's F1 and GOSPA per run.
pub(crate) struct FreshGroup {
    /// The setting in words ("K = 10, true model").
    pub label: String,
    /// The setting in verdict and metric keys ("k10_truth").
    pub key: String,
    /// Per run: MCMCDA's and GNN's F1.
    pub f1: [Vec<f64>; 2],
    /// Per run: MCMCDA's and GNN's GOSPA.
    pub gospa: [Vec<f64>; 2],
}

impl FreshGroup {
    /// Variant `v` of the runs `group` ([`RunScores`]), labelled.
    pub(crate) fn of(label: String, key: String, group: &[RunScores], v: usize) -> Self {
        let pick = |f: fn(&super::Scores) -> f64, mcmcda: bool| -> Vec<f64> {
            group
                .iter()
                .map(|r| f(if mcmcda { &r.mcmcda[v] } else { &r.gnn[v] }))
                .collect()
        };
        Self {
            label,
            key,
            f1: [pick(|s| s.f1, true), pick(|s| s.f1, false)],
            gospa: [pick(|s| s.gospa, true), pick(|s| s.gospa, false)],
        }
    }

    /// Its two comparisons: (key, statement, paired interval, higher is better for ours).
    fn comparisons(&self) -> [(String, String, Paired); 2] {
        let neg = |v: &[f64]| v.iter().map(|x| -x).collect::<Vec<_>>();
        [
            (
                format!("{}_f1", self.key),
                format!("{}: MCMCDA's F1 ≥ the tuned GNN's", self.label),
                Paired::of(&self.f1[0], &self.f1[1]),
            ),
            (
                format!("{}_gospa", self.key),
                format!("{}: MCMCDA's GOSPA ≤ the tuned GNN's", self.label),
                // GOSPA negated: the interval is of GNN's GOSPA − MCMCDA's.
                Paired::of(&neg(&self.gospa[0]), &neg(&self.gospa[1])),
            ),
        ]
    }
}

/// Every recorded verdict names a comparison of `groups`.
pub(crate) fn check_verdicts(
    groups_keys: &[String],
    verdicts: &BTreeMap<String, Verdict>,
) -> Result<()> {
    let keys: Vec<String> = groups_keys
        .iter()
        .flat_map(|k| [format!("{k}_f1"), format!("{k}_gospa")])
        .collect();
    if let Some(k) = verdicts.keys().find(|k| !keys.contains(k)) {
        bail!("fresh_verdicts names {k:?}, which is no comparison");
    }
    Ok(())
}

/// Each comparison's claim: its verdict on the fresh runs is the recorded one.
pub(crate) fn claims(
    groups: &[FreshGroup],
    verdicts: &BTreeMap<String, Verdict>,
    fresh_seed: u64,
) -> Vec<Claim> {
    groups
        .iter()
        .flat_map(|g| {
            let n = g.f1[0].len();
            g.comparisons().map(|(key, statement, paired)| {
                let fresh = format!("the {n} fresh scenarios (seed {fresh_seed})");
                verdict_claim(
                    &statement,
                    &fresh,
                    &paired,
                    0.0,
                    verdicts.get(&key).copied(),
                )
            })
        })
        .collect()
}

/// Each comparison's interval as metrics `fresh_<key>_{diff,low,high}`, and the verdicts'
/// tally (`fresh_holds`, `fresh_undecided`, `fresh_loses`).
pub(crate) fn metrics(groups: &[FreshGroup], m: &mut Metrics) {
    for g in groups {
        for (key, _, p) in g.comparisons() {
            m.insert(format!("fresh_{key}_diff"), p.mean);
            m.insert(format!("fresh_{key}_low"), p.low);
            m.insert(format!("fresh_{key}_high"), p.high);
        }
    }
    let [h, u, l] = tally(groups);
    m.insert("fresh_holds".into(), h as f64);
    m.insert("fresh_undecided".into(), u as f64);
    m.insert("fresh_loses".into(), l as f64);
}

/// The verdicts' tally over `groups`: (holds, undecided, loses).
pub(crate) fn tally(groups: &[FreshGroup]) -> [usize; 3] {
    let mut n = [0; 3];
    for g in groups {
        for (_, _, p) in g.comparisons() {
            n[match Verdict::of(&p, 0.0) {
                Verdict::Holds => 0,
                Verdict::Undecided => 1,
                Verdict::Loses => 2,
            }] += 1;
        }
    }
    n
}

/// Every comparison: the paired difference and interval, the verdict and the recorded one.
pub(crate) fn table(
    groups: &[FreshGroup],
    verdicts: &BTreeMap<String, Verdict>,
    fresh_seed: u64,
) -> Table {
    let [holds, undecided, loses] = tally(groups);
    let mut t = Table::new(
        &format!(
            "Fresh scenarios (seed {fresh_seed}; never used to choose anything): MCMCDA − tuned \
             GNN per scenario (GOSPA negated so that higher is better), mean [95 % paired t \
             interval]; {holds} hold, {undecided} undecided, {loses} lose"
        ),
        &[
            "comparison",
            "scenarios",
            "difference",
            "verdict",
            "recorded",
        ],
    );
    for g in groups {
        for (key, statement, p) in g.comparisons() {
            t.row(vec![
                statement,
                g.f1[0].len().to_string(),
                p.show(),
                Verdict::of(&p, 0.0).name().into(),
                verdicts.get(&key).map_or("—", |v| v.name()).into(),
            ]);
        }
    }
    t
}

/// "3 hold, 1 undecided, 0 lose" for a summary.
pub(crate) fn tally_text(groups: &[FreshGroup]) -> String {
    let [h, u, l] = tally(groups);
    format!("{h} hold, {u} undecided, {l} lose")
}
