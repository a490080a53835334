//! `cargo xtask fetch-data NAME`: real data that may not be committed, fetched into a cache
//! outside the repository (`$TRACKING_DATA_DIR`, else `$XDG_CACHE_HOME/tracking-toolkit`, else
//! `~/.cache/tracking-toolkit`). Nothing in tests or CI needs it.
//!
//! `vtest`: OpenCV's pedestrian video `vtest.avi` (768 × 576, 10 fps), from Debian's
//! `opencv-doc` package (`apt-get download`, no root needed), decoded by Debian's ffmpeg into
//! PNG frames 300–794, named by their frame index in the video (`vtest_000300.png` …). The
//! earlier frames are kept back for outside checks and are never decoded here.
//!
//! `adsb`: the `traffic` package's wheel (2.13, MIT; its samples come from OpenSky and others,
//! under their own terms), downloaded with `pip download --no-deps`; only its quickstart
//! collection (`traffic/data/samples/collections/quickstart.json.gz`: 213 aircraft, 3 hours
//! at 1 s) is extracted, to `adsb/quickstart.json`, and the wheel is deleted. The wheel's
//! other collections are kept back for outside checks and are never extracted.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail, ensure};

use crate::Outcome;

/// The data sets `fetch-data` knows.
pub const NAMES: [&str; 2] = ["vtest", "adsb"];

/// The `traffic` release whose wheel carries the ADS-B quickstart collection.
pub const TRAFFIC_WHEEL: &str = "traffic==2.13";

/// The quickstart collection's file in the cache's `adsb` folder.
pub const ADSB_FILE: &str = "quickstart.json";

/// The frames of `vtest.avi` used for development.
pub const VTEST_FRAMES: (u32, u32) = (300, 794);

/// How many they are.
pub const VTEST_FRAME_COUNT: usize = (VTEST_FRAMES.1 - VTEST_FRAMES.0 + 1) as usize;

/// The cache folder.
pub fn cache_dir() -> Result<PathBuf> {
    if let Some(dir) = std::env::var_os("TRACKING_DATA_DIR") {
        return Ok(PathBuf::from(dir));
    }
    let base = match std::env::var_os("XDG_CACHE_HOME") {
        Some(dir) => PathBuf::from(dir),
        None => PathBuf::from(
            std::env::var_os("HOME").context("neither HOME nor XDG_CACHE_HOME is set")?,
        )
        .join(".cache"),
    };
    Ok(base.join("tracking-toolkit"))
}

/// Fetches `name` unless it is already in the cache.
#[expect(clippy::print_stdout, reason = "where the data went")]
pub fn run(name: &str) -> Outcome {
    match name {
        "vtest" => {
            let frames = fetch_vtest()?;
            println!(
                "vtest frames {}–{} in {}",
                VTEST_FRAMES.0,
                VTEST_FRAMES.1,
                frames.display()
            );
            Ok(true)
        }
        "adsb" => {
            let file = fetch_adsb()?;
            println!("ADS-B quickstart collection in {}", file.display());
            Ok(true)
        }
        other => bail!("no data set \"{other}\"; known: {}", NAMES.join(", ")),
    }
}

/// Runs a command in `dir`, failing with its stderr.
fn run_in(dir: &Path, program: &str, args: &[&str]) -> Result<()> {
    let output = Command::new(program)
        .args(args)
        .current_dir(dir)
        .output()
        .with_context(|| {
            format!(
                "cannot run {program} (Debian: apt-get install {})",
                package_of(program)
            )
        })?;
    ensure!(
        output.status.success(),
        "{program} {} failed: {}",
        args.join(" "),
        String::from_utf8_lossy(&output.stderr).trim()
    );
    Ok(())
}

