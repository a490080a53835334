//! Online (sliding-window) MCMCDA (Oh, Russell & Sastry 2009 Algorithm 4).
//!
//! After each new scan the chain runs on the last `window` scans, starting from the previous
//! MAP restricted to the window with tracks that were alive greedily extended into the new
//! scan (as the authors' code does). A scan's associations are final when it leaves the
//! window; tracks keep their identity across windows through the measurements they share
//! with the previous MAP. Late measurements join their own scan while it is in the window.
//!
//! By default the tracker keeps every measurement and every final association until
//! [`OnlineTracker::finish`], so its memory grows with the run. A long run streams instead:
//! [`OnlineTracker::drain_committed`] hands over the final track pieces committed since the
//! last call and forgets the scans nothing can reach any more, so memory stays bounded by the
//! window (docs/reliability.md records it over 10⁵ scans).

use std::collections::{BTreeMap, HashMap};

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use tracker_model::{Frame, GATE_CHI2_2D, TrackSet, Vec2, ensure_positive};

use crate::config::Model;
use crate::error::{Error, Result, ensure_chains, ensure_samples, invalid_parameter};
use crate::estimates::smoothed_tracks;
use crate::partition::Partition;
use crate::problem::{MeasId, Problem};
use crate::sampler::Chain;

/// Settings of the online tracker.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OnlineConfig {
    /// t_win: scans in the sliding window.
    pub window: usize,
    /// MCMC samples per window and chain (see `chains`).
    pub samples_per_scan: u64,
    /// χ² gate of the greedy extension of live tracks into a new scan.
    pub extension_gate: f64,
    /// A track is reported at the current scan if its last measurement is at most this many
    /// scans old (targets are missed with probability 1 − p_d).
    pub coast_scans: usize,
    /// Adaptive budget: a window's chain stops once this many consecutive samples have not
    /// raised the window's MAP (the best log posterior seen, Algorithm 4's output), and after
    /// `samples_per_scan` samples at most. The chain starts from the previous MAP extended
    /// into the new scan, so in quiet stretches it starts at or near the answer. 0 (the
    /// default) runs every window's full `samples_per_scan`, as Algorithm 4 does. A
    /// heuristic: on the walkers' tuning sequences every value tried (50-1200) lost MOTA
    /// (docs/mot-realistic.md).
    pub patience: u64,
    /// Draw no sample at a scan whose new measurements are all unambiguous given the start
    /// (each taken by the greedy extension of the only live track whose gate holds it, that
    /// track's only gated candidate, and no late measurement added since the last scan); the
    /// start is then kept as the window's MAP. A heuristic: the older scans of such a window
    /// are not revisited. `false` (the default) samples every window.
    pub skip_unambiguous: bool,
    /// With `skip_unambiguous`: a second gated association (another track gating a
    /// measurement, or another measurement in a track's gate) makes the scan ambiguous only
    /// if its log likelihood is within this of the best association of that measurement or
    /// track, i.e. only a rival at least e^−r as likely counts. ∞ (the default) counts every
    /// gated rival.
    pub rival_log_ratio: f64,
    /// With `skip_unambiguous`: a new measurement that no track gates makes the scan
    /// ambiguous only if a free measurement lies in its neighbourhood in one of the last
    /// `birth_lookback` scans, with which it could start a track (a lone false alarm far
    /// from every other free measurement changes nothing the chain would accept; a new
    /// target's detections follow one another; scans beyond d̄ are not looked at, as nothing
    /// there can precede it on a track). 0 (the default) counts every such measurement.
    pub birth_lookback: usize,
    /// Independent chains per window, run in parallel from the same start, each with
    /// `samples_per_scan` samples (and its own `patience`); the best MAP among them is the
    /// window's. Chain i draws from stream i of the tracker's seed, so the output is the same
    /// at any thread count, and 1 (the default) is the single chain of Algorithm 4.
    pub chains: usize,
}

/// The longest sliding window and coasting, in scans: the window's chain and its memory grow
/// with it, and a thousand scans is far past any window Algorithm 4 is run with.
pub const MAX_WINDOW: usize = 1000;

impl Default for OnlineConfig {
    fn default() -> Self {
        Self {
            window: 14,
            samples_per_scan: 2000,
            extension_gate: GATE_CHI2_2D,
            coast_scans: 2,
            patience: 0,
            skip_unambiguous: false,
            rival_log_ratio: f64::INFINITY,
            birth_lookback: 0,
            chains: 1,
        }
    }
}

