//! Grid likelihoods and their fusion (Kushwaha et al. 2008, §4): each selected sensor's profile
//! is projected onto the grid with tracker-model's [`BearingProfile::project`]
//! (L_s(c) = D_s(θ_{s,c})), the grids are fused by a weighted sum or a floored product, and the
//! fused grid's peaks, with covariances from their shape, are the tracker's measurements.
//!
//! [`BearingProfile::project`]: tracker_model::BearingProfile::project

use nalgebra::Matrix2;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use tracker_model::{
    GridNormalisation, LikelihoodGrid, PeakConfig, ProjectionConfig, Region2, Vec2,
    ensure_in_range, ensure_non_negative, ensure_positive,
};

use crate::buffer::Snapshot;
use crate::error::{Result, invalid};
use crate::node::{SensorKind, SensorNode};

/// How each sensor's grid is scaled before a weighted sum.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum SumScaling {
    /// max_c L_s(c) = 1: every sensor's ridge has height w_s, so the cell on all the ridges
    /// stands Σ w_s high and a crossing of two ridges only w_a + w_b (default).
    #[default]
    Max,
    /// Σ_c L_s(c) = 1: every sensor brings the same evidence mass, so a narrow profile (a
    /// camera's, 0.5° bins) concentrates its mass on few cells and its ridge outweighs the
    /// broad audio lobes everywhere along it.
    Sum,
}

/// How the per-sensor grids are combined.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum FusionRule {
    /// L(c) ∝ Σ_s w_s L_s(c), each L_s scaled as `scaling` says: a sensor that misses the
    /// target, or is wrong, dilutes the peak but cannot remove it. A silent sensor (all-zero
    /// profile) adds nothing.
    WeightedSum {
        /// Per-sensor scaling.
        scaling: SumScaling,
    },
    /// L(c) ∝ Π_s (ε + (1 − ε) L_s(c) / max L_s)^{w_s}: each grid is scaled to maximum 1 and
    /// lifted to the floor ε = `floor` before the weighted product, so a sensor that sees
    /// nothing where the others do lowers the cell by at most a factor ε^{w_s} instead of
    /// vetoing it. ε = 0 is the plain product, where one zero vetoes the cell. A silent
    /// sensor is the constant ε everywhere, which the normalisation removes.
    Product {
        /// ε ∈ [0, 1).
        floor: f64,
    },
}

/// Which modalities a fusion uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Modalities {
    /// Audio nodes only.
    Audio,
    /// Video nodes only.
    Video,
    /// Both.
    #[default]
    Both,
}

impl Modalities {
    /// Whether nodes of `kind` take part.
    pub fn includes(self, kind: SensorKind) -> bool {
        matches!(
            (self, kind),
            (Self::Both, _) | (Self::Audio, SensorKind::Audio) | (Self::Video, SensorKind::Video)
        )
    }
}

/// Peak extraction: local maxima of the fused grid at least `relative_threshold` × its
/// maximum and at least `min_contrast` × the grid's mean value (1/n_cells for a fused grid,
/// which sums to 1), thinned by non-maximum
/// suppression within `suppression_radius_m`, at most `max_peaks`, strongest first. Each
/// peak's position and covariance are the mean and second central moment of the cells within
/// `moment_radius_m` of it whose value is at least `moment_fraction` × the peak's, weighted by
/// their excess over that level, plus the cell's own quantisation variance s²/12 per axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeakExtraction {
    /// κ ∈ (0, 1].
    pub relative_threshold: f64,
    /// Peaks below this multiple of the grid's mean value are dropped (≥ 0; 0 keeps all):
    /// a grid with no target is nearly flat and its strongest bump is no measurement.
    pub min_contrast: f64,
    /// NMS radius, metres (≈ the target size).
    pub suppression_radius_m: f64,
    /// Radius of the moment window, metres (> 0).
    pub moment_radius_m: f64,
    /// Cells below this fraction of the peak are outside its shape, in [0, 1).
    pub moment_fraction: f64,
    /// At most this many peaks per scan.
    pub max_peaks: usize,
    /// Peaks whose cell lies within this many cells of the grid's edge are dropped: a
    /// target outside the region pulls the likelihood up towards the edge, and the edge
    /// cells then hold a local maximum that is not a target inside (0 keeps them).
    pub border_cells: usize,
    /// Explaining away, degrees (0: off, plain NMS on the fused grid). When > 0, peaks are
    /// taken one at a time: after each, every sensor's grid is multiplied by the notch
    /// 1 − exp(−½ (Δθ/σ)²), Δθ the angle at the sensor between a cell and the peak,
    /// σ = `explain_away_deg`, the grids are fused again and the strongest peak of this
    /// residual (not within the NMS radius of a kept peak, and with a value in the original
    /// fused grid of at least κ × its maximum) is the next. Two vehicles whose beams merge in
    /// some sensors leave one broad maximum in the fused grid; once the first is explained
    /// away, the sensors that do separate them carry the second (the successive cancellation
    /// of CLEAN-like multi-source localisation, our choice; the paper's extraction is not
    /// known to us). Its shape, and so its position and covariance, come from the residual; its
    /// value is the fused grid's (see [`PeakMeasurement::value`]).
    #[serde(default)]
    pub explain_away_deg: f64,
}

