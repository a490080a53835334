//! `mot-realistic`: `cargo xtask track`'s trackers (offline and online MCMCDA, GNN smoothed and
//! online, SMC-PHD) on realistic pedestrian detection files ([`mot::walkers`]: border-cut
//! boxes, walkers who stop and turn, occlusion, recall ≈ 0.8, 3 % jitter, scored false boxes),
//! with no per-sequence tuning: every model is fitted to the file by
//! [`mot::track::fit_model`] and [`mot::track::fit_scores`]. Scored with
//! eval-metrics (MOTA, IDF1, IDSW) against the sequences' truth, beside Stone Soup's GNN and JPDA
//! tuned on separate sequences (`docs/comparisons/stonesoup_realistic.py`, numbers recorded in
//! the scenario file).

use anyhow::{Result, bail};
use eval_metrics::{EvalConfig, evaluate};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Deserialize;
use tracker_model::TrackSet;

use crate::stats::mean_ci;
use crate::{Claim, Env, Headline, Metrics, Pipeline, Section, Table, fmt_num};
use mot::track::{TrackConfig, TrackerKind, track_detections};
use mot::walkers::WalkersConfig;

/// The `mot-realistic` pipeline.
pub struct MotRealistic;

/// One generated sequence.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SequenceSpec {
    /// Its name (as the peer script's files are named).
    name: String,
    /// Generator seed.
    seed: u64,
    /// Frames per second.
    fps: f64,
    /// Length, seconds.
    seconds: f64,
}

/// One recorded row of the peer script.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeerRow {
    /// Sequence name.
    sequence: String,
    /// "gnn" or "jpda".
    tracker: String,
    /// "online" or "offline".
    output: String,
    mota: f64,
    idf1: f64,
    idsw: f64,
    ms_per_frame: f64,
}

/// Its parameters.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Trackers to run.
    trackers: Vec<TrackerKind>,
    /// The reported sequences.
    sequences: Vec<SequenceSpec>,
    /// The orderings of [`ORDERINGS`] the report claims (the rest are shown, not claimed).
    claimed: Vec<String>,
    /// Stone Soup's results on the same sequences.
    peer: Vec<PeerRow>,
}

/// One tracker on one sequence.
#[derive(Debug, Clone)]
pub struct Score {
    tracker: TrackerKind,
    sequence: usize,
    mota: f64,
    idf1: f64,
    idsw: f64,
    false_positives: usize,
    false_negatives: usize,
    tracks: usize,
    ms_per_frame: f64,
}

/// Every score.
pub struct Output {
    params: Params,
    frames: Vec<u32>,
    truth_boxes: Vec<usize>,
    scores: Vec<Score>,
}

/// The orderings the scenario states (offline and online against the tuned peer), by key.
const ORDERINGS: [&str; 10] = [
    "mcmcda_mota_ge_peer_best_offline",
    "mcmcda_idf1_ge_peer_best_offline",
    "phd_mota_ge_peer_online_gnn",
    "mcmcda_online_mota_ge_peer_online_gnn",
    "gnn_mota_within_0.01_of_peer_gnn",
    "gnn_time_le_peer_gnn_over_20",
    "mcmcda_mota_ge_peer_best_online",
    "mcmcda_mota_gt_gnn",
    "gnn_mota_within_0.01_of_peer_online_gnn",
    "gnn_online_mota_within_0.01_of_peer_online_gnn",
];

impl Output {
    fn of(&self, tracker: TrackerKind) -> impl Iterator<Item = &Score> {
        self.scores.iter().filter(move |s| s.tracker == tracker)
    }

    fn mean(&self, tracker: TrackerKind, f: impl Fn(&Score) -> f64) -> (f64, f64) {
        mean_ci(self.of(tracker).map(f))
    }

