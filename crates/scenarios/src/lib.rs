//! # scenarios
//!
//! The experiments behind `cargo xtask scenarios` and `cargo xtask report`. Each pipeline reads
//! its parameters, simulates or loads its data, runs the trackers of the sibling crates and
//! scores them with eval-metrics. It comes in two parts:
//!
//! - [`Pipeline::compute`] takes the parameters, the scenario's seeded generator and an
//!   [`Env`] (progress and file inputs) and returns a typed result;
//! - [`Pipeline::metrics`] turns that result into the numbers the regression suite pins,
//!   [`Pipeline::present`] into a report [`Section`] of tables and [`Chart`]s, and
//!   [`Pipeline::claims`] into the orderings the report states, which fail the suite when
//!   they do not hold.
//!
//! This crate is a leaf: it combines its siblings and nothing imports it. It touches no file,
//! clock or terminal itself: xtask passes file contents in through [`Inputs`] and the time
//! through [`Clock`], draws progress through [`Progress`], renders the charts and writes the
//! report. Like xtask, and unlike the
//! library crates, it reports errors with `anyhow`: a pipeline's error is read by a person.
//!
//! The detection-file trackers that `cargo xtask track` and the MOT pipelines share, and the
//! MOTChallenge text conventions of `cargo xtask eval`, are the library crate `mot`.
//!
//! Running a scenario file as `cargo xtask scenarios` does, here the Kalman filter and smoother
//! on two crossing targets:
//!
//! ```
//! use scenarios::{Env, NoClock, NoInputs, NoProgress, run_pipeline};
//!
//! #[derive(serde::Deserialize)]
//! struct Scenario { pipeline: String, seed: u64, params: toml::Table }
//!
//! let text = include_str!("../../../fixtures/scenarios/kalman-cv-crossing.toml");
//! let scenario: Scenario = toml::from_str(text)?;
//! // No progress bars, no input files, no clock: xtask passes its own.
//! let env = Env::new(&NoProgress, &NoInputs, &NoClock);
//! let run = run_pipeline(&scenario.pipeline, &scenario.params, scenario.seed, &env)?;
//! print!("{:#?}", run.metrics);
//! assert!(run.metrics["position_rmse_smoothed"] < run.metrics["position_rmse_filtered"]);
//! assert_eq!(run.failed_claims().count(), 0); // the orderings the report states hold
//! # Ok::<(), anyhow::Error>(())
//! ```

use std::collections::BTreeMap;

use anyhow::{Context, Result, anyhow, bail};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::de::DeserializeOwned;

mod fresh;
mod pipelines;

pub use pipelines::adsb_radar::export_plot_files as export_adsb_radar_plots;
mod report;
pub mod seeds;
mod stats;
pub mod tune;

pub use report::{
    Axes, BAR_WIDTH, Chart, Figure, Section, Series, Style, Table, YAxis, fill, fmt_num,
};

/// Metric name → value, sorted so that expected files diff cleanly.
pub type Metrics = BTreeMap<String, f64>;

/// Progress of a long computation; called from worker threads.
pub trait Progress: Sync {
    /// The number of units the computation will report.
    fn set_length(&self, units: u64);
    /// `units` more are done.
    fn advance(&self, units: u64);
}

/// Progress that goes nowhere (tests, library use).
#[derive(Debug, Clone, Copy, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn set_length(&self, _: u64) {}
    fn advance(&self, _: u64) {}
}

/// Where a pipeline's input files come from. Paths are as written in the scenario file
/// (relative to the workspace root); the caller decides how to read them.
pub trait Inputs: Sync {
    /// The file's text; the error names the file.
    fn read_to_string(&self, path: &str) -> Result<String>;

    /// The text of `file` in the real data set `name` that `cargo xtask fetch-data NAME`
    /// keeps outside the repository, or `None` when it has not been fetched (a pipeline then
    /// runs on its stand-in and says so).
    fn fetched(&self, name: &str, file: &str) -> Result<Option<String>> {
        let _ = (name, file);
        Ok(None)
    }
}

/// No input files: every read is an error.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoInputs;

impl Inputs for NoInputs {
    fn read_to_string(&self, path: &str) -> Result<String> {
        bail!("no input files are available here (asked for {path})")
    }
}

/// A wall clock, for the timings a report shows (never for a metric the suite pins).
pub trait Clock: Sync {
    /// Seconds since an arbitrary fixed instant.
    fn now_s(&self) -> f64;
}

/// A clock that stands still: every timing reads 0.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoClock;

impl Clock for NoClock {
    fn now_s(&self) -> f64 {
        0.0
    }
}

