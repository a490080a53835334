//! `camnet-localisation`: camera-network localisation from object image tracks (Meingast, Oh
//! & Sastry, ICCV 2007). People walk on a ground plane seen by several calibrated cameras with
//! wide baselines and partial overlaps. Each camera's simulated blob detector reports a blob
//! per visible, detected person (centroid, top and bottom with pixel noise) plus false blobs;
//! per-camera MCMCDA turns them into image tracks; camnet matches tracks between cameras,
//! estimates pairwise poses and chains them into one frame. The truth is used only to score:
//! pairwise rotation and translation-direction errors, camera positions after a similarity
//! alignment, correspondence precision and recall, over a sweep of pixel noise.

use anyhow::Result;
use camnet::scene::{PairScore, Scene, SceneConfig, align_cameras, score_pairs};
use camnet::{NetworkConfig, PoseRoute, localise};
use nalgebra::Vector3;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Deserialize;

use crate::pipelines::mcmcda::mean_ci;
use crate::{
    Chart, Claim, Env, Figure, Headline, Metrics, Pipeline, Section, Series, Style, Table, fmt_num,
};

/// The `camnet-localisation` pipeline.
pub struct CamnetLocalisation;

/// Its parameters.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Scenes per noise level, each on its own generator stream.
    n_runs: usize,
    /// Pixel noise levels (σ of each blob point, px); the claims read `claim_noise_px`.
    noise_px: Vec<f64>,
    /// The noise level the claims and headlines use.
    claim_noise_px: f64,
    /// Cameras on a ring.
    n_cameras: usize,
    /// Ring radius, m.
    ring_radius_m: f64,
    /// Camera heights range, m.
    camera_height_m: [f64; 2],
    /// Each camera aims at a point this far from the centre, turned `aim_turn_deg` from its
    /// inward direction, so neighbouring views overlap and distant ones may not.
    aim_offset_m: f64,
    /// See `aim_offset_m`.
    aim_turn_deg: f64,
    /// Image size, px.
    image_size: [f64; 2],
    /// Focal length, px.
    focal_px: f64,
    /// People walking, each for part of the run.
    n_people: usize,
    /// Half side of the walking square, m.
    area_half_m: f64,
    /// Walking speed, m per frame.
    speed_m_per_frame: f64,
    /// Person height range, m.
    person_height_m: [f64; 2],
    /// Frames.
    n_frames: u32,
    /// Detection probability of a visible person.
    p_detect: f64,
    /// False blobs per frame per camera (Poisson).
    false_blobs_per_frame: f64,
    /// MCMCDA samples per frame of the sliding window.
    samples_per_scan: u64,
    /// The Sampson threshold is at least this many σ of the pixel noise.
    threshold_sigmas: f64,
    /// The network (correspondence, pose, scale).
    network: NetworkConfig,
}

impl Params {
    /// The simulated scene these parameters describe.
    fn scene(&self) -> SceneConfig {
        SceneConfig {
            n_cameras: self.n_cameras,
            ring_radius_m: self.ring_radius_m,
            camera_height_m: self.camera_height_m,
            aim_offset_m: self.aim_offset_m,
            aim_turn_deg: self.aim_turn_deg,
            image_size: self.image_size,
            focal_px: self.focal_px,
            n_people: self.n_people,
            area_half_m: self.area_half_m,
            speed_m_per_frame: self.speed_m_per_frame,
            person_height_m: self.person_height_m,
            n_frames: self.n_frames,
            p_detect: self.p_detect,
            false_blobs_per_frame: self.false_blobs_per_frame,
        }
    }
}

/// One scene.
#[derive(Debug, Clone)]
struct RunScore {
    noise_px: f64,
    pairs: Vec<PairScore>,
    chosen: usize,
    correct: usize,
    true_pairs: usize,
    /// Placed cameras' position errors, % of scene size.
    position_error_pct: Vec<f64>,
    /// The same before the joint refinement (equal to the above when it did not run).
    position_error_pct_tree: Vec<f64>,
    /// The joint refinement's RMS reprojection error before and after, px.
    bundle_rms_px: Option<(f64, f64)>,
    n_placed: usize,
    /// Top view: true and estimated (aligned) centres and viewing directions.
    true_cams: Vec<(Vector3<f64>, Vector3<f64>)>,
    est_cams: Vec<Option<(Vector3<f64>, Vector3<f64>)>>,
    paths: Vec<Vec<(f64, f64)>>,
}

