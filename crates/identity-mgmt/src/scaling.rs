//! Sinkhorn scaling (iterative proportional fitting) to general row and column targets, and
//! the scalability test that decides, before scaling, whether the zero pattern of a matrix can
//! meet the targets (Balakrishnan, Hwang & Tomlin 2004).
//!
//! All matrices here are dense, row-major, `n_rows × n_cols`, non-negative.
//!
//! * **Exactly scalable**: some matrix with exactly the input's zero pattern meets the
//!   targets. For the square doubly stochastic case this is *total support*: every positive
//!   entry lies on a perfect matching of the positive pattern. Sinkhorn converges linearly.
//! * **Almost scalable**: the targets can be met, but only with some positive entries set to
//!   0 (they are reported). Plain Sinkhorn still converges, but only like 1/k; the default
//!   [`AlmostScalableRule::ZeroForcedEntries`] zeroes them first, which has the same limit
//!   (every matrix with the targets has those zeros, so KL to the input is unchanged) and
//!   converges linearly.
//! * **Not scalable**: no matrix with the pattern meets the targets.
//!
//! Two routes decide it:
//! * square matrix, all targets 1: a perfect matching of the positive pattern from
//!   tracker-model's maintained assignment solver (`lsap`), then the strongly connected
//!   components of the alternating graph (row → column for each positive entry, column →
//!   row for each matched pair): a positive entry (i, j) lies on some perfect matching iff it
//!   is matched or row i and column j share a component (Dulmage-Mendelsohn).
//! * general targets: a maximum flow source → row i (capacity r_i) → column j (for a_ij > 0)
//!   → sink (capacity c_j) from the `pathfinding` crate's Edmonds-Karp, then the same
//!   component test on the residual graph between rows and columns: a zero-flow edge can carry
//!   flow in another maximum flow iff it lies on a residual cycle. `pathfinding` needs an
//!   ordered (integer) capacity type, so both target vectors are normalised to the same total
//!   and rounded to integer units of 2^-40 of it by largest remainder; a flow within
//!   n_rows + n_cols units of the total (the rounding error) counts as feasible, and an edge
//!   flow of at most that many units counts as none (the two roundings can push a few units
//!   through an edge that is forced to 0 in the exact problem). The relative resolution of
//!   the test is thus about (n_rows + n_cols)·1e-12.

use pathfinding::directed::edmonds_karp::edmonds_karp_sparse;
use pathfinding::directed::strongly_connected_components::strongly_connected_components;
use serde::{Deserialize, Serialize};
use tracker_model::{Error as ModelError, ensure_positive};

use crate::error::{Error, Result};

/// Stopping rule of [`sinkhorn`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SinkhornConfig {
    /// Stop when every row and column sum is within this (absolute) distance of its target.
    pub tolerance: f64,
    /// Stop after this many iterations (one row pass and one column pass each) even if not
    /// converged; the report says so.
    pub max_iterations: usize,
}

impl Default for SinkhornConfig {
    fn default() -> Self {
        Self {
            tolerance: 1e-9,
            max_iterations: 100_000,
        }
    }
}

impl SinkhornConfig {
    /// Checks the tolerance is positive and the cap at least 1.
    pub fn check(&self) -> Result<()> {
        ensure_positive(self.tolerance, "sinkhorn.tolerance")?;
        if self.max_iterations == 0 {
            return Err(ModelError::InvalidParameter {
                name: "sinkhorn.max_iterations",
                reason: "must be at least 1".into(),
            }
            .into());
        }
        Ok(())
    }
}

/// What a Sinkhorn run did.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SinkhornReport {
    /// Iterations run (0 if the input already met the targets).
    pub iterations: usize,
    /// Whether the tolerance was reached before the cap.
    pub converged: bool,
    /// The largest |row or column sum − target| at the end.
    pub max_marginal_error: f64,
}