impl OnlineConfig {
    /// Checks the window (at least 2 scans, the shortest a track spans), the extension gate
    /// (finite, > 0), the rival ratio (≥ 0, ∞ allowed), the chain count (1 to 64) and the
    /// bounds on window, coasting and samples ([`MAX_WINDOW`], [`crate::MAX_SAMPLES`]).
    /// [`OnlineTracker::new`] calls this.
    pub fn check(&self) -> Result<()> {
        if self.window < 2 {
            return Err(invalid_parameter(
                "window",
                format!("{} scans; it needs at least 2", self.window),
            ));
        }
        ensure_positive(self.extension_gate, "extension_gate")?;
        if self.rival_log_ratio.is_nan() || self.rival_log_ratio < 0.0 {
            return Err(invalid_parameter(
                "rival_log_ratio",
                format!(
                    "{}; it must be ≥ 0 (∞ counts every gated rival)",
                    self.rival_log_ratio
                ),
            ));
        }
        if self.window > MAX_WINDOW {
            return Err(invalid_parameter(
                "window",
                format!("{} scans; at most {MAX_WINDOW}", self.window),
            ));
        }
        if self.coast_scans > MAX_WINDOW {
            return Err(invalid_parameter(
                "coast_scans",
                format!("{} scans; at most {MAX_WINDOW}", self.coast_scans),
            ));
        }
        ensure_samples(self.samples_per_scan, "samples_per_scan")?;
        ensure_chains(self.chains)
    }
}

/// What the tracker believes after a scan.
#[derive(Debug, Clone, PartialEq)]
pub struct OnlineStep {
    /// The scan's frame.
    pub frame: Frame,
    /// Position estimates (filtered, predicted over missed scans) of the tracks reported at
    /// this scan, with their persistent labels.
    pub estimates: Vec<(u64, Vec2)>,
    /// Log posterior of the window's MAP.
    pub log_posterior: f64,
}

/// Everything an online run produced.
#[derive(Debug, Clone)]
pub struct OnlineResult {
    /// Smoothed tracks, labels as ids.
    pub tracks: TrackSet,
    /// Each label's measurements (final associations).
    pub associations: Vec<(u64, Vec<MeasId>)>,
    /// The measurements, for looking the ids up.
    pub problem: Problem,
}

/// A piece of a track whose associations became final: the measurements a label gained in
/// the scans that left the window since the last [`OnlineTracker::drain_committed`], in
/// scan order.
#[derive(Debug, Clone, PartialEq)]
pub struct CommittedPiece {
    /// The track's persistent label (the same label in every piece of one track and in
    /// [`OnlineTracker::finish`]).
    pub label: u64,
    /// Measurement ids (stable: the ids [`OnlineTracker::push_scan`] gave them).
    pub measurements: Vec<MeasId>,
    /// Frame of each measurement.
    pub frames: Vec<Frame>,
    /// Position of each measurement (as measured, not smoothed).
    pub positions: Vec<Vec2>,
}

/// The sliding-window tracker. Owns the measurements it has seen (the scans it still
/// needs, once [`Self::drain_committed`] is used).
pub struct OnlineTracker {
    model: Model,
    problem: Problem,
    config: OnlineConfig,
    /// One generator per chain: stream i of the seed for chain i (chain 0's also draws the
    /// identity samples of [`Self::sample_joins`]).
    rngs: Vec<ChaCha8Rng>,
    /// The previous window's MAP with labels.
    map: Vec<(u64, Vec<MeasId>)>,
    next_label: u64,
    /// Final associations of the scans that left the window, by label (those not drained
    /// yet, once [`Self::drain_committed`] is used).
    committed: BTreeMap<u64, Vec<MeasId>>,
    /// How many committed measurements each live label has handed over in drained pieces.
    released: BTreeMap<u64, usize>,
    /// The first scan not committed yet.
    open_from: usize,
    /// MCMC samples drawn by the windows so far.
    samples_run: u64,
    /// A late measurement was added since the last window (the next window is ambiguous).
    late_pending: bool,
}

