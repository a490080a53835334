//! `gdt-gaps`: Oh & Jung's (2015) experiment on a synthetic pedestrian scene shaped like PETS2009 S2L1
//! (768×576 pixels, 7 fps): walkers whose speed and heading drift smoothly, a 100×100 mask, and
//! every masked crossing recovered by GDT and by the baselines; MAE per axis, Total (both
//! conventions) and MMAE in the format of Oh & Jung's Table 1, and time per gap (Table 2).

use anyhow::Result;
use eval_metrics::{Mae, mae, mmae};
use gdt_bridge::{
    BSplineConfig, Baseline, GapCase, GdtConfig, Observation, RecoveredGap, gaps_from_mask,
    recover_baseline, recover_gdt, recover_gdt_goal_state,
};
use nalgebra::Vector2;
use rand::{Rng, RngExt};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Deserialize;
use tracker_model::{Region2, Track, TrackId, TrackPoint, TrackSet, Vec2};

use crate::{Chart, Clock, Env, Figure, Metrics, Pipeline, Section, Series, Style, Table, fmt_num};

/// The `gdt-gaps` pipeline.
pub struct GdtGaps;

/// Its parameters.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    width: f64,
    height: f64,
    n_walkers: usize,
    n_frames: u32,
    mask: Region2,
    /// Mean walking speed (pixels per frame).
    speed: f64,
    /// Standard deviation of the heading's turn rate change per frame (radians).
    turn_noise: f64,
    /// Relative speed drift per frame.
    speed_noise: f64,
    /// Detector noise on the observed positions (pixels).
    detection_sigma: f64,
    gdt: GdtConfig,
    bspline: BSplineConfig,
}

/// One walker: enters at a random time from a random border point, heads roughly across the
/// scene, turns smoothly (an integrated random turn rate) and changes speed smoothly, until it
/// leaves the image or the sequence ends.
fn walker(p: &Params, id: u64, rng: &mut impl Rng) -> Result<Option<(Track, Track)>> {
    let start = rng.random_range(0..p.n_frames / 2);
    let (w, h) = (p.width, p.height);
    let side = rng.random_range(0..4);
    let along: f64 = rng.random();
    let mut pos = match side {
        0 => Vector2::new(along * w, 1.0),
        1 => Vector2::new(along * w, h - 1.0),
        2 => Vector2::new(1.0, along * h),
        _ => Vector2::new(w - 1.0, along * h),
    };
    // Aim at a point near the centre so that many walkers cross the mask.
    let target = Vector2::new(
        w / 2.0 + rng.random_range(-0.25..0.25) * w,
        h / 2.0 + rng.random_range(-0.25..0.25) * h,
    );
    let mut heading = (target.y - pos.y).atan2(target.x - pos.x);
    let mut turn_rate = 0.0;
    let mut speed = p.speed * rng.random_range(0.7..1.3);
    let (mut truth, mut seen) = (Vec::new(), Vec::new());
    for f in start..p.n_frames {
        if !(0.0..=w).contains(&pos.x) || !(0.0..=h).contains(&pos.y) {
            break;
        }
        truth.push(TrackPoint::at(f, pos));
        let noise: Vector2<f64> = Vector2::from_fn(|_, _| StandardNormal.sample(rng));
        seen.push(TrackPoint::at(f, pos + noise * p.detection_sigma));
        let n: f64 = StandardNormal.sample(rng);
        turn_rate = 0.9 * turn_rate + p.turn_noise * n;
        heading += turn_rate;
        let s: f64 = StandardNormal.sample(rng);
        speed = (speed * (1.0 + p.speed_noise * s)).clamp(0.3 * p.speed, 2.0 * p.speed);
        pos += Vector2::new(heading.cos(), heading.sin()) * speed;
    }
    if truth.len() < 3 {
        return Ok(None);
    }
    Ok(Some((
        Track::from_points(TrackId(id), truth)?,
        Track::from_points(TrackId(id), seen)?,
    )))
}

