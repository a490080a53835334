//! `mot-realistic`: `cargo xtask track`'s trackers (offline and online MCMCDA, GNN smoothed and
//! online, SMC-PHD) on realistic pedestrian detection files ([`mot::walkers`]: border-cut
//! boxes, walkers who stop and turn, occlusion, recall ≈ 0.8, 3 % jitter, scored false boxes),
//! with no per-sequence tuning: every model is fitted to the file by
//! [`mot::track::fit_model`] and [`mot::track::fit_scores`]. Scored with eval-metrics (MOTA,
//! IDF1, IDSW) against the sequences' truth, beside Stone Soup's GNN and JPDA tuned on separate
//! sequences (`docs/comparisons/stonesoup_realistic.py`, numbers recorded in the scenario
//! file).
//!
//! The seed-use rule of `docs/seeds.md`: the settings the trackers share come from
//! `fixtures/tuned/mot-realistic.toml`, which [`MotRealistic::tune`] (`cargo xtask tune
//! mot-realistic`) writes from the tuning sequences alone. The reported sequences were looked
//! at while the trackers were developed; the fresh ones were generated after the tuning was
//! frozen, and every ordering is claimed on them by a paired 95 % interval.

use std::collections::{BTreeMap, HashMap};

use anyhow::{Context, Result, bail};
use eval_metrics::{EvalConfig, evaluate};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Deserialize;
use tracker_model::TrackSet;

use crate::seeds::check_disjoint;
use crate::stats::{Paired, Verdict, mean_ci};
use crate::tune::{Coordinate, Tuned, coordinate_search, grid_csv, settings_file};
use crate::{Claim, Env, Headline, Metrics, Pipeline, Section, Table, fmt_num};
use mot::track::{TrackConfig, TrackerKind, track_detections};
use mot::walkers::{Sequence, WalkersConfig};

/// The `mot-realistic` pipeline.
pub struct MotRealistic;

/// One generated sequence.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SequenceSpec {
    /// Its name (as the peer script's files are named).
    pub(crate) name: String,
    /// Generator seed.
    pub(crate) seed: u64,
    /// Frames per second.
    pub(crate) fps: f64,
    /// Length, seconds.
    pub(crate) seconds: f64,
}

/// One recorded row of the peer script.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeerRow {
    /// Sequence name.
    sequence: String,
    /// "gnn" or "jpda".
    tracker: String,
    /// "online" (every state as output frame by frame), "offline" (without the coasted tail)
    /// or "smoothed" (the offline states through Stone Soup's RTS smoother).
    output: String,
    mota: f64,
    idf1: f64,
    idsw: f64,
    ms_per_frame: f64,
}

/// One setting the tuning search varies, and the trackers whose mean MOTA scores it.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TunedSetting {
    /// Dotted key of a `cargo xtask track --config` file (e.g. `offline.link_gap_factor`).
    pub(crate) key: String,
    /// Candidates, in the order they are tried.
    pub(crate) values: Vec<toml::Value>,
    /// The trackers the setting changes.
    pub(crate) trackers: Vec<TrackerKind>,
}

/// The tuning search of `cargo xtask tune mot-realistic`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tuning {
    /// The tuning sequences (the only ones the search runs).
    pub(crate) sequences: Vec<SequenceSpec>,
    /// Rounds of the coordinate search, at most.
    pub(crate) max_rounds: usize,
    /// The settings, searched in this order.
    pub(crate) settings: Vec<TunedSetting>,
}

/// Its parameters.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Trackers to run.
    trackers: Vec<TrackerKind>,
    /// The settings file the tuning search wrote (a `cargo xtask track --config` file).
    tuned: String,
    /// The search that writes it.
    tuning: Tuning,
    /// The reported sequences (looked at during development).
    sequences: Vec<SequenceSpec>,
    /// The fresh sequences, generated once after the tuning was frozen.
    fresh_sequences: Vec<SequenceSpec>,
    /// The verdict on the fresh sequences of every ordering of [`ORDERINGS`], recorded from
    /// their first run; the suite checks it stays so.
    fresh_verdicts: BTreeMap<String, Verdict>,
    /// Stone Soup's results on the reported and the fresh sequences.
    peer: Vec<PeerRow>,
}

