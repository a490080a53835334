//! `cargo xtask fuzz [--seconds N] [--filter NAME]`: runs each cargo-fuzz target under `fuzz/`
//! for N seconds on the nightly toolchain, starting from the committed corpus, and prints the
//! executions and the outcome of each. New inputs go to `fuzz/target/corpus/NAME`, so the
//! committed corpus stays small; a crash leaves its input in `fuzz/artifacts/NAME`.

use std::fs;
use std::process::Command;

use anyhow::{Context, Result, bail};

use crate::{Outcome, workspace_root};

/// `cargo` through rustup, with the outer cargo's toolchain choice removed so that `+nightly`
/// applies.
fn cargo() -> Command {
    let mut cmd = Command::new("cargo");
    cmd.env_remove("RUSTUP_TOOLCHAIN")
        .env_remove("CARGO")
        .env_remove("RUSTC")
        .env_remove("RUSTDOC")
        .current_dir(workspace_root().join("fuzz"));
    cmd
}

/// Whether the nightly toolchain is installed.
fn has_nightly() -> bool {
    Command::new("rustup")
        .args(["toolchain", "list"])
        .output()
        .is_ok_and(|out| String::from_utf8_lossy(&out.stdout).contains("nightly"))
}

/// Installs cargo-fuzz unless `cargo fuzz` already runs.
#[expect(clippy::print_stderr, reason = "progress goes to the terminal")]
fn ensure_cargo_fuzz() -> Result<()> {
    let present = cargo()
        .args(["+nightly", "fuzz", "--version"])
        .output()
        .is_ok_and(|out| out.status.success());
    if !present {
        eprintln!("installing cargo-fuzz (cargo install cargo-fuzz)");
        let status = cargo()
            .args(["install", "cargo-fuzz"])
            .status()
            .context("could not run cargo install")?;
        if !status.success() {
            bail!("cargo install cargo-fuzz failed ({status})");
        }
    }
    Ok(())
}

/// libFuzzer's last "Done N runs in S second(s)" or "#N ..." status line: the executions.
fn executions(log: &str) -> Option<u64> {
    log.lines().rev().find_map(|line| {
        if let Some(rest) = line.strip_prefix("Done ") {
            return rest.split_whitespace().next()?.parse().ok();
        }
        let rest = line.strip_prefix('#')?;
        rest.split_whitespace().next()?.parse().ok()
    })
}

/// Runs the targets; false when one crashed.
#[expect(
    clippy::print_stdout,
    clippy::print_stderr,
    reason = "the fuzzing summary goes to the terminal"
)]
pub fn run(seconds: u64, filter: Option<&str>) -> Outcome {
    if !has_nightly() {
        eprintln!(
            "note: no nightly toolchain (`rustup toolchain list`); cargo-fuzz needs it. \
             The corpora are still replayed on stable by `cargo test -p xtask`."
        );
        return Ok(true);
    }
    ensure_cargo_fuzz()?;
    let targets: Vec<&str> = xtask::inputs::FUZZ_TARGETS
        .iter()
        .map(|(name, _)| *name)
        .filter(|name| filter.is_none_or(|f| name.contains(f)))
        .collect();
    if targets.is_empty() {
        bail!("no fuzz target name contains \"{}\"", filter.unwrap_or(""));
    }
    let fuzz_dir = workspace_root().join("fuzz");
    let mut all_ok = true;
    for name in targets {
        let work = fuzz_dir.join("target/corpus").join(name);
        fs::create_dir_all(&work).with_context(|| format!("cannot create {}", work.display()))?;
        eprintln!("==> fuzz {name} for {seconds} s");
        let out = cargo()
            .args(["+nightly", "fuzz", "run", name])
            .arg(&work)
            .arg(fuzz_dir.join("corpus").join(name))
            .arg("--")
            .arg(format!("-max_total_time={seconds}"))
            .args(["-rss_limit_mb=2048", "-timeout=10", "-print_final_stats=1"])
            .output()
            .with_context(|| format!("could not run cargo fuzz for {name}"))?;
        let log = String::from_utf8_lossy(&out.stderr);
        let log_path = fuzz_dir.join("target").join(format!("{name}.log"));
        fs::write(&log_path, log.as_bytes())
            .with_context(|| format!("cannot write {}", log_path.display()))?;
        let runs = executions(&log).map_or("?".to_string(), |n| n.to_string());
        if out.status.success() {
            println!("{name}: {runs} executions in {seconds} s, no crash");
        } else {
            all_ok = false;
            println!(
                "{name}: FAILED after {runs} executions ({}); see {} and fuzz/artifacts/{name}",
                out.status,
                log_path.display()
            );
        }
    }
    Ok(all_ok)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn executions_come_from_libfuzzers_last_status_line() {
        let log =
            "#2\tINITED cov: 10\n#1048576\tpulse  cov: 90\nDone 2345678 runs in 61 second(s)\n";
        assert_eq!(executions(log), Some(2_345_678));
        assert_eq!(executions("#512\tNEW cov: 3\n"), Some(512));
        assert_eq!(executions("nothing\n"), None);
    }
}
