//! Tests of the DMTIM crate.

use identity_mgmt::{FusionConfig, FusionCriterion, IdentityId};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::{
    DmtimConfig, IdentityRun, TruthTarget, manage_identities, observe, seven_radars, track_all,
};

fn config() -> DmtimConfig {
    let (sensors, _) = seven_radars().expect("valid");
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
    c
}

fn run(c: &DmtimConfig, truth: &[TruthTarget], seed: u64) -> IdentityRun {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let obs = observe(truth, c, 100, &mut rng).expect("observe");
    let records = track_all(&obs, c, seed).expect("track");
    manage_identities(&records, &obs, truth, c).expect("identities")
}

/// With a correct read of every target at every sensor in every frame, every scored track's
/// argmax identity is its target's: the read is certain (l = e_i), so after Sinkhorn the
/// column is e_i whatever came before.
#[test]
fn perfect_local_information_gives_every_identity() {
    let (_, truth) = seven_radars().expect("valid");
    let mut c = config();
    c.local_info.sensors = (0..7).collect();
    c.local_info.probability = 1.0;
    c.local_info.error_rate = 0.0;
    c.sensing.p_detect = 1.0;
    for seed in 1..4 {
        let r = run(&c, &truth, seed);
        let scored: usize = r.correct.iter().map(|x| x.1).sum();
        assert!(
            scored > 300,
            "seed {seed}: only {scored} track-frames scored"
        );
        for (frame, &(ok, n)) in r.correct.iter().enumerate() {
            assert_eq!(ok, n, "seed {seed}, frame {frame}: {ok} of {n} correct");
        }
    }
}

/// Without any reads the same runs are not perfect: the test above can fail.
#[test]
fn without_local_information_some_identity_is_wrong() {
    let (_, truth) = seven_radars().expect("valid");
    let mut c = config();
    c.sensing.p_detect = 1.0;
    let wrong: usize = (1..4)
        .map(|seed| {
            run(&c, &truth, seed)
                .correct
                .iter()
                .map(|&(ok, n)| n - ok)
                .sum::<usize>()
        })
        .sum();
    assert!(wrong > 0);
}

/// A straight flight sampled at speed 1 passes through its waypoints and has unit steps.
#[test]
fn along_waypoints() {
    let t = TruthTarget::along(
        IdentityId(1),
        5,
        &[
            tracker_model::Vec2::new(0.0, 0.0),
            tracker_model::Vec2::new(3.0, 0.0),
            tracker_model::Vec2::new(3.0, 2.5),
        ],
        1.0,
    )
    .expect("valid");
    assert_eq!(t.at(4), None);
    assert_eq!(t.at(5), Some(tracker_model::Vec2::new(0.0, 0.0)));
    assert_eq!(t.at(8), Some(tracker_model::Vec2::new(3.0, 0.0)));
    assert_eq!(
        t.positions.last().copied(),
        Some(tracker_model::Vec2::new(3.0, 2.5))
    );
    for w in t.positions.windows(2).take(5) {
        assert!(((w[1] - w[0]).norm() - 1.0).abs() < 1e-12);
    }
    assert!(TruthTarget::along(IdentityId(1), 0, &[tracker_model::Vec2::zeros()], 1.0).is_err());
}

/// Bad configurations are typed errors naming the field.
#[test]
fn config_errors() {
    let mut c = config();
    c.local_info.sensors = vec![9];
    assert!(matches!(
        c.check(),
        Err(crate::Error::InvalidParameter {
            name: "local_info.sensors",
            ..
        })
    ));
    let mut c = config();
    c.sensors.clear();
    assert!(c.check().is_err());
    let mut c = config();
    c.exchange_every = 0;
    assert!(c.check().is_err());
    let parsed: Result<DmtimConfig, _> =
        serde_json::from_str(r#"{"interaction_distance_m": 2.0, "bogus": 1}"#);
    assert!(parsed.is_err(), "unknown fields are rejected");
}

/// Every mixing matrix a run builds is doubly stochastic, and the fusion criteria differ
/// from no fusion only through the exchange (same trackers, same reads).
#[test]
fn mixings_are_doubly_stochastic() {
    let (_, truth) = seven_radars().expect("valid");
    let c = config();
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let obs = observe(&truth, &c, 100, &mut rng).expect("observe");
    let records = track_all(&obs, &c, 2).expect("track");
    let mut n_mixings = 0;
    for frames in &records {
        for f in frames {
            for m in &f.mixings {
                n_mixings += 1;
                let k = m.continuation.n();
                for i in 0..k {
                    let row: f64 = (0..k).map(|j| m.continuation.get(i, j)).sum();
                    let col: f64 = (0..k).map(|j| m.continuation.get(j, i)).sum();
                    assert!((row - 1.0).abs() < 1e-6 && (col - 1.0).abs() < 1e-6);
                }
            }
        }
    }
    assert!(n_mixings > 0, "the crossings produce mixings");
    let mut none = c.clone();
    none.fusion = None;
    let a = manage_identities(&records, &obs, &truth, &none).expect("no fusion");
    let mut chernoff = c.clone();
    chernoff.fusion = Some(FusionConfig {
        criterion: FusionCriterion::Chernoff,
        ..FusionConfig::default()
    });
    let b = manage_identities(&records, &obs, &truth, &chernoff).expect("fusion");
    assert!(b.bytes_exchanged > a.bytes_exchanged);
}
