//! Online boosting for feature selection (Grabner & Bischof, CVPR 2006), with one pool of weak
//! learners shared by every selector (as in Grabner's tracker and OpenCV's `TrackerBoosting`).
//!
//! A sample is a feature vector read through a closure (a feature index → its value) and a
//! label y = ±1. For each sample:
//! 1. every weak learner of the pool updates its class statistics and votes h_m(x);
//! 2. with importance λ = 1, selector n adds λ to λ_corr(n, m) or λ_wrong(n, m) of every weak
//!    learner, picks the one with the smallest e = λ_wrong / (λ_corr + λ_wrong) (not one an
//!    earlier selector holds), sets α_n = ½ ln((1 − e) / e), and passes λ on multiplied by
//!    1 / (2 (1 − e)) if that learner was right and 1 / (2 e) if wrong;
//! 3. the weak learner with the largest error over all selectors (and held by none) is replaced
//!    by a new one on a random feature, with λ_corr = λ_wrong = 1 in every selector.
//!
//! The strong classifier's confidence is Σ α_n h_n(x) / Σ α_n ∈ [−1, 1].
//!
//! A weak learner is an online Gaussian threshold: running means and variances of the feature
//! over positives and over negatives (forgetting with a window), and the vote of the class
//! whose Gaussian gives the value the higher density.

use rand::{Rng, RngExt};

/// Smallest standard deviation a weak learner uses (features are L2-Hys values in [0, 1]).
const MIN_SD: f64 = 0.01;
/// Errors are clamped into [E_MIN, 1 − E_MIN] before α and λ are computed.
const E_MIN: f64 = 1e-3;

/// Running mean and variance with forgetting: the weight of a new sample is 1 / min(n, window).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Running {
    n: f64,
    mean: f64,
    var: f64,
    /// 1 / max(var, MIN_SD²) and ½ ln of it, kept current by `push`.
    inv_var: f64,
    half_log_var: f64,
}

impl Running {
    fn empty() -> Self {
        let var = MIN_SD * MIN_SD;
        Self {
            n: 0.0,
            mean: 0.0,
            var,
            inv_var: 1.0 / var,
            half_log_var: 0.5 * var.ln(),
        }
    }

    fn push(&mut self, x: f64, window: f64) {
        self.n += 1.0;
        let rate = 1.0 / self.n.min(window);
        let d = x - self.mean;
        self.mean += rate * d;
        self.var = (1.0 - rate) * (self.var + rate * d * d);
        let var = self.var.max(MIN_SD * MIN_SD);
        self.inv_var = 1.0 / var;
        self.half_log_var = 0.5 * var.ln();
    }

    #[inline]
    fn log_density(&self, x: f64) -> f64 {
        let d = x - self.mean;
        -0.5 * d * d * self.inv_var - self.half_log_var
    }
}

/// One weak learner: a feature index and its online Gaussian threshold.
#[derive(Debug, Clone, Copy, PartialEq)]
struct WeakLearner {
    feature: usize,
    positive: Running,
    negative: Running,
}

impl WeakLearner {
    fn new(feature: usize) -> Self {
        Self {
            feature,
            positive: Running::empty(),
            negative: Running::empty(),
        }
    }

    fn update(&mut self, value: f64, positive: bool, window: f64) {
        if positive {
            self.positive.push(value, window);
        } else {
            self.negative.push(value, window);
        }
    }

    /// +1 or −1; a learner that has not seen both classes votes −1.
    fn vote(&self, value: f64) -> i8 {
        if self.positive.n == 0.0 || self.negative.n == 0.0 {
            return -1;
        }
        if self.positive.log_density(value) >= self.negative.log_density(value) {
            1
        } else {
            -1
        }
    }
}

/// Settings of an [`OnlineBooster`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BoostConfig {
    /// Selectors N (the strong classifier's size).
    pub selectors: usize,
    /// Weak learners in the shared pool (at least `selectors + 1`).
    pub pool: usize,
    /// Samples over which a weak learner's statistics are averaged before old ones are
    /// forgotten.
    pub window: f64,
}

impl Default for BoostConfig {
    /// 25 selectors over a pool of 100 weak learners, each averaging over its last ~50 samples
    /// of a class.
    fn default() -> Self {
        Self {
            selectors: 25,
            pool: 100,
            window: 50.0,
        }
    }
}

impl BoostConfig {
    /// Checks every field.
    pub fn check(&self) -> crate::Result<()> {
        if self.selectors == 0 || self.pool <= self.selectors {
            return Err(tracker_model::Error::InvalidParameter {
                name: "pool",
                reason: format!(
                    "{} selectors need a pool larger than that; got {}",
                    self.selectors, self.pool
                ),
            }
            .into());
        }
        tracker_model::ensure_in_range(self.window, 1.0, f64::INFINITY, "window")?;
        Ok(())
    }
}

/// A strong classifier trained online by Grabner & Bischof's boosting.
#[derive(Debug, Clone, PartialEq)]
pub struct OnlineBooster {
    config: BoostConfig,
    n_features: usize,
    pool: Vec<WeakLearner>,
    /// λ_corr and λ_wrong per (selector, learner), selector-major.
    corr: Vec<f64>,
    wrong: Vec<f64>,
    /// Selected learner and α per selector.
    selected: Vec<Option<usize>>,
    alpha: Vec<f64>,
    /// Scratch: votes of the pool on the current sample.
    votes: Vec<i8>,
    /// Scratch: learners taken by a selector for the current sample (kept to avoid an
    /// allocation per update).
    taken: Vec<bool>,
    /// Scratch: each learner's error under the current selector.
    errors: Vec<f64>,
}

