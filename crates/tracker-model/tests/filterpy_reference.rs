//! tracker-model's EKF, UKF and IMM against filterpy 2.0.0 on the same inputs: the turning,
//! climbing aircraft of `docs/comparisons/filterpy_nonlinear.py`, whose recorded output is
//! `testdata/filterpy_nonlinear.json`. Every number must agree to 1e-9, relative to its scale
//! where that exceeds one.

use nalgebra::{SMatrix, SVector};
use serde_json::Value;
use tracker_model::{
    ConstantVelocity2, ConstantVelocity3, ConstantVelocityTurnLayout, CoordinatedTurn,
    CoordinatedTurnRate, CvNoise, Gaussian, GaussianFilter, Imm, MeasurementModel, Mode,
    MotionModel, RadarSite, RangeBearing, RangeBearingElevation, SigmaPoints, TurnNoise,
};

const TOLERANCE: f64 = 1e-9;

fn reference() -> Value {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/testdata/filterpy_nonlinear.json"
    );
    serde_json::from_str(&std::fs::read_to_string(path).expect("recorded filterpy output"))
        .expect("valid JSON")
}

fn numbers(v: &Value) -> Vec<f64> {
    match v {
        Value::Array(items) => items.iter().flat_map(numbers).collect(),
        Value::Number(n) => vec![n.as_f64().expect("a float")],
        other => panic!("not a number or array: {other}"),
    }
}

fn vector<const N: usize>(v: &Value) -> SVector<f64, N> {
    SVector::from_column_slice(&numbers(v))
}

fn matrix<const N: usize>(v: &Value) -> SMatrix<f64, N, N> {
    // Row-major in the file; nalgebra fills column by column, so transpose.
    SMatrix::<f64, N, N>::from_column_slice(&numbers(v)).transpose()
}

/// |a − b| ≤ tolerance × max(1, |b|), element by element.
fn assert_close(ours: &[f64], theirs: &[f64], what: &str, scan: usize) {
    assert_eq!(ours.len(), theirs.len(), "{what} at scan {scan}: lengths");
    for (k, (a, b)) in ours.iter().zip(theirs).enumerate() {
        let scale = b.abs().max(1.0);
        assert!(
            (a - b).abs() <= TOLERANCE * scale,
            "{what}[{k}] at scan {scan}: ours {a}, filterpy {b}, difference {}",
            (a - b).abs()
        );
    }
}

fn prior<const N: usize>(doc: &Value, key: &str) -> Gaussian<N> {
    Gaussian::new(vector(&doc[key]["mean"]), matrix(&doc[key]["cov"]))
        .expect("a valid reference input")
}

fn radar2<const N: usize>(doc: &Value) -> RangeBearing<N> {
    let p = numbers(&doc["radar"]);
    let sigma = |k: &str| doc[k].as_f64().expect("a valid reference input");
    RangeBearing::at(
        [p[0], p[1]],
        sigma("sigma_range_m"),
        sigma("sigma_bearing_rad"),
    )
    .expect("a valid reference input")
}

fn radar3(doc: &Value) -> RangeBearingElevation<6> {
    let site = RadarSite {
        position: vector::<3>(&doc["radar"]),
        state_indices: SVector::<usize, 3>::new(0, 1, 2),
    };
    let sigma = |k: &str| doc[k].as_f64().expect("a valid reference input");
    RangeBearingElevation::new(
        site,
        [
            sigma("sigma_range_m"),
            sigma("sigma_bearing_rad"),
            sigma("sigma_elevation_rad"),
        ],
    )
    .expect("a valid reference input")
}

fn unscented(doc: &Value) -> GaussianFilter {
    let s = &doc["sigma_points"];
    let get = |k: &str| s[k].as_f64().expect("a valid reference input");
    GaussianFilter::Unscented(
        SigmaPoints::new(get("alpha"), get("beta"), get("kappa")).expect("a valid reference input"),
    )
}

