//! Writes a few rendered frames (sensors-video's people-like sprites) as PNG and this crate's
//! HOG descriptor of each whole frame as text, for docs/comparisons/opencv_hog.py.
//!
//! `cargo run -p image-detector --example hog_dump -- /tmp/hog_cmp`
//!
//! Descriptor order: blocks row by row (by outer, bx inner); inside a block, cells (0,0),
//! (1,0), (0,1), (1,1) as (x, y); 9 bins per cell.
#![expect(clippy::unwrap_used, reason = "an example on fixed inputs")]

use std::io::Write;

use image::RgbImage;
use image_detector::{BlockGrid, Plane};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use sensors_video::{SpriteConfig, SpriteRenderer};
use tracker_model::BoundingBox;

fn main() {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "/tmp/hog_cmp".to_string());
    std::fs::create_dir_all(&dir).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let renderer = SpriteRenderer::new(SpriteConfig::default(), &mut rng).unwrap();
    for k in 0..3u32 {
        let people: Vec<(u64, BoundingBox)> = (0..5u64)
            .map(|i| {
                let x = 20.0 + 60.0 * i as f64 + 3.0 * f64::from(k);
                let h = 50.0 + 10.0 * i as f64;
                (i, BoundingBox::new(x, 200.0 - h, 0.4 * h, h).unwrap())
            })
            .collect();
        let frame = renderer.render(k * 10, &people, &mut rng).unwrap();
        let (w, h) = (frame.width() as u32, frame.height() as u32);
        let image = RgbImage::from_raw(w, h, frame.into_data()).unwrap();
        image.save(format!("{dir}/frame_{k}.png")).unwrap();
        let blocks = BlockGrid::compute(&Plane::from_rgb(&image).unwrap()).unwrap();
        let d = blocks
            .window_descriptor(0, 0, blocks.blocks_x() + 1, blocks.blocks_y() + 1)
            .unwrap();
        let mut out = std::fs::File::create(format!("{dir}/frame_{k}.hog.txt")).unwrap();
        writeln!(
            out,
            "{} {} {}",
            blocks.blocks_x(),
            blocks.blocks_y(),
            d.len()
        )
        .unwrap();
        for v in d {
            writeln!(out, "{v}").unwrap();
        }
    }
}