impl OnlineBooster {
    /// A booster over features 0..`n_features`, the pool's features drawn from `rng`.
    pub fn new(config: BoostConfig, n_features: usize, rng: &mut impl Rng) -> crate::Result<Self> {
        config.check()?;
        if n_features == 0 {
            return Err(tracker_model::Error::InvalidParameter {
                name: "n_features",
                reason: "no features to learn from".to_string(),
            }
            .into());
        }
        let pool = (0..config.pool)
            .map(|_| WeakLearner::new(rng.random_range(0..n_features)))
            .collect();
        let cells = config.selectors * config.pool;
        Ok(Self {
            config,
            n_features,
            pool,
            corr: vec![1.0; cells],
            wrong: vec![1.0; cells],
            selected: vec![None; config.selectors],
            alpha: vec![0.0; config.selectors],
            votes: vec![0; config.pool],
            taken: vec![false; config.pool],
            errors: vec![0.0; config.pool],
        })
    }

    /// Learns one sample: `feature(i)` is the value of feature i, `positive` its label.
    pub fn update(&mut self, feature: impl Fn(usize) -> f64, positive: bool, rng: &mut impl Rng) {
        let y: i8 = if positive { 1 } else { -1 };
        let window = self.config.window;
        for (m, learner) in self.pool.iter_mut().enumerate() {
            let v = feature(learner.feature);
            learner.update(v, positive, window);
            self.votes[m] = learner.vote(v);
        }
        let n_pool = self.config.pool;
        let mut lambda = 1.0;
        let taken = &mut self.taken;
        taken.fill(false);
        for n in 0..self.config.selectors {
            let (corr, wrong) = (
                &mut self.corr[n * n_pool..(n + 1) * n_pool],
                &mut self.wrong[n * n_pool..(n + 1) * n_pool],
            );
            // Three passes over the pool (λ to every learner, the errors, the lowest untaken
            // error) instead of one: the same values, but the first two have no branches and
            // run several learners at once.
            for ((c, w), &v) in corr.iter_mut().zip(wrong.iter_mut()).zip(&self.votes) {
                let right = v == y;
                *c += if right { lambda } else { 0.0 };
                *w += if right { 0.0 } else { lambda };
            }
            for ((e, &c), &w) in self.errors.iter_mut().zip(corr.iter()).zip(wrong.iter()) {
                *e = w / (c + w);
            }
            let mut best: Option<(usize, f64)> = None;
            for (m, (&e, &t)) in self.errors.iter().zip(taken.iter()).enumerate() {
                if !t && best.is_none_or(|(_, b)| e < b) {
                    best = Some((m, e));
                }
            }
            let Some((m, e)) = best else {
                break;
            };
            taken[m] = true;
            self.selected[n] = Some(m);
            if e >= 0.5 {
                // No better than chance: this selector does not vote and λ passes unchanged.
                self.alpha[n] = 0.0;
                continue;
            }
            let e = e.clamp(E_MIN, 1.0 - E_MIN);
            self.alpha[n] = 0.5 * ((1.0 - e) / e).ln();
            lambda *= if self.votes[m] == y {
                1.0 / (2.0 * (1.0 - e))
            } else {
                1.0 / (2.0 * e)
            };
        }
        // Replace the worst learner no selector holds, judged by its unweighted error (the
        // first selector's λ_wrong / (λ_corr + λ_wrong), where every sample has λ = 1).
        let mut worst: Option<(usize, f64)> = None;
        for m in (0..n_pool).filter(|&m| !taken[m]) {
            let e = self.wrong[m] / (self.corr[m] + self.wrong[m]);
            if worst.is_none_or(|(_, w)| e > w) {
                worst = Some((m, e));
            }
        }
        if let Some((m, _)) = worst {
            self.pool[m] = WeakLearner::new(rng.random_range(0..self.n_features));
            for n in 0..self.config.selectors {
                self.corr[n * n_pool + m] = 1.0;
                self.wrong[n * n_pool + m] = 1.0;
            }
        }
    }

    /// Σ α_n h_n(x) / Σ α_n ∈ [−1, 1]; −1 before any selector has an α.
    pub fn confidence(&self, feature: impl Fn(usize) -> f64) -> f64 {
        self.combine(feature, |l, v| f64::from(l.vote(v)))
    }

    /// The same sum with graded votes: each selected learner's log-likelihood ratio over 8,
    /// clipped to [−1, 1], in place of its ±1 vote. It has the sign of
    /// [`OnlineBooster::confidence`]'s terms but tells a window that fits well from one that
    /// barely passes, which localises the object more finely.
    pub fn soft_confidence(&self, feature: impl Fn(usize) -> f64) -> f64 {
        self.combine(feature, |l, v| {
            if l.positive.n == 0.0 || l.negative.n == 0.0 {
                return -1.0;
            }
            (0.125 * (l.positive.log_density(v) - l.negative.log_density(v))).clamp(-1.0, 1.0)
        })
    }

    fn combine(
        &self,
        feature: impl Fn(usize) -> f64,
        vote: impl Fn(&WeakLearner, f64) -> f64,
    ) -> f64 {
        let (mut num, mut den) = (0.0, 0.0);
        for (sel, &a) in self.selected.iter().zip(&self.alpha) {
            if let Some(m) = sel
                && a > 0.0
            {
                let l = &self.pool[*m];
                num += a * vote(l, feature(l.feature));
                den += a;
            }
        }
        if den > 0.0 { num / den } else { -1.0 }
    }

    /// Whether `confidence` is positive.
    pub fn classify(&self, feature: impl Fn(usize) -> f64) -> bool {
        self.confidence(feature) > 0.0
    }
}
