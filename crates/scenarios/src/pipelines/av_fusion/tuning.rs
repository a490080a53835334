//! The developer searches behind the scenario's settings (never run by the suite): the
//! single-vehicle search of `[params.tuning]` (`AV_FUSION_TUNE=1`), the multi-vehicle search
//! of `[params.multi_tuning]` (`AV_FUSION_TUNE_MULTI=all`, or a comma-separated list of approach
//! indices) and the multi-vehicle error breakdown (`AV_FUSION_DIAG=seed,seed,...`). All run on
//! the tuning seeds given; the reported seed is only simulated by the normal run.

use super::*;

/// Setting this developer option makes the scenario run [`Tuning`]'s grid search on its
/// tuning seeds first and print it (the reported results do not change).
pub(super) const TUNE_ENV: &str = "AV_FUSION_TUNE";

/// Averages of one setting over the tuning runs: A+V mean error over the single-vehicle
/// passes (a pass without a track counts as the match distance) and mean MOTA over all runs.
#[derive(Debug, Clone, Copy)]
pub(super) struct TuneScore {
    pub(super) error_m: f64,
    pub(super) mota: f64,
    pub(super) multi_mota: f64,
    /// Multi-vehicle runs: the fraction of (vehicle, tick) pairs with a peak within 2 m, and
    /// peaks per tick farther than 2 m from every vehicle (is a miss the peaks' fault?).
    pub(super) peak_recall: f64,
    pub(super) false_peaks: f64,
}

/// Peak recall and false peaks per tick of a run (see [`TuneScore`]).
pub(super) fn peak_counts(sim: &Simulated, run: &av_fusion::AvRun) -> (usize, usize, usize, usize) {
    let (mut pairs, mut found, mut false_peaks) = (0, 0, 0);
    for scan in &run.scans {
        let truth = vehicles_at(sim, scan.tick);
        pairs += truth.len();
        found += truth
            .iter()
            .filter(|v| scan.peaks.iter().any(|q| (q.position - *v).norm() <= 2.0))
            .count();
        false_peaks += scan
            .peaks
            .iter()
            .filter(|q| truth.iter().all(|v| (q.position - v).norm() > 2.0))
            .count();
    }
    (pairs, found, false_peaks, run.scans.len())
}

/// The true positions of the vehicles present at tick `tick`.
fn vehicles_at(sim: &Simulated, tick: u64) -> Vec<Vec2> {
    sim.gt
        .tracks()
        .iter()
        .filter_map(|t| {
            t.points()
                .iter()
                .find(|q| u64::from(q.frame) == tick)
                .map(|q| q.location.position())
        })
        .collect()
}

pub(super) fn tune_score(p: &Params, sims: &[(bool, Simulated)], a: usize) -> Result<TuneScore> {
    let scores: Vec<(bool, Score)> = sims
        .par_iter()
        // The single-vehicle settings on every run (the search of `[params.tuning]`).
        .map(|(multi, sim)| {
            Ok((
                *multi,
                score_with(p, sim, nominal(p), a, p.settings.get(a), None)?,
            ))
        })
        .collect::<Result<_>>()?;
    let single: Vec<f64> = scores
        .iter()
        .filter(|(m, _)| !m)
        .flat_map(|(_, s)| s.errors.iter().map(|e| e.unwrap_or(p.match_distance_m)))
        .collect();
    let multi: Vec<f64> = scores
        .iter()
        .filter(|(m, _)| *m)
        .map(|(_, s)| s.mota)
        .collect();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let (mut pairs, mut found, mut false_peaks, mut ticks) = (0, 0, 0, 0);
    for ((multi, sim), (_, s)) in sims.iter().zip(&scores) {
        if *multi {
            let c = peak_counts(sim, &s.result);
            pairs += c.0;
            found += c.1;
            false_peaks += c.2;
            ticks += c.3;
        }
    }
    Ok(TuneScore {
        error_m: mean(&single),
        mota: mean(&scores.iter().map(|(_, s)| s.mota).collect::<Vec<_>>()),
        multi_mota: mean(&multi),
        peak_recall: found as f64 / pairs.max(1) as f64,
        false_peaks: false_peaks as f64 / ticks.max(1) as f64,
    })
}

