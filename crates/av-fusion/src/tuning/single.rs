//! The single-vehicle grid search of [`Tuning`](super::Tuning) and what it reports besides: each sensor's
//! bearing error.

use std::f64::consts::PI;

use rayon::prelude::*;

use super::{Log, Seeded, TuneScore, tune_score};
use crate::scene::{
    Approach, ApproachSettings, Calibration, Params, RunSpec, Simulated, nominal, sensor_nodes,
    simulate_run,
};
use crate::{Error, Modalities, Result};

/// One sensor's bearing error over a set of reports ([`bearing_errors`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BearingError {
    /// Mean, degrees.
    pub mean_deg: f64,
    /// Standard deviation, degrees.
    pub sd_deg: f64,
}

/// Each sensor's bearing error on the single-vehicle passes: the bearing of its profile's
/// maximum from the believed pose at heading error `calib` against the true bearing of the
/// vehicle at the report's time, over the reports where the vehicle is inside the region.
/// Returns one [`BearingError`] per sensor, in sensor order.
pub fn bearing_errors(
    p: &Params,
    sims: &[&Simulated],
    calib: Calibration,
) -> Result<Vec<BearingError>> {
    let nodes = sensor_nodes(p, calib, p.settings.get(Approach::AudioVideoProduct))?;
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
            BearingError {
                mean_deg: m,
                sd_deg: v.sqrt(),
            }
        })
        .collect())
}

/// Stage 1's rule: among the candidates whose error is within the fraction `tolerance` of the
/// lowest, the one with the highest MOTA (ties keep the earlier). Error differences of a few
/// millimetres are noise on 27 passes, while a broad profile that tracks a lone vehicle as
/// well can still cost a great deal of MOTA in false and broken tracks.
pub fn stage1_choice(
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

/// Grid search on the tuning seeds, run for each of the six approaches on its own, from the
/// configured values, by the same stages and objectives. Stage 1: the profile exponent γ of
/// each modality the approach uses, for audio+video the video weight w_v (audio weight 1),
/// and for the product the floor ε, by the approach's mean error over the single-vehicle
/// passes (within `error_tolerance` of the lowest, the highest MOTA: [`stage1_choice`]).
/// Stage 2a, with stage 1's choice: the NMS radius and MCMCDA's p_d and clutter rate by the
/// approach's mean MOTA over every run (single and multi-vehicle). Stage 2b: the peaks' κ by
/// the same MOTA. Ties keep the earlier candidate. The stages repeat until a round changes
/// nothing (at most `max_rounds`).
///
/// Each line goes to `log` as it is measured; returns them all, the choice last as TOML.
pub fn tune(p: &Params, runs: &[RunSpec], seeded: &Seeded, log: &dyn Log) -> Result<String> {
    let t = &p.tuning;
    if seeded.is_empty() {
        return Err(crate::error::invalid("tuning.seeds", "no tuning seeds"));
    }
    let sims = simulate_all(p, runs, seeded)?;
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
            .map(|e| format!("{:+.1}° ± {:.1}°", e.mean_deg, e.sd_deg))
            .collect();
        bearing_lines.push(format!(
            "bearing error of the profile maximum at {calib:?}: {}",
            text.join(", ")
        ));
    }
    let seeds: Vec<u64> = seeded.iter().map(|(seed, _)| *seed).collect();
    let mut search = Search {
        log,
        out: format!("av-fusion tuning on seeds {seeds:?}\n"),
        sims,
        q: p.clone(),
    };
    for line in bearing_lines {
        search.say(&line);
    }
    for a in Approach::ALL {
        let name = a.name();
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
    // The choice as TOML, to paste into the configuration.
    for a in Approach::ALL {
        search.say(&settings_toml(a, search.q.settings.get(a)));
    }
    Ok(search.out)
}

/// Every run of every seed of `seeded` ((multi-vehicle, run)), seed after seed, run i of a
/// seed on stream i of its generator.
fn simulate_all(p: &Params, runs: &[RunSpec], seeded: &Seeded) -> Result<Vec<(bool, Simulated)>> {
    let n_passes = p.passes.len();
    let mut sims = Vec::new();
    for (_, base) in seeded {
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
    Ok(sims)
}

/// The single-vehicle search's state: the simulated tuning runs, the parameters as chosen so
/// far, and the table of every candidate's score, which also goes line by line to the
/// log as it is measured (the search takes minutes).
struct Search<'a> {
    log: &'a dyn Log,
    out: String,
    sims: Vec<(bool, Simulated)>,
    q: Params,
}

impl Search<'_> {
    fn say(&mut self, text: &str) {
        self.log.say(text);
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
    fn score(&self, a: Approach, w: ApproachSettings) -> Result<TuneScore> {
        let mut c = self.q.clone();
        *c.settings.get_mut(a) = w;
        tune_score(&c, &self.sims, a)
    }

    /// Stage 1: the grid of the fusion parameters this approach uses (a single value
    /// elsewhere), chosen by [`stage1_choice`].
    fn stage1(&mut self, a: Approach) -> Result<()> {
        let t = &self.q.tuning.clone();
        let (name, modalities, product) = (a.name(), a.modalities(), a.is_product());
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
            return Err(Error::EmptyGrid { stage: "stage-1" });
        };
        *self.q.settings.get_mut(a) = w;
        self.line(&format!("stage 1 choice {name}: {w:?}"), &s);
        Ok(())
    }

    /// Stage 2a: the NMS radius, p_d and clutter rate by the approach's mean MOTA.
    fn stage2a(&mut self, a: Approach) -> Result<()> {
        let t = &self.q.tuning.clone();
        let name = a.name();
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
            return Err(Error::EmptyGrid { stage: "stage-2a" });
        };
        *self.q.settings.get_mut(a) = w;
        self.line(&format!("stage 2a choice {name}: {w:?}"), &s);
        Ok(())
    }

    /// Stage 2b: the peaks' κ by the same MOTA; returns the round's choice.
    fn stage2b(&mut self, a: Approach) -> Result<(ApproachSettings, TuneScore)> {
        let name = a.name();
        let kappas = if a.is_product() {
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
            return Err(Error::EmptyGrid { stage: "stage-2b" });
        };
        *self.q.settings.get_mut(a) = best.0;
        Ok(best)
    }
}

/// Approach `a`'s settings `w` as a line of TOML for the configuration (only the keys the
/// approach uses).
fn settings_toml(a: Approach, w: &ApproachSettings) -> String {
    let modalities = a.modalities();
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
    format!("{} = {{ {} }}", a.settings_key(), fields.join(", "))
}
