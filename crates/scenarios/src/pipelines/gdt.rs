//! `gdt-gaps`: Oh & Jung's (2015) experiment on synthetic pedestrian scenes shaped like
//! PETS2009 S2L1 (768×576 pixels, 7 fps): walkers whose speed and heading drift smoothly, a
//! 100×100 mask, and every masked crossing of 5 to 40 frames recovered by GDT and by the
//! baselines, over many independent scenes. MAE per axis, Total (both conventions) and MMAE in
//! the format of Oh & Jung's Table 1 with a 95 % interval, paired differences to our method,
//! MAE against gap length, and time per gap (Table 2).
//!
//! Fairness: every fair row sees only the observations of the two segments. GDT and
//! its goal-state variant estimate their noise (r, q) by maximum likelihood over those
//! observations; the rows with the simulator's σ² and the hand-set q are labelled "oracle
//! noise". The smoothing spline's λ (GCV) and the window fits' n (cross-validation on
//! pseudo-gaps cut inside the segments, per gap or summed over a scene's gaps) are chosen from
//! the observations, never from the hidden positions. The reported scenes (streams of the
//! scenario seed) were used for no choice; the two "tuned" rows fix n at the best value on the
//! truth of separate tuning scenes (seed 7). That is tuning on separate seeds, which the
//! project's rules allow, but with a ground truth a practitioner would not have, so those rows
//! stay out of "fair" (observation-only) and are reported beside ours: against them our lead
//! is not significant, and the report says so.

use anyhow::Result;
use eval_metrics::{Mae, mae, mmae};
use gdt_bridge::scene::{ObservedGap, Scene, SceneConfig, cut_gaps, scene_window};
use gdt_bridge::{
    BSplineConfig, Baseline, GcvConfig, GdtConfig, NoiseSearch, Observation, RecoveredGap,
    WindowConfig, estimate_noise, recover_baseline, recover_gdt, recover_gdt_goal_state,
};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Deserialize;
use tracker_model::{Region2, Vec2};

use crate::{
    Chart, Claim, Clock, Env, Figure, Headline, Metrics, Pipeline, Section, Series, Style, Table,
    fmt_num,
};

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
    /// Independent scenes: generator streams 0..n_runs of the scenario's seed.
    n_runs: usize,
    /// Gaps kept: crossings hiding between these many frames (inclusive).
    gap_frames: [usize; 2],
    /// The "oracle noise" model: measurement variance = detection_sigma², q hand-set.
    gdt: GdtConfig,
    /// The maximum-likelihood search of the fair GDT rows.
    noise_search: NoiseSearch,
    /// Oh & Jung's B-spline knot rule.
    bspline: BSplineConfig,
    /// The smoothing spline's λ search.
    gcv: GcvConfig,
    /// The window fits' candidate n.
    window: WindowConfig,
    /// The window (B-spline, cubic) of the "tuned" rows: the best fixed n against the truth of
    /// tuning scenes (a different seed), a ceiling for what choosing n can achieve.
    window_tuned: [usize; 2],
}

impl Params {
    /// The simulated scene these parameters describe.
    fn scene(&self) -> SceneConfig {
        SceneConfig {
            width: self.width,
            height: self.height,
            n_walkers: self.n_walkers,
            n_frames: self.n_frames,
            speed: self.speed,
            turn_noise: self.turn_noise,
            speed_noise: self.speed_noise,
            detection_sigma: self.detection_sigma,
        }
    }
}

/// The methods, in the order of the tables: (metric key, label, fair). A fair method sees only
/// the observations; the oracle rows get the simulator's noise; the last two are the
/// baselines of the earlier comparison, kept with their knot rules.
const METHODS: [(&str, &str, bool); 14] = [
    ("gdt_goal_state_ml", "GDT goal state (ours), ML noise", true),
    ("gdt_ml", "GDT, ML noise", true),
    ("smoothing_spline_gcv", "Smoothing spline, GCV λ", true),
    (
        "window_bspline_scene_cv",
        "Window B-spline, n by CV per scene",
        true,
    ),
    (
        "window_cubic_scene_cv",
        "Window cubic, n by CV per scene",
        true,
    ),
    (
        "window_bspline_cv",
        "Window B-spline, n by CV per gap",
        true,
    ),
    ("window_cubic_cv", "Window cubic, n by CV per gap", true),
    ("linear", "Linear", true),
    (
        "window_bspline_tuned",
        "Window B-spline, n tuned on seed-7 truth",
        false,
    ),
    (
        "window_cubic_tuned",
        "Window cubic, n tuned on seed-7 truth",
        false,
    ),
    (
        "gdt_goal_state_oracle",
        "GDT goal state, oracle noise",
        false,
    ),
    ("gdt_oracle", "GDT, oracle noise", false),
    (
        "cubic_spline",
        "Natural cubic spline (knot at every sample)",
        true,
    ),
    ("b_spline", "LSQ B-spline (Oh & Jung knots)", true),
];

/// Index of a method in [`METHODS`].
fn method(key: &str) -> usize {
    METHODS
        .iter()
        .position(|m| m.0 == key)
        .unwrap_or(usize::MAX)
}

/// One gap and how every method did on it.
pub struct CaseResult {
    /// The scene it comes from.
    run: usize,
    /// Hidden frames.
    n_hidden: usize,
    /// Per method: the per-gap MAE.
    maes: Vec<Mae>,
    /// Per method: wall-clock microseconds (the ML rows include the noise estimation).
    micros: Vec<f64>,
    /// The ML noise estimate (r, q).
    noise: (f64, f64),
}