/// Each sensor's bearing error on the single-vehicle passes: the bearing of its profile's
/// maximum from the believed pose at heading error `calib` against the true bearing of the
/// vehicle at the report's time, over the reports where the vehicle is inside the region.
/// Returns (mean, standard deviation) in degrees per sensor, in sensor order.
pub(super) fn bearing_errors(
    p: &Params,
    sims: &[&Simulated],
    calib: Calibration,
) -> Result<Vec<(f64, f64)>> {
    let nodes = sensor_nodes(p, calib, p.settings.get(5))?;
    let mut acc = vec![Vec::new(); nodes.len()];
    for sim in sims {
        let Some(gt) = sim.gt.tracks().first() else {
            continue;
        };
        let pts = gt.points();
        let (Some(first), Some(last)) = (pts.first(), pts.last()) else {
            continue;
        };
        // The vehicle's straight path from its first and last points.
        let t0 = p.scheduler.tick_time_s(u64::from(first.frame));
        let t1 = p.scheduler.tick_time_s(u64::from(last.frame));
        let (a, b) = (first.location.position(), last.location.position());
        for r in &sim.reports {
            let node = &nodes[r.sensor];
            let t = node.fusion_time_s(r.local_time_s);
            if !(t0..=t1).contains(&t) || t1 <= t0 {
                continue;
            }
            let pos = a + (b - a) * ((t - t0) / (t1 - t0));
            let Some((i, _)) = r
                .values
                .iter()
                .enumerate()
                .max_by(|x, y| x.1.total_cmp(y.1))
                .filter(|(_, v)| **v > 0.0)
            else {
                continue;
            };
            let profile = node.profile(r.values.clone())?;
            let measured = node.pose.heading_rad + profile.bin_angle_rad(i);
            let d = pos - node.pose.position;
            let truth = d.y.atan2(d.x);
            let e = (measured - truth + PI).rem_euclid(2.0 * PI) - PI;
            acc[r.sensor].push(e * 180.0 / PI);
        }
    }
    Ok(acc
        .iter()
        .map(|e| {
            let n = e.len().max(1) as f64;
            let m = e.iter().sum::<f64>() / n;
            let v = e.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / n;
            (m, v.sqrt())
        })
        .collect())
}

/// Stage 1's rule: among the candidates whose error is within the fraction `tolerance` of the
/// lowest, the one with the highest MOTA (ties keep the earlier). Error differences of a few
/// millimetres are noise on 27 passes, while a broad profile that tracks a lone vehicle as
/// well can still cost a great deal of MOTA in false and broken tracks.
pub(super) fn stage1_choice(
    candidates: &[(ApproachSettings, TuneScore)],
    tolerance: f64,
) -> Option<(ApproachSettings, TuneScore)> {
    let lowest = candidates
        .iter()
        .map(|(_, s)| s.error_m)
        .fold(f64::INFINITY, f64::min);
    let mut best: Option<(ApproachSettings, TuneScore)> = None;
    for (w, s) in candidates {
        if s.error_m <= lowest * (1.0 + tolerance)
            && best.as_ref().is_none_or(|b| s.mota > b.1.mota)
        {
            best = Some((*w, *s));
        }
    }
    best
}

/// Runs the developer tools the caller asked for: `AV_FUSION_TUNE` (the single-vehicle
/// search, [`tune`]), `AV_FUSION_FIT_SCORES=<approaches>` (the peak-score tables,
/// [`fit_peak_scores`]), `AV_FUSION_TUNE_MULTI=<approaches>` (the multi-vehicle search,
/// [`tune_multi`]) and `AV_FUSION_DIAG=<seeds>` (per-tick diagnostics, [`diagnose`]); `cargo
/// xtask scenarios` reads them from the environment variables of those names.
pub(super) fn run_developer_tools(dev: &dyn Developer, p: &Params, runs: &[RunSpec]) -> Result<()> {
    if dev.option(TUNE_ENV).is_some() {
        print_tuning(dev, p, runs)?;
    }
    if let Some(which) = dev.option(FIT_SCORES_ENV) {
        fit_peak_scores(dev, p, runs, &which)?;
    }
    if let Some(which) = dev.option(TUNE_MULTI_ENV) {
        tune_multi(dev, p, runs, &which)?;
    }
    if let Some(seeds) = dev.option(DIAG_ENV) {
        diagnose(dev, p, runs, &seeds)?;
    }
    Ok(())
}

/// Grid search on the tuning seeds, run for each of the six approaches on its own, from the
/// configured values, by the same stages and objectives. Stage 1: the profile exponent γ of
/// each modality the approach uses, for audio+video the video weight w_v (audio weight 1),
/// and for the product the floor ε, by the approach's mean error over the single-vehicle
/// passes (within `error_tolerance` of the lowest, the highest MOTA: [`stage1_choice`]).
/// Stage 2a, with stage 1's choice: the NMS radius and MCMCDA's p_d and clutter rate by the
/// approach's mean MOTA over every run (single and multi-vehicle). Stage 2b: the peaks' κ by
/// the same MOTA. Ties keep the earlier candidate. The stages repeat until a round changes
/// nothing (at most `max_rounds`).
pub(super) fn print_tuning(dev: &dyn Developer, p: &Params, runs: &[RunSpec]) -> Result<()> {
    let tuned = tune(dev, p, runs)?;
    dev.say(&tuned);
    Ok(())
}

