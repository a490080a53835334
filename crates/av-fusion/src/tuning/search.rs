//! The coordinate search of [`Tuning`] behind the one configuration: each approach's
//! settings for every run, one vehicle or several, chosen for it alone by the same search
//! (the same coordinates, candidates, rounds and objective for all six approaches).

use rayon::prelude::*;

use super::{Log, Seeded, Tuning, simulate_all};
use crate::scene::{
    Approach, ApproachSettings, Params, RunSpec, Settings, Simulated, count_aware_of, nominal,
    peak_scores_of, score_with,
};
use crate::{LobeEqualisation, Modalities, RangeFade, Result};

/// One coordinate of the search: its name, its candidates and how a candidate sets it.
pub(super) type Coordinate = (&'static str, Vec<f64>, fn(&mut ApproachSettings, f64));

/// The lobe equalisation with β or η replaced; β ≤ 0 turns it off, and one turned on from off
/// takes η = 0.3.
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

/// One candidate the search scored: its approach, round, coordinate and value (a flag as 0 or
/// 1), the [`objective`] and whether the search held it after the coordinate's step.
#[derive(Debug, Clone, PartialEq)]
pub struct SearchRow {
    /// The approach searched.
    pub approach: Approach,
    /// Round (1-based; 0 for the two starting points).
    pub round: usize,
    /// The coordinate (for a starting point: `count-aware single` or `count-aware multi`).
    pub coordinate: &'static str,
    /// The candidate value.
    pub value: f64,
    /// Its objective.
    pub score: f64,
    /// Held after this coordinate's step (for a start: the one the search starts from).
    pub kept: bool,
}

/// What [`objective`] weighs, over the tuning runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectiveParts {
    /// J (higher is better).
    pub value: f64,
    /// Mean MOTA over the single-vehicle passes.
    pub single_mota: f64,
    /// Mean MOTA over the multi-vehicle runs.
    pub multi_mota: f64,
    /// Mean error over the single-vehicle passes, m (a pass without a track counts as the
    /// match distance).
    pub error_m: f64,
}

/// The search's objective for approach `a` with settings `s` on the simulated runs `sims`
/// (every run of the tuning seeds): J = ½ (mean MOTA of the single-vehicle passes) + ½ (mean
/// MOTA of the multi-vehicle runs) − w · (mean single-vehicle error, m), w =
/// [`Tuning::error_weight_per_m`]. Scenes with one vehicle and with several weigh the same,
/// since a deployment meets both; the error term keeps the paper's measure (Kushwaha et al.
/// 2008, Figs. 10–11) in the choice, where MOTA's 5 m match would not see it.
pub fn objective(
    p: &Params,
    sims: &[Simulated],
    a: Approach,
    s: &ApproachSettings,
) -> Result<ObjectiveParts> {
    let table = peak_scores_of(p, a, s)?;
    let scored: Vec<(bool, f64, Vec<f64>)> = sims
        .par_iter()
        .map(|sim| {
            let r = score_with(p, sim, nominal(p), a, s, table)?;
            let errors = r
                .errors
                .iter()
                .map(|e| e.unwrap_or(p.match_distance_m))
                .collect();
            Ok((sim.multi, r.mota, errors))
        })
        .collect::<Result<_>>()?;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let mota_of = |multi: bool| -> Vec<f64> {
        scored
            .iter()
            .filter(|r| r.0 == multi)
            .map(|r| r.1)
            .collect()
    };
    let errors: Vec<f64> = scored
        .iter()
        .filter(|r| !r.0)
        .flat_map(|r| r.2.clone())
        .collect();
    let (single_mota, multi_mota, error_m) =
        (mean(&mota_of(false)), mean(&mota_of(true)), mean(&errors));
    Ok(ObjectiveParts {
        value: 0.5 * single_mota + 0.5 * multi_mota - p.tuning.error_weight_per_m * error_m,
        single_mota,
        multi_mota,
        error_m,
    })
}

