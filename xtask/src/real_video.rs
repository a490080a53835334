//! The report's real-video page: the review's camera pipeline (background mixture with
//! shadows, blobs as detections; `mot::video`) and the trackers on frames 300-794 of OpenCV's
//! `vtest.avi` when `cargo xtask fetch-data vtest` has put them in the cache, else on a
//! stand-in the project renders (people-like sprites walking over clutter, sensors-video's
//! `SpriteRenderer`). The page says which it ran on. There is no ground truth for `vtest.avi`,
//! so identity switches, MOTA and IDF1 are against offline MCMCDA's output.

use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use eval_metrics::{EvalConfig, MatchConfig, evaluate};
use mot::frames::FusedSettings;
use mot::track::{TrackConfig, TrackerKind, track_detections, track_detections_with_frames};
use mot::video::{VideoDetectorConfig, detect_folder, write_overlay_frames};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use scenarios::{Table, fmt_num};
use sensors_video::io::{FrameFolder, write_image};
use sensors_video::{SpriteConfig, SpriteRenderer};
use tracker_model::{BoundingBox, Track, TrackSet};

use crate::data;
use crate::report::{html_escape, page, to_html, to_markdown};

/// What the page shows: where the frames came from, the table, and overlay images (file name
/// in the report folder, caption).
pub struct RealVideo {
    /// One sentence on the source of the frames.
    pub source: String,
    /// Tracks, their lengths, and scores against offline MCMCDA.
    pub table: Table,
    /// Overlay PNGs written into the report folder, with captions.
    pub overlays: Vec<(String, String)>,
}

/// The trackers of the table, by name: the fused PHD is `--tracker phd --video`.
const TRACKERS: [(&str, Option<TrackerKind>); 4] = [
    ("offline MCMCDA (the reference)", Some(TrackerKind::Mcmcda)),
    ("GNN", Some(TrackerKind::Gnn)),
    ("PHD alone", Some(TrackerKind::Phd)),
    ("PHD fused with image local detectors", None),
];

/// The page's name, which `cargo xtask report --filter` matches.
pub const FILTER: &str = "real-video";

/// The real-video page (`real-video.html`, returned), its entry in the index and its
/// Markdown.
pub fn write_page(out_dir: &Path, index: &mut String, md: &mut String) -> Result<String> {
    let title = "Real video: the camera pipeline and the trackers";
    let video = run(out_dir)?;
    let mut body = format!(
        "<p><a href=\"index.html\">← report index</a></p>\n<h1>{t}</h1>\n<p>Ran on {s}. \
         Detections: sensors-video's background mixture with shadows, cleaned, blobs of 300 px or \
         more (<code>cargo xtask track --video</code>). No ground truth exists for these frames, \
         so the scores are against offline MCMCDA's output, a pseudo-truth that favours trackers \
         whose boxes are the blobs themselves (docs/image-detector.md).</p>\n",
        t = html_escape(title),
        s = html_escape(&video.source)
    );
    body += &to_html(&video.table);
    let _ = write!(
        md,
        "# {title}\n\nRan on {}.\n\n{}\n",
        video.source,
        to_markdown(&video.table)
    );
    for (file, caption) in &video.overlays {
        let _ = writeln!(
            body,
            "<figure><img src=\"{file}\" width=\"768\"><figcaption>{}</figcaption></figure>",
            html_escape(caption)
        );
        let _ = writeln!(md, "![{caption}]({file})\n");
    }
    let _ = writeln!(
        index,
        "<li><a href=\"real-video.html\">{}</a></li>",
        html_escape(title)
    );
    fs::write(out_dir.join("real-video.html"), page(title, &body))
        .context("writing real-video.html")?;
    Ok("real-video.html".to_string())
}

/// Runs the pipeline and writes the overlays into `out_dir`.
fn run(out_dir: &Path) -> Result<RealVideo> {
    run_with_cache(out_dir, &data::cache_dir()?)
}

/// [`run`] with the data cache at `cache`.
#[expect(clippy::print_stderr, reason = "progress of a minute-long section")]
fn run_with_cache(out_dir: &Path, cache: &Path) -> Result<RealVideo> {
    let (dir, source) = frames_dir(out_dir, cache)?;
    eprintln!("real video: {source}");
    let folder = FrameFolder::open(&dir)?;
    let rows = detect_folder(&folder, &VideoDetectorConfig::default(), &mut |_| {})?;
    let settings = TrackConfig::default();
    let fused = FusedSettings::default();
    let mut outputs = Vec::new();
    for (name, tracker) in TRACKERS {
        let set = match tracker {
            Some(tracker) => track_detections(tracker, &rows, &settings, 0)?,
            None => {
                let frames = Some((dir.as_path(), &fused));
                track_detections_with_frames(TrackerKind::Phd, &rows, &settings, 0, frames)?.0
            }
        };
        outputs.push((name, set));
    }
    let table = score_table(&outputs, rows.len(), folder.len())?;
    let overlays = write_overlays(out_dir, &folder, &outputs[2..])?;
    Ok(RealVideo {
        source,
        table,
        overlays,
    })
}

