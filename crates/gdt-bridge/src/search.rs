//! One-dimensional golden-section refinement, shared by the smoothing spline's GCV search and
//! the maximum-likelihood noise search.

/// Golden-section search on `[lo, hi]`: `iterations` steps, each keeping the sub-interval
/// around the preferred of the two interior points (`better(a, b)` is true when `a` is
/// preferred) and evaluating one new point. Returns the two interior points' values at the end.
pub(crate) fn golden_section<T, E>(
    (mut lo, mut hi): (f64, f64),
    iterations: usize,
    mut at: impl FnMut(f64) -> Result<T, E>,
    better: impl Fn(&T, &T) -> bool,
) -> Result<[T; 2], E> {
    let ratio = (5f64.sqrt() - 1.0) / 2.0;
    let (mut x1, mut x2) = (hi - ratio * (hi - lo), lo + ratio * (hi - lo));
    let (mut f1, mut f2) = (at(x1)?, at(x2)?);
    for _ in 0..iterations {
        if better(&f1, &f2) {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - ratio * (hi - lo);
            f1 = at(x1)?;
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + ratio * (hi - lo);
            f2 = at(x2)?;
        }
    }
    Ok([f1, f2])
}
