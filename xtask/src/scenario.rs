//! The scenario regression suite: `fixtures/scenarios/NAME.toml` names a pipeline, a seed, its
//! parameters and tolerances; `fixtures/expected/NAME.json` holds the metrics it must reproduce.

use std::collections::BTreeMap;
use std::fs;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, anyhow, bail};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use scenarios::{Clock, Env, Inputs, Metrics, Progress, Run};
use serde::Serialize;

use crate::{Outcome, read_file, workspace_root};

pub use xtask::scenario_file::ScenarioFile;

/// A scenario with its name (the file stem).
#[derive(Debug, Clone)]
pub struct Scenario {
    /// File stem, e.g. `kalman-cv-crossing`.
    pub name: String,
    /// Parsed contents.
    pub file: ScenarioFile,
}

/// Progress bars of the suite, one per scenario.
struct Bar(ProgressBar);

impl Progress for Bar {
    fn set_length(&self, units: u64) {
        self.0.set_length(units);
    }

    fn advance(&self, units: u64) {
        self.0.inc(units);
    }
}

/// Wall-clock time since the first reading.
struct WallClock(Instant);

impl Clock for WallClock {
    fn now_s(&self) -> f64 {
        self.0.elapsed().as_secs_f64()
    }
}

/// Input files named in scenario files are relative to the workspace root.
pub struct WorkspaceFiles;

impl Inputs for WorkspaceFiles {
    fn read_to_string(&self, path: &str) -> Result<String> {
        read_file(&workspace_root().join(path))
    }

    fn fetched(&self, name: &str, file: &str) -> Result<Option<String>> {
        let path = crate::data::cache_dir()?.join(name).join(file);
        if path.is_file() {
            read_file(&path).map(Some)
        } else {
            Ok(None)
        }
    }
}

/// A finished scenario run.
pub struct RunResult {
    /// The scenario.
    pub scenario: Scenario,
    /// Its output, or the error that stopped it.
    pub output: Result<Run>,
    /// Wall time.
    pub elapsed: Duration,
}

fn scenarios_dir() -> PathBuf {
    workspace_root().join("fixtures/scenarios")
}

/// `NAME.json`, or `NAME@DATA.json` for a run on the fetched real data set DATA.
fn expected_path(name: &str, data: Option<&str>) -> PathBuf {
    let file = match data {
        None => format!("{name}.json"),
        Some(data) => format!("{name}@{data}.json"),
    };
    workspace_root().join("fixtures/expected").join(file)
}

/// Loads every scenario file, sorted by name, optionally filtered; an error when none is left.
pub fn load_all(filter: Option<&str>) -> Result<Vec<Scenario>> {
    let dir = scenarios_dir();
    let mut out = Vec::new();
    for entry in fs::read_dir(&dir).with_context(|| format!("reading {}", dir.display()))? {
        let path = entry?.path();
        if path.extension().and_then(|e| e.to_str()) != Some("toml") {
            continue;
        }
        let name = path
            .file_stem()
            .and_then(|s| s.to_str())
            .ok_or_else(|| anyhow!("bad file name {}", path.display()))?
            .to_string();
        if filter.is_some_and(|f| !name.contains(f)) {
            continue;
        }
        out.push(Scenario {
            file: load_file(&path)?,
            name,
        });
    }
    out.sort_by(|a, b| a.name.cmp(&b.name));
    match filter {
        _ if !out.is_empty() => Ok(out),
        Some(f) => bail!("no scenario name contains \"{f}\" (see {})", dir.display()),
        None => bail!("no scenario files in {}", dir.display()),
    }
}

fn load_file(path: &Path) -> Result<ScenarioFile> {
    let text = fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    xtask::scenario_file::load_scenario(&text, &path.display().to_string())
}