impl Default for PeakExtraction {
    fn default() -> Self {
        Self {
            relative_threshold: 0.3,
            min_contrast: 0.0,
            suppression_radius_m: 3.0,
            moment_radius_m: 2.0,
            moment_fraction: 0.5,
            max_peaks: 8,
            border_cells: 1,
            explain_away_deg: 0.0,
        }
    }
}

/// A sensor's evidence about a cell fades with the cell's distance r from it, by
/// g(r) = min(1, (r₀ / r)^q): a far vehicle is heard or seen weakly, so a profile that shows
/// nothing towards a far cell says little against it. With several vehicles the nodes near a
/// loud one see only it, and under the plain product their floor-level values towards a
/// distant vehicle veto that vehicle's cell, which the nodes near it support (our choice; the
/// paper's grid is not known to us). Each sensor's contribution is taken relative to its
/// average cell — under the product g·w·(ln t(c) − mean ln t), t(c) the floored term; under the
/// sum w·(m + g·(L(c) − m)), m the mean scaled value — so a faded sensor tends to neutral,
/// not to its best or worst value. Without a fade the subtraction only shifts every cell
/// alike and is not made. Under the plain product (ε = 0) a zero value still vetoes its cell at
/// any distance: the fade weakens floored terms, it does not lift vetoes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RangeFade {
    /// r₀, metres (> 0): full weight within it.
    pub full_weight_m: f64,
    /// q (> 0): how fast the weight falls beyond r₀.
    pub power: f64,
}

impl RangeFade {
    /// Checks r₀ and q.
    pub fn check(&self) -> Result<()> {
        ensure_positive(self.full_weight_m, "range_fade.full_weight_m")?;
        ensure_positive(self.power, "range_fade.power")?;
        Ok(())
    }

    /// g(r) of a distance r in metres: 1 within r₀, (r₀ / r)^q beyond.
    pub fn factor(&self, r: f64) -> f64 {
        if r <= self.full_weight_m {
            1.0
        } else {
            (self.full_weight_m / r).powf(self.power)
        }
    }
}

/// The grid, the rule and the peaks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FusionConfig {
    /// The region covered, metres.
    pub region: Region2,
    /// Side of a square cell, metres.
    pub cell_size_m: f64,
    /// Cells farther than this from a sensor get nothing from it (`None`: unlimited).
    pub max_range_m: Option<f64>,
    /// Cells nearer than this to a sensor get nothing from it (the bearing is undefined there).
    pub min_range_m: f64,
    /// Each sensor's evidence fades with the cell's distance from it (`None`: it counts the
    /// same everywhere; see [`RangeFade`]).
    #[serde(default)]
    pub range_fade: Option<RangeFade>,
    /// How grids combine.
    pub rule: FusionRule,
    /// Which modalities take part.
    pub modalities: Modalities,
    /// How peaks are extracted.
    pub peaks: PeakExtraction,
}

