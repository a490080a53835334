//! A synthetic scene for the detector's tests, examples and peer comparisons: a textured
//! person-like sprite over a cluttered background with pixel noise. Every draw comes from the
//! generator passed in, so a seed gives the same pictures in the tests, in
//! `examples/boosting_sequence.rs` and in docs/comparisons/opencv_tracker_boosting.py.

use image::{Rgb, RgbImage};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use tracker_model::BoundingBox;

use crate::error::Result;

/// A cluttered background: random coloured rectangles and stripes.
pub fn background(w: u32, h: u32, rng: &mut ChaCha8Rng) -> RgbImage {
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

/// A textured person-like sprite (head, striped shirt, trousers) drawn at box `b`.
pub fn draw_sprite(im: &mut RgbImage, b: &BoundingBox) {
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

/// One frame: the background with the sprite at its box, then ±8 levels of uniform pixel
/// noise.
pub fn noisy_frame(bg: &RgbImage, b: &BoundingBox, rng: &mut ChaCha8Rng) -> RgbImage {
    let mut im = bg.clone();
    draw_sprite(&mut im, b);
    for p in im.pixels_mut() {
        for c in &mut p.0 {
            *c = (f64::from(*c) + rng.random_range(-8.0..8.0)).clamp(0.0, 255.0) as u8;
        }
    }
    im
}

/// The sprite's 24 × 60 box along a slow wave (one pixel a frame to the right, ±25 pixels up
/// and down over about 190 frames) for `n` frames.
pub fn wandering_path(n: usize) -> Result<Vec<BoundingBox>> {
    (0..n)
        .map(|k| {
            let t = k as f64;
            Ok(BoundingBox::new(
                60.0 + t,
                90.0 + 25.0 * (t / 30.0).sin(),
                24.0,
                60.0,
            )?)
        })
        .collect()
}
