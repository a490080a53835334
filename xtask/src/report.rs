//! `cargo xtask report`: runs every scenario, prints each section's tables and writes
//! `index.html` (the regression status and a table of contents), one HTML page per paper
//! (tables and inline SVG plots) and `report.md` (everything on one page, plots linked as
//! files).

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

use anyhow::Context;
use scenarios::Table;

use crate::scenario::{self, RunResult, Verdict};
use crate::{Outcome, appendix, plot, real_video, screenshot};

/// A table as Markdown (also readable as plain text on a terminal).
pub fn to_markdown(table: &Table) -> String {
    let widths: Vec<usize> = (0..table.header.len())
        .map(|c| {
            table
                .rows
                .iter()
                .filter_map(|r| r.get(c))
                .chain(std::iter::once(&table.header[c]))
                .map(|s| s.chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    let line = |cells: &[String]| {
        let padded: Vec<String> = cells
            .iter()
            .zip(&widths)
            .map(|(c, w)| format!("{c:<w$}"))
            .collect();
        format!("| {} |\n", padded.join(" | "))
    };
    let mut out = format!("**{}**\n\n", table.caption);
    out += &line(&table.header);
    let rule: Vec<String> = widths.iter().map(|w| "-".repeat(*w)).collect();
    out += &line(&rule);
    for r in &table.rows {
        out += &line(r);
    }
    out
}

pub(crate) fn to_html(table: &Table) -> String {
    let esc = html_escape;
    let mut out = format!("<table>\n<caption>{}</caption>\n<tr>", esc(&table.caption));
    for h in &table.header {
        let _ = write!(out, "<th>{}</th>", esc(h));
    }
    out += "</tr>\n";
    for r in &table.rows {
        out += "<tr>";
        for c in r {
            let _ = write!(out, "<td>{}</td>", esc(c));
        }
        out += "</tr>\n";
    }
    out + "</table>\n"
}

pub(crate) fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The papers (and the foundations) the scenarios belong to, by pipeline-name prefix: the
/// report has one page per entry, in this order.
const PAPERS: [(&str, &str, &str); 11] = [
    (
        "kalman",
        "foundations",
        "Foundations: Kalman filtering and the multi-target simulator",
    ),
    (
        "mcmcda",
        "mcmcda",
        "Oh, Russell & Sastry 2009: Markov chain Monte Carlo data association",
    ),
    (
        "dmtim",
        "identity",
        "Oh, Hwang & Sastry 2008: distributed tracking with identity management",
    ),
    (
        "camnet",
        "camnet",
        "Meingast, Oh & Sastry 2007: camera-network localisation from object image tracks",
    ),
    (
        "audio",
        "audio",
        "Kushwaha et al. 2008: audio beamforming and bearing likelihoods",
    ),
    (
        "video",
        "video",
        "Kushwaha et al. 2008: video background subtraction and angle profiles",
    ),
    (
        "av-fusion",
        "av-fusion",
        "Kushwaha et al. 2008: audio-video fusion on a grid, tracked by MCMCDA",
    ),
    (
        "hmm",
        "hmm",
        "Huynh & Vu 2006: ground-target tracking with a hidden Markov model",
    ),
    (
        "gdt",
        "gdt",
        "Oh & Jung 2015: goal-directed recovery of trajectory gaps",
    ),
    (
        "phd",
        "phd",
        "Yoon et al. 2016: PHD filtering with global and local detectors",
    ),
    (
        "mot",
        "mot",
        "Evaluation and tracking of MOTChallenge files",
    ),
];

/// The (page slug, page title) of a pipeline.
fn paper_of(pipeline: &str) -> (&'static str, &'static str) {
    let (_, slug, title) = PAPERS
        .iter()
        .find(|(prefix, _, _)| pipeline.starts_with(prefix))
        .copied()
        .unwrap_or(PAPERS[0]);
    (slug, title)
}

/// `cargo xtask report`.
#[expect(
    clippy::print_stdout,
    reason = "the report's tables are printed on the terminal"
)]
pub fn run(out_dir: &Path, filter: Option<&str>, screenshots: bool) -> Outcome {
    let start = std::time::Instant::now();
    // The real-video page is not a scenario: `--filter real-video` asks for it alone.
    let with_real_video = filter.is_none_or(|f| real_video::FILTER.contains(f));
    let scenarios = match filter {
        Some(f) if real_video::FILTER.contains(f) => Vec::new(),
        _ => scenario::load_all(filter)?,
    };
    let results = scenario::run_all(scenarios);
    for r in &results {
        if let Ok(out) = &r.output {
            println!("\n## {}\n", out.section.title);
            for t in &out.section.tables {
                println!("{}", to_markdown(t));
            }
        }
    }
    println!("\n## Regression check\n");
    let verdicts = scenario::verdicts(&results, false)?;
    let ok = scenario::print_verdicts(&verdicts, false);
    let pages = write(out_dir, &results, &verdicts, with_real_video)?;
    println!(
        "\nreport written to {} ({} pages) and {}",
        out_dir.join("index.html").display(),
        pages.len(),
        out_dir.join("report.md").display()
    );
    if screenshots {
        screenshot::take(out_dir, &pages)?;
    }
    let failed = verdicts.iter().filter(|v| !v.passed()).count();
    println!(
        "report: {} scenarios, {} passed, {failed} failed; {} pages; {:.0} s in all",
        verdicts.len(),
        verdicts.len() - failed,
        pages.len(),
        start.elapsed().as_secs_f64()
    );
    Ok(ok)
}

const STYLE: &str = "body{font-family:sans-serif;max-width:1100px;margin:auto;padding:1em;color:#222}\
table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}\
td:first-child,th:first-child{text-align:left}th{background:#eee}caption{font-weight:bold;text-align:left;padding:4px 0}\
figure{margin:1em 0}figcaption{font-style:italic}.fail{color:#b00;font-weight:bold}.pass{color:#070}\
nav{margin:0.5em 0 1.5em;font-size:90%}";

pub(crate) fn page(title: &str, body: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{t}</title>\n<style>{STYLE}</style>\n</head><body>\n{body}</body></html>\n",
        t = html_escape(title)
    )
}