/// The developer tools a pipeline may run besides its experiment (tuning searches,
/// diagnostics): which ones the caller asked for, and where their text goes. `cargo xtask
/// scenarios` reads each option from the environment variable of the same name and writes the
/// text to the terminal; the crate itself touches neither.
pub trait Developer: Sync {
    /// The value of the developer option `name` (e.g. `AV_FUSION_DIAG`), if it is set.
    fn option(&self, name: &str) -> Option<String>;
    /// One line (or table) of a developer tool's output, shown as it is measured.
    fn say(&self, text: &str);
}

/// No developer tools: no option is set and nothing is said (tests, library use, the suite).
#[derive(Debug, Clone, Copy, Default)]
pub struct NoDeveloper;

impl Developer for NoDeveloper {
    fn option(&self, _: &str) -> Option<String> {
        None
    }
    fn say(&self, _: &str) {}
}

/// What a pipeline may use besides its parameters and generator.
#[derive(Clone, Copy)]
pub struct Env<'a> {
    /// Progress reporting.
    pub progress: &'a dyn Progress,
    /// Input files named in the parameters.
    pub inputs: &'a dyn Inputs,
    /// Wall-clock time, for reported timings.
    pub clock: &'a dyn Clock,
    /// Developer options and their output.
    pub developer: &'a dyn Developer,
    /// The scenario's seed, for library calls that take a seed rather than a generator.
    pub seed: u64,
}

impl<'a> Env<'a> {
    /// An environment with seed 0 (`run_pipeline` sets the scenario's).
    pub fn new(progress: &'a dyn Progress, inputs: &'a dyn Inputs, clock: &'a dyn Clock) -> Self {
        Self {
            progress,
            inputs,
            clock,
            developer: &NoDeveloper,
            seed: 0,
        }
    }
}

/// One kind of experiment.
pub trait Pipeline {
    /// The scenario file's `[params]` table; unknown keys are errors.
    type Params: DeserializeOwned;
    /// What `compute` measured, before any formatting.
    type Output;

    /// Runs the experiment. Parallel work gives each task its own stream of `rng`
    /// (`set_stream`) so the output does not depend on the thread count.
    fn compute(params: &Self::Params, rng: &mut ChaCha8Rng, env: &Env<'_>) -> Result<Self::Output>;

    /// The numbers the regression suite compares with `fixtures/expected/`.
    fn metrics(output: &Self::Output) -> Metrics;

    /// The report section: tables and charts.
    fn present(output: &Self::Output) -> Section;

    /// The orderings and bounds that the report or the docs state about this result (e.g.
    /// "MCMCDA's F1 ≥ GNN's at every K"). The suite fails when one does not hold, whatever
    /// the expected file says, so a claim cannot silently turn false.
    fn claims(output: &Self::Output) -> Vec<Claim> {
        let _ = output;
        Vec::new()
    }

    /// The few numbers that sum the result up beside the paper's own and a peer's, for the
    /// report's front page.
    fn headlines(output: &Self::Output) -> Vec<Headline> {
        let _ = output;
        Vec::new()
    }

    /// The fetched real data set this output came from, if any (see [`Inputs::fetched`]).
    fn data_set(output: &Self::Output) -> Option<String> {
        let _ = output;
        None
    }

    /// Re-runs the searches behind the scenario's settings on its tuning seeds (`cargo xtask
    /// tune NAME`); `None` for a pipeline with nothing tuned.
    fn tune(params: &Self::Params, env: &Env<'_>) -> Result<Option<tune::Tuned>> {
        let _ = (params, env);
        Ok(None)
    }
}

/// One row of the report's headline table: a quantity, the paper's value, ours and a peer's.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Headline {
    /// What is measured, with its setting (e.g. "MMAE (px), 200 gaps, GDT").
    pub quantity: String,
    /// The paper's published value, where it reports one (with its own setting if different).
    pub paper: Option<String>,
    /// Ours, formatted (with its confidence interval where there is one).
    pub ours: String,
    /// A peer implementation's value on the same data, and which peer.
    pub peer: Option<String>,
}

impl Headline {
    /// A headline read from a run's metrics: `ours` is a metric key and the key of its 95 %
    /// CI half-width, if any; `peer` names the compared method and its keys the same way.
    /// A key the run lacks reads as NaN, which the report shows (it never hides a row).
    pub(crate) fn of_metrics(
        metrics: &Metrics,
        quantity: &str,
        ours: (&str, Option<&str>),
        peer: Option<(&str, &str, Option<&str>)>,
    ) -> Self {
        let value = |key: &str, ci: Option<&str>| {
            let get = |k: &str| metrics.get(k).copied().unwrap_or(f64::NAN);
            match ci {
                Some(ci) => format!("{} ± {}", fmt_num(get(key)), fmt_num(get(ci))),
                None => fmt_num(get(key)),
            }
        };
        Self {
            quantity: quantity.to_string(),
            paper: None,
            ours: value(ours.0, ours.1),
            peer: peer.map(|(name, key, ci)| format!("{name}: {}", value(key, ci))),
        }
    }
}