impl RunScore {
    fn precision(&self) -> f64 {
        self.correct as f64 / self.chosen.max(1) as f64
    }
    fn recall(&self) -> f64 {
        self.correct as f64 / self.true_pairs.max(1) as f64
    }
    /// Pairs with at least two shared tracks.
    fn judged(&self) -> impl Iterator<Item = &PairScore> {
        self.pairs.iter().filter(|p| p.shared_tracks >= 2)
    }
}

/// What the pipeline computed.
pub struct Output {
    runs: Vec<RunScore>,
    claim_noise_px: f64,
    n_cameras: usize,
}

/// One scene of Meingast, Oh & Sastry (2007)'s experiment: people walk, every camera tracks
/// them, camnet localises the network, and the result is scored against the truth.
fn run_scene(
    p: &Params,
    scene: &Scene,
    noise_px: f64,
    rng: &mut ChaCha8Rng,
    seed: u64,
) -> Result<RunScore> {
    let people = scene.walk(rng);
    let cams = scene.cameras(rng)?;
    let config = scene.image_track_config(noise_px, p.samples_per_scan)?;
    let tracked = scene.track_cameras(&cams, &people, noise_px, &config, rng, seed)?;
    // The inlier threshold follows the detector's known noise level: 3σ, at least the
    // configured value.
    let mut network = p.network;
    network.correspondence.threshold_px = network
        .correspondence
        .threshold_px
        .max(p.threshold_sigmas * noise_px);
    let net = localise(&tracked.cameras, &network, seed)?;
    let tally = score_pairs(&net, &tracked, &cams, p.network.correspondence.min_overlap)?;
    let aligned = align_cameras(&net, &cams)?;
    let bundle_rms_px = net
        .bundle
        .as_ref()
        .map(|b| (b.initial_rms * p.focal_px, b.final_rms * p.focal_px));
    let true_cams = cams
        .iter()
        .map(|c| (c.centre(), c.rotation.inverse() * Vector3::z()))
        .collect();
    let paths = people
        .iter()
        .map(|pp| pp.ground.iter().step_by(4).map(|g| (g.x, g.y)).collect())
        .collect();
    Ok(RunScore {
        noise_px,
        pairs: tally.pairs,
        chosen: tally.chosen,
        correct: tally.correct,
        true_pairs: tally.true_pairs,
        position_error_pct: aligned.position_error_pct,
        position_error_pct_tree: aligned.position_error_pct_tree,
        bundle_rms_px,
        n_placed: aligned.placed.len(),
        true_cams,
        est_cams: aligned.est_cams,
        paths,
    })
}

/// Every count, size and range a scenario file sets, before anything is drawn: a reversed
/// range or an empty image would panic in the generator, a huge count would run for hours.
/// The scene's own settings are checked by camnet ([`SceneConfig::check`]).
fn check_params(p: &Params) -> Result<Scene> {
    let counts = [
        ("n_runs", p.n_runs, 1, 1000),
        ("noise levels in noise_px", p.noise_px.len(), 1, 100),
    ];
    for (name, value, lo, hi) in counts {
        anyhow::ensure!(
            (lo..=hi).contains(&value),
            "{name} = {value}; it must be in {lo}..={hi}"
        );
    }
    let scene = p.scene().check()?;
    tracker_model::ensure_positive(p.threshold_sigmas, "threshold_sigmas")?;
    anyhow::ensure!(
        p.noise_px.iter().all(|s| s.is_finite() && *s >= 0.0),
        "noise_px must be finite and ≥ 0"
    );
    anyhow::ensure!(
        p.noise_px.contains(&p.claim_noise_px),
        "claim_noise_px must be in noise_px"
    );
    anyhow::ensure!(
        (1..=mcmcda::MAX_SAMPLES).contains(&p.samples_per_scan),
        "samples_per_scan = {}; it must be in 1..={}",
        p.samples_per_scan,
        mcmcda::MAX_SAMPLES
    );
    Ok(scene)
}

