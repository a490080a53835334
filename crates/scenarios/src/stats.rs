//! The summary statistics the pipelines report.

use std::borrow::Borrow;

/// Mean and half-width of the normal-approximation 95 % confidence interval, 1.96·s/√n with s
/// the sample standard deviation: (mean, 0) for one value, (NaN, NaN) for none, so that an
/// empty group cannot pass the suite's finite-metrics check unnoticed.
pub(crate) fn mean_ci<I>(values: I) -> (f64, f64)
where
    I: IntoIterator,
    I::Item: Borrow<f64>,
{
    let xs: Vec<f64> = values.into_iter().map(|x| *x.borrow()).collect();
    if xs.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    if xs.len() < 2 {
        return (mean, 0.0);
    }
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, 1.96 * (var / n).sqrt())
}

/// A mean with the half-width of its 95 % confidence interval ([`mean_ci`] as a value).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MeanCi {
    /// Mean.
    pub(crate) mean: f64,
    /// Half-width of the 95 % CI.
    pub(crate) ci: f64,
}

impl MeanCi {
    /// [`mean_ci`] of `values`.
    pub(crate) fn of<I>(values: I) -> Self
    where
        I: IntoIterator,
        I::Item: Borrow<f64>,
    {
        let (mean, ci) = mean_ci(values);
        Self { mean, ci }
    }

    /// "mean ± half-width", shortest round-trip numbers.
    pub(crate) fn show(&self) -> String {
        format!(
            "{} ± {}",
            crate::fmt_num(self.mean),
            crate::fmt_num(self.ci)
        )
    }
}

/// Student's t quantile t₀.₉₇₅(ν) for ν degrees of freedom: the published table for ν ≤ 30,
/// Cornish–Fisher's expansion about the normal quantile beyond (within 1e-3 there).
pub(crate) fn t_975(dof: usize) -> f64 {
    const TABLE: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
        2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
        2.052, 2.048, 2.045, 2.042,
    ];
    match dof {
        0 => f64::NAN,
        1..=30 => TABLE[dof - 1],
        _ => {
            let (z, v) = (1.959_964_f64, dof as f64);
            z + (z.powi(3) + z) / (4.0 * v)
                + (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / (96.0 * v * v)
        }
    }
}

/// A paired comparison: the mean of the per-case differences (ours − theirs) and its 95 %
/// Student-t interval, `mean ± t₀.₉₇₅(n − 1)·s/√n`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Paired {
    /// Mean difference.
    pub(crate) mean: f64,
    /// Lower and upper ends of the 95 % interval.
    pub(crate) low: f64,
    pub(crate) high: f64,
}

impl Paired {
    /// The interval of `ours[i] − theirs[i]`; NaN ends with fewer than two pairs.
    pub(crate) fn of(ours: &[f64], theirs: &[f64]) -> Self {
        let diffs: Vec<f64> = ours.iter().zip(theirs).map(|(a, b)| a - b).collect();
        let n = diffs.len();
        let mean = diffs.iter().sum::<f64>() / n as f64;
        if n < 2 || ours.len() != theirs.len() {
            return Self {
                mean,
                low: f64::NAN,
                high: f64::NAN,
            };
        }
        let var = diffs.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (n as f64 - 1.0);
        let half = t_975(n - 1) * (var / n as f64).sqrt();
        Self {
            mean,
            low: mean - half,
            high: mean + half,
        }
    }

    /// The same interval with every end multiplied by `factor` (e.g. 100 for points).
    pub(crate) fn scaled(self, factor: f64) -> Self {
        Self {
            mean: factor * self.mean,
            low: factor * self.low,
            high: factor * self.high,
        }
    }

    /// "mean [low, high]".
    pub(crate) fn show(&self) -> String {
        format!(
            "{} [{}, {}]",
            crate::fmt_num(self.mean),
            crate::fmt_num(self.low),
            crate::fmt_num(self.high)
        )
    }
}

/// What a paired interval says of an ordering "ours ≥ theirs − margin" (the verdict a scenario
/// records from its fresh runs and the suite then checks).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum Verdict {
    /// The whole interval lies above −margin.
    Holds,
    /// The whole interval lies below −margin: a loss.
    Loses,
    /// The interval straddles −margin: not shown either way.
    Undecided,
}

impl Verdict {
    pub(crate) fn of(paired: &Paired, margin: f64) -> Self {
        if paired.low > -margin {
            Verdict::Holds
        } else if paired.high < -margin {
            Verdict::Loses
        } else {
            Verdict::Undecided
        }
    }

    pub(crate) fn name(self) -> &'static str {
        match self {
            Verdict::Holds => "holds",
            Verdict::Loses => "loses",
            Verdict::Undecided => "undecided",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{Paired, mean_ci, t_975};

    #[test]
    fn t_quantiles_match_the_published_table() {
        // t₀.₉₇₅ for ν = 7, 40, 60, 120 from the standard tables: 2.365, 2.021, 2.000, 1.980.
        assert!((t_975(7) - 2.365).abs() < 1e-12);
        for (dof, table) in [(40, 2.021), (60, 2.000), (120, 1.980)] {
            assert!((t_975(dof) - table).abs() < 1e-3, "{dof}: {}", t_975(dof));
        }
        assert!(t_975(0).is_nan());
    }

    #[test]
    fn paired_interval_by_hand() {
        // Differences 1, 2, 3, 6: mean 3, s² = 14/3, half-width 3.182·√(14/3)/2.
        let p = Paired::of(&[2.0, 4.0, 6.0, 10.0], &[1.0, 2.0, 3.0, 4.0]);
        let half = 3.182 * (14.0f64 / 3.0).sqrt() / 2.0;
        assert!((p.mean - 3.0).abs() < 1e-12);
        assert!((p.low - (3.0 - half)).abs() < 1e-12 && (p.high - (3.0 + half)).abs() < 1e-12);
        assert!(Paired::of(&[1.0], &[0.0]).low.is_nan());
    }

    #[test]
    fn interval_by_hand() {
        // Values 1, 2, 3: mean 2, s² = 1, half-width 1.96/√3.
        let (m, h) = mean_ci([1.0, 2.0, 3.0]);
        assert!((m - 2.0).abs() < 1e-15 && (h - 1.96 / 3f64.sqrt()).abs() < 1e-15);
        assert_eq!(mean_ci(&[5.0][..]), (5.0, 0.0));
        assert!(mean_ci(Vec::<f64>::new()).0.is_nan());
    }
}