/// One scenario's section as (HTML, Markdown); SVG files are written beside.
fn section(out_dir: &Path, r: &RunResult) -> anyhow::Result<(String, String)> {
    let name = &r.scenario.name;
    let (mut html, mut md) = (String::new(), String::new());
    let out = match &r.output {
        Ok(out) => out,
        Err(err) => {
            let _ = write!(md, "## {name}\n\nFAILED: {err:#}\n\n");
            let _ = writeln!(
                html,
                "<h2 id=\"{name}\">{name}</h2>\n<p class=\"fail\">FAILED: {}</p>",
                html_escape(&format!("{err:#}"))
            );
            return Ok((html, md));
        }
    };
    let s = &out.section;
    let what = &r.scenario.file.description;
    let _ = write!(
        md,
        "## {} <a id=\"{name}\"></a>\n\nScenario `{name}`: {what} {}\n\n",
        s.title, s.summary
    );
    let _ = writeln!(
        html,
        "<h2 id=\"{name}\">{}</h2>\n<p>Scenario <code>{name}</code>: {} {}</p>",
        html_escape(&s.title),
        html_escape(what),
        html_escape(&s.summary)
    );
    for t in &s.tables {
        md += &to_markdown(t);
        md += "\n";
        html += &to_html(t);
    }
    for p in &s.figures {
        let svg = plot::render(&p.chart)?;
        let file = format!("{name}-{}.svg", p.name);
        fs::write(out_dir.join(&file), &svg).with_context(|| format!("writing {file}"))?;
        let _ = write!(md, "![{}]({file})\n\n*{}*\n\n", p.caption, p.caption);
        let _ = writeln!(
            html,
            "<figure>{svg}<figcaption>{}</figcaption></figure>",
            html_escape(&p.caption)
        );
    }
    Ok((html, md))
}

/// The status table: every scenario, pass or fail against its expected metrics and claims.
fn status_table(results: &[RunResult], verdicts: &[Verdict]) -> (String, String) {
    let mut table = Table::new(
        "Regression check: each scenario against fixtures/expected/ and its claims",
        &["scenario", "page", "status", "time (s)", "details"],
    );
    let mut html = String::from(
        "<table>\n<caption>Regression check: each scenario against <code>fixtures/expected/</code> and its claims</caption>\n<tr><th>scenario</th><th>page</th><th>status</th><th>time (s)</th><th>details</th></tr>\n",
    );
    for (r, v) in results.iter().zip(verdicts) {
        let (slug, title) = paper_of(&r.scenario.file.pipeline);
        let (status, class) = if v.passed() {
            ("pass", "pass")
        } else {
            ("FAIL", "fail")
        };
        let details = if v.passed() {
            v.summary.clone()
        } else {
            v.problems.join("; ")
        };
        let _ = writeln!(
            html,
            "<tr><td><a href=\"{slug}.html#{n}\">{n}</a></td><td>{}</td><td class=\"{class}\">{status}</td><td>{:.2}</td><td>{}</td></tr>",
            html_escape(title.split(':').next().unwrap_or(title)),
            v.seconds,
            html_escape(&details),
            n = v.name,
        );
        table.row(vec![
            format!("[{n}](#{n})", n = v.name),
            title.split(':').next().unwrap_or(title).to_string(),
            status.into(),
            format!("{:.2}", v.seconds),
            details,
        ]);
    }
    (html + "</table>\n", to_markdown(&table))
}

