//! The peak-score fit of [`ScoreFit`] and the multi-vehicle error breakdown.

use rayon::prelude::*;

use super::{Log, ScoreFit, Seeded, peak_counts, simulate_multi, simulate_multi_all, vehicles_at};
use crate::error::invalid;
use crate::scene::{
    Approach, Params, RunSpec, Settings, Simulated, nominal, peak_scores_of, score_with,
};
use crate::{PeakScores, Result};

/// The score tables of [`Params::multi_peak_scores`] for the approaches `which`, learnt as
/// [`ScoreFit`] says on the multi-vehicle runs of the seeds of `seeded`, each printed to `log`
/// as TOML with its counts. For each approach, with its count-aware multi-vehicle settings
/// (but `max_peaks` peaks per tick, unscored), every peak is labelled
/// by whether a vehicle is within `near_m` at its tick (the truth of calibration runs, as a
/// detector's confidence is calibrated on labelled data; the reported seed is never simulated
/// here), and [`score_table`] bins their contrasts. The committed tables were fitted in turns
/// with the count-aware searches (docs/av-fusion.md); the one configuration's search
/// ([`tune_one_config`](super::tune_one_config)) uses them as committed.
pub fn fit_peak_scores(
    p: &Params,
    runs: &[RunSpec],
    seeded: &Seeded,
    which: &[Approach],
    log: &dyn Log,
) -> Result<()> {
    let f = &p.score_fit;
    check_score_fit(f)?;
    let sims = simulate_multi_all(p, runs, seeded)?;
    for &a in which {
        let mut s = *p.count_aware.multi.get(a);
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
        log.say(&format!(
            "scores {a} ({near_n} near, {far_n} far peaks; per bin far/near {counts:?}):"
        ));
        // Shortest round-trip form: the pasted table is the fitted one to the bit.
        let fmt = |v: &[f64]| v.iter().map(f64::to_string).collect::<Vec<_>>().join(", ");
        log.say(&format!(
            "{} = {{ contrast_edges = [{}], log_ratios = [{}] }}",
            a.settings_key(),
            fmt(&table.contrast_edges),
            fmt(&table.log_ratios)
        ));
    }
    Ok(())
}

/// Checks [`ScoreFit`]'s bins, peaks per tick and distance.
fn check_score_fit(f: &ScoreFit) -> Result<()> {
    if f.bins < 2 {
        return Err(invalid("score_fit.bins", "must be at least 2"));
    }
    if f.max_peaks < 1 {
        return Err(invalid("score_fit.max_peaks", "must be at least 1"));
    }
    if f.near_m.is_nan() || f.near_m <= 0.0 {
        return Err(invalid("score_fit.near_m", "must be > 0"));
    }
    Ok(())
}

/// The score table of labelled contrasts `peaks` ((contrast, near a vehicle)) in `bins` bins
/// whose edges are the pooled contrasts' quantiles (equal edges merged and none at the
/// smallest contrast, so fewer bins when many contrasts tie), each bin's ln f₁/f₀ the log of
/// its share of the near peaks over its share of the far ones, each count plus one (Laplace,
/// so an empty bin stays finite). Also returns the counts per bin, \[far, near\].
pub fn score_table(peaks: &[(f64, bool)], bins: usize) -> Result<(PeakScores, Vec<[usize; 2]>)> {
    if bins < 1 {
        return Err(invalid("bins", "a score table needs at least one bin"));
    }
    if !peaks.iter().all(|p| p.0.is_finite()) {
        return Err(invalid("peaks", "a peak's contrast is not finite"));
    }
    let mut sorted: Vec<f64> = peaks.iter().map(|p| p.0).collect();
    sorted.sort_by(f64::total_cmp);
    if sorted.is_empty() {
        return Err(invalid("peaks", "no peaks to learn scores from"));
    }
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

/// Where the multi-vehicle runs' MOTA errors come from: for each seed of `seeded`, each
/// multi-vehicle run and each approach (with its settings of `settings`), a line to `log` with
/// MOTA, OSPA, the CLEAR MOT counts, the tracks, each vehicle's ticks with a peak within 2 m
/// and the peaks farther than 2 m from every vehicle.
pub fn diagnose(
    p: &Params,
    settings: &Settings,
    runs: &[RunSpec],
    seeded: &Seeded,
    log: &dyn Log,
) -> Result<()> {
    for (seed, base) in seeded {
        let sims = simulate_multi(p, runs, base)?;
        for (r, sim) in sims.iter().enumerate() {
            for a in Approach::ALL {
                let line = diagnosis(p, sim, a, settings.get(a))?;
                log.say(&format!("seed {seed} run {r} {line}"));
            }
        }
    }
    Ok(())
}

/// Approach `a` on one multi-vehicle run: its line of [`diagnose`] after the seed and run.
fn diagnosis(
    p: &Params,
    sim: &Simulated,
    a: Approach,
    settings: &crate::scene::ApproachSettings,
) -> Result<String> {
    let s = score_with(
        p,
        sim,
        nominal(p),
        a,
        settings,
        peak_scores_of(p, a, settings)?,
    )?;
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
    let counts = peak_counts(sim, &s.result);
    Ok(format!(
        "{a}: MOTA {:.3} OSPA {:.2} | TP {} FN {} FP {} IDSW {} frag {} | tracks {} | peaks near vehicle {} | false peaks {}/{} ticks",
        c.mota,
        s.ospa,
        c.true_positives,
        c.false_negatives,
        c.false_positives,
        c.id_switches,
        c.fragmentations,
        s.result.tracks.len(),
        per_vehicle.join(" "),
        counts.false_peaks,
        counts.ticks
    ))
}