impl FusionConfig {
    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        ensure_positive(self.cell_size_m, "cell_size_m")?;
        ProjectionConfig {
            normalisation: GridNormalisation::None,
            max_range_m: self.max_range_m,
            min_range_m: self.min_range_m,
        }
        .check()?;
        if let Some(fade) = &self.range_fade {
            fade.check()?;
        }
        if let FusionRule::Product { floor } = self.rule
            && !(floor.is_finite() && (0.0..1.0).contains(&floor))
        {
            return Err(invalid("floor", format!("{floor} is outside [0, 1)")));
        }
        let p = &self.peaks;
        if !(p.relative_threshold > 0.0 && p.relative_threshold <= 1.0) {
            return Err(invalid(
                "relative_threshold",
                format!("{} is outside (0, 1]", p.relative_threshold),
            ));
        }
        ensure_non_negative(p.min_contrast, "min_contrast")?;
        ensure_non_negative(p.suppression_radius_m, "suppression_radius_m")?;
        ensure_positive(p.moment_radius_m, "moment_radius_m")?;
        ensure_non_negative(p.explain_away_deg, "explain_away_deg")?;
        ensure_in_range(p.moment_fraction, 0.0, 1.0, "moment_fraction")?;
        if p.moment_fraction >= 1.0 {
            return Err(invalid("moment_fraction", "must be below 1"));
        }
        // The grid itself: LikelihoodGrid::zeros checks the cell count.
        LikelihoodGrid::zeros(self.region, self.cell_size_m)?;
        Ok(())
    }

    fn projection(&self) -> ProjectionConfig {
        ProjectionConfig {
            normalisation: GridNormalisation::None,
            max_range_m: self.max_range_m,
            min_range_m: self.min_range_m,
        }
    }
}

/// A peak of the fused grid as a measurement.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PeakMeasurement {
    /// Weighted mean of the peak's shape, metres.
    pub position: Vec2,
    /// Second central moment of the shape plus s²/12 per axis (symmetric positive definite).
    pub covariance: Matrix2<f64>,
    /// The fused grid's value at the peak cell (for a peak found by explaining away, at the
    /// cell of its position: the residual only finds it).
    pub value: f64,
}

/// The result of fusing one tick.
#[derive(Debug, Clone, PartialEq)]
pub struct FusedScan {
    /// Tick index.
    pub tick: u64,
    /// Fusion time of the tick.
    pub time_s: f64,
    /// Sensors whose grids were fused (present in the snapshot, of the chosen modalities,
    /// with weight > 0), in sensor order.
    pub used: Vec<usize>,
    /// The fused grid (sums to 1; all zero when no sensor had evidence).
    pub grid: LikelihoodGrid,
    /// Its peaks, strongest first.
    pub peaks: Vec<PeakMeasurement>,
}

/// Projects the snapshot's profiles of `sensors` onto the grid, fuses them and extracts the
/// peaks. Sensors are projected in parallel and combined in sensor order, so the result does
/// not depend on the thread count. `config` must have passed [`FusionConfig::check`]. With a
/// [`RangeFade`], each call computes every sensor's fade over the grid; [`crate::AvPipeline`]
/// computes them once.
pub fn fuse_snapshot(
    sensors: &[SensorNode],
    snapshot: &Snapshot<'_>,
    config: &FusionConfig,
) -> Result<FusedScan> {
    fuse_snapshot_with(
        sensors,
        snapshot,
        config,
        &RangeFades::new(sensors, config)?,
    )
}

/// Each sensor's fade g(r) = min(1, (r₀ / r)^q) over the grid's cells, by sensor index (all
/// `None` when the fade is off): fixed while the sensors' believed poses are.
pub(crate) struct RangeFades {
    by_sensor: Vec<Option<Vec<f64>>>,
}

impl RangeFades {
    pub(crate) fn new(sensors: &[SensorNode], config: &FusionConfig) -> Result<Self> {
        let Some(fade) = config.range_fade else {
            return Ok(Self {
                by_sensor: vec![None; sensors.len()],
            });
        };
        let centres = cell_centres(&LikelihoodGrid::zeros(config.region, config.cell_size_m)?);
        let by_sensor = sensors
            .iter()
            .map(|node| {
                let at = node.pose.position;
                Some(
                    centres
                        .iter()
                        .map(|c| fade.factor((c - at).norm()))
                        .collect(),
                )
            })
            .collect();
        Ok(Self { by_sensor })
    }

    fn of(&self, sensor: usize) -> Option<&[f64]> {
        self.by_sensor.get(sensor).and_then(|f| f.as_deref())
    }
}

