//! OSPA (Schuhmacher, Vo & Vo, IEEE TSP 2008) and GOSPA with α = 2 (Rahmathullah,
//! García-Fernández & Svensson, FUSION 2017) between finite sets of points.

use serde::{Deserialize, Serialize};
use tracker_model::{Frame, TrackSet, Vec2, ensure_positive};

use crate::error::{Error, Result, invalid_parameter};

/// Cut-off c and order p of OSPA and GOSPA; checked by [`OspaConfig::check`] in every
/// function that takes one.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OspaConfig {
    /// c > 0: the largest distance a pair can contribute, and the price of a cardinality error.
    pub cutoff: f64,
    /// p ≥ 1.
    pub order: f64,
}

impl OspaConfig {
    /// Checks c > 0 and p ≥ 1 (both finite).
    pub fn check(&self) -> Result<()> {
        ensure_positive(self.cutoff, "OSPA cut-off c")?;
        if !(self.order.is_finite() && self.order >= 1.0) {
            return Err(invalid_parameter(
                "OSPA order p",
                format!("{} must be finite and >= 1", self.order),
            ));
        }
        Ok(())
    }
}

/// OSPA distance with its localisation and cardinality parts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Ospa {
    /// d_p^(c)(X, Y).
    pub distance: f64,
    /// ((1/n) min Σ d^(c)(x, y)^p)^(1/p).
    pub localisation: f64,
    /// ((1/n) c^p (n − m))^(1/p).
    pub cardinality: f64,
}

/// GOSPA (α = 2) and its decomposition. The three parts are in units of distance^p and sum to
/// `distance^p`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Gospa {
    /// d_p^(c,2)(X, Y).
    pub distance: f64,
    /// Σ d(x, y)^p over the assigned pairs closer than c.
    pub localisation: f64,
    /// (c^p / 2) · number of missed truth points.
    pub missed: f64,
    /// (c^p / 2) · number of false estimates.
    pub false_targets: f64,
    /// Missed truth points.
    pub n_missed: usize,
    /// False estimates.
    pub n_false: usize,
}

fn check_points(points: &[Vec2], what: &'static str) -> Result<()> {
    if points.iter().all(|p| p.x.is_finite() && p.y.is_finite()) {
        Ok(())
    } else {
        Err(Error::Model(tracker_model::Error::NonFinite { what }))
    }
}

/// Optimal assignment of min(d, c)^p between `x` and `y`: (sum of assigned costs, assigned
/// pairs with d < c).
fn cutoff_assignment(
    x: &[Vec2],
    y: &[Vec2],
    cfg: &OspaConfig,
) -> Result<(f64, Vec<(usize, usize)>)> {
    let cp = cfg.cutoff.powf(cfg.order);
    let costs: Vec<f64> = x
        .iter()
        .flat_map(|a| {
            y.iter()
                .map(move |b| ((a - b).norm().min(cfg.cutoff)).powf(cfg.order))
        })
        .collect();
    let pairs = tracker_model::assignment::minimise(x.len(), y.len(), &costs)?;
    let total = pairs.iter().map(|&(i, j)| costs[i * y.len() + j]).sum();
    let close = pairs
        .into_iter()
        .filter(|&(i, j)| costs[i * y.len() + j] < cp)
        .collect();
    Ok((total, close))
}

/// OSPA between two point sets; 0 when both are empty, c when exactly one is.
pub fn ospa(x: &[Vec2], y: &[Vec2], cfg: &OspaConfig) -> Result<Ospa> {
    cfg.check()?;
    ospa_checked(x, y, cfg)
}

