//! Scenario files and the fuzz entry points.
//!
//! Each `fuzz_*` function takes arbitrary bytes, runs one parser the way the command line
//! does and checks what must hold of its result; it panics only when such a property fails
//! (the fuzz targets call these, and a stable test replays the committed corpora through them).

use std::collections::BTreeMap;

use anyhow::{Context, Result, bail};
use serde::Deserialize;

/// One scenario file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioFile {
    /// Which pipeline runs it (see `scenarios::pipeline_names`).
    pub pipeline: String,
    /// Seed of the scenario's generator.
    pub seed: u64,
    /// One sentence on what the scenario pins.
    #[serde(default)]
    pub description: String,
    /// Pipeline parameters, read by the pipeline into its own config struct.
    #[serde(default)]
    pub params: toml::Table,
    /// How far each metric may move before it counts as a regression.
    #[serde(default)]
    pub tolerance: Tolerances,
}

/// Tolerances: a default and per-metric overrides.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tolerances {
    /// Applies to every metric without an override.
    #[serde(default)]
    pub default: Tolerance,
    /// Per-metric overrides.
    #[serde(default)]
    pub metrics: BTreeMap<String, Tolerance>,
}

/// |actual − expected| ≤ abs + rel·|expected|; both parts finite and ≥ 0 (checked when the
/// file is read: a negative part would make every comparison fail, or with the other part
/// large, quietly loosen it).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields, try_from = "RawTolerance")]
pub struct Tolerance {
    /// Absolute part.
    pub abs: f64,
    /// Relative part.
    pub rel: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTolerance {
    #[serde(default)]
    abs: f64,
    #[serde(default)]
    rel: f64,
}

impl TryFrom<RawTolerance> for Tolerance {
    type Error = String;

    fn try_from(raw: RawTolerance) -> Result<Self, String> {
        for (name, v) in [("abs", raw.abs), ("rel", raw.rel)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("tolerance {name} = {v} must be finite and ≥ 0"));
            }
        }
        Ok(Self {
            abs: raw.abs,
            rel: raw.rel,
        })
    }
}

impl Default for Tolerance {
    fn default() -> Self {
        // Same seed, same code: only libm differences across platforms should move a metric.
        Self {
            abs: 1e-12,
            rel: 1e-9,
        }
    }
}

