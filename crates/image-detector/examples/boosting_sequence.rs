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
//! The drawing code repeats `src/tests.rs`'s `background`, `draw_sprite`, `frame` and
//! `wandering_path` (the seed and the order of draws are the same, so the pictures are those of
//! the test).
#![expect(
    clippy::unwrap_used,
    clippy::print_stdout,
    reason = "an example on fixed inputs that prints its result"
)]

use std::sync::Arc;
use std::time::Instant;

use image::{Rgb, RgbImage};
use image_detector::{DetectorConfig, FrameFeed, ImageDetectors};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tracker_model::{BoundingBox, LocalDetector};

const SEED: u64 = 11;
const FRAMES: usize = 200;

fn background(w: u32, h: u32, rng: &mut ChaCha8Rng) -> RgbImage {
    let mut im = RgbImage::from_pixel(w, h, Rgb([110, 120, 100]));
    for _ in 0..120 {
        let (x0, y0) = (rng.random_range(0..w), rng.random_range(0..h));
        let (rw, rh) = (rng.random_range(4..30), rng.random_range(4..30));
        let c = Rgb([rng.random::<u8>(), rng.random::<u8>(), rng.random::<u8>()]);
        for y in y0..(y0 + rh).min(h) {
            for x in x0..(x0 + rw).min(w) {
                im.put_pixel(x, y, c);
            }
        }
    }
    im
}

fn draw_sprite(im: &mut RgbImage, b: &BoundingBox) {
    let (w, h) = (im.width() as i64, im.height() as i64);
    for y in b.top.floor() as i64..b.bottom().ceil() as i64 {
        for x in b.left.floor() as i64..b.right().ceil() as i64 {
            if x < 0 || y < 0 || x >= w || y >= h {
                continue;
            }
            let v = (y as f64 - b.top) / b.height;
            let u = (x as f64 - b.left) / b.width;
            let c = if v < 0.18 {
                if (u - 0.5).abs() < 0.25 {
                    Rgb([230, 190, 160])
                } else {
                    continue;
                }
            } else if v < 0.55 {
                if ((v * 20.0) as i64) % 2 == 0 {
                    Rgb([30, 60, 200])
                } else {
                    Rgb([240, 240, 60])
                }
            } else if (u - 0.5).abs() < 0.08 {
                continue;
            } else {
                Rgb([40, 30, 30])
            };
            im.put_pixel(x as u32, y as u32, c);
        }
    }
}

fn frame(bg: &RgbImage, b: &BoundingBox, rng: &mut ChaCha8Rng) -> RgbImage {
    let mut im = bg.clone();
    draw_sprite(&mut im, b);
    for p in im.pixels_mut() {
        for c in &mut p.0 {
            *c = (f64::from(*c) + rng.random_range(-8.0..8.0)).clamp(0.0, 255.0) as u8;
        }
    }
    im
}

fn wandering_path(n: usize) -> Vec<BoundingBox> {
    (0..n)
        .map(|k| {
            let t = k as f64;
            BoundingBox::new(60.0 + 1.0 * t, 90.0 + 25.0 * (t / 30.0).sin(), 24.0, 60.0).unwrap()
        })
        .collect()
}

fn write(dir: &str, seed: u64) {
    std::fs::create_dir_all(dir).unwrap();
    let path = wandering_path(FRAMES);
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
    let path = wandering_path(FRAMES);
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