/// Which route decides scalability.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ScalabilityMethod {
    /// The assignment solver and alternating-graph components when the matrix is square and
    /// every target is 1; the maximum flow otherwise.
    #[default]
    Auto,
    /// Always the maximum flow.
    MaxFlow,
}

/// What to do with an almost scalable matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum AlmostScalableRule {
    /// Set the entries that every matrix with the targets has at 0 to 0, then scale: the same
    /// limit as plain Sinkhorn, reached linearly instead of like 1/k.
    #[default]
    ZeroForcedEntries,
    /// Plain Sinkhorn on the input up to the iteration cap (the forced entries decay like 1/k,
    /// so it usually stops at the cap, not converged).
    IterateRaw,
}

/// What to do when local information (or a fused column) makes the matrix not scalable.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub enum NotScalableRule {
    /// Return [`Error::NotScalable`] and leave the matrix unchanged.
    #[default]
    Error,
    /// Soften the new column l to (1 − w)·l + w·(old column) and retry. The old matrix met
    /// the targets, so any w > 0 restores at least almost-scalability (the softened pattern
    /// contains the old one).
    Soften {
        /// The weight w ∈ (0, 1] given to the old column.
        old_weight: f64,
    },
}

/// Everything a scaling with a scalability test needs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ScalingConfig {
    /// Stopping rule.
    pub sinkhorn: SinkhornConfig,
    /// Which test decides scalability.
    pub method: ScalabilityMethod,
    /// What to do when almost scalable.
    pub almost_scalable: AlmostScalableRule,
    /// What to do when not scalable (used where there is an old column to soften towards).
    pub not_scalable: NotScalableRule,
    /// Largest relative difference between Σ row targets and Σ column targets accepted.
    pub marginal_tolerance: f64,
}

impl Default for ScalingConfig {
    fn default() -> Self {
        Self {
            sinkhorn: SinkhornConfig::default(),
            method: ScalabilityMethod::Auto,
            almost_scalable: AlmostScalableRule::ZeroForcedEntries,
            not_scalable: NotScalableRule::Error,
            marginal_tolerance: 1e-6,
        }
    }
}

impl ScalingConfig {
    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        self.sinkhorn.check()?;
        ensure_positive(self.marginal_tolerance, "scaling.marginal_tolerance")?;
        if let NotScalableRule::Soften { old_weight } = self.not_scalable
            && !(old_weight.is_finite() && old_weight > 0.0 && old_weight <= 1.0)
        {
            return Err(ModelError::InvalidParameter {
                name: "scaling.not_scalable.old_weight",
                reason: format!("{old_weight} is outside (0, 1]"),
            }
            .into());
        }
        Ok(())
    }
}

/// The outcome of the scalability test.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scalability {
    /// Every positive entry can stay positive.
    Exact,
    /// The targets can be met only with these positive entries (row, column) at 0.
    Almost {
        /// Entries every matrix with the targets has at 0, in row-major order.
        forced_zero: Vec<(usize, usize)>,
    },
    /// The targets cannot be met.
    NotScalable {
        /// The mass the pattern can carry.
        carried: f64,
        /// The mass required.
        required: f64,
    },
}

impl Scalability {
    /// Whether Sinkhorn has a limit (exactly or almost scalable).
    pub fn is_scalable(&self) -> bool {
        !matches!(self, Scalability::NotScalable { .. })
    }
}

/// What [`scale_to_marginals`] did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScalingReport {
    /// The scalability found before scaling.
    pub scalability: Scalability,
    /// The Sinkhorn run.
    pub sinkhorn: SinkhornReport,
}

