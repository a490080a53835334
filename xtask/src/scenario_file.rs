//! Scenario files: what `cargo xtask scenarios` reads from `fixtures/scenarios/*.toml`, checked
//! when read (known pipeline, tolerances ≥ 0, σ parameters ≥ 0).

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
    scenarios::check_params(&file.params)?;
    Ok(file)
}

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
}
