//! The searches behind the road scene's settings ([`crate::scene`]), run on tuning seeds
//! apart from any reported one: the single-vehicle grid search of [`Tuning`] ([`tune`]), the
//! multi-vehicle coordinate search of [`MultiTuning`] ([`tune_multi`]), the peak-score fit of
//! [`ScoreFit`] ([`fit_peak_scores`]) and the multi-vehicle error breakdown ([`diagnose`]).
//!
//! The searches take minutes; each line they measure goes to the caller's [`Log`] as it is
//! measured, and the choices come out as lines of TOML to paste into the configuration. They
//! draw from the generators the caller seeded ([`Seeded`]): run `i` of a seed is simulated from
//! a clone of its generator on stream `i`, as the reported runs are.

use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Deserialize;
use tracker_model::Vec2;

use crate::scene::{
    Approach, Params, RunSpec, Score, Simulated, nominal, score_with, simulate_run,
};
use crate::{AvRun, Error, Result};

mod multi;
mod scores;
mod single;
#[cfg(test)]
mod tests;

pub use multi::tune_multi;
pub use scores::{diagnose, fit_peak_scores, score_table};
pub use single::{BearingError, bearing_errors, stage1_choice, tune};

/// Where a search's lines go, one at a time as they are measured: any `Fn(&str) + Sync`, such
/// as a closure that prints them.
pub trait Log: Sync {
    /// One line (or table) of output.
    fn say(&self, text: &str);
}

impl<F: Fn(&str) + Sync> Log for F {
    fn say(&self, text: &str) {
        self(text);
    }
}

/// A search's seeds, each with the generator the caller seeded from it (the generator the
/// reported runs of that seed draw from, so that run `i` of a seed is simulated as it would
/// be reported).
pub type Seeded = [(u64, ChaCha8Rng)];

/// The single-vehicle grid search behind [`Params::settings`]: each approach's fusion
/// weights, peak extraction and tracker model ([`tune`]).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tuning {
    /// Tuning seeds (the reported seed must not be among them).
    pub seeds: Vec<u64>,
    /// Candidate video weights (audio weight 1) of the audio+video approaches.
    pub video_weight: Vec<f64>,
    /// Candidate profile exponents γ of the acoustic nodes.
    pub audio_exponent: Vec<f64>,
    /// Candidate profile exponents γ of the cameras.
    pub video_exponent: Vec<f64>,
    /// Candidate product floors ε.
    pub product_floor: Vec<f64>,
    /// Candidate relative thresholds κ of the weighted sum's peaks.
    pub relative_threshold_sum: Vec<f64>,
    /// Candidate relative thresholds κ of the product's peaks.
    pub relative_threshold_product: Vec<f64>,
    /// Candidate NMS radii, m.
    pub suppression_radius_m: Vec<f64>,
    /// Candidate MCMCDA detection probabilities.
    pub p_detect: Vec<f64>,
    /// Candidate MCMCDA clutter rates per scan.
    pub clutter_per_scan: Vec<f64>,
    /// Stage 1 takes, among the candidates whose error is within this fraction of the lowest,
    /// the one with the highest MOTA.
    pub error_tolerance: f64,
    /// The stages are repeated until a round leaves the approach's settings unchanged, at most
    /// this many rounds.
    pub max_rounds: usize,
}

