//! Entropy, Kullback-Leibler divergence, and the fusion of two beliefs about one physical
//! track (Hwang, Roy, Balakrishnan & Tomlin 2004 name the Shannon, Chernoff and KL-sum
//! criteria and a Bayesian fusion; the formulas follow Hurley's (2002) information-theoretic
//! fusion over the geometric-mixture family
//! r_ω(i) = p(i)^ω q(i)^{1−ω} / Σ_k p(k)^ω q(k)^{1−ω}, ω ∈ [0, 1]; see
//! `docs/identity.md` for which parts are reconstructed).

use serde::{Deserialize, Serialize};
use tracker_model::{Error as ModelError, ensure_positive};

use crate::error::{Error, Result};
use crate::scaling::{check_entries, check_len};

/// The unit of an entropy.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EntropyUnit {
    /// Natural logarithm (the unit of the paper's 2.9091 → 2.3602, see `docs/identity.md`).
    #[default]
    Nats,
    /// Base-2 logarithm.
    Bits,
}

impl EntropyUnit {
    /// Divisor that turns nats into this unit.
    fn per_nat(self) -> f64 {
        match self {
            EntropyUnit::Nats => 1.0,
            EntropyUnit::Bits => std::f64::consts::LN_2,
        }
    }
}

/// Shannon entropy −Σ p log p of a (not necessarily normalised) non-negative vector, with
/// 0 log 0 = 0.
pub fn entropy(p: &[f64], unit: EntropyUnit) -> f64 {
    -p.iter()
        .filter(|&&v| v > 0.0)
        .map(|&v| v * v.ln())
        .sum::<f64>()
        / unit.per_nat()
}

/// D(p‖q) = Σ p log(p/q) in nats; +∞ if p puts mass where q has none.
pub fn kl_divergence(p: &[f64], q: &[f64]) -> f64 {
    p.iter()
        .zip(q)
        .filter(|&(&a, _)| a > 0.0)
        .map(|(&a, &b)| {
            if b > 0.0 {
                a * (a / b).ln()
            } else {
                f64::INFINITY
            }
        })
        .sum()
}

/// The fusion criterion.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub enum FusionCriterion {
    /// The member of the geometric family with the least entropy (the most Shannon
    /// information log N − H): a grid over ω, refined by golden-section search.
    Shannon,
    /// The member of the geometric family equally far, in D(r‖·), from both inputs: the
    /// Chernoff point, found by bisection on D(r_ω‖p) − D(r_ω‖q), which decreases in ω.
    #[default]
    Chernoff,
    /// argmin_r D(r‖p) + D(r‖q): the normalised geometric mean (ω = 1/2).
    KlSumGeometric,
    /// argmin_r D(p‖r) + D(q‖r), the other argument order: the arithmetic mean.
    KlSumArithmetic,
    /// Independent evidence with a shared prior π: r ∝ p·q/π. `None` is the uniform prior
    /// (r ∝ p·q).
    Bayesian {
        /// The prior over identities; must be positive wherever p·q is.
        prior: Option<Vec<f64>>,
    },
}

/// The criterion and the numerical settings of the searches.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FusionConfig {
    /// Which criterion.
    pub criterion: FusionCriterion,
    /// Points of the initial ω grid for the Shannon criterion (its entropy need not be
    /// unimodal in ω), at least 3.
    pub grid_points: usize,
    /// Width in ω at which golden-section search and bisection stop.
    pub omega_tolerance: f64,
}

impl Default for FusionConfig {
    fn default() -> Self {
        Self {
            criterion: FusionCriterion::default(),
            grid_points: 101,
            omega_tolerance: 1e-12,
        }
    }
}

impl FusionConfig {
    /// Checks the numerical settings and the prior.
    pub fn check(&self) -> Result<()> {
        if self.grid_points < 3 {
            return Err(ModelError::InvalidParameter {
                name: "fusion.grid_points",
                reason: format!("{} is fewer than 3", self.grid_points),
            }
            .into());
        }
        ensure_positive(self.omega_tolerance, "fusion.omega_tolerance")?;
        if let FusionCriterion::Bayesian { prior: Some(prior) } = &self.criterion {
            check_entries("fusion prior", prior, 1)?;
        }
        Ok(())
    }
}