/// Runs scenarios in parallel (each on its own seeded generator), returning results in name
/// order. A progress bar per scenario is drawn when stderr is a terminal; otherwise (a CI log,
/// a pipe) a line when each scenario finishes, so a long run is never silent.
#[expect(
    clippy::print_stderr,
    reason = "progress lines when stderr is not a terminal"
)]
pub fn run_all(scenarios: Vec<Scenario>) -> Vec<RunResult> {
    let terminal = std::io::stderr().is_terminal();
    let total = scenarios.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let multi = MultiProgress::with_draw_target(if terminal {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    });
    let style = ProgressStyle::with_template("{prefix:>28} {bar:30} {pos}/{len} {elapsed}")
        .unwrap_or_else(|_| ProgressStyle::default_bar());
    scenarios
        .into_par_iter()
        .map(|scenario| {
            let bar = Bar(multi.add(ProgressBar::new(1).with_style(style.clone())));
            bar.0.set_prefix(scenario.name.clone());
            let start = Instant::now();
            let file = &scenario.file;
            let output = scenarios::run_pipeline(
                &file.pipeline,
                &file.params,
                file.seed,
                &Env {
                    developer: &Terminal,
                    ..Env::new(&bar, &WorkspaceFiles, &WallClock(start))
                },
            )
            .with_context(|| format!("scenario {}", scenario.name));
            bar.0.finish_and_clear();
            if !terminal {
                let n = 1 + done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                eprintln!(
                    "[{n}/{total}] {} {:.1} s",
                    scenario.name,
                    start.elapsed().as_secs_f64()
                );
            }
            RunResult {
                scenario,
                output,
                elapsed: start.elapsed(),
            }
        })
        .collect()
}

/// Compares metrics with the expected file; returns the problems found (empty = pass).
fn compare(scenario: &Scenario, metrics: &Metrics, data: Option<&str>) -> Result<Vec<String>> {
    let path = expected_path(&scenario.name, data);
    let text = match fs::read_to_string(&path) {
        Ok(text) => text,
        Err(_) => {
            return Ok(vec![format!(
                "no {} yet; review the numbers and run `cargo xtask scenarios --bless`",
                path.display()
            )]);
        }
    };
    let expected: Metrics =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    let tol = &scenario.file.tolerance;
    let mut problems = Vec::new();
    for (key, &want) in &expected {
        let t = tol.metrics.get(key).copied().unwrap_or(tol.default);
        match metrics.get(key) {
            None => problems.push(format!("{key}: missing (expected {want})")),
            Some(&got) if !t.accepts(got, want) => problems.push(format!(
                "{key}: got {got}, expected {want} (abs {} + rel {})",
                t.abs, t.rel
            )),
            Some(_) => {}
        }
    }
    for key in metrics.keys().filter(|k| !expected.contains_key(*k)) {
        problems.push(format!(
            "{key}: new metric not in the expected file (bless to add it)"
        ));
    }
    Ok(problems)
}

/// Writes the expected file of a scenario (sorted keys, pretty JSON).
fn bless(scenario: &Scenario, metrics: &Metrics, data: Option<&str>) -> Result<()> {
    #[derive(Serialize)]
    #[serde(transparent)]
    struct Sorted<'a>(&'a Metrics);
    let path = expected_path(&scenario.name, data);
    if let Some(dir) = path.parent() {
        fs::create_dir_all(dir)?;
    }
    let text = serde_json::to_string_pretty(&Sorted(metrics))? + "\n";
    fs::write(&path, text).with_context(|| format!("writing {}", path.display()))
}

/// Writes every scenario's metrics (or its error) as JSON with sorted keys: the file the CI
/// determinism step compares across thread counts.
fn write_metrics(results: &[RunResult], path: &Path) -> Result<()> {
    let all: BTreeMap<&str, serde_json::Value> = results
        .iter()
        .map(|r| {
            let value = match &r.output {
                Ok(out) => serde_json::to_value(&out.metrics),
                Err(err) => Ok(serde_json::Value::String(format!("error: {err:#}"))),
            };
            value.map(|v| (r.scenario.name.as_str(), v))
        })
        .collect::<Result<_, _>>()?;
    fs::write(path, serde_json::to_string_pretty(&all)? + "\n")
        .with_context(|| format!("writing {}", path.display()))
}