/// Checks shape, entries and targets of a scaling problem; returns Σ row targets.
pub(crate) fn check_problem(
    a: &[f64],
    n_rows: usize,
    n_cols: usize,
    row_targets: &[f64],
    col_targets: &[f64],
    marginal_tolerance: f64,
) -> Result<f64> {
    check_len("matrix", a.len(), n_rows * n_cols)?;
    check_len("row targets", row_targets.len(), n_rows)?;
    check_len("column targets", col_targets.len(), n_cols)?;
    check_entries("matrix", a, n_cols.max(1))?;
    check_entries("row targets", row_targets, 1)?;
    check_entries("column targets", col_targets, 1)?;
    let row_total: f64 = row_targets.iter().sum();
    let col_total: f64 = col_targets.iter().sum();
    if (row_total - col_total).abs() > marginal_tolerance * row_total.max(1.0) {
        return Err(Error::MarginalMismatch {
            row_total,
            col_total,
        });
    }
    Ok(row_total)
}

pub(crate) fn check_len(what: &'static str, got: usize, expected: usize) -> Result<()> {
    if got == expected {
        Ok(())
    } else {
        Err(Error::Shape {
            what,
            expected,
            got,
        })
    }
}

/// Checks every entry is finite and non-negative (`width` = entries per row, for messages).
pub(crate) fn check_entries(what: &'static str, values: &[f64], width: usize) -> Result<()> {
    match values.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
        None => Ok(()),
        Some(k) => Err(Error::InvalidEntry {
            what,
            row: k / width,
            col: k % width,
            value: values[k],
        }),
    }
}

/// Sinkhorn / iterative proportional fitting of `a` (row-major, non-negative) in place:
/// alternately scale the rows to `row_targets` and the columns to `col_targets` until every
/// sum is within `config.tolerance` of its target or `config.max_iterations` is reached.
/// Rows and columns with target 0 are set to 0. It does not test scalability (see
/// [`scale_to_marginals`]): a pattern that is not scalable runs to the cap without converging,
/// except that a row or column with a positive target and no positive entry (outside lines
/// with target 0) is [`Error::NotScalable`], found before `a` is changed.
///
/// ```
/// use identity_mgmt::{sinkhorn, SinkhornConfig};
/// let mut a = vec![1.0, 2.0, 3.0, 4.0];
/// let report = sinkhorn(&mut a, 2, 2, &[1.0, 1.0], &[1.0, 1.0], &SinkhornConfig::default())?;
/// assert!(report.converged);
/// assert!((a[0] + a[1] - 1.0).abs() < 1e-9 && (a[0] + a[2] - 1.0).abs() < 1e-9);
/// # Ok::<(), identity_mgmt::Error>(())
/// ```
pub fn sinkhorn(
    a: &mut [f64],
    n_rows: usize,
    n_cols: usize,
    row_targets: &[f64],
    col_targets: &[f64],
    config: &SinkhornConfig,
) -> Result<SinkhornReport> {
    config.check()?;
    check_problem(a, n_rows, n_cols, row_targets, col_targets, f64::INFINITY)?;
    sinkhorn_unchecked(a, n_rows, n_cols, row_targets, col_targets, config)
}

/// Sinkhorn on a checked problem. Each iteration is two passes over the matrix: the first
/// scales the rows and accumulates the column sums, the second scales the columns and
/// accumulates the row sums that decide convergence (the columns are exact after it).
pub(crate) fn sinkhorn_unchecked(
    a: &mut [f64],
    n_rows: usize,
    n_cols: usize,
    row_targets: &[f64],
    col_targets: &[f64],
    config: &SinkhornConfig,
) -> Result<SinkhornReport> {
    let mut row_sums = vec![0.0; n_rows];
    let mut col_sums = vec![0.0; n_cols];
    if n_rows == 0 || n_cols == 0 {
        return Ok(SinkhornReport {
            iterations: 0,
            converged: true,
            max_marginal_error: 0.0,
        });
    }
    marginal_sums(a, n_rows, n_cols, &mut row_sums, &mut col_sums);
    let mut err = marginal_error(&row_sums, &col_sums, row_targets, col_targets);
    if err <= config.tolerance {
        return Ok(SinkhornReport {
            iterations: 0,
            converged: true,
            max_marginal_error: err,
        });
    }
    check_lines_alive(a, n_rows, n_cols, row_targets, col_targets)?;
    let mut factors = vec![0.0; n_cols];
    for iteration in 1..=config.max_iterations {
        err = sinkhorn_iteration(
            a,
            n_cols,
            (&mut row_sums, &mut col_sums),
            &mut factors,
            row_targets,
            col_targets,
        )?;
        if err <= config.tolerance {
            return Ok(SinkhornReport {
                iterations: iteration,
                converged: true,
                max_marginal_error: err,
            });
        }
    }
    Ok(SinkhornReport {
        iterations: config.max_iterations,
        converged: false,
        max_marginal_error: err,
    })
}

