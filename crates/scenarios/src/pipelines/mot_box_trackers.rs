//! `mot-box-trackers`: the comparison users ask for. SORT, ByteTrack and OC-SORT (the
//! `box-trackers` crate, equal to roboflow `trackers`) beside our online MCMCDA, online GNN,
//! PHD tracker, and offline GNN and MCMCDA, on realistic pedestrian detection files
//! ([`mot::walkers`]).
//!
//! The box trackers' settings come from `fixtures/tuned/mot-box-trackers.toml`, which
//! [`MotBoxTrackers::tune`] (`cargo xtask tune mot-box-trackers`) writes from mot-realistic's
//! tuning sequences, exactly as ours were tuned (`fixtures/tuned/mot-realistic.toml`). They
//! also run at the reference's defaults, for the effect of tuning. The scored sequences were
//! generated once, with seeds never used before, after both searches were frozen; every
//! comparison of an online tracker of ours with a box tracker is judged there by a paired 95 %
//! interval, with the verdict of the first run recorded.

use std::collections::BTreeMap;

use anyhow::{Context, Result, bail};
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;

use super::mot_realistic::{
    Measure, SequenceSpec, SetScores, Tuning, pm, score_set, search, verdict_claim,
};
use crate::seeds::check_disjoint;
use crate::stats::{Paired, Verdict, mean_ci};
use crate::tune::Tuned;
use crate::{
    BAR_WIDTH, Chart, Claim, Env, Figure, Headline, Metrics, Pipeline, Section, Series, Style,
    Table, fmt_num,
};
use mot::track::{TrackConfig, TrackerKind};

/// The `mot-box-trackers` pipeline.
pub struct MotBoxTrackers;

/// Its parameters.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Every tracker, ours and the box trackers.
    trackers: Vec<TrackerKind>,
    /// Our trackers' settings (mot-realistic's search).
    ours_tuned: String,
    /// The box trackers' settings, which this scenario's search writes.
    tuned: String,
    /// That search.
    tuning: Tuning,
    /// The scored sequences.
    sequences: Vec<SequenceSpec>,
    /// The verdict of every comparison on them, recorded from their first run.
    fresh_verdicts: BTreeMap<String, Verdict>,
}

/// Our online trackers, each compared with each box tracker.
const OURS: [TrackerKind; 3] = [
    TrackerKind::McmcdaOnline,
    TrackerKind::GnnOnline,
    TrackerKind::Phd,
];
const BOX: [TrackerKind; 3] = [
    TrackerKind::Sort,
    TrackerKind::ByteTrack,
    TrackerKind::OcSort,
];
const MEASURES: [Measure; 3] = [Measure::Mota, Measure::Idf1, Measure::Hota];

/// "ours's measure ≥ the box tracker's", margin 0, fixed before the sequences ran.
#[derive(Debug, Clone, Copy)]
struct Comparison {
    ours: TrackerKind,
    theirs: TrackerKind,
    measure: Measure,
}

impl Comparison {
    fn all() -> impl Iterator<Item = Comparison> {
        OURS.into_iter().flat_map(|ours| {
            BOX.into_iter().flat_map(move |theirs| {
                MEASURES.into_iter().map(move |measure| Comparison {
                    ours,
                    theirs,
                    measure,
                })
            })
        })
    }

    fn key(&self) -> String {
        format!(
            "{}_{}_ge_{}",
            self.ours.name().replace('-', "_"),
            self.measure.name().to_lowercase(),
            self.theirs.name()
        )
    }

    fn statement(&self) -> String {
        format!(
            "{}'s {} ≥ tuned {}'s",
            self.ours,
            self.measure.name(),
            self.theirs
        )
    }

    fn paired(&self, set: &SetScores) -> Paired {
        Paired::of(
            &set.ours(self.ours, self.measure),
            &set.ours(self.theirs, self.measure),
        )
    }
}

/// The scored runs: every tracker with the tuned settings, and the box trackers at the
/// reference's defaults.
pub struct Output {
    params: Params,
    tuned: SetScores,
    defaults: SetScores,
}

/// The tuning and the scored seeds apart, and at least 12 scored sequences.
fn check_seeds(p: &Params) -> Result<()> {
    let seeds = |specs: &[SequenceSpec]| specs.iter().map(|s| s.seed).collect::<Vec<_>>();
    check_disjoint(&[
        ("tuning", &seeds(&p.tuning.sequences)),
        ("scored", &seeds(&p.sequences)),
    ])?;
    if p.sequences.len() < 12 {
        bail!("the comparison needs at least 12 scored sequences");
    }
    Ok(())
}