/// How one scenario fared.
pub struct Verdict {
    /// The scenario's name.
    pub name: String,
    /// Wall time of its run.
    pub seconds: f64,
    /// What went wrong: an error, metrics off their expected values, claims that do not hold.
    /// Empty when it passed.
    pub problems: Vec<String>,
    /// A short account of a pass, e.g. "14 metrics match, 2 claims hold".
    pub summary: String,
}

impl Verdict {
    /// Whether the scenario passed.
    pub fn passed(&self) -> bool {
        self.problems.is_empty()
    }
}

/// Checks (or blesses) every result. A claim that does not hold fails its scenario even when
/// blessing.
pub fn verdicts(results: &[RunResult], bless_results: bool) -> Result<Vec<Verdict>> {
    let mut verdicts = Vec::with_capacity(results.len());
    for r in results {
        let (name, seconds) = (r.scenario.name.clone(), r.elapsed.as_secs_f64());
        let out = match &r.output {
            Ok(out) => out,
            Err(err) => {
                verdicts.push(Verdict {
                    name,
                    seconds,
                    problems: vec![format!("error: {err:#}")],
                    summary: String::new(),
                });
                continue;
            }
        };
        let mut problems: Vec<String> = out
            .failed_claims()
            .map(|c| format!("claim does not hold: {}", c.statement))
            .collect();
        let metrics = plural(out.metrics.len(), "metric", "metrics");
        let mut summary = if bless_results {
            bless(&r.scenario, &out.metrics, out.data.as_deref())?;
            format!("{metrics} written")
        } else {
            problems.extend(compare(&r.scenario, &out.metrics, out.data.as_deref())?);
            format!("{metrics} match")
        };
        if !out.claims.is_empty() {
            let claims = plural(out.claims.len(), "claim holds", "claims hold");
            summary = format!("{summary}, {claims}");
        }
        verdicts.push(Verdict {
            name,
            seconds,
            problems,
            summary,
        });
    }
    Ok(verdicts)
}

/// "1 scenario", "3 scenarios".
pub fn plural(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// Prints one line per scenario (and its problems); true when all passed.
#[expect(clippy::print_stdout, reason = "the suite reports on the terminal")]
pub fn print_verdicts(verdicts: &[Verdict], bless_results: bool) -> bool {
    for v in verdicts {
        let (name, secs) = (&v.name, v.seconds);
        if v.passed() {
            let word = if bless_results { "bless" } else { "ok" };
            println!("{word:<4} {name:<28} {secs:>7.2}s  {}", v.summary);
        } else {
            println!("FAIL {name:<28} {secs:>7.2}s");
            for p in &v.problems {
                println!("       {p}");
            }
        }
    }
    verdicts.iter().all(Verdict::passed)
}

/// `cargo xtask scenarios`.
#[expect(clippy::print_stdout, reason = "the suite reports on the terminal")]
pub fn run_suite(
    filter: Option<&str>,
    bless_results: bool,
    junit: Option<&Path>,
    metrics_out: Option<&Path>,
) -> Outcome {
    let scenarios = load_all(filter)?;
    let n = scenarios.len();
    let results = run_all(scenarios);
    if let Some(path) = metrics_out {
        write_metrics(&results, path)?;
    }
    let verdicts = verdicts(&results, bless_results)?;
    let ok = print_verdicts(&verdicts, bless_results);
    if let Some(path) = junit {
        fs::write(path, crate::junit::xml(&verdicts))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    let verdict = match (bless_results, ok) {
        (true, true) => "blessed",
        (true, false) => "blessed, with failures listed above",
        (false, true) => "passed",
        (false, false) => "run, with failures listed above",
    };
    println!("{} {verdict}", plural(n, "scenario", "scenarios"));
    Ok(ok)
}

/// Developer options from the environment variables of their names; their text to stderr.
pub struct Terminal;

impl scenarios::Developer for Terminal {
    fn option(&self, name: &str) -> Option<String> {
        std::env::var(name).ok()
    }

    #[expect(
        clippy::print_stderr,
        reason = "developer tools (tuning searches) report to the terminal as they measure"
    )]
    fn say(&self, text: &str) {
        eprintln!("{text}");
    }
}
