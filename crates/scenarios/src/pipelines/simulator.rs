//! `simulator-poisson`: draws many scenarios from the MCMCDA model and compares the observed
//! birth, clutter, detection and disappearance rates with the parameters that generated them.

use anyhow::Result;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Deserialize;
use tracker_model::{Origin, Simulation, SimulationConfig};

use crate::{Chart, Claim, Env, Figure, Metrics, Pipeline, Section, Series, Style, Table, fmt_num};

/// The `simulator-poisson` pipeline.
pub struct SimulatorPoisson;

/// Its parameters.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Independent simulations, each on its own generator stream.
    n_runs: usize,
    /// The model.
    config: SimulationConfig,
}

/// Counts from one simulation, or summed over many.
#[derive(Default, Clone)]
pub struct Counts {
    scans: usize,
    births: usize,
    clutter: usize,
    clutter_histogram: Vec<usize>,
    target_scans: usize,
    detections: usize,
    transitions: usize,
    disappearances: usize,
    max_speed_seen: f64,
}

fn count(sim: &Simulation, n_scans: u32) -> Counts {
    let mut c = Counts {
        scans: sim.scans.len(),
        births: sim.truth.len(),
        target_scans: sim.truth.n_points(),
        ..Counts::default()
    };
    for scan in &sim.scans {
        let clutter = scan
            .measurements
            .iter()
            .filter(|m| m.origin == Origin::Clutter)
            .count();
        c.clutter += clutter;
        c.detections += scan.measurements.len() - clutter;
        if c.clutter_histogram.len() <= clutter {
            c.clutter_histogram.resize(clutter + 1, 0);
        }
        c.clutter_histogram[clutter] += 1;
    }
    for t in sim.truth.tracks() {
        // A target that ends before the last scan disappeared; each scan it survived is a
        // transition, and so is the one in which it vanished.
        let vanished = t.last_frame().is_some_and(|f| f + 1 < n_scans);
        c.transitions += t.len() - 1 + usize::from(vanished);
        c.disappearances += usize::from(vanished);
        for p in t.points() {
            if let Some(v) = p.velocity {
                c.max_speed_seen = c.max_speed_seen.max(v.norm());
            }
        }
    }
    c
}

impl Counts {
    fn add(&mut self, o: &Counts) {
        self.scans += o.scans;
        self.births += o.births;
        self.clutter += o.clutter;
        self.target_scans += o.target_scans;
        self.detections += o.detections;
        self.transitions += o.transitions;
        self.disappearances += o.disappearances;
        self.max_speed_seen = self.max_speed_seen.max(o.max_speed_seen);
        if self.clutter_histogram.len() < o.clutter_histogram.len() {
            self.clutter_histogram.resize(o.clutter_histogram.len(), 0);
        }
        for (a, b) in self.clutter_histogram.iter_mut().zip(&o.clutter_histogram) {
            *a += b;
        }
    }
}

/// ln P(X = k) for X ~ Poisson(λ).
fn poisson_ln_pmf(k: usize, lambda: f64) -> f64 {
    let ln_fact: f64 = (1..=k).map(|i| (i as f64).ln()).sum();
    k as f64 * lambda.ln() - lambda - ln_fact
}

/// The summed counts and the model that produced them.
pub struct Output {
    n_runs: usize,
    config: SimulationConfig,
    total: Counts,
}

impl Pipeline for SimulatorPoisson {
    type Params = Params;
    type Output = Output;