/// How one method did over all gaps.
pub struct MethodResult {
    /// MAE over all hidden positions pooled.
    pooled: Mae,
    /// Mean of the per-gap MAEs.
    mmae: Mae,
    /// 95 % half-width of the mean per-gap Euclidean MAE.
    mmae_ci95: f64,
    /// Mean wall-clock microseconds per gap.
    micros: f64,
}

/// The scenes, the gaps and every method's errors.
pub struct Output {
    width: f64,
    height: f64,
    n_frames: u32,
    n_runs: usize,
    gap_frames: [usize; 2],
    /// Walkers kept (at least three frames in view), over all scenes.
    n_walkers: usize,
    /// The simulator's detection variance σ² (px²).
    detection_variance: f64,
    /// Crossings outside the gap-length range, not scored.
    n_dropped: usize,
    mask_lower: Vec2,
    mask_upper: Vec2,
    /// Hidden positions over all gaps.
    n_hidden: usize,
    /// The window (B-spline, cubic) chosen for each scene with gaps.
    scene_windows: Vec<[usize; 2]>,
    /// Every scored gap, in scene order.
    cases: Vec<CaseResult>,
    /// Per method, in the order of [`METHODS`].
    methods: Vec<MethodResult>,
    /// The longest gap with its observations and every method's recovery.
    longest: (ObservedGap, Vec<RecoveredGap>),
}

use crate::stats::mean_ci;

/// Every method's recovery of one gap, its wall-clock microseconds, and the ML noise (r, q).
type Recovered = (Vec<RecoveredGap>, Vec<f64>, (f64, f64));

/// Recovers one gap with every method (in the order of [`METHODS`]), timing each.
fn recover_all(
    p: &Params,
    gap: &ObservedGap,
    scene_n: [usize; 2],
    clock: &dyn Clock,
) -> Result<Recovered> {
    let (a, b) = (&gap.before, &gap.after);
    let fixed = |n: usize| WindowConfig {
        candidates: vec![n],
    };
    let oracle = p.gdt.check()?;
    let t0 = clock.now_s();
    let estimate = estimate_noise(&[a, b], &p.noise_search)?;
    let ml = estimate.config.check()?;
    let fit_s = clock.now_s() - t0;
    let mut recovered = Vec::with_capacity(METHODS.len());
    let mut micros = Vec::with_capacity(METHODS.len());
    for (key, _, _) in METHODS {
        let start = clock.now_s();
        let r = match key {
            "gdt_goal_state_ml" => recover_gdt_goal_state(a, b, &ml),
            "gdt_ml" => recover_gdt(a, b, &ml),
            "smoothing_spline_gcv" => {
                recover_baseline(a, b, &Baseline::SmoothingSpline(p.gcv.clone()))
            }
            "window_bspline_cv" => {
                recover_baseline(a, b, &Baseline::WindowBSpline(p.window.clone()))
            }
            "window_cubic_cv" => recover_baseline(a, b, &Baseline::WindowCubic(p.window.clone())),
            "window_bspline_tuned" => {
                recover_baseline(a, b, &Baseline::WindowBSpline(fixed(p.window_tuned[0])))
            }
            "window_cubic_tuned" => {
                recover_baseline(a, b, &Baseline::WindowCubic(fixed(p.window_tuned[1])))
            }
            "window_bspline_scene_cv" => {
                recover_baseline(a, b, &Baseline::WindowBSpline(fixed(scene_n[0])))
            }
            "window_cubic_scene_cv" => {
                recover_baseline(a, b, &Baseline::WindowCubic(fixed(scene_n[1])))
            }
            "linear" => recover_baseline(a, b, &Baseline::Linear),
            "gdt_goal_state_oracle" => recover_gdt_goal_state(a, b, &oracle),
            "gdt_oracle" => recover_gdt(a, b, &oracle),
            "cubic_spline" => recover_baseline(a, b, &Baseline::NaturalCubicSpline),
            "b_spline" => recover_baseline(a, b, &Baseline::LeastSquaresBSpline(p.bspline.clone())),
            other => anyhow::bail!("no recovery for method {other}"),
        }?;
        let mut s = clock.now_s() - start;
        if key.ends_with("_ml") {
            s += fit_s;
        }
        micros.push(s * 1e6);
        recovered.push(r);
    }
    let noise = (
        estimate.config.measurement_variance,
        estimate.config.accel_psd,
    );
    Ok((recovered, micros, noise))
}

/// One scene: its walkers, its gaps in the length range, and every method's recovery.
type RunOut = (
    usize,
    usize,
    [usize; 2],
    Vec<(ObservedGap, Vec<RecoveredGap>, Vec<f64>, (f64, f64))>,
);

