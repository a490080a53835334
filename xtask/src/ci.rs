//! `cargo xtask ci`: every check CI makes, in the order that fails fastest.

use std::process::Command;

use anyhow::{Context, bail};

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
pub fn run() -> Outcome {
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
    eprintln!("==> scenarios");
    scenario::run_suite(None, false, None)
}