/// The search behind [`Params::multi_settings`] ([`tune_multi`]): for each approach on its
/// own, from its configured multi-vehicle settings, one coordinate at a time (each over its
/// candidate list, the others held), by the approach's mean MOTA over the multi-vehicle runs
/// of the tuning seeds; rounds over all coordinates repeat until one changes nothing (at most
/// `max_rounds`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MultiTuning {
    /// Tuning seeds (the reported seed must not be among them).
    pub seeds: Vec<u64>,
    /// Candidate lobe equalisation powers β of each modality (0: off).
    pub lobe_power: Vec<f64>,
    /// Candidate lobe equalisation fractions η.
    pub lobe_fraction: Vec<f64>,
    /// Candidate profile exponents γ of the acoustic nodes.
    pub audio_exponent: Vec<f64>,
    /// Candidate profile exponents γ of the cameras.
    pub video_exponent: Vec<f64>,
    /// Candidate video weights of the audio+video approaches.
    pub video_weight: Vec<f64>,
    /// Candidate relative thresholds κ of the weighted sum's peaks.
    pub relative_threshold_sum: Vec<f64>,
    /// Candidate relative thresholds κ of the product's peaks.
    pub relative_threshold_product: Vec<f64>,
    /// Candidate NMS radii, m.
    pub suppression_radius_m: Vec<f64>,
    /// Candidate MCMCDA detection probabilities.
    pub p_detect: Vec<f64>,
    /// Candidate MCMCDA clutter rates per scan.
    pub clutter_per_scan: Vec<f64>,
    /// Candidate MCMCDA birth rates per scan.
    pub births_per_scan: Vec<f64>,
    /// Candidate explaining-away notch widths σ, degrees (0: off).
    pub explain_away_deg: Vec<f64>,
    /// Candidate product floors ε.
    pub product_floor: Vec<f64>,
    /// Candidate peaks per scan.
    pub max_peaks: Vec<usize>,
    /// Candidate MCMCDA speed limits v̄, m/s.
    pub max_speed: Vec<f64>,
    /// Candidate MCMCDA largest gaps d̄, scans.
    pub max_gap: Vec<u32>,
    /// Candidate range fade distances r₀, m (0: off).
    pub fade_full_weight_m: Vec<f64>,
    /// Candidate range fade powers q.
    pub fade_power: Vec<f64>,
    /// At most this many rounds.
    pub max_rounds: usize,
}

/// How the peak-score tables of [`Params::multi_peak_scores`] are learnt
/// ([`fit_peak_scores`]).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScoreFit {
    /// Tuning seeds (never the reported one).
    pub seeds: Vec<u64>,
    /// Peaks per tick while learning (≥ the largest `max_peaks` the search may choose, so
    /// the table covers the weak peaks too).
    pub max_peaks: usize,
    /// Bins of the table (edges at the pooled contrasts' quantiles).
    pub bins: usize,
    /// A peak within this distance of a vehicle at its tick counts as the vehicle's.
    pub near_m: f64,
}

/// Averages of one setting over the tuning runs: mean error over the single-vehicle passes (a
/// pass without a track counts as the match distance) and mean MOTA over all runs.
#[derive(Debug, Clone, Copy)]
pub struct TuneScore {
    /// Mean error over the single-vehicle passes, m.
    pub error_m: f64,
    /// Mean MOTA over every run.
    pub mota: f64,
    /// Mean MOTA over the multi-vehicle runs.
    pub multi_mota: f64,
    /// Multi-vehicle runs: the fraction of (vehicle, tick) pairs with a peak within 2 m (is a
    /// miss the peaks' fault?).
    pub peak_recall: f64,
    /// Multi-vehicle runs: peaks per tick farther than 2 m from every vehicle.
    pub false_peaks: f64,
}

/// The peaks of one or more runs against the vehicles (see [`TuneScore`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct PeakCounts {
    /// (Vehicle, tick) pairs.
    pairs: usize,
    /// Pairs with a peak within 2 m.
    found: usize,
    /// Peaks farther than 2 m from every vehicle.
    false_peaks: usize,
    /// Ticks.
    ticks: usize,
}

impl std::ops::AddAssign for PeakCounts {
    fn add_assign(&mut self, c: PeakCounts) {
        self.pairs += c.pairs;
        self.found += c.found;
        self.false_peaks += c.false_peaks;
        self.ticks += c.ticks;
    }
}

/// The [`PeakCounts`] of a run.
fn peak_counts(sim: &Simulated, run: &AvRun) -> PeakCounts {
    let (mut pairs, mut found, mut false_peaks) = (0, 0, 0);
    for scan in &run.scans {
        let truth = vehicles_at(sim, scan.tick);
        pairs += truth.len();
        found += truth
            .iter()
            .filter(|v| scan.peaks.iter().any(|q| (q.position - *v).norm() <= 2.0))
            .count();
        false_peaks += scan
            .peaks
            .iter()
            .filter(|q| truth.iter().all(|v| (q.position - v).norm() > 2.0))
            .count();
    }
    PeakCounts {
        pairs,
        found,
        false_peaks,
        ticks: run.scans.len(),
    }
}