/// A method's name and how it recovers a gap.
type Method = (
    &'static str,
    Box<dyn Fn(&[Observation], &[Observation]) -> gdt_bridge::Result<RecoveredGap>>,
);

/// A masked crossing with the noisy observations before and after it.
type Case = (GapCase, Vec<Observation>, Vec<Observation>);

/// How one method did over all gaps.
pub struct MethodResult {
    name: &'static str,
    /// MAE over all hidden positions pooled.
    pooled: Mae,
    /// Mean of the per-gap MAEs.
    mmae: Mae,
    /// Wall-clock microseconds per gap.
    micros: f64,
    /// Its recovery of the longest gap.
    longest: RecoveredGap,
}

/// The scene, the gaps and every method's errors.
pub struct Output {
    width: f64,
    height: f64,
    n_frames: u32,
    /// Walkers kept (at least three frames in view).
    n_walkers: usize,
    mask_lower: Vec2,
    mask_upper: Vec2,
    n_gaps: usize,
    /// Hidden positions over all gaps.
    n_hidden: usize,
    /// The longest gap with its observations before and after.
    longest: Case,
    /// Per method, in the order of the tables.
    methods: Vec<MethodResult>,
}

/// The walkers' true and observed tracks, drawn in order from `rng`.
fn simulate(p: &Params, rng: &mut impl Rng) -> Result<(TrackSet, TrackSet)> {
    let (mut truth, mut seen) = (Vec::new(), Vec::new());
    for id in 0..p.n_walkers as u64 {
        if let Some((t, s)) = walker(p, id, rng)? {
            truth.push(t);
            seen.push(s);
        }
    }
    Ok((TrackSet::from_tracks(truth)?, TrackSet::from_tracks(seen)?))
}

/// Gaps are cut from the truth; the methods see the noisy observations at the same frames.
fn cut_gaps(truth: &TrackSet, seen: &TrackSet, mask: &Region2) -> Vec<Case> {
    let observed = |c: &GapCase, side: &[Observation]| -> Vec<Observation> {
        let track = seen.get(c.truth_id);
        side.iter()
            .filter_map(|o| {
                track.and_then(|t| t.at(o.frame)).map(|q| Observation {
                    frame: o.frame,
                    position: q.location.position(),
                })
            })
            .collect()
    };
    gaps_from_mask(truth, mask)
        .into_iter()
        .map(|c| {
            let (b, a) = (observed(&c, &c.before), observed(&c, &c.after));
            (c, b, a)
        })
        .collect()
}

/// GDT, its goal-state variant and the baselines.
fn methods(p: &Params) -> Result<Vec<Method>> {
    let gdt = p.gdt.check()?;
    let bs = p.bspline.clone();
    Ok(vec![
        (
            "GDT",
            Box::new(move |a: &[Observation], b: &[Observation]| recover_gdt(a, b, &gdt)),
        ),
        (
            "GDT goal state",
            Box::new(move |a: &[Observation], b: &[Observation]| {
                recover_gdt_goal_state(a, b, &gdt)
            }),
        ),
        (
            "Linear",
            Box::new(|a: &[Observation], b: &[Observation]| {
                recover_baseline(a, b, &Baseline::Linear)
            }),
        ),
        (
            "Cubic spline",
            Box::new(|a: &[Observation], b: &[Observation]| {
                recover_baseline(a, b, &Baseline::NaturalCubicSpline)
            }),
        ),
        (
            "B-spline",
            Box::new(move |a: &[Observation], b: &[Observation]| {
                recover_baseline(a, b, &Baseline::LeastSquaresBSpline(bs.clone()))
            }),
        ),
    ])
}