fn one_run(
    p: &Params,
    scene: &Scene,
    run: usize,
    rng: &mut ChaCha8Rng,
    clock: &dyn Clock,
) -> Result<RunOut> {
    let (truth, seen) = scene.simulate(rng)?;
    let cases = cut_gaps(&truth, &seen, &p.mask);
    let n_all = cases.len();
    let [lo, hi] = p.gap_frames;
    // Each side needs two observations for the filters and three for the window B-spline.
    let cases: Vec<ObservedGap> = cases
        .into_iter()
        .filter(|c| {
            (lo..=hi).contains(&c.case.hidden.len()) && c.before.len() >= 3 && c.after.len() >= 3
        })
        .collect();
    // One window per scene: the candidate with the least cross-validation error summed over
    // the scene's gaps (observations only).
    let mut scene_n = [0; 2];
    for (slot, method) in [
        Baseline::WindowBSpline(p.window.clone()),
        Baseline::WindowCubic(p.window.clone()),
    ]
    .iter()
    .enumerate()
    {
        scene_n[slot] = match scene_window(&cases, method)? {
            Some(n) => n,
            None if cases.is_empty() => 0,
            None => anyhow::bail!("no window candidate fits every gap of scene {run}"),
        };
    }
    let mut out = Vec::new();
    for case in cases {
        let (recovered, micros, noise) = recover_all(p, &case, scene_n, clock)?;
        out.push((case, recovered, micros, noise));
    }
    Ok((truth.len(), n_all - out.len(), scene_n, out))
}

/// Checks that the oracle rows and the ML rows share what Oh & Jung's (2015) comparison
/// holds fixed: the oracle's measurement variance is the simulator's σ², and both start
/// from the same initial velocity variance.
fn check_params(p: &Params) -> Result<()> {
    anyhow::ensure!(p.n_runs > 0, "need n_runs > 0");
    anyhow::ensure!(
        (p.gdt.measurement_variance - p.detection_sigma.powi(2)).abs() < 1e-12,
        "the oracle's measurement_variance must be detection_sigma²"
    );
    anyhow::ensure!(
        (p.gdt.initial_velocity_variance - p.noise_search.initial_velocity_variance).abs() < 1e-12,
        "the oracle and the ML rows must share initial_velocity_variance"
    );
    Ok(())
}

/// Every scene, in parallel: scene r on stream r of the scenario's generator, so the result
/// does not depend on rayon's thread count; results come back in scene order.
fn run_scenes(p: &Params, rng: &ChaCha8Rng, env: &Env<'_>) -> Result<Vec<RunOut>> {
    let scene = p.scene().check()?;
    let base = rng.clone();
    (0..p.n_runs)
        .into_par_iter()
        .map(|r| {
            let mut rng = base.clone();
            rng.set_stream(r as u64);
            let out = one_run(p, &scene, r, &mut rng, env.clock);
            env.progress.advance(1);
            out
        })
        .collect::<Result<_>>()
}

/// The gaps of every scene pooled, in scene order.
struct Pooled {
    n_walkers: usize,
    n_dropped: usize,
    cases: Vec<CaseResult>,
    /// Every hidden position, and every method's estimate of it, in gap order.
    all_truth: Vec<Vec2>,
    all_est: Vec<Vec<Vec2>>,
    /// The longest gap (the first of that length) with every method's recovery.
    longest: Option<(ObservedGap, Vec<RecoveredGap>)>,
    scene_windows: Vec<[usize; 2]>,
}

/// Pools the scenes' gaps: each gap's per-method MAE (Oh & Jung 2015, Table 1's per-gap
/// error), the hidden positions with every method's estimates for the pooled MAE, and the
/// longest gap for the figures.
fn pool_gaps(runs: Vec<RunOut>) -> Result<Pooled> {
    let mut pooled = Pooled {
        n_walkers: 0,
        n_dropped: 0,
        cases: Vec::new(),
        all_truth: Vec::new(),
        all_est: vec![Vec::new(); METHODS.len()],
        longest: None,
        scene_windows: Vec::new(),
    };
    for (run, (walkers, dropped, windows, gaps)) in runs.into_iter().enumerate() {
        pooled.n_walkers += walkers;
        pooled.n_dropped += dropped;
        if !gaps.is_empty() {
            pooled.scene_windows.push(windows);
        }
        for (case, recovered, micros, noise) in gaps {
            let truth: Vec<Vec2> = case.case.hidden.iter().map(|o| o.position).collect();
            let maes = recovered
                .iter()
                .map(|r| mae(&truth, &r.positions))
                .collect::<eval_metrics::Result<Vec<_>>>()?;
            for (k, r) in recovered.iter().enumerate() {
                pooled.all_est[k].extend(r.positions.iter().copied());
            }
            pooled.all_truth.extend(&truth);
            pooled.cases.push(CaseResult {
                run,
                n_hidden: truth.len(),
                maes,
                micros,
                noise,
            });
            if pooled
                .longest
                .as_ref()
                .is_none_or(|(c, _)| c.case.hidden.len() < truth.len())
            {
                pooled.longest = Some((case, recovered));
            }
        }
    }
    Ok(pooled)
}

/// Every method's MAE over the pooled hidden positions, MMAE with its 95 % interval over the
/// gaps, and mean time per gap: the columns of Oh & Jung's (2015) Tables 1 and 2.
fn method_results(
    cases: &[CaseResult],
    all_truth: &[Vec2],
    all_est: &[Vec<Vec2>],
) -> Result<Vec<MethodResult>> {
    (0..METHODS.len())
        .map(|k| -> Result<MethodResult> {
            let per_gap: Vec<Mae> = cases.iter().map(|c| c.maes[k]).collect();
            let euclid: Vec<f64> = per_gap.iter().map(|m| m.euclidean).collect();
            let micros: Vec<f64> = cases.iter().map(|c| c.micros[k]).collect();
            Ok(MethodResult {
                pooled: mae(all_truth, &all_est[k])?,
                mmae: mmae(&per_gap)?,
                mmae_ci95: mean_ci(&euclid).1,
                micros: mean_ci(&micros).0,
            })
        })
        .collect::<Result<Vec<_>>>()
}