/// The cached `vtest` frames, or the stand-in rendered into `out_dir/standin-frames`.
fn frames_dir(out_dir: &Path, cache: &Path) -> Result<(PathBuf, String)> {
    let cached = cache.join("vtest").join("frames");
    if FrameFolder::open(&cached).is_ok_and(|f| f.len() == data::VTEST_FRAME_COUNT) {
        return Ok((
            cached,
            "OpenCV's vtest.avi (768 × 576), frames 300-794, from `cargo xtask fetch-data vtest`"
                .into(),
        ));
    }
    let dir = out_dir.join("standin-frames");
    render_standin(&dir)?;
    Ok((
        dir,
        "a STAND-IN rendered by the project (120 frames, 320 × 240, five sprites walking over \
         clutter): run `cargo xtask fetch-data vtest` for the real video"
            .into(),
    ))
}

/// Five sprites crossing a 320 × 240 scene of clutter in straight lines, 120 frames.
fn render_standin(dir: &Path) -> Result<()> {
    fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut rng = ChaCha8Rng::seed_from_u64(2026);
    let config = SpriteConfig {
        width: 320,
        height: 240,
        ..SpriteConfig::default()
    };
    let renderer = SpriteRenderer::new(config, &mut rng)?;
    for f in 1..=120u32 {
        let t = f64::from(f);
        let people: Vec<(u64, BoundingBox)> = (0..5u64)
            .filter_map(|k| {
                let kf = k as f64;
                let x = if k % 2 == 0 {
                    -20.0 + (1.5 + 0.3 * kf) * t
                } else {
                    330.0 - (1.2 + 0.2 * kf) * t
                };
                BoundingBox::new(x, 60.0 + 30.0 * kf, 18.0, 44.0)
                    .ok()
                    .map(|b| (k + 1, b))
            })
            .collect();
        let frame = renderer.render(f, &people, &mut rng)?;
        write_image(&frame, &dir.join(format!("{f:06}.png")))?;
    }
    Ok(())
}

/// Tracks, median length, and IDSW / MOTA / IDF1 against the first tracker's output.
fn score_table(outputs: &[(&str, TrackSet)], detections: usize, frames: usize) -> Result<Table> {
    let mut table = Table::new(
        &format!(
            "{detections} detections in {frames} frames: tracks, their lengths, and scores \
             against offline MCMCDA's output (IoU ≥ 0.5)"
        ),
        &[
            "tracker",
            "tracks",
            "median boxes per track",
            "IDSW",
            "MOTA",
            "IDF1",
        ],
    );
    let reference = &outputs[0].1;
    let config = EvalConfig {
        matching: MatchConfig::iou(0.5),
    };
    for (k, (name, set)) in outputs.iter().enumerate() {
        let mut lengths: Vec<usize> = set.tracks().iter().map(Track::len).collect();
        lengths.sort_unstable();
        let n = lengths.len();
        let median = match n {
            0 => 0.0,
            _ if n % 2 == 1 => lengths[n / 2] as f64,
            _ => (lengths[n / 2 - 1] + lengths[n / 2]) as f64 / 2.0,
        };
        let mut row = vec![(*name).to_string(), set.len().to_string(), fmt_num(median)];
        if k == 0 {
            row.extend(["—".to_string(), "—".to_string(), "—".to_string()]);
        } else {
            let report = evaluate(reference, set, &config)?;
            row.extend([
                report.clear.id_switches.to_string(),
                fmt_num(report.clear.mota),
                fmt_num(report.identity.idf1),
            ]);
        }
        table.row(row);
    }
    Ok(table)
}

/// Three frames (a quarter, a half and three quarters in) of each tracker in `outputs`, with
/// its tracks drawn, as PNG files in `out_dir/real-video-K/`.
fn write_overlays(
    out_dir: &Path,
    folder: &FrameFolder,
    outputs: &[(&str, TrackSet)],
) -> Result<Vec<(String, String)>> {
    let frames: Vec<u32> = folder.frames().collect();
    let picks = [1, 2, 3].map(|q| frames[q * (frames.len() - 1) / 4]);
    let mut written = Vec::new();
    for (k, (name, set)) in outputs.iter().enumerate() {
        let sub = format!("real-video-{k}");
        write_overlay_frames(folder, set, &out_dir.join(&sub), &picks, &mut |_| {})?;
        for frame in picks {
            let shown = set.tracks().iter().filter(|t| t.at(frame).is_some());
            let caption = format!("{name}, frame {frame}: {} tracks", shown.count());
            written.push((format!("{sub}/{frame:06}.png"), caption));
        }
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_the_cache_the_page_runs_on_the_stand_in_and_says_so() {
        let root = std::env::temp_dir().join(format!("xtask-real-video-{}", std::process::id()));
        let (cache, out) = (root.join("cache"), root.join("report"));
        fs::create_dir_all(&cache).unwrap();
        fs::create_dir_all(&out).unwrap();
        let video = run_with_cache(&out, &cache).unwrap();
        assert!(video.source.contains("STAND-IN"), "{}", video.source);
        assert_eq!(video.table.rows.len(), TRACKERS.len());
        // Five sprites cross the scene: every tracker finds some, none a hundred.
        for row in &video.table.rows {
            let tracks: usize = row[1].parse().unwrap();
            assert!((3..100).contains(&tracks), "{row:?}");
        }
        assert_eq!(video.overlays.len(), 6);
        for (file, _) in &video.overlays {
            assert!(out.join(file).is_file(), "{file}");
        }
        fs::remove_dir_all(&root).unwrap();
    }
}