#[expect(clippy::print_stderr, reason = "progress of a download")]
fn fetch_adsb() -> Result<PathBuf> {
    let root = cache_dir()?.join("adsb");
    let file = root.join(ADSB_FILE);
    if file.is_file() {
        return Ok(file);
    }
    std::fs::create_dir_all(&root).with_context(|| format!("cannot create {}", root.display()))?;
    eprintln!(
        "downloading the {TRAFFIC_WHEEL} wheel (≈ 28 MB) into {}",
        root.display()
    );
    run_in(
        &root,
        "python3",
        &[
            "-m",
            "pip",
            "download",
            "--no-deps",
            "--quiet",
            TRAFFIC_WHEEL,
            "-d",
            ".",
        ],
    )?;
    let wheel = std::fs::read_dir(&root)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|x| x == "whl"))
        .context("pip download left no wheel")?;
    // A wheel is a zip file; Python (which pip needs anyway) reads it and the gzip member.
    let script = format!(
        "import gzip, zipfile; z = zipfile.ZipFile({wheel:?}); \
         open({ADSB_FILE:?}, 'wb').write(gzip.decompress(z.read(\
         'traffic/data/samples/collections/quickstart.json.gz')))",
        wheel = wheel.display().to_string()
    );
    run_in(&root, "python3", &["-c", &script])?;
    std::fs::remove_file(&wheel)?;
    ensure!(
        file.is_file(),
        "the quickstart collection was not extracted"
    );
    Ok(file)
}

fn package_of(program: &str) -> &str {
    match program {
        "dpkg-deb" => "dpkg",
        "apt-get" => "apt",
        "python3" => "python3 python3-pip",
        other => other,
    }
}

#[expect(clippy::print_stderr, reason = "progress of a download")]
fn fetch_vtest() -> Result<PathBuf> {
    let root = cache_dir()?.join("vtest");
    let frames = root.join("frames");
    let (first, last) = VTEST_FRAMES;
    let expected = VTEST_FRAME_COUNT;
    if count_pngs(&frames) == expected {
        return Ok(frames);
    }
    std::fs::create_dir_all(&root).with_context(|| format!("cannot create {}", root.display()))?;
    let video = root.join("vtest.avi");
    if !video.is_file() {
        eprintln!(
            "downloading Debian's opencv-doc (≈ 96 MB) into {}",
            root.display()
        );
        run_in(&root, "apt-get", &["download", "opencv-doc"])?;
        let deb = std::fs::read_dir(&root)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .find(|p| p.extension().is_some_and(|x| x == "deb"))
            .context("apt-get download left no .deb")?;
        let member = "./usr/share/doc/opencv-doc/examples/data/vtest.avi";
        let script = format!(
            "dpkg-deb --fsys-tarfile '{}' | tar -xO '{member}' > vtest.avi",
            deb.display()
        );
        run_in(&root, "sh", &["-c", &script])?;
        std::fs::remove_file(&deb)?;
    }
    eprintln!("decoding frames {first}–{last} with ffmpeg");
    let _ = std::fs::remove_dir_all(&frames);
    std::fs::create_dir_all(&frames)?;
    let select = format!("select='between(n\\,{first}\\,{last})'");
    let start = first.to_string();
    let pattern = frames.join("vtest_%06d.png");
    let pattern = pattern.to_str().context("the cache path is not UTF-8")?;
    run_in(
        &root,
        "ffmpeg",
        &[
            "-loglevel",
            "error",
            "-i",
            "vtest.avi",
            "-vf",
            &select,
            "-fps_mode",
            "passthrough",
            "-start_number",
            &start,
            pattern,
        ],
    )?;
    let found = count_pngs(&frames);
    ensure!(
        found == expected,
        "ffmpeg wrote {found} frames, not {expected}"
    );
    Ok(frames)
}

fn count_pngs(dir: &Path) -> usize {
    std::fs::read_dir(dir).map_or(0, |entries| {
        entries
            .filter_map(Result::ok)
            .filter(|e| e.path().extension().is_some_and(|x| x == "png"))
            .count()
    })
}
