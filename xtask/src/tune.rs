//! `cargo xtask tune NAME`: re-runs the tuning searches of scenario NAME on its tuning seeds
//! (`scenarios::tune_pipeline`) and writes the settings file its `tuned` parameter names, with
//! the grid of every scored candidate beside it (`…-grid.csv`); `--check` compares instead of
//! writing, so a changed search or a hand-edited file fails.

use std::fs;
use std::path::PathBuf;

use anyhow::{Context, Result, anyhow, bail};
use scenarios::{Env, NoClock, NoProgress};

use crate::scenario::{Terminal, WorkspaceFiles, load_all};
use crate::workspace_root;

/// The settings file a scenario reads (its `tuned` parameter) and the grid beside it.
pub fn tuned_paths(params: &toml::Table) -> Result<Option<(PathBuf, PathBuf)>> {
    let Some(tuned) = params.get("tuned") else {
        return Ok(None);
    };
    let tuned = tuned
        .as_str()
        .ok_or_else(|| anyhow!("params.tuned must be a path"))?;
    let Some(stem) = tuned.strip_suffix(".toml") else {
        bail!("params.tuned = {tuned:?} must name a .toml file");
    };
    let root = workspace_root();
    Ok(Some((
        root.join(tuned),
        root.join(format!("{stem}-grid.csv")),
    )))
}

/// Runs the search of the scenario whose file stem is `name` and writes (or, with `check`,
/// compares) its two files. `Ok(false)` when `check` finds a difference.
#[expect(clippy::print_stdout, reason = "the command's result")]
pub fn run(name: &str, check: bool) -> Result<bool> {
    let scenario = load_all(Some(name))?
        .into_iter()
        .find(|s| s.name == name)
        .ok_or_else(|| anyhow!("no scenario file fixtures/scenarios/{name}.toml"))?;
    let (settings_path, grid_path) = tuned_paths(&scenario.file.params)?
        .ok_or_else(|| anyhow!("{name} reads no tuned settings (it has no params.tuned)"))?;
    let env = Env {
        developer: &Terminal,
        ..Env::new(&NoProgress, &WorkspaceFiles, &NoClock)
    };
    let tuned = scenarios::tune_pipeline(
        &scenario.file.pipeline,
        &scenario.file.params,
        scenario.file.seed,
        &env,
    )?;
    let files = [(&settings_path, &tuned.settings), (&grid_path, &tuned.grid)];
    if check {
        let mut same = true;
        for (path, text) in files {
            let committed = fs::read_to_string(path).unwrap_or_default();
            if committed != *text {
                println!("{} differs from what the search writes", path.display());
                same = false;
            }
        }
        if same {
            println!("{name}: the committed settings and grid are reproduced exactly");
        }
        return Ok(same);
    }
    for (path, text) in files {
        if let Some(dir) = path.parent() {
            fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
        fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(true)
}
