//! The crate's rule: pipelines get files, the clock, developer options and the terminal only
//! through `Env` (xtask supplies them), so the crate's sources name no file system, process
//! environment, clock or print macro. This reads every source file and fails on one that does.

use std::path::Path;

/// What the sources may not name, with why.
const FORBIDDEN: [(&str, &str); 14] = [
    ("std::fs", "files come through Env's Inputs"),
    ("fs::", "files come through Env's Inputs"),
    ("File::", "files come through Env's Inputs"),
    ("std::env", "options come through Env's Developer"),
    ("env::var", "options come through Env's Developer"),
    ("println!", "text goes to the report or Env's Developer"),
    ("eprintln!", "text goes to the report or Env's Developer"),
    ("print!", "text goes to the report or Env's Developer"),
    ("eprint!", "text goes to the report or Env's Developer"),
    ("dbg!", "text goes to the report or Env's Developer"),
    ("Instant::now", "time comes through Env's Clock"),
    ("SystemTime", "time comes through Env's Clock"),
    ("io::stdout", "text goes to the report or Env's Developer"),
    ("io::stderr", "text goes to the report or Env's Developer"),
];

/// Whether a line of code names something forbidden, including `fs` or `env` imported from
/// a `use std::{…}` group.
fn forbidden(code: &str) -> Option<(&'static str, &'static str)> {
    if let Some(&found) = FORBIDDEN.iter().find(|(name, _)| code.contains(name)) {
        return Some(found);
    }
    let grouped = code.contains("use std::{")
        && code
            .split(|c: char| !c.is_alphanumeric() && c != '_')
            .any(|word| word == "fs" || word == "env");
    grouped.then_some((
        "fs or env in a use std::{..} group",
        "files and options come through Env",
    ))
}

fn sources(dir: &Path, out: &mut Vec<std::path::PathBuf>) -> std::io::Result<()> {
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        if path.is_dir() {
            sources(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    Ok(())
}

#[test]
fn the_sources_touch_no_file_environment_clock_or_terminal() {
    let mut files = Vec::new();
    sources(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("src"),
        &mut files,
    )
    .unwrap();
    assert!(files.len() > 10, "found only {} source files", files.len());
    let mut found = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        for (n, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            if let Some((name, why)) = forbidden(code) {
                found.push(format!("{}:{}: {name} ({why})", file.display(), n + 1));
            }
        }
    }
    assert!(found.is_empty(), "{}", found.join("\n"));
}

#[test]
fn the_check_finds_what_it_forbids() {
    // The check itself can fail: a line naming the file system is caught, a comment is not.
    let caught = |line: &str| forbidden(line.split("//").next().unwrap_or("")).is_some();
    assert!(caught("let t = std::fs::read_to_string(p)?;"));
    assert!(caught("    eprintln!(\"{x}\");"));
    assert!(caught("let v = std::env::var(\"X\");"));
    assert!(caught("use std::{collections::BTreeMap, fs};"));
    assert!(caught("let mut out = std::io::stderr();"));
    assert!(!caught("use std::{collections::BTreeMap, fmt};"));
    assert!(!caught("// std::fs is for xtask"));
}