impl OnlineTracker {
    /// A tracker whose first scan is `first_frame`; every random draw comes from ChaCha8
    /// seeded with `seed`. Fails if `config` does not pass [`OnlineConfig::check`].
    pub fn new(model: Model, first_frame: Frame, config: OnlineConfig, seed: u64) -> Result<Self> {
        config.check()?;
        Ok(Self {
            problem: Problem::empty(&model, first_frame),
            model,
            config,
            rngs: (0..config.chains)
                .map(|i| {
                    let mut rng = ChaCha8Rng::seed_from_u64(seed);
                    rng.set_stream(i as u64);
                    rng
                })
                .collect(),
            map: Vec::new(),
            next_label: 0,
            committed: BTreeMap::new(),
            released: BTreeMap::new(),
            open_from: 0,
            samples_run: 0,
            late_pending: false,
        })
    }

    /// The measurements received so far (from `Problem::first_kept_scan` on, once
    /// [`Self::drain_committed`] has forgotten older scans).
    pub fn problem(&self) -> &Problem {
        &self.problem
    }

    fn window_start(&self) -> usize {
        self.problem.n_scans().saturating_sub(self.config.window)
    }

    /// Adds a measurement that arrived late for `frame`, whose scan must still be open (in
    /// the next window); it is used from the next window on.
    pub fn add_late(&mut self, frame: Frame, position: Vec2) -> Result<MeasId> {
        let lo = self.problem.first_frame() + self.open_from as Frame;
        if frame < lo {
            return Err(Error::LateMeasurement {
                frame,
                window_start: lo,
            });
        }
        let id = self.problem.add_measurement(frame, position)?;
        self.late_pending = true;
        Ok(id)
    }

    /// Processes the scan at `frame` (after any empty scans needed to reach it).
    pub fn push_scan(&mut self, frame: Frame, points: &[Vec2]) -> Result<OnlineStep> {
        self.push_and_sample(frame, points, None)
    }

    /// [`Self::push_scan`] with each point's score likelihood ratio ln f₁(s)/f₀(s)
    /// ([`Problem::push_scan_scored`]).
    pub fn push_scan_scored(
        &mut self,
        frame: Frame,
        points: &[Vec2],
        log_score_ratios: &[f64],
    ) -> Result<OnlineStep> {
        self.push_and_sample(frame, points, Some(log_score_ratios))
    }

    /// Both of the above (all ratios 0 when `None`).
    fn push_and_sample(
        &mut self,
        frame: Frame,
        points: &[Vec2],
        log_score_ratios: Option<&[f64]>,
    ) -> Result<OnlineStep> {
        self.problem.push_scored(frame, points, log_score_ratios)?;
        let hi = *self.problem.all_scans()?.end();
        let lo = self.window_start();
        // Scans leaving the window now (one, or more after a jump in frames) keep the
        // associations of the last MAP that saw them: those become final.
        if lo > self.open_from {
            self.commit(self.open_from..=lo - 1);
        }
        let mut start = Partition::empty(&self.model, &self.problem, lo..=hi)?;
        for (_, track) in &self.map {
            let kept: Vec<MeasId> = track
                .iter()
                .copied()
                .filter(|&m| self.problem.scan_of(m) >= lo)
                .collect();
            if kept.len() >= 2 {
                start.insert(kept, None);
            }
        }
        let ambiguous = extend_into_last_scan(&mut start, &self.config);
        let (best, log_posterior) = if ambiguous || self.late_pending {
            let (best, log_posterior, samples) = sample_window(start, &mut self.rngs, &self.config);
            self.samples_run += samples;
            (best, log_posterior)
        } else {
            (start.canonical(), start.log_posterior())
        };
        self.late_pending = false;
        self.map = relabel(&self.map, best, &mut self.next_label);
        let map_partition = Partition::from_tracks(
            &self.model,
            &self.problem,
            lo..=hi,
            &self.map.iter().map(|(_, t)| t.clone()).collect::<Vec<_>>(),
        )?;
        let estimates = self
            .map
            .iter()
            .zip(&map_partition.tracks)
            .filter_map(|((label, track), state)| {
                let last = self.problem.scan_of(track[track.len() - 1]);
                (hi - last <= self.config.coast_scans).then(|| {
                    let node = &state.nodes[state.nodes.len() - 1];
                    (
                        *label,
                        node.position_after((hi - last) as f64 * self.model.config().motion.dt_s()),
                    )
                })
            })
            .collect();
        Ok(OnlineStep {
            frame: self.problem.first_frame() + hi as Frame,
            estimates,
            log_posterior,
        })
    }