impl Pipeline for CamnetLocalisation {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        let scene = check_params(p)?;
        let base = rng.clone();
        let tasks: Vec<(usize, f64)> = p
            .noise_px
            .iter()
            .flat_map(|&s| (0..p.n_runs).map(move |r| (r, s)))
            .collect();
        env.progress.set_length(tasks.len() as u64);
        let runs = tasks
            .par_iter()
            .map(|&(r, noise)| {
                // The same scene at every noise level: stream r draws the scene; the noise
                // level changes only the pixel noise drawn after it.
                let mut rng = base.clone();
                rng.set_stream(r as u64);
                let out = run_scene(p, &scene, noise, &mut rng, env.seed.wrapping_add(r as u64));
                env.progress.advance(1);
                out
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Output {
            runs,
            claim_noise_px: p.claim_noise_px,
            n_cameras: p.n_cameras,
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut m = Metrics::new();
        for s in levels(out) {
            let runs: Vec<&RunScore> = out.runs.iter().filter(|r| same(r.noise_px, s)).collect();
            let key = format!("noise_{}px", fmt_num(s).replace('.', "_"));
            pose_metrics(&mut m, &key, &runs);
            position_metrics(&mut m, &key, &runs);
            correspondence_metrics(&mut m, &key, &runs);
        }
        m
    }

    fn claims(out: &Output) -> Vec<Claim> {
        let runs: Vec<&RunScore> = out
            .runs
            .iter()
            .filter(|r| same(r.noise_px, out.claim_noise_px))
            .collect();
        let judged: Vec<&PairScore> = runs.iter().flat_map(|r| r.judged()).collect();
        // Every judged pair must have a pose: a pair without one fails the bound.
        let rot_ok = !judged.is_empty()
            && judged
                .iter()
                .all(|p| p.error_deg.is_some_and(|e| e.0 <= 1.0));
        let dir_ok = !judged.is_empty()
            && judged
                .iter()
                .all(|p| p.error_deg.is_some_and(|e| e.1 <= 2.0));
        let own_points = judged
            .iter()
            .all(|p| matches!(p.route, Some(PoseRoute::Direct | PoseRoute::Guided)));
        let pos_ok = runs
            .iter()
            .all(|r| r.n_placed == out.n_cameras && r.position_error_pct.iter().all(|e| *e <= 2.0));
        let s = fmt_num(out.claim_noise_px);
        vec![
            Claim::new(
                format!(
                    "with {s} px noise, every camera pair sharing ≥ 2 tracks gets a pose with rotation error ≤ 1°"
                ),
                rot_ok,
            ),
            Claim::new(
                format!(
                    "with {s} px noise, every camera pair sharing ≥ 2 tracks gets a pose with translation-direction error ≤ 2°"
                ),
                dir_ok,
            ),
            Claim::new(
                format!(
                    "with {s} px noise, every camera pair sharing ≥ 2 tracks has its pose estimated from its own matched tracks (direct search, or guided by the network's composed pose), none only composed"
                ),
                own_points,
            ),
            Claim::new(
                format!(
                    "with {s} px noise, every camera is placed within 2 % of the scene size after similarity alignment"
                ),
                pos_ok,
            ),
        ]
    }

    fn headlines(out: &Output) -> Vec<Headline> {
        let runs: Vec<&RunScore> = out
            .runs
            .iter()
            .filter(|r| same(r.noise_px, out.claim_noise_px))
            .collect();
        let errs: Vec<(f64, f64)> = runs
            .iter()
            .flat_map(|r| r.judged().filter_map(|p| p.error_deg))
            .collect();
        let pos: Vec<f64> = runs
            .iter()
            .flat_map(|r| r.position_error_pct.iter().copied())
            .collect();
        let (rm, rc) = mean_ci(errs.iter().map(|e| e.0));
        let (pm, pc) = mean_ci(pos.iter().copied());
        vec![
            Headline {
                quantity: format!(
                    "pairwise rotation error (°), {} px noise",
                    fmt_num(out.claim_noise_px)
                ),
                paper: None,
                ours: format!("{} ± {}", fmt_num(rm), fmt_num(rc)),
                peer: None,
            },
            Headline {
                quantity: format!(
                    "camera position error (% of scene), {} px noise",
                    fmt_num(out.claim_noise_px)
                ),
                paper: None,
                ours: format!("{} ± {}", fmt_num(pm), fmt_num(pc)),
                peer: None,
            },
        ]
    }

    fn present(out: &Output) -> Section {
        let run0 = out
            .runs
            .iter()
            .find(|r| same(r.noise_px, out.claim_noise_px));
        let stats: Vec<LevelStats> = levels(out)
            .into_iter()
            .map(|s| level_stats(out, s))
            .collect();
        let mut figures = Vec::new();
        if let Some(r) = run0 {
            figures.push(top_view_figure(r));
        }
        figures.push(noise_figure(&stats));
        Section {
            title: "Camera-network localisation from image tracks (Meingast, Oh & Sastry 2007)"
                .into(),
            summary: SUMMARY.into(),
            tables: vec![pair_table(out, run0), sweep_table(&stats)],
            figures,
        }
    }
}

/// The report's summary: the simulated scene and the steps of camnet's localisation
/// (Meingast, Oh & Sastry 2007), and how the errors are measured.
const SUMMARY: &str = "People walk on a ground plane seen by calibrated cameras on a ring, each aimed off-centre so that some pairs share no one. A simulated blob detector reports each visible person's centroid, top and bottom with Gaussian pixel noise, misses some, and adds false blobs. Online MCMCDA tracks the centroids in each image; camnet matches the image tracks between cameras (pooled time-aligned top and bottom points must fit one essential matrix), estimates each pair's pose (normalised 8-point in LO-RANSAC, cheirality, Levenberg-Marquardt), chains the poses over the maximum spanning tree of the view graph and sets the scales from points seen by three cameras; a pair the search left without a pose is matched again under the pose composed through the network (its pose then comes from its own points), and a joint refinement (bundle adjustment) over all cameras and triangulated track points polishes the positions. Errors are against the truth; positions after a similarity (Umeyama) alignment, as % of the largest distance between cameras.";

/// The pose metrics of one noise level: the pairwise rotation and translation-direction
/// errors of the pairs sharing ≥ 2 tracks (Meingast, Oh & Sastry 2007), the pairs left
/// without a pose, and the route each pose took.
fn pose_metrics(m: &mut Metrics, key: &str, runs: &[&RunScore]) {
    let errs: Vec<(f64, f64)> = runs
        .iter()
        .flat_map(|r| r.judged().filter_map(|p| p.error_deg))
        .collect();
    m.insert(
        format!("{key}_rotation_error_deg_max"),
        errs.iter().map(|e| e.0).fold(0.0, f64::max),
    );
    m.insert(
        format!("{key}_translation_error_deg_max"),
        errs.iter().map(|e| e.1).fold(0.0, f64::max),
    );
    m.insert(
        format!("{key}_rotation_error_deg_mean"),
        mean_ci(errs.iter().map(|e| e.0)).0,
    );
    m.insert(
        format!("{key}_translation_error_deg_mean"),
        mean_ci(errs.iter().map(|e| e.1)).0,
    );
    let missing = runs
        .iter()
        .map(|r| r.judged().filter(|p| p.error_deg.is_none()).count())
        .sum::<usize>();
    m.insert(format!("{key}_judged_pairs_missing"), missing as f64);
    for (route, name) in ROUTES {
        let count = runs
            .iter()
            .map(|r| r.judged().filter(|p| p.route == Some(route)).count())
            .sum::<usize>();
        m.insert(format!("{key}_judged_pairs_{name}"), count as f64);
    }
    let judged = runs.iter().map(|r| r.judged().count()).sum::<usize>();
    m.insert(format!("{key}_judged_pairs"), judged as f64);
}

/// The position metrics of one noise level: camera position errors after the similarity
/// alignment, before and after the joint refinement, and its reprojection RMS.
fn position_metrics(m: &mut Metrics, key: &str, runs: &[&RunScore]) {
    let pos: Vec<f64> = runs
        .iter()
        .flat_map(|r| r.position_error_pct.iter().copied())
        .collect();
    m.insert(
        format!("{key}_position_error_pct_max"),
        pos.iter().copied().fold(0.0, f64::max),
    );
    m.insert(
        format!("{key}_position_error_pct_mean"),
        mean_ci(pos.iter().copied()).0,
    );
    let tree: Vec<f64> = runs
        .iter()
        .flat_map(|r| r.position_error_pct_tree.iter().copied())
        .collect();
    m.insert(
        format!("{key}_position_error_pct_mean_before_bundle"),
        mean_ci(tree.iter().copied()).0,
    );
    let rms: Vec<(f64, f64)> = runs.iter().filter_map(|r| r.bundle_rms_px).collect();
    m.insert(format!("{key}_bundle_runs"), rms.len() as f64);
    m.insert(
        format!("{key}_bundle_rms_px_before"),
        mean_ci(rms.iter().map(|e| e.0)).0,
    );
    m.insert(
        format!("{key}_bundle_rms_px_after"),
        mean_ci(rms.iter().map(|e| e.1)).0,
    );
}

/// The correspondence metrics of one noise level: precision and recall of the matched track
/// pairs, and the cameras placed.
fn correspondence_metrics(m: &mut Metrics, key: &str, runs: &[&RunScore]) {
    m.insert(
        format!("{key}_correspondence_precision"),
        mean_ci(runs.iter().map(|r| r.precision())).0,
    );
    m.insert(
        format!("{key}_correspondence_recall"),
        mean_ci(runs.iter().map(|r| r.recall())).0,
    );
    m.insert(
        format!("{key}_cameras_placed"),
        runs.iter().map(|r| r.n_placed).sum::<usize>() as f64,
    );
}

/// The pair table: run 0 at the claims' noise level, each pair's shared true tracks, pose
/// route and pose errors (the pairwise errors of Meingast, Oh & Sastry 2007).
fn pair_table(out: &Output, run0: Option<&RunScore>) -> Table {
    let mut pair_table = Table::new(
        &format!(
            "Camera pairs at {} px noise, run 0: shared true track pairs and pose errors",
            fmt_num(out.claim_noise_px)
        ),
        &[
            "pair",
            "shared tracks",
            "pose from",
            "rotation error (°)",
            "translation-direction error (°)",
        ],
    );
    if let Some(r) = run0 {
        for p in &r.pairs {
            let (re, te) = p.error_deg.map_or(("–".into(), "–".into()), |e| {
                (fmt_num(e.0), fmt_num(e.1))
            });
            pair_table.row(vec![
                format!("{}–{}", p.a, p.b),
                p.shared_tracks.to_string(),
                route_name(p.route).into(),
                re,
                te,
            ]);
        }
    }
    pair_table
}

/// One noise level's errors over all its runs, for the sweep table and the noise chart.
struct LevelStats {
    noise_px: f64,
    /// (mean, max) of the rotation errors (°).
    rotation: (f64, f64),
    /// (mean, max) of the translation-direction errors (°).
    direction: (f64, f64),
    /// (mean, max) of the position errors (%).
    position: (f64, f64),
    /// (mean, max) of the position errors before the joint refinement (%).
    position_tree: (f64, f64),
    /// Pairs direct / guided / composed / none.
    routes: String,
    /// The reprojection RMS before / after the joint refinement, "–" when it never ran.
    bundle_rms: String,
    precision: f64,
    recall: f64,
}

/// The errors of noise level `s` over its runs: pairs sharing ≥ 2 tracks, positions after
/// the Umeyama alignment (Meingast, Oh & Sastry 2007 report both).
fn level_stats(out: &Output, s: f64) -> LevelStats {
    let runs: Vec<&RunScore> = out.runs.iter().filter(|r| same(r.noise_px, s)).collect();
    let errs: Vec<(f64, f64)> = runs
        .iter()
        .flat_map(|r| r.judged().filter_map(|p| p.error_deg))
        .collect();
    let by_route = |route: Option<PoseRoute>| {
        runs.iter()
            .map(|r| r.judged().filter(|p| p.route == route).count())
            .sum::<usize>()
    };
    let routes = format!(
        "{} / {} / {} / {}",
        by_route(Some(PoseRoute::Direct)),
        by_route(Some(PoseRoute::Guided)),
        by_route(Some(PoseRoute::Composed)),
        by_route(None)
    );
    let pos: Vec<f64> = runs
        .iter()
        .flat_map(|r| r.position_error_pct.iter().copied())
        .collect();
    let mm = |v: &mut dyn Iterator<Item = f64>| {
        let v: Vec<f64> = v.collect();
        (
            mean_ci(v.iter().copied()).0,
            v.iter().copied().fold(0.0, f64::max),
        )
    };
    let rms: Vec<(f64, f64)> = runs.iter().filter_map(|r| r.bundle_rms_px).collect();
    LevelStats {
        noise_px: s,
        rotation: mm(&mut errs.iter().map(|e| e.0)),
        direction: mm(&mut errs.iter().map(|e| e.1)),
        position: mm(&mut pos.iter().copied()),
        position_tree: mm(&mut runs
            .iter()
            .flat_map(|r| r.position_error_pct_tree.iter().copied())),
        routes,
        bundle_rms: if rms.is_empty() {
            "–".into()
        } else {
            format!(
                "{} / {}",
                fmt_num(mean_ci(rms.iter().map(|e| e.0)).0),
                fmt_num(mean_ci(rms.iter().map(|e| e.1)).0)
            )
        },
        precision: mean_ci(runs.iter().map(|r| r.precision())).0,
        recall: mean_ci(runs.iter().map(|r| r.recall())).0,
    }
}

/// The sweep table: every noise level's pose and position errors, routes, refinement and
/// correspondence quality, over all runs.
fn sweep_table(stats: &[LevelStats]) -> Table {
    let mut sweep = Table::new(
        "Against pixel noise (all runs): pairs sharing ≥ 2 tracks; positions after Umeyama alignment",
        &[
            "noise (px)",
            "rotation error mean / max (°)",
            "direction error mean / max (°)",
            "pairs direct / guided / composed / none",
            "position error mean / max (%)",
            "before joint refinement (%)",
            "reprojection RMS before / after refinement (px)",
            "correspondence precision",
            "recall",
        ],
    );
    let mean_max = |(mean, max): (f64, f64)| format!("{} / {}", fmt_num(mean), fmt_num(max));
    for l in stats {
        sweep.row(vec![
            fmt_num(l.noise_px),
            mean_max(l.rotation),
            mean_max(l.direction),
            l.routes.clone(),
            mean_max(l.position),
            mean_max(l.position_tree),
            l.bundle_rms.clone(),
            fmt_num(l.precision),
            fmt_num(l.recall),
        ]);
    }
    sweep
}

/// The "camnet_top_view" figure: run 0 from above, the walking paths, the true cameras and
/// the estimate after the similarity alignment, with a wedge along each optical axis.
fn top_view_figure(r: &RunScore) -> Figure {
    let mut series = Vec::new();
    for path in &r.paths {
        series.push(Series::new("", path.clone(), Style::Faint, 7));
    }
    let fov = |c: &Vector3<f64>, axis: &Vector3<f64>| {
        let a = axis.y.atan2(axis.x);
        let half = 0.6;
        let l = 6.0;
        vec![
            (c.x + l * (a + half).cos(), c.y + l * (a + half).sin()),
            (c.x, c.y),
            (c.x + l * (a - half).cos(), c.y + l * (a - half).sin()),
        ]
    };
    for (i, (c, axis)) in r.true_cams.iter().enumerate() {
        series.push(Series::new(
            if i == 0 {
                "true camera, field of view"
            } else {
                ""
            },
            fov(c, axis),
            Style::ThinLine,
            0,
        ));
    }
    for (i, e) in r.est_cams.iter().enumerate() {
        if let Some((c, axis)) = e {
            series.push(Series::new(
                if i == 0 { "estimated (aligned)" } else { "" },
                fov(c, axis),
                Style::ThinLine,
                1,
            ));
        }
    }
    series.push(Series::new(
        "true centres",
        r.true_cams.iter().map(|c| (c.0.x, c.0.y)).collect(),
        Style::Markers,
        0,
    ));
    series.push(Series::new(
        "estimated centres",
        r.est_cams
            .iter()
            .flatten()
            .map(|c| (c.0.x, c.0.y))
            .collect(),
        Style::Markers,
        1,
    ));
    Figure::new(
        "camnet_top_view",
        "Top view of run 0: walking paths (grey), true cameras and the estimate after similarity alignment, with a wedge along each optical axis",
        Chart::new("Cameras from above", "x (m)", "y (m)", series).with_equal_aspect(),
    )
}

/// The "camnet_noise" figure: the mean rotation, direction and position errors against the
/// pixel noise, the sweep table's means.
fn noise_figure(stats: &[LevelStats]) -> Figure {
    let points = |f: fn(&LevelStats) -> f64| -> Vec<(f64, f64)> {
        stats.iter().map(|l| (l.noise_px, f(l))).collect()
    };
    Figure::new(
        "camnet_noise",
        "Mean errors against pixel noise (pairs sharing ≥ 2 tracks; all placed cameras)",
        Chart::new(
            "Error against pixel noise",
            "pixel noise σ (px)",
            "error (° or % of scene)",
            vec![
                Series::new(
                    "rotation error (°)",
                    points(|l| l.rotation.0),
                    Style::Line,
                    0,
                ),
                Series::new(
                    "translation-direction error (°)",
                    points(|l| l.direction.0),
                    Style::Line,
                    1,
                ),
                Series::new(
                    "position error (% of scene)",
                    points(|l| l.position.0),
                    Style::Line,
                    2,
                ),
            ],
        ),
    )
}

/// The routes a pair's pose can take, with their metric names.
const ROUTES: [(PoseRoute, &str); 3] = [
    (PoseRoute::Direct, "direct"),
    (PoseRoute::Guided, "guided"),
    (PoseRoute::Composed, "composed"),
];

fn route_name(route: Option<PoseRoute>) -> &'static str {
    match route {
        Some(PoseRoute::Direct) => "direct",
        Some(PoseRoute::Guided) => "guided",
        Some(PoseRoute::Composed) => "composed",
        None => "–",
    }
}

fn levels(out: &Output) -> Vec<f64> {
    let mut v: Vec<f64> = out.runs.iter().map(|r| r.noise_px).collect();
    v.sort_by(f64::total_cmp);
    v.dedup();
    v
}

/// Noise levels are read from the scenario file and copied, never computed: equal within
/// rounding.
fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scenario's own parameters with one key replaced.
    fn params_with(key: &str, value: toml::Value) -> Params {
        let file: toml::Table = toml::from_str(include_str!(
            "../../../../fixtures/scenarios/camnet-people.toml"
        ))
        .unwrap();
        let mut params = file["params"].as_table().unwrap().clone();
        params.insert(key.into(), value);
        toml::Value::Table(params).try_into().unwrap()
    }

    #[test]
    fn bad_ranges_and_sizes_are_errors_not_panics() {
        let pair = |a: f64, b: f64| toml::Value::Array(vec![a.into(), b.into()]);
        assert!(check_params(&params_with("n_runs", 2.into())).is_ok());
        // Each panicked ("cannot sample empty range") or ran without bound before.
        for (key, value) in [
            ("camera_height_m", pair(6.0, 3.5)),
            ("person_height_m", pair(1.9, 1.9)),
            ("image_size", pair(0.0, 0.0)),
            ("image_size", pair(1e300, 720.0)),
            ("n_frames", 4_294_967_295_i64.into()),
            ("n_people", 0.into()),
            ("samples_per_scan", 4_294_967_296_000_i64.into()),
        ] {
            let err = check_params(&params_with(key, value.clone())).unwrap_err();
            let name = key.split('_').next().unwrap();
            assert!(
                format!("{err:#}").contains(name),
                "{key} = {value}: {err:#}"
            );
        }
    }
}