/// Before the scored runs: the seeds, the compared trackers, a verdict for every comparison.
fn check(p: &Params) -> Result<()> {
    check_seeds(p)?;
    for t in OURS.iter().chain(&BOX) {
        if !p.trackers.contains(t) {
            bail!("the comparisons need the tracker {t}");
        }
    }
    let keys: Vec<String> = Comparison::all().map(|c| c.key()).collect();
    if let Some(k) = keys.iter().find(|k| !p.fresh_verdicts.contains_key(*k)) {
        bail!("fresh_verdicts has no verdict for {k:?}");
    }
    if let Some(k) = p.fresh_verdicts.keys().find(|k| !keys.contains(k)) {
        bail!("fresh_verdicts names {k:?}, which is no comparison");
    }
    Ok(())
}

/// Our tuned settings and the box trackers' in one configuration (their tables are apart).
fn config(p: &Params, env: &Env<'_>) -> Result<TrackConfig> {
    let mut table = toml::Table::new();
    for path in [&p.ours_tuned, &p.tuned] {
        let text = env.inputs.read_to_string(path)?;
        let part: toml::Table = toml::from_str(&text).with_context(|| format!("reading {path}"))?;
        if let Some(key) = part.keys().find(|k| table.contains_key(*k)) {
            bail!("{path} sets [{key}], which another settings file sets too");
        }
        table.extend(part);
    }
    toml::Value::Table(table)
        .try_into()
        .context("the settings are not a `cargo xtask track --config` file")
}

fn tuned_header(p: &Params) -> String {
    let seeds: Vec<String> = p
        .tuning
        .sequences
        .iter()
        .map(|s| s.seed.to_string())
        .collect();
    format!(
        "Written by `cargo xtask tune mot-box-trackers`: do not edit. The coordinate search\n\
         of [params.tuning] in fixtures/scenarios/mot-box-trackers.toml for SORT, ByteTrack\n\
         and OC-SORT, on mot-realistic's tuning sequences only (seeds {}), each setting\n\
         scored by the mean MOTA over them of the tracker it changes; every candidate's\n\
         score is in the grid CSV beside this file. A `cargo xtask track --config` file.",
        seeds.join(", ")
    )
}

impl Pipeline for MotBoxTrackers {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, _: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        check(p)?;
        let config = config(p, env)?;
        let n = p.sequences.len() * (p.trackers.len() + BOX.len());
        env.progress.set_length(n as u64);
        let tuned = score_set("tuned", &p.sequences, &p.trackers, &config, env)?;
        let defaults = score_set("defaults", &p.sequences, &BOX, &TrackConfig::default(), env)?;
        Ok(Output {
            params: p.clone(),
            tuned,
            defaults,
        })
    }

    fn tune(p: &Params, env: &Env<'_>) -> Result<Option<Tuned>> {
        check_seeds(p)?;
        if let Some(s) = p
            .tuning
            .settings
            .iter()
            .find(|s| s.trackers.iter().any(|t| !t.is_sort_family()))
        {
            bail!(
                "the search tunes the box trackers only; {} names another",
                s.key
            );
        }
        Ok(Some(search(&p.tuning, &tuned_header(p), env)?))
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        for (set, prefix) in [(&out.tuned, ""), (&out.defaults, "defaults_")] {
            let trackers: Vec<TrackerKind> = set.scores.iter().map(|s| s.tracker).collect();
            for t in out.params.trackers.iter().filter(|t| trackers.contains(t)) {
                let name = t.name().replace('-', "_");
                for m in MEASURES {
                    let key = format!("{prefix}{name}_{}_mean", m.name().to_lowercase());
                    metrics.insert(key, set.mean(*t, m).0);
                }
            }
        }
        for c in Comparison::all() {
            let paired = c.paired(&out.tuned);
            metrics.insert(format!("{}_diff", c.key()), paired.mean);
            metrics.insert(format!("{}_low", c.key()), paired.low);
        }
        metrics
    }

    fn present(out: &Output) -> Section {
        let verdicts: Vec<Verdict> = Comparison::all()
            .map(|c| Verdict::of(&c.paired(&out.tuned), 0.0))
            .collect();
        let count = |v: Verdict| verdicts.iter().filter(|&&x| x == v).count();
        Section {
            title: "SORT, ByteTrack and OC-SORT against our trackers (mot-box-trackers)".into(),
            summary: format!(
                "{} sequences generated once, with seeds never used before, after every setting \
                 was frozen (mot::walkers, half at 25 fps, half at 10 fps). The box trackers are \
                 box-trackers' (equal to roboflow trackers 2.6.1), tuned by `cargo xtask tune \
                 mot-box-trackers` on mot-realistic's {} tuning sequences, as ours were by `cargo \
                 xtask tune mot-realistic`; they are shown at the reference's defaults too. Each \
                 of our online trackers is compared with each box tracker by a paired 95 % \
                 interval; offline GNN and MCMCDA, which smooth over the whole file, are shown \
                 but not compared. Of the {} comparisons {} hold, {} are undecided and {} lose: \
                 where the table says so, the tuned box trackers track these files better than \
                 our online trackers.",
                out.params.sequences.len(),
                out.params.tuning.sequences.len(),
                verdicts.len(),
                count(Verdict::Holds),
                count(Verdict::Undecided),
                count(Verdict::Loses)
            ),
            tables: vec![means_table(out), comparisons_table(out)],
            figures: vec![means_figure(out)],
        }
    }

    fn claims(out: &Output) -> Vec<Claim> {
        Comparison::all()
            .map(|c| {
                let expected = out.params.fresh_verdicts[&c.key()];
                let n = out.params.sequences.len();
                verdict_claim(
                    &c.statement(),
                    &format!("the {n} fresh sequences"),
                    &c.paired(&out.tuned),
                    0.0,
                    Some(expected),
                )
            })
            .collect()
    }

    fn headlines(out: &Output) -> Vec<Headline> {
        let mota = |t| pm(out.tuned.mean(t, Measure::Mota));
        vec![
            Headline {
                quantity: "MOTA, online MCMCDA vs tuned ByteTrack (mot-box-trackers, fresh \
                           sequences; ours loses)"
                    .into(),
                paper: None,
                ours: mota(TrackerKind::McmcdaOnline),
                peer: Some(mota(TrackerKind::ByteTrack)),
            },
            Headline {
                quantity: "MOTA, offline MCMCDA vs tuned SORT (mot-box-trackers, fresh sequences; \
                           offline against online)"
                    .into(),
                paper: None,
                ours: mota(TrackerKind::Mcmcda),
                peer: Some(mota(TrackerKind::Sort)),
            },
        ]
    }
}