/// A fused distribution and, for the geometric-family criteria, the ω chosen.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fused {
    /// The fused probability vector.
    pub distribution: Vec<f64>,
    /// ω of r_ω for Shannon, Chernoff and the geometric KL sum (1/2); `None` otherwise.
    pub omega: Option<f64>,
}

/// r_ω ∝ p^ω q^{1−ω}, computed in log space; `None` if the normaliser is 0 (disjoint
/// supports, for ω ∈ (0, 1)).
pub fn geometric_mixture(p: &[f64], q: &[f64], omega: f64) -> Option<Vec<f64>> {
    let logs: Vec<f64> = p
        .iter()
        .zip(q)
        .map(|(&a, &b)| {
            // At the ends the family is p or q itself, whatever the other's zeros.
            if omega >= 1.0 {
                a.ln()
            } else if omega <= 0.0 {
                b.ln()
            } else {
                omega * a.ln() + (1.0 - omega) * b.ln()
            }
        })
        .collect();
    normalise_logs(&logs)
}

fn normalise_logs(logs: &[f64]) -> Option<Vec<f64>> {
    let max = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !max.is_finite() {
        return None;
    }
    let w: Vec<f64> = logs.iter().map(|l| (l - max).exp()).collect();
    let s: f64 = w.iter().sum();
    Some(w.into_iter().map(|v| v / s).collect())
}

/// Checks a probability vector: finite, non-negative, sum 1 within 1e-6 (beliefs come from
/// sums of many products).
pub(crate) fn check_probability(what: &'static str, p: &[f64]) -> Result<()> {
    check_entries(what, p, 1)?;
    let sum: f64 = p.iter().sum();
    if (sum - 1.0).abs() > 1e-6 {
        return Err(Error::NotProbability { what, sum });
    }
    Ok(())
}

/// Fuses two beliefs p and q over the same identities by `config.criterion`.
///
/// ```
/// use identity_mgmt::{fuse, FusionConfig, FusionCriterion};
/// let config = FusionConfig { criterion: FusionCriterion::KlSumArithmetic, ..Default::default() };
/// let r = fuse(&[0.8, 0.2], &[0.4, 0.6], &config)?;
/// assert!((r.distribution[0] - 0.6).abs() < 1e-12);
/// # Ok::<(), identity_mgmt::Error>(())
/// ```
pub fn fuse(p: &[f64], q: &[f64], config: &FusionConfig) -> Result<Fused> {
    config.check()?;
    check_len("second belief", q.len(), p.len())?;
    check_probability("first belief", p)?;
    check_probability("second belief", q)?;
    let at = |omega: f64| geometric_mixture(p, q, omega).ok_or(Error::DisjointSupports);
    // Every geometric criterion looks inside (0, 1), where the support is p's ∩ q's.
    if geometric_mixture(p, q, 0.5).is_none() {
        return Err(Error::DisjointSupports);
    }
    match &config.criterion {
        FusionCriterion::KlSumGeometric => Ok(Fused {
            distribution: at(0.5)?,
            omega: Some(0.5),
        }),
        FusionCriterion::KlSumArithmetic => Ok(Fused {
            distribution: p.iter().zip(q).map(|(a, b)| 0.5 * (a + b)).collect(),
            omega: None,
        }),
        FusionCriterion::Bayesian { prior } => Ok(Fused {
            distribution: bayesian(p, q, prior.as_deref())?,
            omega: None,
        }),
        FusionCriterion::Chernoff => {
            let omega = chernoff_omega(p, q, config.omega_tolerance)?;
            Ok(Fused {
                distribution: at(omega)?,
                omega: Some(omega),
            })
        }
        FusionCriterion::Shannon => {
            let omega = shannon_omega(p, q, config)?;
            Ok(Fused {
                distribution: at(omega)?,
                omega: Some(omega),
            })
        }
    }
}

