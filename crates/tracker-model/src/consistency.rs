//! Filter-consistency checks: the χ² interval that an average NEES must fall in.

/// The validation gate on a squared Mahalanobis distance in two dimensions that the trackers
/// use by default: about the 99.9 % quantile of χ² with 2 degrees of freedom (−2 ln 0.001 =
/// 13.82), so a true measurement falls outside it once in a thousand scans.
pub const GATE_CHI2_2D: f64 = 13.8;

/// The 97.5 % quantile of the standard normal distribution (published constant).
const Z_975: f64 = 1.959_963_984_540_054;

/// Wilson-Hilferty approximation of the χ² quantile with `dof` degrees of freedom at the
/// standard-normal quantile `z`; relative error below 0.1 % from about 30 degrees of freedom.
pub fn chi_square_quantile_wh(dof: f64, z: f64) -> f64 {
    let a = 2.0 / (9.0 * dof);
    dof * (1.0 - a + z * a.sqrt()).powi(3).max(0.0)
}

/// The two-sided 95 % interval of the average NEES of `n_runs` independent runs of a
/// `state_dim`-dimensional consistent filter: n_runs · ANEES ~ χ²(n_runs · state_dim)
/// (Bar-Shalom, Li & Kirubarajan 2001, §5.4).
pub fn anees_interval_95(state_dim: usize, n_runs: usize) -> (f64, f64) {
    let dof = (state_dim * n_runs) as f64;
    let n = n_runs as f64;
    (
        chi_square_quantile_wh(dof, -Z_975) / n,
        chi_square_quantile_wh(dof, Z_975) / n,
    )
}