/// A statement about a result, and whether this run bears it out.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Claim {
    /// The statement, as the report prints it.
    pub statement: String,
    /// Whether it holds in this run.
    pub holds: bool,
}

impl Claim {
    /// A claim and its verdict.
    pub fn new(statement: impl Into<String>, holds: bool) -> Self {
        Self {
            statement: statement.into(),
            holds,
        }
    }
}

/// A finished pipeline run.
#[derive(Debug, Clone)]
pub struct Run {
    /// The metrics; every one is finite.
    pub metrics: Metrics,
    /// The report section; it ends with a table of the claims when there are any.
    pub section: Section,
    /// The claims checked on this run.
    pub claims: Vec<Claim>,
    /// The rows this run adds to the report's headline table.
    pub headlines: Vec<Headline>,
    /// The fetched real data set it ran on (`None`: the committed or generated inputs); the
    /// suite keeps the expected metrics of each apart.
    pub data: Option<String>,
}

impl Run {
    /// The claims that do not hold.
    pub fn failed_claims(&self) -> impl Iterator<Item = &Claim> {
        self.claims.iter().filter(|c| !c.holds)
    }
}

/// Whether a parameter is a standard deviation by its name (`*sigma*`, `*_std`, `std_*`).
fn is_sigma(key: &str) -> bool {
    key.contains("sigma") || key.ends_with("_std") || key.starts_with("std_") || key == "std"
}

/// Every σ-named parameter (and every number in an array or table under one) must be finite
/// and ≥ 0: pipelines square σ into a variance, so a negative one would act as its absolute
/// value.
fn check_sigmas(path: &str, value: &toml::Value, under_sigma: bool) -> Result<()> {
    match value {
        toml::Value::Float(v) if under_sigma && !(v.is_finite() && *v >= 0.0) => {
            bail!("params.{path} = {v}: a standard deviation must be finite and ≥ 0")
        }
        toml::Value::Integer(v) if under_sigma && *v < 0 => {
            bail!("params.{path} = {v}: a standard deviation must be ≥ 0")
        }
        toml::Value::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                check_sigmas(&format!("{path}[{i}]"), item, under_sigma)?;
            }
            Ok(())
        }
        toml::Value::Table(table) => {
            for (key, item) in table {
                check_sigmas(&format!("{path}.{key}"), item, under_sigma || is_sigma(key))?;
            }
            Ok(())
        }
        _ => Ok(()),
    }
}

/// The checks every pipeline's parameters get before they are read, whoever runs it: every
/// σ-named parameter (`*sigma*`, `*_std`, `std_*`, and every number under one) is finite and ≥ 0.
pub fn check_params(params: &toml::Table) -> Result<()> {
    for (key, value) in params {
        check_sigmas(key, value, is_sigma(key))?;
    }
    Ok(())
}

