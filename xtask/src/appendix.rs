//! The report's appendix: for every scenario whose settings come from `cargo xtask tune`, the
//! settings file it read and every candidate the search scored, one row per setting and round.

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

use anyhow::{Context, Result, anyhow};
use scenarios::Table;

use crate::report::{html_escape, page, to_html, to_markdown};
use crate::scenario::RunResult;
use crate::tune::tuned_paths;

/// The page's file name.
pub const FILE: &str = "tuning.html";

/// One line of a grid CSV: (round, key, value, score, chosen).
fn parse_row(line: &str) -> Result<(String, String, String, String, bool)> {
    let bad = || anyhow!("bad grid line {line:?}");
    let (round, rest) = line.split_once(',').ok_or_else(bad)?;
    let (key, rest) = rest.split_once(',').ok_or_else(bad)?;
    let rest = rest.strip_prefix('"').ok_or_else(bad)?;
    let (value, rest) = rest.split_once("\",").ok_or_else(bad)?;
    let (score, chosen) = rest.split_once(',').ok_or_else(bad)?;
    Ok((
        round.into(),
        key.into(),
        value.into(),
        score.into(),
        chosen == "true",
    ))
}

/// The grid as a table: per (round, setting), every candidate with its score, ★ on the kept one.
fn grid_table(name: &str, csv: &str) -> Result<Table> {
    let mut table = Table::new(
        &format!("{name}: every candidate of the tuning search (★ kept)"),
        &["round", "setting", "candidates: score"],
    );
    let mut current: Option<(String, String, Vec<String>)> = None;
    for line in csv.lines().skip(1) {
        let (round, key, value, score, chosen) = parse_row(line)?;
        let cell = format!("{value}: {score}{}", if chosen { " ★" } else { "" });
        match &mut current {
            Some((r, k, cells)) if *r == round && *k == key => cells.push(cell),
            _ => {
                if let Some((r, k, cells)) = current.take() {
                    table.row(vec![r, k, cells.join("; ")]);
                }
                current = Some((round, key, vec![cell]));
            }
        }
    }
    if let Some((r, k, cells)) = current {
        table.row(vec![r, k, cells.join("; ")]);
    }
    Ok(table)
}

/// Writes the appendix page when any result read tuned settings; its entry goes into the
/// index and the Markdown. Returns the page's file name, if written.
pub fn write_page(
    out_dir: &Path,
    results: &[RunResult],
    index: &mut String,
    md: &mut String,
) -> Result<Option<String>> {
    let mut body = String::from(
        "<nav><a href=\"index.html\">← report index</a></nav>\n<h1>Appendix: tuning searches</h1>\n\
         <p>Each search ran on its scenario's tuning seeds only (<code>cargo xtask tune \
         NAME</code>; <code>--check</code> reproduces the committed files exactly).</p>\n",
    );
    let _ = write!(md, "# Appendix: tuning searches\n\n");
    let mut any = false;
    for r in results {
        let Some((settings, grid)) = tuned_paths(&r.scenario.file.params)? else {
            continue;
        };
        any = true;
        let name = &r.scenario.name;
        let read =
            |p: &Path| fs::read_to_string(p).with_context(|| format!("reading {}", p.display()));
        let (settings, grid) = (read(&settings)?, read(&grid)?);
        let table = grid_table(name, &grid)?;
        let _ = writeln!(
            body,
            "<h2 id=\"{name}\">{name}</h2>\n<pre>{}</pre>\n{}",
            html_escape(&settings),
            to_html(&table)
        );
        let _ = write!(
            md,
            "## {name}\n\n```toml\n{settings}```\n\n{}\n",
            to_markdown(&table)
        );
    }
    if !any {
        return Ok(None);
    }
    fs::write(out_dir.join(FILE), page("Appendix: tuning searches", &body))
        .with_context(|| format!("writing {FILE}"))?;
    let _ = writeln!(
        index,
        "<li><a href=\"{FILE}\">Appendix: tuning searches</a></li>"
    );
    Ok(Some(FILE.into()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_rows_group_by_round_and_setting() {
        let csv = "round,key,value,score,chosen\n1,a.x,\"1.0\",0.5,false\n1,a.x,\"2.0\",0.6,true\n\
                   1,b,\"[1, 2]\",0.7,true\n2,a.x,\"1.0\",0.5,false\n";
        let t = grid_table("s", csv).unwrap();
        let md = to_markdown(&t);
        assert!(md.contains("1.0: 0.5; 2.0: 0.6 ★"), "{md}");
        assert!(md.contains("[1, 2]: 0.7 ★"), "{md}");
        assert_eq!(md.matches("a.x").count(), 2, "{md}");
        assert!(grid_table("s", "h\nno commas").is_err());
    }
}