impl Pipeline for GdtGaps {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        check_params(p)?;
        env.progress.set_length(p.n_runs as u64);
        let runs = run_scenes(p, rng, env)?;
        let pooled = pool_gaps(runs)?;
        let longest = pooled
            .longest
            .ok_or_else(|| anyhow::anyhow!("no crossing of the mask in the gap range"))?;
        let methods = method_results(&pooled.cases, &pooled.all_truth, &pooled.all_est)?;
        Ok(Output {
            width: p.width,
            height: p.height,
            n_frames: p.n_frames,
            n_runs: p.n_runs,
            gap_frames: p.gap_frames,
            n_walkers: pooled.n_walkers,
            detection_variance: p.detection_sigma.powi(2),
            n_dropped: pooled.n_dropped,
            mask_lower: *p.mask.lower(),
            mask_upper: *p.mask.upper(),
            n_hidden: pooled.all_truth.len(),
            scene_windows: pooled.scene_windows,
            cases: pooled.cases,
            methods,
            longest,
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        for ((key, _, _), r) in METHODS.iter().zip(&out.methods) {
            metrics.insert(format!("{key}_mae_x"), r.pooled.x);
            metrics.insert(format!("{key}_mae_y"), r.pooled.y);
            metrics.insert(format!("{key}_total_euclidean"), r.pooled.euclidean);
            metrics.insert(format!("{key}_total_axis_mean"), r.pooled.axis_mean);
            metrics.insert(format!("{key}_mmae"), r.mmae.euclidean);
            metrics.insert(format!("{key}_mmae_ci95"), r.mmae_ci95);
        }
        metrics.insert("n_gaps".into(), out.cases.len() as f64);
        metrics.insert("n_hidden".into(), out.n_hidden as f64);
        metrics.insert("n_dropped".into(), out.n_dropped as f64);
        let scenes: std::collections::BTreeSet<usize> = out.cases.iter().map(|c| c.run).collect();
        metrics.insert("n_scenes_with_gaps".into(), scenes.len() as f64);
        let (r, q) = noise_medians(out);
        metrics.insert("ml_measurement_variance_median".into(), r);
        metrics.insert("ml_accel_psd_median".into(), q);
        metrics
    }

    fn present(out: &Output) -> Section {
        Section {
            title: "Goal-directed gap recovery against spline baselines".into(),
            summary: summary(out),
            tables: vec![
                error_table(out),
                paired_table(out),
                length_table(out),
                noise_table(out),
                timing_table(out),
            ],
            figures: vec![
                Figure::new(
                    "length",
                    "Mean per-gap MAE against gap length (fair methods, ± 95 % CI of GDT goal state)",
                    length_chart(out),
                ),
                Figure::new(
                    "band",
                    "x of the longest crossing: truth, recoveries and the goal-state GDT's ±2σ band",
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

    fn claims(out: &Output) -> Vec<Claim> {
        claims(out)
    }

    fn headlines(out: &Output) -> Vec<Headline> {
        let mmae = |key: &str| {
            let m = &out.methods[method(key)];
            format!("{} ± {}", fmt_num(m.mmae.euclidean), fmt_num(m.mmae_ci95))
        };
        // Oh & Jung (2015), Table 1 on PETS2009 S2L1; ours are the synthetic scenes, so the
        // columns compare orderings, not values.
        [
            (
                "MMAE (px), GDT with Oh & Jung's goal",
                "gdt_ml",
                Some("2.21"),
            ),
            (
                "MMAE (px), GDT goal state (ours)",
                "gdt_goal_state_ml",
                None,
            ),
            (
                "MMAE (px), cubic spline (their baseline)",
                "cubic_spline",
                Some("2.77"),
            ),
            (
                "MMAE (px), smoothing spline with GCV λ",
                "smoothing_spline_gcv",
                None,
            ),
        ]
        .into_iter()
        .map(|(quantity, key, paper)| Headline {
            quantity: quantity.to_string(),
            paper: paper.map(str::to_string),
            ours: mmae(key),
            peer: None,
        })
        .collect()
    }
}

/// The report's summary: the scenes, what every fair method sees, and the result against Oh &
/// Jung's (2015) ordering, with the numbers of the tables.
fn summary(out: &Output) -> String {
    let (lo, hi) = (out.mask_lower, out.mask_upper);
    let best = best_fair(out);
    let m = |key: &str| mmae_pm(out, key);
    let d = |key: &str| difference_pm(out, key);
    let (dg, dg_ci) = paired_difference(out, method("gdt_ml"), method("smoothing_spline_gcv"));
    format!(
        "{} scenes (generator streams 0–{} of the scenario seed) with {} walkers on average \
         over {} frames each in a {}×{} image; a {}×{} mask hides each crossing. {} crossings \
         of {}–{} frames ({} hidden positions) are scored; {} crossings outside that range \
         (or with fewer than 3 observations on a side) are not. MMAE is mean ± 95 % CI \
         (1.96·s/√n over gaps); differences are paired over the same gaps. Every fair \
         method sees only the observed frames: GDT's noise (r, q) is a maximum-likelihood \
         estimate over the two segments, the smoothing spline's λ is chosen by GCV, the \
         window fits' n by cross-validation on pseudo-gaps of the same length cut inside \
         the segments (per gap, or summed over a scene's gaps: median n {} for the B-spline \
         and {} for the cubic). No reported seed was used for tuning. Result: the best fair \
         method is {} (MMAE {}). Ours is the goal-state variant (the goal is B's full state \
         from a backward filter, not in Oh & Jung): {}. It beats the GCV smoothing spline \
         ({}) by {} px per gap, a small margin; {} GDT as Oh & Jung define it (goal: B's first \
         observation) loses to every fair spline: {} against {} for the smoothing spline \
         (paired difference {} px), {} for the window B-spline with n chosen per scene and \
         {} for the window cubic. A window B-spline whose n was fixed on the truth of \
         tuning scenes (seed 7) is not distinguishable from ours ({}, difference {} px), so \
         ours wins against what a practitioner can tune from the observations, not against \
         every spline. Noise estimated by maximum likelihood costs nothing measurable: the \
         oracle-noise rows differ from the ML rows by {} px (goal state). Oh & Jung report \
         MMAE 2.21 px (GDT) against 2.77 (cubic spline) and 2.84 (B-spline) on PETS2009 \
         S2L1; their ordering comes from splines that interpolate the noise or underfit \
         (our last two rows) and does not hold against fairly tuned splines.",
        out.n_runs,
        out.n_runs - 1,
        fmt_num(out.n_walkers as f64 / out.n_runs as f64),
        out.n_frames,
        out.width,
        out.height,
        hi.x - lo.x,
        hi.y - lo.y,
        out.cases.len(),
        out.gap_frames[0],
        out.gap_frames[1],
        out.n_hidden,
        out.n_dropped,
        median_window(out, 0),
        median_window(out, 1),
        METHODS[best].1,
        pm(
            out.methods[best].mmae.euclidean,
            out.methods[best].mmae_ci95
        ),
        m("gdt_goal_state_ml"),
        m("smoothing_spline_gcv"),
        d("smoothing_spline_gcv"),
        ties_sentence(out),
        m("gdt_ml"),
        m("smoothing_spline_gcv"),
        pm(dg, dg_ci),
        m("window_bspline_scene_cv"),
        m("window_cubic_scene_cv"),
        m("window_bspline_tuned"),
        d("window_bspline_tuned"),
        d("gdt_goal_state_oracle"),
    )
}

/// A method's MMAE ± 95 % CI, as the summary quotes it.
fn mmae_pm(out: &Output, key: &str) -> String {
    let r = &out.methods[method(key)];
    pm(r.mmae.euclidean, r.mmae_ci95)
}

/// A method's paired per-gap MAE difference to the goal-state GDT (ours), as the summary
/// quotes it.
fn difference_pm(out: &Output, key: &str) -> String {
    let (d, ci) = paired_difference(out, method(key), method("gdt_goal_state_ml"));
    pm(d, ci)
}

/// The median window n chosen per scene by cross-validation (slot 0 the B-spline, 1 the
/// cubic).
fn median_window(out: &Output, slot: usize) -> usize {
    let mut ns: Vec<usize> = out.scene_windows.iter().map(|w| w[slot]).collect();
    ns.sort_unstable();
    ns.get(ns.len() / 2).copied().unwrap_or(0)
}

/// The summary's sentence on the gap-length bins where the GCV smoothing spline is at or
/// below ours.
fn ties_sentence(out: &Output) -> String {
    let ties = spline_ties(out);
    if ties.is_empty() {
        "ours has the lower mean in every gap-length bin.".to_string()
    } else {
        format!(
            "not in every gap-length bin: the spline's mean is at or below ours for \
             gaps of {} frames.",
            ties.join(", ")
        )
    }
}

/// Median of the ML noise estimates (r, q) over the gaps.
fn noise_medians(out: &Output) -> (f64, f64) {
    let median = |mut xs: Vec<f64>| {
        xs.sort_by(f64::total_cmp);
        xs.get(xs.len() / 2).copied().unwrap_or(f64::NAN)
    };
    (
        median(out.cases.iter().map(|c| c.noise.0).collect()),
        median(out.cases.iter().map(|c| c.noise.1).collect()),
    )
}

/// Quartiles (25 %, 75 %) of `xs`.
fn quartiles(mut xs: Vec<f64>) -> (f64, f64) {
    xs.sort_by(f64::total_cmp);
    let at = |f: f64| {
        xs.get((f * (xs.len() - 1) as f64).round() as usize)
            .copied()
    };
    (at(0.25).unwrap_or(f64::NAN), at(0.75).unwrap_or(f64::NAN))
}

/// The fair method with the lowest MMAE.
fn best_fair(out: &Output) -> usize {
    (0..METHODS.len())
        .filter(|&k| METHODS[k].2)
        .min_by(|&i, &j| {
            out.methods[i]
                .mmae
                .euclidean
                .total_cmp(&out.methods[j].mmae.euclidean)
        })
        .unwrap_or(0)
}

/// Mean and 95 % half-width of the per-gap difference MAE_k − MAE_reference (paired: the same
/// gaps).
fn paired_difference(out: &Output, k: usize, reference: usize) -> (f64, f64) {
    let d: Vec<f64> = out
        .cases
        .iter()
        .map(|c| c.maes[k].euclidean - c.maes[reference].euclidean)
        .collect();
    mean_ci(&d)
}

/// Formats a mean with its 95 % half-width.
fn pm(mean: f64, ci: f64) -> String {
    format!("{} ± {}", fmt_num(mean), fmt_num(ci))
}

/// How a method's noise or smoothing is set, for the error table's "noise / tuning" column.
fn tuning(key: &str) -> &'static str {
    match key {
        "gdt_goal_state_ml" | "gdt_ml" => "r, q by ML on the segments",
        "smoothing_spline_gcv" => "λ by GCV on the segments",
        "window_bspline_cv" | "window_cubic_cv" => "n by CV on the gap's observations",
        "window_bspline_scene_cv" | "window_cubic_scene_cv" => {
            "n by CV on the scene's observations"
        }
        "gdt_goal_state_oracle" | "gdt_oracle" => "oracle: simulator σ², hand-set q",
        "window_bspline_tuned" | "window_cubic_tuned" => "n fixed on tuning scenes' truth",
        "cubic_spline" => "interpolates every observation",
        "b_spline" => "fixed knots per side",
        _ => "none",
    }
}

/// The error table in the format of Oh & Jung (2015), Table 1: MAE per axis, both Totals and
/// MMAE ± 95 % CI per method.
fn error_table(out: &Output) -> Table {
    let mut table = Table::new(
        &format!(
            "Recovery error in pixels over {} masked crossings of {}–{} frames ({} hidden positions) \
             in {} scenes, format of Oh & Jung 2015, Table 1; MMAE is the mean per-gap Euclidean \
             MAE ± 95 % CI over gaps",
            out.cases.len(),
            out.gap_frames[0],
            out.gap_frames[1],
            out.n_hidden,
            out.n_runs
        ),
        &[
            "method",
            "noise / tuning",
            "MAE X",
            "MAE Y",
            "Total (mean Euclidean)",
            "Total (mean of axes)",
            "MMAE (Euclidean)",
        ],
    );
    for ((key, name, _), r) in METHODS.iter().zip(&out.methods) {
        table.row(vec![
            (*name).into(),
            tuning(key).into(),
            fmt_num(r.pooled.x),
            fmt_num(r.pooled.y),
            fmt_num(r.pooled.euclidean),
            fmt_num(r.pooled.axis_mean),
            pm(r.mmae.euclidean, r.mmae_ci95),
        ]);
    }
    table
}

/// The paired table: each method's per-gap MAE difference to the goal-state GDT with ML
/// noise (ours) over the same gaps, and the gaps where it beats ours.
fn paired_table(out: &Output) -> Table {
    let mut paired = Table::new(
        "Per-gap MAE difference to the goal-state GDT with ML noise (ours), mean ± 95 % CI over \
         the same gaps; positive: the method errs more than ours",
        &["method", "Δ MMAE (px)", "gaps where it beats ours"],
    );
    let goal = method("gdt_goal_state_ml");
    for (key, name, _) in METHODS.iter() {
        let k = method(key);
        if k != goal {
            let (d, ci) = paired_difference(out, k, goal);
            let wins = out
                .cases
                .iter()
                .filter(|c| c.maes[k].euclidean < c.maes[goal].euclidean)
                .count();
            paired.row(vec![
                (*name).into(),
                pm(d, ci),
                format!("{wins} of {}", out.cases.len()),
            ]);
        }
    }
    paired
}

/// The timing table in the format of Oh & Jung (2015), Table 2: wall-clock microseconds per
/// gap per method.
fn timing_table(out: &Output) -> Table {
    let mut timing = Table::new(
        "Execution time per gap (Oh & Jung 2015, Table 2 format; wall clock in the build that \
         ran the report, two threads; the ML rows include the noise search, the per-gap CV \
         rows their cross-validation; the per-scene rows exclude the scene's cross-validation)",
        &["method", "µs per gap"],
    );
    for ((_, name, _), r) in METHODS.iter().zip(&out.methods) {
        timing.row(vec![(*name).into(), fmt_num(r.micros)]);
    }
    timing
}

/// The noise table: GDT's maximum-likelihood (r, q) over the two segments of each gap
/// (median and quartiles over gaps) beside the oracle rows' values.
fn noise_table(out: &Output) -> Table {
    let mut noise = Table::new(
        "GDT's noise: maximum-likelihood estimates over the two segments of each gap (median and \
         quartiles over gaps) against the oracle rows' values",
        &["parameter", "ML median", "ML quartiles", "oracle"],
    );
    let (r, q) = noise_medians(out);
    let (r25, r75) = quartiles(out.cases.iter().map(|c| c.noise.0).collect());
    let (q25, q75) = quartiles(out.cases.iter().map(|c| c.noise.1).collect());
    noise.row(vec![
        "measurement variance r (px²)".into(),
        fmt_num(r),
        format!("{}–{}", fmt_num(r25), fmt_num(r75)),
        "detection σ²".into(),
    ]);
    noise.row(vec![
        "acceleration density q (px²/frame³)".into(),
        fmt_num(q),
        format!("{}–{}", fmt_num(q25), fmt_num(q75)),
        "hand-set (scenario file)".into(),
    ]);
    noise
}

/// Gap-length bins of the length chart: [5, 10), [10, 15), … up to the longest gap.
fn length_bins(out: &Output) -> Vec<(usize, usize)> {
    let [lo, hi] = out.gap_frames;
    let mut bins = Vec::new();
    let mut start = lo;
    while start <= hi {
        // The last bin takes the remainder rather than leaving a sliver.
        let end = if start + 10 > hi + 1 {
            hi + 1
        } else {
            start + 5
        };
        bins.push((start, end));
        start = end;
    }
    bins
}

/// The gap-length bins where the smoothing spline's mean per-gap MAE is at or below ours.
fn spline_ties(out: &Output) -> Vec<String> {
    let (goal, spline) = (method("gdt_goal_state_ml"), method("smoothing_spline_gcv"));
    length_bins(out)
        .into_iter()
        .filter_map(|(a, b)| {
            let cs: Vec<&CaseResult> = out
                .cases
                .iter()
                .filter(|c| c.n_hidden >= a && c.n_hidden < b)
                .collect();
            let mean = |k: usize| cs.iter().map(|c| c.maes[k].euclidean).sum::<f64>();
            (!cs.is_empty() && mean(spline) <= mean(goal)).then(|| format!("{a}–{}", b - 1))
        })
        .collect()
}

/// The numbers of the length chart for the main fair methods: mean per-gap MAE ± 95 % CI per
/// gap-length bin.
fn length_table(out: &Output) -> Table {
    let keys = [
        "gdt_goal_state_ml",
        "gdt_ml",
        "smoothing_spline_gcv",
        "window_bspline_scene_cv",
    ];
    let mut header = vec!["hidden frames", "gaps"];
    header.extend(keys.iter().map(|k| METHODS[method(k)].1));
    let mut table = Table::new("Mean per-gap MAE (px) ± 95 % CI by gap length", &header);
    for (a, b) in length_bins(out) {
        let cs: Vec<&CaseResult> = out
            .cases
            .iter()
            .filter(|c| c.n_hidden >= a && c.n_hidden < b)
            .collect();
        if cs.is_empty() {
            continue;
        }
        let mut row = vec![format!("{a}–{}", b - 1), cs.len().to_string()];
        for key in keys {
            let k = method(key);
            let (m, ci) = mean_ci(cs.iter().map(|c| c.maes[k].euclidean).collect::<Vec<_>>());
            row.push(pm(m, ci));
        }
        table.row(row);
    }
    table
}

/// Mean per-gap MAE against gap length, per fair method (the two earlier baselines are off
/// the scale and left out), with the 95 % band of ours.
fn length_chart(out: &Output) -> Chart {
    let shown = [
        "gdt_goal_state_ml",
        "gdt_ml",
        "smoothing_spline_gcv",
        "window_bspline_scene_cv",
        "window_cubic_scene_cv",
        "linear",
        "window_bspline_tuned",
    ];
    let bins = length_bins(out);
    let in_bin = |(a, b): (usize, usize)| -> Vec<&CaseResult> {
        out.cases
            .iter()
            .filter(|c| c.n_hidden >= a && c.n_hidden < b)
            .collect()
    };
    let mut series = Vec::new();
    for (colour, key) in shown.iter().enumerate() {
        let k = method(key);
        let mut pts = Vec::new();
        let mut band = (Vec::new(), Vec::new());
        for &bin in &bins {
            let cs = in_bin(bin);
            if cs.is_empty() {
                continue;
            }
            let len = cs.iter().map(|c| c.n_hidden as f64).sum::<f64>() / cs.len() as f64;
            let (m, ci) = mean_ci(cs.iter().map(|c| c.maes[k].euclidean).collect::<Vec<_>>());
            pts.push((len, m));
            band.0.push((len, m - ci));
            band.1.push((len, m + ci));
        }
        // Every method in a full colour of its own (pale shades of the baselines were hard
        // to tell apart); ours's CI in thin lines of its colour.
        series.push(Series::new(METHODS[k].1, pts, Style::Line, colour));
        if colour == 0 {
            series.push(Series::new("ours ± 95 % CI", band.0, Style::ThinLine, 0));
            series.push(Series::new("", band.1, Style::ThinLine, 0));
        }
    }
    Chart::new(
        "Mean per-gap MAE against gap length (bins of 5 frames)",
        "hidden frames",
        "mean per-gap MAE (px)",
        series,
    )
}

/// The methods drawn on the longest gap (the earlier baselines would hide the others).
const DRAWN: [&str; 5] = [
    "gdt_goal_state_ml",
    "gdt_ml",
    "smoothing_spline_gcv",
    "window_bspline_scene_cv",
    "linear",
];

/// The longest gap: x against frame with the goal-state GDT's ±2σ band.
fn band_chart(out: &Output) -> Chart {
    let (gap, recovered) = &out.longest;
    let (case, before, after) = (&gap.case, &gap.before, &gap.after);
    let frame_x = |obs: &[Observation]| {
        obs.iter()
            .map(|o| (f64::from(o.frame), o.position.x))
            .collect::<Vec<_>>()
    };
    // The observations near the gap only: as many frames either side as it is long.
    let span = case.hidden.len() as u32;
    let (first, last) = (
        case.hidden
            .first()
            .map_or(0, |o| o.frame.saturating_sub(span)),
        case.hidden
            .last()
            .map_or(0, |o| o.frame.saturating_add(span)),
    );
    let near: Vec<(f64, f64)> = frame_x(before)
        .into_iter()
        .chain(frame_x(after))
        .filter(|(f, _)| *f >= f64::from(first) && *f <= f64::from(last))
        .collect();
    let mut series = vec![
        Series::new("observed", near, Style::Markers, 7),
        Series::new("truth", frame_x(&case.hidden), Style::Line, 5).in_front(),
    ];
    for (c, key) in DRAWN.iter().enumerate() {
        let k = method(key);
        let r = &recovered[k];
        let pts = r
            .frames
            .iter()
            .zip(&r.positions)
            .map(|(f, q)| (f64::from(*f), q.x))
            .collect();
        series.push(Series::new(METHODS[k].1, pts, Style::Line, c));
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
                    if sign < 0.0 { "ours ± 2σ" } else { "" },
                    band,
                    Style::ThinLine,
                    0,
                ));
            }
        }
    }
    Chart::new(
        "Longest masked crossing: x against frame",
        "frame",
        "x (px)",
        series,
    )
}