/// [`ospa`] with a checked configuration.
fn ospa_checked(x: &[Vec2], y: &[Vec2], cfg: &OspaConfig) -> Result<Ospa> {
    check_points(x, "OSPA points")?;
    check_points(y, "OSPA points")?;
    let (small, large) = if x.len() <= y.len() { (x, y) } else { (y, x) };
    let (m, n) = (small.len(), large.len());
    if n == 0 {
        return Ok(Ospa {
            distance: 0.0,
            localisation: 0.0,
            cardinality: 0.0,
        });
    }
    let (loc_sum, _) = cutoff_assignment(small, large, cfg)?;
    let card_sum = cfg.cutoff.powf(cfg.order) * (n - m) as f64;
    let nf = n as f64;
    let root = |v: f64| (v / nf).powf(1.0 / cfg.order);
    Ok(Ospa {
        distance: root(loc_sum + card_sum),
        localisation: root(loc_sum),
        cardinality: root(card_sum),
    })
}

/// GOSPA with α = 2 between truth `x` and estimates `y`.
pub fn gospa(x: &[Vec2], y: &[Vec2], cfg: &OspaConfig) -> Result<Gospa> {
    cfg.check()?;
    gospa_checked(x, y, cfg)
}

/// [`gospa`] with a checked configuration.
fn gospa_checked(x: &[Vec2], y: &[Vec2], cfg: &OspaConfig) -> Result<Gospa> {
    check_points(x, "GOSPA points")?;
    check_points(y, "GOSPA points")?;
    let (_, close) = cutoff_assignment(x, y, cfg)?;
    let localisation: f64 = close
        .iter()
        .map(|&(i, j)| (x[i] - y[j]).norm().powf(cfg.order))
        .sum();
    let half = cfg.cutoff.powf(cfg.order) / 2.0;
    let n_missed = x.len() - close.len();
    let n_false = y.len() - close.len();
    let missed = half * n_missed as f64;
    let false_targets = half * n_false as f64;
    Ok(Gospa {
        distance: (localisation + missed + false_targets).powf(1.0 / cfg.order),
        localisation,
        missed,
        false_targets,
        n_missed,
        n_false,
    })
}

/// The positions of every track point at each frame from `first` to `last`.
fn positions_at(set: &TrackSet, first: Frame, last: Frame) -> Vec<Vec<Vec2>> {
    let mut out = vec![Vec::new(); (last - first + 1) as usize];
    for t in set.tracks() {
        for p in t.points() {
            if (first..=last).contains(&p.frame) {
                out[(p.frame - first) as usize].push(p.location.position());
            }
        }
    }
    out
}

/// OSPA at every frame of the union of both sets' frame ranges (frames with nothing on
/// either side give 0).
pub fn ospa_over_time(
    gt: &TrackSet,
    pred: &TrackSet,
    cfg: &OspaConfig,
) -> Result<Vec<(Frame, Ospa)>> {
    cfg.check()?;
    per_frame(gt, pred, |x, y| ospa_checked(x, y, cfg))
}

/// GOSPA at every frame of the union of both sets' frame ranges.
pub fn gospa_over_time(
    gt: &TrackSet,
    pred: &TrackSet,
    cfg: &OspaConfig,
) -> Result<Vec<(Frame, Gospa)>> {
    cfg.check()?;
    per_frame(gt, pred, |x, y| gospa_checked(x, y, cfg))
}

/// `metric` between the two sets' positions at each frame of the union of their ranges.
fn per_frame<M>(
    gt: &TrackSet,
    pred: &TrackSet,
    metric: impl Fn(&[Vec2], &[Vec2]) -> Result<M>,
) -> Result<Vec<(Frame, M)>> {
    let range = match (gt.frame_range(), pred.frame_range()) {
        (None, None) => return Ok(Vec::new()),
        (Some(a), None) | (None, Some(a)) => a,
        (Some(a), Some(b)) => (a.0.min(b.0), a.1.max(b.1)),
    };
    let xs = positions_at(gt, range.0, range.1);
    let ys = positions_at(pred, range.0, range.1);
    xs.iter()
        .zip(&ys)
        .zip(range.0..)
        .map(|((x, y), frame)| Ok((frame, metric(x, y)?)))
        .collect()
}
