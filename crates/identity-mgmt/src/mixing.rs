//! Mixing matrices: m_ij = P(track piece j after an interaction continues piece i before it)
//! (Hwang et al. 2004's identity-mass flow; Oh, Hwang & Sastry 2008 take m_ij from MCMCDA
//! samples). Plain data in, so this crate needs no tracker.

use serde::{Deserialize, Serialize};
use tracker_model::{Error as ModelError, ensure_non_negative};

use crate::error::{Error, Result};
use crate::scaling::{ScalingConfig, SinkhornReport, check_entries, check_len, scale_to_marginals};

/// Largest deviation of a row or column sum from 1 that [`Continuation::new`] accepts.
pub const DOUBLY_STOCHASTIC_TOLERANCE: f64 = 1e-6;

/// A doubly stochastic n × n continuation matrix (row-major). Rows sum to 1 so identity mass
/// is conserved; columns sum to 1 so the columns of B·M stay probability vectors.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "ContinuationData")]
pub struct Continuation {
    n: usize,
    data: Vec<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ContinuationData {
    n: usize,
    data: Vec<f64>,
}

impl TryFrom<ContinuationData> for Continuation {
    type Error = Error;
    fn try_from(d: ContinuationData) -> Result<Self> {
        Continuation::new(d.n, d.data)
    }
}

/// Where the mass of a pre-interaction piece goes in the samples where it is joined to no
/// post-interaction piece.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum UnjoinedRule {
    /// Spread uniformly over the post-interaction pieces: the sample says nothing about which
    /// piece continues it.
    #[default]
    Uniform,
    /// Keep it on the piece with the same index (no evidence of a swap).
    Stay,
}

/// How [`Continuation::from_samples`] turns join counts into a doubly stochastic matrix.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FromSamplesConfig {
    /// Where unjoined mass goes.
    pub unjoined: UnjoinedRule,
    /// A count added to every (i, j) before normalising (0: none). Positive values make M
    /// positive, hence always exactly scalable, at the price of leaking identity mass.
    pub pseudo_count: f64,
    /// The final scaling to doubly stochastic.
    pub scaling: ScalingConfig,
}

impl Default for FromSamplesConfig {
    fn default() -> Self {
        Self {
            unjoined: UnjoinedRule::Uniform,
            pseudo_count: 0.0,
            scaling: ScalingConfig::default(),
        }
    }
}

impl FromSamplesConfig {
    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        ensure_non_negative(self.pseudo_count, "from_samples.pseudo_count")?;
        self.scaling.check()
    }
}

impl Continuation {
    /// Checks that `data` (row-major n × n) is non-negative and doubly stochastic within
    /// [`DOUBLY_STOCHASTIC_TOLERANCE`].
    pub fn new(n: usize, data: Vec<f64>) -> Result<Self> {
        check_len("continuation matrix", data.len(), n * n)?;
        check_entries("continuation matrix", &data, n.max(1))?;
        let mut max_error = 0.0_f64;
        for i in 0..n {
            let row: f64 = data[i * n..(i + 1) * n].iter().sum();
            let col: f64 = (0..n).map(|k| data[k * n + i]).sum();
            max_error = max_error.max((row - 1.0).abs()).max((col - 1.0).abs());
        }
        if max_error > DOUBLY_STOCHASTIC_TOLERANCE {
            return Err(Error::NotDoublyStochastic {
                what: "continuation matrix",
                max_error,
            });
        }
        Ok(Self { n, data })
    }

    /// No ambiguity: every piece continues itself.
    pub fn identity(n: usize) -> Self {
        let mut data = vec![0.0; n * n];
        for i in 0..n {
            data[i * n + i] = 1.0;
        }
        Self { n, data }
    }

    /// Builds M from MCMC samples. `samples[s]` lists the pairs (i, j) such that, in sample
    /// s, pre-interaction piece i and post-interaction piece j lie on the same track (each
    /// piece at most once per sample). m_ij starts as the fraction of samples joining i to
    /// j; unjoined mass follows `config.unjoined`; `config.pseudo_count` is added; then the
    /// matrix is Sinkhorn-scaled to doubly stochastic (the report is returned). A pattern
    /// that cannot be scaled is [`Error::NotScalable`].
    ///
    /// ```
    /// use identity_mgmt::{Continuation, FromSamplesConfig};
    /// // Two pieces; 3 of 4 samples keep them apart, 1 swaps them.
    /// let samples = vec![vec![(0, 0), (1, 1)]; 3].into_iter()
    ///     .chain([vec![(0, 1), (1, 0)]]).collect::<Vec<_>>();
    /// let (m, _) = Continuation::from_samples(2, &samples, &FromSamplesConfig::default())?;
    /// assert!((m.get(0, 0) - 0.75).abs() < 1e-12 && (m.get(0, 1) - 0.25).abs() < 1e-12);
    /// # Ok::<(), identity_mgmt::Error>(())
    /// ```
    pub fn from_samples(
        n: usize,
        samples: &[Vec<(usize, usize)>],
        config: &FromSamplesConfig,
    ) -> Result<(Self, SinkhornReport)> {
        config.check()?;
        if samples.is_empty() {
            return Err(ModelError::Empty {
                what: "MCMC samples",
            }
            .into());
        }
        let mut counts = vec![0.0; n * n];
        let mut unjoined = vec![0.0; n];
        for (s, pairs) in samples.iter().enumerate() {
            let mut pre_seen = vec![false; n];
            let mut post_seen = vec![false; n];
            for &(i, j) in pairs {
                if i >= n || j >= n {
                    return Err(Error::BadSample {
                        sample: s,
                        reason: format!("pair ({i}, {j}) outside {n} pieces"),
                    });
                }
                if pre_seen[i] || post_seen[j] {
                    return Err(Error::BadSample {
                        sample: s,
                        reason: format!("pair ({i}, {j}) reuses a piece"),
                    });
                }
                pre_seen[i] = true;
                post_seen[j] = true;
                counts[i * n + j] += 1.0;
            }
            for (u, seen) in unjoined.iter_mut().zip(pre_seen) {
                if !seen {
                    *u += 1.0;
                }
            }
        }
        for i in 0..n {
            match config.unjoined {
                UnjoinedRule::Uniform => {
                    for j in 0..n {
                        counts[i * n + j] += unjoined[i] / n as f64;
                    }
                }
                UnjoinedRule::Stay => counts[i * n + i] += unjoined[i],
            }
        }
        let total = samples.len() as f64 + n as f64 * config.pseudo_count;
        let mut data: Vec<f64> = counts
            .iter()
            .map(|c| (c + config.pseudo_count) / total)
            .collect();
        let ones = vec![1.0; n];
        let report = scale_to_marginals(&mut data, n, n, &ones, &ones, &config.scaling)?;
        Ok((Self { n, data }, report.sinkhorn))
    }

    /// Number of pieces on each side.
    pub fn n(&self) -> usize {
        self.n
    }

    /// m_ij.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.data[i * self.n + j]
    }

    /// The row-major entries.
    pub fn as_row_major(&self) -> &[f64] {
        &self.data
    }
}