/// Recovers every gap with one method, times it and scores it.
fn evaluate(
    method: &Method,
    cases: &[Case],
    longest: usize,
    clock: &dyn Clock,
) -> Result<MethodResult> {
    let (name, recover) = method;
    let mut per_gap: Vec<Mae> = Vec::with_capacity(cases.len());
    let (mut all_truth, mut all_est) = (Vec::new(), Vec::new());
    let start = clock.now_s();
    let recovered: Vec<RecoveredGap> = cases
        .iter()
        .map(|(_, before, after)| recover(before, after))
        .collect::<gdt_bridge::Result<_>>()?;
    let micros = (clock.now_s() - start) * 1e6 / cases.len() as f64;
    for ((case, _, _), r) in cases.iter().zip(&recovered) {
        let t: Vec<Vec2> = case.hidden.iter().map(|o| o.position).collect();
        per_gap.push(mae(&t, &r.positions)?);
        all_truth.extend(t);
        all_est.extend(r.positions.iter().copied());
    }
    let pooled = mae(&all_truth, &all_est)?;
    let m = mmae(&per_gap)?;
    Ok(MethodResult {
        name,
        pooled,
        mmae: m,
        micros,
        longest: recovered[longest].clone(),
    })
}

impl Pipeline for GdtGaps {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        let (truth, seen) = simulate(p, rng)?;
        let mut cases = cut_gaps(&truth, &seen, &p.mask);
        anyhow::ensure!(
            !cases.is_empty(),
            "no trajectory crosses the mask; change the seed or the scene"
        );
        let methods = methods(p)?;
        env.progress.set_length(methods.len() as u64);
        let longest = cases
            .iter()
            .enumerate()
            .max_by_key(|(_, c)| c.0.hidden.len())
            .map_or(0, |(i, _)| i);
        let mut results = Vec::with_capacity(methods.len());
        for method in &methods {
            results.push(evaluate(method, &cases, longest, env.clock)?);
            env.progress.advance(1);
        }
        Ok(Output {
            width: p.width,
            height: p.height,
            n_frames: p.n_frames,
            n_walkers: truth.len(),
            mask_lower: *p.mask.lower(),
            mask_upper: *p.mask.upper(),
            n_gaps: cases.len(),
            n_hidden: cases.iter().map(|c| c.0.hidden.len()).sum(),
            longest: cases.swap_remove(longest),
            methods: results,
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        for r in &out.methods {
            let key = r.name.to_lowercase().replace([' ', '-'], "_");
            metrics.insert(format!("{key}_mae_x"), r.pooled.x);
            metrics.insert(format!("{key}_mae_y"), r.pooled.y);
            metrics.insert(format!("{key}_total_euclidean"), r.pooled.euclidean);
            metrics.insert(format!("{key}_total_axis_mean"), r.pooled.axis_mean);
            metrics.insert(format!("{key}_mmae"), r.mmae.euclidean);
        }
        metrics.insert("n_gaps".into(), out.n_gaps as f64);
        metrics
    }

    fn present(out: &Output) -> Section {
        let (lo, hi) = (out.mask_lower, out.mask_upper);
        let (table, timing) = tables(out);
        Section {
            title: "Goal-directed gap recovery against spline baselines".into(),
            summary: format!(
                "{} walkers over {} frames in a {}×{} image; a {}×{} mask hides each crossing. \
                 Oh & Jung (2015) report MMAE 2.21 px (GDT) against 2.77 (cubic spline) and 2.84 (B-spline) on \
                 PETS2009 S2L1; here the scene is synthetic, so compare the ordering, not the values.",
                out.n_walkers,
                out.n_frames,
                out.width,
                out.height,
                hi.x - lo.x,
                hi.y - lo.y
            ),
            tables: vec![table, timing],
            figures: vec![
                Figure::new(
                    "band",
                    "x of the longest crossing: truth, recoveries and GDT's ±2σ band",
                    band_chart(out),
                ),
                Figure::new(
                    "path",
                    "The longest crossing in the image with the mask",
                    path_chart(out),
                ),
            ],
        }
    }
}

/// The error table (Oh & Jung 2015, Table 1) and the timing table (Table 2).
fn tables(out: &Output) -> (Table, Table) {
    let mut table = Table::new(
        &format!(
            "Recovery error in pixels over {} masked crossings ({} hidden positions), format of Oh & Jung 2015, Table 1",
            out.n_gaps, out.n_hidden
        ),
        &[
            "method",
            "MAE X",
            "MAE Y",
            "Total (mean Euclidean)",
            "Total (mean of axes)",
            "MMAE (Euclidean)",
        ],
    );
    let mut timing = Table::new(
        "Execution time per gap (Oh & Jung 2015, Table 2 format; wall clock, this machine)",
        &["method", "µs per gap"],
    );
    for r in &out.methods {
        table.row(vec![
            r.name.into(),
            fmt_num(r.pooled.x),
            fmt_num(r.pooled.y),
            fmt_num(r.pooled.euclidean),
            fmt_num(r.pooled.axis_mean),
            fmt_num(r.mmae.euclidean),
        ]);
        timing.row(vec![r.name.into(), fmt_num(r.micros)]);
    }
    (table, timing)
}

/// The longest gap: x against frame with GDT's ±2σ band.
fn band_chart(out: &Output) -> Chart {
    let (case, before, after) = &out.longest;
    let frame_x = |obs: &[Observation]| {
        obs.iter()
            .map(|o| (f64::from(o.frame), o.position.x))
            .collect::<Vec<_>>()
    };
    let mut series = vec![
        Series::new(
            "observed",
            frame_x(before).into_iter().chain(frame_x(after)).collect(),
            Style::Markers,
            7,
        ),
        Series::new("truth", frame_x(&case.hidden), Style::Line, 5),
    ];
    for (c, m) in out.methods.iter().enumerate() {
        let r = &m.longest;
        let pts = r
            .frames
            .iter()
            .zip(&r.positions)
            .map(|(f, q)| (f64::from(*f), q.x))
            .collect();
        series.push(Series::new(
            m.name,
            pts,
            if c == 0 { Style::Line } else { Style::ThinLine },
            c,
        ));
        if c == 0 {
            for sign in [-2.0, 2.0] {
                let band = r
                    .frames
                    .iter()
                    .zip(&r.positions)
                    .zip(&r.covariances)
                    .map(|((f, q), cov)| (f64::from(*f), q.x + sign * cov[(0, 0)].sqrt()))
                    .collect();
                series.push(Series::new(
                    if sign < 0.0 { "GDT ± 2σ" } else { "" },
                    band,
                    Style::ThinLine,
                    4,
                ));
            }
        }
    }
    Chart::new(
        "Longest masked crossing: x against frame",
        "frame",
        "x (pixels)",
        series,
    )
}

/// The longest gap's path in the image, with the mask.
fn path_chart(out: &Output) -> Chart {
    let (case, before, after) = &out.longest;
    let xy = |obs: &[Observation]| {
        obs.iter()
            .map(|o| (o.position.x, o.position.y))
            .collect::<Vec<_>>()
    };
    let (lo, hi) = (out.mask_lower, out.mask_upper);
    let mut series = vec![
        Series::new(
            "mask",
            vec![
                (lo.x, lo.y),
                (hi.x, lo.y),
                (hi.x, hi.y),
                (lo.x, hi.y),
                (lo.x, lo.y),
            ],
            Style::ThinLine,
            7,
        ),
        Series::new(
            "observed",
            xy(before).into_iter().chain(xy(after)).collect(),
            Style::Markers,
            7,
        ),
        Series::new("truth", xy(&case.hidden), Style::Line, 5),
    ];
    for (c, m) in out.methods.iter().enumerate() {
        series.push(Series::new(
            m.name,
            m.longest.positions.iter().map(|q| (q.x, q.y)).collect(),
            Style::Line,
            c,
        ));
    }
    Chart::new(
        "Longest masked crossing in the image",
        "x (pixels)",
        "y (pixels)",
        series,
    )
}