/// The row and column sums of `a` (row-major, `n_rows` × `n_cols`) into `row_sums` and
/// `col_sums`.
fn marginal_sums(
    a: &[f64],
    n_rows: usize,
    n_cols: usize,
    row_sums: &mut [f64],
    col_sums: &mut [f64],
) {
    col_sums.iter_mut().for_each(|c| *c = 0.0);
    for (i, row) in a.chunks_exact(n_cols.max(1)).enumerate().take(n_rows) {
        row_sums[i] = row.iter().sum();
        for (c, v) in col_sums.iter_mut().zip(row) {
            *c += v;
        }
    }
}

/// The largest distance of a row or column sum from its target.
fn marginal_error(
    row_sums: &[f64],
    col_sums: &[f64],
    row_targets: &[f64],
    col_targets: &[f64],
) -> f64 {
    let r = row_sums.iter().zip(row_targets).map(|(s, t)| (s - t).abs());
    let c = col_sums.iter().zip(col_targets).map(|(s, t)| (s - t).abs());
    r.chain(c).fold(0.0_f64, f64::max)
}

/// Rejects, before anything is changed, a line that Sinkhorn's first pass would leave empty
/// against a positive target: an entry survives the first pass iff its row and column
/// targets are positive, and then stays positive, so a line with a positive target and no
/// surviving entry would fail midway ([`Error::NotScalable`]; rows first, then columns).
fn check_lines_alive(
    a: &[f64],
    n_rows: usize,
    n_cols: usize,
    row_targets: &[f64],
    col_targets: &[f64],
) -> Result<()> {
    let alive = |i: usize, j: usize| {
        a[i * n_cols + j] > 0.0 && row_targets[i] > 0.0 && col_targets[j] > 0.0
    };
    for (i, &t) in row_targets.iter().enumerate() {
        if t > 0.0 && !(0..n_cols).any(|j| alive(i, j)) {
            return Err(Error::NotScalable {
                carried: 0.0,
                required: t,
            });
        }
    }
    for (j, &t) in col_targets.iter().enumerate() {
        if t > 0.0 && !(0..n_rows).any(|i| alive(i, j)) {
            return Err(Error::NotScalable {
                carried: 0.0,
                required: t,
            });
        }
    }
    Ok(())
}

/// One Sinkhorn-Knopp iteration (Sinkhorn 1964; iterative proportional fitting) in two
/// passes: scale the rows to their targets, accumulating the new column sums; then scale the
/// columns to theirs (`factors` is scratch), accumulating the new row sums. Returns the
/// largest row-sum error (the columns are exact after the second pass).
fn sinkhorn_iteration(
    a: &mut [f64],
    n_cols: usize,
    (row_sums, col_sums): (&mut [f64], &mut [f64]),
    factors: &mut [f64],
    row_targets: &[f64],
    col_targets: &[f64],
) -> Result<f64> {
    // Rows: scale to the targets, accumulating the new column sums.
    col_sums.iter_mut().for_each(|c| *c = 0.0);
    for (i, row) in a.chunks_exact_mut(n_cols).enumerate() {
        let f = scale_factor(row_sums[i], row_targets[i])?;
        for (c, v) in col_sums.iter_mut().zip(row.iter_mut()) {
            *v *= f;
            *c += *v;
        }
    }
    for (j, f) in factors.iter_mut().enumerate() {
        *f = scale_factor(col_sums[j], col_targets[j])?;
    }
    // Columns: scale to the targets, accumulating the new row sums.
    for (i, row) in a.chunks_exact_mut(n_cols).enumerate() {
        let mut s = 0.0;
        for (v, f) in row.iter_mut().zip(factors.iter()) {
            *v *= f;
            s += *v;
        }
        row_sums[i] = s;
    }
    Ok(row_sums
        .iter()
        .zip(row_targets)
        .map(|(s, t)| (s - t).abs())
        .fold(0.0, f64::max))
}

