//! The multi-vehicle coordinate search of [`MultiTuning`].

use rayon::prelude::*;

use super::{Log, MultiTuning, Seeded, simulate_multi_all};
use crate::scene::{
    Approach, ApproachSettings, Params, RunSpec, nominal, peak_scores_of, score_with,
};
use crate::{LobeEqualisation, Modalities, RangeFade, Result};

/// One coordinate of the multi-vehicle search: its name and how a candidate value sets it.
type Coordinate = (&'static str, Vec<f64>, fn(&mut ApproachSettings, f64));

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

/// [`MultiTuning`]'s search for the approaches `which` (in search order; see
/// [`approaches_in`](super::approaches_in)) on the multi-vehicle runs of the seeds
/// of `seeded`: each line goes to `log` as it is measured, the choices last (as `key (MOTA m)
/// = settings`). An approach with a peak-score table is searched from both starts, unscored
/// and scored, and the better end point is kept.
pub fn tune_multi(
    p: &Params,
    runs: &[RunSpec],
    seeded: &Seeded,
    which: &[Approach],
    log: &dyn Log,
) -> Result<()> {
    let t = &p.multi_tuning;
    let sims = simulate_multi_all(p, runs, seeded)?;
    let objective = |a: Approach, s: &ApproachSettings| -> Result<(f64, Vec<f64>)> {
        let motas: Vec<f64> = sims
            .par_iter()
            .map(|sim| Ok(score_with(p, sim, nominal(p), a, s, peak_scores_of(p, a, s)?)?.mota))
            .collect::<Result<_>>()?;
        Ok((motas.iter().sum::<f64>() / motas.len().max(1) as f64, motas))
    };
    let mut chosen = Vec::new();
    for &a in which {
        let name = a.name();
        let coords = multi_coordinates(p, a);
        // Scores change what every rate and threshold should be, so turning them on alone
        // from settings tuned without them rarely pays: an approach with a score table is
        // searched from both starts (unscored and scored), and the better end point is kept.
        let configured = *p.multi_settings.get(a);
        let starts: Vec<ApproachSettings> = if p.multi_peak_scores.contains_key(a.settings_key()) {
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
                coordinate_search(log, name, start, &coords, t.max_rounds, |c| objective(a, c))?;
            if score > best_score {
                (best, best_score) = (end, score);
            }
        }
        chosen.push(format!(
            "{} (MOTA {best_score:.3}) = {best:?}",
            a.settings_key()
        ));
    }
    for line in chosen {
        log.say(&line);
    }
    Ok(())
}

/// The coordinates of the multi-vehicle search of approach `a`, in search order: the
/// explaining-away width, the profile shaping of the modalities it uses, then the peaks'
/// threshold and suppression, MCMCDA's rates and limits, and the range fade.
fn multi_coordinates(p: &Params, a: Approach) -> Vec<Coordinate> {
    let t = &p.multi_tuning;
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

/// From `start`, one coordinate at a time over its candidates (the others held), keeping a
/// candidate that raises `objective`; rounds repeat until one changes nothing, at most
/// `max_rounds` (≥ 1). Returns the end point and its objective.
fn coordinate_search(
    log: &dyn Log,
    name: &str,
    start: ApproachSettings,
    coords: &[Coordinate],
    max_rounds: usize,
    objective: impl Fn(&ApproachSettings) -> Result<(f64, Vec<f64>)>,
) -> Result<(ApproachSettings, f64)> {
    let mut best = start;
    let (mut best_score, motas) = objective(&best)?;
    log.say(&format!(
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
                log.say(&format!(
                    "multi {name} round {round}: {what} {v}: MOTA {m:.3} {motas:.2?}"
                ));
                if m > best_score {
                    best = c;
                    best_score = m;
                }
            }
        }
        log.say(&format!(
            "multi {name} round {round} choice: MOTA {best_score:.3} {best:?}"
        ));
        if best == before {
            break;
        }
    }
    Ok((best, best_score))
}
