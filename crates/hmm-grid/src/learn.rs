//! Baum-Welch re-estimation over several observation sequences (Huynh & Vu 2006 eq. 12;
//! Rabiner 1989 §V.B for multiple sequences), with frozen components, pseudo-counts and a
//! parallel E-step.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use tracker_model::ensure_non_negative;

use crate::error::{Error, Result};
use crate::inference::{backward_with_xi, forward_in};
use crate::model::Hmm;

/// Which parts of λ stay fixed during training; frozen parts come out bit-identical.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Freeze {
    /// Keep π.
    pub initial: bool,
    /// Keep A.
    pub transitions: bool,
    /// Keep B.
    pub emissions: bool,
}

/// Dirichlet pseudo-counts added to the expected counts before normalising (MAP estimation).
/// Transition pseudo-counts go only to transitions the model allows (a_ij > 0), so kinematic
/// constraints survive training; initial and emission pseudo-counts smooth every entry.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PseudoCounts {
    /// Added to each π_i count (≥ 0).
    pub initial: f64,
    /// Added to each allowed a_ij count (≥ 0).
    pub transitions: f64,
    /// Added to each b_i(m) count (≥ 0).
    pub emissions: f64,
}

/// Baum-Welch settings, checked once into a [`BaumWelch`] trainer by
/// [`BaumWelchConfig::check`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BaumWelchConfig {
    /// Upper bound on re-estimation steps.
    pub max_iterations: usize,
    /// Stop when the total log-likelihood changes by less than this (absolute, ≥ 0).
    pub tolerance: f64,
    /// Also stop when the change is at most this fraction of the log-likelihood,
    /// |ΔLL| ≤ rel · |LL| (≥ 0; 0 turns it off). The absolute tolerance alone never triggers on
    /// large training sets: the log-likelihood grows with the number of steps, and EM's late
    /// steps shrink only linearly (Dempster, Laird & Rubin 1977), so a fixed absolute change
    /// is reached ever later; a relative one scales with the data.
    pub relative_tolerance: f64,
    /// Frozen components.
    pub freeze: Freeze,
    /// Pseudo-counts.
    pub pseudo_counts: PseudoCounts,
}

impl Default for BaumWelchConfig {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            tolerance: 1e-6,
            relative_tolerance: 0.0,
            freeze: Freeze::default(),
            pseudo_counts: PseudoCounts::default(),
        }
    }
}

impl BaumWelchConfig {
    /// Checks every field (the tolerance and the pseudo-counts must be finite and ≥ 0) and
    /// returns the trainer that runs with them.
    pub fn check(&self) -> Result<BaumWelch> {
        ensure_non_negative(self.tolerance, "tolerance")?;
        ensure_non_negative(self.relative_tolerance, "relative_tolerance")?;
        let pc = self.pseudo_counts;
        ensure_non_negative(pc.initial, "pseudo_counts.initial")?;
        ensure_non_negative(pc.transitions, "pseudo_counts.transitions")?;
        ensure_non_negative(pc.emissions, "pseudo_counts.emissions")?;
        Ok(BaumWelch { config: *self })
    }
}

/// A Baum-Welch trainer with a checked [`BaumWelchConfig`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaumWelch {
    config: BaumWelchConfig,
}

/// How training went.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitReport {
    /// Total log-likelihood of the training sequences under each successive model, the initial
    /// one first and the returned one last.
    pub log_likelihoods: Vec<f64>,
    /// Whether the change fell below the absolute or the relative tolerance within
    /// `max_iterations`.
    pub converged: bool,
}

impl FitReport {
    /// Re-estimation steps taken (M-steps).
    pub fn iterations(&self) -> usize {
        self.log_likelihoods.len().saturating_sub(1)
    }
}

/// Expected counts of one sequence (the E-step), or of several summed.
#[derive(Debug, Clone)]
struct Stats {
    log_likelihood: f64,
    /// γ_1(i).
    initial: Vec<f64>,
    /// Σ_t ξ_t per stored transition entry.
    xi: Vec<f64>,
    /// Σ_t γ_t(i) [o_t = m], by symbol (M × N, row m holding state i at i): each step adds
    /// to one contiguous row instead of N entries a row of B apart.
    emissions: Vec<f64>,
}

impl Stats {
    fn zeros(hmm: &Hmm) -> Self {
        Self {
            log_likelihood: 0.0,
            initial: vec![0.0; hmm.n_states()],
            xi: vec![0.0; hmm.transitions().n_stored()],
            emissions: vec![0.0; hmm.n_states() * hmm.n_symbols()],
        }
    }

    fn add(&mut self, o: &Stats) {
        self.log_likelihood += o.log_likelihood;
        for (a, b) in [
            (&mut self.initial, &o.initial),
            (&mut self.xi, &o.xi),
            (&mut self.emissions, &o.emissions),
        ] {
            a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
        }
    }
}