/// MOTA, IDF1 or HOTA.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Measure {
    Mota,
    Idf1,
    Hota,
}

impl Measure {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Measure::Mota => "MOTA",
            Measure::Idf1 => "IDF1",
            Measure::Hota => "HOTA",
        }
    }
}

/// Who an ordering compares against.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Against {
    /// One of our trackers.
    Ours(TrackerKind),
    /// A Stone Soup tracker's output: (tracker, output) of [`PeerRow`].
    Peer(&'static str, &'static str),
}

/// "ours's measure ≥ against's − margin", per sequence, judged by a paired interval. Each
/// compares like with like: offline (smoothed over the file) with offline smoothed, online
/// (causal, coasting) with online.
pub(crate) struct Ordering {
    pub(crate) key: &'static str,
    pub(crate) measure: Measure,
    pub(crate) ours: TrackerKind,
    pub(crate) against: Against,
    pub(crate) margin: f64,
}

/// Every ordering the scenario states, fixed with its margin before the fresh sequences ran.
const ORDERINGS: [Ordering; 10] = [
    ordering(
        "mcmcda_mota_gt_gnn",
        Measure::Mota,
        TrackerKind::Mcmcda,
        Against::Ours(TrackerKind::Gnn),
        0.0,
    ),
    ordering(
        "mcmcda_mota_ge_peer_smoothed_gnn",
        Measure::Mota,
        TrackerKind::Mcmcda,
        Against::Peer("gnn", "smoothed"),
        0.0,
    ),
    ordering(
        "mcmcda_mota_ge_peer_smoothed_jpda",
        Measure::Mota,
        TrackerKind::Mcmcda,
        Against::Peer("jpda", "smoothed"),
        0.0,
    ),
    ordering(
        "mcmcda_idf1_ge_peer_smoothed_gnn",
        Measure::Idf1,
        TrackerKind::Mcmcda,
        Against::Peer("gnn", "smoothed"),
        0.0,
    ),
    ordering(
        "mcmcda_idf1_ge_peer_smoothed_jpda",
        Measure::Idf1,
        TrackerKind::Mcmcda,
        Against::Peer("jpda", "smoothed"),
        0.0,
    ),
    ordering(
        "gnn_mota_within_0.01_of_peer_smoothed_gnn",
        Measure::Mota,
        TrackerKind::Gnn,
        Against::Peer("gnn", "smoothed"),
        0.01,
    ),
    ordering(
        "mcmcda_online_mota_ge_peer_online_gnn",
        Measure::Mota,
        TrackerKind::McmcdaOnline,
        Against::Peer("gnn", "online"),
        0.0,
    ),
    ordering(
        "mcmcda_online_mota_ge_peer_online_jpda",
        Measure::Mota,
        TrackerKind::McmcdaOnline,
        Against::Peer("jpda", "online"),
        0.0,
    ),
    ordering(
        "gnn_online_mota_within_0.01_of_peer_online_gnn",
        Measure::Mota,
        TrackerKind::GnnOnline,
        Against::Peer("gnn", "online"),
        0.01,
    ),
    ordering(
        "phd_mota_ge_peer_online_gnn",
        Measure::Mota,
        TrackerKind::Phd,
        Against::Peer("gnn", "online"),
        0.0,
    ),
];

pub(crate) const fn ordering(
    key: &'static str,
    measure: Measure,
    ours: TrackerKind,
    against: Against,
    margin: f64,
) -> Ordering {
    Ordering {
        key,
        measure,
        ours,
        against,
        margin,
    }
}

impl Ordering {
    pub(crate) fn statement(&self) -> String {
        let against = match self.against {
            Against::Ours(t) => format!("our {t}"),
            Against::Peer(t, o) => format!("Stone Soup's {t} ({o})"),
        };
        let margin = if self.margin > 0.0 {
            format!(" − {}", fmt_num(self.margin))
        } else {
            String::new()
        };
        format!(
            "{}'s {} ≥ {against}'s{margin}",
            self.ours,
            self.measure.name()
        )
    }
}