/// The headline table of one paper's scenarios, when any of them gives headlines.
fn headline_table(title: &str, members: &[&RunResult]) -> Option<Table> {
    let mut table = Table::new(
        &format!("Headline results: {title}"),
        &["scenario", "quantity", "paper", "ours", "peer"],
    );
    for r in members {
        let Ok(out) = &r.output else { continue };
        for h in &out.headlines {
            let dash = || "—".to_string();
            table.row(vec![
                r.scenario.name.clone(),
                h.quantity.clone(),
                h.paper.clone().unwrap_or_else(dash),
                h.ours.clone(),
                h.peer.clone().unwrap_or_else(dash),
            ]);
        }
    }
    (!table.rows.is_empty()).then_some(table)
}

/// Writes index.html, one HTML page per paper, report.md and the SVG files; returns the pages.
fn write(
    out_dir: &Path,
    results: &[RunResult],
    verdicts: &[Verdict],
    with_real_video: bool,
) -> anyhow::Result<Vec<String>> {
    fs::create_dir_all(out_dir).with_context(|| format!("creating {}", out_dir.display()))?;
    let intro = "Generated by <code>cargo xtask report</code> from the scenarios in <code>fixtures/scenarios/</code>.";
    let (status_html, status_md) = status_table(results, verdicts);
    let mut index = format!(
        "<h1>Tracking toolkit report</h1>\n<p>{intro}</p>\n{status_html}<h2>Contents</h2>\n<ul>\n"
    );
    let mut md = format!(
        "# Tracking toolkit report\n\nGenerated by `cargo xtask report` from the scenarios in `fixtures/scenarios/`.\n\n{status_md}\n"
    );
    let mut pages = vec!["index.html".to_string()];
    let mut headlines = String::new();
    for (_, slug, title) in PAPERS {
        let members: Vec<&RunResult> = results
            .iter()
            .filter(|r| paper_of(&r.scenario.file.pipeline).0 == slug)
            .collect();
        if members.is_empty() {
            continue;
        }
        pages.push(write_paper(
            out_dir,
            (slug, title),
            &members,
            &mut index,
            &mut md,
            &mut headlines,
        )?);
    }
    if with_real_video {
        pages.push(real_video::write_page(out_dir, &mut index, &mut md)?);
    }
    pages.extend(appendix::write_page(out_dir, results, &mut index, &mut md)?);
    index += "</ul>\n";
    if !headlines.is_empty() {
        index += "<h2>Headline results</h2>\n";
        index += &headlines;
    }
    fs::write(
        out_dir.join("index.html"),
        page("Tracking toolkit report", &index),
    )
    .context("writing index.html")?;
    fs::write(out_dir.join("report.md"), md).context("writing report.md")?;
    Ok(pages)
}

/// One paper's page (`slug.html`, returned): its headline table, its sections in HTML, their
/// entries in the index's contents, and their Markdown.
fn write_paper(
    out_dir: &Path,
    (slug, title): (&str, &str),
    members: &[&RunResult],
    index: &mut String,
    md: &mut String,
    headlines: &mut String,
) -> anyhow::Result<String> {
    let _ = write!(md, "# {title}\n\n");
    if let Some(table) = headline_table(title, members) {
        *headlines += &to_html(&table);
        *md += &to_markdown(&table);
        *md += "\n";
    }
    let file = format!("{slug}.html");
    let _ = write!(
        index,
        "<li><a href=\"{file}\">{}</a><ul>",
        html_escape(title)
    );
    let mut body = format!(
        "<nav><a href=\"index.html\">← report index</a></nav>\n<h1>{}</h1>\n<ul>\n",
        html_escape(title)
    );

    let mut sections = String::new();
    for r in members {
        let name = &r.scenario.name;
        let heading = r
            .output
            .as_ref()
            .map_or(name.as_str(), |o| o.section.title.as_str());
        let _ = write!(
            index,
            "<li><a href=\"{file}#{name}\">{}</a></li>",
            html_escape(heading)
        );
        let _ = writeln!(
            body,
            "<li><a href=\"#{name}\">{}</a></li>",
            html_escape(heading)
        );
        let (html, text) = section(out_dir, r)?;
        sections += &html;
        *md += &text;
    }
    *index += "</ul></li>\n";
    body += "</ul>\n";
    fs::write(out_dir.join(&file), page(title, &(body + &sections)))
        .with_context(|| format!("writing {file}"))?;
    Ok(file)
}
