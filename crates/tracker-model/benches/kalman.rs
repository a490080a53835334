//! Kalman benchmarks: one constant-velocity predict + update, and a 1000-step filter followed
//! by the RTS smoother (filterpy needs ≈ 26 ms for the latter on this machine:
//! docs/comparisons/filterpy_cv2d_1000.py, docs/benchmarks.md); and the EKF, UKF and IMM runs
//! of docs/comparisons/filterpy_nonlinear.py (its `time` mode times filterpy on the same 43
//! scans of testdata/filterpy_nonlinear.json).
#![expect(clippy::unwrap_used, reason = "benchmarks run on fixed, valid inputs")]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Matrix4, Vector2, Vector4};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use tracker_model::{
    ConstantVelocity2, CvNoise, Gaussian, ObservationModel, TransitionModel, filter,
    position_measurement, smooth,
};

fn bench_kalman(c: &mut Criterion) {
    let motion = ConstantVelocity2::new(1.0, CvNoise::WhiteAcceleration { q: 0.1 }).unwrap();
    let sensor = position_measurement(4.0).unwrap();
    let prior =
        Gaussian::new(Vector4::new(0.0, 0.0, 1.0, 1.0), Matrix4::identity() * 10.0).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let measurements: Vec<Option<Vector2<f64>>> = (0..1000)
        .map(|k| {
            let t = k as f64;
            let n: [f64; 2] = [
                StandardNormal.sample(&mut rng),
                StandardNormal.sample(&mut rng),
            ];
            (k % 10 != 3).then(|| Vector2::new(t + 2.0 * n[0], t + 2.0 * n[1]))
        })
        .collect();

    c.bench_function("cv2d_predict_update", |b| {
        let z = Vector2::new(1.0, 1.2);
        b.iter(|| {
            let predicted = motion.predict(black_box(&prior));
            sensor.update(&predicted, black_box(&z)).unwrap()
        })
    });
    c.bench_function("cv2d_filter_1000_steps", |b| {
        b.iter(|| filter(&motion, &sensor, &prior, black_box(&measurements)).unwrap())
    });
    let run = filter(&motion, &sensor, &prior, &measurements).unwrap();
    c.bench_function("cv2d_rts_1000_steps", |b| {
        b.iter(|| smooth(&motion, black_box(&run)).unwrap())
    });
    c.bench_function("cv2d_filter_and_rts_1000_steps", |b| {
        b.iter(|| {
            let run = filter(&motion, &sensor, &prior, black_box(&measurements)).unwrap();
            smooth(&motion, &run).unwrap()
        })
    });
}

/// The 43 range-bearing plots of the filterpy reference, with their times.
fn reference_scans() -> (Vec<(f64, nalgebra::Vector2<f64>)>, serde_json::Value) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/testdata/filterpy_nonlinear.json"
    );
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let num = |v: &serde_json::Value| v.as_f64().unwrap();
    let times = doc["times"].as_array().unwrap().iter().map(num);
    let zs = doc["range_bearing"].as_array().unwrap().iter().map(|z| {
        let z = z.as_array().unwrap();
        nalgebra::Vector2::new(num(&z[0]), num(&z[1]))
    });
    (times.zip(zs).collect(), doc)
}

/// The three-mode IMM of the reference (CV, CT ±ω₀, EKF) with its start probabilities.
fn reference_imm(doc: &serde_json::Value) -> tracker_model::Imm<4> {
    use tracker_model::{CoordinatedTurn, GaussianFilter, Imm, Mode};
    let num = |v: &serde_json::Value| v.as_f64().unwrap();
    let w = num(&doc["turns"][0]["turn_rate_rad_s"]);
    let q = num(&doc["cv"]["q"]);
    let modes: Vec<Mode<4>> = vec![
        Box::new(ConstantVelocity2::new(1.0, CvNoise::WhiteAcceleration { q }).unwrap()),
        Box::new(CoordinatedTurn::new(w, q).unwrap()),
        Box::new(CoordinatedTurn::new(-w, q).unwrap()),
    ];
    let switching: Vec<Vec<f64>> = doc["switching_cv_ct"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r.as_array().unwrap().iter().map(num).collect())
        .collect();
    Imm::new(modes, &switching, GaussianFilter::Extended)
        .unwrap()
        .with_start_probabilities(&[0.8, 0.1, 0.1])
        .unwrap()
}

fn bench_nonlinear(c: &mut Criterion) {
    use tracker_model::{
        CoordinatedTurnRate, GaussianFilter, RangeBearing, SigmaPoints, SingleModel,
        StateEstimator, TurnNoise,
    };
    let (scans, doc) = reference_scans();
    let num = |v: &serde_json::Value| v.as_f64().unwrap();
    let flat = |v: &serde_json::Value| -> Vec<f64> {
        v.as_array()
            .unwrap()
            .iter()
            .flat_map(|r| r.as_array().unwrap().iter().map(num))
            .collect()
    };
    let mean5 = nalgebra::SVector::<f64, 5>::from_iterator(
        doc["prior5"]["mean"].as_array().unwrap().iter().map(num),
    );
    let cov5 = nalgebra::SMatrix::<f64, 5, 5>::from_row_slice(&flat(&doc["prior5"]["cov"]));
    let prior5 = Gaussian::new(mean5, cov5).unwrap();
    let prior4 = Gaussian::new(
        mean5.fixed_rows::<4>(0).into_owned(),
        cov5.fixed_view::<4, 4>(0, 0).into_owned(),
    )
    .unwrap();
    let radar = doc["radar"].as_array().unwrap();
    let site = [num(&radar[0]), num(&radar[1])];
    let (sr, sb) = (num(&doc["sigma_range_m"]), num(&doc["sigma_bearing_rad"]));
    let noise = TurnNoise {
        q_accel: num(&doc["turn_rate"]["q_accel"]),
        q_turn: num(&doc["turn_rate"]["q_turn"]),
    };
    fn run<E: StateEstimator<N>, const N: usize>(
        e: &E,
        sensor: &RangeBearing<N>,
        prior: &Gaussian<N>,
        scans: &[(f64, nalgebra::Vector2<f64>)],
    ) -> E::Belief {
        let mut belief = e.start(prior.clone()).unwrap();
        let mut last = 0.0;
        for (t, z) in scans {
            let predicted = e.predict(&belief, t - last).unwrap();
            belief = e.update(sensor, &predicted, z).unwrap().belief;
            last = *t;
        }
        belief
    }
    let rb5 = RangeBearing::<5>::at(site, sr, sb).unwrap();
    let rb4 = RangeBearing::<4>::at(site, sr, sb).unwrap();
    let ct = CoordinatedTurnRate::new(noise).unwrap();
    let ekf = SingleModel {
        motion: ct,
        filter: GaussianFilter::Extended,
    };
    c.bench_function("ekf_turn_rate_43_scans", |b| {
        b.iter(|| run(&ekf, &rb5, black_box(&prior5), &scans))
    });
    let sigma = SigmaPoints::new(0.5, 2.0, -1.0).unwrap();
    let ukf = SingleModel {
        motion: ct,
        filter: GaussianFilter::Unscented(sigma),
    };
    c.bench_function("ukf_turn_rate_43_scans", |b| {
        b.iter(|| run(&ukf, &rb5, black_box(&prior5), &scans))
    });
    let imm = reference_imm(&doc);
    c.bench_function("imm_ekf_cv_ct_43_scans", |b| {
        b.iter(|| run(&imm, &rb4, black_box(&prior4), &scans))
    });
}

criterion_group!(benches, bench_kalman, bench_nonlinear);
criterion_main!(benches);
