//! Claims on fresh seeds (docs/seeds.md): a scenario compares two computed quantities per
//! fresh unit (a run, a pass, a scenario) by a paired 95 % Student-t interval against a margin
//! of 0 fixed before the fresh runs; the verdict of their first run is recorded in the scenario
//! file (`fresh_verdicts`), and the claim is that it stays the same. One shape for every
//! scenario: [`Comparison`], and the claims, metrics, tally and table of a list of them.

use std::collections::BTreeMap;

use anyhow::{Result, bail};

use crate::pipelines::mot_realistic::verdict_claim;
use crate::stats::{Paired, Verdict};
use crate::{Claim, Metrics, Table};

/// One comparison on the fresh units: "ours ≥ theirs", unit by unit (a quantity where lower is
/// better is negated on both sides).
pub(crate) struct Comparison {
    /// The key of its recorded verdict and of its metrics.
    pub key: String,
    /// What is claimed.
    pub statement: String,
    /// The units compared, plural ("passes", "scenarios").
    pub units: &'static str,
    /// Per unit: ours, theirs (higher is better).
    pub ours: Vec<f64>,
    pub theirs: Vec<f64>,
}

impl Comparison {
    /// The paired interval of ours − theirs.
    pub(crate) fn paired(&self) -> Paired {
        Paired::of(&self.ours, &self.theirs)
    }

    /// Its verdict against margin 0.
    pub(crate) fn verdict(&self) -> Verdict {
        Verdict::of(&self.paired(), 0.0)
    }
}

/// `values` negated, for a quantity where lower is better.
pub(crate) fn negated(values: &[f64]) -> Vec<f64> {
    values.iter().map(|x| -x).collect()
}

/// Every recorded verdict names one of `comparisons` (one without a record fails its claim).
pub(crate) fn check_verdicts(
    comparisons: &[Comparison],
    verdicts: &BTreeMap<String, Verdict>,
) -> Result<()> {
    if let Some(k) = verdicts
        .keys()
        .find(|k| !comparisons.iter().any(|c| &c.key == *k))
    {
        bail!("fresh_verdicts names {k:?}, which is no comparison");
    }
    Ok(())
}

/// Each comparison's claim: its verdict on the fresh units (`seeds`, e.g. "seed 72009") is
/// the recorded one.
pub(crate) fn claims(
    comparisons: &[Comparison],
    verdicts: &BTreeMap<String, Verdict>,
    seeds: &str,
) -> Vec<Claim> {
    comparisons
        .iter()
        .map(|c| {
            let fresh = format!("the {} fresh {} ({seeds})", c.ours.len(), c.units);
            verdict_claim(
                &c.statement,
                &fresh,
                &c.paired(),
                0.0,
                verdicts.get(&c.key).copied(),
            )
        })
        .collect()
}

/// The verdicts' tally: (holds, undecided, loses).
pub(crate) fn tally(comparisons: &[Comparison]) -> [usize; 3] {
    let mut n = [0; 3];
    for c in comparisons {
        n[match c.verdict() {
            Verdict::Holds => 0,
            Verdict::Undecided => 1,
            Verdict::Loses => 2,
        }] += 1;
    }
    n
}

/// "11 hold, 5 undecided, 0 lose".
pub(crate) fn tally_text(comparisons: &[Comparison]) -> String {
    let [h, u, l] = tally(comparisons);
    format!("{h} hold, {u} undecided, {l} lose")
}

/// Each comparison's interval as metrics `fresh_<key>_{diff,low,high}`, and the tally
/// (`fresh_holds`, `fresh_undecided`, `fresh_loses`).
pub(crate) fn metrics(comparisons: &[Comparison], m: &mut Metrics) {
    for c in comparisons {
        let p = c.paired();
        m.insert(format!("fresh_{}_diff", c.key), p.mean);
        m.insert(format!("fresh_{}_low", c.key), p.low);
        m.insert(format!("fresh_{}_high", c.key), p.high);
    }
    let [h, u, l] = tally(comparisons);
    m.insert("fresh_holds".into(), h as f64);
    m.insert("fresh_undecided".into(), u as f64);
    m.insert("fresh_loses".into(), l as f64);
}

/// Every comparison, titled `title` (with the tally appended): its units, the paired
/// difference and interval, the verdict and the recorded one.
pub(crate) fn table(
    title: &str,
    comparisons: &[Comparison],
    verdicts: &BTreeMap<String, Verdict>,
) -> Table {
    let mut t = Table::new(
        &format!(
            "{title}; mean [95 % paired t interval], holds when the interval lies above 0, \
             loses when below, else undecided: {}",
            tally_text(comparisons)
        ),
        &["comparison", "units", "difference", "verdict", "recorded"],
    );
    for c in comparisons {
        t.row(vec![
            c.statement.clone(),
            format!("{} {}", c.ours.len(), c.units),
            c.paired().show(),
            c.verdict().name().into(),
            verdicts.get(&c.key).map_or("—", |v| v.name()).into(),
        ]);
    }
    t
}
