//! `cargo xtask ci`: every check CI makes, in the order that fails fastest.

use std::process::Command;

use std::path::Path;

use anyhow::{Context, Result, bail};

use crate::{Outcome, scenario, workspace_root};

/// One cargo invocation of the CI run.
struct Step {
    name: &'static str,
    args: &'static [&'static str],
    env: Option<(&'static str, &'static str)>,
}

const STEPS: [Step; 5] = [
    Step {
        name: "format",
        args: &["fmt", "--all", "--", "--check"],
        env: None,
    },
    Step {
        name: "clippy",
        args: &[
            "clippy",
            "--workspace",
            "--all-targets",
            "--",
            "-D",
            "warnings",
        ],
        env: None,
    },
    // The README's test command.
    Step {
        name: "tests",
        args: &["test", "--workspace"],
        env: None,
    },
    Step {
        name: "docs",
        args: &["doc", "--workspace", "--no-deps"],
        env: Some(("RUSTDOCFLAGS", "-D warnings")),
    },
    Step {
        name: "bench build",
        args: &["bench", "--workspace", "--no-run"],
        env: None,
    },
];

/// Runs the steps, then the scenario suite; stops at the first failure.
#[expect(
    clippy::print_stderr,
    reason = "progress of the CI steps goes to the terminal"
)]
pub fn run(determinism_only: bool) -> Outcome {
    if determinism_only {
        determinism()?;
        return Ok(true);
    }
    for step in &STEPS {
        eprintln!("==> {}: cargo {}", step.name, step.args.join(" "));
        let mut cmd = Command::new(env!("CARGO"));
        cmd.args(step.args).current_dir(workspace_root());
        if let Some((key, value)) = step.env {
            cmd.env(key, value);
        }
        let status = cmd
            .status()
            .with_context(|| format!("could not start cargo for {}", step.name))?;
        if !status.success() {
            bail!("{} failed ({status})", step.name);
        }
    }
    eprintln!("==> determinism: the tracker CLIs and a few scenarios at 1 and 2 threads");
    determinism()?;
    for name in TUNED_SCENARIOS {
        // At one thread: the committed files were written at two, so this also shows the
        // search does not depend on the thread count.
        eprintln!("==> tuning: xtask tune {name} --check, at 1 thread");
        xtask_at("1", &["tune", name, "--check"], true)?;
    }
    eprintln!("==> scenarios");
    scenario::run_suite(None, false, None, None)
}

/// The scenarios whose settings file `cargo xtask tune NAME --check` must reproduce in CI.
/// `av-fusion-road`'s search (about 25 minutes on two cores, every candidate scored on 36
/// simulated runs) would not fit CI's budget; its `--check` is run by hand
/// (docs/av-fusion.md).
const TUNED_SCENARIOS: [&str; 2] = ["mot-realistic", "mot-box-trackers"];

/// The scenarios the determinism step runs (name filters): fast ones that use rayon.
const DETERMINISM_SCENARIOS: [&str; 3] = ["kalman", "simulator", "mot-track"];

/// Runs `cargo xtask` (this binary) with `args` at `threads` rayon threads. With `must_pass`
/// false only a failure to run counts (a scenario off its expected metrics is the suite's
/// business, later in CI; here only the written metrics matter).
fn xtask_at(threads: &str, args: &[&str], must_pass: bool) -> Result<()> {
    let exe = std::env::current_exe().context("cannot find the xtask binary")?;
    let out = Command::new(exe)
        .args(args)
        .env("RAYON_NUM_THREADS", threads)
        .current_dir(workspace_root())
        .output()
        .with_context(|| format!("could not run xtask {}", args.join(" ")))?;
    if must_pass && !out.status.success() {
        bail!(
            "xtask {} at {threads} thread(s) failed: {}{}",
            args.join(" "),
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    Ok(())
}

/// The bytes of `path`; the error names it.
fn bytes(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))
}

/// Every tracker on the walkers' detections and a few scenarios, at RAYON_NUM_THREADS = 1 and
/// 2: the written tracks and metrics must be byte-identical. Parallel work draws from one
/// generator stream per task and reduces in task order, so the thread count must not show.
#[expect(
    clippy::print_stderr,
    reason = "progress of the CI steps goes to the terminal"
)]
fn determinism() -> Result<()> {
    let dir = workspace_root().join("target/determinism");
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let mut outputs: Vec<(String, [std::path::PathBuf; 2])> = Vec::new();
    for tracker in ["mcmcda", "gnn", "phd"] {
        let files = ["1", "2"].map(|t| dir.join(format!("track-{tracker}-{t}threads.txt")));
        for (threads, file) in ["1", "2"].iter().zip(&files) {
            let out = file.display().to_string();
            xtask_at(
                threads,
                &[
                    "track",
                    "--tracker",
                    tracker,
                    "--input",
                    "fixtures/mot/walkers-dets.txt",
                    "--out",
                    &out,
                ],
                true,
            )?;
        }
        outputs.push((format!("track --tracker {tracker}"), files));
    }
    for filter in DETERMINISM_SCENARIOS {
        let files = ["1", "2"].map(|t| dir.join(format!("scenarios-{filter}-{t}threads.json")));
        for (threads, file) in ["1", "2"].iter().zip(&files) {
            let out = file.display().to_string();
            xtask_at(
                threads,
                &["scenarios", "--filter", filter, "--metrics-out", &out],
                false,
            )?;
        }
        outputs.push((format!("scenarios --filter {filter}"), files));
    }
    for (what, [one, two]) in &outputs {
        if bytes(one)? != bytes(two)? {
            bail!(
                "{what} differs between 1 and 2 threads: compare {} and {}",
                one.display(),
                two.display()
            );
        }
        eprintln!("    {what}: identical at 1 and 2 threads");
    }
    Ok(())
}