    /// MCMC samples the windows have drawn so far, all chains together (`chains` ×
    /// `samples_per_scan` per scan unless [`OnlineConfig::patience`] stops chains early or
    /// [`OnlineConfig::skip_unambiguous`] skips scans; [`Self::sample_joins`] is not counted).
    pub fn samples_run(&self) -> u64 {
        self.samples_run
    }

    /// The current window's MAP tracks with their persistent labels (measurement ids in scan
    /// order), as of the last [`Self::push_scan`].
    pub fn map_tracks(&self) -> &[(u64, Vec<MeasId>)] {
        &self.map
    }

    /// The scans of the current window (indices into [`Self::problem`]); `None` before the
    /// first scan.
    pub fn window(&self) -> Option<std::ops::RangeInclusive<usize>> {
        let hi = *self.problem.all_scans().ok()?.end();
        Some(self.window_start()..=hi)
    }

    /// Per-sample associations for identity management (the mixing matrices of Oh, Hwang &
    /// Sastry 2008): runs `n_samples` further MCMC steps on the current window, starting from
    /// its MAP, and for every sample lists the pairs (i, j) such that `pre[i]` and `post[j]`
    /// lie on the same track. Where several listed pieces share a track, only the adjacent
    /// ones are joined (the latest pre piece before the earliest post piece after it), so
    /// each piece is in at most one pair per sample, as
    /// `identity_mgmt::Continuation::from_samples` expects. The chain draws from this
    /// tracker's generator and leaves the MAP unchanged. Every piece must lie in the window
    /// ([`Error::MeasurementOutsideWindow`] otherwise).
    pub fn sample_joins(
        &mut self,
        pre: &[MeasId],
        post: &[MeasId],
        n_samples: u64,
    ) -> Result<Vec<Vec<(usize, usize)>>> {
        let window = self.problem.all_scans()?;
        let (lo, hi) = (self.window_start(), *window.end());
        for (k, &m) in pre.iter().chain(post).enumerate() {
            if self.problem.is_forgotten(m) {
                return Err(Error::MeasurementOutsideWindow { track: k, id: m });
            }
            if !self.problem.contains(m) {
                return Err(Error::UnknownMeasurement { track: k, id: m });
            }
            if self.problem.scan_of(m) < lo {
                return Err(Error::MeasurementOutsideWindow { track: k, id: m });
            }
        }
        let tracks: Vec<Vec<MeasId>> = self.map.iter().map(|(_, t)| t.clone()).collect();
        let start = Partition::from_tracks(&self.model, &self.problem, lo..=hi, &tracks)?;
        let problem = &self.problem;
        let mut chain = Chain::new(start, &mut self.rngs[0]);
        let mut samples = Vec::with_capacity(usize::try_from(n_samples).unwrap_or(0));
        for _ in 0..n_samples {
            chain.step();
            let state = chain.state();
            // For every track holding pieces: (scan, is_post, index), joined where a pre
            // piece is immediately followed by a post piece in time.
            let mut by_track: BTreeMap<usize, Vec<(usize, bool, usize)>> = BTreeMap::new();
            for (i, &m) in pre.iter().enumerate() {
                if let Some(t) = state.track_of(m) {
                    by_track
                        .entry(t)
                        .or_default()
                        .push((problem.scan_of(m), false, i));
                }
            }
            for (j, &m) in post.iter().enumerate() {
                if let Some(t) = state.track_of(m) {
                    by_track
                        .entry(t)
                        .or_default()
                        .push((problem.scan_of(m), true, j));
                }
            }
            let mut pairs = Vec::new();
            for pieces in by_track.values_mut() {
                pieces.sort_unstable();
                for w in pieces.windows(2) {
                    if let [(_, false, i), (_, true, j)] = w {
                        pairs.push((*i, *j));
                    }
                }
            }
            samples.push(pairs);
        }
        Ok(samples)
    }

    /// Makes the current MAP's associations in `scans` final.
    fn commit(&mut self, scans: std::ops::RangeInclusive<usize>) {
        self.open_from = self.open_from.max(scans.end() + 1);
        for (label, track) in &self.map {
            let in_scans = track
                .iter()
                .filter(|&&m| scans.contains(&self.problem.scan_of(m)));
            let entry = self.committed.entry(*label).or_default();
            entry.extend(in_scans);
        }
    }