/// The longest gap's path in the image, with the mask.
fn path_chart(out: &Output) -> Chart {
    let (gap, recovered) = &out.longest;
    let (case, before, after) = (&gap.case, &gap.before, &gap.after);
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
        Series::new("truth", xy(&case.hidden), Style::Line, 5).in_front(),
    ];
    for (c, key) in DRAWN.iter().enumerate() {
        let k = method(key);
        series.push(Series::new(
            METHODS[k].1,
            recovered[k].positions.iter().map(|q| (q.x, q.y)).collect(),
            Style::Line,
            c,
        ));
    }
    Chart::new(
        "Longest masked crossing in the image",
        "x (px)",
        "y (px)",
        series,
    )
    .in_image_coordinates()
    .with_equal_aspect()
}

/// The orderings the report states, each checked on this run.
fn claims(out: &Output) -> Vec<Claim> {
    let mmae = |key: &str| out.methods[method(key)].mmae.euclidean;
    let mut claims = vec![
        Claim::new(
            format!(
                "at least 200 gaps of {}–{} frames over at least 20 scenes",
                out.gap_frames[0], out.gap_frames[1]
            ),
            out.cases.len() >= 200
                && out.n_runs >= 20
                && out.gap_frames[0] <= 5
                && out.gap_frames[1] >= 40,
        ),
        Claim::new(
            "every fair spline (smoothing, window B-spline, window cubic) beats the natural cubic \
             spline through every observation and the LSQ B-spline with Oh & Jung's knots",
            [
                "smoothing_spline_gcv",
                "window_bspline_cv",
                "window_cubic_cv",
            ]
            .iter()
            .all(|k| mmae(k) < mmae("cubic_spline") && mmae(k) < mmae("b_spline")),
        ),
    ];
    claims.extend(extra_claims(out));
    claims
}