    /// The peer's mean over the reported sequences of one tracker and output.
    fn peer_mean(&self, tracker: &str, output: &str, f: impl Fn(&PeerRow) -> f64) -> f64 {
        let rows: Vec<f64> = self
            .params
            .peer
            .iter()
            .filter(|r| r.tracker == tracker && r.output == output)
            .map(f)
            .collect();
        rows.iter().sum::<f64>() / rows.len().max(1) as f64
    }

    /// The peer's means the orderings compare against.
    fn peer_means(&self) -> PeerMeans {
        let best = |trackers: [&str; 2], output: &str, f: fn(&PeerRow) -> f64| {
            trackers
                .map(|t| self.peer_mean(t, output, f))
                .into_iter()
                .fold(f64::NEG_INFINITY, f64::max)
        };
        PeerMeans {
            best_off_mota: best(["gnn", "jpda"], "offline", |r| r.mota),
            best_off_idf1: best(["gnn", "jpda"], "offline", |r| r.idf1),
            online_gnn: self.peer_mean("gnn", "online", |r| r.mota),
            gnn_best: ["online", "offline"]
                .map(|o| self.peer_mean("gnn", o, |r| r.mota))
                .into_iter()
                .fold(f64::NEG_INFINITY, f64::max),
            gnn_ms: self.peer_mean("gnn", "online", |r| r.ms_per_frame),
            best_online: best(["gnn", "jpda"], "online", |r| r.mota),
        }
    }

    /// Our mean MOTA of one tracker over the sequences.
    fn mota(&self, t: TrackerKind) -> f64 {
        self.mean(t, |s| s.mota).0
    }

    /// (key, statement, holds) of every ordering, in the order of [`ORDERINGS`].
    fn orderings(&self) -> Vec<(&'static str, String, bool)> {
        let peer = self.peer_means();
        let mut all = self.offline_orderings(&peer);
        all.extend(self.online_orderings(&peer));
        all.extend(self.gnn_orderings(&peer));
        all.extend(self.mcmcda_orderings(&peer));
        all.extend(self.gnn_online_orderings(&peer));
        all
    }

    /// Orderings 0–1: offline MCMCDA's MOTA and IDF1 against the tuned peer's best offline
    /// output.
    fn offline_orderings(&self, peer: &PeerMeans) -> Vec<(&'static str, String, bool)> {
        let idf1 = self.mean(TrackerKind::Mcmcda, |s| s.idf1).0;
        vec![
            (
                ORDERINGS[0],
                format!(
                    "offline MCMCDA's mean MOTA ({}) ≥ the tuned peer's best offline mean MOTA ({})",
                    fmt_num(self.mota(TrackerKind::Mcmcda)),
                    fmt_num(peer.best_off_mota)
                ),
                self.mota(TrackerKind::Mcmcda) >= peer.best_off_mota,
            ),
            (
                ORDERINGS[1],
                format!(
                    "offline MCMCDA's mean IDF1 ({}) ≥ the tuned peer's best offline mean IDF1 ({})",
                    fmt_num(idf1),
                    fmt_num(peer.best_off_idf1)
                ),
                idf1 >= peer.best_off_idf1,
            ),
        ]
    }

    /// Orderings 2–3: the online PHD tracker and online MCMCDA against the peer's online GNN.
    fn online_orderings(&self, peer: &PeerMeans) -> Vec<(&'static str, String, bool)> {
        vec![
            (
                ORDERINGS[2],
                format!(
                    "the PHD tracker's mean MOTA ({}) ≥ the peer's online GNN ({})",
                    fmt_num(self.mota(TrackerKind::Phd)),
                    fmt_num(peer.online_gnn)
                ),
                self.mota(TrackerKind::Phd) >= peer.online_gnn,
            ),
            (
                ORDERINGS[3],
                format!(
                    "online MCMCDA's mean MOTA ({}) ≥ the peer's online GNN ({})",
                    fmt_num(self.mota(TrackerKind::McmcdaOnline)),
                    fmt_num(peer.online_gnn)
                ),
                self.mota(TrackerKind::McmcdaOnline) >= peer.online_gnn,
            ),
        ]
    }