pub(super) fn tune(dev: &dyn Developer, p: &Params, runs: &[RunSpec]) -> Result<String> {
    let t = &p.tuning;
    ensure!(!t.seeds.is_empty(), "no tuning seeds");
    let mut sims = Vec::new();
    for &seed in &t.seeds {
        let base = ChaCha8Rng::seed_from_u64(seed);
        let n_passes = p.passes.len();
        let batch: Vec<(bool, Simulated)> = runs
            .par_iter()
            .enumerate()
            .map(|(i, run)| {
                let mut rng = base.clone();
                rng.set_stream(i as u64);
                Ok((i >= n_passes, simulate_run(p, run, &mut rng)?))
            })
            .collect::<Result<_>>()?;
        sims.extend(batch);
    }
    let singles: Vec<&Simulated> = sims.iter().filter(|(m, _)| !m).map(|(_, s)| s).collect();
    let mut bearing_lines = Vec::new();
    for calib in [
        Calibration {
            audio_deg: 0.0,
            video_deg: 0.0,
        },
        nominal(p),
    ] {
        let stats = bearing_errors(p, &singles, calib)?;
        let text: Vec<String> = stats
            .iter()
            .map(|(m, s)| format!("{m:+.1}° ± {s:.1}°"))
            .collect();
        bearing_lines.push(format!(
            "bearing error of the profile maximum at {calib:?}: {}",
            text.join(", ")
        ));
    }
    let mut search = Search {
        dev,
        out: format!("av-fusion tuning on seeds {:?}\n", t.seeds),
        sims,
        q: p.clone(),
    };
    for line in bearing_lines {
        search.say(&line);
    }
    for (a, (name, _, _)) in APPROACHES.iter().enumerate() {
        let s = tune_score(&search.q, &search.sims, a)?;
        search.line(&format!("{name}: as configured"), &s);
        // The stages are repeated until a round changes nothing (a fixed point) or for
        // `max_rounds`.
        for round in 1..=t.max_rounds.max(1) {
            let before = *search.q.settings.get(a);
            search.say(&format!("{name}: round {round}"));
            search.stage1(a)?;
            search.stage2a(a)?;
            let w = search.stage2b(a)?;
            search.line(&format!("round {round} choice {name}: {w:?}"), &w.1);
            if w.0 == before {
                break;
            }
        }
    }
    // The choice as TOML, to paste into the scenario file.
    for a in 0..APPROACHES.len() {
        search.say(&settings_toml(a, search.q.settings.get(a)));
    }
    Ok(search.out)
}

/// The single-vehicle search's state: the simulated tuning runs, the parameters as chosen so
/// far, and the table of every candidate's score, which also goes line by line to the
/// developer as it is measured (the search takes minutes).
struct Search<'a> {
    dev: &'a dyn Developer,
    out: String,
    sims: Vec<(bool, Simulated)>,
    q: Params,
}