/// Bayesian fusion of two beliefs from a common prior (the independent-likelihood pool):
/// r ∝ p q / prior, computed in logarithms and normalised ([`normalise_logs`]). The prior
/// defaults to uniform; it must be positive wherever both beliefs are.
fn bayesian(p: &[f64], q: &[f64], prior: Option<&[f64]>) -> Result<Vec<f64>> {
    let n = p.len();
    let uniform = vec![1.0 / n as f64; n];
    let prior = prior.unwrap_or(&uniform);
    check_len("fusion prior", prior.len(), n)?;
    let mut logs = Vec::with_capacity(n);
    for k in 0..n {
        let evidence = p[k] * q[k];
        if evidence > 0.0 && prior[k] <= 0.0 {
            return Err(Error::InvalidEntry {
                what: "fusion prior (zero where both beliefs are positive)",
                row: k,
                col: 0,
                value: prior[k],
            });
        }
        logs.push(if evidence > 0.0 {
            p[k].ln() + q[k].ln() - prior[k].ln()
        } else {
            f64::NEG_INFINITY
        });
    }
    normalise_logs(&logs).ok_or(Error::DisjointSupports)
}

/// The weight ω of the geometric mixture r_ω ∝ p^ω q^{1−ω} ([`geometric_mixture`]) with the
/// least Shannon entropy: the best of `grid_points` equally spaced ω, then golden-section
/// search (Kiefer 1953) between its grid neighbours.
fn shannon_omega(p: &[f64], q: &[f64], config: &FusionConfig) -> Result<f64> {
    let at = |omega: f64| geometric_mixture(p, q, omega).ok_or(Error::DisjointSupports);
    let h = |omega: f64| at(omega).map(|r| entropy(&r, EntropyUnit::Nats));
    let n = config.grid_points;
    let mut best = (0, f64::INFINITY);
    for k in 0..n {
        let v = h(k as f64 / (n - 1) as f64)?;
        if v < best.1 {
            best = (k, v);
        }
    }
    let step = 1.0 / (n - 1) as f64;
    let lo = (best.0 as f64 - 1.0).max(0.0) * step;
    let hi = (best.0 as f64 + 1.0).min((n - 1) as f64) * step;
    let omega = golden_section(lo, hi, config.omega_tolerance, |w| {
        h(w).unwrap_or(f64::INFINITY)
    });
    // Keep the grid point if the refinement did not improve on it (an endpoint, where
    // the support jumps, can be the minimum).
    Ok(if h(omega)? <= best.1 {
        omega
    } else {
        best.0 as f64 * step
    })
}

/// The Chernoff point: g(ω) = D(r_ω‖p) − D(r_ω‖q) = −E_{r_ω}[log p/q] has derivative
/// −Var_{r_ω}(log p/q) ≤ 0, g(0) = D(q‖p) ≥ 0 and g(1) = −D(p‖q) ≤ 0, so bisection finds its
/// root. Only interior points are evaluated (on the common support, where g is finite).
fn chernoff_omega(p: &[f64], q: &[f64], tolerance: f64) -> Result<f64> {
    let g = |omega: f64| -> Result<f64> {
        let r = geometric_mixture(p, q, omega).ok_or(Error::DisjointSupports)?;
        Ok(r.iter()
            .zip(p.iter().zip(q))
            .filter(|&(&ri, _)| ri > 0.0)
            .map(|(&ri, (&a, &b))| ri * (b / a).ln())
            .sum())
    };
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    // 200 halvings reach any tolerance representable near 1.
    for _ in 0..200 {
        if hi - lo <= tolerance {
            break;
        }
        let mid = 0.5 * (lo + hi);
        if g(mid)? > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// Golden-section minimisation of `f` on [lo, hi] to width `tolerance`.
fn golden_section(mut lo: f64, mut hi: f64, tolerance: f64, f: impl Fn(f64) -> f64) -> f64 {
    let inv_phi = (5.0_f64.sqrt() - 1.0) / 2.0;
    let mut x1 = hi - inv_phi * (hi - lo);
    let mut x2 = lo + inv_phi * (hi - lo);
    let (mut f1, mut f2) = (f(x1), f(x2));
    // Each step shrinks the bracket by 1/φ; 200 steps reach any tolerance above 1e-40.
    for _ in 0..200 {
        if hi - lo <= tolerance {
            break;
        }
        if f1 <= f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - inv_phi * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + inv_phi * (hi - lo);
            f2 = f(x2);
        }
    }
    0.5 * (lo + hi)
}