/// The one configuration: for each approach on its own, [`Tuning`]'s search on every run of
/// the seeds of `seeded`; each line goes to `log` as it is measured.
/// Returns each approach's choice and every scored candidate.
pub fn tune_one_config(
    p: &Params,
    runs: &[RunSpec],
    seeded: &Seeded,
    log: &dyn Log,
) -> Result<(Settings, Vec<SearchRow>)> {
    let sims = simulate_all(p, runs, seeded)?;
    log.say(&format!("{} tuning runs simulated", sims.len()));
    let mut rows = Vec::new();
    let settings = Settings::try_from_fn(|a| tune_approach(p, &sims, a, log, &mut rows))?;
    Ok((settings, rows))
}

/// Approach `a`'s search: from the better (by [`objective`]; a tie keeps the multi-vehicle
/// one) of its two count-aware reference settings, the coordinate search over
/// [`coordinates`], each candidate's row pushed to `rows`.
fn tune_approach(
    p: &Params,
    sims: &[Simulated],
    a: Approach,
    log: &dyn Log,
    rows: &mut Vec<SearchRow>,
) -> Result<ApproachSettings> {
    let j = |s: &ApproachSettings| -> Result<f64> {
        let parts = objective(p, sims, a, s)?;
        log.say(&format!("{a}: {parts:?}"));
        Ok(parts.value)
    };
    let (multi, single) = (*count_aware_of(p, a, true), *count_aware_of(p, a, false));
    let (jm, js) = (j(&multi)?, j(&single)?);
    let from_single = js > jm;
    for (coordinate, score, kept) in [
        ("count-aware multi", jm, !from_single),
        ("count-aware single", js, from_single),
    ] {
        rows.push(SearchRow {
            approach: a,
            round: 0,
            coordinate,
            value: 0.0,
            score,
            kept,
        });
    }
    let start = if from_single {
        (single, js)
    } else {
        (multi, jm)
    };
    let coords = coordinates(p, a);
    let (end, score) = coordinate_search(a, start, &coords, p.tuning.max_rounds, &j, rows)?;
    log.say(&format!("{a}: chosen, J {score:.4}: {end:?}"));
    Ok(end)
}

/// The coordinates of the search of approach `a`, in search order: the
/// explaining-away width, the profile shaping of the modalities it uses, then the peaks'
/// threshold and suppression, MCMCDA's rates and limits, and the range fade.
fn coordinates(p: &Params, a: Approach) -> Vec<Coordinate> {
    let t = &p.tuning;
    let mut coords: Vec<Coordinate> = vec![("explain away", t.explain_away_deg.clone(), |s, v| {
        s.explain_away_deg = v
    })];
    coords.extend(profile_coordinates(t, a.modalities()));
    let product = &a.is_product();
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
    if p.multi_peak_scores.contains_key(a.settings_key()) {
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
fn profile_coordinates(t: &Tuning, modalities: Modalities) -> Vec<Coordinate> {
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

/// From `start` (settings and objective), one coordinate at a time over its candidates (the
/// others held), keeping a candidate that raises `objective` strictly (so a tie keeps the
/// incumbent); rounds repeat until one changes nothing, at most `max_rounds` (≥ 1). Every
/// candidate goes to `rows`, the incumbent with its known score. Returns the end point and
/// its objective.
pub(super) fn coordinate_search(
    a: Approach,
    start: (ApproachSettings, f64),
    coords: &[Coordinate],
    max_rounds: usize,
    objective: &dyn Fn(&ApproachSettings) -> Result<f64>,
    rows: &mut Vec<SearchRow>,
) -> Result<(ApproachSettings, f64)> {
    let (mut best, mut best_score) = start;
    for round in 1..=max_rounds.max(1) {
        let before = best;
        for (what, values, set) in coords {
            let incumbent = best;
            let mut held = None;
            for &v in values {
                let mut c = incumbent;
                set(&mut c, v);
                let score = if c == incumbent {
                    held.get_or_insert(rows.len());
                    best_score
                } else {
                    objective(&c)?
                };
                if score > best_score {
                    (best, best_score, held) = (c, score, Some(rows.len()));
                }
                rows.push(SearchRow {
                    approach: a,
                    round,
                    coordinate: what,
                    value: v,
                    score,
                    kept: false,
                });
            }
            if let Some(i) = held {
                rows[i].kept = true;
            }
        }
        if best == before {
            break;
        }
    }
    Ok((best, best_score))
}
