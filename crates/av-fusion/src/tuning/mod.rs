//! The searches behind the road scene's settings ([`crate::scene`]), run on tuning seeds
//! apart from any reported one: the coordinate search of [`Tuning`] behind the one
//! configuration every run uses, whatever its number of vehicles ([`tune_one_config`]), the
//! peak-score fit of [`ScoreFit`] ([`fit_peak_scores`]) and the multi-vehicle error breakdown
//! ([`diagnose`]).
//!
//! The searches take minutes; each line they measure goes to the caller's [`Log`] as it is
//! measured. They draw from the generators the caller seeded ([`Seeded`]): run `i` of a seed
//! is simulated from a clone of its generator on stream `i`, as the reported runs are.

use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Deserialize;
use tracker_model::Vec2;

use crate::error::invalid;
use crate::scene::{Approach, Params, RunSpec, Simulated, simulate_run};
use crate::{AvRun, Error, Result};

mod scores;
mod search;
#[cfg(test)]
mod tests;

pub use scores::{diagnose, fit_peak_scores, score_table};
pub use search::{SearchRow, objective, tune_one_config};

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

/// The search behind the one configuration ([`tune_one_config`]): for each approach on its
/// own, one coordinate at a time (each over its candidate list, the others held), by the
/// approach's [`objective`] over every run of the tuning seeds, one vehicle or several; rounds
/// over all coordinates repeat until one changes nothing (at most `max_rounds`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tuning {
    /// Tuning seeds (never reported, never fresh).
    pub seeds: Vec<u64>,
    /// The objective's price of a metre of mean single-vehicle error, in MOTA ([`objective`]).
    pub error_weight_per_m: f64,
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

/// The most rounds of [`Tuning`]'s search, and the most candidates of one coordinate.
pub const MAX_ROUNDS: usize = 20;
/// See [`MAX_ROUNDS`].
pub const MAX_CANDIDATES: usize = 64;

impl Tuning {
    /// Checks the search's shape: 1 to [`MAX_ROUNDS`] rounds, at most [`MAX_CANDIDATES`]
    /// finite candidates per coordinate, and a finite, non-negative error weight. (A candidate
    /// the scene rejects is an error when the search tries it.)
    pub fn check(&self) -> Result<()> {
        if !(1..=MAX_ROUNDS).contains(&self.max_rounds) {
            return Err(invalid(
                "max_rounds",
                format!("{}: 1 to {MAX_ROUNDS}", self.max_rounds),
            ));
        }
        if !(self.error_weight_per_m.is_finite() && self.error_weight_per_m >= 0.0) {
            return Err(invalid(
                "error_weight_per_m",
                format!("{}: must be finite and ≥ 0", self.error_weight_per_m),
            ));
        }
        // (name, candidates, all finite) of every coordinate; integer lists are finite.
        let lists: [(&'static str, usize, bool); 18] = [
            ("max_peaks", self.max_peaks.len(), true),
            ("max_gap", self.max_gap.len(), true),
            finite("lobe_power", &self.lobe_power),
            finite("lobe_fraction", &self.lobe_fraction),
            finite("audio_exponent", &self.audio_exponent),
            finite("video_exponent", &self.video_exponent),
            finite("video_weight", &self.video_weight),
            finite("relative_threshold_sum", &self.relative_threshold_sum),
            finite(
                "relative_threshold_product",
                &self.relative_threshold_product,
            ),
            finite("suppression_radius_m", &self.suppression_radius_m),
            finite("p_detect", &self.p_detect),
            finite("clutter_per_scan", &self.clutter_per_scan),
            finite("births_per_scan", &self.births_per_scan),
            finite("explain_away_deg", &self.explain_away_deg),
            finite("product_floor", &self.product_floor),
            finite("max_speed", &self.max_speed),
            finite("fade_full_weight_m", &self.fade_full_weight_m),
            finite("fade_power", &self.fade_power),
        ];
        for (name, n, all_finite) in lists {
            if n > MAX_CANDIDATES || !all_finite {
                return Err(invalid(
                    name,
                    format!("{n} candidates: at most {MAX_CANDIDATES}, all finite"),
                ));
            }
        }
        Ok(())
    }
}

/// A float coordinate's (name, candidates, all finite) for [`Tuning::check`].
fn finite(name: &'static str, values: &[f64]) -> (&'static str, usize, bool) {
    (name, values.len(), values.iter().all(|v| v.is_finite()))
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

/// The peaks of one or more runs against the vehicles ([`diagnose`]).
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

/// Every run (`runs`, single-vehicle passes then multi-vehicle runs) of every seed of
/// `seeded`, seed after seed, run i of a seed on stream i as the reported runs draw them.
fn simulate_all(p: &Params, runs: &[RunSpec], seeded: &Seeded) -> Result<Vec<Simulated>> {
    let mut sims = Vec::new();
    for (_, base) in seeded {
        let one: Vec<Simulated> = runs
            .par_iter()
            .enumerate()
            .map(|(i, run)| {
                let mut rng = base.clone();
                rng.set_stream(i as u64);
                simulate_run(p, run, &mut rng)
            })
            .collect::<Result<_>>()?;
        sims.extend(one);
    }
    Ok(sims)
}