    /// Streams the output: returns the final track pieces committed since the last call
    /// (by label, each piece's measurements in scan order) and drops them, together with the
    /// scans nothing can reach any more (older than the window's start minus d̄, so every
    /// neighbourhood a window can use stays whole). Called after every
    /// [`Self::push_scan`] (or every few), it keeps the tracker's memory bounded by the
    /// window however long the run; [`Self::finish`] then returns only what was not drained.
    ///
    /// As in [`Self::finish`], a label must end up with at least two committed measurements
    /// to be a track: a label's first committed measurement is held back until a second one
    /// is committed, and dropped if its track leaves the MAP before that. The pieces of
    /// each label, concatenated in drain order and followed by its association in
    /// [`Self::finish`], are exactly the association a run without draining returns.
    /// After a drain, [`Self::problem`] holds only the scans kept and [`OnlineResult`]'s
    /// `problem` too.
    ///
    /// ```
    /// use mcmcda::{McmcdaConfig, OnlineConfig, OnlineTracker};
    /// use tracker_model::Vec2;
    ///
    /// let model = McmcdaConfig::default().check()?;
    /// let config = OnlineConfig { window: 5, samples_per_scan: 200, ..OnlineConfig::default() };
    /// let mut tracker = OnlineTracker::new(model, 0, config, 7)?;
    /// let mut pieces = Vec::new();
    /// for frame in 0..40 {
    ///     let t = f64::from(frame);
    ///     tracker.push_scan(frame, &[Vec2::new(100.0 + 20.0 * t, 500.0)])?;
    ///     pieces.extend(tracker.drain_committed());
    /// }
    /// // Only the window (5 scans) and the d̄ = 5 scans before it are kept.
    /// assert_eq!(tracker.problem().kept_scans()?, 30..=39);
    /// assert_eq!(tracker.problem().n_kept_measurements(), 10);
    /// let rest = tracker.finish()?;
    /// let streamed: usize = pieces.iter().map(|p| p.measurements.len()).sum();
    /// let held: usize = rest.associations.iter().map(|(_, m)| m.len()).sum();
    /// assert_eq!(streamed + held, 40);
    /// # Ok::<(), mcmcda::Error>(())
    /// ```
    pub fn drain_committed(&mut self) -> Vec<CommittedPiece> {
        let alive: Vec<u64> = self.map.iter().map(|(l, _)| *l).collect();
        let mut pieces = Vec::new();
        let committed = std::mem::take(&mut self.committed);
        for (label, meas) in committed {
            let before = self.released.get(&label).copied().unwrap_or(0);
            if before + meas.len() < 2 {
                if alive.contains(&label) && !meas.is_empty() {
                    self.committed.insert(label, meas);
                }
                continue;
            }
            self.released.insert(label, before + meas.len());
            if meas.is_empty() {
                continue;
            }
            let problem = &self.problem;
            pieces.push(CommittedPiece {
                label,
                frames: meas
                    .iter()
                    .map(|&m| problem.first_frame() + problem.scan_of(m) as Frame)
                    .collect(),
                positions: meas.iter().map(|&m| problem.position(m)).collect(),
                measurements: meas,
            });
        }
        self.released.retain(|l, _| alive.contains(l));
        // Scans before the window and d̄ more are out of every neighbourhood the next
        // windows use; held-back measurements keep their scans.
        let held_back = self
            .committed
            .values()
            .flatten()
            .map(|&m| self.problem.scan_of(m))
            .min()
            .unwrap_or(usize::MAX);
        let keep_from = self
            .open_from
            .saturating_sub(self.problem.max_gap())
            .min(held_back);
        self.problem.forget_before(keep_from);
        pieces
    }

    /// Commits the current window and returns every track (label as id) smoothed over its
    /// committed measurements, with the associations. After [`Self::drain_committed`], only
    /// what was not drained: the smoothing then runs over each label's remaining
    /// measurements only, and a label that already handed over pieces keeps even a single
    /// remaining measurement in `associations` (its smoothed track then has one point).
    pub fn finish(mut self) -> Result<OnlineResult> {
        self.finish_in_place()
    }