/// [`fuse_snapshot`] with the sensors' fades computed beforehand.
pub(crate) fn fuse_snapshot_with(
    sensors: &[SensorNode],
    snapshot: &Snapshot<'_>,
    config: &FusionConfig,
    fades: &RangeFades,
) -> Result<FusedScan> {
    let projection = config.projection();
    let chosen: Vec<_> = snapshot
        .selected
        .iter()
        .filter(|s| {
            sensors
                .get(s.sensor)
                .is_some_and(|n| n.weight > 0.0 && config.modalities.includes(n.kind))
        })
        .collect();
    let grids: Vec<(usize, f64, LikelihoodGrid)> = chosen
        .par_iter()
        .map(|s| {
            let node = &sensors[s.sensor];
            let grid = node.profile(s.values.to_vec())?.project(
                config.region,
                config.cell_size_m,
                &projection,
            )?;
            Ok((s.sensor, node.weight, grid))
        })
        .collect::<Result<_>>()?;
    let mut grid = LikelihoodGrid::zeros(config.region, config.cell_size_m)?;
    let fused = fuse_values(
        grid.values().len(),
        grids.iter().map(|(s, w, g)| (g.values(), *w, fades.of(*s))),
        config.rule,
    )?;
    fill(&mut grid, fused)?;
    let peaks = if config.peaks.explain_away_deg > 0.0 {
        explain_away(sensors, &grids, fades, &grid, config)?
    } else {
        extract_peaks(&grid, &config.peaks)?
    };
    Ok(FusedScan {
        tick: snapshot.tick,
        time_s: snapshot.time_s,
        used: grids.iter().map(|(s, _, _)| *s).collect(),
        grid,
        peaks,
    })
}

/// Peaks by explaining away (see [`PeakExtraction::explain_away_deg`]): `grids` are the
/// sensors' projections (sensor, weight, grid), `fused` their fusion.
fn explain_away(
    sensors: &[SensorNode],
    grids: &[(usize, f64, LikelihoodGrid)],
    fades: &RangeFades,
    fused: &LikelihoodGrid,
    config: &FusionConfig,
) -> Result<Vec<PeakMeasurement>> {
    let pc = &config.peaks;
    let Some(first) = extract_peaks(fused, pc)?.into_iter().next() else {
        return Ok(Vec::new());
    };
    let top = fused.values().iter().copied().fold(0.0, f64::max);
    let centres = cell_centres(fused);
    // One residual grid, refilled after every notch.
    let mut grid = LikelihoodGrid::zeros(config.region, config.cell_size_m)?;
    let mut residual: Vec<Vec<f64>> = grids.iter().map(|(_, _, g)| g.values().to_vec()).collect();
    let sigma = pc.explain_away_deg.to_radians();
    let mut kept = vec![first];
    while kept.len() < pc.max_peaks {
        let Some(last) = kept.last().map(|p| p.position) else {
            break;
        };
        residual
            .par_iter_mut()
            .zip(grids)
            .for_each(|(values, (s, _, _))| {
                let at = sensors[*s].pose.position;
                let d = last - at;
                let peak_bearing = d.y.atan2(d.x);
                for (v, c) in values.iter_mut().zip(&centres) {
                    let e = c - at;
                    let off = tracker_model::wrap_angle_rad(e.y.atan2(e.x) - peak_bearing) / sigma;
                    *v *= 1.0 - (-0.5 * off * off).exp();
                }
            });
        let Some(acc) = fuse_values(
            centres.len(),
            residual
                .iter()
                .zip(grids)
                .map(|(v, (s, w, _))| (v.as_slice(), *w, fades.of(*s))),
            config.rule,
        )?
        else {
            break;
        };
        fill(&mut grid, Some(acc))?;
        let r2 = pc.suppression_radius_m * pc.suppression_radius_m;
        let next = extract_peaks(
            &grid,
            &PeakExtraction {
                max_peaks: usize::MAX,
                ..*pc
            },
        )?
        .into_iter()
        .find(|q| {
            kept.iter()
                .all(|k| (k.position - q.position).norm_squared() >= r2)
                && fused
                    .cell_of(&q.position)
                    .is_some_and(|(c, r)| fused.value(c, r) >= pc.relative_threshold * top)
        });
        match next {
            // The value is the fused grid's, not the residual's: the residual is renormalised
            // after each notch, which would lift a weak later peak to a strong one's height.
            Some(q) => kept.push(PeakMeasurement {
                value: fused
                    .cell_of(&q.position)
                    .map_or(q.value, |(c, r)| fused.value(c, r)),
                ..q
            }),
            None => break,
        }
    }
    Ok(kept)
}

