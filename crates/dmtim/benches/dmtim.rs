//! The seven-sensor scenario, 100 frames, all sensors: tracking (every sensor's online
//! MCMCDA and mixing samples) plus the identity layer with Chernoff fusion.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use dmtim::{DmtimConfig, manage_identities, observe, seven_radars, track_all};
use rand::SeedableRng;

fn config() -> DmtimConfig {
    let (sensors, _) = seven_radars().expect("the built-in scene is valid");
    let mut c = DmtimConfig {
        sensors,
        ..DmtimConfig::default()
    };
    c.mcmcda.max_speed = 2.0;
    c.mcmcda.measurement_noise = nalgebra::Matrix2::identity() * 0.09;
    c.mcmcda.motion = tracker_model::ConstantVelocity2::mcmcda(1.0, 0.01).expect("valid");
    c.mcmcda.births_per_scan = 0.05;
    c.mcmcda.p_disappear = 0.01;
    c.mcmcda.max_gap = 3;
    c.local_info.sensors = vec![6];
    c.local_info.probability = 0.1;
    c.local_info.error_rate = 0.05;
    c
}

fn bench(c: &mut Criterion) {
    let config = config();
    let (_, truth) = seven_radars().expect("valid");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let obs = observe(&truth, &config, 100, &mut rng).expect("valid");
    c.bench_function("dmtim seven radars 100 frames", |b| {
        b.iter(|| {
            let records = track_all(black_box(&obs), &config, 1).expect("tracks");
            manage_identities(&records, &obs, &truth, &config).expect("identities")
        });
    });
}

/// The scaling case: 30 radars on a 6 × 5 grid (spacing 30, range 20) and 40 aircraft on
/// straight lines between random points of the 180 × 150 region, all present from frame 0
/// to 100.
fn large(c: &mut Criterion) {
    use identity_mgmt::IdentityId;
    use rand::RngExt;
    use tracker_model::Vec2;
    let mut config = config();
    config.sensors = (0..30)
        .map(|k| dmtim::SensorSpec {
            name: format!("R{k}"),
            centre: [
                15.0 + 30.0 * f64::from(k % 6),
                15.0 + 30.0 * f64::from(k / 6),
            ],
            range_m: 20.0,
        })
        .collect();
    config.local_info.sensors = vec![14];
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(30);
    let truth: Vec<dmtim::TruthTarget> = (0..40)
        .map(|k| {
            let mut point = || Vec2::new(rng.random::<f64>() * 180.0, rng.random::<f64>() * 150.0);
            let a = point();
            let mut b = point();
            while (b - a).norm() < 100.0 {
                b = point();
            }
            dmtim::TruthTarget::along(IdentityId(k + 1), 0, &[a, b], 1.0).expect("valid")
        })
        .collect();
    let obs = observe(&truth, &config, 100, &mut rng).expect("valid");
    c.bench_function("dmtim 30 radars 40 aircraft 100 frames", |b| {
        b.iter(|| {
            let records = track_all(black_box(&obs), &config, 1).expect("tracks");
            manage_identities(&records, &obs, &truth, &config).expect("identities")
        });
    });
}

criterion_group!(benches, bench, large);
criterion_main!(benches);
