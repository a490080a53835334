//! The sequence of the crate's 200-frame test (a textured sprite wandering over a cluttered
//! 320 × 240 background with ±8 levels of pixel noise), for docs/comparisons/
//! opencv_tracker_boosting.py:
//!
//! * `cargo run --release -p image-detector --example boosting_sequence -- write DIR [SEED]`
//!   writes `DIR/000000.png` … `DIR/000199.png` and `DIR/truth.txt` (frame, left, top, width,
//!   height); SEED (default 11, the test's) draws the background and the noise, so another seed
//!   gives a tuning sequence on the same path;
//! * `… -- track DIR` reads the PNGs and runs one `ImageDetector` on them as the test does
//!   (trained on frame 0's true box, then confirmed wherever it finds itself), printing
//!   `frame,left,top,width,height` per frame (empty fields when it found nothing) and, last,
//!   `# ms_per_frame MEDIAN MEAN` over frames 1.. (search and update only, not the PNG decode).
//!
//! The pictures come from `image_detector::scene`, as the test's do (same seed, same order of
//! draws).
#![expect(
    clippy::unwrap_used,
    clippy::print_stdout,
    reason = "an example on fixed inputs that prints its result"
)]

use std::sync::Arc;
use std::time::Instant;

use image_detector::scene::{background, noisy_frame as frame, wandering_path};
use image_detector::{DetectorConfig, FrameFeed, ImageDetectors};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use tracker_model::LocalDetector;

const SEED: u64 = 11;
const FRAMES: usize = 200;

fn write(dir: &str, seed: u64) {
    std::fs::create_dir_all(dir).unwrap();
    let path = wandering_path(FRAMES).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let bg = background(320, 240, &mut rng);
    let mut truth = String::new();
    for (k, b) in path.iter().enumerate() {
        frame(&bg, b, &mut rng)
            .save(format!("{dir}/{k:06}.png"))
            .unwrap();
        truth.push_str(&format!(
            "{k},{},{},{},{}\n",
            b.left, b.top, b.width, b.height
        ));
    }
    std::fs::write(format!("{dir}/truth.txt"), truth).unwrap();
}

fn track(dir: &str) {
    let path = wandering_path(FRAMES).unwrap();
    let load = |k: usize| image::open(format!("{dir}/{k:06}.png")).unwrap().to_rgb8();
    let feed = FrameFeed::new();
    let mut factory = ImageDetectors::new(DetectorConfig::default(), feed.clone(), SEED).unwrap();
    feed.set(0, Arc::new(load(0)));
    let mut d = factory.detector(0, &path[0]).unwrap();
    let mut last = path[0];
    let b = path[0];
    println!("0,{},{},{},{}", b.left, b.top, b.width, b.height);
    let mut ms = Vec::with_capacity(FRAMES);
    for k in 1..FRAMES {
        let image = Arc::new(load(k));
        let f = k as u32;
        let start = Instant::now();
        feed.set(f, image);
        let found = d.detect(f, &last);
        if let Some(b) = found {
            d.confirm(f, &b);
            last = b;
        }
        ms.push(1e3 * start.elapsed().as_secs_f64());
        match found {
            Some(b) => println!("{k},{},{},{},{}", b.left, b.top, b.width, b.height),
            None => println!("{k},,,,"),
        }
    }
    let mean = ms.iter().sum::<f64>() / ms.len() as f64;
    ms.sort_by(f64::total_cmp);
    println!("# ms_per_frame {:.4} {:.4}", ms[ms.len() / 2], mean);
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    match (args.get(1).map(String::as_str), args.get(2)) {
        (Some("write"), Some(dir)) => write(dir, args.get(3).map_or(SEED, |s| s.parse().unwrap())),
        (Some("track"), Some(dir)) => track(dir),
        _ => println!("usage: boosting_sequence write|track DIR"),
    }
}