impl Search<'_> {
    fn say(&mut self, text: &str) {
        self.dev.say(text);
        self.out.push_str(text);
        self.out.push('\n');
    }

    fn line(&mut self, what: &str, s: &TuneScore) {
        self.say(&format!(
            "{what}: error {:.3} m, MOTA {:.3} (multi-vehicle {:.3}, peak recall {:.2}, false peaks/tick {:.2})",
            s.error_m, s.mota, s.multi_mota, s.peak_recall, s.false_peaks
        ));
    }

    /// The score of approach `a` with settings `w`.
    fn score(&self, a: usize, w: ApproachSettings) -> Result<TuneScore> {
        let mut c = self.q.clone();
        *c.settings.get_mut(a) = w;
        tune_score(&c, &self.sims, a)
    }

    /// Stage 1: the grid of the fusion parameters this approach uses (a single value
    /// elsewhere), chosen by [`stage1_choice`].
    fn stage1(&mut self, a: usize) -> Result<()> {
        let t = &self.q.tuning.clone();
        let (name, modalities, product) = APPROACHES[a];
        let uses_audio = modalities != Modalities::Video;
        let uses_video = modalities != Modalities::Audio;
        let configured = *self.q.settings.get(a);
        let video_weights: Vec<f64> = if modalities == Modalities::Both {
            t.video_weight.clone()
        } else {
            vec![configured.video_weight]
        };
        let audio_exponents = if uses_audio {
            t.audio_exponent.clone()
        } else {
            vec![configured.audio_exponent]
        };
        let video_exponents = if uses_video {
            t.video_exponent.clone()
        } else {
            vec![configured.video_exponent]
        };
        let floors: Vec<Option<f64>> = if product {
            t.product_floor.iter().copied().map(Some).collect()
        } else {
            vec![None]
        };
        let mut candidates: Vec<(ApproachSettings, TuneScore)> = Vec::new();
        for &video_weight in &video_weights {
            for &audio_exponent in &audio_exponents {
                for &video_exponent in &video_exponents {
                    for &product_floor in &floors {
                        let w = ApproachSettings {
                            audio_weight: 1.0,
                            video_weight,
                            audio_exponent,
                            video_exponent,
                            product_floor,
                            ..configured
                        };
                        let s = self.score(a, w)?;
                        self.line(
&format!(
                                "stage 1 {name}: w_v {video_weight}, gamma_a {audio_exponent}, gamma_v {video_exponent}, floor {product_floor:?}"
                            ),
                            &s,
                        );
                        candidates.push((w, s));
                    }
                }
            }
        }
        let Some((w, s)) = stage1_choice(&candidates, t.error_tolerance) else {
            anyhow::bail!("an empty stage-1 grid");
        };
        *self.q.settings.get_mut(a) = w;
        self.line(&format!("stage 1 choice {name}: {w:?}"), &s);
        Ok(())
    }

    /// Stage 2a: the NMS radius, p_d and clutter rate by the approach's mean MOTA.
    fn stage2a(&mut self, a: usize) -> Result<()> {
        let t = &self.q.tuning.clone();
        let name = APPROACHES[a].0;
        let mut best: Option<(ApproachSettings, TuneScore)> = None;
        for &nms in &t.suppression_radius_m {
            for &pd in &t.p_detect {
                for &clutter in &t.clutter_per_scan {
                    let w = ApproachSettings {
                        suppression_radius_m: nms,
                        p_detect: pd,
                        clutter_per_scan: clutter,
                        ..*self.q.settings.get(a)
                    };
                    let s = self.score(a, w)?;
                    self.line(
                        &format!("stage 2a {name}: nms {nms} m, p_d {pd}, clutter {clutter}"),
                        &s,
                    );
                    if best.as_ref().is_none_or(|b| s.mota > b.1.mota) {
                        best = Some((w, s));
                    }
                }
            }
        }
        let Some((w, s)) = best else {
            anyhow::bail!("an empty stage-2a grid");
        };
        *self.q.settings.get_mut(a) = w;
        self.line(&format!("stage 2a choice {name}: {w:?}"), &s);
        Ok(())
    }

    /// Stage 2b: the peaks' κ by the same MOTA; returns the round's choice.
    fn stage2b(&mut self, a: usize) -> Result<(ApproachSettings, TuneScore)> {
        let (name, _, product) = APPROACHES[a];
        let kappas = if product {
            self.q.tuning.relative_threshold_product.clone()
        } else {
            self.q.tuning.relative_threshold_sum.clone()
        };
        let mut best: Option<(ApproachSettings, TuneScore)> = None;
        for &kappa in &kappas {
            let w = ApproachSettings {
                relative_threshold: kappa,
                ..*self.q.settings.get(a)
            };
            let s = self.score(a, w)?;
            self.line(&format!("stage 2b {name}: kappa {kappa}"), &s);
            if best.as_ref().is_none_or(|b| s.mota > b.1.mota) {
                best = Some((w, s));
            }
        }
        let Some(best) = best else {
            anyhow::bail!("an empty stage-2b grid");
        };
        *self.q.settings.get_mut(a) = best.0;
        Ok(best)
    }
}

/// Approach `a`'s settings `w` as a line of TOML for the scenario file (only the keys the
/// approach uses).
fn settings_toml(a: usize, w: &ApproachSettings) -> String {
    let (name, modalities, _) = APPROACHES[a];
    let mut fields = Vec::new();
    if modalities == Modalities::Both {
        fields.push(format!("audio_weight = {:?}", w.audio_weight));
        fields.push(format!("video_weight = {:?}", w.video_weight));
    }
    if modalities != Modalities::Video {
        fields.push(format!("audio_exponent = {:?}", w.audio_exponent));
    }
    if modalities != Modalities::Audio {
        fields.push(format!("video_exponent = {:?}", w.video_exponent));
    }
    if let Some(f) = w.product_floor {
        fields.push(format!("product_floor = {f:?}"));
    }
    fields.push(format!("relative_threshold = {:?}", w.relative_threshold));
    fields.push(format!(
        "suppression_radius_m = {:?}",
        w.suppression_radius_m
    ));
    fields.push(format!("p_detect = {:?}", w.p_detect));
    fields.push(format!("clutter_per_scan = {:?}", w.clutter_per_scan));
    format!(
        "{} = {{ {} }}",
        key(name).replace("audiovideo", "audio_video"),
        fields.join(", ")
    )
}

/// Setting this environment variable (`all`, or approach indices) learns the peak-score tables
/// of `[params.multi_peak_scores]` first and prints them as TOML. The tables are fitted with
/// the multi-vehicle settings as configured, and the search of `AV_FUSION_TUNE_MULTI` uses the
/// tables as configured (not those just printed): fit, paste, search, paste, and fit again
/// until neither moves.
pub(super) const FIT_SCORES_ENV: &str = "AV_FUSION_FIT_SCORES";

/// How the peak-score tables are learnt (`[params.score_fit]`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScoreFit {
    /// Tuning seeds (never the reported one).
    pub(super) seeds: Vec<u64>,
    /// Peaks per tick while learning (≥ the largest `max_peaks` the search may choose, so
    /// the table covers the weak peaks too).
    pub(super) max_peaks: usize,
    /// Bins of the table (edges at the pooled contrasts' quantiles).
    pub(super) bins: usize,
    /// A peak within this distance of a vehicle at its tick counts as the vehicle's.
    pub(super) near_m: f64,
}