/// One tracker on one sequence.
#[derive(Debug, Clone)]
pub struct Score {
    pub(crate) tracker: TrackerKind,
    pub(crate) sequence: usize,
    pub(crate) mota: f64,
    pub(crate) idf1: f64,
    pub(crate) hota: f64,
    pub(crate) idsw: f64,
    pub(crate) false_positives: usize,
    pub(crate) false_negatives: usize,
    pub(crate) tracks: usize,
    pub(crate) ms_per_frame: f64,
}

impl Score {
    pub(crate) fn of(&self, m: Measure) -> f64 {
        match m {
            Measure::Mota => self.mota,
            Measure::Idf1 => self.idf1,
            Measure::Hota => self.hota,
        }
    }
}

/// Every score on one set of sequences.
pub struct SetScores {
    /// "reported" or "fresh".
    pub(crate) name: &'static str,
    pub(crate) specs: Vec<SequenceSpec>,
    pub(crate) frames: Vec<u32>,
    pub(crate) truth_boxes: Vec<usize>,
    pub(crate) scores: Vec<Score>,
}

/// Both sets.
pub struct Output {
    params: Params,
    /// Reported, then fresh.
    sets: [SetScores; 2],
}

impl SetScores {
    pub(crate) fn of(&self, tracker: TrackerKind) -> impl Iterator<Item = &Score> {
        self.scores.iter().filter(move |s| s.tracker == tracker)
    }

    /// One of our trackers' measure on each sequence, in sequence order.
    pub(crate) fn ours(&self, tracker: TrackerKind, m: Measure) -> Vec<f64> {
        let mut v = vec![f64::NAN; self.specs.len()];
        for s in self.of(tracker) {
            v[s.sequence] = s.of(m);
        }
        v
    }

    /// The peer's rows of one tracker and output on this set's sequences, in sequence order.
    fn peer_rows<'a>(
        &self,
        peer: &'a [PeerRow],
        tracker: &str,
        output: &str,
    ) -> Vec<Option<&'a PeerRow>> {
        self.specs
            .iter()
            .map(|s| peer_row(peer, &s.name, tracker, output))
            .collect()
    }

    fn against(&self, peer: &[PeerRow], a: Against, m: Measure) -> Vec<f64> {
        match a {
            Against::Ours(t) => self.ours(t, m),
            Against::Peer(t, o) => self
                .peer_rows(peer, t, o)
                .into_iter()
                .map(|r| {
                    r.map_or(f64::NAN, |r| match m {
                        Measure::Mota => r.mota,
                        Measure::Idf1 => r.idf1,
                        // The peer script records no HOTA.
                        Measure::Hota => f64::NAN,
                    })
                })
                .collect(),
        }
    }

    /// The paired interval of an ordering on this set.
    pub(crate) fn paired(&self, peer: &[PeerRow], o: &Ordering) -> Paired {
        Paired::of(
            &self.ours(o.ours, o.measure),
            &self.against(peer, o.against, o.measure),
        )
    }

    pub(crate) fn mean(&self, tracker: TrackerKind, m: Measure) -> (f64, f64) {
        mean_ci(self.of(tracker).map(|s| s.of(m)))
    }
}

/// The peer's row of one sequence, tracker and output.
fn peer_row<'a>(
    peer: &'a [PeerRow],
    sequence: &str,
    tracker: &str,
    output: &str,
) -> Option<&'a PeerRow> {
    peer.iter()
        .find(|r| r.sequence == sequence && r.tracker == tracker && r.output == output)
}

/// The checks before anything runs: the three seed sets apart, and sequences in each.
fn check_seeds(p: &Params) -> Result<()> {
    let seeds = |specs: &[SequenceSpec]| specs.iter().map(|s| s.seed).collect::<Vec<_>>();
    check_disjoint(&[
        ("tuning", &seeds(&p.tuning.sequences)),
        ("reported", &seeds(&p.sequences)),
        ("fresh", &seeds(&p.fresh_sequences)),
    ])?;
    if p.sequences.is_empty() || p.fresh_sequences.len() < 2 || p.tuning.sequences.is_empty() {
        bail!("needs reported and tuning sequences and at least two fresh ones");
    }
    Ok(())
}