/// The factor that takes a line summing to `sum` to `target`; a positive target on an empty
/// line cannot be met.
fn scale_factor(sum: f64, target: f64) -> Result<f64> {
    if target == 0.0 {
        Ok(0.0)
    } else if sum > 0.0 {
        Ok(target / sum)
    } else {
        Err(Error::NotScalable {
            carried: 0.0,
            required: target,
        })
    }
}

/// Decides whether `a` can be scaled to the targets, and which positive entries are forced to
/// 0 (module docs). `config` supplies the route and the marginal tolerance.
pub fn scalability(
    a: &[f64],
    n_rows: usize,
    n_cols: usize,
    row_targets: &[f64],
    col_targets: &[f64],
    config: &ScalingConfig,
) -> Result<Scalability> {
    config.check()?;
    check_problem(
        a,
        n_rows,
        n_cols,
        row_targets,
        col_targets,
        config.marginal_tolerance,
    )?;
    scalability_unchecked(a, n_rows, n_cols, row_targets, col_targets, config)
}

pub(crate) fn scalability_unchecked(
    a: &[f64],
    n_rows: usize,
    n_cols: usize,
    row_targets: &[f64],
    col_targets: &[f64],
    config: &ScalingConfig,
) -> Result<Scalability> {
    // A positive matrix with positive targets is exactly scalable (every entry lies on a
    // positive diagonal; Sinkhorn & Knopp 1967), so the common case skips the graph work.
    if a.iter().all(|&v| v > 0.0) && row_targets.iter().chain(col_targets).all(|&t| t > 0.0) {
        return Ok(Scalability::Exact);
    }
    let doubly_stochastic = n_rows == n_cols
        && row_targets
            .iter()
            .chain(col_targets)
            .all(|t| (t - 1.0).abs() <= config.marginal_tolerance);
    if config.method == ScalabilityMethod::Auto && doubly_stochastic {
        square_scalability(a, n_rows)
    } else {
        flow_scalability(a, n_rows, n_cols, row_targets, col_targets)
    }
}

/// The square doubly stochastic route: a perfect matching of the positive pattern from the
/// assignment solver (cost 0 on a positive entry, 1 on a zero), then the alternating graph's
/// strongly connected components.
pub fn square_scalability(a: &[f64], n: usize) -> Result<Scalability> {
    check_len("matrix", a.len(), n * n)?;
    check_entries("matrix", a, n.max(1))?;
    let costs: Vec<f64> = a.iter().map(|&v| if v > 0.0 { 0.0 } else { 1.0 }).collect();
    let pairs = tracker_model::assignment::minimise(n, n, &costs)?;
    let matched = pairs.iter().filter(|&&(i, j)| a[i * n + j] > 0.0).count();
    if matched < n {
        return Ok(Scalability::NotScalable {
            carried: matched as f64,
            required: n as f64,
        });
    }
    let mut row_of_col = vec![0; n];
    for &(i, j) in &pairs {
        row_of_col[j] = i;
    }
    // Nodes 0..n are rows, n..2n columns.
    let successors = |&v: &usize| -> Vec<usize> {
        if v < n {
            (0..n)
                .filter(|&j| a[v * n + j] > 0.0)
                .map(|j| n + j)
                .collect()
        } else {
            vec![row_of_col[v - n]]
        }
    };
    Ok(classify_by_components(a, n, n, 2 * n, successors))
}