fn turn_noise(doc: &Value) -> TurnNoise {
    TurnNoise {
        q_accel: doc["turn_rate"]["q_accel"]
            .as_f64()
            .expect("a valid reference input"),
        q_turn: doc["turn_rate"]["q_turn"]
            .as_f64()
            .expect("a valid reference input"),
    }
}

fn scans<const M: usize>(doc: &Value, key: &str) -> Vec<(f64, SVector<f64, M>)> {
    let times = numbers(&doc["times"]);
    let zs = doc[key].as_array().expect("a valid reference input");
    times.into_iter().zip(zs.iter().map(vector::<M>)).collect()
}

fn check_single<T, O, const N: usize, const M: usize>(
    doc: &Value,
    run: &str,
    filter: GaussianFilter,
    motion: &T,
    sensor: &O,
    start: Gaussian<N>,
    measurements: &[(f64, SVector<f64, M>)],
) where
    T: MotionModel<N>,
    O: MeasurementModel<N, M>,
{
    let expected = doc["runs"][run]
        .as_array()
        .expect("a valid reference input");
    assert_eq!(expected.len(), measurements.len());
    let (mut state, mut t_last) = (start, 0.0);
    for (k, ((t, z), want)) in measurements.iter().zip(expected).enumerate() {
        let predicted = filter
            .predict(motion, &state, t - t_last)
            .expect("a valid reference input");
        assert_close(
            predicted.mean().as_slice(),
            &numbers(&want["prior_mean"]),
            run,
            k,
        );
        let updated = filter
            .update(sensor, &predicted, z)
            .expect("a valid reference input");
        state = updated.state;
        assert_close(state.mean().as_slice(), &numbers(&want["mean"]), run, k);
        let cov = state.covariance().transpose();
        assert_close(cov.as_slice(), &numbers(&want["cov"]), run, k);
        let ll = updated.innovation.log_likelihood;
        assert_close(
            &[ll],
            &[want["log_likelihood"]
                .as_f64()
                .expect("a valid reference input")],
            run,
            k,
        );
        t_last = *t;
    }
}

fn check_imm<O, const N: usize, const M: usize>(
    doc: &Value,
    run: &str,
    imm: &Imm<N>,
    sensor: &O,
    start: Gaussian<N>,
    probabilities: &[f64],
    measurements: &[(f64, SVector<f64, M>)],
) where
    O: MeasurementModel<N, M>,
{
    let expected = doc["runs"][run]
        .as_array()
        .expect("a valid reference input");
    let mut state = imm
        .start(start, probabilities)
        .expect("a valid reference input");
    let mut t_last = 0.0;
    for (k, ((t, z), want)) in measurements.iter().zip(expected).enumerate() {
        let predicted = imm
            .predict(&state, t - t_last)
            .expect("a valid reference input");
        let priors: Vec<f64> = predicted
            .modes()
            .iter()
            .flat_map(|g| g.mean().iter().copied())
            .collect();
        assert_close(&priors, &numbers(&want["mode_prior_means"]), run, k);
        let updated = imm
            .update(sensor, &predicted, z)
            .expect("a valid reference input");
        let p = &want["probabilities"];
        assert_close(updated.state.probabilities(), &numbers(p), run, k);
        let combined = updated.state.combined();
        assert_close(combined.mean().as_slice(), &numbers(&want["mean"]), run, k);
        let cov = combined.covariance().transpose();
        assert_close(cov.as_slice(), &numbers(&want["cov"]), run, k);
        let ll = want["log_likelihood"]
            .as_f64()
            .expect("a valid reference input");
        assert_close(&[updated.log_likelihood], &[ll], run, k);
        state = updated.state;
        t_last = *t;
    }
}