    /// [`Self::finish`] on a borrowed tracker, which is spent afterwards: its measurements and
    /// associations are handed out (its problem left empty), and a failed smoothing leaves it
    /// as it was.
    pub(crate) fn finish_in_place(&mut self) -> Result<OnlineResult> {
        if let Ok(all) = self.problem.all_scans()
            && self.open_from <= *all.end()
        {
            self.commit(self.open_from..=*all.end());
        }
        let mut tracks = TrackSet::new();
        let mut associations = Vec::new();
        for (&label, meas) in &self.committed {
            let released = self.released.get(&label).copied().unwrap_or(0);
            if meas.is_empty() || released + meas.len() < 2 {
                continue;
            }
            let one = smoothed_tracks(
                &self.model,
                &self.problem,
                std::slice::from_ref(meas),
                label,
            )?;
            for t in one.tracks() {
                tracks.push(t.clone())?;
            }
            associations.push((label, meas.clone()));
        }
        let first = self.problem.first_frame();
        let problem = std::mem::replace(&mut self.problem, Problem::empty(&self.model, first));
        self.committed.clear();
        self.released.clear();
        self.map.clear();
        Ok(OnlineResult {
            tracks,
            associations,
            problem,
        })
    }
}

/// Runs the window's chains from `start` (one per generator, in parallel when more than one)
/// and returns the best MAP (the first chain's on a tie), its log posterior and the samples
/// drawn by all chains.
pub(crate) fn sample_window(
    start: Partition<'_>,
    rngs: &mut [ChaCha8Rng],
    config: &OnlineConfig,
) -> (Vec<Vec<MeasId>>, f64, u64) {
    let one = |start: Partition<'_>, rng: &mut ChaCha8Rng| {
        let mut chain = Chain::new(start, rng);
        let samples = run_window(&mut chain, config);
        let (best, log_posterior) = chain.map();
        (best.to_vec(), log_posterior, samples)
    };
    if let [rng] = rngs {
        return one(start, rng);
    }
    let runs: Vec<_> = rngs
        .par_iter_mut()
        .map(|rng| one(start.clone(), rng))
        .collect();
    let samples = runs.iter().map(|r| r.2).sum();
    let mut best = runs
        .into_iter()
        .reduce(|best, run| if run.1 > best.1 { run } else { best })
        .unwrap_or_default();
    best.2 = samples;
    best
}

/// Runs a window's chain: `samples_per_scan` steps, or with [`OnlineConfig::patience`] > 0
/// until that many consecutive steps leave the MAP unchanged (at most `samples_per_scan`).
/// Returns the steps taken. With patience 0 this is exactly [`Chain::run`].
pub(crate) fn run_window<R: rand::Rng>(chain: &mut Chain<'_, R>, config: &OnlineConfig) -> u64 {
    let budget = config.samples_per_scan;
    if config.patience == 0 {
        chain.run(budget);
        return budget;
    }
    let mut best = chain.map().1;
    let mut stale = 0;
    for n in 1..=budget {
        chain.step();
        let log_posterior = chain.map().1;
        if log_posterior > best {
            best = log_posterior;
            stale = 0;
        } else {
            stale += 1;
            if stale >= config.patience {
                return n;
            }
        }
    }
    budget
}

/// Greedily extends every track that can still grow into the last scan of the window, by
/// increasing innovation cost, gated by `extension_gate`. Returns whether the window needs
/// sampling: always, unless `skip_unambiguous`; then only if [`last_scan_is_ambiguous`].
fn extend_into_last_scan(partition: &mut Partition<'_>, config: &OnlineConfig) -> bool {
    let (model, problem, hi) = (partition.model, partition.problem, partition.hi);
    // (−Δ log likelihood of adding m to track k, k, m) for every gated pair.
    let mut pairs: Vec<(f64, usize, MeasId)> = Vec::new();
    for (k, t) in partition.tracks.iter().enumerate() {
        let last = t.meas[t.meas.len() - 1];
        let gap = hi - problem.scan_of(last);
        if gap == 0 || gap > problem.max_gap() {
            continue;
        }
        for &m in problem.forward(last, gap) {
            if !partition.is_free(m) {
                continue;
            }
            let node = &t.nodes[t.nodes.len() - 1];
            let (next, maha) = model.step(node, problem.position(m), gap);
            if maha <= config.extension_gate {
                pairs.push((node.cum_log_likelihood() - next.cum_log_likelihood(), k, m));
            }
        }
    }
    let ambiguous = !config.skip_unambiguous || last_scan_is_ambiguous(partition, &pairs, config);
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut extended: HashMap<usize, MeasId> = HashMap::new();
    let mut taken: Vec<MeasId> = Vec::new();
    for (_, k, m) in pairs {
        if !extended.contains_key(&k) && !taken.contains(&m) {
            extended.insert(k, m);
            taken.push(m);
        }
    }
    // Replace the extended tracks (highest index first, so lower indices stay put).
    let mut ks: Vec<usize> = extended.keys().copied().collect();
    ks.sort_unstable_by(|a, b| b.cmp(a));
    for k in ks {
        let old = partition.remove(k);
        let mut meas = old.meas.clone();
        meas.push(extended[&k]);
        let keep = old.meas.len();
        partition.insert(meas, Some((&old.nodes, keep)));
    }
    ambiguous
}

