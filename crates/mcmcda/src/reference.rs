//! Slow, independent routes to what the sampler computes incrementally, for tests and for users
//! checking a partition: the log posterior from the per-scan counts of Oh, Russell & Sastry 2009
//! eq. 9 with each track filtered by tracker-model's general Kalman filter, and the enumeration of
//! every feasible partition of a tiny problem.

use nalgebra::Vector4;
use tracker_model::{Gaussian, LinearObservation, ObservationModel, TransitionModel};

use crate::config::{Model, TrackEnd, TrackInit};
use crate::error::{Error, Result};
use crate::partition::Partition;
use crate::problem::{MeasId, Problem};

/// log P(ω | Y) + const from the counts e_t, z_t, c_t, a_t, d_t, g_t, f_t of every scan in
/// `window` and a general Kalman filter per track. Agrees with
/// [`Partition::log_posterior`] (tested); about a hundred times slower.
pub fn log_posterior_by_counts(
    model: &Model,
    problem: &Problem,
    window: std::ops::RangeInclusive<usize>,
    tracks: &[Vec<MeasId>],
) -> Result<f64> {
    let cfg = model.config();
    let (lo, hi) = (*window.start(), *window.end());
    let sensor = LinearObservation::leading_components(cfg.measurement_noise)?;
    let present = |t: usize, tr: &[MeasId]| {
        problem.scan_of(tr[0]) <= t && t <= problem.scan_of(tr[tr.len() - 1])
    };
    let mut lp = 0.0;
    for t in lo..=hi {
        let e_prev = if t == lo {
            0
        } else {
            tracks.iter().filter(|tr| present(t - 1, tr)).count()
        };
        let z = if t == lo {
            0
        } else {
            tracks
                .iter()
                .filter(|tr| problem.scan_of(tr[tr.len() - 1]) == t - 1)
                .count()
        };
        let c = e_prev - z;
        let a = tracks
            .iter()
            .filter(|tr| problem.scan_of(tr[0]) == t)
            .count();
        let d = tracks
            .iter()
            .flat_map(|tr| tr.iter())
            .filter(|&&m| problem.scan_of(m) == t)
            .count();
        let g = c + a - d;
        let f = problem.scan(t).len() - d;
        // With TrackEnd::Undetected each track's end is scored below instead of by z_t.
        let z = if cfg.track_end == TrackEnd::Disappeared {
            z
        } else {
            0
        };
        let counts = [z, c, d, g, a, f].map(|v| v as f64);
        let logs = [
            cfg.p_disappear.ln(),
            (1.0 - cfg.p_disappear).ln(),
            cfg.p_detect.ln(),
            (1.0 - cfg.p_detect).ln(),
            (cfg.births_per_scan / cfg.volume).ln(),
            (cfg.clutter_per_scan / cfg.volume).ln(),
        ];
        lp += counts.iter().zip(logs).map(|(n, l)| n * l).sum::<f64>();
    }
    for tr in tracks {
        lp += track_log_likelihood(model, problem, &sensor, tr)?;
        // A detection's score density is f₁(s), a false alarm's f₀(s): against the
        // all-clutter constant Π f₀, each measurement of a track adds ln f₁(s)/f₀(s).
        lp += tr.iter().map(|&m| problem.log_score_ratio(m)).sum::<f64>();
        let remaining = hi - problem.scan_of(tr[tr.len() - 1]);
        if cfg.track_end == TrackEnd::Undetected && remaining > 0 {
            // Σ over when the target disappeared unseen, or that it survived unseen.
            let s = (1.0 - cfg.p_disappear) * (1.0 - cfg.p_detect);
            let p: f64 = (0..remaining)
                .map(|j| s.powf(j as f64) * cfg.p_disappear)
                .sum::<f64>()
                + s.powf(remaining as f64);
            lp += p.ln();
        }
        if let TrackInit::TwoPoint { .. } = cfg.track_init {
            lp -= (std::f64::consts::PI * cfg.max_speed.powi(2)).ln();
        }
    }
    Ok(lp)
}