    /// Orderings 4–5: our GNN against the peer's GNN, in MOTA (best output) and in time.
    fn gnn_orderings(&self, peer: &PeerMeans) -> Vec<(&'static str, String, bool)> {
        let gnn_ms = self.mean(TrackerKind::Gnn, |s| s.ms_per_frame).0;
        vec![
            (
                ORDERINGS[4],
                format!(
                    "GNN's mean MOTA ({}) is at least the peer's GNN (best output, {}) − 0.01",
                    fmt_num(self.mota(TrackerKind::Gnn)),
                    fmt_num(peer.gnn_best)
                ),
                self.mota(TrackerKind::Gnn) >= peer.gnn_best - 0.01,
            ),
            (
                ORDERINGS[5],
                format!(
                    "GNN's time per frame ({} ms, model fit included, dev profile) ≤ 1/20 of the \
                     peer GNN's ({} ms)",
                    fmt_num(gnn_ms),
                    fmt_num(peer.gnn_ms)
                ),
                gnn_ms <= peer.gnn_ms / 20.0,
            ),
        ]
    }

    /// Orderings 6–7: offline MCMCDA against the peer's best online output and against our
    /// GNN on the same fitted model.
    fn mcmcda_orderings(&self, peer: &PeerMeans) -> Vec<(&'static str, String, bool)> {
        vec![
            (
                ORDERINGS[6],
                format!(
                    "offline MCMCDA's mean MOTA ({}) ≥ the peer's best online mean MOTA ({})",
                    fmt_num(self.mota(TrackerKind::Mcmcda)),
                    fmt_num(peer.best_online)
                ),
                self.mota(TrackerKind::Mcmcda) >= peer.best_online,
            ),
            (
                ORDERINGS[7],
                format!(
                    "offline MCMCDA's mean MOTA ({}) > our GNN's ({}) on the same fitted model",
                    fmt_num(self.mota(TrackerKind::Mcmcda)),
                    fmt_num(self.mota(TrackerKind::Gnn))
                ),
                self.mota(TrackerKind::Mcmcda) > self.mota(TrackerKind::Gnn),
            ),
        ]
    }

    /// Orderings 8–9: our GNN, smoothed and online, against the peer's online GNN.
    fn gnn_online_orderings(&self, peer: &PeerMeans) -> Vec<(&'static str, String, bool)> {
        vec![
            (
                ORDERINGS[8],
                format!(
                    "GNN's mean MOTA ({}) is at least the peer's online GNN ({}) − 0.01",
                    fmt_num(self.mota(TrackerKind::Gnn)),
                    fmt_num(peer.online_gnn)
                ),
                self.mota(TrackerKind::Gnn) >= peer.online_gnn - 0.01,
            ),
            (
                ORDERINGS[9],
                format!(
                    "online GNN's mean MOTA ({}, frame-by-frame output with coasting, like the \
                     peer's) is at least the peer's online GNN ({}) − 0.01",
                    fmt_num(self.mota(TrackerKind::GnnOnline)),
                    fmt_num(peer.online_gnn)
                ),
                self.mota(TrackerKind::GnnOnline) >= peer.online_gnn - 0.01,
            ),
        ]
    }
}

/// The peer's (Stone Soup's) means over the reported sequences that the orderings compare
/// against (`docs/comparisons/stonesoup_realistic.py`).
struct PeerMeans {
    /// Best offline mean MOTA and IDF1 of GNN and JPDA.
    best_off_mota: f64,
    best_off_idf1: f64,
    /// Online GNN's mean MOTA.
    online_gnn: f64,
    /// GNN's mean MOTA, the better of its online and offline outputs.
    gnn_best: f64,
    /// Online GNN's time per frame.
    gnn_ms: f64,
    /// Best online mean MOTA of GNN and JPDA.
    best_online: f64,
}