impl Tolerance {
    /// Whether `actual` is close enough to `expected`.
    pub fn accepts(&self, actual: f64, expected: f64) -> bool {
        (actual - expected).abs() <= self.abs + self.rel * expected.abs()
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

/// Parses and checks a scenario file's text: known pipeline, tolerances ≥ 0, σ parameters ≥ 0.
/// Errors name the problem; the caller adds the file name.
pub fn parse_scenario(text: &str) -> Result<ScenarioFile> {
    let file: ScenarioFile = toml::from_str(text)?;
    if !scenarios::is_pipeline(&file.pipeline) {
        bail!(
            "unknown pipeline {:?}; known: {}",
            file.pipeline,
            scenarios::pipeline_names().join(", ")
        );
    }
    for (key, value) in &file.params {
        check_sigmas(key, value, is_sigma(key))?;
    }
    Ok(file)
}

/// Fuzz entry: the MOTChallenge reader. A file that parses formats back to text that parses
/// to the same rows, and its rows with ids ≥ 0 group into tracks or give an error.
pub fn fuzz_mot(data: &[u8]) {
    let Ok(file) = tracker_model::read_mot(data) else {
        return;
    };
    let text = tracker_model::format_mot(&file.rows);
    let again = tracker_model::parse_mot(text.as_bytes());
    assert_eq!(
        again.as_ref(),
        Ok(&file.rows),
        "format_mot did not round-trip"
    );
    let _ = tracker_model::TrackSet::from_mot_rows(&file.rows);
    // The command-line conventions on top (headers, empty files).
    let text = String::from_utf8_lossy(data);
    let _ = scenarios::mot::load_evaluation_pair((&text, "gt"), (&text, "pred"));
}

/// Fuzz entry: a scenario file (parsing and checks only; no pipeline runs).
pub fn fuzz_scenario_toml(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = parse_scenario(text);
    }
}

/// Fuzz entry: a `cargo xtask track` configuration. One that resolves prints as TOML that
/// loads back to the same configuration.
pub fn fuzz_track_config(data: &[u8]) {
    use scenarios::track::{TrackConfig, render_config};
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(config) = toml::from_str::<TrackConfig>(text) else {
        return;
    };
    let Ok(effective) = config.resolve(&[]) else {
        return;
    };
    let printed = render_config(&effective, None).expect("a resolved configuration prints");
    let back: TrackConfig = toml::from_str(&printed).expect("the printed configuration parses");
    let again = back
        .resolve(&[])
        .expect("the printed configuration resolves");
    assert_eq!(
        render_config(&again, None).expect("prints"),
        printed,
        "the configuration changed on the round trip"
    );
}

/// Fuzz entry: an HMM model as JSON (hmm-grid's `Hmm`, checked by its `try_from`). A model
/// that loads serialises and loads again.
pub fn fuzz_hmm_json(data: &[u8]) {
    let Ok(hmm) = serde_json::from_slice::<hmm_grid::Hmm>(data) else {
        return;
    };
    let json = serde_json::to_string(&hmm).expect("a checked model serialises");
    serde_json::from_str::<hmm_grid::Hmm>(&json).expect("a serialised model loads again");
}

/// A fuzz entry function.
pub type FuzzEntry = fn(&[u8]);

/// The fuzz targets: name (also the corpus directory under `fuzz/corpus/`) and entry.
pub const FUZZ_TARGETS: [(&str, FuzzEntry); 4] = [
    ("mot_reader", fuzz_mot),
    ("scenario_toml", fuzz_scenario_toml),
    ("track_config", fuzz_track_config),
    ("hmm_json", fuzz_hmm_json),
];

/// A short description of a load error with its file, for callers that read files.
pub fn load_scenario(text: &str, file: &str) -> Result<ScenarioFile> {
    parse_scenario(text).with_context(|| format!("parsing {file}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario(params: &str, tolerance: &str) -> Result<ScenarioFile> {
        parse_scenario(&format!(
            "pipeline = \"kalman-crossing\"\nseed = 1\n[params]\n{params}\n{tolerance}"
        ))
    }

    #[test]
    fn negative_tolerances_are_errors() {
        assert!(scenario("", "[tolerance.default]\nabs = 0.1\nrel = 0.0").is_ok());
        for bad in [
            "[tolerance.default]\nabs = -0.1",
            "[tolerance.default]\nrel = -1e-9",
            "[tolerance.metrics.mota]\nabs = -1.0",
            "[tolerance.default]\nabs = inf",
        ] {
            let err = format!("{:#}", scenario("", bad).unwrap_err());
            assert!(err.contains("must be finite and ≥ 0"), "{bad}: {err}");
        }
    }

    #[test]
    fn negative_sigmas_are_errors() {
        assert!(scenario("measurement_sigma = 3.0\nmeasurement_std = [1.0, 2]", "").is_ok());
        for (bad, path) in [
            ("measurement_sigma = -1.0", "params.measurement_sigma"),
            ("measurement_sigma = -1", "params.measurement_sigma"),
            ("measurement_std = [1.0, -2.0]", "params.measurement_std[1]"),
            (
                "[params.sensor]\nbase_sigma = -0.5",
                "params.sensor.base_sigma",
            ),
            ("prior_sigma_position = nan", "params.prior_sigma_position"),
        ] {
            let err = format!("{:#}", scenario(bad, "").unwrap_err());
            assert!(
                err.contains(path) && err.contains("standard deviation"),
                "{bad}: {err}"
            );
        }
        // Negative numbers under other names are the pipelines' business.
        assert!(scenario("offset = -3.0", "").is_ok());
    }

    #[test]
    fn every_committed_scenario_file_passes_the_checks() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/scenarios");
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            let text = std::fs::read_to_string(&path).unwrap();
            load_scenario(&text, &path.display().to_string()).unwrap();
        }
    }

    #[test]
    fn the_fuzz_corpora_replay_without_a_failure() {
        // Every input the fuzzers kept (and every crash they found, once fixed) runs through
        // the same entry functions on stable Rust.
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus");
        for (name, entry) in FUZZ_TARGETS {
            let dir = root.join(name);
            let mut n = 0;
            for file in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{dir:?}: {e}")) {
                let path = file.unwrap().path();
                entry(&std::fs::read(&path).unwrap());
                n += 1;
            }
            assert!(n > 0, "no corpus for {name}");
        }
    }
}