/// The score tables of `[params.multi_peak_scores]`: for each approach, with its
/// multi-vehicle settings (but `score_fit.max_peaks` peaks per tick), every peak of the tuning
/// seeds' multi-vehicle runs is labelled by whether a vehicle is within `near_m` at its tick
/// (the truth of calibration runs, as a detector's confidence is calibrated on labelled data;
/// the reported seed is never simulated here). The contrasts are binned at their pooled
/// quantiles and each bin's ln f₁/f₀ is the log ratio of its share of the near peaks to its
/// share of the far ones, each count plus one (Laplace), so an empty bin stays finite.
pub(super) fn fit_peak_scores(
    dev: &dyn Developer,
    p: &Params,
    runs: &[RunSpec],
    which: &str,
) -> Result<()> {
    let f = &p.score_fit;
    ensure!(f.bins >= 2, "score_fit.bins must be at least 2");
    ensure!(f.max_peaks >= 1, "score_fit.max_peaks must be at least 1");
    ensure!(f.near_m > 0.0, "score_fit.near_m must be > 0");
    let mut sims = Vec::new();
    for &seed in &f.seeds {
        sims.extend(simulate_multi(p, runs, seed)?);
    }
    for a in approaches_in(which)? {
        let mut s = *p.multi_settings.get(a);
        s.max_peaks = Some(f.max_peaks);
        s.scored = false;
        // (contrast, near a vehicle) of every peak of every run.
        let labelled: Vec<Vec<(f64, bool)>> = sims
            .par_iter()
            .map(|sim| {
                let run = score_with(p, sim, nominal(p), a, &s, None)?.result;
                let mut out = Vec::new();
                for scan in &run.scans {
                    let cells = scan.grid.values().len() as f64;
                    let truth = vehicles_at(sim, scan.tick);
                    for m in &scan.peaks {
                        let near = truth.iter().any(|v| (v - m.position).norm() <= f.near_m);
                        out.push((m.value * cells, near));
                    }
                }
                Ok(out)
            })
            .collect::<Result<_>>()?;
        let peaks: Vec<(f64, bool)> = labelled.into_iter().flatten().collect();
        let (table, counts) = score_table(&peaks, f.bins)?;
        let [far_n, near_n] = totals(&counts);
        dev.say(&format!(
            "scores {} ({near_n} near, {far_n} far peaks; per bin far/near {counts:?}):",
            APPROACHES[a].0
        ));
        // Shortest round-trip form: the pasted table is the fitted one to the bit.
        let fmt = |v: &[f64]| v.iter().map(f64::to_string).collect::<Vec<_>>().join(", ");
        dev.say(&format!(
            "{} = {{ contrast_edges = [{}], log_ratios = [{}] }}",
            settings_key(a),
            fmt(&table.contrast_edges),
            fmt(&table.log_ratios)
        ));
    }
    Ok(())
}

/// The score table of labelled contrasts `peaks` ((contrast, near a vehicle)) in `bins` bins
/// whose edges are the pooled contrasts' quantiles (equal edges merged and none at the
/// smallest contrast, so fewer bins when many contrasts tie), each bin's ln f₁/f₀ the log of its share of the near peaks over its
/// share of the far ones, each count plus one (Laplace). Also returns the counts per bin,
/// \[far, near\].
pub(super) fn score_table(
    peaks: &[(f64, bool)],
    bins: usize,
) -> Result<(PeakScores, Vec<[usize; 2]>)> {
    ensure!(bins >= 1, "a score table needs at least one bin");
    ensure!(
        peaks.iter().all(|p| p.0.is_finite()),
        "a peak's contrast is not finite"
    );
    let mut sorted: Vec<f64> = peaks.iter().map(|p| p.0).collect();
    sorted.sort_by(f64::total_cmp);
    ensure!(!sorted.is_empty(), "no peaks to learn scores from");
    let mut edges: Vec<f64> = (1..bins).map(|i| sorted[i * sorted.len() / bins]).collect();
    edges.dedup();
    // An edge at the smallest contrast would leave the bin below it empty.
    edges.retain(|&e| e > sorted[0]);
    let mut counts = vec![[0usize; 2]; edges.len() + 1];
    for &(c, near) in peaks {
        counts[edges.partition_point(|&e| e <= c)][usize::from(near)] += 1;
    }
    let [far_n, near_n] = totals(&counts);
    let b = counts.len() as f64;
    let log_ratios = counts
        .iter()
        .map(|c| {
            ((c[1] + 1) as f64 / (near_n as f64 + b)).ln()
                - ((c[0] + 1) as f64 / (far_n as f64 + b)).ln()
        })
        .collect();
    let table = PeakScores {
        contrast_edges: edges,
        log_ratios,
    };
    table.check()?;
    Ok((table, counts))
}