/// Positive entries whose row and column fall in different components of the residual
/// (alternating) graph are forced to 0.
fn classify_by_components(
    a: &[f64],
    n_rows: usize,
    n_cols: usize,
    n_nodes: usize,
    successors: impl FnMut(&usize) -> Vec<usize>,
) -> Scalability {
    let nodes: Vec<usize> = (0..n_nodes).collect();
    let mut component = vec![usize::MAX; n_nodes];
    for (k, comp) in strongly_connected_components(&nodes, successors)
        .into_iter()
        .enumerate()
    {
        for v in comp {
            component[v] = k;
        }
    }
    let forced_zero: Vec<(usize, usize)> = (0..n_rows)
        .flat_map(|i| (0..n_cols).map(move |j| (i, j)))
        .filter(|&(i, j)| a[i * n_cols + j] > 0.0 && component[i] != component[n_rows + j])
        .collect();
    if forced_zero.is_empty() {
        Scalability::Exact
    } else {
        Scalability::Almost { forced_zero }
    }
}

/// Total integer mass the targets are rounded to in the flow test (module docs).
const FLOW_UNITS: i64 = 1 << 40;

/// Rounds `values` (normalised to sum 1) to integers summing to [`FLOW_UNITS`] by largest
/// remainder.
fn apportion(values: &[f64]) -> Vec<i64> {
    let total: f64 = values.iter().sum();
    if total <= 0.0 {
        return vec![0; values.len()];
    }
    let exact: Vec<f64> = values
        .iter()
        .map(|v| v / total * FLOW_UNITS as f64)
        .collect();
    let mut units: Vec<i64> = exact.iter().map(|e| e.floor() as i64).collect();
    let missing = FLOW_UNITS - units.iter().sum::<i64>();
    let mut order: Vec<usize> = (0..values.len()).filter(|&k| values[k] > 0.0).collect();
    order.sort_by(|&x, &y| (exact[y] - exact[y].floor()).total_cmp(&(exact[x] - exact[x].floor())));
    for &k in order.iter().cycle().take(missing.max(0) as usize) {
        units[k] += 1;
    }
    units
}

/// The general route: a maximum flow on the positive pattern, then residual components.
pub fn flow_scalability(
    a: &[f64],
    n_rows: usize,
    n_cols: usize,
    row_targets: &[f64],
    col_targets: &[f64],
) -> Result<Scalability> {
    let tolerance = ScalingConfig::default().marginal_tolerance;
    check_problem(a, n_rows, n_cols, row_targets, col_targets, tolerance)?;
    let required: f64 = row_targets.iter().sum();
    if required <= 0.0 {
        let forced_zero = positive_entries(a, n_rows, n_cols);
        return Ok(if forced_zero.is_empty() {
            Scalability::Exact
        } else {
            Scalability::Almost { forced_zero }
        });
    }
    let rows = apportion(row_targets);
    let cols = apportion(col_targets);
    let source = n_rows + n_cols;
    let sink = source + 1;
    let vertices: Vec<usize> = (0..sink + 1).collect();
    let mut caps = Vec::new();
    for (i, &r) in rows.iter().enumerate() {
        if r > 0 {
            caps.push(((source, i), r));
        }
    }
    for (i, j) in positive_entries(a, n_rows, n_cols) {
        caps.push(((i, n_rows + j), FLOW_UNITS));
    }
    for (j, &c) in cols.iter().enumerate() {
        if c > 0 {
            caps.push(((n_rows + j, sink), c));
        }
    }
    let (flows, total, _cut) = edmonds_karp_sparse(&vertices, &source, &sink, caps);
    let slack = (n_rows + n_cols) as i64;
    if total < FLOW_UNITS - slack {
        let carried = required * total as f64 / FLOW_UNITS as f64;
        return Ok(Scalability::NotScalable { carried, required });
    }
    let mut has_flow = vec![false; n_rows * n_cols];
    for ((from, to), f) in flows {
        // Flow within the rounding error is noise: the two target vectors round
        // differently, and the difference can push a few units through an edge that is
        // forced to 0 in the exact problem.
        if f > slack && from < n_rows && (n_rows..n_rows + n_cols).contains(&to) {
            has_flow[from * n_cols + (to - n_rows)] = true;
        }
    }
    // Residual graph between rows and columns: row → column on every positive entry (its
    // capacity is never reached), column → row where flow runs.
    let successors = |&v: &usize| -> Vec<usize> {
        if v < n_rows {
            (0..n_cols)
                .filter(|&j| a[v * n_cols + j] > 0.0)
                .map(|j| n_rows + j)
                .collect()
        } else {
            let j = v - n_rows;
            (0..n_rows).filter(|&i| has_flow[i * n_cols + j]).collect()
        }
    };
    Ok(classify_by_components(
        a,
        n_rows,
        n_cols,
        n_rows + n_cols,
        successors,
    ))
}