/// The fused values (summing to 1) of per-sensor value slices of `n` cells with their weights
/// by `rule`; `None` when no slice carries evidence.
fn fuse_values<'a>(
    n: usize,
    grids: impl IntoIterator<Item = (&'a [f64], f64, Option<&'a [f64]>)>,
    rule: FusionRule,
) -> Result<Option<Vec<f64>>> {
    let mut acc = vec![0.0; n];
    let mut any = false;
    let mut logs = Vec::new();
    for (v, w, fade) in grids {
        ensure_non_negative(w, "fusion weight")?;
        any |= match rule {
            FusionRule::WeightedSum { scaling } => add_weighted(&mut acc, v, w, fade, scaling),
            FusionRule::Product { floor } => {
                add_log_product(&mut acc, &mut logs, (v, w, fade), floor)
            }
        };
    }
    if !any {
        return Ok(None);
    }
    if let FusionRule::Product { .. } = rule {
        let top = acc.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if top == f64::NEG_INFINITY {
            // Every cell vetoed by some sensor (ε = 0): no evidence anywhere.
            return Ok(None);
        }
        acc.iter_mut().for_each(|a| *a = (*a - top).exp());
    }
    let total: f64 = acc.iter().sum();
    acc.iter_mut().for_each(|a| *a /= total);
    Ok(Some(acc))
}

/// Adds one sensor's term of the weighted-sum rule (linear opinion pool) to `acc`:
/// w · v / total(v), `total` by `scaling`, each cell pulled towards the slice's mean by its
/// `fade` gain when given. Returns whether the sensor carried evidence (positive total and
/// weight); otherwise `acc` is unchanged.
fn add_weighted(
    acc: &mut [f64],
    v: &[f64],
    w: f64,
    fade: Option<&[f64]>,
    scaling: SumScaling,
) -> bool {
    let total: f64 = match scaling {
        SumScaling::Sum => v.iter().sum(),
        SumScaling::Max => v.iter().copied().fold(0.0, f64::max),
    };
    if !(total > 0.0 && w > 0.0) {
        return false;
    }
    let k = w / total;
    match fade {
        None => acc.iter_mut().zip(v).for_each(|(a, x)| *a += k * x),
        Some(f) => {
            let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
            acc.iter_mut()
                .zip(v)
                .zip(f)
                .for_each(|((a, x), g)| *a += k * (mean + g * (x - mean)));
        }
    }
    true
}

/// Adds one sensor's term of the floored product rule (logarithmic opinion pool) to `acc`
/// in logarithms: w · ln(ε + (1 − ε) v / max v), or with `fade` gains g, g · w · (l − mean l)
/// over the finite logarithms l (a −∞ veto stays a veto). `logs` is scratch shared by the
/// sensors. Returns whether the sensor carried evidence (positive maximum and weight);
/// otherwise `acc` is unchanged.
fn add_log_product(
    acc: &mut [f64],
    logs: &mut Vec<f64>,
    (v, w, fade): (&[f64], f64, Option<&[f64]>),
    floor: f64,
) -> bool {
    let max = v.iter().copied().fold(0.0, f64::max);
    if !(max > 0.0 && w > 0.0) {
        return false;
    }
    let scale = (1.0 - floor) / max;
    match fade {
        None => acc
            .iter_mut()
            .zip(v)
            .for_each(|(a, x)| *a += w * (floor + scale * x).ln()),
        Some(f) => {
            // The logarithms once, into a buffer shared by the sensors.
            logs.clear();
            logs.extend(v.iter().map(|x| (floor + scale * x).ln()));
            // Over the finite logarithms: under ε = 0 a zero value is −∞,
            // which must still veto its cell, not make the mean −∞ (and
            // every cell NaN).
            let (sum, count) = logs
                .iter()
                .filter(|l| l.is_finite())
                .fold((0.0, 0usize), |(s, n), l| (s + l, n + 1));
            let mean = sum / count.max(1) as f64;
            acc.iter_mut()
                .zip(logs.iter())
                .zip(f)
                .for_each(|((a, l), g)| {
                    // A veto stays a veto even where g underflows to 0
                    // (0 · −∞ would be NaN).
                    *a += if *l == f64::NEG_INFINITY {
                        *l
                    } else {
                        g * w * (l - mean)
                    }
                });
        }
    }
    true
}

