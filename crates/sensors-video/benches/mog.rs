//! Background mixture throughput on 768 × 576 frames (PAL), grey and colour, rendered once
//! outside the timed closure. The model is warmed past its first phase (L = 200 frames) so
//! the window update is what is timed.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use sensors_video::{
    BackgroundModel, MogConfig, ObjectKind, PinholeCamera, PixelFormat, Scene, SceneConfig,
    SceneObject,
};

fn scene(format: PixelFormat) -> Vec<sensors_video::VideoFrame> {
    let mut cfg = SceneConfig::small();
    cfg.format = format;
    cfg.camera = PinholeCamera {
        width: 768,
        height: 576,
        fx: 720.0,
        fy: 720.0,
        cx: 383.5,
        cy: 287.5,
        ..cfg.camera
    };
    let objects = vec![
        SceneObject {
            kind: ObjectKind::Person,
            start_m: [14.0, -6.0],
            velocity_mps: [0.0, 1.4],
            colour: [200, 40, 40],
            appear_s: 0.0,
            vanish_s: 1e9,
        },
        SceneObject {
            kind: ObjectKind::Vehicle,
            start_m: [22.0, 8.0],
            velocity_mps: [0.0, -4.0],
            colour: [30, 60, 170],
            appear_s: 0.0,
            vanish_s: 1e9,
        },
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let Ok(scene) = Scene::new(cfg, objects, &mut rng) else {
        panic!("bench scene config is valid");
    };
    (0..8)
        .map(|k| match scene.render(k, &mut rng) {
            Ok(r) => r.frame,
            Err(e) => panic!("render failed: {e}"),
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    for (name, format) in [
        ("grey_768x576", PixelFormat::Grey),
        ("rgb_768x576", PixelFormat::Rgb),
    ] {
        let frames = scene(format);
        let Ok(mut model) = BackgroundModel::new(&MogConfig::default(), 768, 576, format) else {
            panic!("valid config");
        };
        for k in 0..210 {
            let _ = model.apply(&frames[k % frames.len()]);
        }
        let mut mask = model.apply(&frames[0]).unwrap_or_else(|e| panic!("{e}"));
        let mut group = c.benchmark_group("mog");
        group.throughput(Throughput::Elements(1));
        group.sample_size(30);
        let mut k = 0;
        group.bench_function(name, |b| {
            b.iter(|| {
                k += 1;
                let r =
                    model.apply_into(std::hint::black_box(&frames[k % frames.len()]), &mut mask);
                std::hint::black_box(r.is_ok())
            })
        });
        group.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