fn positive_entries(a: &[f64], n_rows: usize, n_cols: usize) -> Vec<(usize, usize)> {
    (0..n_rows)
        .flat_map(|i| (0..n_cols).map(move |j| (i, j)))
        .filter(|&(i, j)| a[i * n_cols + j] > 0.0)
        .collect()
}

/// Tests scalability, then scales `a` in place to the targets: an exactly scalable matrix
/// directly, an almost scalable one by `config.almost_scalable`; a matrix that is not
/// scalable is [`Error::NotScalable`] and is left unchanged (softening needs an old column;
/// see [`crate::BeliefMatrix::incorporate_local_information`]).
///
/// ```
/// use identity_mgmt::{scale_to_marginals, Scalability, ScalingConfig};
/// let t = 1.0 / 3.0;
/// let mut a = vec![t, t, 0.0, t, t, 0.0, t, t, 1.0];
/// let ones = [1.0; 3];
/// let report = scale_to_marginals(&mut a, 3, 3, &ones, &ones, &ScalingConfig::default())?;
/// assert_eq!(report.scalability, Scalability::Almost { forced_zero: vec![(2, 0), (2, 1)] });
/// assert!((a[0] - 0.5).abs() < 1e-9 && a[6] == 0.0 && (a[8] - 1.0).abs() < 1e-9);
/// # Ok::<(), identity_mgmt::Error>(())
/// ```
pub fn scale_to_marginals(
    a: &mut [f64],
    n_rows: usize,
    n_cols: usize,
    row_targets: &[f64],
    col_targets: &[f64],
    config: &ScalingConfig,
) -> Result<ScalingReport> {
    config.check()?;
    check_problem(
        a,
        n_rows,
        n_cols,
        row_targets,
        col_targets,
        config.marginal_tolerance,
    )?;
    let scalability = scalability_unchecked(a, n_rows, n_cols, row_targets, col_targets, config)?;
    let sinkhorn = scale_classified(
        a,
        n_rows,
        n_cols,
        row_targets,
        col_targets,
        &scalability,
        config,
    )?;
    Ok(ScalingReport {
        scalability,
        sinkhorn,
    })
}

/// Scales a problem whose scalability is known.
pub(crate) fn scale_classified(
    a: &mut [f64],
    n_rows: usize,
    n_cols: usize,
    row_targets: &[f64],
    col_targets: &[f64],
    scalability: &Scalability,
    config: &ScalingConfig,
) -> Result<SinkhornReport> {
    match scalability {
        Scalability::NotScalable { carried, required } => {
            return Err(Error::NotScalable {
                carried: *carried,
                required: *required,
            });
        }
        Scalability::Almost { forced_zero }
            if config.almost_scalable == AlmostScalableRule::ZeroForcedEntries =>
        {
            for &(i, j) in forced_zero {
                a[i * n_cols + j] = 0.0;
            }
        }
        _ => {}
    }
    sinkhorn_unchecked(
        a,
        n_rows,
        n_cols,
        row_targets,
        col_targets,
        &config.sinkhorn,
    )
}