/// The checks before the scored runs: every ordering with a recorded verdict and its tracker,
/// the peer's rows complete for every compared output.
fn check_orderings(p: &Params) -> Result<()> {
    for o in &ORDERINGS {
        if !p.fresh_verdicts.contains_key(o.key) {
            bail!("fresh_verdicts has no verdict for {:?}", o.key);
        }
        if !p.trackers.contains(&o.ours) {
            bail!("the ordering {:?} needs the tracker {}", o.key, o.ours);
        }
    }
    if let Some(k) = p
        .fresh_verdicts
        .keys()
        .find(|k| !ORDERINGS.iter().any(|o| o.key == *k))
    {
        bail!("fresh_verdicts names {k:?}, which is no ordering");
    }
    for o in &ORDERINGS {
        let Against::Peer(t, out) = o.against else {
            continue;
        };
        for s in p.sequences.iter().chain(&p.fresh_sequences) {
            if peer_row(&p.peer, &s.name, t, out).is_none() {
                bail!(
                    "no peer row for {} {t} ({out}); run docs/comparisons/stonesoup_realistic.py",
                    s.name
                );
            }
        }
    }
    Ok(())
}

/// The sequences and their truth.
pub(crate) fn generate(specs: &[SequenceSpec]) -> Result<(Vec<Sequence>, Vec<TrackSet>)> {
    let seqs = specs
        .iter()
        .map(|s| {
            WalkersConfig {
                fps: s.fps,
                duration_s: s.seconds,
                ..WalkersConfig::default()
            }
            .generate_seeded(s.seed)
        })
        .collect::<Result<Vec<_>, mot::Error>>()?;
    let gts = seqs
        .iter()
        .map(|s| Ok(TrackSet::from_mot_rows(&s.gt)?))
        .collect::<Result<Vec<_>>>()?;
    Ok((seqs, gts))
}