/// The far and near peaks over all bins of per-bin \[far, near\] counts.
fn totals(counts: &[[usize; 2]]) -> [usize; 2] {
    counts
        .iter()
        .fold([0, 0], |[f0, f1], c| [f0 + c[0], f1 + c[1]])
}

/// The approaches named by a developer variable: `all`, or comma-separated indices into
/// `APPROACHES`.
fn approaches_in(which: &str) -> Result<Vec<usize>> {
    if which.trim() == "all" {
        return Ok((0..APPROACHES.len()).collect());
    }
    which
        .split(',')
        .map(|s| match s.trim().parse::<usize>() {
            Ok(a) if a < APPROACHES.len() => Ok(a),
            _ => anyhow::bail!(
                "{s:?} is not `all` or an approach index 0..{}",
                APPROACHES.len()
            ),
        })
        .collect()
}

/// From `start`, one coordinate at a time over its candidates (the others held), keeping a
/// candidate that raises `objective`; rounds repeat until one changes nothing, at most
/// `max_rounds` (≥ 1). Returns the end point and its objective.
fn coordinate_search(
    dev: &dyn Developer,
    name: &str,
    start: ApproachSettings,
    coords: &[Coordinate],
    max_rounds: usize,
    objective: impl Fn(&ApproachSettings) -> Result<(f64, Vec<f64>)>,
) -> Result<(ApproachSettings, f64)> {
    let mut best = start;
    let (mut best_score, motas) = objective(&best)?;
    dev.say(&format!(
        "multi {name}: from {start:?}: MOTA {best_score:.3} {motas:.2?}"
    ));
    for round in 1..=max_rounds.max(1) {
        let before = best;
        for (what, values, set) in coords {
            for &v in values {
                let mut c = best;
                set(&mut c, v);
                if c == best {
                    continue;
                }
                let (m, motas) = objective(&c)?;
                dev.say(&format!(
                    "multi {name} round {round}: {what} {v}: MOTA {m:.3} {motas:.2?}"
                ));
                if m > best_score {
                    best = c;
                    best_score = m;
                }
            }
        }
        dev.say(&format!(
            "multi {name} round {round} choice: MOTA {best_score:.3} {best:?}"
        ));
        if best == before {
            break;
        }
    }
    Ok((best, best_score))
}

/// Setting this environment variable runs [`MultiTuning`]'s search first and prints it.
pub(super) const TUNE_MULTI_ENV: &str = "AV_FUSION_TUNE_MULTI";