/// Orderings between the methods, as they come out on the reported scenes; a paired
/// difference "beats" only when its 95 % interval excludes zero.
fn extra_claims(out: &Output) -> Vec<Claim> {
    let mmae = |key: &str| out.methods[method(key)].mmae.euclidean;
    let beats = |a: &str, b: &str| {
        let (d, ci) = paired_difference(out, method(b), method(a));
        d - ci > 0.0
    };
    let (d_oracle, ci_oracle) = paired_difference(
        out,
        method("gdt_goal_state_oracle"),
        method("gdt_goal_state_ml"),
    );
    let (r, _) = noise_medians(out);
    vec![
        Claim::new(
            "the goal-state GDT with ML noise (ours) has the lowest MMAE of the fair methods",
            best_fair(out) == method("gdt_goal_state_ml"),
        ),
        Claim::new(
            "ours beats the GCV smoothing spline (paired 95 % CI of the difference excludes 0)",
            beats("gdt_goal_state_ml", "smoothing_spline_gcv"),
        ),
        Claim::new(
            "GDT with B's first observation as the goal (Oh & Jung), ML noise, has a higher MMAE \
             than every fair spline (smoothing, window B-spline and cubic with n per scene or \
             per gap)",
            [
                "smoothing_spline_gcv",
                "window_bspline_scene_cv",
                "window_cubic_scene_cv",
                "window_bspline_cv",
                "window_cubic_cv",
            ]
            .iter()
            .all(|k| mmae(k) < mmae("gdt_ml")),
        ),
        Claim::new(
            "the GCV smoothing spline beats GDT with B's first observation as the goal, ML noise \
             (paired 95 % CI excludes 0)",
            beats("smoothing_spline_gcv", "gdt_ml"),
        ),
        Claim::new(
            "ours beats GDT with B's first observation as the goal, with ML and with oracle noise \
             (paired 95 % CI excludes 0)",
            beats("gdt_goal_state_ml", "gdt_ml") && beats("gdt_goal_state_ml", "gdt_oracle"),
        ),
        Claim::new(
            "the window B-spline with n tuned on seed-7 truth is not distinguishable from ours \
             (paired 95 % CI includes 0)",
            {
                let (d, ci) = paired_difference(
                    out,
                    method("window_bspline_tuned"),
                    method("gdt_goal_state_ml"),
                );
                d - ci <= 0.0 && d + ci >= 0.0
            },
        ),
        Claim::new(
            "ML noise is as good as the oracle noise for the goal-state GDT (paired 95 % CI \
             includes 0)",
            d_oracle - ci_oracle <= 0.0 && d_oracle + ci_oracle >= 0.0,
        ),
        Claim::new(
            "the median ML measurement variance is within 10 % of the simulator's σ²",
            (r / out.detection_variance - 1.0).abs() < 0.1,
        ),
    ]
}