/// Every tracker on every sequence of one set.
pub(crate) fn score_set(
    name: &'static str,
    specs: &[SequenceSpec],
    trackers: &[TrackerKind],
    config: &TrackConfig,
    env: &Env<'_>,
) -> Result<SetScores> {
    let (seqs, gts) = generate(specs)?;
    let jobs: Vec<(usize, TrackerKind)> = (0..seqs.len())
        .flat_map(|i| trackers.iter().map(move |&t| (i, t)))
        .collect();
    let scores = jobs
        .par_iter()
        .map(|&(i, tracker)| {
            let start = env.clock.now_s();
            let tracks = track_detections(tracker, &seqs[i].detections, config, env.seed)?;
            let seconds = env.clock.now_s() - start;
            let report = evaluate(&gts[i], &tracks, &EvalConfig::default())?;
            env.progress.advance(1);
            Ok(Score {
                tracker,
                sequence: i,
                mota: report.clear.mota,
                idf1: report.identity.idf1,
                hota: report.hota.hota,
                idsw: report.clear.id_switches as f64,
                false_positives: report.clear.false_positives,
                false_negatives: report.clear.false_negatives,
                tracks: tracks.len(),
                ms_per_frame: 1e3 * seconds / f64::from(seqs[i].n_frames),
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(SetScores {
        name,
        specs: specs.to_vec(),
        frames: seqs.iter().map(|s| s.n_frames).collect(),
        truth_boxes: seqs.iter().map(|s| s.gt.len()).collect(),
        scores,
    })
}

/// A settings table as a tracker configuration.
pub(crate) fn track_config(settings: &toml::Table) -> Result<TrackConfig> {
    toml::Value::Table(settings.clone())
        .try_into()
        .context("the tuned settings are not a `cargo xtask track --config` file")
}

/// The tuning search's score of a settings table for one setting: the mean MOTA over the
/// tuning sequences of the trackers the setting changes (cached by settings and tracker, so
/// a candidate already run costs nothing).
struct TuningScore<'a> {
    tuning: &'a Tuning,
    seqs: Vec<Sequence>,
    gts: Vec<TrackSet>,
    cache: HashMap<(String, &'static str), f64>,
    env: &'a Env<'a>,
}

impl TuningScore<'_> {
    fn score(&mut self, settings: &toml::Table, setting: usize) -> Result<f64> {
        let trackers = &self.tuning.settings[setting].trackers;
        let key = toml::to_string(settings)?;
        let config = track_config(settings)?;
        let mut sum = 0.0;
        for &t in trackers {
            if let Some(m) = self.cache.get(&(key.clone(), t.name())) {
                sum += m;
                continue;
            }
            let motas = (0..self.seqs.len())
                .into_par_iter()
                .map(|i| {
                    let tracks =
                        track_detections(t, &self.seqs[i].detections, &config, self.env.seed)?;
                    Ok(evaluate(&self.gts[i], &tracks, &EvalConfig::default())?
                        .clear
                        .mota)
                })
                .collect::<Result<Vec<f64>>>()?;
            let m = motas.iter().sum::<f64>() / motas.len() as f64;
            self.cache.insert((key.clone(), t.name()), m);
            sum += m;
        }
        Ok(sum / trackers.len().max(1) as f64)
    }
}

/// The coordinate search of `tuning` on its sequences, as a settings file with `header` and
/// the grid of every scored candidate.
pub(crate) fn search(tuning: &Tuning, header: &str, env: &Env<'_>) -> Result<Tuned> {
    let coordinates: Vec<Coordinate> = tuning
        .settings
        .iter()
        .map(|s| Coordinate {
            key: s.key.clone(),
            values: s.values.clone(),
        })
        .collect();
    let (seqs, gts) = generate(&tuning.sequences)?;
    let mut scorer = TuningScore {
        tuning,
        seqs,
        gts,
        cache: HashMap::new(),
        env,
    };
    let log = |line: &str| env.developer.say(line);
    let (settings, grid) = coordinate_search(
        &toml::Table::new(),
        &coordinates,
        tuning.max_rounds,
        |settings, i| scorer.score(settings, i),
        &log,
    )?;
    track_config(&settings)?.resolve(&[])?;
    Ok(Tuned {
        settings: settings_file(header, &settings)?,
        grid: grid_csv(&grid),
    })
}

/// The settings file's header.
fn tuned_header(p: &Params) -> String {
    let seeds: Vec<String> = p
        .tuning
        .sequences
        .iter()
        .map(|s| s.seed.to_string())
        .collect();
    format!(
        "Written by `cargo xtask tune mot-realistic`: do not edit. The coordinate search of\n\
         [params.tuning] in fixtures/scenarios/mot-realistic.toml, on the tuning sequences\n\
         only (seeds {}), each setting scored by the mean MOTA over them of\n\
         the trackers it changes; every candidate's score is in the grid CSV beside this file.\n\
         A `cargo xtask track --config` file: pass it to track pedestrian detection files\n\
         with these settings.",
        seeds.join(", ")
    )
}

impl Pipeline for MotRealistic {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, _: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        check_seeds(p)?;
        check_orderings(p)?;
        let text = env.inputs.read_to_string(&p.tuned)?;
        let config: TrackConfig =
            toml::from_str(&text).with_context(|| format!("reading {}", p.tuned))?;
        let n = (p.sequences.len() + p.fresh_sequences.len()) * p.trackers.len();
        env.progress.set_length(n as u64);
        let reported = score_set("reported", &p.sequences, &p.trackers, &config, env)?;
        let fresh = score_set("fresh", &p.fresh_sequences, &p.trackers, &config, env)?;
        Ok(Output {
            params: p.clone(),
            sets: [reported, fresh],
        })
    }

    fn tune(p: &Params, env: &Env<'_>) -> Result<Option<Tuned>> {
        check_seeds(p)?;
        Ok(Some(search(&p.tuning, &tuned_header(p), env)?))
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        for set in &out.sets {
            let prefix = if set.name == "fresh" { "fresh_" } else { "" };
            for s in &set.scores {
                let seq = &set.specs[s.sequence].name;
                let t = s.tracker.name().replace('-', "_");
                metrics.insert(format!("{t}_{seq}_mota"), s.mota);
                metrics.insert(format!("{t}_{seq}_idf1"), s.idf1);
                metrics.insert(format!("{t}_{seq}_idsw"), s.idsw);
            }
            for &t in &out.params.trackers {
                let name = t.name().replace('-', "_");
                metrics.insert(
                    format!("{prefix}{name}_mota_mean"),
                    set.mean(t, Measure::Mota).0,
                );
                metrics.insert(
                    format!("{prefix}{name}_idf1_mean"),
                    set.mean(t, Measure::Idf1).0,
                );
            }
        }
        for o in &ORDERINGS {
            let paired = out.sets[1].paired(&out.params.peer, o);
            let key = o.key.replace('.', "_");
            metrics.insert(format!("fresh_{key}_diff"), paired.mean);
            metrics.insert(format!("fresh_{key}_low"), paired.low);
        }
        metrics
    }

    fn present(out: &Output) -> Section {
        Section {
            title: "Trackers on realistic pedestrian detections (mot-realistic)".into(),
            summary: format!(
                "{} reported and {} fresh generated sequences (mot::walkers); every tracker \
                 fitted to each file, no per-sequence tuning, the shared settings from \
                 `cargo xtask tune mot-realistic` on {} tuning sequences (the appendix shows \
                 its grid). The fresh sequences were generated after the tuning was frozen; \
                 every ordering is claimed there by a paired 95 % interval. The peer is Stone \
                 Soup 1.9 GNN and JPDA with a constant-velocity box model, tuned on the tuning \
                 sequences (docs/comparisons/stonesoup_realistic.py); its smoothed output runs \
                 its RTS smoother over each track.",
                out.sets[0].specs.len(),
                out.sets[1].specs.len(),
                out.params.tuning.sequences.len()
            ),
            tables: vec![
                mean_table(out),
                orderings_table(out),
                per_sequence_table(out),
            ],
            figures: vec![],
        }
    }

    fn claims(out: &Output) -> Vec<Claim> {
        let fresh = &out.sets[1];
        ORDERINGS
            .iter()
            .map(|o| {
                let paired = fresh.paired(&out.params.peer, o);
                let expected = out.params.fresh_verdicts[o.key];
                verdict_claim(
                    &o.statement(),
                    &format!("the {} fresh sequences", fresh.specs.len()),
                    &paired,
                    o.margin,
                    Some(expected),
                )
            })
            .collect()
    }

    fn headlines(out: &Output) -> Vec<Headline> {
        let fresh = &out.sets[1];
        let peer_mean = |t: &'static str, o: &'static str| {
            mean_ci(fresh.against(&out.params.peer, Against::Peer(t, o), Measure::Mota)).0
        };
        let ours = |t| {
            let (m, h) = fresh.mean(t, Measure::Mota);
            format!("{} ± {}", fmt_num(m), fmt_num(h))
        };
        vec![
            Headline {
                quantity: "MOTA, offline MCMCDA vs Stone Soup's smoothed JPDA (mot-realistic, \
                           fresh sequences)"
                    .into(),
                paper: None,
                ours: ours(TrackerKind::Mcmcda),
                peer: Some(fmt_num(peer_mean("jpda", "smoothed"))),
            },
            Headline {
                quantity: "MOTA, online MCMCDA vs Stone Soup's online GNN (mot-realistic, \
                           fresh sequences)"
                    .into(),
                paper: None,
                ours: ours(TrackerKind::McmcdaOnline),
                peer: Some(fmt_num(peer_mean("gnn", "online"))),
            },
        ]
    }
}

/// The claim that `statement`'s verdict on `fresh` (the fresh units, e.g. "the 8 fresh
/// sequences"; its paired interval against `margin`) is still the `expected` one, recorded
/// from their first run. With no recorded verdict the claim fails, saying the verdict to
/// record.
pub(crate) fn verdict_claim(
    statement: &str,
    fresh: &str,
    paired: &Paired,
    margin: f64,
    expected: Option<Verdict>,
) -> Claim {
    let verdict = Verdict::of(paired, margin);
    Claim::new(
        format!(
            "{statement} on {fresh}: difference {} (95 % paired t) — {} (recorded: {})",
            paired.show(),
            verdict.name(),
            expected.map_or("none", Verdict::name)
        ),
        expected == Some(verdict),
    )
}

/// "mean ± half-width" of a (mean, 95 % half-width) pair.
pub(crate) fn pm((m, h): (f64, f64)) -> String {
    format!("{} ± {}", fmt_num(m), fmt_num(h))
}

/// The mean table: each of our trackers and each of Stone Soup's tuned outputs, MOTA and
/// IDF1 ± 95 % CI on the reported and the fresh sequences, time per frame (fresh).
fn mean_table(out: &Output) -> Table {
    let mut table = Table::new(
        "Means over the sequences (± 95 % CI over sequences); time per frame on the fresh \
         sequences includes the model fit (ours, dev profile, sequences in parallel) or is \
         Stone Soup's tracking loop alone",
        &[
            "tracker",
            "MOTA, reported",
            "IDF1, reported",
            "MOTA, fresh",
            "IDF1, fresh",
            "ms per frame",
        ],
    );
    let [reported, fresh] = &out.sets;
    for &t in &out.params.trackers {
        table.row(vec![
            format!("ours: {t}"),
            pm(reported.mean(t, Measure::Mota)),
            pm(reported.mean(t, Measure::Idf1)),
            pm(fresh.mean(t, Measure::Mota)),
            pm(fresh.mean(t, Measure::Idf1)),
            fmt_num(mean_ci(fresh.of(t).map(|s| s.ms_per_frame)).0),
        ]);
    }
    for tracker in ["gnn", "jpda"] {
        for output in ["online", "offline", "smoothed"] {
            let a = Against::Peer(tracker, output);
            let peer = &out.params.peer;
            let ms = fresh
                .peer_rows(peer, tracker, output)
                .into_iter()
                .flatten()
                .map(|r| r.ms_per_frame);
            table.row(vec![
                format!("Stone Soup {tracker} ({output}, tuned)"),
                pm(mean_ci(reported.against(peer, a, Measure::Mota))),
                pm(mean_ci(reported.against(peer, a, Measure::Idf1))),
                pm(mean_ci(fresh.against(peer, a, Measure::Mota))),
                pm(mean_ci(fresh.against(peer, a, Measure::Idf1))),
                fmt_num(mean_ci(ms).0),
            ]);
        }
    }
    table
}

/// The per-sequence table: every tracker's tracks, MOTA, IDF1, IDSW, FP and FN on each
/// sequence of both sets, then the peer's recorded rows.
fn per_sequence_table(out: &Output) -> Table {
    let mut per_seq = Table::new(
        "Per sequence",
        &[
            "set",
            "sequence",
            "frames",
            "truth boxes",
            "tracker",
            "tracks",
            "MOTA",
            "IDF1",
            "IDSW",
            "FP",
            "FN",
        ],
    );
    for set in &out.sets {
        for s in &set.scores {
            let spec = &set.specs[s.sequence];
            per_seq.row(vec![
                set.name.into(),
                format!("{} ({} fps)", spec.name, spec.fps),
                set.frames[s.sequence].to_string(),
                set.truth_boxes[s.sequence].to_string(),
                s.tracker.to_string(),
                s.tracks.to_string(),
                fmt_num(s.mota),
                fmt_num(s.idf1),
                s.idsw.to_string(),
                s.false_positives.to_string(),
                s.false_negatives.to_string(),
            ]);
        }
    }
    for r in &out.params.peer {
        let set = out
            .sets
            .iter()
            .find(|s| s.specs.iter().any(|x| x.name == r.sequence));
        per_seq.row(vec![
            set.map_or("", |s| s.name).into(),
            r.sequence.clone(),
            String::new(),
            String::new(),
            format!("Stone Soup {} ({})", r.tracker, r.output),
            String::new(),
            fmt_num(r.mota),
            fmt_num(r.idf1),
            r.idsw.to_string(),
            String::new(),
            String::new(),
        ]);
    }
    per_seq
}

/// The orderings table: each ordering's paired interval and verdict on both sets, and the
/// verdict recorded for the fresh set (which the suite checks).
fn orderings_table(out: &Output) -> Table {
    let mut table = Table::new(
        "The orderings: per-sequence difference (ours − theirs), mean [95 % paired t interval]; \
         holds when the interval lies above −margin, loses when below, else undecided. Only the \
         fresh verdict is claimed",
        &["ordering", "reported", "fresh", "recorded fresh verdict"],
    );
    for o in &ORDERINGS {
        let cell = |set: &SetScores| {
            let paired = set.paired(&out.params.peer, o);
            format!(
                "{} {}",
                paired.show(),
                Verdict::of(&paired, o.margin).name()
            )
        };
        table.row(vec![
            o.statement(),
            cell(&out.sets[0]),
            cell(&out.sets[1]),
            out.params.fresh_verdicts[o.key].name().into(),
        ]);
    }
    table
}