type RunFn = fn(&toml::Table, u64, &Env<'_>) -> Result<Run>;

/// The checks every pipeline's parameters get, then the parameters as the pipeline's type.
fn typed_params<P: Pipeline>(params: &toml::Table) -> Result<P::Params> {
    check_params(params)?;
    toml::Value::Table(params.clone())
        .try_into()
        .context("bad [params]")
}

fn run_typed<P: Pipeline>(params: &toml::Table, seed: u64, env: &Env<'_>) -> Result<Run> {
    let params = typed_params::<P>(params)?;
    let env = Env { seed, ..*env };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let output = P::compute(&params, &mut rng, &env)?;
    let metrics = P::metrics(&output);
    if let Some((key, value)) = metrics.iter().find(|(_, v)| !v.is_finite()) {
        bail!("metric {key} is not finite ({value})");
    }
    let claims = P::claims(&output);
    let mut section = P::present(&output);
    if !claims.is_empty() {
        let mut table = Table::new("Claims the suite checks on every run", &["claim", "holds"]);
        for c in &claims {
            table.row(vec![
                c.statement.clone(),
                if c.holds { "yes" } else { "NO" }.into(),
            ]);
        }
        section.tables.push(table);
    }
    Ok(Run {
        metrics,
        section,
        claims,
        headlines: P::headlines(&output),
        data: P::data_set(&output),
    })
}

type TuneFn = fn(&toml::Table, u64, &Env<'_>) -> Result<Option<tune::Tuned>>;

fn tune_typed<P: Pipeline>(
    params: &toml::Table,
    seed: u64,
    env: &Env<'_>,
) -> Result<Option<tune::Tuned>> {
    P::tune(&typed_params::<P>(params)?, &Env { seed, ..*env })
}

/// The pipelines whose settings come from a tuning search (`cargo xtask tune`).
const TUNERS: &[(&str, TuneFn)] = &[
    (
        "mot-realistic",
        tune_typed::<pipelines::mot_realistic::MotRealistic>,
    ),
    (
        "mot-box-trackers",
        tune_typed::<pipelines::mot_box_trackers::MotBoxTrackers>,
    ),
    ("av-fusion", tune_typed::<pipelines::av_fusion::AvFusion>),
];

/// Re-runs the tuning searches of pipeline `name` on `params` (its tuning seeds only): the
/// settings file and the grid of every scored candidate. An error for a pipeline that tunes
/// nothing.
pub fn tune_pipeline(
    name: &str,
    params: &toml::Table,
    seed: u64,
    env: &Env<'_>,
) -> Result<tune::Tuned> {
    let tune = registered(TUNERS, name).ok_or_else(|| {
        anyhow!(
            "pipeline {name:?} has no tuning search; tunable: {}",
            TUNERS
                .iter()
                .map(|(n, _)| *n)
                .collect::<Vec<_>>()
                .join(", ")
        )
    })?;
    tune(params, seed, env)?.ok_or_else(|| anyhow!("pipeline {name:?} returned no settings"))
}

/// Every pipeline by the name a scenario file gives it.
const PIPELINES: &[(&str, RunFn)] = &[
    ("adsb-radar", run_typed::<pipelines::adsb_radar::AdsbRadar>),
    ("audio-doa", run_typed::<pipelines::audio::AudioDoa>),
    ("av-fusion", run_typed::<pipelines::av_fusion::AvFusion>),
    (
        "dmtim-seven-radars",
        run_typed::<pipelines::dmtim::DmtimSevenRadars>,
    ),
    ("gdt-gaps", run_typed::<pipelines::gdt::GdtGaps>),
    ("hmm-tracking", run_typed::<pipelines::hmm::HmmTracking>),
    (
        "kalman-crossing",
        run_typed::<pipelines::kalman::KalmanCrossing>,
    ),
    ("mcmcda-batch", run_typed::<pipelines::mcmcda::Batch>),
    ("mcmcda-online", run_typed::<pipelines::mcmcda::Online>),
    ("mcmcda-sweep", run_typed::<pipelines::mcmcda::Sweep>),
    (
        "mot-box-trackers",
        run_typed::<pipelines::mot_box_trackers::MotBoxTrackers>,
    ),
    ("mot-eval", run_typed::<pipelines::mot_eval::MotEval>),
    ("mot-track", run_typed::<pipelines::mot_track::MotTrack>),
    (
        "mot-realistic",
        run_typed::<pipelines::mot_realistic::MotRealistic>,
    ),
    ("phd-images", run_typed::<pipelines::phd_images::PhdImages>),
    (
        "phd-pedestrians",
        run_typed::<pipelines::phd::PhdPedestrians>,
    ),
    (
        "simulator-poisson",
        run_typed::<pipelines::simulator::SimulatorPoisson>,
    ),
    (
        "camnet-localisation",
        run_typed::<pipelines::camnet::CamnetLocalisation>,
    ),
    ("video-mog", run_typed::<pipelines::video::VideoMog>),
];

/// The entry of `name` in a registry of pipelines by name.
fn registered<F: Copy>(registry: &[(&str, F)], name: &str) -> Option<F> {
    registry.iter().find(|(n, _)| *n == name).map(|(_, f)| *f)
}

/// Whether a pipeline of this name exists.
pub fn is_pipeline(name: &str) -> bool {
    PIPELINES.iter().any(|(n, _)| *n == name)
}

/// All pipeline names, for error messages.
pub fn pipeline_names() -> Vec<&'static str> {
    PIPELINES.iter().map(|(n, _)| *n).collect()
}

/// Runs the pipeline `name` on `params` with a generator seeded from `seed`.
pub fn run_pipeline(name: &str, params: &toml::Table, seed: u64, env: &Env<'_>) -> Result<Run> {
    let run = registered(PIPELINES, name).ok_or_else(|| {
        anyhow!(
            "unknown pipeline {name:?}; known: {}",
            pipeline_names().join(", ")
        )
    })?;
    run(params, seed, env)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn negative_sigmas_are_refused_by_the_pipelines_themselves() {
        // Not only by xtask's scenario-file loader: a library caller gets the same error.
        let env = Env::new(&NoProgress, &NoInputs, &NoClock);
        for bad in [
            "measurement_sigma = -1",
            "[sensor]\nbase_sigma = -0.5",
            "pixel_std = [1.0, nan]",
        ] {
            let params: toml::Table = toml::from_str(bad).expect("valid TOML");
            let err = run_pipeline("kalman-crossing", &params, 1, &env)
                .err()
                .map(|e| format!("{e:#}"))
                .unwrap_or_default();
            assert!(err.contains("standard deviation"), "{bad}: {err:?}");
        }
    }
}