/// One coordinate of the multi-vehicle search: its name and how a candidate value sets it.
pub(super) type Coordinate = (&'static str, Vec<f64>, fn(&mut ApproachSettings, f64));

pub(super) fn lobes_with(
    l: Option<LobeEqualisation>,
    power: Option<f64>,
    fraction: Option<f64>,
) -> Option<LobeEqualisation> {
    let base = l.unwrap_or(LobeEqualisation {
        min_fraction: 0.3,
        power: 0.0,
    });
    let next = LobeEqualisation {
        min_fraction: fraction.unwrap_or(base.min_fraction),
        power: power.unwrap_or(base.power),
    };
    (next.power > 0.0).then_some(next)
}

/// The range fade with r₀ or q replaced. A candidate r₀ ≤ 0 turns it off; a fade turned on
/// from off takes q = 1, and a q tried while it is off changes nothing.
pub(super) fn fade_with(
    f: Option<RangeFade>,
    full_weight_m: Option<f64>,
    power: Option<f64>,
) -> Option<RangeFade> {
    let full_weight_m = full_weight_m.unwrap_or(f.map_or(0.0, |f| f.full_weight_m));
    let power = power.unwrap_or(f.map_or(1.0, |f| f.power));
    (full_weight_m > 0.0).then_some(RangeFade {
        full_weight_m,
        power,
    })
}

pub(super) fn tune_multi(
    dev: &dyn Developer,
    p: &Params,
    runs: &[RunSpec],
    which: &str,
) -> Result<()> {
    let order = approaches_in(which)?;
    let t = &p.multi_tuning;
    let mut sims = Vec::new();
    for &seed in &t.seeds {
        sims.extend(simulate_multi(p, runs, seed)?);
    }
    let objective = |a: usize, s: &ApproachSettings| -> Result<(f64, Vec<f64>)> {
        let motas: Vec<f64> = sims
            .par_iter()
            .map(|sim| Ok(score_with(p, sim, nominal(p), a, s, peak_scores_of(p, a, s)?)?.mota))
            .collect::<Result<_>>()?;
        Ok((motas.iter().sum::<f64>() / motas.len().max(1) as f64, motas))
    };
    let mut chosen = Vec::new();
    for a in order {
        let name = APPROACHES[a].0;
        let coords = multi_coordinates(p, a);
        // Scores change what every rate and threshold should be, so turning them on alone
        // from settings tuned without them rarely pays: an approach with a score table is
        // searched from both starts (unscored and scored), and the better end point is kept.
        let configured = *p.multi_settings.get(a);
        let starts: Vec<ApproachSettings> = if p.multi_peak_scores.contains_key(&settings_key(a)) {
            [false, true]
                .iter()
                .map(|&scored| ApproachSettings {
                    scored,
                    ..configured
                })
                .collect()
        } else {
            vec![configured]
        };
        let (mut best, mut best_score) = (configured, f64::NEG_INFINITY);
        for start in starts {
            let (end, score) =
                coordinate_search(dev, name, start, &coords, t.max_rounds, |c| objective(a, c))?;
            if score > best_score {
                (best, best_score) = (end, score);
            }
        }
        chosen.push((settings_key(a), best, best_score));
    }
    for (k, s, m) in chosen {
        dev.say(&format!("{k} (MOTA {m:.3}) = {s:?}"));
    }
    Ok(())
}

/// The coordinates of the multi-vehicle search of approach `a`, in search order: the
/// explaining-away width, the profile shaping of the modalities it uses, then the peaks'
/// threshold and suppression, MCMCDA's rates and limits, and the range fade.
fn multi_coordinates(p: &Params, a: usize) -> Vec<Coordinate> {
    let t = &p.multi_tuning;
    let mut coords: Vec<Coordinate> = vec![("explain away", t.explain_away_deg.clone(), |s, v| {
        s.explain_away_deg = v
    })];
    coords.extend(profile_coordinates(t, APPROACHES[a].1));
    let product = APPROACHES[a].2;
    let product = &product;
    coords.push((
        "kappa",
        if *product {
            t.relative_threshold_product.clone()
        } else {
            t.relative_threshold_sum.clone()
        },
        |s, v| s.relative_threshold = v,
    ));
    coords.push(("nms", t.suppression_radius_m.clone(), |s, v| {
        s.suppression_radius_m = v
    }));
    coords.push(("p_d", t.p_detect.clone(), |s, v| s.p_detect = v));
    coords.push(("clutter", t.clutter_per_scan.clone(), |s, v| {
        s.clutter_per_scan = v
    }));
    if *product {
        coords.push(("floor", t.product_floor.clone(), |s, v| {
            s.product_floor = Some(v);
        }));
    }
    coords.push((
        "max peaks",
        t.max_peaks.iter().map(|&n| n as f64).collect(),
        |s, v| s.max_peaks = Some(v as usize),
    ));
    coords.push(("births", t.births_per_scan.clone(), |s, v| {
        s.births_per_scan = Some(v)
    }));
    if p.multi_peak_scores.contains_key(&settings_key(a)) {
        coords.push(("scored", vec![0.0, 1.0], |s, v| s.scored = v > 0.5));
    }
    coords.push(("max speed", t.max_speed.clone(), |s, v| {
        s.max_speed = Some(v)
    }));
    coords.push((
        "max gap",
        t.max_gap.iter().map(|&d| f64::from(d)).collect(),
        |s, v| s.max_gap = Some(v as u32),
    ));
    coords.push(("fade r0", t.fade_full_weight_m.clone(), |s, v| {
        s.range_fade = fade_with(s.range_fade, Some(v), None);
    }));
    coords.push(("fade power", t.fade_power.clone(), |s, v| {
        s.range_fade = fade_with(s.range_fade, None, Some(v));
    }));
    coords
}

/// The lobe equalisation, exponents and (for both modalities) the video weight.
fn profile_coordinates(t: &MultiTuning, modalities: Modalities) -> Vec<Coordinate> {
    let modalities = &modalities;
    let mut coords: Vec<Coordinate> = Vec::new();
    if *modalities != Modalities::Video {
        coords.push(("audio lobe power", t.lobe_power.clone(), |s, v| {
            s.audio_lobes = lobes_with(s.audio_lobes, Some(v), None);
        }));
        coords.push(("audio lobe fraction", t.lobe_fraction.clone(), |s, v| {
            s.audio_lobes = lobes_with(s.audio_lobes, None, Some(v));
        }));
        coords.push(("audio exponent", t.audio_exponent.clone(), |s, v| {
            s.audio_exponent = v
        }));
    }
    if *modalities != Modalities::Audio {
        coords.push(("video lobe power", t.lobe_power.clone(), |s, v| {
            s.video_lobes = lobes_with(s.video_lobes, Some(v), None);
        }));
        coords.push(("video lobe fraction", t.lobe_fraction.clone(), |s, v| {
            s.video_lobes = lobes_with(s.video_lobes, None, Some(v));
        }));
        coords.push(("video exponent", t.video_exponent.clone(), |s, v| {
            s.video_exponent = v
        }));
    }
    if *modalities == Modalities::Both {
        coords.push(("video weight", t.video_weight.clone(), |s, v| {
            s.video_weight = v
        }));
    }
    coords
}

/// `AV_FUSION_DIAG=1,2,3`: where the multi-vehicle runs' MOTA errors come from.
pub(super) const DIAG_ENV: &str = "AV_FUSION_DIAG";

pub(super) fn diagnose(
    dev: &dyn Developer,
    p: &Params,
    runs: &[RunSpec],
    seeds: &str,
) -> Result<()> {
    for seed in seeds
        .split(',')
        .filter_map(|s| s.trim().parse::<u64>().ok())
    {
        let sims = simulate_multi(p, runs, seed)?;
        for (r, sim) in sims.iter().enumerate() {
            for (a, (name, _, _)) in APPROACHES.iter().enumerate() {
                let s = score(p, sim, nominal(p), a)?;
                let c = &s.clear;
                let mut per_vehicle = Vec::new();
                for g in sim.gt.tracks() {
                    let (mut n, mut near) = (0, 0);
                    for q in g.points() {
                        n += 1;
                        if let Some(scan) = s.result.scans.get(q.frame as usize)
                            && scan
                                .peaks
                                .iter()
                                .any(|m| (m.position - q.location.position()).norm() <= 2.0)
                        {
                            near += 1;
                        }
                    }
                    per_vehicle.push(format!("{near}/{n}"));
                }
                let (_, _, false_peaks, ticks) = peak_counts(sim, &s.result);
                dev.say(&format!(
                    "seed {seed} run {r} {}: MOTA {:.3} OSPA {:.2} | TP {} FN {} FP {} IDSW {} frag {} | tracks {} | peaks near vehicle {} | false peaks {}/{} ticks",
                    name,
                    c.mota,
                    s.ospa,
                    c.true_positives,
                    c.false_negatives,
                    c.false_positives,
                    c.id_switches,
                    c.fragmentations,
                    s.result.tracks.len(),
                    per_vehicle.join(" "),
                    false_peaks,
                    ticks
                ));
            }
        }
    }
    Ok(())
}

/// The multi-vehicle runs (`runs` after the single-vehicle passes) simulated from `seed`, run i
/// on stream `n_passes + i` as the scenario itself draws them.
fn simulate_multi(p: &Params, runs: &[RunSpec], seed: u64) -> Result<Vec<Simulated>> {
    let n_passes = p.passes.len();
    let base = ChaCha8Rng::seed_from_u64(seed);
    runs[n_passes..]
        .par_iter()
        .enumerate()
        .map(|(i, run)| {
            let mut rng = base.clone();
            rng.set_stream((n_passes + i) as u64);
            simulate_run(p, run, &mut rng)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn score_table_by_hand() {
        // Contrasts 1..=6, the three largest near a vehicle; two bins split at the 3rd of
        // 6 sorted values (index 3: contrast 4): bin 0 = {1, 2, 3} all far, bin 1 = {4, 5, 6}
        // all near. With Laplace counts: near shares 1/5 and 4/5, far shares 4/5 and 1/5,
        // so ln f₁/f₀ = ln(1/4) and ln 4.
        let peaks: Vec<(f64, bool)> = (1..=6).map(|c| (f64::from(c), c > 3)).collect();
        let (table, counts) = score_table(&peaks, 2).expect("fits");
        assert_eq!(table.contrast_edges, vec![4.0]);
        assert_eq!(counts, vec![[3, 0], [0, 3]]);
        let want = [0.25f64.ln(), 4f64.ln()];
        for (got, want) in table.log_ratios.iter().zip(want) {
            assert!((got - want).abs() < 1e-12, "{got} against {want}");
        }
        // Ties merge edges: six equal contrasts leave one bin.
        let flat: Vec<(f64, bool)> = (0..6).map(|i| (2.0, i % 2 == 0)).collect();
        let (table, _) = score_table(&flat, 3).expect("fits");
        assert!(table.contrast_edges.is_empty());
        assert_eq!(table.log_ratios.len(), 1);
        assert!(score_table(&[], 3).is_err());
        assert!(score_table(&[(f64::NAN, true)], 3).is_err());
    }

    #[test]
    fn fade_coordinates_turn_on_change_and_turn_off() {
        let on = fade_with(None, Some(8.0), None);
        assert_eq!(
            on,
            Some(RangeFade {
                full_weight_m: 8.0,
                power: 1.0
            })
        );
        let half = fade_with(on, None, Some(0.5));
        assert_eq!(half.map(|f| (f.full_weight_m, f.power)), Some((8.0, 0.5)));
        assert_eq!(fade_with(half, Some(0.0), None), None);
        assert_eq!(fade_with(None, None, Some(2.0)), None);
    }

    #[test]
    fn approaches_are_all_or_valid_indices() {
        assert_eq!(
            approaches_in("all").expect("all"),
            (0..6).collect::<Vec<_>>()
        );
        assert_eq!(approaches_in("5, 2").expect("list"), vec![5, 2]);
        assert!(approaches_in("6").is_err());
        assert!(approaches_in("1,x").is_err());
        assert!(approaches_in("").is_err());
    }
}
