//! `cargo xtask report --screenshots`: a PNG of every report page, taken with headless
//! Chromium, so that the pages get looked at. Skipped with a note when no browser is found.

use std::fs;
use std::path::Path;
use std::process::Command;

use anyhow::{Context, Result};

/// The tallest window taken, px.
const MAX_HEIGHT: usize = 16_000;

/// Browser executables tried in order.
const BROWSERS: [&str; 3] = ["chromium", "chromium-browser", "google-chrome"];

/// Writes `screenshots/PAGE.png` for each page (file names relative to `out_dir`).
#[expect(
    clippy::print_stderr,
    reason = "where the screenshots went, or why none were taken"
)]
pub fn take(out_dir: &Path, pages: &[String]) -> Result<()> {
    let Some(browser) = BROWSERS.iter().find(|b| {
        Command::new(b)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    }) else {
        eprintln!(
            "note: no chromium on the PATH, so no screenshots (Debian: apt-get install chromium)"
        );
        return Ok(());
    };
    let dir = out_dir.join("screenshots");
    fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let out_dir = fs::canonicalize(out_dir)?;
    for page in pages {
        let html = fs::read_to_string(out_dir.join(page))?;
        // A tall enough window for the whole page: the screenshot is of the window, and a
        // short estimate cuts off the last figure (long summaries and wrapped table cells are
        // not counted), so half as much again; a white margin at the bottom costs nothing.
        let content =
            400 + 560 * html.matches("<figure>").count() + 26 * html.matches("<tr>").count();
        let height = content * 3 / 2;
        // Only the unpadded estimate says the page is longer than the window (the padding
        // made the note fire on pages that fitted).
        if content > MAX_HEIGHT {
            eprintln!(
                "note: {page} is about {content} px long; its screenshot shows the first \
                 {MAX_HEIGHT} px"
            );
        }
        let png = dir.join(page.replace(".html", ".png"));
        let status = Command::new(browser)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--hide-scrollbars",
                // No network: the machine's is closed, and every attempt costs a timeout.
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--no-first-run",
                &format!("--window-size=1200,{}", height.min(MAX_HEIGHT)),
                &format!("--screenshot={}", png.display()),
            ])
            .arg(format!("file://{}", out_dir.join(page).display()))
            .output()
            .with_context(|| format!("running {browser}"))?;
        if !status.status.success() {
            anyhow::bail!(
                "{browser} failed on {page}: {}",
                String::from_utf8_lossy(&status.stderr)
            );
        }
    }
    eprintln!("screenshots of {} pages in {}", pages.len(), dir.display());
    Ok(())
}