/// Σ log N(y_i; C x̂⁻_i, S_i) for i ≥ 2 with the general filter, predicting each gap in one
/// jump of Δ scans (A(Δ), Q(Δ)) as the sampler does.
fn track_log_likelihood(
    model: &Model,
    problem: &Problem,
    sensor: &LinearObservation<4, 2>,
    track: &[MeasId],
) -> Result<f64> {
    let cfg = model.config();
    let y1 = problem.position(track[0]);
    let mut state = match cfg.track_init {
        TrackInit::FirstMeasurement { .. } => {
            let (mean, cov) = model.start_at(y1, model.initial_velocity_variance);
            Gaussian::new(mean, cov)?
        }
        TrackInit::TwoPoint { initial_covariance } => {
            let y2 = problem.position(track[1]);
            let gap = (problem.scan_of(track[1]) - problem.scan_of(track[0])) as f64;
            let v = (y2 - y1) / (gap * cfg.motion.dt_s());
            Gaussian::new(Vector4::new(y1.x, y1.y, v.x, v.y), initial_covariance)?
        }
    };
    let mut ll = 0.0;
    for pair in track.windows(2) {
        let gap = (problem.scan_of(pair[1]) - problem.scan_of(pair[0])) as u32;
        let predicted = cfg.motion.predict_steps(&state, gap);
        let updated = sensor.update(&predicted, &problem.position(pair[1]))?;
        ll += updated.innovation.log_likelihood;
        state = updated.state;
    }
    Ok(ll)
}

/// Every feasible partition of the scans `window` (tracks of ≥ 2 measurements, one per scan,
/// gaps ≤ d̄ within the neighbourhood radius). Exponential: for problems of a handful of
/// measurements only. Fails with [`Error::NoNeighbourhoods`] on a problem built
/// [`Problem::without_neighbourhoods`].
pub fn enumerate_partitions(
    model: &Model,
    problem: &Problem,
    window: std::ops::RangeInclusive<usize>,
) -> Result<Vec<Vec<Vec<MeasId>>>> {
    if !problem.has_neighbourhoods() {
        return Err(Error::NoNeighbourhoods);
    }
    let ids: Vec<MeasId> = window
        .clone()
        .flat_map(|s| problem.scan(s).iter().copied())
        .collect();
    // Every feasible track (as a chain of neighbours).
    let mut tracks: Vec<Vec<MeasId>> = Vec::new();
    let mut stack: Vec<Vec<MeasId>> = ids.iter().map(|&m| vec![m]).collect();
    while let Some(t) = stack.pop() {
        if t.len() >= 2 {
            tracks.push(t.clone());
        }
        let last = t[t.len() - 1];
        for d in 1..=problem.max_gap() {
            if problem.scan_of(last) + d > *window.end() {
                break;
            }
            for &n in problem.forward(last, d) {
                let mut longer = t.clone();
                longer.push(n);
                stack.push(longer);
            }
        }
    }
    tracks.sort();
    // Sets of pairwise disjoint tracks, each set listed once (increasing track index).
    let mut out = Vec::new();
    let mut chosen: Vec<usize> = Vec::new();
    let mut used = vec![false; problem.n_measurements()];
    fn recurse(
        tracks: &[Vec<MeasId>],
        start: usize,
        chosen: &mut Vec<usize>,
        used: &mut Vec<bool>,
        out: &mut Vec<Vec<Vec<MeasId>>>,
    ) {
        out.push(chosen.iter().map(|&i| tracks[i].clone()).collect());
        for i in start..tracks.len() {
            if tracks[i].iter().any(|&m| used[m as usize]) {
                continue;
            }
            tracks[i].iter().for_each(|&m| used[m as usize] = true);
            chosen.push(i);
            recurse(tracks, i + 1, chosen, used, out);
            chosen.pop();
            tracks[i].iter().for_each(|&m| used[m as usize] = false);
        }
    }
    recurse(&tracks, 0, &mut chosen, &mut used, &mut out);
    // Validate through the same checks a user's partition gets.
    for p in &out {
        Partition::from_tracks(model, problem, window.clone(), p)?;
    }
    Ok(out)
}