/// Every row of the means table: (tracker, its scores, its settings).
fn rows(out: &Output) -> Vec<(TrackerKind, &SetScores, &'static str)> {
    let ours = |t: TrackerKind| {
        if t.is_sort_family() {
            "tuned"
        } else {
            "ours, tuned"
        }
    };
    out.params
        .trackers
        .iter()
        .map(|&t| (t, &out.tuned, ours(t)))
        .chain(
            BOX.into_iter()
                .map(|t| (t, &out.defaults, "reference defaults")),
        )
        .collect()
}

/// MOTA, IDF1 and HOTA of every row as grouped bars, each with its 95 % interval.
fn means_figure(out: &Output) -> Figure {
    let rows = rows(out);
    let mut series = Vec::new();
    for (k, m) in MEASURES.into_iter().enumerate() {
        let offset = BAR_WIDTH * (k as f64 - 1.0);
        let at = |i: usize| (i + 1) as f64 + offset;
        let means: Vec<(f64, (f64, f64))> = rows
            .iter()
            .enumerate()
            .map(|(i, (t, set, _))| (at(i), set.mean(*t, m)))
            .collect();
        let bars = means.iter().map(|&(x, (mean, _))| (x, mean)).collect();
        series.push(Series::new(m.name(), bars, Style::Bars, k));
        for &(x, (mean, half)) in &means {
            let interval = vec![(x, mean - half), (x, mean + half)];
            series.push(Series::new("", interval, Style::Line, 7).in_front());
        }
    }
    let order: Vec<String> = rows
        .iter()
        .enumerate()
        .map(|(i, (t, _, settings))| format!("{} {t} ({settings})", i + 1))
        .collect();
    Figure::new(
        "means",
        &format!(
            "Means over the sequences with their 95 % intervals (dark lines). Trackers: {}.",
            order.join(", ")
        ),
        Chart::new(
            "MOTA, IDF1 and HOTA per tracker",
            "tracker (numbered as in the caption)",
            "score",
            series,
        ),
    )
}

fn means_table(out: &Output) -> Table {
    let mut table = Table::new(
        "Means over the sequences (± 95 % CI over sequences); time per frame is the whole \
         `cargo xtask track` run (the model fit included for ours) in the dev profile with the \
         sequences in parallel: indicative only (docs/benchmarks.md has the criterion medians)",
        &[
            "tracker",
            "settings",
            "MOTA",
            "IDF1",
            "HOTA",
            "IDSW",
            "ms per frame",
        ],
    );
    for (t, set, settings) in rows(out) {
        let mut row = vec![t.to_string(), settings.into()];
        row.extend(MEASURES.map(|m| pm(set.mean(t, m))));
        row.push(fmt_num(mean_ci(set.of(t).map(|s| s.idsw)).0));
        row.push(fmt_num(mean_ci(set.of(t).map(|s| s.ms_per_frame)).0));
        table.row(row);
    }
    table
}

fn comparisons_table(out: &Output) -> Table {
    let mut table = Table::new(
        "Our online trackers against the tuned box trackers: per-sequence difference (ours − \
         theirs), mean [95 % paired t interval]; holds when the interval lies above 0, loses \
         when below, else undecided",
        &["comparison", "difference", "verdict", "recorded verdict"],
    );
    for c in Comparison::all() {
        let paired = c.paired(&out.tuned);
        table.row(vec![
            c.statement(),
            paired.show(),
            Verdict::of(&paired, 0.0).name().into(),
            out.params.fresh_verdicts[&c.key()].name().into(),
        ]);
    }
    table
}
