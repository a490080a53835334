//! Renders a scene, runs our background mixture on it, and writes the frames and our masks as
//! PNG for `docs/comparisons/opencv_bgsegm_mog.py`, which runs OpenCV's `bgsegm` MOG on the
//! same frames. Prints our median time per frame (release build: `cargo run --release -p
//! sensors-video --example mog_compare -- DIR WIDTH HEIGHT FRAMES grey|rgb`).

use std::path::PathBuf;
use std::time::Instant;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use sensors_video::{
    BackgroundModel, MogConfig, ObjectKind, PixelFormat, Scene, SceneConfig, SceneObject,
    VideoFrame, io,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, dir, w, h, n, fmt] = args.as_slice() else {
        return Err("usage: mog_compare DIR WIDTH HEIGHT FRAMES grey|rgb".into());
    };
    let (w, h, n): (usize, usize, usize) = (w.parse()?, h.parse()?, n.parse()?);
    let format = if fmt == "grey" {
        PixelFormat::Grey
    } else {
        PixelFormat::Rgb
    };
    let dir = PathBuf::from(dir);
    std::fs::create_dir_all(dir.join("frames"))?;
    std::fs::create_dir_all(dir.join("ours"))?;
    let mut cfg = SceneConfig::small();
    cfg.format = format;
    let scale = w as f64 / 160.0;
    cfg.camera.width = w;
    cfg.camera.height = h;
    cfg.camera.fx = 150.0 * scale;
    cfg.camera.fy = 150.0 * scale;
    cfg.camera.cx = (w as f64 - 1.0) / 2.0;
    cfg.camera.cy = (h as f64 - 1.0) / 2.0;
    let objects = [
        (ObjectKind::Person, 12.0, 1.4f64, [200, 40, 40], 10.0),
        (ObjectKind::Person, 16.0, -1.2, [40, 60, 200], 12.0),
        (ObjectKind::Vehicle, 20.0, 3.0, [230, 220, 60], 14.0),
    ]
    .map(|(kind, x, v, colour, t0)| SceneObject {
        kind,
        start_m: [x, -v.signum() * 0.55 * x - v * t0],
        velocity_mps: [0.0, v],
        colour,
        appear_s: t0,
        vanish_s: 1e9,
    });
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let scene = Scene::new(cfg, objects.to_vec(), &mut rng)?;
    let frames: Vec<VideoFrame> = (0..n)
        .map(|k| scene.render(k, &mut rng).map(|r| r.frame))
        .collect::<Result<_, _>>()?;
    let mut model = BackgroundModel::new(&MogConfig::default(), w, h, format)?;
    let mut times = Vec::new();
    for (k, f) in frames.iter().enumerate() {
        let t = Instant::now();
        let mask = model.apply(f)?;
        times.push(t.elapsed().as_secs_f64());
        io::write_image(f, &dir.join(format!("frames/{k:06}.png")))?;
        let m = VideoFrame::new(w, h, PixelFormat::Grey, mask.labels)?;
        io::write_image(&m, &dir.join(format!("ours/{k:06}.png")))?;
    }
    times.sort_by(f64::total_cmp);
    #[expect(clippy::print_stdout, reason = "an example reports to the terminal")]
    {
        println!("ours_median_ms {:.3}", 1e3 * times[times.len() / 2]);
    }
    Ok(())
}