/// Fuses unnormalised grids (all over `region` with cells of `cell_size_m`) with their
/// weights by `rule`; the result sums to 1, or is all zero when no grid carries evidence.
pub fn fuse_grids<'a>(
    region: Region2,
    cell_size_m: f64,
    grids: impl IntoIterator<Item = (&'a LikelihoodGrid, f64)>,
    rule: FusionRule,
) -> Result<LikelihoodGrid> {
    let mut out = LikelihoodGrid::zeros(region, cell_size_m)?;
    let (cols, rows) = out.shape();
    let mut checked = Vec::new();
    for (g, w) in grids {
        if g.shape() != (cols, rows) || g.region() != &region {
            return Err(tracker_model::Error::ShapeMismatch(
                "a sensor grid does not cover the fusion grid's cells".into(),
            )
            .into());
        }
        checked.push((g.values(), w, None));
    }
    let fused = fuse_values(cols * rows, checked, rule)?;
    fill(&mut out, fused)?;
    Ok(out)
}

/// The centres of `grid`'s cells, row-major (the order of its values).
fn cell_centres(grid: &LikelihoodGrid) -> Vec<Vec2> {
    let (cols, rows) = grid.shape();
    (0..rows)
        .flat_map(|r| (0..cols).map(move |c| (c, r)))
        .map(|(c, r)| grid.cell_centre(c, r))
        .collect()
}

/// Sets `grid`'s cells (row-major) to `values`; `None` leaves it as it is.
fn fill(grid: &mut LikelihoodGrid, values: Option<Vec<f64>>) -> Result<()> {
    let Some(values) = values else {
        return Ok(());
    };
    let (cols, rows) = grid.shape();
    for row in 0..rows {
        for col in 0..cols {
            grid.set(col, row, values[row * cols + col])?;
        }
    }
    Ok(())
}

/// The peaks of a grid as measurements (see [`PeakExtraction`]).
pub fn extract_peaks(
    grid: &LikelihoodGrid,
    config: &PeakExtraction,
) -> Result<Vec<PeakMeasurement>> {
    let mut raw = grid.peaks(&PeakConfig {
        relative_threshold: config.relative_threshold,
        suppression_radius: config.suppression_radius_m,
    })?;
    let (cols, rows) = grid.shape();
    let mean = grid.values().iter().sum::<f64>() / (cols * rows) as f64;
    let b = config.border_cells;
    raw.retain(|p| {
        p.value >= config.min_contrast * mean
            && grid
                .cell_of(&p.position)
                .is_some_and(|(c, r)| c >= b && r >= b && c + b < cols && r + b < rows)
    });
    raw.truncate(config.max_peaks);
    let s = grid.cell_size();
    let reach = (config.moment_radius_m / s).ceil() as isize;
    let r2 = config.moment_radius_m * config.moment_radius_m;
    let quantisation = s * s / 12.0;
    let mut out = Vec::with_capacity(raw.len());
    for p in raw {
        let Some((pc, pr)) = grid.cell_of(&p.position) else {
            continue;
        };
        let level = config.moment_fraction * p.value;
        let mut cells: Vec<(Vec2, f64)> = Vec::new();
        for dr in -reach..=reach {
            for dc in -reach..=reach {
                let (c, r) = (pc as isize + dc, pr as isize + dr);
                if c < 0 || r < 0 || c >= cols as isize || r >= rows as isize {
                    continue;
                }
                let centre = grid.cell_centre(c as usize, r as usize);
                let v = grid.value(c as usize, r as usize);
                if (centre - p.position).norm_squared() <= r2 && v >= level {
                    cells.push((centre, v - level));
                }
            }
        }
        let total: f64 = cells.iter().map(|c| c.1).sum();
        let (mean, cov) = if total > 0.0 {
            let mean = cells.iter().map(|(q, w)| q * *w).sum::<Vec2>() / total;
            let cov = cells
                .iter()
                .map(|(q, w)| (q - mean) * (q - mean).transpose() * *w)
                .sum::<Matrix2<f64>>()
                / total;
            (mean, cov)
        } else {
            // A flat peak (moment_fraction 0 on a plateau): the cell itself.
            (p.position, Matrix2::zeros())
        };
        out.push(PeakMeasurement {
            position: mean,
            covariance: cov + Matrix2::identity() * quantisation,
            value: p.value,
        });
    }
    Ok(out)
}