    fn compute(p: &Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Output> {
        anyhow::ensure!(p.n_runs > 0, "n_runs must be > 0");
        let sim = p.config.check()?;
        let n_scans = p.config.n_scans;
        env.progress.set_length(p.n_runs as u64);
        let base = rng.clone();
        let per_run: Vec<Counts> = (0..p.n_runs)
            .into_par_iter()
            .map(|r| {
                let mut rng = base.clone();
                rng.set_stream(r as u64);
                let counts = sim.simulate(&mut rng).map(|s| count(&s, n_scans));
                env.progress.advance(1);
                counts
            })
            .collect::<Result<_, _>>()?;
        let mut total = Counts::default();
        per_run.iter().for_each(|c| total.add(c));
        Ok(Output {
            n_runs: p.n_runs,
            config: p.config.clone(),
            total,
        })
    }

    fn metrics(out: &Output) -> Metrics {
        let mut metrics = Metrics::new();
        for (name, _, observed, _, z) in rates(out) {
            let key = name.replace(' ', "_");
            metrics.insert(format!("{key}_observed"), observed);
            metrics.insert(format!("{key}_z"), z);
        }
        if let Some(v_max) = out.config.max_speed {
            metrics.insert(
                "max_speed_over_bound".into(),
                out.total.max_speed_seen / v_max,
            );
        }
        metrics
    }

    fn claims(out: &Output) -> Vec<Claim> {
        let mut claims = vec![Claim::new(
            "every observed rate (births, false alarms, detections, disappearances) lies within \
             4 standard errors of the model value",
            rates(out).iter().all(|r| r.4.abs() < 4.0),
        )];
        if let Some(v_max) = out.config.max_speed {
            claims.push(Claim::new(
                "no simulated target exceeds the speed bound",
                out.total.max_speed_seen <= v_max,
            ));
        }
        claims
    }

    fn present(out: &Output) -> Section {
        let (cfg, total) = (&out.config, &out.total);
        let mut table = Table::new(
            &format!(
                "Observed rates against the model, {} runs × {} scans",
                out.n_runs, cfg.n_scans
            ),
            &[
                "quantity",
                "model",
                "observed",
                "std. error",
                "z",
                "within 4 s.e.",
            ],
        );
        for (name, expected, observed, se, z) in rates(out) {
            table.row(vec![
                name.into(),
                fmt_num(expected),
                fmt_num(observed),
                fmt_num(se),
                format!("{z:+.2}"),
                if z.abs() < 4.0 { "yes" } else { "NO" }.into(),
            ]);
        }
        if let Some(v_max) = cfg.max_speed {
            table.row(vec![
                "largest speed / bound".into(),
                "≤ 1".into(),
                fmt_num(total.max_speed_seen / v_max),
                String::new(),
                String::new(),
                if total.max_speed_seen <= v_max {
                    "yes"
                } else {
                    "NO"
                }
                .into(),
            ]);
        }
        let scans = total.scans as f64;
        let empirical: Vec<(f64, f64)> = total
            .clutter_histogram
            .iter()
            .enumerate()
            .map(|(k, &n)| (k as f64, n as f64 / scans))
            .collect();
        let pmf: Vec<(f64, f64)> = (0..total.clutter_histogram.len())
            .map(|k| (k as f64, poisson_ln_pmf(k, cfg.clutter_per_scan).exp()))
            .collect();
        let chart = Chart::new(
            "False alarms per scan",
            "false alarms in a scan",
            "share of scans",
            vec![
                Series::new(
                    &format!("Poisson({})", cfg.clutter_per_scan),
                    pmf,
                    Style::Line,
                    0,
                ),
                Series::new("simulated", empirical, Style::Markers, 1),
            ],
        );
        Section {
            title: "Multi-target simulator of the MCMCDA model".into(),
            summary: "Births and false alarms are Poisson, detections and disappearances Bernoulli; \
                      each observed rate should lie within a few standard errors of the model value."
                .into(),
            tables: vec![table],
            figures: vec![Figure::new(
                "clutter",
                "Distribution of false alarms per scan against the Poisson model",
                chart,
            )],
        }
    }
}

/// (name, model value, observed mean, its standard error under the model, z-score)
fn rates(out: &Output) -> [(&'static str, f64, f64, f64, f64); 4] {
    let (cfg, total) = (&out.config, &out.total);
    let scans = total.scans as f64;
    let rows = [
        (
            "births per scan",
            cfg.births_per_scan,
            total.births as f64 / scans,
            (cfg.births_per_scan / scans).sqrt(),
        ),
        (
            "clutter per scan",
            cfg.clutter_per_scan,
            total.clutter as f64 / scans,
            (cfg.clutter_per_scan / scans).sqrt(),
        ),
        (
            "detection probability",
            cfg.p_detect,
            total.detections as f64 / total.target_scans as f64,
            (cfg.p_detect * (1.0 - cfg.p_detect) / total.target_scans as f64).sqrt(),
        ),
        (
            "disappearance probability",
            cfg.p_disappear,
            total.disappearances as f64 / total.transitions as f64,
            (cfg.p_disappear * (1.0 - cfg.p_disappear) / total.transitions as f64).sqrt(),
        ),
    ];
    rows.map(|(name, expected, observed, se)| {
        (name, expected, observed, se, (observed - expected) / se)
    })
}