#[test]
fn ekf_and_ukf_with_turn_rate_in_the_state_equal_filterpy() {
    let doc = reference();
    let motion = CoordinatedTurnRate::new(turn_noise(&doc)).expect("a valid reference input");
    let radar = radar2::<5>(&doc);
    let zs = scans::<2>(&doc, "range_bearing");
    let start = prior::<5>(&doc, "prior5");
    let ekf = GaussianFilter::Extended;
    check_single(
        &doc,
        "ekf_turn_rate",
        ekf,
        &motion,
        &radar,
        start.clone(),
        &zs,
    );
    let ukf = unscented(&doc);
    check_single(&doc, "ukf_turn_rate", ukf, &motion, &radar, start, &zs);
}

#[test]
fn ekf_and_ukf_with_range_bearing_elevation_equal_filterpy() {
    let doc = reference();
    let motion = ConstantVelocity3::new(doc["cv3"]["q"].as_f64().expect("a valid reference input"))
        .expect("a valid reference input");
    let radar = radar3(&doc);
    let zs = scans::<3>(&doc, "range_bearing_elevation");
    let start = prior::<6>(&doc, "prior6");
    let ekf = GaussianFilter::Extended;
    check_single(&doc, "ekf_cv3", ekf, &motion, &radar, start.clone(), &zs);
    check_single(
        &doc,
        "ukf_cv3",
        unscented(&doc),
        &motion,
        &radar,
        start,
        &zs,
    );
}

fn switching(doc: &Value, key: &str) -> Vec<Vec<f64>> {
    doc[key]
        .as_array()
        .expect("a valid reference input")
        .iter()
        .map(numbers)
        .collect()
}

#[test]
fn imm_of_cv_and_two_known_turns_with_ekfs_equals_filterpy() {
    let doc = reference();
    let q = doc["cv"]["q"].as_f64().expect("a valid reference input");
    let mut modes: Vec<Mode<4>> = vec![Box::new(
        ConstantVelocity2::new(1.0, CvNoise::WhiteAcceleration { q })
            .expect("a valid reference input"),
    )];
    for turn in doc["turns"].as_array().expect("a valid reference input") {
        let rate = turn["turn_rate_rad_s"]
            .as_f64()
            .expect("a valid reference input");
        let q = turn["q"].as_f64().expect("a valid reference input");
        modes.push(Box::new(
            CoordinatedTurn::new(rate, q).expect("a valid reference input"),
        ));
    }
    let imm = Imm::new(
        modes,
        &switching(&doc, "switching_cv_ct"),
        GaussianFilter::Extended,
    )
    .expect("a valid reference input");
    let p5 = prior::<5>(&doc, "prior5");
    let start = Gaussian::new(
        p5.mean().fixed_rows::<4>(0).into_owned(),
        p5.covariance().fixed_view::<4, 4>(0, 0).into_owned(),
    )
    .expect("a valid reference input");
    let mu = numbers(&doc["start_cv_ct"]);
    let zs = scans::<2>(&doc, "range_bearing");
    let radar = radar2::<4>(&doc);
    check_imm(&doc, "imm_ekf_cv_ct", &imm, &radar, start, &mu, &zs);
}

#[test]
fn imm_of_straight_flight_and_turn_rate_with_ukfs_equals_filterpy() {
    let doc = reference();
    let noise = turn_noise(&doc);
    let modes: Vec<Mode<5>> = vec![
        Box::new(ConstantVelocityTurnLayout::new(noise).expect("a valid reference input")),
        Box::new(CoordinatedTurnRate::new(noise).expect("a valid reference input")),
    ];
    let imm = Imm::new(
        modes,
        &switching(&doc, "switching_turn_layout"),
        unscented(&doc),
    )
    .expect("a valid reference input");
    let mu = numbers(&doc["start_turn_layout"]);
    let zs = scans::<2>(&doc, "range_bearing");
    let start = prior::<5>(&doc, "prior5");
    check_imm(
        &doc,
        "imm_ukf_turn_layout",
        &imm,
        &radar2::<5>(&doc),
        start,
        &mu,
        &zs,
    );
}