fn e_step(hmm: &Hmm, obs: &[usize], sequence: usize) -> Result<Stats> {
    let n = hmm.n_states();
    let f = forward_in(hmm, obs, sequence)?;
    let mut s = Stats::zeros(hmm);
    s.log_likelihood = f.log_likelihood;
    let Stats {
        initial,
        xi,
        emissions,
        ..
    } = &mut s;
    backward_with_xi(hmm, obs, &f, xi, |t, beta| {
        let alpha_t = &f.alpha[t * n..(t + 1) * n];
        // γ_t adds to the contiguous row of symbol o_t.
        let o = obs[t];
        let counts = &mut emissions[o * n..(o + 1) * n];
        for ((c, a), b) in counts.iter_mut().zip(alpha_t).zip(beta) {
            *c += a * b;
        }
        if t == 0 {
            for ((p, a), b) in initial.iter_mut().zip(alpha_t).zip(beta) {
                *p = a * b;
            }
        }
    });
    Ok(s)
}

/// Sums the E-step over all sequences: in parallel, then reduced in sequence order so the
/// result does not depend on the number of threads.
fn expected_counts(hmm: &Hmm, sequences: &[Vec<usize>]) -> Result<Stats> {
    let per_sequence: Vec<Stats> = sequences
        .par_iter()
        .enumerate()
        .map(|(k, obs)| e_step(hmm, obs, k))
        .collect::<Result<_>>()?;
    // The first sequence's counts are the start of the sum (0 + x = x, so this is the sum
    // from zero without a pass over N·M zeros).
    let mut per_sequence = per_sequence.into_iter();
    let mut total = per_sequence.next().unwrap_or_else(|| Stats::zeros(hmm));
    per_sequence.for_each(|s| total.add(&s));
    Ok(total)
}

/// Normalises `counts + pseudo` (pseudo only where `allowed`) into a probability row; a row with
/// no evidence keeps `old`.
fn renormalise(counts: &[f64], old: &[f64], pseudo: f64, only_allowed: bool) -> Vec<f64> {
    let padded: Vec<f64> = counts
        .iter()
        .zip(old)
        .map(|(c, o)| {
            if only_allowed && *o == 0.0 {
                0.0
            } else {
                c + pseudo
            }
        })
        .collect();
    let total: f64 = padded.iter().sum();
    if total > 0.0 {
        padded.iter().map(|v| v / total).collect()
    } else {
        old.to_vec()
    }
}

fn m_step(hmm: &Hmm, stats: &Stats, cfg: &BaumWelchConfig) -> Result<Hmm> {
    let n = hmm.n_states();
    let m = hmm.n_symbols();
    let pc = cfg.pseudo_counts;
    let initial = if cfg.freeze.initial {
        hmm.initial().to_vec()
    } else {
        renormalise(&stats.initial, hmm.initial(), pc.initial, false)
    };
    let transitions = if cfg.freeze.transitions {
        hmm.transitions().clone()
    } else {
        let a = hmm.transitions();
        let mut values = a.values().to_vec();
        for i in 0..n {
            let range = a.row_range(i);
            let row = renormalise(
                &stats.xi[range.clone()],
                &a.values()[range.clone()],
                pc.transitions,
                true,
            );
            values[range].copy_from_slice(&row);
        }
        a.with_values(values)?
    };
    let emissions = if cfg.freeze.emissions {
        hmm.emissions().to_vec()
    } else {
        let mut out = Vec::with_capacity(n * m);
        let mut counts = vec![0.0; m];
        for i in 0..n {
            for (c, by_symbol) in counts.iter_mut().zip(stats.emissions.chunks_exact(n)) {
                *c = by_symbol[i];
            }
            out.extend(renormalise(
                &counts,
                &hmm.emissions()[i * m..(i + 1) * m],
                pc.emissions,
                false,
            ));
        }
        out
    };
    Hmm::new(initial, transitions, emissions, m)
}

impl BaumWelch {
    /// The settings it runs with.
    pub fn config(&self) -> &BaumWelchConfig {
        &self.config
    }

    /// Trains `hmm` on `sequences` and returns the trained model with the log-likelihood
    /// history. Without pseudo-counts the history never decreases (EM).
    pub fn fit(&self, hmm: &Hmm, sequences: &[Vec<usize>]) -> Result<(Hmm, FitReport)> {
        let config = &self.config;
        if sequences.is_empty() {
            return Err(Error::Empty("training sequences"));
        }
        for (k, obs) in sequences.iter().enumerate() {
            hmm.check_observations(obs, k)?;
        }
        let mut model = hmm.clone();
        let mut history = Vec::new();
        let mut stats = expected_counts(&model, sequences)?;
        history.push(stats.log_likelihood);
        let mut converged = false;
        for _ in 0..config.max_iterations {
            let next = m_step(&model, &stats, config)?;
            let next_stats = expected_counts(&next, sequences)?;
            let gain = next_stats.log_likelihood - stats.log_likelihood;
            model = next;
            stats = next_stats;
            history.push(stats.log_likelihood);
            if gain.abs() < config.tolerance
                || (config.relative_tolerance > 0.0
                    && gain.abs() <= config.relative_tolerance * stats.log_likelihood.abs())
            {
                converged = true;
                break;
            }
        }
        Ok((
            model,
            FitReport {
                log_likelihoods: history,
                converged,
            },
        ))
    }
}

/// Trains `hmm` on `sequences` by Baum-Welch: `config.check()?.fit(hmm, sequences)`.
pub fn baum_welch(
    hmm: &Hmm,
    sequences: &[Vec<usize>],
    config: &BaumWelchConfig,
) -> Result<(Hmm, FitReport)> {
    config.check()?.fit(hmm, sequences)
}