impl Pipeline for MotRealistic {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, _: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        if let Some(c) = p.claimed.iter().find(|c| !ORDERINGS.contains(&c.as_str())) {
            bail!("claimed = {c:?} is not one of {ORDERINGS:?}");
        }
        if p.sequences.is_empty() {
            bail!("no sequences");
        }
        let seqs = p
            .sequences
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
        let jobs: Vec<(usize, TrackerKind)> = (0..seqs.len())
            .flat_map(|i| p.trackers.iter().map(move |&t| (i, t)))
            .collect();
        env.progress.set_length(jobs.len() as u64);
        let scores = jobs
            .par_iter()
            .map(|&(i, tracker)| {
                let start = env.clock.now_s();
                let tracks = track_detections(
                    tracker,
                    &seqs[i].detections,
                    &TrackConfig::default(),
                    env.seed,
                )?;
                let seconds = env.clock.now_s() - start;
                let report = evaluate(&gts[i], &tracks, &EvalConfig::default())?;
                env.progress.advance(1);
                Ok(Score {
                    tracker,
                    sequence: i,
                    mota: report.clear.mota,
                    idf1: report.identity.idf1,
                    idsw: report.clear.id_switches as f64,
                    false_positives: report.clear.false_positives,
                    false_negatives: report.clear.false_negatives,
                    tracks: tracks.len(),
                    ms_per_frame: 1e3 * seconds / f64::from(seqs[i].n_frames),
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Output {
            params: p.clone(),
            frames: seqs.iter().map(|s| s.n_frames).collect(),
            truth_boxes: seqs.iter().map(|s| s.gt.len()).collect(),
            scores,
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        for s in &out.scores {
            let seq = &out.params.sequences[s.sequence].name;
            let t = s.tracker.name().replace('-', "_");
            metrics.insert(format!("{t}_{seq}_mota"), s.mota);
            metrics.insert(format!("{t}_{seq}_idf1"), s.idf1);
            metrics.insert(format!("{t}_{seq}_idsw"), s.idsw);
        }
        for &t in &out.params.trackers {
            let name = t.name().replace('-', "_");
            metrics.insert(format!("{name}_mota_mean"), out.mean(t, |s| s.mota).0);
            metrics.insert(format!("{name}_idf1_mean"), out.mean(t, |s| s.idf1).0);
        }
        metrics
    }

    fn present(out: &Output) -> Section {
        Section {
            title: "Trackers on realistic pedestrian detections (mot-realistic)".into(),
            summary: format!(
                "{} generated sequences (mot::walkers, seeds separate from the peer's \
                 tuning seeds); every tracker fitted to each file, no per-sequence tuning. The \
                 peer is Stone Soup 1.9 GNN and JPDA with a constant-velocity box model tuned on \
                 the tuning sequences (docs/comparisons/stonesoup_realistic.py).",
                out.params.sequences.len()
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
        out.orderings()
            .into_iter()
            .filter(|(key, _, _)| out.params.claimed.iter().any(|c| c == key))
            .map(|(_, statement, holds)| Claim::new(statement, holds))
            .collect()
    }

    fn headlines(out: &Output) -> Vec<Headline> {
        let best_off = ["gnn", "jpda"]
            .map(|t| out.peer_mean(t, "offline", |r| r.mota))
            .into_iter()
            .fold(f64::NEG_INFINITY, f64::max);
        vec![
            Headline {
                quantity: "MOTA, offline MCMCDA vs Stone Soup's best offline (mot-realistic)"
                    .into(),
                paper: None,
                ours: fmt_num(out.mean(TrackerKind::Mcmcda, |s| s.mota).0),
                peer: Some(fmt_num(best_off)),
            },
            Headline {
                quantity: "MOTA, online MCMCDA vs Stone Soup's online GNN (mot-realistic)".into(),
                paper: None,
                ours: fmt_num(out.mean(TrackerKind::McmcdaOnline, |s| s.mota).0),
                peer: Some(fmt_num(out.peer_mean("gnn", "online", |r| r.mota))),
            },
        ]
    }
}

/// "mean ± half-width" of a (mean, 95 % half-width) pair.
fn pm((m, h): (f64, f64)) -> String {
    format!("{} ± {}", fmt_num(m), fmt_num(h))
}

/// The mean table: each of our trackers and each of Stone Soup's tuned trackers
/// (`docs/comparisons/stonesoup_realistic.py`) over the reported sequences, MOTA and IDF1 ±
/// 95 % CI, ID switches per 100 frames and time per frame.
fn mean_table(out: &Output) -> Table {
    let mut table = Table::new(
        "Mean over the reported sequences (± 95 % CI over sequences); time per frame \
         includes the model fit (ours, dev profile, sequences in parallel) or is Stone \
         Soup's tracking loop alone",
        &[
            "tracker",
            "MOTA",
            "IDF1",
            "IDSW / 100 frames",
            "ms per frame",
        ],
    );
    let n_frames: f64 = out.frames.iter().map(|&f| f64::from(f)).sum();
    for &t in &out.params.trackers {
        let idsw: f64 = out.of(t).map(|s| s.idsw).sum();
        table.row(vec![
            format!("ours: {t}"),
            pm(out.mean(t, |s| s.mota)),
            pm(out.mean(t, |s| s.idf1)),
            fmt_num(100.0 * idsw / n_frames),
            fmt_num(out.mean(t, |s| s.ms_per_frame).0),
        ]);
    }
    for (tracker, output) in [
        ("gnn", "online"),
        ("gnn", "offline"),
        ("jpda", "online"),
        ("jpda", "offline"),
    ] {
        let rows: Vec<&PeerRow> = out
            .params
            .peer
            .iter()
            .filter(|r| r.tracker == tracker && r.output == output)
            .collect();
        if rows.is_empty() {
            continue;
        }
        let idsw: f64 = rows.iter().map(|r| r.idsw).sum();
        table.row(vec![
            format!("Stone Soup {tracker} ({output}, tuned)"),
            pm(mean_ci(rows.iter().map(|r| r.mota))),
            pm(mean_ci(rows.iter().map(|r| r.idf1))),
            fmt_num(100.0 * idsw / n_frames),
            fmt_num(mean_ci(rows.iter().map(|r| r.ms_per_frame)).0),
        ]);
    }
    table
}

/// The per-sequence table: every tracker's tracks, MOTA, IDF1, IDSW, FP and FN on each
/// sequence, then the peer's recorded rows.
fn per_sequence_table(out: &Output) -> Table {
    let mut per_seq = Table::new(
        "Per sequence",
        &[
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
    for s in &out.scores {
        let spec = &out.params.sequences[s.sequence];
        per_seq.row(vec![
            format!("{} ({} fps)", spec.name, spec.fps),
            out.frames[s.sequence].to_string(),
            out.truth_boxes[s.sequence].to_string(),
            s.tracker.to_string(),
            s.tracks.to_string(),
            fmt_num(s.mota),
            fmt_num(s.idf1),
            s.idsw.to_string(),
            s.false_positives.to_string(),
            s.false_negatives.to_string(),
        ]);
    }
    for r in &out.params.peer {
        per_seq.row(vec![
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

/// The orderings table: every ordering of [`ORDERINGS`] against the peer, whether it holds
/// and whether the scenario claims it.
fn orderings_table(out: &Output) -> Table {
    let mut orderings = Table::new(
        "The orderings (claimed ones are checked by the suite; an unclaimed one either \
         fails, where we lose, or compares our output, smoothed over the whole file, with \
         the peer's online output)",
        &["ordering", "holds", "claimed"],
    );
    for (key, statement, holds) in out.orderings() {
        orderings.row(vec![
            statement,
            if holds { "yes" } else { "no" }.into(),
            if out.params.claimed.iter().any(|c| c == key) {
                "yes"
            } else {
                "no"
            }
            .into(),
        ]);
    }
    orderings
}