/// Whether the last scan leaves the chain anything to decide, given the gated `pairs`
/// (cost, track, measurement) of the greedy extension, before it: a track or a measurement
/// with a rival (a second gated association whose cost is within `rival_log_ratio` of its
/// best), or a measurement no track gates with a free measurement in its neighbourhood in
/// the last `birth_lookback` scans (any, with 0).
fn last_scan_is_ambiguous(
    partition: &Partition<'_>,
    pairs: &[(f64, usize, MeasId)],
    config: &OnlineConfig,
) -> bool {
    let mut best_of_track: BTreeMap<usize, f64> = BTreeMap::new();
    let mut best_of_meas: BTreeMap<MeasId, f64> = BTreeMap::new();
    for &(cost, k, m) in pairs {
        let best = best_of_track.entry(k).or_insert(f64::INFINITY);
        *best = best.min(cost);
        let best = best_of_meas.entry(m).or_insert(f64::INFINITY);
        *best = best.min(cost);
    }
    // ∞ counts every gated pair, whatever the costs (as before the ratio existed).
    let close = |cost: f64, best: f64| {
        config.rival_log_ratio == f64::INFINITY || cost <= best + config.rival_log_ratio
    };
    let mut close_of_track: BTreeMap<usize, usize> = BTreeMap::new();
    let mut close_of_meas: BTreeMap<MeasId, usize> = BTreeMap::new();
    for &(cost, k, m) in pairs {
        if close(cost, best_of_track[&k]) {
            *close_of_track.entry(k).or_default() += 1;
        }
        if close(cost, best_of_meas[&m]) {
            *close_of_meas.entry(m).or_default() += 1;
        }
    }
    if close_of_track
        .values()
        .chain(close_of_meas.values())
        .any(|&n| n > 1)
    {
        return true;
    }
    // A free measurement more than d̄ scans back cannot precede m on a track.
    let lookback = config.birth_lookback.min(partition.problem.max_gap());
    let could_start_a_track = |m: MeasId| {
        config.birth_lookback == 0
            || (1..=lookback).any(|d| {
                partition
                    .predecessors(m, d)
                    .iter()
                    .any(|&n| partition.is_free(n))
            })
    };
    partition
        .problem
        .scan(partition.hi)
        .iter()
        .any(|&m| !best_of_meas.contains_key(&m) && could_start_a_track(m))
}

/// Labels the new MAP's tracks: each takes the label of the previous track it shares the most
/// measurements with (each label used once, larger overlaps first); the rest get new labels.
fn relabel(
    previous: &[(u64, Vec<MeasId>)],
    tracks: Vec<Vec<MeasId>>,
    next_label: &mut u64,
) -> Vec<(u64, Vec<MeasId>)> {
    let owner: HashMap<MeasId, u64> = previous
        .iter()
        .flat_map(|(l, t)| t.iter().map(move |&m| (m, *l)))
        .collect();
    let mut overlaps: Vec<(usize, usize, u64)> = Vec::new();
    for (i, t) in tracks.iter().enumerate() {
        let mut count: BTreeMap<u64, usize> = BTreeMap::new();
        for m in t {
            if let Some(&l) = owner.get(m) {
                *count.entry(l).or_default() += 1;
            }
        }
        overlaps.extend(count.into_iter().map(|(l, n)| (n, i, l)));
    }
    // Larger overlaps first; ties by track then label, for determinism.
    overlaps.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut label_of: Vec<Option<u64>> = vec![None; tracks.len()];
    let mut used: Vec<u64> = Vec::new();
    for (_, i, l) in overlaps {
        if label_of[i].is_none() && !used.contains(&l) {
            label_of[i] = Some(l);
            used.push(l);
        }
    }
    tracks
        .into_iter()
        .zip(label_of)
        .map(|(t, l)| {
            let label = l.unwrap_or_else(|| {
                *next_label += 1;
                *next_label - 1
            });
            (label, t)
        })
        .collect()
}