/// The true positions of the vehicles present at tick `tick`.
fn vehicles_at(sim: &Simulated, tick: u64) -> Vec<Vec2> {
    sim.gt
        .tracks()
        .iter()
        .filter_map(|t| {
            t.points()
                .iter()
                .find(|q| u64::from(q.frame) == tick)
                .map(|q| q.location.position())
        })
        .collect()
}

/// Approach `a`'s [`TuneScore`] with its single-vehicle settings on every run of `sims`
/// ((multi-vehicle, run)).
pub fn tune_score(p: &Params, sims: &[(bool, Simulated)], a: Approach) -> Result<TuneScore> {
    let scores: Vec<(bool, Score)> = sims
        .par_iter()
        // The single-vehicle settings on every run (the search of `Params::tuning`).
        .map(|(multi, sim)| {
            Ok((
                *multi,
                score_with(p, sim, nominal(p), a, p.settings.get(a), None)?,
            ))
        })
        .collect::<Result<_>>()?;
    let single: Vec<f64> = scores
        .iter()
        .filter(|(m, _)| !m)
        .flat_map(|(_, s)| s.errors.iter().map(|e| e.unwrap_or(p.match_distance_m)))
        .collect();
    let multi: Vec<f64> = scores
        .iter()
        .filter(|(m, _)| *m)
        .map(|(_, s)| s.mota)
        .collect();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let mut counts = PeakCounts::default();
    for ((multi, sim), (_, s)) in sims.iter().zip(&scores) {
        if *multi {
            counts += peak_counts(sim, &s.result);
        }
    }
    Ok(TuneScore {
        error_m: mean(&single),
        mota: mean(&scores.iter().map(|(_, s)| s.mota).collect::<Vec<_>>()),
        multi_mota: mean(&multi),
        peak_recall: counts.found as f64 / counts.pairs.max(1) as f64,
        false_peaks: counts.false_peaks as f64 / counts.ticks.max(1) as f64,
    })
}

/// The approaches named by a developer's list: `all`, or comma-separated items each an index
/// into [`Approach::ALL`] or an approach's [`settings_key`](Approach::settings_key)
/// (`5, audio_sum`), in the list's order.
pub fn approaches_in(which: &str) -> Result<Vec<Approach>> {
    if which.trim() == "all" {
        return Ok(Approach::ALL.to_vec());
    }
    which
        .split(',')
        .map(|s| {
            let item = s.trim();
            let found = match item.parse::<usize>() {
                Ok(i) => Approach::from_index(i),
                Err(_) => Approach::from_settings_key(item),
            };
            found.ok_or_else(|| Error::ApproachListItem {
                given: s.to_string(),
                n_approaches: Approach::ALL.len(),
                known: Approach::ALL.map(Approach::settings_key).join(", "),
            })
        })
        .collect()
}

/// The multi-vehicle runs (`runs` after the single-vehicle passes) simulated from the
/// generator `base`, run i on stream `n_passes + i` as the reported runs draw them.
fn simulate_multi(p: &Params, runs: &[RunSpec], base: &ChaCha8Rng) -> Result<Vec<Simulated>> {
    let n_passes = p.passes.len();
    runs[n_passes..]
        .par_iter()
        .enumerate()
        .map(|(i, run)| {
            let mut rng = base.clone();
            rng.set_stream((n_passes + i) as u64);
            simulate_run(p, run, &mut rng)
        })
        .collect()
}

/// The multi-vehicle runs of every seed of `seeded`, seed after seed.
fn simulate_multi_all(p: &Params, runs: &[RunSpec], seeded: &Seeded) -> Result<Vec<Simulated>> {
    let mut sims = Vec::new();
    for (_, base) in seeded {
        sims.extend(simulate_multi(p, runs, base)?);
    }
    Ok(sims)
}
