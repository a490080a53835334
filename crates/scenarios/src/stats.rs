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

#[cfg(test)]
mod tests {
    use super::mean_ci;

    #[test]
    fn interval_by_hand() {
        // Values 1, 2, 3: mean 2, s² = 1, half-width 1.96/√3.
        let (m, h) = mean_ci([1.0, 2.0, 3.0]);
        assert!((m - 2.0).abs() < 1e-15 && (h - 1.96 / 3f64.sqrt()).abs() < 1e-15);
        assert_eq!(mean_ci(&[5.0][..]), (5.0, 0.0));
        assert!(mean_ci(Vec::<f64>::new()).0.is_nan());
    }
}
